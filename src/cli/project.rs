//! The options that choose rows and name devices (shared by every protocol), the project file
//! `busnoop.toml`, and how the two combine into a [`Spec`].
//!
//! The project file holds one table per protocol (`[sport]`, `[sbus]`, …: its subcommand or an
//! alias) with the keys every protocol has (`baud`, `format`, `stats`, `names` and a `filter`
//! table) and the protocol's own (its descriptor's `config_keys`, such as `timeout-ms`, read by
//! the protocol's options). Unknown keys and bad values are errors that name the file and the
//! line. Options on the command line override the file: a list option given on the
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
use crate::protocol::front::{FileKeys, find_key, line_of};
use crate::protocols::PROTOCOLS;
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

    /// Hide polls nobody answered.
    #[arg(long)]
    pub hide_polls: bool,

    /// Hide keep-alive rows (`Null`).
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

    /// Show only rows whose Device column is one of these names (case-insensitive), the names
    /// --name gives included.
    // A value with `=` names a device instead, as --name does (`--device motor=5`): the older
    // way, kept working but no longer shown.
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

/// The project file: one section per protocol, by its subcommand or an alias (`[sport]`,
/// `[sab]`), and the file's name and text for messages.
#[derive(Debug, Default)]
pub struct File {
    sections: BTreeMap<String, Section>,
    path: PathBuf,
    text: String,
}

/// One protocol's section: the keys every protocol has, and its own (the descriptor's
/// `config_keys`, read by the protocol's options).
#[derive(Debug, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub struct Section {
    #[serde(default, deserialize_with = "baud")]
    pub baud: Option<u32>,
    #[serde(default, deserialize_with = "format")]
    pub format: Option<Format>,
    pub stats: Option<bool>,
    /// Name → ID.
    #[serde(default)]
    pub names: BTreeMap<String, Value>,
    #[serde(default)]
    pub filter: FilterSection,
    /// The protocol's own keys.
    #[serde(flatten)]
    pub own: toml::Table,
}

/// The keys every protocol's section has.
const SHARED_KEYS: &str = "baud, format, stats, names, filter";

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

fn format<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Format>, D::Error> {
    let s = String::deserialize(d)?;
    Format::from_str(&s, true).map(Some).map_err(|_| {
        D::Error::custom(format!(
            "format {s:?}: expected \"pretty\", \"tsv\", \"csv\" or \"jsonl\""
        ))
    })
}

impl File {
    /// Parses the text of a project file; errors name `path` and the line.
    pub fn parse(text: &str, path: &Path) -> Result<File, Failure> {
        let err = |e: toml::de::Error| {
            let line = e
                .span()
                .map_or(String::new(), |s| format!(":{}", line_of(text, s.start)));
            Failure::Config(format!(
                "{}{line}: {}",
                path.display(),
                e.message().trim_end()
            ))
        };
        let raw: BTreeMap<String, Section> = toml::from_str(text).map_err(err)?;
        let at = |section: &str, key: Option<&str>| {
            let line = match key {
                Some(k) => find_key(text, section, k),
                None => find_section(text, section),
            };
            format!(
                "{}{}",
                path.display(),
                line.map_or(String::new(), |l| format!(":{l}"))
            )
        };
        let mut sections = BTreeMap::new();
        for (name, section) in raw {
            let Some(p) = PROTOCOLS.iter().find(|p| p.answers_to(&name)) else {
                let known: Vec<&str> = PROTOCOLS.iter().map(|p| p.command).collect();
                return Err(Failure::Config(format!(
                    "{}: unknown field `{name}`: sections are {}",
                    at(&name, None),
                    known
                        .iter()
                        .map(|c| format!("[{c}]"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            };
            for key in section.own.keys() {
                if p.config_keys.iter().any(|(k, _)| k == key) {
                    continue;
                }
                let owners: Vec<String> = PROTOCOLS
                    .iter()
                    .filter(|o| o.config_keys.iter().any(|(k, _)| k == key))
                    .map(|o| format!("[{}]", o.command))
                    .collect();
                let own: Vec<&str> = p.config_keys.iter().map(|(k, _)| *k).collect();
                let keys = if own.is_empty() {
                    SHARED_KEYS.to_string()
                } else {
                    format!("{SHARED_KEYS}, {}", own.join(", "))
                };
                let what = PROTOCOLS
                    .iter()
                    .flat_map(|o| o.config_keys.iter())
                    .find(|(k, _)| k == key)
                    .map(|(_, w)| *w);
                return Err(Failure::Config(match what {
                    Some(what) => format!(
                        "{}: [{name}] has no key `{key}`: {what} are for {}",
                        at(&name, Some(key)),
                        owners.join(", ")
                    ),
                    None => format!(
                        "{}: unknown field `{key}` in [{name}]; its keys are {keys}",
                        at(&name, Some(key))
                    ),
                }));
            }
            let ints = match &section.filter.sensor {
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
            if sections.insert(p.command.to_owned(), section).is_some() {
                return Err(Failure::Config(format!(
                    "{}: [{name}] repeats the section of {} ([{}]): keep one",
                    at(&name, None),
                    p.name,
                    p.command
                )));
            }
        }
        Ok(File {
            sections,
            path: path.to_owned(),
            text: text.to_owned(),
        })
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

    /// Reads the project file ([`File::path`]).
    pub fn load(args: &SelectArgs) -> Result<Option<File>, Failure> {
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
        Ok(Some(File::parse(&text, &path)?))
    }

    /// The file's name.
    pub fn name(&self) -> &Path {
        &self.path
    }

    /// What the file sets for `protocol`, in one line (`[sport] filter.id = [1], format =
    /// "csv"`); `None` when it has no section for it.
    pub fn settings(&self, protocol: &Protocol) -> Option<String> {
        fn flatten(prefix: &str, v: &toml::Value, out: &mut Vec<String>) {
            match v {
                toml::Value::Table(t) => {
                    for (k, v) in t {
                        flatten(&format!("{prefix}{k}."), v, out);
                    }
                }
                v => out.push(format!("{} = {}", prefix.trim_end_matches('.'), text(v))),
            }
        }
        fn text(v: &toml::Value) -> String {
            match v {
                toml::Value::String(s) => format!("{s:?}"),
                toml::Value::Integer(i) => i.to_string(),
                toml::Value::Float(f) => f.to_string(),
                toml::Value::Boolean(b) => b.to_string(),
                toml::Value::Datetime(d) => d.to_string(),
                toml::Value::Array(a) => {
                    let items: Vec<String> = a.iter().map(text).collect();
                    format!("[{}]", items.join(", "))
                }
                toml::Value::Table(t) => {
                    let items: Vec<String> = t
                        .iter()
                        .map(|(k, v)| format!("{k} = {}", text(v)))
                        .collect();
                    format!("{{ {} }}", items.join(", "))
                }
            }
        }
        let table: toml::Table = self.text.parse().ok()?;
        let (name, section) = table.iter().find(|(k, _)| protocol.answers_to(k))?;
        let mut parts = Vec::new();
        flatten("", section, &mut parts);
        Some(format!("[{name}] {}", parts.join(", ")))
    }

    /// The section of `protocol`, if the file has one.
    pub fn section(&self, protocol: &Protocol) -> Option<&Section> {
        self.sections.get(protocol.command)
    }

    /// The protocol's own keys of its section, for its options (empty when it has none).
    pub fn own_keys<'a>(&'a self, protocol: &'a Protocol, empty: &'a toml::Table) -> FileKeys<'a> {
        FileKeys {
            table: self.section(protocol).map_or(empty, |s| &s.own),
            path: &self.path,
            text: &self.text,
            section: protocol.command,
        }
    }
}

/// The line of the header `[section]` (or the first `[section.*]`).
fn find_section(text: &str, section: &str) -> Option<usize> {
    text.lines()
        .position(|l| {
            let t = l.trim();
            t.strip_prefix('[').is_some_and(|h| {
                let h = h.trim_end_matches(']').trim();
                h == section || h.starts_with(&format!("{section}."))
            })
        })
        .map(|i| i + 1)
}

/// The largest project file read: ample for any TOML a person writes, and a bound on what
/// `--config /dev/zero` (or a link to a capture) costs.
const MAX_SIZE: u64 = 1 << 20;

/// Reads `path` up to one byte past [`MAX_SIZE`], so that a larger file is told apart without
/// being read whole (`--config /dev/zero` would grow memory without end).
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
    Ok(Selection {
        filter,
        names,
        sensors: sensors.to_vec(),
    })
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
        let sport = f.section(&crate::sport::PROTOCOL).unwrap();
        assert_eq!(sport.baud, Some(115_200));
        assert_eq!(sport.format, Some(Format::Csv));
        let empty = toml::Table::new();
        let sbus = f.own_keys(&crate::sbus::PROTOCOL, &empty);
        assert_eq!(sbus.millis("timeout-ms").unwrap(), Some(500));
        let s = file_spec(sport);
        assert_eq!(s.id, ["1", "24"]);
        assert!(s.hide_polls && !s.errors);
        assert_eq!(s.sensor, ["Cels"]);
        assert_eq!(s.names, ["Pack=1", "Rx=24"]);
        // `[sab]` is the section of `sab2`, its alias.
        let sab = f.own_keys(&crate::sab::PROTOCOL, &empty);
        assert_eq!(sab.pairs("commands").unwrap(), ["speed=52"]);
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
        let s = spec(&args, f.section(&crate::sport::PROTOCOL), &["S=3".into()]);
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
