//! `busnoop sab2`'s own options and its project-file keys (the one file of the folder that knows
//! clap).

use clap::ValueEnum;

use super::{DEFAULT_TIMEOUT_MS, FramingChoice, hdlc};
use crate::exit::Failure;
use crate::protocol::front::FileKeys;
use crate::protocol::{Decoder, Options, Setup};

/// The options of `busnoop sab2`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Framing on the wire: `sync` = SAB v1 (`54 LEN HDR CMD DATA CRC8`, what modm's
    /// documentation describes), `hdlc` = SAB2 (`7E HDR CMD DATA CRC16 7E`, what modm's SAB2 code
    /// sends), `auto` = detect it and say which one was chosen.
    #[arg(long, value_enum, default_value_t = SabFraming::Auto)]
    pub framing: SabFraming,

    /// Name a command in the Sensor column (repeatable): `--command speed=0x34`,
    /// `--command reset=7`.
    #[arg(long, value_name = "NAME=CODE", value_parser = super::parse_command)]
    pub command: Vec<(String, u8)>,

    /// Read a command's payloads as numbers of a type (repeatable): CMD=TYPE[*SCALE][:UNIT], as
    /// `--value distance=u16*0.01:m`, `--value 0x34=f32:deg`. TYPE: u8 i8 u16 i16 u32 i32 f32
    /// (little endian); SCALE multiplies
    /// (a plain decimal); UNIT goes to the Unit column. CMD is a code or a --command name, with
    /// `.req` or `.ack` for one direction only. Undeclared payloads of 1, 2 or 4 bytes are
    /// unsigned integers.
    #[arg(long, value_name = "CMD=TYPE")]
    // The text above is `--help`'s, as written there: `[:UNIT]` is not a link.
    #[allow(rustdoc::broken_intra_doc_links)]
    pub value: Vec<String>,

    /// Master timeout: a request without a response within this time gets a `Timeout` row
    /// [default: 10].
    #[arg(long, value_name = "MS", value_parser = crate::protocol::front::parse_ms)]
    pub timeout_ms: Option<u64>,

    /// SAB2 payload limit (modm's template parameter `N` of `sab2::Interface`): longer frames
    /// are flagged as overlong.
    #[arg(long, value_name = "BYTES", default_value_t = hdlc::DEFAULT_MAX_PAYLOAD as u16,
          value_parser = crate::protocol::front::parse_byte_count)]
    pub max_payload: u16,

    /// The project file's value declarations (`[sab2.values]`), before the command line's.
    #[arg(skip)]
    file_values: Vec<String>,
}

/// `sab2 --framing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SabFraming {
    /// Detect the framing from the stream (and say which one was chosen).
    Auto,
    /// SAB v1: `54 LEN HDR CMD DATA CRC8` (what modm's documentation describes).
    #[value(alias = "sab1", alias = "v1")]
    Sync,
    /// SAB2: `7E HDR CMD DATA CRC16 7E`, byte-stuffed (what modm's SAB2 code sends).
    #[value(alias = "sab2")]
    Hdlc,
}

impl Options for Args {
    fn configure(&mut self, file: &FileKeys<'_>) -> Result<(), Failure> {
        if self.timeout_ms.is_none() {
            self.timeout_ms = file.millis("timeout-ms")?;
        }
        // The file's command names first, the command line's after them (later ones win).
        let mut commands = Vec::new();
        for c in file.pairs("commands")? {
            commands.push(super::parse_command(&c).map_err(|e| file.error("commands", &e))?);
        }
        commands.append(&mut self.command);
        self.command = commands;
        self.file_values = file_values(file)?;
        // Checked here, so that a mistake names the file.
        for v in &self.file_values {
            super::declare::parse_value(v, &self.command).map_err(|e| file.error("values", &e))?;
        }
        Ok(())
    }

    fn check(&self) -> Result<(), Failure> {
        super::check_commands(&self.command).map_err(Failure::Usage)
    }

    fn sensors(&self) -> Vec<String> {
        self.command.iter().map(|(n, _)| n.clone()).collect()
    }

    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure> {
        // The file's declarations first, the command line's over them (later ones win).
        let mut values = Vec::new();
        for v in &self.file_values {
            values.push(
                super::declare::parse_value(v, &self.command)
                    .map_err(|e| Failure::Config(format!("[sab2.values] {e}")))?,
            );
        }
        for v in &self.value {
            values.push(
                super::declare::parse_value(v, &self.command)
                    .map_err(|e| Failure::Usage(format!("--value {e}")))?,
            );
        }
        let opts = super::Options {
            framing: match self.framing {
                SabFraming::Auto => FramingChoice::Auto,
                SabFraming::Sync => FramingChoice::Sync,
                SabFraming::Hdlc => FramingChoice::Hdlc,
            },
            baud: setup.line.baud,
            timeout_micros: self.timeout_ms.unwrap_or(DEFAULT_TIMEOUT_MS) * 1000,
            max_payload: self.max_payload as usize,
            devices: setup.names_u8(),
            commands: self.command.clone(),
            values,
        };
        Ok(super::decoder(opts))
    }
}

/// `[sab2.values]`: `CMD = "TYPE[*SCALE][:UNIT]"`, or one per direction (`CMD.req = "u8"`, a
/// dotted key), as `CMD=SPEC` / `CMD.req=SPEC` texts.
fn file_values(file: &FileKeys<'_>) -> Result<Vec<String>, Failure> {
    const WHAT: &str = "expected a text such as \"u16*0.01:m\" (TYPE[*SCALE][:UNIT]), or `req`/`ack` \
         entries of such texts (CMD.req = \"u8\")";
    let Some(v) = file.get("values") else {
        return Ok(Vec::new());
    };
    let toml::Value::Table(t) = v else {
        return Err(file.error("values", WHAT));
    };
    let mut out = Vec::new();
    let bad = |cmd: &str, v: &toml::Value| {
        let shown = match v {
            toml::Value::Integer(i) => i.to_string(),
            other => format!("a {}", other.type_str()),
        };
        file.error_in("values", Some(cmd), &format!("{cmd} = {shown}: {WHAT}"))
    };
    for (cmd, v) in t {
        match v {
            toml::Value::String(s) => out.push(format!("{cmd}={s}")),
            toml::Value::Table(dirs) => {
                for (d, s) in dirs {
                    let toml::Value::String(s) = s else {
                        return Err(bad(&format!("{cmd}.{d}"), s));
                    };
                    out.push(format!("{cmd}.{d}={s}"));
                }
            }
            _ => return Err(bad(cmd, v)),
        }
    }
    Ok(out)
}
