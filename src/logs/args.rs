//! `busnoop log`'s own options: none beyond the ones every protocol shares.

use crate::exit::Failure;
use crate::protocol::{Decoder, Options, Setup};

/// The options of `busnoop log`.
#[derive(clap::Args, Debug)]
pub struct Args {}

impl Options for Args {
    fn decoder(&self, _setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        Ok(super::decoder())
    }
}
