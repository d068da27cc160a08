//! Futaba SBUS / SBUS2: the RC channel bus of most receivers (100000 baud 8E2, inverted), and
//! SBUS2's telemetry slots.
//!
//! Not to be confused with Saia S-Bus ([`crate::sbus`], `busnoop sbus`), a PLC bus of the
//! same name: the subcommand here is `busnoop futaba`.
//!
//! * [`wire`]: the frame layout, the slot ids, encoders and the pure reassembler;
//! * `map.rs`: frames and slots onto the log table, and the statistics;
//! * `vocab.rs`: what filters may name.
//!
//! The table mapping and the choices made where the wire is ambiguous are in `docs/futaba.md`.

mod map;
mod vocab;
pub mod wire;

pub use map::{CHANNELS_TYPE, SLOT_TYPE, Stats};

use crate::protocol::{Decoder, Kind, Line, Parity, Protocol};
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// What the shared code needs to know: 100000 baud 8E2. The line is inverted: the adapter
/// must invert it (docs/futaba.md, "Wiring").
pub const PROTOCOL: Protocol = Protocol {
    name: "Futaba SBUS",
    command: "futaba",
    line: Line {
        baud: wire::BAUD,
        data_bits: 8,
        parity: Parity::Even,
        stop_bits: 2,
    },
    accepts: &[Kind::Raw, Kind::Serial, Kind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 2, 8, 8, 7, 5, 79, 4, 0],
    vocab: &vocab::VOCAB,
};

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Note"];

/// Decoder settings (from the command line).
#[derive(Clone, Debug)]
pub struct Options {
    /// Line speed, for the times of sources without time (100000; INAV also knows 200000).
    pub baud: u32,
}

impl Default for Options {
    fn default() -> Self {
        Options { baud: wire::BAUD }
    }
}

/// The Futaba decoder: reassembler + table mapping + statistics.
pub struct FutabaDecoder {
    re: wire::Reassembler,
    map: map::Mapper,
}

impl FutabaDecoder {
    pub fn new(opts: &Options) -> Self {
        FutabaDecoder {
            re: wire::Reassembler::new(),
            map: map::Mapper::new(opts.baud),
        }
    }

    /// The counters so far.
    pub fn counters(&self) -> &Stats {
        &self.map.stats
    }
}

/// The Futaba decoder (every input kind [`PROTOCOL`] accepts is a byte stream).
pub fn decoder(opts: Options) -> Box<dyn Decoder> {
    Box::new(FutabaDecoder::new(&opts))
}

/// The ways `busnoop detect` reads a capture as Futaba SBUS: `(label, inverted, decoder)`. The
/// bytes as they are (an inverting adapter), and inverted back (an adapter that does not
/// invert: a rough reading, the UART also misplaces the start bits, but frames often survive).
/// Saia S-Bus (`busnoop sbus`) is told apart by scoring: its telegrams end in a CRC, not in
/// `00`/`04`…`34` 25 bytes after a `0F`, and SBUS frames fail the S-Bus CRC.
pub fn detect_variants(baud: Option<u32>) -> Vec<(&'static str, bool, Box<dyn Decoder>)> {
    let opts = || Options {
        baud: baud.unwrap_or(wire::BAUD),
    };
    vec![
        ("Futaba SBUS", false, decoder(opts())),
        ("Futaba SBUS, inverted line", true, decoder(opts())),
    ]
}

impl Decoder for FutabaDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        let map = &mut self.map;
        self.re.push(data, time, &mut |e| map.event(e, &mut out));
        out.result()
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        let map = &mut self.map;
        self.re.finish(&mut |e| map.event(e, &mut out));
        out.result()
    }

    fn valid_frames(&self) -> u64 {
        self.map.stats.frames() + self.map.stats.slot_answers()
    }

    fn stats(&self) -> Report {
        self.map.report()
    }

    fn problems(&self) -> Problems {
        self.map.problems()
    }

    fn no_frames_hint(&self) -> &'static str {
        "SBUS runs at 100000 baud 8E2 on an inverted line: the adapter must invert (or use an \
         FTDI with inverted RX, see docs/futaba.md); Saia S-Bus is `busnoop sbus`"
    }
}

#[cfg(test)]
mod tests;
