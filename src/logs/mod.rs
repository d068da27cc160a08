//! Telemetry logs other tools wrote, read as rows: a radio's SD-card log (EdgeTX, OpenTX: CSV
//! with `Date,Time` and one column per sensor) and S-Port_Snoop's log table (busnoop's own TSV
//! too). They are decoded telemetry, not bytes from a wire; reading them gives `plot`, `--wide`,
//! `--stats` and the filters on their numbers, and `busnoop FILE` recognises them.
//!
//! * [`wire`]: the pure line reassembler and the header that names the log;
//! * `map.rs`: lines onto the log table, and the statistics;
//! * `vocab.rs`: what filters may name.
//!
//! The mapping is in `docs/logs.md`. The rows are built from lines of text, a few per second
//! of flight: a line's fields and numbers are collected in small vectors, unlike the wire
//! decoders, which allocate nothing per frame.

mod args;
mod map;
mod vocab;
pub mod wire;

pub use map::{COLUMNS, LOG_TYPE};

use crate::protocol::{Decoder, Front, InputKind, Line, Probe, Protocol, Variant};
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// Telemetry logs: no line of their own (`detect` never listens for them on a port).
pub const PROTOCOL: Protocol = Protocol {
    name: "telemetry log",
    command: "log",
    aliases: &[],
    summary: "Telemetry logs other tools wrote: a radio's SD-card CSV (EdgeTX, OpenTX), an \
              S-Port_Snoop table; their numbers for plot, --wide, --stats and the filters",
    about: "Telemetry logs other tools wrote, read as rows: a radio's SD-card log (EdgeTX, \
            OpenTX: CSV with Date, Time and one column per sensor) gives one row per line with \
            every column's number named as the radio names it (RSSI, RxBt with the unit of \
            `RxBt(V)`); an S-Port_Snoop table (or busnoop's own TSV) gives its rows back. They \
            are telemetry the radio or the logger already decoded, not bytes from the wire: \
            `plot`, `--wide`, `--stats` and the filters work on their numbers. `busnoop FILE` \
            recognises both by content.",
    examples: "Examples:\n  busnoop log MODEL-2024-05-01.csv --stats\n  busnoop plot \
               MODEL-2024-05-01.csv --sensor RSSI,RxBt -o flight.svg\n  busnoop log snoop.tsv \
               --sensor Alt --wide -f csv",
    source_help: "What to read: a radio's SD-card log (CSV starting `Date,Time,`), an \
                  S-Port_Snoop table (tab-separated, starting `Counter Millis ID Device Type \
                  Sensor # Sensor Data`; busnoop's own TSV too), or `-` for standard input. \
                  Recognised by content.",
    line: Line::n81(115_200),
    inverted: false,
    rates: &[],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "text logs (a radio's SD-card CSV, an S-Port_Snoop table)",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 2, 8, 5, 8, 8, 40, 4, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[],
    export: None,
};

/// `detect` reads any text as a telemetry log: its header line says which one it is.
fn variants(_probe: &Probe) -> Vec<Variant> {
    vec![Variant {
        label: "telemetry log",
        args: &[],
        decoder: decoder(),
    }]
}

/// The telemetry log decoder: line reassembler + table mapping + statistics.
#[derive(Default)]
pub struct LogDecoder {
    lines: wire::Lines,
    map: map::Mapper,
}

/// A telemetry log decoder.
pub fn decoder() -> Box<dyn Decoder> {
    Box::new(LogDecoder::default())
}

impl LogDecoder {
    /// Which log the header named, once it was read.
    pub fn format(&self) -> Option<wire::Format> {
        self.lines.format()
    }
}

impl Decoder for LogDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    /// `time` is not used: a log's times are in its lines.
    fn push(&mut self, data: &[u8], _time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let (lines, map) = (&mut self.lines, &mut self.map);
        Latch::with(out, |out| {
            lines.push(data, &mut |e| {
                if !out.stopped() {
                    let _ = map.event(e, out);
                }
            })
        })
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let (lines, map) = (&mut self.lines, &mut self.map);
        Latch::with(out, |out| {
            lines.finish(&mut |e| {
                if !out.stopped() {
                    let _ = map.event(e, out);
                }
            })
        })
    }

    fn valid_frames(&self) -> u64 {
        self.map.stats.lines
    }

    fn stats(&self) -> Report {
        self.map.report()
    }

    fn problems(&self) -> Problems {
        self.map.problems()
    }

    fn no_frames_hint(&self) -> &'static str {
        "a telemetry log starts with its header line (`Date,Time,` or `Counter<TAB>Millis…`)"
    }
}

#[cfg(test)]
mod tests;
