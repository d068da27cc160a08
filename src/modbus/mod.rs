//! Modbus RTU (and Modbus ASCII) on a serial line: reassembly by content, the log table
//! mapping, request/response pairing, statistics, the register map and the Wireshark export.
//!
//! * [`function`]: the public function codes, their names and frame lengths;
//! * [`wire`]: the pure RTU reassembler (frames by function code, length and CRC, never by
//!   silence); [`ascii`]: the ASCII framing (`:` … LRC CR LF);
//! * [`pdu`]: the Data cell and the numbers of every function; [`regmap`]: register names,
//!   types, word orders, scales and units from the project file;
//! * `pairing.rs` (on the shared pairing core), `stats.rs`, `decoder.rs` ([`ModbusDecoder`]);
//! * [`export`]: each frame as a Modbus/UDP datagram for Wireshark's own dissector.
//!
//! The table mapping and the wiring are documented in `docs/modbus.md`.

mod args;
pub mod ascii;
mod decoder;
pub mod export;
mod fast;
pub mod function;
pub(crate) mod pairing;
pub mod pdu;
pub mod regmap;
mod stats;
pub(crate) mod vocab;
pub mod wire;

pub use decoder::ModbusDecoder;
pub use regmap::RegisterMap;
pub use stats::{FunctionStats, Totals};

use crate::protocol::front::{Export, Front, Probe, Variant};
use crate::protocol::{Decoder, InputKind, Line, Parity, Protocol};

/// Default serial speed: the Modbus serial line specification's default.
pub const DEFAULT_BAUD: u32 = 19_200;

/// The default line: 19200 baud, 8 data bits, even parity, 1 stop bit (the specification's
/// default; 8N2, 8N1 and 8O1 are seen too).
pub const LINE: Line = Line {
    baud: DEFAULT_BAUD,
    data_bits: 8,
    parity: Parity::Even,
    stop_bits: 1,
};

/// Bits per character of the default line (start, 8 data, parity, stop): Millis of a raw
/// capture without times is the byte offset times this at the line's rate.
pub const BITS_PER_CHAR: u32 = 11;

/// Default master timeout (ms): the specification leaves it to the application; 1 s is a
/// common setting of PLCs and SCADA masters (libmodbus waits 0.5 s, pymodbus 3 s).
pub const DEFAULT_TIMEOUT_MS: u64 = 1000;

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Resp ms", "Note"];

/// Modbus RTU (and ASCII with `--ascii`): 19200 8E1 by default, raw bytes, live lines and
/// recordings; register maps from the project file; Modbus/UDP for Wireshark.
pub const PROTOCOL: Protocol = Protocol {
    name: "Modbus",
    command: "modbus",
    aliases: &[],
    summary: "Modbus RTU/ASCII: requests and responses paired, framed by length and CRC, not by \
              silence (19200 8E1)",
    about: "Modbus RTU (and Modbus ASCII with --ascii) on RS-485 or RS-232: a master polls \
            slaves 1-247. Frames are found by function code, length and CRC-16, never by \
            silence, so a USB-serial adapter's bursts do not break them; requests and responses \
            are paired (response times, timeouts, retries, late answers, exceptions). Registers \
            show as R<addr> and coils as C<addr> at their 0-based wire address, or by the names, \
            types and units of the project file's register map ([modbus.registers], \
            docs/modbus.md). The line is 19200 8E1 by default; set yours with --baud and --line \
            (9600-8N1, 8N2).",
    examples: "Examples:\n  busnoop modbus /dev/ttyUSB0\n  busnoop modbus /dev/ttyUSB0 --line \
               9600-8N1 --stats\n  busnoop modbus capture.bin -f jsonl\n  busnoop modbus \
               /dev/ttyUSB0 --id 3 --type Exception,Timeout",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3) on the \
                  RS-485 pair (A, B and ground, no termination added), a capture file (raw \
                  wire bytes, a busnoop .pcap or .pcapng recording) or `-` for standard input. \
                  File kinds are recognised by content.",
    line: LINE,
    inverted: false,
    rates: &[DEFAULT_BAUD, 9600, 38_400, 57_600, 115_200, 4800],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw serial bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Resp ms Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 22, 40, 4, 7, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[
        ("timeout-ms", "master timeouts"),
        ("slaves", "slave names"),
        ("registers", "register maps"),
    ],
    export: Some(Export {
        linktype: crate::pcap::linktype::RAW,
        linktype_name: "RAW",
        dissector: "mbudp (Wireshark's own Modbus/UDP)",
        extcap: "Modbus RTU (busnoop)",
        wrap: Some(wrap),
    }),
};

fn wrap() -> Box<dyn crate::protocol::Wrap> {
    Box::<export::ModbusWrap>::default()
}

/// `detect` reads the bytes as RTU and as ASCII, at the line it listens to.
fn variants(probe: &Probe) -> Vec<Variant> {
    let opts = |framing| Options {
        line: probe.line,
        framing,
        ..Options::default()
    };
    vec![
        Variant {
            label: "Modbus RTU",
            args: &[],
            decoder: decoder(opts(Framing::Rtu)),
        },
        Variant {
            label: "Modbus ASCII",
            args: &["--ascii"],
            decoder: decoder(opts(Framing::Ascii)),
        },
    ]
}

/// The framing on the line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Framing {
    /// Binary frames with a CRC-16 (the usual one).
    #[default]
    Rtu,
    /// `:`, hexadecimal text, an LRC, CR LF.
    Ascii,
}

/// Decoder settings.
#[derive(Clone, Debug)]
pub struct Options {
    /// The line's speed and character format (Millis of sources without times).
    pub line: Line,
    /// Master timeout (ms): a request without an answer for this long is a `Timeout`, an answer
    /// after it is late.
    pub timeout_ms: u64,
    /// Slave names and register names, types and units.
    pub map: RegisterMap,
    pub framing: Framing,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            line: LINE,
            timeout_ms: DEFAULT_TIMEOUT_MS,
            map: RegisterMap::default(),
            framing: Framing::Rtu,
        }
    }
}

/// The Modbus decoder for `opts`.
pub fn decoder(opts: Options) -> Box<dyn Decoder> {
    Box::new(ModbusDecoder::new(opts))
}

#[cfg(test)]
pub(crate) mod tests;
