//! Replays a busnoop recording (classic pcap or pcapng, link type RTAC serial or USER0; see
//! [`crate::record`]) as timed byte batches, read with the shared [`PcapStream`]. Records of
//! other tools' RTAC serial captures that are not line data (line events, lost data, status
//! changes) become rows ([`Message::Note`]) at their place among the bytes.
//!
//! A recording of several ports (one interface per port, `busnoop PROTO SRC1 SRC2 --record
//! FILE.pcapng`) is read once per port, each reader keeping the records of its interface
//! ([`RecordingReader::interface`]); all of them take the capture's start from its first record,
//! so the ports share one clock as they did when recorded.

use std::io::{self, Read};
use std::path::PathBuf;
use std::sync::mpsc::SyncSender;

use super::{Batch, Chunk, ChunkReader, Message, Opened};
use crate::exit::Failure;
use crate::pcap::rtac::{
    self, EVENT_DATA_LOST, EVENT_OVERFLOW, EVENT_RX_DATA, EVENT_RX_END, EVENT_STATUS,
    EVENT_TX_START, LINK_DOWN, LINK_UP, START, START_UNTIMED,
};
use crate::pcap::{self, Packets, PcapError, PcapStream, linktype};

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

/// Records larger than this are not busnoop recordings; stop instead of allocating.
const MAX_RECORD: usize = 1 << 20;

/// A batch is handed on at the latest when it holds this many bytes.
const BATCH_BYTES: usize = 64 * 1024;

/// Replays a busnoop recording (pcap, RTAC serial or USER0) as timed batches.
pub struct RecordingReader {
    reader: Box<dyn Read + Send>,
    name: String,
    /// The file header, until it is whole.
    head: Vec<u8>,
    /// Its link type (all 32 bits), once read.
    link_type: Option<u32>,
    stream: PcapStream,
    /// Records parsed and not yet handed on: `records[next..]`.
    records: Packets,
    next: usize,
    /// The parser failed after `records`: reported when they are handed on.
    broken: Option<Failure>,
    /// Where reads land before they are parsed.
    scratch: Vec<u8>,
    eof: bool,
    anchored: bool,
    untimed: bool,
    /// The last record was stamped outside the calendar (a `TimeJump` row said so).
    out_of_range: bool,
    /// The bytes skipped before the current record were told (it may be taken twice).
    skip_told: bool,
    pending: Option<Message>,
    /// A failure met after some records were read; reported on the next call.
    failure: Option<Failure>,
    /// Records that are not data, shown as rows and counted for the summary warning.
    counts: EventCounts,
    /// Only the records of this interface (one port of a recording of several).
    only: Option<u32>,
    /// The interface of the first record, and whether a record of another was met (read as
    /// one line, the user is told once).
    first_interface: Option<u32>,
    mixed: bool,
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

impl RecordingReader {
    pub fn new(opened: Opened) -> Self {
        RecordingReader {
            reader: opened.reader,
            name: opened.name,
            head: opened.prefix,
            link_type: None,
            stream: PcapStream::with_max_record(MAX_RECORD),
            records: Packets::default(),
            next: 0,
            broken: None,
            scratch: vec![0; 64 * 1024],
            eof: false,
            anchored: false,
            untimed: false,
            out_of_range: false,
            skip_told: false,
            pending: None,
            failure: None,
            counts: EventCounts::default(),
            only: None,
            first_interface: None,
            mixed: false,
        }
    }

    /// Reads only the records of pcapng interface `interface` (a port of a recording of
    /// several), and the capture's start from the first record of any.
    pub fn interface(mut self, interface: u32) -> Self {
        self.only = Some(interface);
        self
    }

    fn bad(&self, what: &str) -> Failure {
        Failure::Input(format!("{}: {what}", self.name))
    }

    /// Reads once into the scratch buffer; 0 at the end of the input.
    fn read(&mut self) -> Result<usize, Failure> {
        loop {
            match self.reader.read(&mut self.scratch) {
                Ok(n) => {
                    self.eof = n == 0;
                    return Ok(n);
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(self.bad(&format!("cannot read: {e}"))),
            }
        }
    }

    /// Reads the file header and checks it is classic pcap.
    fn header(&mut self) -> Result<(), Failure> {
        while self.head.len() < 24 && !self.eof {
            let n = self.read()?;
            self.head.extend_from_slice(&self.scratch[..n]);
        }
        if self.head.len() < 24 {
            return Err(self.bad("truncated pcap header"));
        }
        // Classic pcap, or pcapng (`--record FILE.pcapng`) whose first interface is the line.
        let link_type = pcap::link_type(&self.head)
            .or_else(|| pcap::pcapng_link_type(&self.head))
            .ok_or_else(|| self.bad("not a pcap or pcapng file"))?;
        self.link_type = Some(link_type);
        let head = std::mem::take(&mut self.head);
        self.parse(&head);
        Ok(())
    }

    /// Parses `bytes` into `records`.
    fn parse(&mut self, bytes: &[u8]) {
        let records = &mut self.records;
        if let Err(e) = self.stream.push(bytes, &mut |p| records.push(&p)) {
            self.broken = Some(self.parse_failure(e));
        }
    }

    fn parse_failure(&self, e: PcapError) -> Failure {
        match e {
            PcapError::BadLength { len, .. } => {
                self.bad(&format!("record of {len} bytes: not a busnoop recording"))
            }
            e => self.bad(&e.to_string()),
        }
    }

    /// At the end of the input: a warning when it stopped inside a record, or had to skip
    /// damaged parts.
    fn end(&mut self, tx: &SyncSender<Message>) {
        let have = self.stream.buffered();
        let finished = self.stream.finish();
        if let Some(w) = super::skipped_warning(&self.name, self.stream.skipped()) {
            let _ = tx.send(w);
        }
        let Err(PcapError::Truncated { missing, .. }) = finished else {
            return;
        };
        let msg = if have < 16 {
            format!(
                "{}: the recording ends inside a record header ({have} bytes ignored)",
                self.name
            )
        } else {
            format!(
                "{}: the last record is cut short ({} of {} bytes), ignored",
                self.name,
                have - 16,
                have - 16 + missing as usize
            )
        };
        let _ = tx.send(Message::Warning(msg));
    }
}

impl ChunkReader for RecordingReader {
    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Chunk>, Failure> {
        if let Some(f) = self.failure.take() {
            self.summary(tx);
            return Err(f);
        }
        if let Some(m) = self.pending.take() {
            let _ = tx.send(m);
        }
        let mut batch = Batch::default();
        match self.fill(tx, &mut batch) {
            Ok(()) if !batch.bytes.is_empty() => Ok(Some(Chunk::Bytes(batch))),
            Ok(()) => {
                self.summary(tx);
                Ok(None)
            }
            // Hand out what was read before the failure; report the failure next time.
            Err(f) if !batch.bytes.is_empty() => {
                self.failure = Some(f);
                Ok(Some(Chunk::Bytes(batch)))
            }
            Err(f) => {
                self.summary(tx);
                Err(f)
            }
        }
    }
}

impl RecordingReader {
    /// Adds records to `batch` until it is worth sending (every record read so far is in it,
    /// or it is large), a status event must go out first, or the input ends.
    fn fill(&mut self, tx: &SyncSender<Message>, batch: &mut Batch) -> Result<(), Failure> {
        if self.link_type.is_none() {
            self.header()?;
        }
        loop {
            if self.next >= self.records.len() {
                if !batch.bytes.is_empty() {
                    return Ok(());
                }
                self.records.clear();
                self.next = 0;
                if let Some(f) = self.broken.take() {
                    return Err(f);
                }
                if self.eof {
                    self.end(tx);
                    return Ok(());
                }
                let n = self.read()?;
                let scratch = std::mem::take(&mut self.scratch);
                self.parse(&scratch[..n]);
                self.scratch = scratch;
                continue;
            }
            if batch.bytes.len() >= BATCH_BYTES {
                return Ok(());
            }
            let Some(p) = self.records.get(self.next) else {
                return Ok(());
            };
            let micros = p.time;
            if p.skipped > 0 && !self.skip_told {
                if !batch.bytes.is_empty() {
                    // The row goes between the bytes before and after: take the record again.
                    return Ok(());
                }
                self.skip_told = true;
                let time = (!self.untimed).then_some(micros);
                let _ = tx.send(super::skipped_note(p.skipped, time));
            }
            let stamped = pcap::in_calendar(p.ts_micros);
            if !stamped && !self.out_of_range {
                if !batch.bytes.is_empty() {
                    // The row goes between the bytes before and after: take the record again.
                    return Ok(());
                }
                let time = (!self.untimed).then_some(micros);
                let _ = tx.send(super::time_out_of_range(p.ts_micros, time));
            }
            self.out_of_range = !stamped;
            // The first record in the calendar starts the capture (PcapStream::start).
            if !self.anchored && stamped {
                self.anchored = true;
                if let Some(a) = pcap::anchor(p.ts_micros) {
                    let _ = tx.send(Message::Anchor(a));
                }
            }
            if self.only.is_some_and(|i| i != p.interface) {
                self.next += 1;
                continue;
            }
            let first = *self.first_interface.get_or_insert(p.interface);
            if self.only.is_none() && p.interface != first && !self.mixed {
                self.mixed = true;
                let _ = tx.send(Message::Warning(format!(
                    "{}: a recording of several ports (interfaces {first} and {}), read as one \
                     line; name the file itself to read each port apart",
                    self.name, p.interface
                )));
            }
            // pcapng names the link type per interface: each packet carries its own.
            let (event, lines, payload) = match p.link_type {
                linktype::RTAC_SERIAL => rtac::parse(p.data).unwrap_or((SHORT_RECORD, 0, &[])),
                _ => (EVENT_RX_DATA, 0, p.data),
            };
            let note = self.note_for(event, lines, payload, micros);
            if let Some(note) = note {
                if !batch.bytes.is_empty() {
                    // The row goes between the bytes before and after: send these first and
                    // take the record again next time.
                    return Ok(());
                }
                self.counts.add(event);
                let _ = tx.send(note);
            }
            self.next += 1;
            self.skip_told = false;
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
                        p if p.starts_with(LINK_UP) => Some(Message::LinkUp {
                            micros,
                            path: link_up_device(p).unwrap_or_else(|| PathBuf::from(&self.name)),
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
                START | START_UNTIMED | LINK_DOWN => return None,
                p if p.starts_with(LINK_UP) => return None,
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

/// The device a link-up record names (`busnoop link up at /dev/ttyUSB0`), if it names one.
fn link_up_device(payload: &[u8]) -> Option<PathBuf> {
    use std::os::unix::ffi::OsStrExt;
    let device = payload
        .strip_prefix(LINK_UP)?
        .strip_prefix(crate::pcap::rtac::LINK_UP_AT)?;
    (!device.is_empty()).then(|| PathBuf::from(std::ffi::OsStr::from_bytes(device)))
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
    use crate::record::{Content, Recorder};
    use crate::time::Anchor;
    use chrono::{DateTime, Utc};

    fn replay(bytes: Vec<u8>) -> Vec<Message> {
        let opened = Opened {
            kind: crate::protocol::InputKind::Recording,
            prefix: Vec::new(),
            reader: Box::new(io::Cursor::new(bytes)),
            name: "rec.pcap".into(),
        };
        let (tx, rx) = std::sync::mpsc::sync_channel(1000);
        let mut r = RecordingReader::new(opened);
        while let Some(c) = r.next_batch(&tx).unwrap() {
            tx.send(c.into()).unwrap();
        }
        drop(tx);
        rx.iter().collect()
    }

    #[test]
    fn record_and_replay_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.pcap");
        let anchor: DateTime<Utc> = "2026-01-02T03:04:05.678901Z".parse().unwrap();
        let mut rec = Recorder::create(&path, Content::Line { timed: true }).unwrap();
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

    /// L9 (issue 32): a replayed `--reconnect` recording named the recording in its LinkUp row
    /// (`adapter back at rec.pcap`) instead of the device. The record names the device now.
    #[test]
    fn a_replayed_reconnect_names_the_device() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["r.pcap", "r.pcapng"] {
            let path = dir.path().join(name);
            let mut rec = Recorder::create(&path, Content::Line { timed: true }).unwrap();
            rec.describe("/dev/ttyUSB0", "FrSky S.Port, 57600 baud 8N1");
            rec.data(&[0x7E, 0x00], Some(1_000)).unwrap();
            rec.link(false, 20_000).unwrap();
            rec.link(true, 3_020_000).unwrap();
            rec.flush().unwrap();
            let ups: Vec<PathBuf> = replay(std::fs::read(&path).unwrap())
                .into_iter()
                .filter_map(|m| match m {
                    Message::LinkUp { path, .. } => Some(path),
                    _ => None,
                })
                .collect();
            assert_eq!(ups, [PathBuf::from("/dev/ttyUSB0")], "{name}");
        }
    }

    #[test]
    fn untimed_sources_replay_untimed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.pcap");
        let mut rec = Recorder::create(&path, Content::Line { timed: false }).unwrap();
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
    fn foreign_rtac_serial_captures_show_every_record() {
        // A capture another tool wrote: data in DATA_RX_END records, no busnoop start record,
        // a record too short for its header, line events, lost data, an unknown event type and
        // a status change with control lines.
        let anchor: DateTime<Utc> = "2026-01-02T03:04:05Z".parse().unwrap();
        let write_record = |f: &mut Vec<u8>, micros: i64, event, data: &[u8]| {
            rtac::record(f, anchor.timestamp_micros() + micros, event, data)
        };
        let mut f = Vec::new();
        pcap::write::header_with_snaplen(&mut f, linktype::RTAC_SERIAL, 65_535);
        write_record(&mut f, 0, 0x04, &[0x7E, 0xA1]);
        let t = anchor.timestamp() as u32;
        f.extend_from_slice(&t.to_le_bytes());
        f.extend_from_slice(&1000u32.to_le_bytes());
        f.extend_from_slice(&5u32.to_le_bytes());
        f.extend_from_slice(&5u32.to_le_bytes());
        f.extend_from_slice(&[1, 2, 3, 4, 5]);
        write_record(&mut f, 2000, 0x07, &[]);
        write_record(&mut f, 3000, 0x05, &[]);
        write_record(&mut f, 4000, 0x33, &[]);
        let mut status = Vec::new();
        write_record(&mut status, 5000, EVENT_STATUS, &[]);
        status[16 + 9] = 0x19; // CTS, RTS, DTR
        f.extend_from_slice(&status);
        write_record(&mut f, 6000, 0x02, &[0x7E, 0x22]);
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
