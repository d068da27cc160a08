//! modm SAB and SAB2 (Sensor Actuator Bus): both framings, auto-detection, request/response
//! pairing, the log table mapping and statistics.
//!
//! * `sync`: SAB v1 framing `54 LEN HDR CMD DATA CRC8` (backtracking reassembler).
//! * `hdlc`: SAB2 framing `7E HDR CMD DATA CRC16 7E` as modm's code sends it.
//! * `detect`: which of the two is on the line.
//! * [`header`]: flags, address, NACK codes; `pairing`: responses to requests, timeouts.
//! * [`SabDecoder`]: detection, reassembly and the table mapping together (`decoder`, `map`,
//!   `names`); the options and line defaults are in `config`.
//!
//! The table mapping, the timing rules and the options are documented in `docs/sab.md`.

mod args;
mod config;
pub(crate) mod declare;
mod decoder;
pub(crate) mod detect;
pub mod frame;
pub(crate) mod hdlc;
pub mod header;
mod map;
mod names;
pub(crate) mod pairing;
pub mod sample;
pub(crate) mod stats;
pub(crate) mod sync;
pub mod values;
mod vocab;

pub use config::{
    BITS_PER_BYTE, COLUMNS, DEFAULT_BAUD, DEFAULT_TIMEOUT_MS, FramingChoice, Options, PROTOCOL,
};
pub use decoder::SabDecoder;
pub use names::{check_commands, parse_command, parse_device};
pub use values::{Declared, Direction, Scale, ValueType};

/// The SAB decoder (every input kind [`PROTOCOL`] accepts is a byte stream).
pub fn decoder(opts: Options) -> Box<dyn crate::protocol::Decoder> {
    Box::new(SabDecoder::new(opts))
}

#[cfg(test)]
mod tests;
