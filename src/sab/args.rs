//! Command-line arguments of `busnoop sab2` (alias `sab`).

use clap::Args;

use super::{DEFAULT_TIMEOUT_MS, FramingChoice, Options, hdlc};
use crate::cli::CaptureArgs;

#[derive(Args, Debug)]
pub struct SabArgs {
    #[command(flatten)]
    pub capture: CaptureArgs,

    /// Framing on the wire: `sync` = SAB v1 (`54 LEN HDR CMD DATA CRC8`, what modm's
    /// documentation describes), `hdlc` = SAB2 (`7E HDR CMD DATA CRC16 7E`, what modm's SAB2 code
    /// sends), `auto` = detect it and say which one was chosen.
    #[arg(long, value_enum, default_value_t = FramingChoice::Auto)]
    pub framing: FramingChoice,

    /// Name an address in the Device column (repeatable): `--device motor=5`,
    /// `--device imu=0x12`.
    #[arg(long, value_name = "NAME=ADDR", value_parser = parse_device)]
    pub device: Vec<(String, u8)>,

    /// Name a command in the Sensor column (repeatable): `--command speed=0x34`,
    /// `--command reset=7`.
    #[arg(long, value_name = "NAME=CODE", value_parser = parse_command)]
    pub command: Vec<(String, u8)>,

    /// Master timeout: a request without a response within this time gets a `Timeout` row.
    #[arg(long, value_name = "MS", default_value_t = DEFAULT_TIMEOUT_MS,
          value_parser = clap::value_parser!(u64).range(1..=3_600_000))]
    pub timeout_ms: u64,

    /// SAB2 payload limit (modm's template parameter `N` of `sab2::Interface`): longer frames
    /// are flagged as overlong.
    #[arg(long, value_name = "BYTES", default_value_t = hdlc::DEFAULT_MAX_PAYLOAD as u16,
          value_parser = clap::value_parser!(u16).range(1..=255))]
    pub max_payload: u16,
}

impl SabArgs {
    /// The decoder settings for a line at `baud` (`--baud` or the protocol's default): raw
    /// captures carry no time, busnoop reconstructs it from the byte position, 10 bits per byte
    /// at this rate.
    pub fn options(&self, baud: u32) -> Options {
        Options {
            framing: self.framing,
            baud,
            timeout_micros: self.timeout_ms * 1000,
            max_payload: self.max_payload as usize,
            devices: self.device.clone(),
            commands: self.command.clone(),
        }
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

/// `NAME=CODE`, command 0..=255.
pub fn parse_command(arg: &str) -> Result<(String, u8), String> {
    parse_pair(arg, "CODE", 0xFF)
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
