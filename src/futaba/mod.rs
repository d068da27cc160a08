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

mod args;
mod direct;
mod map;
mod names;
mod vocab;
pub mod wire;

pub use map::Stats;
pub use names::{CHANNELS_TYPE, SLOT_TYPE};

use crate::protocol::{Decoder, Front, InputKind, Line, Parity, Probe, Protocol, Variant};
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// Futaba SBUS / SBUS2: 100000 baud 8E2, inverted on the wire (the adapter must invert, see
/// docs/futaba.md).
pub const PROTOCOL: Protocol = Protocol {
    name: "Futaba SBUS",
    command: "futaba",
    aliases: &[],
    summary: "Futaba SBUS / SBUS2 (RC receivers): 25-byte channel frames, SBUS2 telemetry slots \
              (100000 baud 8E2, inverted); not Saia S-Bus, which is `busnoop sbus`",
    about: "Futaba SBUS / SBUS2, the channel bus of most RC receivers: a 25-byte frame every 6 to \
            14 ms (`0F`, 16 channels of 11 bits, flags, end byte), one row each with CH1 … CH16 \
            in µs (Betaflight's 5/8 × raw + 880), CH17, CH18, frame lost and failsafe; SBUS2 \
            telemetry slot answers as rows with the slot number as ID. 100000 baud 8E2, \
            inverted on the wire: the adapter must invert (docs/futaba.md). Saia S-Bus, the PLC \
            bus of a similar name, is `busnoop sbus`.",
    examples: "Examples:\n  busnoop futaba /dev/ttyUSB0\n  busnoop futaba capture.bin --type Slot\n  \
               busnoop futaba capture.bin --wide -o channels.csv\n  busnoop plot capture.bin \
               --protocol futaba --sensor CH1,CH2",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, a busnoop .pcap or .pcapng recording) or `-` for \
                  standard input. File kinds are recognised by content.",
    line: Line::new(wire::BAUD, 8, Parity::Even, 2),
    inverted: true,
    rates: &[wire::BAUD, 200_000],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 2, 8, 9, 7, 5, 79, 4, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[],
    export: None,
};

/// `detect` reads SBUS one way at the probe's speed (an inverted line is tried for every
/// inverted protocol). Saia S-Bus (`busnoop sbus`) is told apart by the scores: its telegrams
/// end in a CRC, not in an end byte 24 bytes after a `0F`, and SBUS frames fail S-Bus's CRC.
fn variants(probe: &Probe) -> Vec<Variant> {
    vec![Variant {
        label: "Futaba SBUS",
        args: &[],
        decoder: decoder(Options {
            baud: probe.line.baud,
        }),
    }]
}

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

impl Decoder for FutabaDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let (re, map) = (&mut self.re, &mut self.map);
        Latch::with(out, |out| re.push(data, time, &mut |e| map.event(e, out)))
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let (re, map) = (&mut self.re, &mut self.map);
        Latch::with(out, |out| re.finish(&mut |e| map.event(e, out)))
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
