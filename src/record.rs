//! Recordings: what came off the wire, kept while decoding (`--record FILE`), and replayed later.
//!
//! * `FILE.pcap`: classic pcap, link type `RTAC_SERIAL` (250), one record per read chunk with the
//!   chunk's arrival time, so a replay feeds the decoder exactly the bytes and times the live run
//!   saw and prints exactly the same rows. Each record carries the 12-byte RTAC serial header
//!   (time, event type, control lines), which Wireshark shows as "RTAC Serial". The first record
//!   (a status event, time 0 of the capture) marks the start; adapter unplug/replug are status
//!   events too. Link type `USER0` (147, raw bytes per record) is read as well.
//! * any other name (`FILE.bin` recommended): the raw bytes exactly as received, the same format
//!   as a raw capture.

use std::fs::File;
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::SyncSender;

use chrono::{DateTime, Utc};

use crate::exit::Failure;
use crate::time::Anchor;
use crate::source::{Batch, ChunkReader, Message, Opened};

/// pcap link type of the RTAC serial encapsulation.
pub const LINKTYPE_RTAC_SERIAL: u32 = 250;
/// pcap link type USER0 (raw bytes per record).
pub const LINKTYPE_USER0: u32 = 147;

/// RTAC serial event types (as Wireshark's `rtacser` dissector names them). Every record starts
/// with a 12-byte header: the arrival time (seconds and microseconds, big-endian), the event
/// type, the control lines (CTS 0x01, DCD 0x02, DSR 0x04, RTS 0x08, DTR 0x10, RING 0x20,
/// MBOK 0x40) and a 2-byte footer; the bytes of the line follow.
const EVENT_STATUS: u8 = 0x00;
const EVENT_TX_START: u8 = 0x01;
const EVENT_RX_DATA: u8 = 0x02;
const EVENT_RX_END: u8 = 0x04;
const EVENT_DATA_LOST: u8 = 0x05;
const EVENT_OVERFLOW: u8 = 0x0A;

/// What an event other than data means, for its row.
fn event_name(event: u8) -> Option<&'static str> {
    Some(match event {
        0x05 => "the capture device lost data here (CAPTURE_DATA_LOST)",
        0x06 => "the capture device ended the capture (CAPTURE_COMPLETE)",
        0x07 => "framing error (FRAMING_ERROR)",
        0x08 => "parity error (PARITY_ERROR)",
        0x09 => "break on the line (SERIAL_BREAK_EVENT)",
        0x0A => "the capture device's buffer overflowed (SERIAL_OVERFLOW_EVENT)",
        _ => return None,
    })
}

/// The control lines byte as text: `CTS /DCD …`.
fn control_lines(bits: u8) -> String {
    const NAMES: [&str; 7] = ["CTS", "DCD", "DSR", "RTS", "DTR", "RING", "MBOK"];
    let mut s = String::new();
    for (i, n) in NAMES.iter().enumerate() {
        if !s.is_empty() {
            s.push(' ');
        }
        if bits & (1 << i) == 0 {
            s.push('/');
        }
        s.push_str(n);
    }
    s
}

/// Payloads of the status records busnoop writes.
const START: &[u8] = b"busnoop capture start";
const START_UNTIMED: &[u8] = b"busnoop capture start (untimed)";
const LINK_DOWN: &[u8] = b"busnoop link down";
const LINK_UP: &[u8] = b"busnoop link up";

/// Writes a recording while the capture is decoded.
pub struct Recorder {
    /// `None` for standard output.
    path: Option<PathBuf>,
    out: BufWriter<Box<dyn Write>>,
    format: RecordFormat,
    timed: bool,
    anchor: Option<DateTime<Utc>>,
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
            let r = write_global_header(&mut self.out).and_then(|()| {
                let start = if self.timed { START } else { START_UNTIMED };
                write_record(&mut self.out, t, 0, EVENT_STATUS, start)
            });
            r.map_err(|e| self.fail(e))?;
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
                write_record(
                    &mut self.out,
                    anchor,
                    micros.unwrap_or(0),
                    EVENT_RX_DATA,
                    bytes,
                )
            }
        };
        r.map_err(|e| self.fail(e))
    }

    /// The adapter went away (`up = false`) or came back.
    pub fn link(&mut self, up: bool, micros: u64) -> Result<(), Failure> {
        self.start(None)?;
        if self.format == RecordFormat::Pcap {
            let anchor = self.anchor.unwrap_or_else(Utc::now);
            let payload = if up { LINK_UP } else { LINK_DOWN };
            write_record(&mut self.out, anchor, micros, EVENT_STATUS, payload)
                .map_err(|e| self.fail(e))?;
        }
        Ok(())
    }

    /// Writes everything buffered to the file.
    pub fn flush(&mut self) -> Result<(), Failure> {
        self.out.flush().map_err(|e| self.fail(e))
    }
}

fn write_global_header(w: &mut impl Write) -> io::Result<()> {
    let mut h = Vec::with_capacity(24);
    h.extend_from_slice(&0xA1B2_C3D4u32.to_le_bytes()); // microsecond timestamps
    h.extend_from_slice(&2u16.to_le_bytes());
    h.extend_from_slice(&4u16.to_le_bytes());
    h.extend_from_slice(&0i32.to_le_bytes());
    h.extend_from_slice(&0u32.to_le_bytes());
    h.extend_from_slice(&65_535u32.to_le_bytes());
    h.extend_from_slice(&LINKTYPE_RTAC_SERIAL.to_le_bytes());
    w.write_all(&h)
}

/// One pcap record: the RTAC serial header (time, event, control lines, footer) then `data`.
fn write_record(
    w: &mut impl Write,
    anchor: DateTime<Utc>,
    micros: u64,
    event: u8,
    data: &[u8],
) -> io::Result<()> {
    let t = anchor + chrono::Duration::microseconds(micros as i64);
    let secs = t.timestamp() as u32;
    let usecs = t.timestamp_subsec_micros();
    let len = (12 + data.len()) as u32;
    let mut rec = Vec::with_capacity(16 + 12 + data.len());
    rec.extend_from_slice(&secs.to_le_bytes());
    rec.extend_from_slice(&usecs.to_le_bytes());
    rec.extend_from_slice(&len.to_le_bytes());
    rec.extend_from_slice(&len.to_le_bytes());
    rec.extend_from_slice(&secs.to_be_bytes());
    rec.extend_from_slice(&usecs.to_be_bytes());
    rec.push(event);
    rec.push(0); // control lines unknown
    rec.extend_from_slice(&[0, 0]); // footer
    rec.extend_from_slice(data);
    w.write_all(&rec)
}

/// The link type of a classic pcap file from its first 24 bytes.
pub fn pcap_link_type(header: &[u8]) -> Option<u32> {
    let magic: [u8; 4] = header.get(..4)?.try_into().ok()?;
    let lt: [u8; 4] = header.get(20..24)?.try_into().ok()?;
    match magic {
        [0xD4, 0xC3, 0xB2, 0xA1] | [0x4D, 0x3C, 0xB2, 0xA1] => Some(u32::from_le_bytes(lt)),
        [0xA1, 0xB2, 0xC3, 0xD4] | [0xA1, 0xB2, 0x3C, 0x4D] => Some(u32::from_be_bytes(lt)),
        _ => None,
    }
}

/// Replays a busnoop recording (pcap, RTAC serial or USER0) as timed batches.
pub struct RecordingReader {
    reader: Box<dyn Read + Send>,
    name: String,
    /// Unparsed input is `buf[pos..]`.
    buf: Vec<u8>,
    pos: usize,
    /// Where reads land before they are appended to `buf`.
    scratch: Vec<u8>,
    eof: bool,
    header: Option<Header>,
    first: Option<i64>,
    untimed: bool,
    pending: Option<Message>,
    /// A failure met after some records were read; reported on the next call.
    failure: Option<Failure>,
    /// Records that are not data, shown as rows and counted for the summary warning.
    counts: EventCounts,
}

/// RTAC serial records that are not line data, by kind.
#[derive(Default)]
struct EventCounts {
    short: u64,
    lost: u64,
    line: u64,
    status: u64,
    unknown: u64,
}

impl EventCounts {
    /// `2 line events (framing/parity errors, breaks), 1 short record`, or `None`.
    fn summary(&self) -> Option<String> {
        use crate::exit::count;
        let parts: Vec<String> = [
            (self.lost, "data-lost event", "data-lost events"),
            (
                self.line,
                "line event (framing/parity error, break, end)",
                "line events (framing/parity errors, breaks, end)",
            ),
            (self.status, "status change", "status changes"),
            (
                self.unknown,
                "event of an unknown type",
                "events of unknown types",
            ),
            (
                self.short,
                "record shorter than its 12-byte header",
                "records shorter than their 12-byte header",
            ),
        ]
        .iter()
        .filter(|(n, ..)| *n > 0)
        .map(|&(n, one, many)| count(n, one, many))
        .collect();
        (!parts.is_empty()).then(|| parts.join(", "))
    }
}

#[derive(Clone, Copy)]
struct Header {
    little: bool,
    nanos: bool,
    link_type: u32,
}

/// Records larger than this are not busnoop recordings; stop instead of allocating.
const MAX_RECORD: usize = 1 << 20;

impl RecordingReader {
    pub fn new(opened: Opened) -> Self {
        RecordingReader {
            reader: opened.reader,
            name: opened.name,
            buf: opened.prefix,
            pos: 0,
            scratch: vec![0; 64 * 1024],
            eof: false,
            header: None,
            first: None,
            untimed: false,
            pending: None,
            failure: None,
            counts: EventCounts::default(),
        }
    }

    fn bad(&self, what: &str) -> Failure {
        Failure::Input(format!("{}: {what}", self.name))
    }

    /// Makes at least `n` unread bytes available; false at the end of the input.
    fn want(&mut self, n: usize) -> Result<bool, Failure> {
        while self.buf.len() - self.pos < n {
            if self.eof {
                return Ok(false);
            }
            if self.pos > 0 {
                self.buf.drain(..self.pos);
                self.pos = 0;
            }
            match self.reader.read(&mut self.scratch) {
                Ok(k) => {
                    self.buf.extend_from_slice(&self.scratch[..k]);
                    self.eof = k == 0;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(self.bad(&format!("cannot read: {e}"))),
            }
        }
        Ok(true)
    }

    fn u32_at(&self, at: usize, little: bool) -> u32 {
        let b: [u8; 4] = self.buf[at..at + 4].try_into().unwrap();
        if little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        }
    }

    /// Whether a read would block now (no unread bytes buffered).
    fn drained(&self) -> bool {
        self.pos >= self.buf.len()
    }
}

impl ChunkReader for RecordingReader {
    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Batch>, Failure> {
        if let Some(f) = self.failure.take() {
            self.summary(tx);
            return Err(f);
        }
        if let Some(m) = self.pending.take() {
            let _ = tx.send(m);
        }
        let mut batch = Batch::default();
        match self.fill(tx, &mut batch) {
            Ok(()) if !batch.bytes.is_empty() => Ok(Some(batch)),
            Ok(()) => {
                self.summary(tx);
                Ok(None)
            }
            // Hand out what was read before the failure; report the failure next time.
            Err(f) if !batch.bytes.is_empty() => {
                self.failure = Some(f);
                Ok(Some(batch))
            }
            Err(f) => {
                self.summary(tx);
                Err(f)
            }
        }
    }
}

impl RecordingReader {
    /// Adds records to `batch` until it is worth sending, a status event must go out first, or
    /// the input ends.
    fn fill(&mut self, tx: &SyncSender<Message>, batch: &mut Batch) -> Result<(), Failure> {
        if self.header.is_none() {
            if !self.want(24)? {
                return Err(self.bad("truncated pcap header"));
            }
            let h = &self.buf[self.pos..self.pos + 24];
            let link_type = pcap_link_type(h).ok_or_else(|| self.bad("not a pcap file"))?;
            let little = matches!(h[0], 0xD4 | 0x4D);
            let nanos = matches!(h[..4], [0x4D, 0x3C, 0xB2, 0xA1] | [0xA1, 0xB2, 0x3C, 0x4D]);
            self.header = Some(Header {
                little,
                nanos,
                link_type,
            });
            self.pos += 24;
        }
        let h = self.header.unwrap();
        loop {
            if !batch.bytes.is_empty() && (self.drained() || batch.bytes.len() >= 64 * 1024) {
                return Ok(());
            }
            if !self.want(16)? {
                if self.buf.len() > self.pos {
                    let _ = tx.send(Message::Warning(format!(
                        "{}: the recording ends inside a record header ({} bytes ignored)",
                        self.name,
                        self.buf.len() - self.pos
                    )));
                    self.pos = self.buf.len();
                }
                return Ok(());
            }
            let secs = self.u32_at(self.pos, h.little) as i64;
            let frac = self.u32_at(self.pos + 4, h.little) as i64;
            let incl = self.u32_at(self.pos + 8, h.little) as usize;
            if incl > MAX_RECORD {
                return Err(self.bad(&format!("record of {incl} bytes: not a busnoop recording")));
            }
            if !self.want(16 + incl)? {
                let _ = tx.send(Message::Warning(format!(
                    "{}: the last record is cut short ({} of {incl} bytes), ignored",
                    self.name,
                    self.buf.len() - self.pos - 16
                )));
                self.pos = self.buf.len();
                return Ok(());
            }
            let micros_abs = secs * 1_000_000 + if h.nanos { frac / 1000 } else { frac };
            let record_at = self.pos;
            let start = self.pos + 16;
            self.pos = start + incl;
            let first = *self.first.get_or_insert_with(|| {
                let t = DateTime::from_timestamp_micros(micros_abs).unwrap_or_default();
                let _ = tx.send(Message::Anchor(Anchor::Instant(t)));
                micros_abs
            });
            let micros = (micros_abs - first).max(0) as u64;
            let record = &self.buf[start..start + incl];
            let (event, lines, payload) = match h.link_type {
                LINKTYPE_RTAC_SERIAL if record.len() >= 12 => (record[8], record[9], &record[12..]),
                LINKTYPE_RTAC_SERIAL => (SHORT_RECORD, 0, &[][..]),
                _ => (EVENT_RX_DATA, 0, record),
            };
            let note = self.note_for(event, lines, payload, micros);
            if let Some(note) = note {
                if !batch.bytes.is_empty() {
                    // The row goes between the bytes before and after: send these first and
                    // read the record again next time.
                    self.pos = record_at;
                    return Ok(());
                }
                self.counts.add(event);
                let _ = tx.send(note);
            }
            match event {
                EVENT_TX_START..=EVENT_RX_END => {
                    let time = (!self.untimed).then_some(micros);
                    if batch.marks.last().map(|m| m.1) != Some(time) {
                        batch.marks.push((batch.bytes.len(), time));
                    }
                    batch.bytes.extend_from_slice(payload);
                }
                EVENT_STATUS => {
                    let msg = match payload {
                        START_UNTIMED => {
                            self.untimed = true;
                            None
                        }
                        LINK_DOWN => Some(Message::LinkDown { micros }),
                        LINK_UP => Some(Message::LinkUp {
                            micros,
                            path: PathBuf::from(&self.name),
                        }),
                        _ => None,
                    };
                    if let Some(m) = msg {
                        if batch.bytes.is_empty() {
                            let _ = tx.send(m);
                        } else {
                            self.pending = Some(m);
                            return Ok(());
                        }
                    }
                }
                // Line events (framing/parity errors, breaks, lost data) are rows; bytes
                // they carry (a character received with a framing error) are still line data.
                _ if !payload.is_empty() && event != SHORT_RECORD => {
                    let time = (!self.untimed).then_some(micros);
                    batch.marks.push((batch.bytes.len(), time));
                    batch.bytes.extend_from_slice(payload);
                }
                _ => {}
            }
        }
    }

    /// At the end: how many records were not data (each was a row).
    fn summary(&mut self, tx: &SyncSender<Message>) {
        if let Some(s) = std::mem::take(&mut self.counts).summary() {
            let _ = tx.send(Message::Warning(format!(
                "{}: {s}; each is a row in the table",
                self.name
            )));
        }
    }

    /// The row for a record that is not plain data (or busnoop's own status records).
    fn note_for(&self, event: u8, lines: u8, payload: &[u8], micros: u64) -> Option<Message> {
        use crate::row::Class;
        let micros = (!self.untimed).then_some(micros);
        let (kind, class, data, gap) = match event {
            EVENT_TX_START..=EVENT_RX_END => return None,
            EVENT_STATUS => match payload {
                START | START_UNTIMED | LINK_DOWN | LINK_UP => return None,
                _ => (
                    "Status",
                    Class::Info,
                    format!("control lines {}", control_lines(lines)),
                    false,
                ),
            },
            SHORT_RECORD => (
                "BadRecord",
                Class::Error,
                "RTAC serial record shorter than its 12-byte header".to_string(),
                false,
            ),
            EVENT_DATA_LOST | EVENT_OVERFLOW => (
                "DataLost",
                Class::Error,
                event_name(event).unwrap_or_default().to_string(),
                true,
            ),
            _ => match event_name(event) {
                Some(name) => ("LineEvent", Class::Warning, name.to_string(), false),
                None => (
                    "LineEvent",
                    Class::Warning,
                    format!("RTAC serial event of unknown type 0x{event:02X}"),
                    false,
                ),
            },
        };
        Some(Message::Note {
            micros,
            kind,
            class,
            data,
            gap,
        })
    }
}

impl EventCounts {
    fn add(&mut self, event: u8) {
        let c = self;
        match event {
            SHORT_RECORD => c.short += 1,
            EVENT_DATA_LOST | EVENT_OVERFLOW => c.lost += 1,
            EVENT_STATUS => c.status += 1,
            _ if event_name(event).is_some() => c.line += 1,
            _ => c.unknown += 1,
        }
    }
}

/// Stands for a record too short for the RTAC serial header (not a real event type).
const SHORT_RECORD: u8 = 0xFF;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn link_type_from_header() {
        let mut out = Vec::new();
        write_global_header(&mut out).unwrap();
        assert_eq!(pcap_link_type(&out), Some(LINKTYPE_RTAC_SERIAL));
        let mut be = vec![0xA1, 0xB2, 0xC3, 0xD4];
        be.extend_from_slice(&[0; 16]);
        be.extend_from_slice(&1u32.to_be_bytes());
        assert_eq!(pcap_link_type(&be), Some(1));
        assert_eq!(pcap_link_type(b"hello"), None);
    }

    fn replay(bytes: Vec<u8>) -> Vec<Message> {
        let opened = Opened {
            kind: crate::protocol::Kind::Recording,
            prefix: Vec::new(),
            reader: Box::new(io::Cursor::new(bytes)),
            name: "rec.pcap".into(),
        };
        let (tx, rx) = std::sync::mpsc::sync_channel(1000);
        let mut r = RecordingReader::new(opened);
        while let Some(b) = r.next_batch(&tx).unwrap() {
            tx.send(Message::Data(b)).unwrap();
        }
        drop(tx);
        rx.iter().collect()
    }

    #[test]
    fn record_and_replay_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.pcap");
        let anchor: DateTime<Utc> = "2026-01-02T03:04:05.678901Z".parse().unwrap();
        let mut rec = Recorder::create(&path, true).unwrap();
        rec.start(Some(Anchor::Instant(anchor))).unwrap();
        rec.data(&[0x7E, 0x00], Some(1_000)).unwrap();
        rec.data(&[0x7E, 0xA1], Some(13_000)).unwrap();
        rec.link(false, 20_000).unwrap();
        rec.link(true, 3_020_000).unwrap();
        rec.data(&[0x7E, 0x22], Some(3_030_000)).unwrap();
        rec.flush().unwrap();
        let msgs = replay(std::fs::read(&path).unwrap());
        let mut data = Vec::new();
        let mut links = Vec::new();
        for m in &msgs {
            match m {
                Message::Anchor(Anchor::Instant(t)) => assert_eq!(*t, anchor),
                Message::Data(b) => {
                    for (bytes, t) in b.segments() {
                        data.push((bytes.to_vec(), t));
                    }
                }
                Message::LinkDown { micros } => links.push((false, *micros, data.len())),
                Message::LinkUp { micros, .. } => links.push((true, *micros, data.len())),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(
            data,
            [
                (vec![0x7E, 0x00], Some(1_000)),
                (vec![0x7E, 0xA1], Some(13_000)),
                (vec![0x7E, 0x22], Some(3_030_000))
            ]
        );
        assert_eq!(links, [(false, 20_000, 2), (true, 3_020_000, 2)]);
    }

    #[test]
    fn untimed_sources_replay_untimed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.pcap");
        let mut rec = Recorder::create(&path, false).unwrap();
        rec.data(&[0x7E, 0x00], None).unwrap();
        rec.flush().unwrap();
        let msgs = replay(std::fs::read(&path).unwrap());
        let seg: Vec<_> = msgs
            .iter()
            .filter_map(|m| match m {
                Message::Data(b) => Some(b.marks.clone()),
                _ => None,
            })
            .collect();
        assert_eq!(seg, [vec![(0, None)]]);
    }

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
    fn foreign_rtac_serial_captures_show_every_record() {
        // A capture another tool wrote: data in DATA_RX_END records, no busnoop start record,
        // a record too short for its header, line events, lost data, an unknown event type and
        // a status change with control lines.
        let anchor: DateTime<Utc> = "2026-01-02T03:04:05Z".parse().unwrap();
        let mut f = Vec::new();
        write_global_header(&mut f).unwrap();
        write_record(&mut f, anchor, 0, 0x04, &[0x7E, 0xA1]).unwrap();
        let t = anchor.timestamp() as u32;
        f.extend_from_slice(&t.to_le_bytes());
        f.extend_from_slice(&1000u32.to_le_bytes());
        f.extend_from_slice(&5u32.to_le_bytes());
        f.extend_from_slice(&5u32.to_le_bytes());
        f.extend_from_slice(&[1, 2, 3, 4, 5]);
        write_record(&mut f, anchor, 2000, 0x07, &[]).unwrap();
        write_record(&mut f, anchor, 3000, 0x05, &[]).unwrap();
        write_record(&mut f, anchor, 4000, 0x33, &[]).unwrap();
        let mut status = Vec::new();
        write_record(&mut status, anchor, 5000, EVENT_STATUS, &[]).unwrap();
        status[16 + 9] = 0x19; // CTS, RTS, DTR
        f.extend_from_slice(&status);
        write_record(&mut f, anchor, 6000, 0x02, &[0x7E, 0x22]).unwrap();
        let msgs = replay(f);
        let mut seen = Vec::new();
        let mut warning = None;
        for m in &msgs {
            match m {
                Message::Anchor(_) => {}
                Message::Data(b) => seen.push(format!("data {:?} {:?}", b.bytes, b.marks)),
                Message::Note {
                    micros,
                    kind,
                    class,
                    data,
                    gap,
                } => seen.push(format!("{kind} {micros:?} {class:?} {gap} {data}")),
                Message::Warning(w) => warning = Some(w.clone()),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(
            seen,
            [
                "data [126, 161] [(0, Some(0))]",
                "BadRecord Some(1000) Error false RTAC serial record shorter than its 12-byte header",
                "LineEvent Some(2000) Warning false framing error (FRAMING_ERROR)",
                "DataLost Some(3000) Error true the capture device lost data here (CAPTURE_DATA_LOST)",
                "LineEvent Some(4000) Warning false RTAC serial event of unknown type 0x33",
                "Status Some(5000) Info false control lines CTS /DCD /DSR RTS DTR /RING /MBOK",
                "data [126, 34] [(0, Some(6000))]",
            ]
        );
        assert_eq!(
            warning.as_deref(),
            Some(
                "rec.pcap: 1 data-lost event, 1 line event (framing/parity error, break, end), \
                 1 status change, 1 event of an unknown type, 1 record shorter than its 12-byte \
                 header; each is a row in the table"
            )
        );
    }
}
