//! `busnoop fport`'s own options (the one file of the folder that knows clap).

use clap::ValueEnum;

use super::{FBUS_BAUD, Variant};
use crate::exit::Failure;
use crate::protocol::{Decoder, Line, Options, Setup};

/// The options of `busnoop fport`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Which F.Port: `v1` (0x7E-delimited, byte-stuffed), `v2` (F.Port 2: length-prefixed),
    /// `fbus` (F.Port 2 framing at 460800 baud), `auto` = choose the framing from the stream
    /// and say which one was chosen (--stats).
    #[arg(long, value_enum, default_value_t = FportVariant::Auto)]
    pub variant: FportVariant,
}

/// `fport --variant`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FportVariant {
    /// Choose the framing from the stream.
    Auto,
    /// F.Port (v1): `7E len type data crc 7E`, byte-stuffed, 115200 baud.
    #[value(alias = "fport", alias = "1")]
    V1,
    /// F.Port 2: `len type data crc`, no stuffing, 115200 baud.
    #[value(alias = "fport2", alias = "2")]
    V2,
    /// FBUS: the F.Port 2 framing at 460800 baud.
    Fbus,
}

impl FportVariant {
    fn variant(self) -> Variant {
        match self {
            FportVariant::Auto => Variant::Auto,
            FportVariant::V1 => Variant::V1,
            FportVariant::V2 => Variant::V2,
            FportVariant::Fbus => Variant::Fbus,
        }
    }
}

impl Options for Args {
    /// FBUS runs at 460800 baud.
    fn line(&self, line: Line) -> Line {
        match self.variant {
            FportVariant::Fbus => Line {
                baud: FBUS_BAUD,
                ..line
            },
            _ => line,
        }
    }

    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        Ok(super::decoder(super::Options {
            variant: self.variant.variant(),
            baud: Some(setup.line.baud),
        }))
    }
}
