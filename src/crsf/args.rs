//! `busnoop crsf`'s own options: none beyond the ones every protocol shares (`--baud`,
//! `--line`: the line, which also gives raw captures their byte times).

use crate::exit::Failure;
use crate::protocol::{Decoder, Options, Setup};

/// The options of `busnoop crsf`.
#[derive(clap::Args, Debug)]
pub struct Args {}

impl Options for Args {
    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        Ok(super::decoder(super::Options { line: setup.line }))
    }
}
