//! Names for the Device and Sensor columns, from `--device` and `--command`.

use super::config::Options;
use super::header::ADDRESSES;

/// Names from `--device` and `--command`.
#[derive(Clone, Debug)]
pub(super) struct Names {
    devices: Vec<String>,
    commands: Vec<String>,
    /// The name of a row's number per (command, request or ACK), index `command * 2 + ack`:
    /// the command's name or `0xNN`, `.req` after it for a request (`speed.req`, `0x34`).
    parts: Vec<String>,
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
        let mut parts = Vec::with_capacity(512);
        for (code, name) in commands.iter().enumerate() {
            let mut part = if name.is_empty() {
                crate::fmt::hex_0x(code as u8).to_owned()
            } else {
                name.clone()
            };
            let ack = part.clone();
            part.push_str(".req");
            parts.push(part);
            parts.push(ack);
        }
        Names {
            devices,
            commands,
            parts,
        }
    }

    pub(super) fn device(&self, addr: u8) -> &str {
        self.devices.get(addr as usize).map_or("", String::as_str)
    }

    pub(super) fn command(&self, code: u8) -> &str {
        &self.commands[code as usize]
    }

    /// The name of the number of a request (`ack` false) or ACK of `command` (`speed.req`,
    /// `0x34`).
    pub(super) fn part(&self, command: u8, ack: bool) -> &str {
        &self.parts[command as usize * 2 + usize::from(ack)]
    }
}

/// Parses `0x12`, `0X12` or `18`.
fn parse_number(text: &str) -> Option<u64> {
    let t = text.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => t.parse().ok(),
    }
}

fn parse_pair(arg: &str, what: &str, max: u64) -> Result<(String, u8), String> {
    let Some((name, value)) = arg.rsplit_once('=') else {
        return Err(format!("expected NAME={what}, for example motor=0x05"));
    };
    if name.is_empty() {
        return Err(format!("the name before `={value}` is empty"));
    }
    match parse_number(value) {
        Some(v) if v <= max => Ok((name.to_owned(), v as u8)),
        Some(_) => Err(format!(
            "{what} `{value}` is out of range 0..={max} (0x{max:02X})"
        )),
        None => Err(format!(
            "{what} `{value}` is not a number (write 0x34 for hex, 52 for decimal)"
        )),
    }
}

/// `NAME=ADDR`, address 0..=63.
pub fn parse_device(arg: &str) -> Result<(String, u8), String> {
    parse_pair(arg, "ADDR", super::header::ADDRESS_MASK as u64)
}

/// `NAME=CODE`, command 0..=255. The name becomes a column of the wide table and a series of
/// a plot, beside the time columns, the codes of unnamed commands (`0x10`) and request columns
/// (`speed.req`), and is chosen in comma-separated lists (`--sensor`) and as `NAME@ADDRESS`:
/// a name that would read as one of those is refused.
pub fn parse_command(arg: &str) -> Result<(String, u8), String> {
    let (name, code) = parse_pair(arg, "CODE", 0xFF)?;
    if ["Millis", "Date", "Time"]
        .iter()
        .any(|c| c.eq_ignore_ascii_case(name.trim()))
    {
        return Err(format!(
            "the name `{name}` is a time column of the wide table; choose another"
        ));
    }
    if parse_number(&name).is_some() {
        return Err(format!(
            "the name `{name}` reads as a command code; a name must not (the column of an \
             unnamed command is its code)"
        ));
    }
    if name.to_ascii_lowercase().ends_with(".req") {
        return Err(format!(
            "the name `{name}` ends with `.req`, which marks the payloads of requests"
        ));
    }
    if let Some(c) = name.chars().find(|c| matches!(c, ',' | '@')) {
        return Err(format!(
            "the name `{name}` holds `{c}`, which separates names in lists (`,`) and a name \
             from its address (`@`)"
        ));
    }
    Ok((name, code))
}

/// Refuses one name for two commands (the later `--command` of one code overrides an earlier
/// one, the project file's included): their numbers would share a column.
pub fn check_commands(commands: &[(String, u8)]) -> Result<(), String> {
    let mut last: std::collections::BTreeMap<u8, &str> = std::collections::BTreeMap::new();
    for (name, code) in commands {
        last.insert(*code, name);
    }
    let mut by_name: std::collections::BTreeMap<String, u8> = std::collections::BTreeMap::new();
    for (code, name) in last {
        if let Some(other) = by_name.insert(name.to_ascii_lowercase(), code) {
            return Err(format!(
                "--command: the name `{name}` is given to 0x{other:02X} and 0x{code:02X}; a \
                 name names one command"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn name_value_pairs() {
        assert_eq!(parse_device("motor=5"), Ok(("motor".into(), 5)));
        assert_eq!(parse_device("imu=0x3F"), Ok(("imu".into(), 63)));
        assert_eq!(parse_device("a=b=0X12"), Ok(("a=b".into(), 0x12)));
        assert!(parse_device("x=64").unwrap_err().contains("out of range"));
        assert!(parse_device("x=0x40").is_err());
        assert!(parse_device("x").unwrap_err().contains("NAME=ADDR"));
        assert!(parse_device("=3").unwrap_err().contains("empty"));
        assert!(parse_device("x=zz").unwrap_err().contains("not a number"));
        assert_eq!(parse_command("speed=0x34"), Ok(("speed".into(), 0x34)));
        assert_eq!(parse_command("reset=255"), Ok(("reset".into(), 255)));
        assert!(parse_command("big=256").is_err());
    }
}
