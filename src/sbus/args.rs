//! `busnoop sbus`'s own options (the one file of the folder that knows clap).

use clap::ValueEnum;

use super::{DEFAULT_PORT, Mode};
use crate::exit::Failure;
use crate::protocol::front::FileKeys;
use crate::protocol::{Decoder, Options, Setup};

/// The options of `busnoop sbus`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Serial mode; auto picks data/secure mode when the stream uses 0xB5 framing, break mode
    /// otherwise.
    #[arg(long, value_enum, default_value_t = SbusMode::Auto)]
    pub mode: SbusMode,

    /// Master timeout in ms for Timeout rows and late answers [default: by mode and baud rate
    /// (375 ms data mode, 250 ms break/parity mode at 9600), 1000 ms for Ether-S-Bus].
    #[arg(long, value_name = "MS", value_parser = crate::protocol::front::parse_ms)]
    pub timeout_ms: Option<u64>,

    /// Serial sources with time: a silence longer than this ends a telegram [default: 20
    /// character times, at least 20 ms].
    #[arg(long, value_name = "MS", value_parser = crate::protocol::front::parse_ms)]
    pub gap_ms: Option<u64>,

    /// Name a station in the Device column (repeatable), e.g. `--station Boiler=10`; the same
    /// as --name.
    // Hidden: `--name` is the one way to name a device; this stays for older command lines.
    #[arg(long = "station", value_name = "NAME=ADDR", value_parser = super::parse_station,
          hide = true)]
    pub stations: Vec<(String, u8)>,

    /// Ether-S-Bus UDP port (datagrams to or from it are decoded).
    // `--port` was its name first; kept as a hidden alias.
    #[arg(long = "udp-port", alias = "port", value_name = "PORT",
          default_value_t = DEFAULT_PORT,
          value_parser = crate::protocol::front::parse_port)]
    pub port: u16,
}

/// `sbus --mode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SbusMode {
    /// Data/secure mode when the stream uses 0xB5 framing, break mode otherwise.
    Auto,
    /// SM2 data mode (0xB5 framing, DLE escaping); secure telegrams are read too.
    Data,
    /// SM2 secure data mode (`B5 10|11 LEN SEQ` + telegram); standard telegrams are read too.
    Secure,
    /// SM0 break mode: a break (read as 0x00) before each request.
    Break,
    /// SM1 parity mode: the 9th bit marks the address (lost by most UARTs).
    Parity,
}

impl Options for Args {
    fn configure(&mut self, file: &FileKeys<'_>) -> Result<(), Failure> {
        if self.timeout_ms.is_none() {
            self.timeout_ms = file.millis("timeout-ms")?;
        }
        Ok(())
    }

    fn names(&self) -> Vec<String> {
        self.stations
            .iter()
            .map(|(n, a)| format!("{n}={a}"))
            .collect()
    }

    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        let opts = super::Options {
            mode: match self.mode {
                SbusMode::Auto => Mode::Auto,
                SbusMode::Data => Mode::Data,
                SbusMode::Secure => Mode::Secure,
                SbusMode::Break => Mode::Break,
                SbusMode::Parity => Mode::Parity,
            },
            baud: setup.line.baud,
            timeout_ms: self.timeout_ms,
            gap_ms: self.gap_ms,
            stations: setup.names_u8(),
            port: self.port,
        };
        Ok(super::decoder(opts, setup.input))
    }
}
