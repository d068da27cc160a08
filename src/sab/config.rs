//! SAB settings: line defaults, the table's extra columns, `--framing` and the decoder options.

use super::hdlc;
use crate::protocol::{Export, Front, InputKind, Line, Probe, Protocol, Variant};

/// SAB runs at 115200 baud 8N1.
pub const DEFAULT_BAUD: u32 = 115_200;

/// modm SAB / SAB2 at 115200 baud 8N1.
pub const PROTOCOL: Protocol = Protocol {
    name: "SAB",
    command: "sab2",
    aliases: &["sab"],
    summary: "modm SAB / SAB2: both framings (0x54 + CRC-8, 0x7E + CRC-16) auto-detected, \
              requests paired with responses",
    about: "modm SAB (Sensor Actuator Bus) and SAB2: SAB v1 frames `54 LEN HDR CMD DATA CRC8`, \
            SAB2 frames `7E HDR CMD DATA CRC16 7E` (byte-stuffed); the framing is detected (or \
            set with --framing), responses are paired with requests and timed. 115200 baud 8N1.",
    examples: "Examples:\n  busnoop sab2 /dev/ttyUSB0 --command speed=0x34\n  busnoop sab2 \
               session.bin --value speed=u16*0.01:m/s\n  busnoop sab2 session.bin --stats",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, a busnoop .pcap or .pcapng recording) or `-` for \
                  standard input. File kinds are recognised by content; `--baud` also sets the \
                  byte times of raw files.",
    line: Line::n81(DEFAULT_BAUD),
    inverted: false,
    rates: &[DEFAULT_BAUD, 9600, 19_200, 38_400, 57_600, 230_400],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor#(0x10) Sensor Data | Unit Addr Resp ms Framing Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 10, 36, 4, 4, 7, 7, 0],
    vocab: &super::vocab::VOCAB,
    front: Front::of::<super::args::Args>(),
    variants,
    config_keys: &[
        ("timeout-ms", "master timeouts"),
        ("commands", "command names"),
        ("values", "value declarations"),
    ],
    export: Some(Export {
        linktype: crate::pcap::linktype::USER1,
        linktype_name: "USER1",
        dissector: "busnoop-sab.lua",
        extcap: "modm SAB / SAB2 (busnoop)",
        wrap: None,
    }),
};

/// `detect` tries each framing on its own.
fn variants(probe: &Probe) -> Vec<Variant> {
    [
        ("SAB v1 (sync framing)", FramingChoice::Sync),
        ("SAB2 (HDLC framing)", FramingChoice::Hdlc),
    ]
    .into_iter()
    .map(|(label, framing)| Variant {
        label,
        args: &[],
        decoder: super::decoder(Options {
            framing,
            baud: probe.line.baud,
            ..Options::default()
        }),
    })
    .collect()
}

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
