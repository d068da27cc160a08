//! FrSky F.Port (v1), F.Port 2 and FBUS: the receiver's channels and the S.Port telemetry on
//! one inverted wire. Reassembly of both framings, the choice between them, the log table
//! mapping (telemetry through the S.Port table) and statistics. See `docs/fport.md`.

mod args;
mod decoder;
pub mod detect;
mod direct;
pub mod frame;
mod map;
#[cfg(feature = "selfcheck")]
pub mod selfcheck;
mod stats;
mod table;
pub mod v1;
pub mod v2;
pub(crate) mod vocab;
pub mod wire;

pub use decoder::{FportDecoder, Reason};
pub use stats::{PhysStats, Stats};
pub use table::{COLUMNS, RECEIVER, V1_PHYS, V1_REQUEST_PHYS};

use crate::protocol::{Decoder, Front, InputKind, Line, Probe, Protocol};

/// F.Port and F.Port 2 run at 115200 baud 8N1.
pub const DEFAULT_BAUD: u32 = 115_200;
/// FBUS is F.Port 2 at 460800 baud.
pub const FBUS_BAUD: u32 = 460_800;
/// The line is inverted (idle low) like S.Port: an inverting adapter is needed (some
/// receivers have an uninverted F.Port 2 pad).
pub const INVERTED: bool = true;

/// FrSky F.Port, F.Port 2 and FBUS: 115200 baud 8N1 (FBUS 460800), inverted on the wire.
pub const PROTOCOL: Protocol = Protocol {
    name: "F.Port",
    command: "fport",
    aliases: &[],
    summary: "FrSky F.Port, F.Port 2, FBUS: receiver channels in µs and S.Port telemetry on one \
              wire (115200 baud, FBUS 460800)",
    about: "FrSky F.Port (v1), F.Port 2 and FBUS: the receiver's control frames (16 channels in \
            µs on Betaflight's scale 5/8 x + 880, flags, RSSI), its telemetry polls and the \
            flight controller's answers, decoded as S.Port sensor frames; OTA firmware-update \
            frames. The framing (v1: 0x7E-delimited and byte-stuffed; F.Port 2 and FBUS: \
            length-prefixed) is chosen from the stream or set with --variant. 115200 baud 8N1, \
            FBUS 460800, inverted on the wire: the adapter must invert (docs/fport.md).",
    examples: "Examples:\n  busnoop fport /dev/ttyUSB0\n  busnoop fport /dev/ttyUSB0 --variant \
               fbus\n  busnoop fport flight.bin --hide-polls --sensor VFAS\n  busnoop fport \
               flight.bin --wide -o channels.csv",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, a busnoop .pcap or .pcapng recording) or `-` for \
                  standard input. File kinds are recognised by content; `--baud` also sets the \
                  byte times of raw files.",
    line: Line::n81(DEFAULT_BAUD),
    inverted: INVERTED,
    rates: &[DEFAULT_BAUD, FBUS_BAUD],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Frame Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 10, 30, 4, 8, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[],
    export: None,
};

/// `detect` tries each framing on its own; at FBUS speed the F.Port 2 framing is FBUS.
fn variants(probe: &Probe) -> Vec<crate::protocol::Variant> {
    let baud = probe.line.baud;
    let v2 = if baud >= FBUS_BAUD {
        ("FBUS", &["--variant", "fbus"][..], Variant::Fbus)
    } else {
        ("F.Port 2", &["--variant", "v2"][..], Variant::V2)
    };
    [("F.Port v1", &["--variant", "v1"][..], Variant::V1), v2]
        .into_iter()
        .map(|(label, args, variant)| crate::protocol::Variant {
            label,
            args,
            decoder: decoder(Options {
                variant,
                baud: Some(baud),
            }),
        })
        .collect()
}

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
