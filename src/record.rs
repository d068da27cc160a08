//! Recordings: what came off the wire, kept while decoding (`--record FILE`). They are read
//! back by [`crate::source::recording`].
//!
//! * `FILE.pcap`: classic pcap, link type `RTAC_SERIAL` (250, [`crate::pcap::rtac`]), one record
//!   per read chunk with the chunk's arrival time, so a replay feeds the decoder exactly the bytes
//!   and times the live run saw and prints exactly the same rows. Each record carries the 12-byte
//!   RTAC serial header (time, event type, control lines), which Wireshark shows as "RTAC
//!   Serial". The first record (a status event, time 0 of the capture) marks the start; adapter
//!   unplug/replug are status events too.
//! * any other name (`FILE.bin` recommended): the raw bytes exactly as received, the same format
//!   as a raw capture.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use chrono::{DateTime, Utc};

use crate::exit::Failure;
use crate::pcap::{self, linktype, rtac};
use crate::time::Anchor;

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
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RecordFormat {
    Raw,
    Pcap,
}

impl Recorder {
    /// Creates the recording; `timed` says whether the source has arrival times.
    pub fn create(path: &Path, timed: bool) -> Result<Recorder, Failure> {
        let format = match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("pcap") => RecordFormat::Pcap,
            _ => RecordFormat::Raw,
        };
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
        }
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
        let t = match anchor {
            Some(Anchor::Instant(t)) => t,
            Some(Anchor::Naive(n)) => n.and_utc(),
            None => Utc::now(),
        };
        self.anchor = Some(t);
        if self.format == RecordFormat::Pcap {
            let start = if self.timed {
                rtac::START
            } else {
                rtac::START_UNTIMED
            };
            let mut header = Vec::with_capacity(24);
            pcap::write::header_with_snaplen(&mut header, linktype::RTAC_SERIAL, 65_535);
            self.out.write_all(&header).map_err(|e| self.fail(e))?;
            self.write_record(t, 0, rtac::EVENT_STATUS, start)?;
        }
        Ok(())
    }

    /// Bytes that arrived at `micros`.
    pub fn data(&mut self, bytes: &[u8], micros: Option<u64>) -> Result<(), Failure> {
        self.start(None)?;
        let r = match self.format {
            RecordFormat::Raw => self.out.write_all(bytes),
            RecordFormat::Pcap => {
                let anchor = self.anchor.unwrap_or_else(Utc::now);
                return self.write_record(anchor, micros.unwrap_or(0), rtac::EVENT_RX_DATA, bytes);
            }
        };
        r.map_err(|e| self.fail(e))
    }

    /// The adapter went away (`up = false`) or came back.
    pub fn link(&mut self, up: bool, micros: u64) -> Result<(), Failure> {
        self.start(None)?;
        if self.format == RecordFormat::Pcap {
            let anchor = self.anchor.unwrap_or_else(Utc::now);
            let payload = if up { rtac::LINK_UP } else { rtac::LINK_DOWN };
            self.write_record(anchor, micros, rtac::EVENT_STATUS, payload)?;
        }
        Ok(())
    }

    /// Writes one RTAC serial record at `micros` after `anchor`.
    fn write_record(
        &mut self,
        anchor: DateTime<Utc>,
        micros: u64,
        event: u8,
        data: &[u8],
    ) -> Result<(), Failure> {
        let t = anchor + chrono::Duration::microseconds(micros as i64);
        self.scratch.clear();
        rtac::record(&mut self.scratch, t.timestamp_micros(), event, data);
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
}
