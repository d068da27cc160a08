//! FlySky iBUS: the RC channel line (115200 baud 8N1, not inverted) and the sensor bus, polled
//! half duplex like S.Port.
//!
//! * [`wire`]: checksum, encoders, the pure framer and the pairing of polls with answers;
//! * [`sensors`]: sensor types, names, units and value decoding;
//! * `map.rs`: the mapping onto the log table, the types learned per address, statistics;
//! * `vocab.rs`: what filters may name.
//!
//! The table mapping, the sources and the check against a real capture are in `docs/ibus.md`.

mod args;
mod direct;
mod map;
mod names;
pub mod sensors;
mod vocab;
pub mod wire;

pub use map::{
    AddrStats, CHANNELS, DISCOVER, Learned, MEASURE, OTHER, SENSOR_TYPE, Stats, UNKNOWN,
};

use crate::protocol::{Decoder, Front, InputKind, Line, Probe, Protocol, Variant};
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// FlySky iBUS: 115200 baud 8N1, normal levels.
pub const PROTOCOL: Protocol = Protocol {
    name: "FlySky iBUS",
    command: "ibus",
    aliases: &[],
    summary: "FlySky iBUS: RC channel frames and the sensor bus (polls paired with answers, sensor \
              values in units; 115200 baud)",
    about: "FlySky iBUS: the receiver's servo line (a frame `20 40` with 14 channels in µs every \
            7.7 ms; channels 15-18 in the high nibbles of newer receivers) and its sensor line, \
            polled half duplex like S.Port: discover, type and measurement polls (`04 cmd|addr \
            chk`) paired with the sensors' answers, the sensor type named as EdgeTX names it \
            and its value in units; polls nobody answered are poll rows (--hide-polls). \
            115200 baud 8N1, normal levels (docs/ibus.md).",
    examples: "Examples:\n  busnoop ibus /dev/ttyUSB0\n  busnoop ibus sensors.bin --hide-polls \
               --sensor ExtV\n  busnoop ibus sensors.bin --sensor-type 1=ExtV --sensor-type \
               2=RPM\n  busnoop ibus servo.bin --wide -o channels.csv",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, a busnoop .pcap or .pcapng recording) or `-` for \
                  standard input. File kinds are recognised by content.",
    line: Line::n81(wire::BAUD),
    inverted: false,
    rates: &[wire::BAUD],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 3, 1, 10, 7, 6, 30, 4, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[(
        "sensor-types",
        "the sensor type at an address (1 = \"ExtV\"), as --sensor-type",
    )],
    export: None,
};

/// `detect` reads iBUS one way (the line is not inverted).
fn variants(probe: &Probe) -> Vec<Variant> {
    vec![Variant {
        label: "FlySky iBUS",
        args: &[],
        decoder: decoder(Options {
            baud: probe.line.baud,
            ..Options::default()
        }),
    }]
}

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Note"];

/// Decoder settings (from the command line).
#[derive(Clone, Debug)]
pub struct Options {
    /// Line speed, for the times of sources without time.
    pub baud: u32,
    /// Sensor types known in advance, `(address, type code)`: measurements of these addresses
    /// decode before (or without) a type answer in the capture.
    pub types: Vec<(u8, u8)>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            baud: wire::BAUD,
            types: Vec::new(),
        }
    }
}

/// Parses `ADDR=TYPE` (`1=ExtV`, `2=0x01`, `3=2`): an address 0-15 and a type by name or code.
pub fn parse_sensor_type(s: &str) -> Result<(u8, u8), String> {
    let (addr, ty) = s
        .split_once('=')
        .ok_or_else(|| format!("expected ADDR=TYPE (1=ExtV), got {s:?}"))?;
    let addr: u8 = addr
        .trim()
        .parse()
        .ok()
        .filter(|a| *a < 16)
        .ok_or_else(|| format!("the sensor address must be 0-15, got {addr:?}"))?;
    let ty = ty.trim();
    let code = if let Some(t) = sensors::TYPES
        .iter()
        .find(|t| t.name.eq_ignore_ascii_case(ty))
    {
        t.code
    } else if let Some(h) = ty.strip_prefix("0x").or_else(|| ty.strip_prefix("0X")) {
        u8::from_str_radix(h, 16).map_err(|_| format!("not a type code: {ty:?}"))?
    } else {
        ty.parse().map_err(|_| {
            format!("unknown sensor type {ty:?} (a name such as ExtV, or a code such as 0x03)")
        })?
    };
    Ok((addr, code))
}

/// The iBUS decoder: framer and pairing + table mapping + statistics.
pub struct IbusDecoder {
    re: wire::Reassembler,
    map: map::Mapper,
}

impl IbusDecoder {
    pub fn new(opts: &Options) -> Self {
        IbusDecoder {
            re: wire::Reassembler::new(),
            map: map::Mapper::new(opts.baud, &opts.types),
        }
    }

    /// The counters so far.
    pub fn counters(&self) -> &Stats {
        &self.map.stats
    }

    /// The type learned for a sensor address.
    pub fn learned(&self, addr: u8) -> Option<Learned> {
        self.map.learned(addr)
    }
}

/// The iBUS decoder (every input kind [`PROTOCOL`] accepts is a byte stream).
pub fn decoder(opts: Options) -> Box<dyn Decoder> {
    Box::new(IbusDecoder::new(&opts))
}

impl Decoder for IbusDecoder {
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
        self.map.stats.valid_frames
    }

    fn stats(&self) -> Report {
        self.map.report()
    }

    fn problems(&self) -> Problems {
        self.map.problems()
    }

    fn no_frames_hint(&self) -> &'static str {
        "iBUS runs at 115200 baud 8N1 with normal (not inverted) levels: check the baud rate and \
         that the adapter does not invert"
    }
}

#[cfg(test)]
mod tests;
