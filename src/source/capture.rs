//! Captures of network traffic (pcap, pcapng), read with the shared [`PcapStream`] in the reader
//! thread. The capture's start (the first packet's time) goes out as [`Message::Anchor`] before
//! the first packets; packets go out with their times as soon as a read completes them (a
//! `tcpdump -U -w -` pipe gives a row per packet as it arrives); a broken container goes out as
//! [`Message::CaptureError`] at its place after the packets before it, and the rest of the
//! input is read but not parsed.

use std::io::{self, Read};
use std::sync::mpsc::SyncSender;

use super::{Chunk, ChunkReader, Message, Opened, READ_SIZE};
use crate::exit::Failure;
use crate::pcap::{self, Packets, PcapError, PcapStream};

/// Packets read from a capture, and the input bytes they came from when the reader keeps
/// them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Captured {
    pub packets: Packets,
    /// The bytes read (empty unless the reader keeps its input).
    pub input: Vec<u8>,
    /// The capture's link type once its headers told it ([`PcapStream::link_type`]): a
    /// recording of a capture without packets still gets its header.
    pub link_type: Option<u32>,
}

/// Reads a pcap or pcapng capture as packets.
pub struct CaptureReader {
    prefix: Option<Vec<u8>>,
    reader: Box<dyn Read + Send>,
    name: String,
    stream: PcapStream,
    buf: Vec<u8>,
    /// How many more of the input's bytes to hand on with the packets (the first few KiB, for
    /// the wrong-protocol check after the run).
    keep_input: u64,
    anchored: bool,
    /// The last packet was stamped outside the calendar (a `TimeJump` row said so).
    out_of_range: bool,
    /// A parse failure to send before anything else.
    error: Option<PcapError>,
}

impl CaptureReader {
    /// `keep_input`: the reads also hand on the bytes as read, up to this many in all (0:
    /// none).
    pub fn new(opened: Opened, keep_input: u64) -> Self {
        CaptureReader {
            prefix: Some(opened.prefix),
            reader: opened.reader,
            name: opened.name,
            stream: PcapStream::new(),
            buf: vec![0; READ_SIZE],
            keep_input,
            anchored: false,
            out_of_range: false,
            error: None,
        }
    }

    /// Reads the next bytes of the input (the detection prefix first) into `buf`; 0 at its end.
    fn read(&mut self) -> Result<usize, Failure> {
        if let Some(p) = self.prefix.take().filter(|p| !p.is_empty()) {
            self.buf[..p.len()].copy_from_slice(&p);
            return Ok(p.len());
        }
        loop {
            match self.reader.read(&mut self.buf) {
                Ok(n) => return Ok(n),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Failure::Input(format!("cannot read {}: {e}", self.name))),
            }
        }
    }
}

impl ChunkReader for CaptureReader {
    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Chunk>, Failure> {
        loop {
            if let Some(e) = self.error.take() {
                let _ = tx.send(Message::CaptureError(e));
            }
            let n = self.read()?;
            if n == 0 {
                if let Err(e) = self.stream.finish() {
                    let _ = tx.send(Message::CaptureError(e));
                }
                if let Some(w) = super::skipped_warning(&self.name, self.stream.skipped()) {
                    let _ = tx.send(w);
                }
                return Ok(None);
            }
            let mut packets = Packets::for_input(n);
            let input = &self.buf[..n];
            let (anchored, out_of_range) = (&mut self.anchored, &mut self.out_of_range);
            let link_type = self.stream.link_type();
            let mut each = |p: pcap::Packet<'_>| {
                let stamped = pcap::in_calendar(p.ts_micros);
                // The first packet in the calendar starts the capture (PcapStream::start).
                if stamped && !*anchored {
                    *anchored = true;
                    if let Some(a) = pcap::anchor(p.ts_micros) {
                        let _ = tx.send(Message::Anchor(a));
                    }
                }
                if p.skipped > 0 {
                    if !packets.is_empty() {
                        let before = std::mem::replace(&mut packets, Packets::for_input(n));
                        let _ = tx.send(Message::Packets(Captured {
                            packets: before,
                            input: Vec::new(),
                            link_type,
                        }));
                    }
                    let _ = tx.send(super::skipped_note(p.skipped, Some(p.time)));
                }
                if !stamped && !*out_of_range {
                    // The row goes between the packets before and after it.
                    if !packets.is_empty() {
                        let before = std::mem::replace(&mut packets, Packets::for_input(n));
                        let _ = tx.send(Message::Packets(Captured {
                            packets: before,
                            input: Vec::new(),
                            link_type,
                        }));
                    }
                    let _ = tx.send(super::time_out_of_range(p.ts_micros, Some(p.time)));
                }
                *out_of_range = !stamped;
                packets.push(&p);
            };
            self.error = self.stream.push(input, &mut each).err();
            if !packets.is_empty() || self.keep_input > 0 {
                let keep = usize::try_from(self.keep_input).map_or(n, |k| k.min(n));
                self.keep_input -= keep as u64;
                let input = self.buf[..keep].to_vec();
                let link_type = self.stream.link_type();
                return Ok(Some(Chunk::Packets(Captured {
                    packets,
                    input,
                    link_type,
                })));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcap::write;

    /// Every message the reader sends, in order, with packets as (time, bytes).
    fn messages(bytes: Vec<u8>, keep_input: u64) -> Vec<String> {
        let opened = Opened {
            kind: crate::protocol::InputKind::Pcap,
            prefix: Vec::new(),
            reader: Box::new(io::Cursor::new(bytes)),
            name: "c.pcap".into(),
        };
        let (tx, rx) = std::sync::mpsc::sync_channel(1000);
        let mut r = CaptureReader::new(opened, keep_input);
        while let Some(c) = r.next_batch(&tx).unwrap() {
            tx.send(c.into()).unwrap();
        }
        drop(tx);
        rx.iter()
            .map(|m| match m {
                Message::Packets(c) => {
                    let p: Vec<_> = c.packets.iter().map(|p| (p.time, p.data)).collect();
                    format!("packets {p:?} input {}", c.input.len())
                }
                Message::Anchor(a) => format!("anchor {a:?}"),
                Message::CaptureError(e) => format!("error {e}"),
                m => format!("{m:?}"),
            })
            .collect()
    }

    #[test]
    fn anchor_first_then_timed_packets_then_the_error() {
        let mut f = Vec::new();
        write::header(&mut f, 1);
        write::record(&mut f, 1_000_000, b"ab");
        write::record(&mut f, 1_250_000, b"c");
        write::record(&mut f, 2_000_000, b"cut");
        f.truncate(f.len() - 1);
        assert_eq!(
            messages(f.clone(), 0),
            [
                "anchor Instant(1970-01-01T00:00:01Z)",
                "packets [(0, [97, 98]), (250000, [99])] input 0",
                "error the capture ends inside the record at byte 59 (1 bytes missing)",
            ]
        );
        let kept = messages(f.clone(), u64::MAX);
        assert_eq!(
            kept[1],
            format!("packets [(0, [97, 98]), (250000, [99])] input {}", f.len())
        );
        // At most 30 bytes handed on, whatever was read.
        let some = messages(f.clone(), 30);
        assert_eq!(some[1], "packets [(0, [97, 98]), (250000, [99])] input 30");
    }

    /// A capture larger than one read: the input is handed on up to the limit and no further,
    /// batch after batch, and every packet still comes.
    #[test]
    fn kept_input_stops_at_its_limit() {
        let mut f = Vec::new();
        write::header(&mut f, 1);
        let records = 3 * READ_SIZE / 116;
        for i in 0..records {
            write::record(&mut f, i as i64, &[i as u8; 100]);
        }
        for (limit, want) in [(0, 0), (1000, 1000), (READ_SIZE as u64 + 7, READ_SIZE + 7)] {
            let opened = Opened {
                kind: crate::protocol::InputKind::Pcap,
                prefix: Vec::new(),
                reader: Box::new(io::Cursor::new(f.clone())),
                name: "c.pcap".into(),
            };
            let (tx, _rx) = std::sync::mpsc::sync_channel(1000);
            let mut r = CaptureReader::new(opened, limit);
            let (mut input, mut packets) = (0, 0);
            while let Some(c) = r.next_batch(&tx).unwrap() {
                if let Chunk::Packets(c) = c {
                    input += c.input.len();
                    packets += c.packets.iter().count();
                }
            }
            assert_eq!((input, packets), (want, records), "limit {limit}");
        }
    }
}
