//! The options that choose rows and name devices (shared by every protocol), the project file
//! `busnoop.toml`, and how the two combine into a [`Spec`](crate::filter::Spec).
//!
//! The project file holds one table per protocol (`[sport]`, `[sbus]`, `[sab2]`) with defaults
//! (`baud`, `format`, `stats`, `timeout-ms` where the protocol has one), `names`, SAB's
//! `commands` and a `filter` table. Unknown keys and bad values are errors that name the file
//! and the line. Options on the command line override the file: a list option given on the
//! command line replaces the file's list, names are added (the command line's name for an ID
//! wins), and a switch (`--hide-polls`) is on when either turns it on. `docs/config.md`
//! describes the format.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use serde::{Deserialize, Deserializer, de::Error as _};

use crate::cli::OutputArgs;
use crate::exit::Failure;
use crate::filter::{Filter, Names, Selection, Spec};
use crate::protocol::Protocol;
use crate::sink::Format;

/// The file looked for in the current directory.
pub const FILE_NAME: &str = "busnoop.toml";

/// Filters and names, shared by every protocol.
#[derive(Args, Debug, Clone, Default)]
#[command(next_help_heading = "Filters and names (AND across options, OR within one)")]
pub struct SelectArgs {
    /// Show only rows of these IDs: `2,8`, `0x1B`, ranges `0-9` (repeatable).
    #[arg(long, value_name = "LIST")]
    pub id: Vec<String>,

    /// Hide the rows of these IDs (same forms as --id).
    #[arg(long, value_name = "LIST")]
    pub not_id: Vec<String>,

    /// Show only rows of these types, e.g. `Data,BadCRC` (case-insensitive; S.Port: `Poll` is an
    /// unanswered poll).
    #[arg(long = "type", value_name = "LIST")]
    pub types: Vec<String>,

    /// Hide the rows of these types.
    #[arg(long = "not-type", value_name = "LIST")]
    pub not_types: Vec<String>,

    /// Hide polls nobody answered (S.Port).
    #[arg(long)]
    pub hide_polls: bool,

    /// Hide keep-alive rows (S.Port `Null`).
    #[arg(long)]
    pub hide_null: bool,

    /// Show only warning and error rows (and busnoop's own gap rows).
    #[arg(long)]
    pub errors: bool,

    /// Show only rows whose Sensor or Sensor # column is one of these, e.g. `Cels,RxBt` or
    /// `0x0210` (case-insensitive; hex numbers match with or without `0x` and leading zeros:
    /// `0210`, `210`).
    #[arg(long, value_name = "LIST")]
    pub sensor: Vec<String>,

    /// Show only rows whose Device column is one of these names (case-insensitive). A value
    /// with `=` names a device instead, like --name (`--device motor=5`).
    #[arg(long, value_name = "LIST")]
    pub device: Vec<String>,

    /// Name an ID in the Device column (repeatable): S.Port physical ID, S-Bus station, SAB
    /// address, e.g. `--name Pack=1`, `--name Boiler=0x0A`.
    #[arg(long, value_name = "NAME=ID")]
    pub name: Vec<String>,

    /// Read this project file instead of ./busnoop.toml.
    #[arg(long, value_name = "FILE", conflicts_with = "no_config")]
    pub config: Option<PathBuf>,

    /// Ignore ./busnoop.toml.
    #[arg(long)]
    pub no_config: bool,
}

/// The project file.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct File {
    #[serde(default)]
    pub sport: Section,
    #[serde(default)]
    pub sbus: Section,
    #[serde(default, alias = "sab")]
    pub sab2: Section,
}

/// One protocol's table. `timeout-ms` is refused for S.Port, `commands` for all but SAB (see
/// [`File::check`]).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Section {
    #[serde(default, deserialize_with = "baud")]
    pub baud: Option<u32>,
    #[serde(default, deserialize_with = "format")]
    pub format: Option<Format>,
    pub stats: Option<bool>,
    #[serde(default, deserialize_with = "millis")]
    pub timeout_ms: Option<u64>,
    /// Name → ID.
    #[serde(default)]
    pub names: BTreeMap<String, Value>,
    /// SAB: name → command code.
    #[serde(default)]
    pub commands: BTreeMap<String, Value>,
    /// SAB: command → `TYPE[*SCALE][:UNIT]` (`--value`), or per direction (`CMD.req = "u8"`).
    #[serde(default)]
    pub values: BTreeMap<String, ValueSpec>,
    #[serde(default)]
    pub filter: FilterSection,
}

/// `[<protocol>.filter]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct FilterSection {
    pub id: Option<List>,
    pub not_id: Option<List>,
    #[serde(rename = "type")]
    pub types: Option<List>,
    pub not_type: Option<List>,
    pub hide_polls: Option<bool>,
    pub hide_null: Option<bool>,
    pub errors: Option<bool>,
    pub sensor: Option<List>,
    pub device: Option<List>,
}

/// A number (`10`, `0x0A`) or a text (`"0-9"`, `"Cels"`).
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Value {
    Int(i64),
    Text(String),
}

impl Value {
    fn text(&self) -> String {
        match self {
            Value::Int(i) => i.to_string(),
            Value::Text(s) => s.clone(),
        }
    }
}

/// `[sab2.values]`: a declaration, or one per direction (`heading.req = "u8"` is a dotted key).
#[derive(Debug, Clone)]
pub enum ValueSpec {
    Spec(String),
    Directions(BTreeMap<String, String>),
}

/// What a `[sab2.values]` entry must be, for the error message.
const VALUE_SPEC: &str = "a text such as \"u16*0.01:m\" (TYPE[*SCALE][:UNIT]), or `req`/`ack` \
     entries of such texts (CMD.req = \"u8\")";

impl<'de> Deserialize<'de> for ValueSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ValueSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(VALUE_SPEC)
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<ValueSpec, E> {
                Ok(ValueSpec::Spec(v.to_owned()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<ValueSpec, A::Error> {
                let mut out = BTreeMap::new();
                while let Some((k, v)) = map.next_entry::<String, String>()? {
                    out.insert(k, v);
                }
                Ok(ValueSpec::Directions(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// One value or an array of them.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum List {
    One(Value),
    Many(Vec<Value>),
}

impl List {
    fn texts(l: &Option<List>) -> Vec<String> {
        match l {
            None => Vec::new(),
            Some(List::One(v)) => vec![v.text()],
            Some(List::Many(v)) => v.iter().map(Value::text).collect(),
        }
    }
}

fn baud<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    let v = i64::deserialize(d)?;
    if !crate::cli::BAUD_RANGE.contains(&v) {
        return Err(D::Error::custom(format!(
            "baud {v} is out of range (50 to 12000000)"
        )));
    }
    Ok(Some(v as u32))
}

fn millis<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    let v = i64::deserialize(d)?;
    match u64::try_from(v) {
        Ok(ms) if crate::cli::MS_RANGE.contains(&ms) => Ok(Some(ms)),
        _ => Err(D::Error::custom(format!(
            "timeout-ms {v} is out of range (1 to 3600000)"
        ))),
    }
}

fn format<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Format>, D::Error> {
    let s = String::deserialize(d)?;
    Format::from_str(&s, true).map(Some).map_err(|_| {
        D::Error::custom(format!(
            "format {s:?}: expected \"pretty\", \"tsv\", \"csv\" or \"jsonl\""
        ))
    })
}

/// The 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

impl File {
    /// Parses the text of a project file; errors name `path` and the line.
    pub fn parse(text: &str, path: &Path) -> Result<File, Failure> {
        let file: File = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map_or(String::new(), |s| format!(":{}", line_of(text, s.start)));
            Failure::Config(format!(
                "{}{line}: {}",
                path.display(),
                e.message().trim_end()
            ))
        })?;
        file.check(text, path)?;
        Ok(file)
    }

    /// Refuses keys a protocol does not have (`timeout-ms` for S.Port, `commands` outside SAB).
    fn check(&self, text: &str, path: &Path) -> Result<(), Failure> {
        let bad = |section: &str, key: &str, what: &str| {
            let line = find_key(text, section, key).map_or(String::new(), |l| format!(":{l}"));
            Failure::Config(format!(
                "{}{line}: [{section}] has no key `{key}`: {what}",
                path.display()
            ))
        };
        if self.sport.timeout_ms.is_some() {
            return Err(bad("sport", "timeout-ms", "S.Port has no master timeout"));
        }
        for (name, s) in [("sport", &self.sport), ("sbus", &self.sbus)] {
            if !s.commands.is_empty() {
                return Err(bad(
                    name,
                    "commands",
                    "command names are for SAB ([sab2.commands])",
                ));
            }
            if !s.values.is_empty() {
                return Err(bad(
                    name,
                    "values",
                    "value declarations are for SAB ([sab2.values])",
                ));
            }
        }
        for (name, s) in [
            ("sport", &self.sport),
            ("sbus", &self.sbus),
            ("sab2", &self.sab2),
        ] {
            let ints = match &s.filter.sensor {
                Some(List::One(Value::Int(_))) => true,
                Some(List::Many(v)) => v.iter().any(|v| matches!(v, Value::Int(_))),
                _ => false,
            };
            let table = format!("{name}.filter");
            if let (true, Some(line)) = (ints, find_key(text, &table, "sensor"))
                && let Some(literal) = radix_literal(text.lines().nth(line - 1).unwrap_or(""))
            {
                // `sensor = 0x0300` is the TOML integer 768, which busnoop would read as the
                // hex digits `768`: refuse it rather than select another sensor.
                return Err(Failure::Config(format!(
                    "{}:{line}: [{table}] sensor {literal} is a TOML integer, not hex digits: \
                     write sensor numbers as text, sensor = \"{literal}\"",
                    path.display()
                )));
            }
        }
        Ok(())
    }

    /// The project file a run reads: `--config FILE`, or ./busnoop.toml when it exists; none
    /// with `--no-config`.
    pub fn path(args: &SelectArgs) -> Option<PathBuf> {
        if args.no_config {
            return None;
        }
        match &args.config {
            Some(p) => Some(p.clone()),
            None => Some(PathBuf::from(FILE_NAME)).filter(|p| p.is_file()),
        }
    }

    /// Reads the project file ([`File::path`]). Returns the file and its name (for messages).
    pub fn load(args: &SelectArgs) -> Result<Option<(File, PathBuf)>, Failure> {
        let Some(path) = File::path(args) else {
            return Ok(None);
        };
        let text = match read_limited(&path) {
            Ok(b) if b.len() as u64 > MAX_SIZE => {
                return Err(Failure::Config(format!(
                    "{}: larger than 1 MiB, not a project file (busnoop.toml is a few lines of \
                     TOML)",
                    path.display()
                )));
            }
            Ok(b) => String::from_utf8(b)
                .map_err(|_| Failure::Config(format!("{}: not UTF-8 text", path.display())))?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(Failure::NotFound {
                    path,
                    hint: Some("--config names a project file that does not exist".into()),
                });
            }
            Err(e) => {
                return Err(Failure::Config(format!(
                    "cannot read {}: {e}",
                    path.display()
                )));
            }
        };
        Ok(Some((File::parse(&text, &path)?, path)))
    }

    /// The section of the protocol with subcommand `command`.
    pub fn section(&self, command: &str) -> &Section {
        match command {
            "sport" => &self.sport,
            "sbus" => &self.sbus,
            _ => &self.sab2,
        }
    }
}

/// The largest project file read: ample for any TOML a person writes, and a bound on what
/// `--config /dev/zero` (or a link to a capture) costs.
const MAX_SIZE: u64 = 1 << 20;

/// Reads `path` up to one byte past [`MAX_SIZE`], so that a larger file is told apart without
/// being read whole (it used to be: `/dev/zero` grew memory until the machine ran out).
fn read_limited(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_SIZE + 1)
        .read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// A `0x`, `0o` or `0b` integer literal outside quotes and comments on a `key = …` line.
fn radix_literal(line: &str) -> Option<&str> {
    let value = line.split_once('=')?.1;
    let mut quoted = None;
    for (i, c) in value.char_indices() {
        match (quoted, c) {
            (None, '"' | '\'') => quoted = Some(c),
            (Some(q), c) if c == q => quoted = None,
            (None, '#') => return None,
            (None, '0') => {
                let rest = &value[i..];
                if rest.starts_with("0x") || rest.starts_with("0o") || rest.starts_with("0b") {
                    let end = rest
                        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                        .unwrap_or(rest.len());
                    return Some(&rest[..end]);
                }
            }
            _ => {}
        }
    }
    None
}

/// The line of `key` inside `[section]` (or `[section.*]`), for messages.
fn find_key(text: &str, section: &str, key: &str) -> Option<usize> {
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

/// The filter and name options of one run: the command line over the file's section.
/// `extra_names` are names from protocol options (`--station`), as `NAME=ID`.
pub fn spec(args: &SelectArgs, file: Option<&Section>, extra_names: &[String]) -> Spec {
    let f = file.map(|s| &s.filter);
    let pick = |cli: &Vec<String>, file: fn(&FilterSection) -> &Option<List>| {
        if !cli.is_empty() {
            cli.clone()
        } else {
            f.map_or(Vec::new(), |f| List::texts(file(f)))
        }
    };
    let (named, device): (Vec<&String>, Vec<&String>) =
        args.device.iter().partition(|d| d.contains('='));
    let cli_devices: Vec<String> = device.into_iter().cloned().collect();
    let mut names: Vec<String> = Vec::new();
    if let Some(s) = file {
        names.extend(s.names.iter().map(|(n, v)| format!("{n}={}", v.text())));
    }
    names.extend(extra_names.iter().cloned());
    names.extend(named.into_iter().cloned());
    names.extend(args.name.iter().cloned());
    let flag = |cli: bool, file: fn(&FilterSection) -> Option<bool>| {
        cli || f.and_then(file).unwrap_or(false)
    };
    Spec {
        id: pick(&args.id, |f| &f.id),
        not_id: pick(&args.not_id, |f| &f.not_id),
        types: pick(&args.types, |f| &f.types),
        not_types: pick(&args.not_types, |f| &f.not_type),
        hide_polls: flag(args.hide_polls, |f| f.hide_polls),
        hide_null: flag(args.hide_null, |f| f.hide_null),
        errors: flag(args.errors, |f| f.errors),
        sensor: pick(&args.sensor, |f| &f.sensor),
        device: pick(&cli_devices, |f| &f.device),
        names,
    }
}

/// The file's own filter and names alone, checked so that a mistake in the file is reported
/// as the file's (with its name), not as an option's.
pub fn file_spec(section: &Section) -> Spec {
    spec(&SelectArgs::default(), Some(section), &[])
}

/// SAB's command names from the file, as `NAME=CODE`.
pub fn file_commands(section: &Section) -> Vec<String> {
    section
        .commands
        .iter()
        .map(|(n, v)| format!("{n}={}", v.text()))
        .collect()
}

/// SAB's value declarations from the file, as `CMD=SPEC` (`CMD.req=SPEC` for a dotted key).
pub fn file_values(section: &Section) -> Vec<String> {
    let mut out = Vec::new();
    for (cmd, v) in &section.values {
        match v {
            ValueSpec::Spec(s) => out.push(format!("{cmd}={s}")),
            ValueSpec::Directions(m) => {
                out.extend(m.iter().map(|(d, s)| format!("{cmd}.{d}={s}")));
            }
        }
    }
    out
}

/// The filter and names of a run on `protocol`: the file's section (checked on its own first,
/// so that its mistakes name the file), then the command line over it. `extra_names` come from
/// protocol options (`--station`), `sensors` are names the Sensor column gets from options
/// (SAB's commands).
pub fn selection(
    args: &SelectArgs,
    protocol: &Protocol,
    file: Option<(&Section, &Path)>,
    extra_names: &[String],
    sensors: &[String],
) -> Result<Selection, Failure> {
    let vocab = protocol.vocab;
    if let Some((section, path)) = file {
        let at = |table: &str, e: String| {
            Failure::Config(format!(
                "{}: [{}{table}] {}",
                path.display(),
                protocol.command,
                e.trim_start_matches("--")
            ))
        };
        let own = file_spec(section);
        let names = Names::parse(&own.names, "names", vocab).map_err(|e| at("", e))?;
        Filter::new(&own, vocab, &names, sensors, protocol.name).map_err(|e| at(".filter", e))?;
    }
    let spec = spec(args, file.map(|f| f.0), extra_names);
    let names = Names::parse(&spec.names, "--name", vocab).map_err(Failure::Usage)?;
    let filter =
        Filter::new(&spec, vocab, &names, sensors, protocol.name).map_err(Failure::Usage)?;
    Ok(Selection { filter, names })
}

/// Puts the file's defaults where the command line left an option unset: the format (unless
/// `-o`'s extension picks one), the baud rate, `stats`.
pub fn apply_defaults(section: &Section, output: &mut OutputArgs, baud: &mut Option<u32>) {
    if output.format.is_none() && output.output_file().and_then(Format::from_path).is_none() {
        output.format = section.format;
    }
    if baud.is_none() {
        *baud = section.baud;
    }
    if section.stats == Some(true) {
        output.stats = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<File, String> {
        File::parse(text, Path::new("busnoop.toml")).map_err(|f| f.to_string())
    }

    #[test]
    fn a_full_file() {
        let f = parse(
            r#"
[sport]
baud = 115200
format = "csv"
stats = true
names = { Pack = 1, Rx = 0x18 }

[sport.filter]
id = [1, "24"]
hide-polls = true
sensor = "Cels"

[sbus]
timeout-ms = 500
[sbus.names]
Boiler = 10

[sab.commands]
speed = 0x34
"#,
        )
        .unwrap();
        assert_eq!(f.sport.baud, Some(115_200));
        assert_eq!(f.sport.format, Some(Format::Csv));
        assert_eq!(f.sbus.timeout_ms, Some(500));
        let s = file_spec(&f.sport);
        assert_eq!(s.id, ["1", "24"]);
        assert!(s.hide_polls && !s.errors);
        assert_eq!(s.sensor, ["Cels"]);
        assert_eq!(s.names, ["Pack=1", "Rx=24"]);
        assert_eq!(file_commands(&f.sab2), ["speed=52"]);
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("[sport]\nbaud = 57600\nbogus = 1\n").unwrap_err();
        assert!(
            e.starts_with("busnoop.toml:3: unknown field `bogus`"),
            "{e}"
        );
        let e = parse("[sport.filter]\nid = 1\nhide_polls = true\n").unwrap_err();
        assert!(
            e.starts_with("busnoop.toml:3: unknown field `hide_polls`"),
            "{e}"
        );
        let e = parse("[sport]\nformat = \"xml\"\n").unwrap_err();
        assert!(
            e.starts_with("busnoop.toml:2:") && e.contains("\"jsonl\""),
            "{e}"
        );
        let e = parse("[sbus]\nbaud = 10\n").unwrap_err();
        assert!(
            e.starts_with("busnoop.toml:2:") && e.contains("out of range"),
            "{e}"
        );
        let e = parse("[sport]\n\ntimeout-ms = 5\n").unwrap_err();
        assert!(
            e.starts_with("busnoop.toml:3: [sport] has no key `timeout-ms`"),
            "{e}"
        );
        let e = parse("[sbus.commands]\nx = 1\n").unwrap_err();
        assert!(
            e.starts_with("busnoop.toml:1: [sbus] has no key `commands`"),
            "{e}"
        );
        let e = parse("[canbus]\n").unwrap_err();
        assert!(
            e.starts_with("busnoop.toml:1: unknown field `canbus`"),
            "{e}"
        );
        let e = parse("[sport\n").unwrap_err();
        assert!(e.starts_with("busnoop.toml:1:"), "{e}");
    }

    #[test]
    fn the_command_line_wins() {
        let f = parse("[sport.filter]\nid = \"0-9\"\nsensor = [\"Cels\"]\n[sport.names]\nA = 1\n")
            .unwrap();
        let args = SelectArgs {
            id: vec!["2".into()],
            hide_null: true,
            name: vec!["B=1".into()],
            device: vec!["motor=5".into(), "FLVSS".into()],
            ..SelectArgs::default()
        };
        let s = spec(&args, Some(&f.sport), &["S=3".into()]);
        assert_eq!(
            s.id,
            ["2"],
            "a list on the command line replaces the file's"
        );
        assert_eq!(
            s.sensor,
            ["Cels"],
            "the file's list where the command line has none"
        );
        assert!(s.hide_null);
        assert_eq!(
            s.names,
            ["A=1", "S=3", "motor=5", "B=1"],
            "command line last: it wins"
        );
        assert_eq!(s.device, ["FLVSS"]);
    }

    #[test]
    fn radix_literals_outside_quotes_and_comments() {
        assert_eq!(radix_literal("sensor = 0x0300"), Some("0x0300"));
        assert_eq!(
            radix_literal("sensor = [\"Cels\", 0xF1_01]"),
            Some("0xF1_01")
        );
        assert_eq!(radix_literal("sensor = 0b11 # x"), Some("0b11"));
        assert_eq!(radix_literal("sensor = \"0x0300\""), None);
        assert_eq!(radix_literal("sensor = '0x0300'"), None);
        assert_eq!(radix_literal("sensor = 300 # 0x0300"), None);
        assert_eq!(radix_literal("sensor = 100"), None);
    }
}
