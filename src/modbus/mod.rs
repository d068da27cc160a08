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

pub mod ascii;
mod decoder;
pub mod export;
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

use crate::protocol::{Decoder, Kind, Line, Parity, Protocol};

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

/// What the shared command-line code needs to know: 19200 8E1, raw bytes, live lines and
/// recordings.
pub const PROTOCOL: Protocol = Protocol {
    name: "Modbus",
    command: "modbus",
    line: LINE,
    accepts: &[Kind::Raw, Kind::Serial, Kind::Recording],
    accepts_text: "raw serial bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Resp ms Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 22, 40, 4, 7, 0],
    vocab: &vocab::VOCAB,
};

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
