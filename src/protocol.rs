//! What every protocol provides, and the table of protocols.
//!
//! A protocol lives in a folder of its own (`src/<protocol>/`): its wire format and pure
//! reassembler, its name tables, the mapping of frames onto the log table ([`crate::row`]) and
//! its [`Protocol`] descriptor. It implements [`Decoder`], the one interface the driver
//! (`crate::run`) sees. A protocol never imports the command line, the sinks or the sources:
//! everything it learns comes in through its options, [`Line`] and the input [`InputKind`].
//!
//! ## The reassembler contract
//!
//! Every decoder wraps a reassembler that is **pure** (bytes and times in, frames out, no I/O)
//! and **chunk-invariant**: feeding the same bytes with the same times in any split gives the
//! same rows (`push` once or byte by byte). The three entry points are
//!
//! * [`Decoder::push`]: bytes that arrived at a time; every frame they complete is emitted at
//!   once, nothing is held back that is already known to be whole;
//! * [`Decoder::packet`]: one packet of a capture of network traffic (the source opened the
//!   pcap/pcapng container; [`Decoder::capture_error`] if it is broken);
//! * [`Decoder::idle`]: time passed on a live line without bytes (timeouts, end-of-frame
//!   gaps), never called for files;
//! * [`Decoder::finish`]: the end of the input, or a gap (an unplugged adapter); whatever is open
//!   comes out (a truncated frame, trailing garbage, unanswered requests), and the decoder must
//!   be ready for more bytes after it.
//!
//! A decoder never panics on any input; broken input becomes rows of [`crate::row::kind`]
//! `BadCRC`, `Truncated`, `Garbage` and counts. Memory stays bounded whatever the input.
//!
//! ## Adding a protocol
//!
//! See `docs/architecture.md`: a folder, one entry in `crate::protocols::PROTOCOLS`, a
//! subcommand in `cli.rs`.

use crate::pcap::{Packet, PcapError, PcapStream};
use crate::row::{Class, Row, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// Parity of a serial line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parity {
    None,
    Odd,
    Even,
}

/// Character format and speed of a serial line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Line {
    pub baud: u32,
    /// 5 to 8.
    pub data_bits: u8,
    pub parity: Parity,
    /// 1 or 2.
    pub stop_bits: u8,
}

impl Line {
    /// 8N1 at `baud`.
    pub const fn n81(baud: u32) -> Self {
        Line {
            baud,
            data_bits: 8,
            parity: Parity::None,
            stop_bits: 1,
        }
    }

    /// Bits per character on the wire (start + data + parity + stop).
    pub fn bits_per_char(&self) -> u32 {
        let parity = u32::from(self.parity != Parity::None);
        1 + u32::from(self.data_bits) + parity + u32::from(self.stop_bits)
    }
}

/// What an input turned out to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// Bytes exactly as they were on the wire, without time.
    Raw,
    /// EdgeTX/OpenTX debug log: `YYYY-MM-DD,HH:MM:SS.mmm: 7E A1 …`.
    EdgeTxLog,
    /// Classic pcap (by its magic number) of network traffic.
    Pcap,
    /// A busnoop recording: classic pcap with link type RTAC serial (250) or USER0 (147).
    Recording,
    /// A live serial device.
    Serial,
    /// pcapng (by its section header block).
    Pcapng,
}

/// What a protocol tells the shared code: its name, its line and the inputs it reads.
#[derive(Debug)]
pub struct Protocol {
    /// Name in messages ("S.Port").
    pub name: &'static str,
    /// The subcommand ("sport").
    pub command: &'static str,
    /// Character format and default speed of a live line.
    pub line: Line,
    /// The input kinds its decoder reads.
    pub accepts: &'static [InputKind],
    /// The same in words, for the message that refuses another kind ("raw wire bytes, EdgeTX
    /// logs or busnoop recordings").
    pub accepts_text: &'static str,
    /// Pretty output: the width of each column, the eight base columns and then the decoder's
    /// extra columns in order (the last one's is unused: it is not padded). A column grows for
    /// a longer value.
    pub pretty_widths: &'static [usize],
    /// What its table can show (ID range, types, sensors, devices), for checking filters.
    pub vocab: &'static crate::filter::Vocab,
}

impl Protocol {
    /// Whether this protocol's decoder reads inputs of `kind`.
    pub fn reads(&self, kind: InputKind) -> bool {
        self.accepts.contains(&kind)
    }
}

/// A protocol decoder as the driver sees it.
pub trait Decoder {
    /// Extra column names that follow the eight base columns.
    fn columns(&self) -> &'static [&'static str];

    /// Feeds bytes that arrived at `time` (microseconds since the capture started; `None` for
    /// sources without time). Rows for every frame completed by these bytes are emitted at once.
    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult;

    /// One packet of a capture (sources of [`InputKind::Pcap`] and [`InputKind::Pcapng`]); `p.time` is µs
    /// since the capture started. Rows for everything it completes are emitted at once. A
    /// byte-stream protocol takes its captured bytes as bytes that arrived at that time.
    fn packet(&mut self, p: &Packet<'_>, out: &mut dyn RowOut) -> RowResult {
        self.push(p.data, Some(p.time), out)
    }

    /// The capture container is broken here (after the packets before it); no packets follow.
    /// By default a `Truncated` error row with the reason.
    fn capture_error(&mut self, e: &PcapError, out: &mut dyn RowOut) -> RowResult {
        let data = e.to_string();
        out.row(&Row {
            stamp: 0,
            kind: crate::row::kind::TRUNCATED,
            class: Class::Error,
            data: &data,
            ..Row::empty(None)
        })
    }

    /// Time passed without data on a live serial source; `now` is the current capture time
    /// (µs since the capture started). Lets a decoder report timeouts promptly.
    fn idle(&mut self, _now: u64, _out: &mut dyn RowOut) -> RowResult {
        Ok(())
    }

    /// End of input, or a gap in a live capture (adapter unplugged): emits whatever is still open
    /// (a truncated frame, trailing garbage, unanswered requests). After a gap, `push` is called
    /// again with the bytes that follow it, so the decoder must be ready to go on.
    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult;

    /// Frames with a valid check decoded so far.
    fn valid_frames(&self) -> u64;

    /// The `--stats` report (the driver prints it).
    fn stats(&self) -> Report;

    /// What went wrong (CRC errors, truncated frames, garbage): the driver prints its one line
    /// when it is not empty.
    fn problems(&self) -> Problems;

    /// A hint printed once when bytes keep arriving but no frame is found (live sources).
    fn no_frames_hint(&self) -> &'static str {
        "check the baud rate and the wiring"
    }
}

/// A decoder that takes pcap/pcapng bytes: runs them through a [`PcapStream`] into `D`'s
/// packet entry, as the capture source and the driver do (benchmarks, fuzzing and tests that
/// feed raw capture bytes, in any chunking).
pub struct PcapBytes<D> {
    stream: PcapStream,
    pub decoder: D,
}

impl<D: Decoder> PcapBytes<D> {
    pub fn new(decoder: D) -> Self {
        PcapBytes {
            stream: PcapStream::new(),
            decoder,
        }
    }
}

impl<D: Decoder> Decoder for PcapBytes<D> {
    fn columns(&self) -> &'static [&'static str] {
        self.decoder.columns()
    }

    /// `time` is ignored: packets carry their own.
    fn push(&mut self, data: &[u8], _time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let d = &mut self.decoder;
        let mut latch = crate::row::Latch::new(out);
        let parsed = self.stream.push(data, &mut |p| {
            let _ = d.packet(&p, &mut latch);
        });
        latch.result()?;
        match parsed {
            Err(e) => d.capture_error(&e, out),
            Ok(()) => Ok(()),
        }
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        if let Err(e) = self.stream.finish() {
            self.decoder.capture_error(&e, out)?;
        }
        self.decoder.finish(out)
    }

    fn valid_frames(&self) -> u64 {
        self.decoder.valid_frames()
    }

    fn stats(&self) -> Report {
        self.decoder.stats()
    }

    fn problems(&self) -> Problems {
        self.decoder.problems()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_per_char() {
        assert_eq!(Line::n81(9600).bits_per_char(), 10);
        let parity = Line {
            parity: Parity::Even,
            ..Line::n81(9600)
        };
        assert_eq!(parity.bits_per_char(), 11);
    }
}
