//! A protocol's face towards the shared code: its own command-line options and how they become
//! a decoder ([`Front`], [`Options`]), its project-file keys ([`FileKeys`]), the ways `detect`
//! tries it ([`Variant`]) and its frames as packets for Wireshark ([`Export`]).
//!
//! A protocol's options are a clap `Args` struct in its folder (`args.rs`, the one file there
//! that knows clap); the command line adds them to the protocol's subcommand and hands them back
//! parsed, as an [`Options`] value. Everything else the decoder needs comes in a [`Setup`].

use std::path::Path;

use super::{Decoder, InputKind, Line};
use crate::exit::Failure;
use crate::row::{Row, Unframed};

/// Valid values of the millisecond options (`--timeout-ms`, `--gap-ms`, `timeout-ms` in the
/// project file): 1 ms to one hour.
pub const MS_RANGE: std::ops::RangeInclusive<u64> = 1..=3_600_000;

/// A whole number from `lo` to `hi`, the range said in words when it is not (clap's own
/// message reads `0 is not in 1..=3600000`).
pub fn whole_in(s: &str, lo: u64, hi: u64) -> Result<u64, String> {
    let t = s.trim();
    match t.parse::<u64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        Ok(_) => Err(format!("{t} is out of range: from {lo} to {hi}")),
        Err(_) if t.starts_with('-') => Err(format!("{t} is out of range: from {lo} to {hi}")),
        Err(_) => Err(format!("expected a whole number from {lo} to {hi}")),
    }
}

/// The millisecond options (`--timeout-ms`, `--gap-ms`): [`MS_RANGE`], in words.
pub fn parse_ms(s: &str) -> Result<u64, String> {
    whole_in(s, *MS_RANGE.start(), *MS_RANGE.end())
}

/// A byte count from 1 to 255 (`--max-payload`).
pub fn parse_byte_count(s: &str) -> Result<u16, String> {
    whole_in(s, 1, 255).map(|v| v as u16)
}

/// A UDP or TCP port, 1 to 65535.
pub fn parse_port(s: &str) -> Result<u16, String> {
    whole_in(s, 1, 65_535).map(|v| v as u16)
}

/// A protocol's own options: how to add them to its subcommand and how to read them back.
#[derive(Clone, Copy)]
pub struct Front {
    /// Adds the options to the subcommand (`clap::Args::augment_args` of the protocol's struct).
    pub args: fn(clap::Command) -> clap::Command,
    /// Reads them back from the parsed subcommand.
    pub parse: fn(&clap::ArgMatches) -> Result<Box<dyn Options>, clap::Error>,
}

impl Front {
    /// The front of the clap `Args` struct `A`.
    pub const fn of<A: clap::Args + clap::FromArgMatches + Options + 'static>() -> Front {
        Front {
            args: A::augment_args,
            parse: parse::<A>,
        }
    }
}

fn parse<A: clap::FromArgMatches + Options + 'static>(
    m: &clap::ArgMatches,
) -> Result<Box<dyn Options>, clap::Error> {
    Ok(Box::new(A::from_arg_matches(m)?))
}

/// What a decoder is built from besides the protocol's own options.
#[derive(Clone, Copy, Debug)]
pub struct Setup<'a> {
    /// What the input turned out to be (a network capture, raw bytes, a live line …).
    pub input: InputKind,
    /// The line: the protocol's, with `--baud` and `--line` applied (untimed bytes get their
    /// times from its speed).
    pub line: Line,
    /// Names given to IDs (`--name`, the project file's `names`), for the decoder's statistics.
    pub names: &'a [(String, u32)],
}

impl Setup<'_> {
    /// The names whose IDs fit a byte (S-Bus stations, SAB addresses).
    pub fn names_u8(&self) -> Vec<(String, u8)> {
        self.names
            .iter()
            .filter_map(|(n, id)| Some((n.clone(), u8::try_from(*id).ok()?)))
            .collect()
    }
}

/// A protocol's options, as parsed from its subcommand.
pub trait Options {
    /// The line its options imply, before `--baud` and `--line` (F.Port's `--variant fbus`
    /// runs at 460800); the protocol's own line by default.
    fn line(&self, line: Line) -> Line {
        line
    }

    /// Takes the protocol's keys of the project file ([`FileKeys`]: the descriptor's
    /// `config_keys`) where the command line left them unset.
    fn configure(&mut self, _file: &FileKeys<'_>) -> Result<(), Failure> {
        Ok(())
    }

    /// Checks the options as a whole once the project file's keys are in (SAB: one name for
    /// two commands): a usage error before any source is opened.
    fn check(&self) -> Result<(), Failure> {
        Ok(())
    }

    /// `NAME=ID` names its options give (S-Bus `--station`), for the Device column.
    fn names(&self) -> Vec<String> {
        Vec::new()
    }

    /// Names its options give the Sensor column (SAB `--command`), which `--sensor` accepts.
    fn sensors(&self) -> Vec<String> {
        Vec::new()
    }

    /// The decoder for this run.
    fn decoder(&self, setup: &Setup<'_>) -> Result<Box<dyn Decoder>, Failure>;
}

/// A protocol's own keys of its project-file section (`[sab2]` `commands`, `timeout-ms`), with
/// what messages about them need.
pub struct FileKeys<'a> {
    /// The keys besides the shared ones, as TOML values.
    pub table: &'a toml::Table,
    /// The file's name and text, for messages with a line number.
    pub path: &'a Path,
    pub text: &'a str,
    /// The section's name (`sab2`).
    pub section: &'a str,
}

impl FileKeys<'_> {
    /// The value of `key`.
    pub fn get(&self, key: &str) -> Option<&toml::Value> {
        self.table.get(key)
    }

    /// A mistake in `key`: the file, the line and the key in the message
    /// (`busnoop.toml:4: [sab2.commands] …`).
    pub fn error(&self, key: &str, what: &str) -> Failure {
        self.error_in(key, None, what)
    }

    /// A mistake in the entry `entry` of the table `key` (`[sab2.values]` `speed = 5`), at the
    /// entry's line when it can be found.
    pub fn error_in(&self, key: &str, entry: Option<&str>, what: &str) -> Failure {
        let table = format!("{}.{key}", self.section);
        let line = entry
            .and_then(|e| find_key(self.text, &table, e.trim_matches('"')))
            .or_else(|| find_key(self.text, self.section, key))
            .map_or(String::new(), |l| format!(":{l}"));
        Failure::Config(format!("{}{line}: [{table}] {what}", self.path.display()))
    }

    /// A number of milliseconds from 1 to one hour (`timeout-ms`).
    pub fn millis(&self, key: &str) -> Result<Option<u64>, Failure> {
        match self.get(key) {
            None => Ok(None),
            Some(toml::Value::Integer(v))
                if u64::try_from(*v).is_ok_and(|v| MS_RANGE.contains(&v)) =>
            {
                Ok(Some(*v as u64))
            }
            Some(v) => Err(self.error(
                key,
                &format!(
                    "{} is not a number of milliseconds from 1 to 3600000",
                    shown(v)
                ),
            )),
        }
    }

    /// A table of names (`speed = 0x34`, `"Boiler" = "10"`) as `NAME=VALUE` texts.
    pub fn pairs(&self, key: &str) -> Result<Vec<String>, Failure> {
        let Some(v) = self.get(key) else {
            return Ok(Vec::new());
        };
        let toml::Value::Table(t) = v else {
            return Err(self.error(key, "expected a table of NAME = VALUE"));
        };
        t.iter()
            .map(|(name, v)| match v {
                toml::Value::Integer(i) => Ok(format!("{name}={i}")),
                toml::Value::String(s) => Ok(format!("{name}={s}")),
                other => Err(self.error(
                    key,
                    &format!("{name} = {}: expected a number or a text", shown(other)),
                )),
            })
            .collect()
    }
}

/// A TOML value in a message: a number as it is, anything else by its type.
fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(f) => f.to_string(),
        other => format!("a {}", other.type_str()),
    }
}

/// The 1-based line of byte `offset` in `text`.
pub fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The line of `key` inside `[section]` (or `[section.*]`), for messages.
pub fn find_key(text: &str, section: &str, key: &str) -> Option<usize> {
    let mut inside = false;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if let Some(h) = t.strip_prefix('[') {
            let h = h.trim_end_matches(']').trim();
            inside = h == section || h.starts_with(&format!("{section}."));
            if inside && h == format!("{section}.{key}") {
                return Some(i + 1);
            }
            continue;
        }
        if inside
            && t.split(['=', '.'])
                .next()
                .is_some_and(|k| k.trim().trim_matches('"') == key)
        {
            return Some(i + 1);
        }
    }
    None
}

/// What `detect` tries a protocol on: the input's kind and the line it was read at (a live
/// port's speed and format; for files, the protocol's own line).
#[derive(Clone, Copy, Debug)]
pub struct Probe {
    pub input: InputKind,
    pub line: Line,
}

/// One way `detect` reads the bytes as a protocol (a mode, a framing).
pub struct Variant {
    /// "S-Bus break mode".
    pub label: &'static str,
    /// Options to add to the protocol's command for this variant (`--mode parity`).
    pub args: &'static [&'static str],
    pub decoder: Box<dyn Decoder>,
}

/// A protocol's frames as packets of a pcapng for Wireshark (`--export`, the extcap).
#[derive(Clone, Copy)]
pub struct Export {
    /// The pcapng link type (`USER0` = 147 …) and its name.
    pub linktype: u32,
    pub linktype_name: &'static str,
    /// What decodes the packets in Wireshark ("busnoop-sport.lua", or Wireshark's own
    /// dissector).
    pub dissector: &'static str,
    /// The extcap interface's name in Wireshark's list ("FrSky S.Port (busnoop)").
    pub extcap: &'static str,
    /// A packet per frame other than the frame's bytes as on the wire (serial S-Bus
    /// re-wrapped as Ether-S-Bus datagrams); `None`: the bytes as they were.
    pub wrap: Option<fn() -> Box<dyn Wrap>>,
}

/// Turns a row's frame into the packet the export writes.
pub trait Wrap {
    /// The packet of `row` into `out` (emptied first by the caller); `unframed`: the frame's
    /// content as the decoder re-read it, when it gives one.
    fn packet(&mut self, row: &Row<'_>, unframed: Option<&Unframed<'_>>, out: &mut Vec<u8>);
}
