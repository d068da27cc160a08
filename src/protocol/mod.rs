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
//! same rows (`push` once or byte by byte). The four entry points are
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
//! A protocol is registered by its [`Protocol`] descriptor alone: a folder, one entry in
//! `crate::protocols::PROTOCOLS` and `pub mod` in `lib.rs` (see `docs/architecture.md`,
//! "Adding a protocol"). The command line, detection, the project file, the export, the
//! Wireshark extcap and the filters all loop over the table.

pub mod front;
pub mod vocab;

pub use front::{Export, Front, Options, Probe, Setup, Variant, Wrap};
pub use vocab::Vocab;

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

    /// `data_bits`, `parity` and `stop_bits` at `baud` (`Line::new(100_000, 8, Parity::Even, 2)`).
    pub const fn new(baud: u32, data_bits: u8, parity: Parity, stop_bits: u8) -> Self {
        Line {
            baud,
            data_bits,
            parity,
            stop_bits,
        }
    }

    /// Bits per character on the wire (start + data + parity + stop).
    pub fn bits_per_char(&self) -> u32 {
        let parity = u32::from(self.parity != Parity::None);
        1 + u32::from(self.data_bits) + parity + u32::from(self.stop_bits)
    }

    /// The character format as people write it: `8N1`, `8E2`.
    pub fn format(&self) -> String {
        let p = match self.parity {
            Parity::None => 'N',
            Parity::Even => 'E',
            Parity::Odd => 'O',
        };
        format!("{}{p}{}", self.data_bits, self.stop_bits)
    }

    /// Whether two lines frame characters alike (the speed aside).
    pub fn same_format(&self, other: &Line) -> bool {
        (self.data_bits, self.parity, self.stop_bits)
            == (other.data_bits, other.parity, other.stop_bits)
    }

    /// Reads `8E1`, `8N2`, `9600-8N2` or `19200` over this line: the format and the speed each
    /// where given.
    pub fn parse_over(mut self, text: &str) -> Result<Line, String> {
        let bad = || {
            format!(
                "{text:?}: expected a character format like 8N1, 8E1 or 8N2, optionally after the \
                 speed (9600-8E1)"
            )
        };
        let t = text.trim();
        let (speed, format) = match t.split_once(['-', ':', ' ']) {
            Some((s, f)) => (Some(s), Some(f)),
            None if t.bytes().all(|b| b.is_ascii_digit()) && t.len() > 2 => (Some(t), None),
            None => (None, Some(t)),
        };
        if let Some(s) = speed {
            self.baud = s.parse().map_err(|_| bad())?;
        }
        if let Some(f) = format {
            let b = f.as_bytes();
            if b.len() != 3 {
                return Err(bad());
            }
            self.data_bits = match b[0] {
                d @ b'5'..=b'8' => d - b'0',
                _ => return Err(bad()),
            };
            self.parity = match b[1].to_ascii_uppercase() {
                b'N' => Parity::None,
                b'E' => Parity::Even,
                b'O' => Parity::Odd,
                _ => return Err(bad()),
            };
            self.stop_bits = match b[2] {
                s @ (b'1' | b'2') => s - b'0',
                _ => return Err(bad()),
            };
        }
        Ok(self)
    }
}

/// The time of byte `offset` of a source without times (a raw capture), in µs since its start:
/// `bits` per character on a line of `baud`, each character right after the one before. The
/// one rule every protocol uses for the Millis of untimed bytes ([`Line::bits_per_char`] gives
/// `bits`).
pub fn untimed_micros(offset: u64, bits: u32, baud: u32) -> u64 {
    let baud = baud.max(1);
    match offset.checked_mul(bits as u64 * 1_000_000) {
        // The quotient of the u128 reading below, without its division routine, while the
        // product fits (offsets below 10^12 bytes).
        Some(p) => p / baud as u64,
        None => (offset as u128 * bits as u128 * 1_000_000 / baud as u128) as u64,
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
    /// A logic-analyzer trace (sigrok session, VCD, Saleae CSV export), read through busnoop's
    /// software UART at the protocol's line: a serial line's bytes, each with its exact time.
    Trace,
}

/// Everything the shared code knows of a protocol: the one place it is registered. The
/// command line builds its subcommand from it (help, options, defaults), `detect` tries its
/// variants at its line settings, the project file reads its section, the export and the
/// Wireshark extcap use its link type, and the filters check against its vocabulary.
pub struct Protocol {
    /// Name in messages ("S.Port").
    pub name: &'static str,
    /// The subcommand ("sport").
    pub command: &'static str,
    /// Other names of the subcommand (and of its project-file section).
    pub aliases: &'static [&'static str],
    /// One line for `busnoop --help`.
    pub summary: &'static str,
    /// The subcommand's `--help` text before its options: what the protocol is, its line, what
    /// it reads.
    pub about: &'static str,
    /// Commands to try, shown after the options (`busnoop sport -h`).
    pub examples: &'static str,
    /// What SOURCE may be, in the subcommand's help.
    pub source_help: &'static str,
    /// Character format and default speed of a live line.
    pub line: Line,
    /// The line idles low (an inverted UART signal: S.Port, F.Port, Futaba SBUS): a plain
    /// adapter reads every byte inverted, which `detect` recognises.
    pub inverted: bool,
    /// The speeds `detect` listens at on a serial port, the default first.
    pub rates: &'static [u32],
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
    pub vocab: &'static Vocab,
    /// Its own options and how they become a decoder (`front.rs`).
    pub front: Front,
    /// The ways `detect` reads a capture as this protocol (modes, framings), each a decoder.
    pub variants: fn(&Probe) -> Vec<Variant>,
    /// The keys of its project-file section besides the shared ones (`baud`, `format`,
    /// `stats`, `names`, `filter`), with what each sets, for the message that refuses others.
    pub config_keys: &'static [(&'static str, &'static str)],
    /// Frames as packets for Wireshark (`--export`, the extcap), when it has a dissector.
    pub export: Option<Export>,
}

impl std::fmt::Debug for Protocol {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Protocol")
            .field("command", &self.command)
            .finish_non_exhaustive()
    }
}

impl Protocol {
    /// Whether this protocol's decoder reads inputs of `kind`. A logic-analyzer trace is read
    /// by every protocol that reads a serial line.
    pub fn reads(&self, kind: InputKind) -> bool {
        let kind = match kind {
            InputKind::Trace => InputKind::Serial,
            k => k,
        };
        self.accepts.contains(&kind)
    }

    /// Whether `name` is its subcommand or one of its aliases.
    pub fn answers_to(&self, name: &str) -> bool {
        self.command == name || self.aliases.contains(&name)
    }
}

/// A protocol decoder as the driver sees it. `Send`: with several sources each decoder runs in
/// the thread of its port (`merge`).
pub trait Decoder: Send {
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
    fn untimed_micros_in_u64_is_the_u128_reading() {
        let wide = |o: u64, bits: u32, baud: u32| {
            (o as u128 * bits as u128 * 1_000_000 / baud as u128) as u64
        };
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut offsets = vec![0, 1, 1 << 20, u64::MAX / 11_000_000, u64::MAX / 10_000_000];
        offsets.extend([
            u64::MAX / 10_000_000 + 1,
            u64::MAX / 2,
            u64::MAX - 1,
            u64::MAX,
        ]);
        for _ in 0..2000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            offsets.push(x >> (x % 64));
        }
        for o in offsets {
            for bits in [10, 11] {
                for baud in [1, 300, 9600, 38_400, 115_200, u32::MAX] {
                    assert_eq!(
                        untimed_micros(o, bits, baud),
                        wide(o, bits, baud),
                        "{o} {bits} {baud}"
                    );
                }
            }
        }
    }

    #[test]
    fn line_settings_as_people_write_them() {
        let base = Line::n81(9600);
        let e1 = base.parse_over("8E1").unwrap();
        assert_eq!((e1.baud, e1.parity, e1.stop_bits), (9600, Parity::Even, 1));
        assert_eq!(e1.format(), "8E1");
        let n2 = base.parse_over("19200-8n2").unwrap();
        assert_eq!((n2.baud, n2.format()), (19_200, "8N2".to_owned()));
        assert_eq!(base.parse_over("115200").unwrap().baud, 115_200);
        for bad in ["8X1", "9N1", "8N3", "fast-8N1", "8N"] {
            assert!(base.parse_over(bad).is_err(), "{bad}");
        }
        assert!(e1.same_format(&Line::new(19_200, 8, Parity::Even, 1)));
        assert!(!e1.same_format(&base));
    }

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
