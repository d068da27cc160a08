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

/// Packets read from a capture, and the input bytes they came from when a recording keeps
/// them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Captured {
    pub packets: Packets,
    /// The bytes read (empty unless the reader keeps its input).
    pub input: Vec<u8>,
}

/// Reads a pcap or pcapng capture as packets.
pub struct CaptureReader {
    prefix: Option<Vec<u8>>,
    reader: Box<dyn Read + Send>,
    name: String,
    stream: PcapStream,
    buf: Vec<u8>,
    /// Hand on the input bytes too (for `--record`).
    keep_input: bool,
    anchored: bool,
    /// A parse failure to send before anything else.
    error: Option<PcapError>,
}

impl CaptureReader {
    /// `keep_input`: every read also hands on the bytes as read (for a recording of the input).
    pub fn new(opened: Opened, keep_input: bool) -> Self {
        CaptureReader {
            prefix: Some(opened.prefix),
            reader: opened.reader,
            name: opened.name,
            stream: PcapStream::new(),
            buf: vec![0; READ_SIZE],
            keep_input,
            anchored: false,
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
                return Ok(None);
            }
            let mut packets = Packets::for_input(n);
            let input = &self.buf[..n];
            self.error = self.stream.push(input, &mut |p| packets.push(&p)).err();
            if !self.anchored
                && let Some(start) = self.stream.start()
            {
                self.anchored = true;
                if let Some(a) = pcap::anchor(start) {
                    let _ = tx.send(Message::Anchor(a));
                }
            }
            if !packets.is_empty() || self.keep_input {
                let input = if self.keep_input {
                    self.buf[..n].to_vec()
                } else {
                    Vec::new()
                };
                return Ok(Some(Chunk::Packets(Captured { packets, input })));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcap::write;

    /// Every message the reader sends, in order, with packets as (time, bytes).
    fn messages(bytes: Vec<u8>, keep_input: bool) -> Vec<String> {
        let opened = Opened {
            kind: crate::protocol::Kind::Pcap,
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
            messages(f.clone(), false),
            [
                "anchor Instant(1970-01-01T00:00:01Z)",
                "packets [(0, [97, 98]), (250000, [99])] input 0",
                "error the capture ends inside the record at byte 59 (1 bytes missing)",
            ]
        );
        let kept = messages(f.clone(), true);
        assert_eq!(
            kept[1],
            format!("packets [(0, [97, 98]), (250000, [99])] input {}", f.len())
        );
    }
}
