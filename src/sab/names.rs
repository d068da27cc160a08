//! Names for the Device and Sensor columns, from `--device` and `--command`.

use super::config::Options;
use super::header::ADDRESSES;

/// Names from `--device` and `--command`.
#[derive(Clone, Debug)]
pub(super) struct Names {
    devices: Vec<String>,
    commands: Vec<String>,
}

impl Names {
    pub(super) fn new(opts: &Options) -> Self {
        let mut devices = vec![String::new(); ADDRESSES];
        let mut commands = vec![String::new(); 256];
        for (name, addr) in &opts.devices {
            if let Some(slot) = devices.get_mut(*addr as usize) {
                slot.clone_from(name);
            }
        }
        for (name, code) in &opts.commands {
            commands[*code as usize].clone_from(name);
        }
        Names { devices, commands }
    }

    pub(super) fn device(&self, addr: u8) -> &str {
        self.devices.get(addr as usize).map_or("", String::as_str)
    }

    pub(super) fn command(&self, code: u8) -> &str {
        &self.commands[code as usize]
    }
}
