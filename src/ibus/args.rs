//! `busnoop ibus`'s own options and its project-file key (the one file of the folder that knows
//! clap).

use crate::exit::Failure;
use crate::protocol::front::FileKeys;
use crate::protocol::{Decoder, Options, Setup};

/// The options of `busnoop ibus`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The sensor type at an address (repeatable), for a capture that starts after the
    /// receiver's type queries: `--sensor-type 1=ExtV`, `--sensor-type 2=0x02`. TYPE is a
    /// Sensor name (IntV, Temp, RPM, ExtV, Curr, Fuel …) or a type code; a type answer in the
    /// capture wins.
    #[arg(long = "sensor-type", value_name = "ADDR=TYPE", value_parser = super::parse_sensor_type)]
    pub sensor_types: Vec<(u8, u8)>,
}

impl Options for Args {
    fn configure(&mut self, file: &FileKeys<'_>) -> Result<(), Failure> {
        // The file's first, the command line's after them (later ones win).
        let mut types = Vec::new();
        for p in file.pairs("sensor-types")? {
            types.push(super::parse_sensor_type(&p).map_err(|e| file.error("sensor-types", &e))?);
        }
        types.append(&mut self.sensor_types);
        self.sensor_types = types;
        Ok(())
    }

    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        Ok(super::decoder(super::Options {
            baud: setup.line.baud,
            types: self.sensor_types.clone(),
        }))
    }
}
