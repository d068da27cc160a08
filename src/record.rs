//! Recordings: what came off the wire, kept while decoding (`--record FILE`). They are read
//! back by [`crate::source::recording`].
//!
//! * `FILE.pcap`: classic pcap, link type `RTAC_SERIAL` (250, [`crate::pcap::rtac`]), one record
//!   per read chunk with the chunk's arrival time, so a replay feeds the decoder exactly the bytes
//!   and times the live run saw and prints exactly the same rows. Each record carries the 12-byte
//!   RTAC serial header (time, event type, control lines), which Wireshark shows as "RTAC
//!   Serial". The first record (a status event, time 0 of the capture) marks the start; adapter
//!   unplug/replug are status events too.
//! * `FILE.pcapng`: the same RTAC serial records in pcapng: a section header naming busnoop, an
//!   interface description whose `if_name` is the device (or input file) and whose
//!   `if_description` names the protocol and baud rate, and one enhanced packet block per read
//!   chunk with its arrival time. Adapter unplug/replug records carry a comment (`opt_comment`)
//!   that Wireshark shows on the packet: where a reconnect gap starts and how long it lasted. It
//!   replays to the same rows as the `.pcap`.
//! * `FILE.bin` or `FILE.raw`: the raw bytes exactly as received, the same format as a raw
//!   capture (no times). So does a name without an extension that is a device or a FIFO
//!   (`/dev/null`); any other name is refused ([`RecordFormat::for_path`]), so that a typo never
//!   writes a format the user did not ask for.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use chrono::{DateTime, Utc};

use crate::exit::Failure;
use crate::pcap::{self, linktype, rtac};
use crate::time::Anchor;

/// The pcapng `if_description` of a line: `FrSky S.Port, 57600 baud 8N1`.
pub fn line_description(protocol: &str, line: &crate::protocol::Line) -> String {
    use crate::protocol::Parity;
    let parity = match line.parity {
        Parity::None => 'N',
        Parity::Odd => 'O',
        Parity::Even => 'E',
    };
    format!(
        "{protocol}, {} baud {}{parity}{}",
        line.baud, line.data_bits, line.stop_bits
    )
}

/// Writes a recording while the capture is decoded.
pub struct Recorder {
    /// `None` for standard output.
    path: Option<PathBuf>,
    out: BufWriter<Box<dyn Write>>,
    format: RecordFormat,
    timed: bool,
    anchor: Option<DateTime<Utc>>,
    /// The pcap record being written.
    scratch: Vec<u8>,
    /// The device (or input) and its description, for the pcapng interface block.
    interface: (Option<String>, Option<String>),
    /// When the adapter went away (µs of the capture), for the gap's comment.
    down_since: Option<u64>,
}

/// The format of a recording, from its file name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordFormat {
    Raw,
    Pcap,
    Pcapng,
}

/// The file names `--record` knows, for messages and help.
pub const KNOWN: &str = ".pcap (classic pcap with arrival times), .pcapng (pcapng with arrival \
                         times, device and baud), .bin or .raw (the raw bytes)";

impl RecordFormat {
    /// The format for `path` by its extension (any case); a name without an extension is raw
    /// bytes only when it is an existing device or FIFO (`/dev/null`). Anything else is a usage
    /// error naming the known extensions.
    pub fn for_path(path: &Path) -> Result<RecordFormat, Failure> {
        let ext = path.extension().and_then(|e| e.to_str());
        let is = |x: &str| ext.is_some_and(|e| e.eq_ignore_ascii_case(x));
        if is("pcap") {
            return Ok(RecordFormat::Pcap);
        }
        if is("pcapng") {
            return Ok(RecordFormat::Pcapng);
        }
        if is("bin") || is("raw") {
            return Ok(RecordFormat::Raw);
        }
        if ext.is_none() && std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
            return Ok(RecordFormat::Raw);
        }
        let what = match path.extension() {
            Some(e) => format!("the extension .{}", e.to_string_lossy()),
            None => "a name without an extension".to_string(),
        };
        Err(Failure::Usage(format!(
            "--record {}: {what} names no recording format; use {KNOWN}",
            path.display()
        )))
    }
}

impl Recorder {
    /// Creates the recording; `timed` says whether the source has arrival times.
    pub fn create(path: &Path, timed: bool) -> Result<Recorder, Failure> {
        let format = RecordFormat::for_path(path)?;
        let file = File::create(path).map_err(|e| {
            Failure::Output(format!("cannot create recording {}: {e}", path.display()))
        })?;
        Ok(Recorder {
            path: Some(path.to_owned()),
            out: BufWriter::with_capacity(64 * 1024, Box::new(file)),
            format,
            timed,
            anchor: None,
            scratch: Vec::new(),
            interface: (None, None),
            down_since: None,
        })
    }

    /// Records the raw bytes on standard output (`--record -`).
    pub fn stdout(timed: bool) -> Recorder {
        Recorder {
            path: None,
            out: BufWriter::with_capacity(64 * 1024, Box::new(io::stdout())),
            format: RecordFormat::Raw,
            timed,
            anchor: None,
            scratch: Vec::new(),
            interface: (None, None),
            down_since: None,
        }
    }

    /// Names the interface in a pcapng recording: `name` (the device path) becomes `if_name`,
    /// `description` (protocol and baud rate) `if_description`. Call before the first bytes.
    pub fn describe(&mut self, name: &str, description: &str) {
        self.interface = (Some(name.to_string()), Some(description.to_string()));
    }

    /// The recording's format.
    pub fn format(&self) -> RecordFormat {
        self.format
    }

    fn fail(&self, e: io::Error) -> Failure {
        match &self.path {
            Some(p) => Failure::Output(format!("cannot write recording {}: {e}", p.display())),
            None if e.kind() == io::ErrorKind::BrokenPipe => Failure::BrokenPipe,
            None => Failure::Output(format!(
                "cannot write the recording to standard output: {e}"
            )),
        }
    }

    /// The wall-clock time of the capture's start; writes the pcap headers.
    pub fn start(&mut self, anchor: Option<Anchor>) -> Result<(), Failure> {
        if self.anchor.is_some() {
            return Ok(());
        }
        let t = anchor.map_or_else(Utc::now, Anchor::as_utc);
        self.anchor = Some(t);
        let start = if self.timed {
            rtac::START
        } else {
            rtac::START_UNTIMED
        };
        let mut header = Vec::with_capacity(256);
        match self.format {
            RecordFormat::Raw => return Ok(()),
            RecordFormat::Pcap => {
                pcap::write::header_with_snaplen(&mut header, linktype::RTAC_SERIAL, 65_535)
            }
            RecordFormat::Pcapng => {
                pcap::write_ng::section_header(&mut header);
                pcap::write_ng::interface(
                    &mut header,
                    linktype::RTAC_SERIAL as u16,
                    self.interface.0.as_deref(),
                    self.interface.1.as_deref(),
                );
            }
        }
        self.out.write_all(&header).map_err(|e| self.fail(e))?;
        self.write_record(t, 0, rtac::EVENT_STATUS, start, None)?;
        Ok(())
    }

    /// Bytes that arrived at `micros`.
    pub fn data(&mut self, bytes: &[u8], micros: Option<u64>) -> Result<(), Failure> {
        self.start(None)?;
        let r = match self.format {
            RecordFormat::Raw => self.out.write_all(bytes),
            RecordFormat::Pcap | RecordFormat::Pcapng => {
                let anchor = self.anchor.unwrap_or_else(Utc::now);
                let micros = micros.unwrap_or(0);
                return self.write_record(anchor, micros, rtac::EVENT_RX_DATA, bytes, None);
            }
        };
        r.map_err(|e| self.fail(e))
    }

    /// The adapter went away (`up = false`) or came back.
    pub fn link(&mut self, up: bool, micros: u64) -> Result<(), Failure> {
        self.start(None)?;
        if self.format == RecordFormat::Raw {
            return Ok(());
        }
        let comment = if up {
            let gap = self.down_since.take().map(|d| micros.saturating_sub(d));
            match gap {
                Some(g) => format!(
                    "busnoop: the adapter is back; reconnect gap of {}.{:06} s ends (bytes sent \
                     on the bus meanwhile were not seen)",
                    g / 1_000_000,
                    g % 1_000_000
                ),
                None => "busnoop: the adapter is back; reconnect gap ends".to_string(),
            }
        } else {
            self.down_since = Some(micros);
            "busnoop: the adapter went away; reconnect gap begins".to_string()
        };
        let anchor = self.anchor.unwrap_or_else(Utc::now);
        let payload = if up { rtac::LINK_UP } else { rtac::LINK_DOWN };
        self.write_record(anchor, micros, rtac::EVENT_STATUS, payload, Some(&comment))
    }

    /// Writes one RTAC serial record at `micros` after `anchor` (in pcapng with `comment`).
    fn write_record(
        &mut self,
        anchor: DateTime<Utc>,
        micros: u64,
        event: u8,
        data: &[u8],
        comment: Option<&str>,
    ) -> Result<(), Failure> {
        let t = anchor + chrono::Duration::microseconds(micros as i64);
        let ts = t.timestamp_micros();
        self.scratch.clear();
        if self.format == RecordFormat::Pcapng {
            let mut body = Vec::with_capacity(rtac::HEADER_LEN + data.len());
            rtac::payload(&mut body, ts, event, data);
            pcap::write_ng::packet(&mut self.scratch, 0, ts, &body, comment);
        } else {
            rtac::record(&mut self.scratch, ts, event, data);
        }
        let r = self.out.write_all(&self.scratch);
        r.map_err(|e| self.fail(e))
    }

    /// Writes everything buffered to the file.
    pub fn flush(&mut self) -> Result<(), Failure> {
        self.out.flush().map_err(|e| self.fail(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_recording_is_the_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.bin");
        let mut rec = Recorder::create(&path, true).unwrap();
        rec.data(&[1, 2], Some(5)).unwrap();
        rec.link(false, 6).unwrap();
        rec.data(&[3], Some(7)).unwrap();
        rec.flush().unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), [1, 2, 3]);
    }

    #[test]
    fn formats_by_extension_and_unknown_names_refused() {
        let f = |n: &str| RecordFormat::for_path(Path::new(n));
        assert_eq!(f("a.pcap").unwrap(), RecordFormat::Pcap);
        assert_eq!(f("a.PCAPNG").unwrap(), RecordFormat::Pcapng);
        assert_eq!(f("a.bin").unwrap(), RecordFormat::Raw);
        assert_eq!(f("a.Raw").unwrap(), RecordFormat::Raw);
        assert_eq!(f("/dev/null").unwrap(), RecordFormat::Raw);
        for bad in ["a.txt", "a.pcapn", "/nonexistent/recording"] {
            let Err(Failure::Usage(m)) = f(bad) else {
                panic!("{bad} accepted")
            };
            assert!(
                m.contains(".pcap (") && m.contains(".pcapng") && m.contains(".raw"),
                "{m}"
            );
        }
        assert!(Recorder::create(&std::env::temp_dir().join("busnoop-x.txt"), true).is_err());
    }

    #[test]
    fn pcapng_names_the_interface_and_comments_the_gap() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.pcapng");
        let mut rec = Recorder::create(&path, true).unwrap();
        rec.describe("/dev/ttyUSB0", "FrSky S.Port, 57600 baud 8N1");
        rec.start(None).unwrap();
        rec.data(&[0x7E, 0x1B], Some(5)).unwrap();
        rec.link(false, 1_000).unwrap();
        rec.link(true, 2_501_000).unwrap();
        rec.flush().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains("/dev/ttyUSB0") && text.contains("57600 baud"));
        assert!(text.contains("reconnect gap begins"), "{text}");
        assert!(text.contains("reconnect gap of 2.500000 s ends"), "{text}");
        assert_eq!(pcap::pcapng_link_type(&bytes), Some(linktype::RTAC_SERIAL));
        let mut got = Vec::new();
        let mut s = pcap::PcapStream::default();
        s.push(&bytes, &mut |p| {
            got.push(rtac::parse(p.data).map(|(e, _, d)| (e, d.to_vec())))
        })
        .unwrap();
        assert_eq!(
            got,
            [
                Some((rtac::EVENT_STATUS, rtac::START.to_vec())),
                Some((rtac::EVENT_RX_DATA, vec![0x7E, 0x1B])),
                Some((rtac::EVENT_STATUS, rtac::LINK_DOWN.to_vec())),
                Some((rtac::EVENT_STATUS, rtac::LINK_UP.to_vec())),
            ]
        );
    }
}
