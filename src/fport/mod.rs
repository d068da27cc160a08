//! FrSky F.Port (v1), F.Port 2 and FBUS: the receiver's channels and the S.Port telemetry on
//! one inverted wire. Reassembly of both framings, the choice between them, the log table
//! mapping (telemetry through the S.Port table) and statistics. See `docs/fport.md`.

mod decoder;
pub mod detect;
pub mod frame;
mod map;
#[cfg(feature = "selfcheck")]
pub mod selfcheck;
mod stats;
pub mod v1;
pub mod v2;
pub(crate) mod vocab;
pub mod wire;

pub use decoder::{FportDecoder, Reason};
pub use map::{COLUMNS, RECEIVER, V1_PHYS, V1_REQUEST_PHYS};
pub use stats::{PhysStats, Stats};

use crate::protocol::{Decoder, Kind, Line, Protocol};

/// F.Port and F.Port 2 run at 115200 baud 8N1.
pub const DEFAULT_BAUD: u32 = 115_200;
/// FBUS is F.Port 2 at 460800 baud.
pub const FBUS_BAUD: u32 = 460_800;
/// The line is inverted (idle low) like S.Port: an inverting adapter is needed (some
/// receivers have an uninverted F.Port 2 pad).
pub const INVERTED: bool = true;

/// What the command line needs to know: 115200 baud 8N1, inverted.
pub const PROTOCOL: Protocol = Protocol {
    name: "F.Port",
    command: "fport",
    line: Line::n81(DEFAULT_BAUD),
    accepts: &[Kind::Raw, Kind::Serial, Kind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Frame Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 10, 30, 4, 8, 0],
    vocab: &vocab::VOCAB,
};

/// `--variant`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Variant {
    /// Choose the framing from the stream (and say which one was chosen).
    #[default]
    Auto,
    /// F.Port v1: `7E`-delimited, byte-stuffed.
    V1,
    /// F.Port 2: length-prefixed, no stuffing.
    V2,
    /// FBUS: F.Port 2 framing at 460800 baud.
    Fbus,
}

/// The two framings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Framing {
    V1,
    V2,
}

/// Decoder settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    pub variant: Variant,
    /// Line speed, for the time of sources without time; `None`: the variant's (115200, FBUS
    /// 460800).
    pub baud: Option<u32>,
}

impl Options {
    /// The line speed in use.
    pub fn baud(&self) -> u32 {
        self.baud.unwrap_or(match self.variant {
            Variant::Fbus => FBUS_BAUD,
            _ => DEFAULT_BAUD,
        })
    }
}

/// The F.Port decoder for `opts` (every input kind [`PROTOCOL`] accepts is a byte stream).
pub fn decoder(opts: Options) -> Box<dyn Decoder> {
    Box::new(FportDecoder::new(opts))
}

#[cfg(test)]
mod tests;
