//! The frame export (`--export FILE.pcapng`): one pcapng packet per reassembled frame, valid
//! or not, stamped with the capture time of the frame, for Wireshark.
//!
//! * FrSky S.Port: link type `USER0` (147), the frame's bytes as on the wire (0x7E, physical
//!   ID, and for a sensor's answer the 8 bytes and the CRC, byte-stuffed as sent), decoded by
//!   `contrib/wireshark/busnoop-sport.lua`.
//! * modm SAB / SAB2: link type `USER1` (148), the frame's bytes as on the wire (either
//!   framing), decoded by `contrib/wireshark/busnoop-sab.lua`.
//!
//! * Serial Saia S-Bus: link type `RAW` (101, raw IP), each telegram re-wrapped as the
//!   Ether-S-Bus datagram a PCD would have sent over UDP (see `sbus::export::SbusWrap`),
//!   decoded by Wireshark's own `sbus` dissector.
//!
//! The packets are the rows' `raw` bytes (S-Bus: the telegram the row's decoder re-read,
//! [`Unframed`]), so the export holds exactly the frames the table shows (filters apply); rows
//! without bytes (notes, gaps) are not packets. A frame the table marks as an error carries a
//! packet comment (`opt_comment`) with busnoop's verdict.
//!
//! [`Exporting`] wraps the driver's [`Sink`]: every row goes on to the table unchanged.

use std::io;
use std::path::{Path, PathBuf};

use chrono::{DateTime, Utc};

use crate::exit::Failure;
use crate::pcap::write_ng;
use crate::protocol::{Export, Protocol, Wrap};
use crate::row::{Class, OutputError, Row, RowResult, Unframed};
use crate::sink::{Output, Sink, Tap, Tapped};
use crate::time::Anchor;

/// Writes the export.
pub struct Exporter {
    path: PathBuf,
    /// Whole blocks only: a full disk leaves the file ending with its last whole block.
    out: Output,
    link_type: u32,
    interface: (String, String),
    /// The protocol's packet of a frame, when it is not the frame's bytes as on the wire
    /// (serial S-Bus re-wrapped as Ether-S-Bus).
    wrap: Option<Box<dyn Wrap>>,
    /// The packet being written.
    packet: Vec<u8>,
    anchor: Option<DateTime<Utc>>,
    started: bool,
    scratch: Vec<u8>,
    packets: u64,
}

impl Exporter {
    /// Checks `path` and `protocol` and creates the file; `name` and `description` name the
    /// pcapng interface (the source, the protocol and line).
    pub fn create(
        path: &Path,
        protocol: &Protocol,
        name: &str,
        description: &str,
    ) -> Result<Exporter, Failure> {
        let export = check(path, protocol)?;
        let what = format!("cannot create export {}", path.display());
        let out = crate::files::create_file(path)
            .and_then(|file| Output::file(file, path))
            .map_err(|e| Failure::from_create(&what, &e))?;
        Ok(Exporter {
            path: path.to_owned(),
            out,
            link_type: export.linktype,
            interface: (name.to_string(), description.to_string()),
            wrap: export.wrap.map(|w| w()),
            packet: Vec::new(),
            anchor: None,
            started: false,
            scratch: Vec::new(),
            packets: 0,
        })
    }

    /// Packets written so far.
    #[cfg(test)]
    pub fn packets(&self) -> u64 {
        self.packets
    }

    fn error(&self, error: io::Error) -> OutputError {
        OutputError {
            path: Some(self.path.clone()),
            error,
        }
    }

    fn start(&mut self) -> io::Result<()> {
        if self.started {
            return Ok(());
        }
        self.started = true;
        let mut head = Vec::with_capacity(256);
        write_ng::section_header(&mut head);
        write_ng::interface(
            &mut head,
            self.link_type as u16,
            Some(&self.interface.0),
            Some(&self.interface.1),
        );
        self.out.record(&head).map_err(|e| e.error)
    }

    /// The packet for `row`, when it carries a frame's bytes (every decoder writes one row per
    /// frame); `unframed`: its content re-read, when the decoder gives it. Two rows with the
    /// same bytes and time are two frames (one read of a live line holds several, and RC
    /// buses repeat a frame while the sticks rest): each is a packet.
    fn frame(&mut self, row: &Row<'_>, unframed: Option<&Unframed<'_>>) -> io::Result<()> {
        if row.raw.is_empty() {
            return Ok(());
        }
        self.start()?;
        let anchor = *self.anchor.get_or_insert_with(Utc::now);
        let micros = row.micros.unwrap_or(0).min(i64::MAX as u64) as i64;
        let ts = anchor.timestamp_micros().saturating_add(micros);
        let comment = (row.class == Class::Error).then(|| {
            let mut c = format!("busnoop: {}", row.kind);
            for part in [row.data, row.extra.last().copied().unwrap_or("")] {
                if !part.is_empty() {
                    c.push_str(": ");
                    c.push_str(part);
                }
            }
            c
        });
        let data = match &mut self.wrap {
            Some(wrap) => {
                self.packet.clear();
                wrap.packet(row, unframed, &mut self.packet);
                &self.packet[..]
            }
            None => row.raw,
        };
        self.scratch.clear();
        write_ng::packet(&mut self.scratch, 0, ts, data, comment.as_deref());
        self.out.record(&self.scratch).map_err(|e| e.error)?;
        self.packets += 1;
        Ok(())
    }

    /// Writes the headers (an export of no frames is still a valid pcapng) and everything
    /// buffered.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        self.start().map_err(|e| self.error(e))?;
        self.out.flush()
    }
}

/// Checks an `--export` target before the run: the name ends in `.pcapng` and the protocol has
/// an export. Returns the protocol's export.
pub fn check(path: &Path, protocol: &Protocol) -> Result<Export, Failure> {
    let ext = path.extension().and_then(|e| e.to_str());
    // A FIFO (Wireshark's extcap pipe, `wireshark -k -i FIFO`) takes the export whatever its name.
    use std::os::unix::fs::FileTypeExt;
    let fifo = std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo());
    if !fifo && !ext.is_some_and(|e| e.eq_ignore_ascii_case("pcapng")) {
        return Err(Failure::Usage(format!(
            "--export {}: the export is pcapng; name it FILE.pcapng",
            path.display()
        )));
    }
    protocol.export.ok_or_else(|| {
        let with: Vec<&str> = crate::protocols::PROTOCOLS
            .iter()
            .filter(|p| p.export.is_some())
            .map(|p| p.command)
            .collect();
        Failure::Usage(format!(
            "--export is available for {}; for {}, record the wire with --record FILE.pcapng",
            with.join(", "),
            protocol.command
        ))
    })
}

/// A [`Sink`] that also exports every row's frame.
pub type Exporting<'a, S> = Tapped<'a, S, &'a mut Exporter>;

impl Tap for &mut Exporter {
    fn before_row<S: Sink + ?Sized>(
        &mut self,
        row: &Row<'_>,
        frame: Option<&Unframed<'_>>,
        _inner: &mut S,
    ) -> RowResult {
        self.frame(row, frame).map_err(|e| self.error(e))
    }
    fn flush(&mut self) -> Result<(), OutputError> {
        Exporter::flush(self)
    }
    fn set_anchor(&mut self, anchor: Option<Anchor>) {
        if self.anchor.is_none() {
            self.anchor = anchor.map(Anchor::as_utc);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcap::PcapStream;

    #[test]
    fn one_packet_per_frame_with_times_and_comments() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("e.pcapng");
        let mut ex = Exporter::create(&path, &crate::sport::PROTOCOL, "x.bin", "S.Port").unwrap();
        ex.anchor = Some(DateTime::from_timestamp_micros(1_000_000).unwrap());
        let raw = [0x7E, 0x22, 0x10, 0x10, 0x02, 0, 0, 0, 0, 0xDD];
        let mut row = Row::empty(Some(96_000));
        row.raw = &raw;
        ex.frame(&row, None).unwrap();
        ex.frame(&row, None).unwrap(); // the same bytes at the same time: another frame
        ex.frame(&Row::empty(Some(97_000)), None).unwrap(); // a note: no bytes
        let mut bad = Row::empty(Some(98_000));
        bad.raw = &raw[..4];
        bad.class = Class::Error;
        bad.kind = "BadCRC";
        ex.frame(&bad, None).unwrap();
        ex.flush().unwrap();
        assert_eq!(ex.packets(), 3);
        let bytes = std::fs::read(&path).unwrap();
        assert!(String::from_utf8_lossy(&bytes).contains("busnoop: BadCRC"));
        let mut got = Vec::new();
        let mut s = PcapStream::default();
        s.push(&bytes, &mut |p| {
            got.push((p.ts_micros, p.link_type, p.data.to_vec()))
        })
        .unwrap();
        assert_eq!(
            got,
            [
                (1_096_000, crate::pcap::linktype::USER0, raw.to_vec()),
                (1_096_000, crate::pcap::linktype::USER0, raw.to_vec()),
                (1_098_000, crate::pcap::linktype::USER0, raw[..4].to_vec()),
            ]
        );
    }

    #[test]
    fn names_and_protocols_checked() {
        use crate::pcap::linktype;
        let sport = &crate::sport::PROTOCOL;
        assert!(check(Path::new("a.pcapng"), sport).is_ok());
        assert_eq!(
            check(Path::new("a.PCAPNG"), &crate::sab::PROTOCOL)
                .unwrap()
                .linktype,
            linktype::USER1
        );
        assert!(matches!(
            check(Path::new("a.pcap"), sport),
            Err(Failure::Usage(_))
        ));
        assert_eq!(
            check(Path::new("a.pcapng"), &crate::sbus::PROTOCOL)
                .unwrap()
                .linktype,
            linktype::RAW
        );
    }
}
