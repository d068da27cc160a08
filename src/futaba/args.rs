//! `busnoop futaba`'s own options: none beyond the ones every protocol shares (`--baud` sets
//! the byte times of raw files too).

use crate::exit::Failure;
use crate::protocol::{Decoder, Options, Setup};

/// The options of `busnoop futaba`.
#[derive(clap::Args, Debug)]
pub struct Args {}

impl Options for Args {
    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        Ok(super::decoder(super::Options {
            baud: setup.line.baud,
        }))
    }
}
