//! `busnoop modbus`'s own options and its project-file keys (the one file of the folder that
//! knows clap).

use super::{DEFAULT_TIMEOUT_MS, Framing, RegisterMap};
use crate::exit::Failure;
use crate::protocol::front::{FileKeys, MS_RANGE};
use crate::protocol::{Decoder, Options, Setup};

/// The options of `busnoop modbus`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Master timeout: a request without an answer within this time gets a `Timeout` row, an
    /// answer after it is late [default: 1000].
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(MS_RANGE))]
    pub timeout_ms: Option<u64>,

    /// Modbus ASCII (`:` … LRC CR LF, usually 7E1: add `--line 7E1`) instead of RTU.
    #[arg(long)]
    pub ascii: bool,

    /// The register map of the project file (`[modbus.slaves]`, `[modbus.registers]`).
    #[arg(skip)]
    map: RegisterMap,
}

impl Options for Args {
    fn configure(&mut self, file: &FileKeys<'_>) -> Result<(), Failure> {
        if self.timeout_ms.is_none() {
            self.timeout_ms = file.millis("timeout-ms")?;
        }
        self.map = RegisterMap::from_toml(file.table)
            .map_err(|e| file.error_in(e.table, e.entry.as_deref(), &entry_error(&e)))?;
        Ok(())
    }

    fn names(&self) -> Vec<String> {
        self.map
            .slaves
            .iter()
            .map(|(n, a)| format!("{n}={a}"))
            .collect()
    }

    fn sensors(&self) -> Vec<String> {
        self.map
            .registers()
            .iter()
            .map(|r| r.name.clone())
            .collect()
    }

    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        let mut map = self.map.clone();
        map.slaves = setup.names_u8();
        Ok(super::decoder(super::Options {
            line: setup.line,
            timeout_ms: self.timeout_ms.unwrap_or(DEFAULT_TIMEOUT_MS),
            map,
            framing: if self.ascii {
                Framing::Ascii
            } else {
                Framing::Rtu
            },
        }))
    }
}

/// A map mistake for [`FileKeys::error_in`], which names the table: the entry and what is wrong.
fn entry_error(e: &super::regmap::MapError) -> String {
    match &e.entry {
        Some(entry) => format!("{entry:?}: {}", e.what),
        None => e.what.clone(),
    }
}
