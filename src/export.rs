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
//!   Ether-S-Bus datagram a PCD would have sent over UDP (see [`SbusWrap`]), decoded by
//!   Wireshark's own `sbus` dissector.
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
use crate::pcap::{linktype, write, write_ng};
use crate::row::{Class, OutputError, Row, RowResult, Unframed};
use crate::sbus::telegram::{self, AT_REQUEST};
use crate::sink::{Output, Sink, Tap, Tapped};
use crate::time::Anchor;

/// LINKTYPE_USER1: SAB frames.
pub const USER1: u32 = 148;

/// Protocols the export knows, by command: (link type, dissector).
pub fn link_for(command: &str) -> Option<(u32, &'static str)> {
    match command {
        "sport" => Some((linktype::USER0, "busnoop-sport.lua")),
        "sab2" => Some((USER1, "busnoop-sab.lua")),
        "sbus" => Some((linktype::RAW, "sbus (Wireshark's own)")),
        _ => None,
    }
}

/// Serial S-Bus telegrams as Ether-S-Bus datagrams (docs/wireshark.md, "Serial S-Bus as
/// Ether-S-Bus"):
///
/// * addresses: station N is 10.0.0.N, UDP port 5050 (broadcast 255 is 10.0.0.255); the master
///   is [`MASTER`] (10.0.1.254, outside 10.0.0.0/24 so that no station shares it), port 5050;
///   a request goes master → station, an answer station → master; an answer busnoop could not
///   pair with a request (so its station is unknown) and bytes that are no telegram come from
///   [`UNKNOWN`] (0.0.0.0);
/// * the Ether-S-Bus header: length, version 0, protocol type 0, a sequence number that
///   increases with every request to the station (from [`FIRST_SEQ`], one count per station,
///   as each station is a conversation of its own; a retry keeps its request's number, as an
///   Ether-S-Bus client does, so Wireshark marks it) and is repeated in the answers;
/// * the telegram as the decoder re-read it (DLE pairs undone, no secure header, no break) and
///   a CRC-16 over the datagram, computed afresh; for a telegram whose serial CRC failed, the
///   received CRC bytes instead, so that Wireshark shows the checksum as bad (inverted in the
///   rare case that they happen to fit the datagram);
/// * bytes that are no telegram (garbage, a cut telegram, an unknown attribute): a datagram of
///   those bytes as they were on the wire, from [`UNKNOWN`], with busnoop's verdict as comment.
#[derive(Clone, Debug)]
pub struct SbusWrap {
    /// The sequence number of each station's last request (its conversation), when there was
    /// one.
    seqs: Box<[Option<u16>; 256]>,
    /// The last request's.
    last: Option<u16>,
    payload: Vec<u8>,
}

impl Default for SbusWrap {
    fn default() -> Self {
        SbusWrap {
            seqs: Box::new([None; 256]),
            last: None,
            payload: Vec::new(),
        }
    }
}

/// The master's address in the S-Bus export.
pub const MASTER: [u8; 4] = [10, 0, 1, 254];
/// The address of unknown senders in the S-Bus export.
pub const UNKNOWN: [u8; 4] = [0, 0, 0, 0];
/// The Ether-S-Bus UDP port.
pub const SBUS_PORT: u16 = 5050;
/// The first sequence number: Wireshark's PANA heuristic takes Ether-S-Bus datagrams with
/// sequence numbers 1-4 for PANA, so the numbers stay clear of them.
pub const FIRST_SEQ: u16 = 0x0100;

/// The address of station `n` in the S-Bus export.
pub fn station_address(n: u8) -> [u8; 4] {
    [10, 0, 0, n]
}

impl SbusWrap {
    /// The IPv4/UDP packet of `row` into `out`.
    fn packet(&mut self, row: &Row<'_>, unframed: Option<&Unframed<'_>>, out: &mut Vec<u8>) {
        let Some((&at, tele)) = unframed.and_then(|u| u.bytes.split_first()) else {
            // Bytes that are no telegram: as they were.
            write::udp4_packet(out, (UNKNOWN, SBUS_PORT), (MASTER, SBUS_PORT), row.raw);
            return;
        };
        let seq = if at == AT_REQUEST {
            let station = tele.first().copied().unwrap_or(0) as usize;
            let seq = match self.seqs[station] {
                Some(s) if row.kind == "Retry" => s,
                Some(s) if s < u16::MAX => s + 1,
                _ => FIRST_SEQ,
            };
            self.seqs[station] = Some(seq);
            self.last = Some(seq);
            seq
        } else {
            let of_station = row
                .id
                .and_then(|i| self.seqs.get(i as usize).copied().flatten());
            of_station.or(self.last).unwrap_or(FIRST_SEQ)
        };
        self.payload.clear();
        telegram::encode_ether(&mut self.payload, seq, at, tele);
        if let Some(got) = unframed.and_then(|u| u.bad_check) {
            let n = self.payload.len();
            let fresh = u16::from_be_bytes([self.payload[n - 2], self.payload[n - 1]]);
            let crc = if got == fresh { got ^ 0x00FF } else { got };
            self.payload[n - 2..].copy_from_slice(&crc.to_be_bytes());
        }
        let station = |id: Option<u32>| match id.and_then(|i| u8::try_from(i).ok()) {
            Some(n) => station_address(n),
            None => UNKNOWN,
        };
        let (src, dst) = if at == AT_REQUEST {
            (MASTER, station(tele.first().map(|&s| s as u32)))
        } else {
            (station(row.id), MASTER)
        };
        write::udp4_packet(out, (src, SBUS_PORT), (dst, SBUS_PORT), &self.payload);
    }
}

/// Writes the export.
pub struct Exporter {
    path: PathBuf,
    /// Whole blocks only: a full disk leaves the file ending with its last whole block.
    out: Output,
    link_type: u32,
    interface: (String, String),
    /// Serial S-Bus: re-wrapped as Ether-S-Bus (otherwise the rows' bytes as they are).
    sbus: Option<SbusWrap>,
    /// The packet being written.
    packet: Vec<u8>,
    anchor: Option<DateTime<Utc>>,
    started: bool,
    /// The last packet's time and bytes: rows of one frame (several values) are one packet.
    last: Option<(Option<u64>, Vec<u8>)>,
    scratch: Vec<u8>,
    packets: u64,
}

impl Exporter {
    /// Checks `path` and `command` and creates the file; `name` and `description` name the
    /// pcapng interface (the source, the protocol and line).
    pub fn create(
        path: &Path,
        command: &str,
        name: &str,
        description: &str,
    ) -> Result<Exporter, Failure> {
        let (link_type, _) = check(path, command)?;
        let what = format!("cannot create export {}", path.display());
        let out = crate::sink::create_file(path)
            .and_then(|file| Output::file(file, path))
            .map_err(|e| Failure::from_create(&what, &e))?;
        Ok(Exporter {
            path: path.to_owned(),
            out,
            link_type,
            interface: (name.to_string(), description.to_string()),
            sbus: (command == "sbus").then(SbusWrap::default),
            packet: Vec::new(),
            anchor: None,
            started: false,
            last: None,
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

    /// The packet for `row`, when it carries bytes of a new frame; `unframed`: its content
    /// re-read, when the decoder gives it.
    fn frame(&mut self, row: &Row<'_>, unframed: Option<&Unframed<'_>>) -> io::Result<()> {
        if row.raw.is_empty() {
            return Ok(());
        }
        if let Some((t, bytes)) = &self.last
            && *t == row.micros
            && bytes[..] == *row.raw
        {
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
        let data = match &mut self.sbus {
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
        let last = self.last.get_or_insert_with(|| (None, Vec::new()));
        last.0 = row.micros;
        last.1.clear();
        last.1.extend_from_slice(row.raw);
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
/// an export. Returns the link type and the dissector.
pub fn check(path: &Path, command: &str) -> Result<(u32, &'static str), Failure> {
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
    link_for(command).ok_or_else(|| {
        Failure::Usage(format!(
            "--export is available for sport, sab2 and sbus; for {command}, record the wire \
             with --record FILE.pcapng"
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
        let mut ex = Exporter::create(&path, "sport", "x.bin", "S.Port").unwrap();
        ex.anchor = Some(DateTime::from_timestamp_micros(1_000_000).unwrap());
        let raw = [0x7E, 0x22, 0x10, 0x10, 0x02, 0, 0, 0, 0, 0xDD];
        let mut row = Row::empty(Some(96_000));
        row.raw = &raw;
        ex.frame(&row, None).unwrap();
        ex.frame(&row, None).unwrap(); // a second value of the same frame
        ex.frame(&Row::empty(Some(97_000)), None).unwrap(); // a note: no bytes
        let mut bad = Row::empty(Some(98_000));
        bad.raw = &raw[..4];
        bad.class = Class::Error;
        bad.kind = "BadCRC";
        ex.frame(&bad, None).unwrap();
        ex.flush().unwrap();
        assert_eq!(ex.packets(), 2);
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
                (1_096_000, linktype::USER0, raw.to_vec()),
                (1_098_000, linktype::USER0, raw[..4].to_vec()),
            ]
        );
    }

    #[test]
    fn sbus_telegrams_become_ether_sbus_datagrams() {
        let mut w = SbusWrap::default();
        let mut row = Row::empty(Some(0));
        let mut out = Vec::new();
        let udp = |out: &[u8]| {
            let Extract::Udp(u) = extract(linktype::RAW, out) else {
                panic!("{out:?}")
            };
            (u.src.to_string(), u.dst.to_string(), u.payload.to_vec())
        };
        use crate::sbus::ether::{Extract, extract, parse};
        // A request to station 7, its response, an unpaired response.
        let req = [0u8, 7, 6, 0, 0, 1];
        row.kind = "Request";
        let frame = |bytes, bad_check| Unframed { bytes, bad_check };
        w.packet(&row, Some(&frame(&req, None)), &mut out);
        let (src, dst, payload) = udp(&out);
        assert_eq!(
            (src.as_str(), dst.as_str()),
            ("10.0.1.254:5050", "10.0.0.7:5050")
        );
        let t = parse(&payload).unwrap();
        assert!(t.crc_ok());
        assert_eq!((t.seq, t.at, t.telegram), (FIRST_SEQ, 0, &req[1..]));
        out.clear();
        row.kind = "Response";
        row.id = Some(7);
        w.packet(&row, Some(&frame(&[1, 0, 0, 0, 9], None)), &mut out);
        let (src, _, payload) = udp(&out);
        assert_eq!(src, "10.0.0.7:5050");
        assert_eq!(parse(&payload).unwrap().seq, FIRST_SEQ);
        // A bad CRC stays bad, even when the bytes received happen to fit the datagram.
        let fresh = parse(&payload).unwrap().crc_want;
        for got in [0x1234, fresh] {
            out.clear();
            row.id = None;
            w.packet(&row, Some(&frame(&[1, 0, 0, 0, 9], Some(got))), &mut out);
            let (src, _, payload) = udp(&out);
            assert_eq!(src, "0.0.0.0:5050");
            assert!(!parse(&payload).unwrap().crc_ok());
        }
        // The next request to station 7 counts on; a retry keeps its number.
        for kind in ["Request", "Retry"] {
            out.clear();
            row.kind = kind;
            w.packet(&row, Some(&frame(&req, None)), &mut out);
            assert_eq!(parse(&udp(&out).2).unwrap().seq, FIRST_SEQ + 1);
        }
        // Bytes that are no telegram: as they were.
        out.clear();
        row.raw = &[0x11, 0x22];
        w.packet(&row, None, &mut out);
        assert_eq!(udp(&out).2, [0x11, 0x22]);
    }

    #[test]
    fn names_and_protocols_checked() {
        assert!(check(Path::new("a.pcapng"), "sport").is_ok());
        assert_eq!(check(Path::new("a.PCAPNG"), "sab2").unwrap().0, USER1);
        assert!(matches!(
            check(Path::new("a.pcap"), "sport"),
            Err(Failure::Usage(_))
        ));
        assert_eq!(
            check(Path::new("a.pcapng"), "sbus").unwrap().0,
            linktype::RAW
        );
        assert!(matches!(
            check(Path::new("a.pcapng"), "detect"),
            Err(Failure::Usage(_))
        ));
    }
}
