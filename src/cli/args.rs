//! The command line's options (clap stays here and in `project.rs`): one subcommand per
//! protocol, the options every capture shares, and the ranges numeric options accept.

use std::path::{Path, PathBuf};

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};

use super::{is_dash, project};
use crate::protocol::{InputKind, Options, Protocol};
use crate::protocols::PROTOCOLS;
use crate::sink::{Format, TableOptions};
use crate::source::serial;

#[derive(Parser, Debug)]
#[command(
    name = "busnoop",
    version,
    about = "Passive bus sniffer: listens to a serial bus (or replays a capture), reassembles \
             every frame and prints the S-Port_Snoop log table as coloured text, TSV, CSV or \
             JSON Lines.",
    override_usage = "busnoop <SOURCE> [OPTIONS]            detect the protocol, then decode\n       \
                      busnoop <PROTOCOL> <SOURCE> [OPTIONS] decode as PROTOCOL (sport, sbus …)\n       \
                      busnoop <COMMAND> …",
    after_help = "SOURCE: a serial device (/dev/ttyUSB0), a capture file, or - (standard input, \
                  with a PROTOCOL). `busnoop PROTOCOL -h` lists its options.\n\n\
                  Exit codes: 0 ok, 2 usage, 3 not found, 4 permission denied, 5 port busy, \
                  6 device error, 7 adapter disconnected, 8 output error, 9 input error, \
                  10 nothing decoded (empty input, or no frame of the protocol), \
                  11 no known protocol (detect), 12 bad project file, 13 mostly not frames of \
                  the protocol (--lenient accepts), 129 hangup, 130 Ctrl-C, 141 output closed, \
                  143 SIGTERM."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,

    /// More diagnostics on stderr (-v, -vv); RUST_LOG works too.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
}

/// The subcommands that are not a protocol (each protocol's subcommand is built from its
/// descriptor, see [`command`]).
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Which protocol is on this wire? Tries every protocol (S-Bus modes, SAB framings) on a
    /// file's first megabytes, or on a serial port at the usual baud rates, and prints the
    /// verdict, the evidence and the command to run.
    Detect(DetectArgs),
    /// Plot a capture's numbers as time series: one panel per unit, broken frames marked, as
    /// SVG or PNG (`busnoop plot flight.log --sensor Alt,VFAS -o flight.svg`).
    Plot(Box<PlotArgs>),
    /// List the serial ports of this machine (type, USB VID:PID, serial number, names).
    Ports,
    /// Wireshark extcap interface: lets Wireshark capture an S.Port or SAB bus live (install:
    /// docs/wireshark.md). Wireshark runs it; by hand, `busnoop extcap --extcap-interfaces`.
    Extcap(super::extcap::ExtcapArgs),
    /// Print the shell completion script for SHELL on standard output (see docs/usage.md, "Shell completions").
    Completions {
        /// The shell to complete in.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the manual page busnoop(1) (roff) on standard output, or with --dir write one page
    /// per command into a directory.
    Man {
        /// Write busnoop.1, busnoop-sport.1, … into this directory instead.
        #[arg(long, value_name = "DIR")]
        dir: Option<PathBuf>,
    },
}

/// `busnoop plot`.
#[derive(Args, Debug, Clone)]
pub struct PlotArgs {
    /// The capture to plot: a file (raw wire bytes, an EdgeTX/OpenTX log, a pcap) or `-` (a
    /// pipe, like a FIFO, needs --protocol: it can be read only once).
    pub source: PathBuf,
    /// The image to write: FILE.svg or FILE.png.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// The protocol [default: detected as by `busnoop detect`; required for `-` and FIFOs].
    #[arg(long, value_name = "NAME", value_parser = protocol_names())]
    pub protocol: Option<String>,
    /// Draw from this moment on: seconds since the capture's start (`90`, `1.5`), or a time of
    /// day (`12:34:56`) for sources with wall-clock time.
    #[arg(long, value_name = "TIME", value_parser = crate::plot::When::parse)]
    pub from: Option<crate::plot::When>,
    /// Draw up to this moment (as --from).
    #[arg(long, value_name = "TIME", value_parser = crate::plot::When::parse)]
    pub to: Option<crate::plot::When>,
    /// The table's row selection (--id, --type, --device, --name …) and the project file
    /// (--config, --no-config); `--sensor` names the numbers to plot (see its help).
    #[command(flatten)]
    pub select: project::SelectArgs,
    /// The protocol's own options, after `--`: `busnoop plot cap.bin -o x.svg --protocol sbus
    /// -- --mode data`, `-- --value 0x10=u16*0.01:m`, `-- --baud 38400`.
    #[arg(last = true, value_name = "PROTOCOL OPTIONS")]
    pub protocol_args: Vec<std::ffi::OsString>,
}

/// `busnoop plot --sensor`'s help (the table's `--sensor` selects rows; the plot's, series).
pub(super) const PLOT_SENSOR_HELP: &str = "The numbers to plot, by their names in the wide \
     table without unit (`Alt`, `VFAS`, `Cell1`, `Cell1@8`) or a sensor's Sensor column name \
     (`Volts`, `Cels`), comma-separated [default: every number]";

/// The subcommands of the protocols, for `plot --protocol`.
fn protocol_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(PROTOCOLS.iter().map(|p| p.command))
}

/// `--record`'s help; a protocol that reads network captures adds a sentence (see
/// [`record_help`]).
const RECORD_HELP: &str = "Keep what came off the wire while decoding: FILE.pcap or FILE.pcapng \
     with arrival times (busnoop replays both with the original Millis; Wireshark opens them; \
     pcapng also names the device and baud and comments reconnect gaps), FILE.bin or FILE.raw: \
     the raw bytes; `-`: the raw bytes on standard output (with -o FILE only). Other names are \
     refused";

/// `--record`'s help for `protocol`.
fn record_help(protocol: &Protocol) -> String {
    if protocol.reads(InputKind::Pcap) {
        format!(
            "{RECORD_HELP}. A pcap/pcapng capture of network traffic is recorded as its packets \
             (its link type, times, bytes): FILE.pcap, FILE.pcapng, or `-` as pcap; raw names are \
             refused for it"
        )
    } else {
        RECORD_HELP.to_owned()
    }
}

/// The whole command line: the fixed subcommands of [`Cli`] and one subcommand per protocol of
/// [`PROTOCOLS`], built from its descriptor (its help, its defaults, the shared options and its
/// own), protocols first.
pub fn command() -> clap::Command {
    let mut cmd = Cli::command();
    let fixed: Vec<String> = cmd
        .get_subcommands()
        .map(|c| c.get_name().to_owned())
        .collect();
    for (i, p) in PROTOCOLS.iter().enumerate() {
        cmd = cmd.subcommand(protocol_command(p).display_order(i));
    }
    for (i, name) in fixed.iter().enumerate() {
        cmd = cmd.mut_subcommand(name, |c| c.display_order(PROTOCOLS.len() + i));
    }
    cmd.mut_subcommand("plot", |c| {
        c.mut_arg("sensor", |a| a.help(PLOT_SENSOR_HELP))
    })
}

/// The subcommand of `p`.
///
/// Built in one pass over its options: clap's `Command::mut_arg` moves the option it edits to
/// the end of the list (a `Vec::remove` of large `Arg`s), and editing each of some sixty options
/// that way for every protocol cost two thirds of busnoop's start-up. The protocol's own options
/// are added first and the shared ones after them, the order the help's sections and the
/// completion scripts follow; only the options hidden last are moved (to the end, as before).
fn protocol_command(p: &'static Protocol) -> clap::Command {
    // The protocol's own options: the first words of their help in `-h`.
    let cmd = (p.front.args)(clap::Command::new(p.command).next_help_heading("Protocol options"));
    let own: Vec<clap::Id> = cmd.get_arguments().map(|a| a.get_id().clone()).collect();
    let cmd = CaptureArgs::augment_args(cmd.next_help_heading(None::<&str>));
    // clap numbered the options as they came (the display order, which sorts the help's
    // sections): the shared ones first, as a subcommand built the other way round has them.
    let named = |c: &clap::Command, own_ones: bool| {
        c.get_arguments()
            .filter(|a| !a.is_positional() && own.contains(a.get_id()) == own_ones)
            .count()
    };
    let (own_named, shared_named) = (named(&cmd, true), named(&cmd, false));
    let edits = SharedEdits::new(p);
    let mut cmd = cmd
        .about(p.summary)
        .long_about(p.about)
        .visible_aliases(p.aliases.iter().copied())
        .mut_args(|a| {
            let order = a.get_display_order();
            match (own.contains(a.get_id()), a.is_positional()) {
                (true, true) => own_help(a),
                (true, false) => own_help(a).display_order(order + shared_named),
                (false, true) => edits.apply(a),
                (false, false) => edits.apply(a).display_order(order - own_named),
            }
        })
        .after_help(format!(
            "{}\nEvery option, the defaults and the filters' values: busnoop {} --help",
            p.examples, p.command
        ))
        .after_long_help(p.examples);
    // Filters that cannot apply to this protocol stay out of its help (and are refused with the
    // reason when given).
    let v = p.vocab;
    if !v.polls {
        cmd = cmd.mut_arg("hide_polls", |a| a.hide(true));
    }
    if !v.keepalives {
        cmd = cmd.mut_arg("hide_null", |a| a.hide(true));
    }
    if v.ids.is_none() {
        for id in ["id", "not_id", "name"] {
            cmd = cmd.mut_arg(id, |a| a.hide(true));
        }
    }
    if p.export.is_none() {
        cmd = cmd.mut_arg("export", |a| a.hide(true));
    }
    if v.ids.is_none() && v.devices.is_none() {
        cmd = cmd.mut_arg("device", |a| a.hide(true));
    }
    cmd
}

/// A protocol's own option: the first words of its help in `-h`, the whole in `--help`.
fn own_help(a: clap::Arg) -> clap::Arg {
    match a.get_long_help().or(a.get_help()).cloned() {
        Some(long) => {
            let text = long.to_string();
            a.help(first_words(&text)).long_help(long)
        }
        None => a,
    }
}

/// The start of a help text, up to its first colon, parenthesis or sentence end (the text of
/// an option in `-h`).
fn first_words(text: &str) -> String {
    let cut = [": ", " (", ". ", "; ", ", e.g."]
        .iter()
        .filter_map(|sep| text.find(sep))
        .filter(|&i| i >= 12)
        .min()
        .unwrap_or(text.len());
    text[..cut].trim_end_matches('.').to_string()
}

/// The shared options `-h` shows (one line each, with this text); `--help` shows every option
/// with its long text. The protocol's own options are in both.
fn short_help(p: &Protocol) -> Vec<(&'static str, String)> {
    let v = p.vocab;
    let mut out = vec![
        (
            "source",
            "A serial device, a capture file, or - (standard input)".to_string(),
        ),
        (
            "format",
            "pretty, tsv, csv or jsonl [default: pretty on a terminal]".into(),
        ),
        (
            "output",
            "Write the table to FILE (.csv, .tsv, .jsonl pick the format)".into(),
        ),
        ("stats", "A summary per device on stderr at the end".into()),
        (
            "wide",
            "One line per cycle, one column per number (CSV or TSV)".into(),
        ),
        (
            "top",
            "Full-screen live view: one line per device and sensor".into(),
        ),
        (
            "baud",
            format!("Line speed of a device [default: {}]", p.line.baud),
        ),
        (
            "record",
            "Keep the bytes from the wire: FILE.pcap, FILE.pcapng, FILE.bin".into(),
        ),
        ("types", "Only rows of these types (Data,BadCRC)".into()),
        ("count", "Stop after N rows".into()),
    ];
    if v.ids.is_some() {
        out.push((
            "id",
            format!("Only rows of these IDs ({}): 2,8 or 0-9", v.id_name),
        ));
        out.push((
            "name",
            format!(
                "Name an ID ({}) in the Device column: --name Pack=1",
                v.id_name
            ),
        ));
    }
    out.push((
        "sensor",
        "Only rows of these sensors, by name or number".into(),
    ));
    out
}

/// The protocol's own words in the shared options' help (its defaults, its ID, its types and
/// sensors, its export), and the split between `-h` (a summary) and `--help` (everything).
struct SharedEdits {
    p: &'static Protocol,
    /// `-h`'s text of the shared options it shows; the others only in `--help`.
    short: Vec<(&'static str, String)>,
}

impl SharedEdits {
    fn new(p: &'static Protocol) -> Self {
        SharedEdits {
            p,
            short: short_help(p),
        }
    }

    /// One shared option, edited in place: first the protocol's words, then the `-h` split.
    fn apply(&self, a: clap::Arg) -> clap::Arg {
        let a = self.protocol_words(a);
        match self.short.iter().find(|(s, _)| a.get_id() == *s) {
            Some((_, text)) => {
                let long = a
                    .get_long_help()
                    .or(a.get_help())
                    .cloned()
                    .unwrap_or_default();
                a.help(text.clone()).long_help(long)
            }
            None => a.hide_short_help(true),
        }
    }

    /// The shared option's help in the protocol's words (its defaults, its ID, its types …).
    fn protocol_words(&self, a: clap::Arg) -> clap::Arg {
        let p = self.p;
        let v = p.vocab;
        let line = p.line;
        match a.get_id().as_str() {
            "source" => a.help(p.source_help),
            "record" => a.help(record_help(p)),
            "baud" => a.help(format!(
                "Serial line speed when SOURCE is a device; also sets the byte times of raw \
                 files [default: {}]",
                line.baud
            )),
            "line" => a.help(format!(
                "Character format of a serial device: 8N1, 8E1, 8N2 …, optionally after the \
                 speed (9600-8E1) [default: {}]",
                line.format()
            )),
            "wide" => {
                let cycle = match (&v.ids, v.polls) {
                    (_, true) => {
                        format!("one line per poll cycle (each {}'s next poll)", v.id_name)
                    }
                    (Some(_), false) => {
                        format!("one line per cycle (each {}'s next frame)", v.id_name)
                    }
                    (None, false) => "one line per frame".to_string(),
                };
                a.long_help(format!(
                    "Wide table (CSV or TSV): {cycle}, one column per number seen, named \
                     `Name(unit)`, the last value held; Date and Time when the source has \
                     wall-clock time, else Millis. See docs/wide.md"
                ))
            }
            "types" => {
                let types: Vec<&str> = v.types.iter().copied().take(6).collect();
                a.long_help(format!(
                    "Show only rows of these types, comma-separated and case-insensitive: {}{}",
                    types.join(", "),
                    if v.types.len() > types.len() {
                        " …"
                    } else {
                        ""
                    }
                ))
            }
            "id" => match &v.ids {
                Some(ids) => a.long_help(format!(
                    "Show only rows of these IDs ({}, {} to {}): `2,8`, `0x1B`, ranges `0-9` \
                     (repeatable)",
                    v.id_name,
                    ids.start(),
                    ids.end()
                )),
                None => a,
            },
            "name" => match &v.ids {
                Some(_) => a.long_help(format!(
                    "Name an ID ({}) in the Device column (repeatable): `--name Pack=1`, \
                     `--name Boiler=0x0A`; the name first, then the ID",
                    v.id_name
                )),
                None => a,
            },
            // (Not from `vocab.sensors`, which S.Port builds from every app ID: too slow for a
            // help text built at every start.)
            "sensor" => a.long_help(format!(
                "Show only rows whose Sensor or Sensor # column is one of these, or that carry \
                 a number of that name, comma-separated and case-insensitive; Sensor # {}",
                v.sensor_no_text
            )),
            "export" => match &p.export {
                Some(e) => a.long_help(format!(
                    "Write every reassembled frame (valid or not) as one packet of \
                     FILE.pcapng, with its capture time, for Wireshark: link type {} ({}), \
                     decoded by {} (docs/wireshark.md). Filters apply, as to the table",
                    e.linktype, e.linktype_name, e.dissector
                )),
                None => a,
            },
            _ => a,
        }
    }
}

/// A parsed command line.
pub enum Parsed {
    /// A protocol's subcommand.
    Protocol(Box<Run>),
    /// Any other.
    Other(Command),
}

/// A protocol's subcommand, parsed: the shared options and the protocol's own.
pub struct Run {
    pub protocol: &'static Protocol,
    pub capture: CaptureArgs,
    pub options: Box<dyn Options>,
}

impl Parsed {
    /// Parses `argv` (the program name first) and the `-v` count.
    pub fn from(
        argv: impl IntoIterator<Item = impl Into<std::ffi::OsString> + Clone>,
    ) -> Result<(Parsed, u8), clap::Error> {
        let mut cmd = command();
        let matches = cmd.try_get_matches_from_mut(argv)?;
        let verbose = matches.get_count("verbose");
        let run = matches.subcommand().and_then(|(name, sub)| {
            PROTOCOLS
                .iter()
                .find(|p| p.answers_to(name))
                .map(|&p| (p, sub))
        });
        let parsed = match run {
            Some((protocol, sub)) => {
                let sub_cmd = cmd
                    .find_subcommand_mut(protocol.command)
                    .expect("every protocol has its subcommand");
                let capture = CaptureArgs::from_arg_matches(sub).map_err(|e| e.format(sub_cmd))?;
                let options = (protocol.front.parse)(sub).map_err(|e| e.format(sub_cmd))?;
                Parsed::Protocol(Box::new(Run {
                    protocol,
                    capture,
                    options,
                }))
            }
            None => Parsed::Other(Cli::from_arg_matches(&matches)?.command),
        };
        Ok((parsed, verbose))
    }
}

/// SOURCE and the options every protocol shares.
#[derive(Args, Debug, Clone)]
pub struct CaptureArgs {
    /// What to read (each subcommand names the sources it accepts).
    #[arg(index = 1)]
    pub source: PathBuf,

    /// More sources, decoded at once (each with its own decoder) and merged by time into one
    /// table with a Port column: two adapters on the two wires of a full-duplex link, or two
    /// buses (docs/live.md, "Two wires, two adapters").
    #[arg(index = 2, value_name = "SOURCE")]
    pub more: Vec<PathBuf>,

    #[command(flatten)]
    pub output: OutputArgs,

    #[command(flatten)]
    pub live: LiveArgs,

    #[command(flatten)]
    pub select: project::SelectArgs,

    #[command(flatten)]
    pub run: RunArgs,
}

/// When to stop, and what a script is told.
#[derive(Args, Debug, Clone, Default)]
#[command(next_help_heading = "Stopping and scripts")]
pub struct RunArgs {
    /// Stop after N rows are written (after the filters; busnoop's own notes not counted),
    /// like candump -n and tshark -c.
    #[arg(short = 'c', long, value_name = "N",
          value_parser = |s: &str| crate::protocol::front::whole_in(s, 1, u64::MAX))]
    pub count: Option<u64>,

    /// Stop after this much capture time: on a serial port, seconds since the start; for a
    /// file, its own time (Millis) [units: 1.5, 90, 500ms, 2m, 1h].
    #[arg(long, value_name = "TIME", value_parser = parse_seconds)]
    pub duration: Option<std::time::Duration>,

    /// Stop when no row came for this long (a serial port: the bus went quiet; a file: a gap
    /// in its times) [units as for --duration].
    #[arg(long, value_name = "TIME", value_parser = parse_seconds)]
    pub until_idle: Option<std::time::Duration>,

    /// No table on standard output (it still goes to -o FILE); for --record, --export and
    /// --stats runs, and for the exit code alone.
    #[arg(short, long)]
    pub quiet: bool,

    /// Exit 0 even when most of a file's bytes are not valid frames of the protocol (exit code
    /// 13 otherwise: the wrong protocol, or noise; the rows are written either way).
    #[arg(long)]
    pub lenient: bool,
}

/// A time as people write it: seconds (`1.5`, `90`), or with a unit: `500ms`, `30s`, `2m`,
/// `1h`; more than 0, at most a week.
pub fn parse_seconds(s: &str) -> Result<std::time::Duration, String> {
    let t = s.trim();
    let bad =
        || "expected a time: seconds (1.5, 90) or with a unit (500ms, 30s, 2m, 1h)".to_string();
    let (number, unit) = match t.find(|c: char| c.is_ascii_alphabetic()) {
        Some(i) => (&t[..i], &t[i..]),
        None => (t, "s"),
    };
    let factor = match unit {
        "ms" => 0.001,
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => return Err(bad()),
    };
    if number.is_empty() || !number.bytes().all(|b| b.is_ascii_digit() || b == b'.') {
        return Err(bad());
    }
    let v: f64 = number.parse().map_err(|_| bad())?;
    let secs = v * factor;
    if !(secs > 0.0 && secs <= 7.0 * 86_400.0) {
        return Err(format!(
            "{t} is out of range: more than 0, at most a week (168h)"
        ));
    }
    Ok(std::time::Duration::from_secs_f64(secs))
}

impl CaptureArgs {
    /// SOURCE and the more sources after it, as given.
    pub fn sources(&self) -> impl Iterator<Item = &PathBuf> {
        std::iter::once(&self.source).chain(&self.more)
    }
}

/// Options for live capture.
#[derive(Args, Debug, Clone, Default)]
pub struct LiveArgs {
    // The help names the protocol's default (see `protocol_command`).
    #[arg(long, value_name = "BAUD", value_parser = parse_baud)]
    pub baud: Option<u32>,

    // The help names the protocol's default (see `protocol_command`).
    #[arg(long, value_name = "FORMAT")]
    pub line: Option<String>,

    /// A logic-analyzer trace (sigrok .sr, VCD, Saleae CSV export): the channel to read, by
    /// name or number (default: the only channel, or the only one that changes level; see
    /// docs/logic.md). Several (`--channel RX,TX` or repeated): each channel is a port of its
    /// own, merged by time with a Port column.
    #[arg(long, value_name = "NAME|N", value_delimiter = ',')]
    pub channel: Vec<String>,

    /// Wait for the adapter: when it is not plugged in yet, until it appears; when it is
    /// unplugged, until it is back (by its /dev/serial/by-id name or USB serial number), and
    /// mark the gap with rows.
    #[arg(long)]
    pub reconnect: bool,

    // The help is `record_help`'s.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,

    /// Write every reassembled frame (valid or not) as one packet of FILE.pcapng, with its
    /// capture time, for Wireshark (sport: link type USER0, sab2: USER1, dissectors in
    /// contrib/wireshark/; serial sbus: each telegram as an Ether-S-Bus datagram for
    /// Wireshark's own sbus dissector, station N = 10.0.0.N; see docs/wireshark.md). Filters
    /// apply, as to the table.
    #[arg(long, value_name = "FILE.pcapng")]
    pub export: Option<PathBuf>,

    /// The device's DTR and RTS outputs: low drops them right after opening (an RS-485 adapter
    /// whose driver follows RTS stays off the bus); keep leaves them as the driver sets them
    /// (raised on open), for adapters powered or enabled by them.
    #[arg(long, value_enum, value_name = "MODE", default_value_t)]
    pub dtr_rts: serial::ModemLines,
}

/// When to colour pretty output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColorChoice {
    /// Colour when writing to a terminal and NO_COLOR is not set.
    Auto,
    Always,
    Never,
}

/// `--stats-format`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StatsFormat {
    /// The table for people.
    Text,
    /// One JSON object (see docs/config.md, "Statistics as JSON").
    Json,
}

/// How times are shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TimeMode {
    /// Millis since the capture started only.
    Rel,
    /// Also a `Time` column with the wall-clock time (RFC 3339, milliseconds).
    Abs,
}

/// Options shared by every protocol.
#[derive(Args, Debug, Clone)]
pub struct OutputArgs {
    /// Output format: pretty, tsv, csv or jsonl [default: pretty on a terminal, tsv otherwise,
    /// or from the -o extension].
    #[arg(short, long, value_enum, hide_possible_values = true)]
    pub format: Option<Format>,

    /// Write the table to FILE instead of standard output (.csv, .tsv, .jsonl, .txt pick
    /// the format unless --format is given); `-` is standard output.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,

    /// Colour pretty output.
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto)]
    pub color: ColorChoice,

    /// Add a `Raw` column with each row's bytes as they were on the wire.
    #[arg(long)]
    pub raw: bool,

    /// Pretty table on a terminal: full lines, however wide. By default its rows are fitted
    /// to the terminal's width (Data and Note wrapped within their columns, names cut with
    /// `…`, never a number); a file or a pipe always gets full lines.
    #[arg(long)]
    pub no_fit: bool,

    /// Print a per-device summary on stderr at the end (and on Ctrl-C).
    #[arg(long)]
    pub stats: bool,

    /// Form of the --stats summary: `text`, or `json` (one JSON object, the last line on
    /// stderr, also when the run fails; implies --stats; schema docs/stats.v1.schema.json).
    #[arg(long, value_enum, value_name = "FORM")]
    pub stats_format: Option<StatsFormat>,

    /// Write the statistics as one JSON object into FILE at the end of the run, also when it
    /// fails (schema docs/stats.v1.schema.json); stderr keeps its usual messages.
    #[arg(long, value_name = "FILE")]
    pub stats_json: Option<PathBuf>,

    /// `abs` adds a `Time` column with wall-clock times when the source has them.
    #[arg(long, value_enum, default_value_t = TimeMode::Rel)]
    pub time: TimeMode,

    /// With --time abs: print UTC instead of local time.
    #[arg(long)]
    pub utc: bool,

    /// Full-screen live view instead of the scrolling table: one line per device and sensor
    /// with value, rate, age, min/max and errors (keys: q quit, p pause, s sort, f filter,
    /// space mark). The table can still go to -o FILE.
    #[arg(long)]
    pub top: bool,

    /// Replay speed of captures with times: 1 = real time, 2 = twice as fast, 0 = as fast as
    /// possible [default: 1 with --top, 0 otherwise]. No effect on a live port.
    #[arg(long, value_name = "N", value_parser = parse_speed)]
    pub speed: Option<f64>,

    /// Wide table (CSV or TSV) as a radio's SD-card log: one line per poll cycle, one column per
    /// sensor number seen (`Cell1(V)`, `RxBt(V)`, `R100`), the last value held; Date and Time
    /// when the source has wall-clock time, else Millis. See docs/wide.md.
    #[arg(long)]
    pub wide: bool,

    /// With --wide: one line per MS milliseconds of capture time instead of per poll cycle.
    #[arg(long, value_name = "MS", requires = "wide",
          value_parser = |s: &str| crate::protocol::front::whole_in(s, 1, 3_600_000))]
    pub every: Option<u64>,

    /// With --wide: at most N columns, the first N numbers to appear; the numbers of later
    /// columns are left out, counted in a note [default: 2000].
    #[arg(long, value_name = "N", requires = "wide",
          value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub max_columns: Option<u32>,

    /// `busnoop plot`: rows go to a plot instead.
    #[arg(skip)]
    pub plot: Option<crate::plot::PlotSpec>,

    /// Pretty output: the line above the column names (what the project file sets).
    #[arg(skip)]
    pub preface: Option<String>,
}

/// `--speed`: 0, or a number from 0.001 to 1000. Below a thousandth of real time the pacer's
/// delays grow past what a `Duration` holds (`--speed 1e-300` panicked) or past any replay
/// (`1e-10`: three centuries per second of capture).
fn parse_speed(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v == 0.0 || (0.001..=1000.0).contains(&v) => Ok(v),
        _ => Err(
            "expected 0 (as fast as possible) or a number from 0.001 to 1000 (1 = real time)"
                .into(),
        ),
    }
}

impl OutputArgs {
    /// The `-o` file; `None` for standard output (no `-o`, or `-o -`).
    pub fn output_file(&self) -> Option<&Path> {
        self.output.as_deref().filter(|p| !is_dash(p))
    }

    /// The table's format: `--format`, else `-o`'s extension, else pretty on a terminal and
    /// TSV elsewhere.
    pub(super) fn table_format(&self, to_terminal: bool) -> Format {
        self.format.unwrap_or_else(|| match self.output_file() {
            Some(p) => Format::from_path(p).unwrap_or(Format::Tsv),
            None if to_terminal => Format::Pretty,
            None => Format::Tsv,
        })
    }

    /// The table options for an output that is (or is not) a terminal, given whether the
    /// `NO_COLOR` environment variable is set to a non-empty value.
    pub(super) fn table_options(&self, to_terminal: bool, no_color_env: bool) -> TableOptions {
        let format = self.table_format(to_terminal);
        let color = format == Format::Pretty
            && match self.color {
                ColorChoice::Always => true,
                ColorChoice::Never => false,
                ColorChoice::Auto => to_terminal && !no_color_env,
            };
        TableOptions {
            format,
            color,
            raw: self.raw,
            time_abs: self.time == TimeMode::Abs,
            utc: self.utc,
        }
    }
}

/// Valid line speeds for `--baud`: 0 would mean "hang up" on a real UART, and nothing on a
/// bus busnoop reads runs above 12 Mbaud (the fastest USB adapters, FT232H).
pub const BAUD_RANGE: std::ops::RangeInclusive<i64> = 50..=12_000_000;

/// A line speed as people write it: `57600`, `57.6k`, `420k`, `1M`, `1.5M`; from 50 to
/// 12000000 baud ([`BAUD_RANGE`]).
pub fn parse_baud(s: &str) -> Result<u32, String> {
    let t = s.trim();
    let bad = || "expected a speed in baud: 57600, 57.6k or 1M".to_string();
    let (number, scale) = match t.as_bytes().last() {
        Some(b'k' | b'K') => (&t[..t.len() - 1], 1_000u64),
        Some(b'M') => (&t[..t.len() - 1], 1_000_000),
        _ => (t, 1),
    };
    let (whole, frac) = number.split_once('.').unwrap_or((number, ""));
    let digits = |d: &str| d.bytes().all(|b| b.is_ascii_digit());
    if whole.is_empty() || !digits(whole) || !digits(frac) || frac.len() > 6 {
        return Err(bad());
    }
    let whole: u64 = whole.parse().map_err(|_| bad())?;
    let frac_value: u64 = if frac.is_empty() {
        0
    } else {
        frac.parse().map_err(|_| bad())?
    };
    let denom = 10u64.pow(frac.len() as u32);
    let scaled = frac_value * scale;
    if !scaled.is_multiple_of(denom) {
        return Err(format!("{t} is not a whole number of baud"));
    }
    let baud = whole.saturating_mul(scale).saturating_add(scaled / denom);
    if !BAUD_RANGE.contains(&(baud.min(i64::MAX as u64) as i64)) {
        return Err(format!(
            "{t} is out of range: from {} to {} baud",
            BAUD_RANGE.start(),
            BAUD_RANGE.end()
        ));
    }
    Ok(baud as u32)
}

/// `busnoop detect`.
#[derive(Args, Debug)]
pub struct DetectArgs {
    /// What to examine: a capture file (raw wire bytes, an EdgeTX S.Port log, a busnoop .pcap
    /// recording, a pcap/pcapng capture, a logic-analyzer trace), `-` for standard input, or a
    /// serial device, which is listened to (passively, read-only) at each baud rate in turn.
    pub source: PathBuf,

    /// Serial devices: how long to listen at each baud rate.
    #[arg(long, value_name = "MS", default_value_t = 1500,
          value_parser = |s: &str| crate::protocol::front::whole_in(s, 10, 60_000))]
    pub listen_ms: u64,

    /// Serial devices: the baud rates to try, comma-separated [default: 9600, 19200, 38400,
    /// 57600, 100000, 115200, 230400, 400000, 420000].
    #[arg(long = "baud", value_name = "BAUD", value_delimiter = ',',
          value_parser = parse_baud)]
    pub bauds: Vec<u32>,

    /// Serial devices: DTR and RTS, as for the protocol commands.
    #[arg(long, value_enum, value_name = "MODE", default_value_t)]
    pub dtr_rts: crate::source::serial::ModemLines,

    /// A logic-analyzer trace (sigrok .sr, VCD, Saleae CSV export): the channel to read, by
    /// name or number (default: the only channel, or the only one that changes level).
    #[arg(long, value_name = "NAME|N")]
    pub channel: Option<String>,
}

impl DetectArgs {
    pub fn options(&self) -> crate::detect::Options {
        crate::detect::Options {
            source: self.source.clone(),
            listen_ms: self.listen_ms,
            bauds: self.bauds.clone(),
            dtr_rts: self.dtr_rts,
            channel: self.channel.clone(),
        }
    }
}
