//! SAB settings: line defaults, the table's extra columns, `--framing` and the decoder options.

use super::hdlc;
use crate::protocol::{InputKind, Line, Protocol};

/// SAB runs at 115200 baud 8N1.
pub const DEFAULT_BAUD: u32 = 115_200;

/// What the shared command-line code needs to know about SAB.
pub const PROTOCOL: Protocol = Protocol {
    name: "SAB",
    command: "sab2",
    line: Line::n81(DEFAULT_BAUD),
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor#(0x10) Sensor Data | Unit Addr Resp ms Framing Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 10, 36, 4, 4, 7, 7, 0],
    vocab: &super::vocab::VOCAB,
};

/// modm's `sab::Master` waits 10 ms for a response.
pub const DEFAULT_TIMEOUT_MS: u64 = 10;
/// Bits per byte on the wire (8N1: start, 8 data, stop), for time reconstruction.
pub const BITS_PER_BYTE: u64 = 10;
/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Addr", "Resp ms", "Framing", "Note"];

/// `--framing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FramingChoice {
    /// Detect the framing from the stream (and say which one was chosen).
    Auto,
    /// SAB v1: `54 LEN HDR CMD DATA CRC8` (what modm's documentation describes).
    Sync,
    /// SAB2: `7E HDR CMD DATA CRC16 7E`, byte-stuffed (what modm's SAB2 code sends).
    Hdlc,
}

/// Decoder settings.
#[derive(Clone, Debug)]
pub struct Options {
    pub framing: FramingChoice,
    /// Baud rate, used to reconstruct time for sources without time.
    pub baud: u32,
    /// Master timeout in µs.
    pub timeout_micros: u64,
    /// SAB2 payload limit (modm's template parameter `N`).
    pub max_payload: usize,
    /// `(name, address)` pairs for the Device column.
    pub devices: Vec<(String, u8)>,
    /// `(name, command)` pairs for the Sensor column.
    pub commands: Vec<(String, u8)>,
    /// How payloads are read as numbers (`--value`, `[sab2.values]`); the default rule for the
    /// commands not declared.
    pub values: Vec<super::values::Declared>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            framing: FramingChoice::Auto,
            baud: DEFAULT_BAUD,
            timeout_micros: DEFAULT_TIMEOUT_MS * 1000,
            max_payload: hdlc::DEFAULT_MAX_PAYLOAD,
            devices: Vec::new(),
            commands: Vec::new(),
            values: Vec::new(),
        }
    }
}
