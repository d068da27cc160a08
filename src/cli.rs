//! Command line: argument parsing, wiring source → decoder → sink, messages and exit codes.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::exit::{Failure, code};
use crate::filter::Selection;
use crate::pace::{Paced, Pacer};
use crate::protocol::{Decoder, Kind, Line, Protocol};
use crate::record::Recorder;
use crate::run::{Context, drive};
use crate::signal::Stop;
use crate::sink::{Format, Output, Table, TableOptions};
use crate::source::serial::{self, SerialReader};
use crate::source::{self, ChunkReader, Input};
use crate::top::Top;
use crate::top::view::Info;

#[derive(Parser, Debug)]
#[command(
    name = "busnoop",
    version,
    about = "Passive bus sniffer: listens to a serial bus (or replays a capture), reassembles \
             every frame and prints the S-Port_Snoop log table as coloured text, TSV, CSV or \
             JSON Lines.",
    after_help = "Exit codes: 0 ok, 2 usage, 3 not found, 4 permission denied, 5 port busy, \
                  6 device error, 7 adapter disconnected, 8 output error, 9 input error, \
                  10 nothing decoded (empty input, or no frame of the protocol), \
                  11 detect: no known protocol, 12 bad project file, 130 Ctrl-C, 141 output closed, 143 SIGTERM."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,

    /// More diagnostics on stderr (-v, -vv); RUST_LOG works too.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// FrSky S.Port: polls `7E id`, 8-byte responses, byte stuffing, sum CRC (57600 baud).
    #[command(mut_arg("source", |a| a.help(SPORT_SOURCE)))]
    Sport(SportArgs),
    /// Saia S-Bus (PCD controllers): serial data/secure/break/parity modes (9600 baud), and
    /// Ether-S-Bus (UDP 5050) from pcap/pcapng files or a `tcpdump -U -w -` pipe.
    #[command(mut_arg("source", |a| a.help(SBUS_SOURCE)))]
    Sbus(SbusArgs),
    /// modm SAB / SAB2: both framings (0x54 + CRC-8, 0x7E + CRC-16) auto-detected,
    /// requests paired with responses.
    #[command(visible_alias = "sab", mut_arg("source", |a| a.help(SAB_SOURCE)))]
    Sab2(SabArgs),
    /// Which protocol is on this wire? Tries every protocol (S-Bus modes, SAB framings) on a
    /// file's first megabytes, or on a serial port at the usual baud rates, and prints the
    /// verdict, the evidence and the command to run.
    Detect(crate::detect::DetectArgs),
    /// Plot a capture's numbers as time series: one panel per unit, broken frames marked, as
    /// SVG or PNG (`busnoop plot flight.log --sensor Alt,VFAS -o flight.svg`).
    Plot(crate::cli::PlotArgs),
    /// List the serial ports of this machine (type, USB VID:PID, serial number, names).
    Ports,
    /// Print the shell completion script for SHELL on standard output (see README, "Install").
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

/// The subcommands that are not a protocol.
pub const OTHER_COMMANDS: &[&str] = &["detect", "plot", "ports", "completions", "man"];

/// `busnoop plot`.
#[derive(Args, Debug, Clone)]
pub struct PlotArgs {
    /// The capture to plot: a file (raw wire bytes, an EdgeTX/OpenTX log, a pcap) or `-`.
    pub source: PathBuf,
    /// The numbers to plot, by their names in the wide table without unit (`Alt`, `VFAS`,
    /// `Cell1`, `Cell1@8`), comma-separated [default: every number].
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub sensor: Vec<String>,
    /// The image to write: FILE.svg or FILE.png.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// The protocol [default: detected as by `busnoop detect`].
    #[arg(long, value_name = "NAME", value_parser = ["sport", "sbus", "sab2"])]
    pub protocol: Option<String>,
}

/// `SOURCE` in `busnoop sport --help`: only what S.Port reads.
const SPORT_SOURCE: &str = "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), \
     a capture file (raw wire bytes, an EdgeTX/OpenTX S.Port debug log, a busnoop .pcap \
     recording) or `-` for standard input. File kinds are recognised by content.";
/// `SOURCE` in `busnoop sbus --help`.
const SBUS_SOURCE: &str = "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), \
     a capture file (raw wire bytes, a busnoop .pcap recording, a pcap/pcapng capture of \
     Ether-S-Bus traffic) or `-` for standard input (also a `tcpdump -U -w -` pipe). File kinds \
     are recognised by content; `--baud` also sets the byte times of raw files.";
/// `SOURCE` in `busnoop sab2 --help`.
const SAB_SOURCE: &str = "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), \
     a capture file (raw wire bytes, a busnoop .pcap recording) or `-` for standard input. File \
     kinds are recognised by content; `--baud` also sets the byte times of raw files.";

#[derive(Args, Debug)]
pub struct SbusArgs {
    #[command(flatten)]
    pub capture: CaptureArgs,

    /// Serial mode; auto picks data/secure mode when the stream uses 0xB5 framing, break mode
    /// otherwise.
    #[arg(long, value_enum, default_value_t = SbusMode::Auto)]
    pub mode: SbusMode,

    /// Master timeout in ms for Timeout rows and late answers [default: by mode and baud rate
    /// (375 ms data mode, 250 ms break/parity mode at 9600), 1000 ms for Ether-S-Bus].
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(MS_RANGE))]
    pub timeout_ms: Option<u64>,

    /// Serial sources with time: a silence longer than this ends a telegram [default: 20
    /// character times, at least 20 ms].
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(MS_RANGE))]
    pub gap_ms: Option<u64>,

    /// Name a station in the Device column (repeatable), e.g. `--station Boiler=10`; the same
    /// as --name.
    #[arg(long = "station", value_name = "NAME=ADDR", value_parser = crate::sbus::parse_station)]
    pub stations: Vec<(String, u8)>,

    /// Ether-S-Bus UDP port (datagrams to or from it are decoded).
    // `--port` was its name first; kept as a hidden alias.
    #[arg(long = "udp-port", alias = "port", value_name = "PORT",
          default_value_t = crate::sbus::DEFAULT_PORT,
          value_parser = clap::value_parser!(u16).range(1..=65_535))]
    pub port: u16,
}

/// `sbus --mode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SbusMode {
    /// Data/secure mode when the stream uses 0xB5 framing, break mode otherwise.
    Auto,
    /// SM2 data mode (0xB5 framing, DLE escaping); secure telegrams are read too.
    Data,
    /// SM2 secure data mode (`B5 10|11 LEN SEQ` + telegram); standard telegrams are read too.
    Secure,
    /// SM0 break mode: a break (read as 0x00) before each request.
    Break,
    /// SM1 parity mode: the 9th bit marks the address (lost by most UARTs).
    Parity,
}

impl SbusArgs {
    /// The decoder settings for a line at `baud` (`--baud` or the protocol's default).
    fn options(&self, baud: u32) -> crate::sbus::Options {
        use crate::sbus::Mode;
        crate::sbus::Options {
            mode: match self.mode {
                SbusMode::Auto => Mode::Auto,
                SbusMode::Data => Mode::Data,
                SbusMode::Secure => Mode::Secure,
                SbusMode::Break => Mode::Break,
                SbusMode::Parity => Mode::Parity,
            },
            baud,
            timeout_ms: self.timeout_ms,
            gap_ms: self.gap_ms,
            stations: self.stations.clone(),
            port: self.port,
        }
    }
}

#[derive(Args, Debug)]
pub struct SabArgs {
    #[command(flatten)]
    pub capture: CaptureArgs,

    /// Framing on the wire: `sync` = SAB v1 (`54 LEN HDR CMD DATA CRC8`, what modm's
    /// documentation describes), `hdlc` = SAB2 (`7E HDR CMD DATA CRC16 7E`, what modm's SAB2 code
    /// sends), `auto` = detect it and say which one was chosen.
    #[arg(long, value_enum, default_value_t = SabFraming::Auto)]
    pub framing: SabFraming,

    /// Name a command in the Sensor column (repeatable): `--command speed=0x34`,
    /// `--command reset=7`.
    #[arg(long, value_name = "NAME=CODE", value_parser = crate::sab::parse_command)]
    pub command: Vec<(String, u8)>,

    /// Master timeout: a request without a response within this time gets a `Timeout` row
    /// [default: 10].
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(MS_RANGE))]
    pub timeout_ms: Option<u64>,

    /// SAB2 payload limit (modm's template parameter `N` of `sab2::Interface`): longer frames
    /// are flagged as overlong.
    #[arg(long, value_name = "BYTES", default_value_t = crate::sab::hdlc::DEFAULT_MAX_PAYLOAD as u16,
          value_parser = clap::value_parser!(u16).range(1..=255))]
    pub max_payload: u16,
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

impl SabArgs {
    /// The decoder settings for a line at `baud` (`--baud` or the protocol's default): raw
    /// captures carry no time, busnoop reconstructs it from the byte position, 10 bits per byte
    /// at this rate.
    fn options(&self, baud: u32) -> crate::sab::Options {
        use crate::sab::FramingChoice;
        crate::sab::Options {
            framing: match self.framing {
                SabFraming::Auto => FramingChoice::Auto,
                SabFraming::Sync => FramingChoice::Sync,
                SabFraming::Hdlc => FramingChoice::Hdlc,
            },
            baud,
            timeout_micros: self.timeout_ms.unwrap_or(crate::sab::DEFAULT_TIMEOUT_MS) * 1000,
            max_payload: self.max_payload as usize,
            devices: Vec::new(),
            commands: self.command.clone(),
        }
    }
}

#[derive(Args, Debug)]
pub struct SportArgs {
    #[command(flatten)]
    pub capture: CaptureArgs,
}

/// SOURCE and the options every protocol shares.
#[derive(Args, Debug, Clone)]
pub struct CaptureArgs {
    /// What to read (each subcommand names the sources it accepts).
    pub source: PathBuf,

    #[command(flatten)]
    pub output: OutputArgs,

    #[command(flatten)]
    pub live: LiveArgs,

    #[command(flatten)]
    pub select: crate::project::SelectArgs,
}

/// Options for live capture.
#[derive(Args, Debug, Clone, Default)]
pub struct LiveArgs {
    /// Serial line speed when SOURCE is a device [default: the protocol's: sport 57600, sbus
    /// 9600, sab2 115200]
    #[arg(long, value_name = "BAUD", value_parser = clap::value_parser!(u32).range(BAUD_RANGE))]
    pub baud: Option<u32>,

    /// When the adapter is unplugged, wait for it (by its /dev/serial/by-id name or USB serial
    /// number), go on, and mark the gap with a row.
    #[arg(long)]
    pub reconnect: bool,

    /// Keep what came off the wire while decoding: FILE.pcap with arrival times (busnoop replays
    /// it with the original Millis; Wireshark opens it), any other name: the raw bytes; `-`: the
    /// raw bytes on standard output (with -o FILE only).
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,

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
    /// Output format [default: pretty on a terminal, tsv otherwise, or from the -o extension].
    #[arg(short, long, value_enum)]
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

    /// Print a per-device summary on stderr at the end (and on Ctrl-C).
    #[arg(long)]
    pub stats: bool,

    /// Form of the --stats summary: `text`, or `json` (one JSON object, the last line on
    /// stderr; implies --stats).
    #[arg(long, value_enum, value_name = "FORM")]
    pub stats_format: Option<StatsFormat>,

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
    /// `busnoop plot`: rows go to a plot instead.
    #[arg(skip)]
    pub plot: Option<crate::plot::PlotSpec>,

    #[arg(long, value_name = "MS", requires = "wide",
          value_parser = clap::value_parser!(u64).range(1..=3_600_000))]
    pub every: Option<u64>,
}

/// `--speed`: a number from 0 to 1000.
fn parse_speed(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.0..=1000.0).contains(&v) => Ok(v),
        _ => Err("expected a number from 0 (as fast as possible) to 1000 (1 = real time)".into()),
    }
}

impl OutputArgs {
    /// The `-o` file; `None` for standard output (no `-o`, or `-o -`).
    pub fn output_file(&self) -> Option<&Path> {
        self.output.as_deref().filter(|p| !is_dash(p))
    }

    /// The table options for an output that is (or is not) a terminal, given whether the
    /// `NO_COLOR` environment variable is set to a non-empty value.
    fn table_options(&self, to_terminal: bool, no_color_env: bool) -> TableOptions {
        let format = self.format.unwrap_or_else(|| match self.output_file() {
            Some(p) => Format::from_path(p).unwrap_or(Format::Tsv),
            None if to_terminal => Format::Pretty,
            None => Format::Tsv,
        });
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

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() {
                code::USAGE
            } else {
                code::OK
            });
        }
    };
    init_tracing(cli.verbose);
    match run(cli) {
        Ok(()) => ExitCode::from(code::OK),
        Err(f) => {
            if !f.is_quiet() {
                eprintln!("busnoop: {f}");
            }
            ExitCode::from(f.exit_code())
        }
    }
}

fn init_tracing(verbose: u8) {
    use tracing_subscriber::EnvFilter;
    let default = match verbose {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    // Colour codes only on a terminal (and not with NO_COLOR): `-v 2>log` stays plain text.
    let ansi = std::io::stderr().is_terminal()
        && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty());
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(ansi)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}

/// `busnoop plot`: the protocol's command with its rows going to a plot.
fn plot(a: &PlotArgs) -> Result<(), Failure> {
    let (command, extra): (&str, &[&str]) = match &a.protocol {
        Some(p) => (p.as_str(), &[]),
        None => {
            let (p, args) = crate::detect::protocol_of(&a.source)?;
            (p.command, args)
        }
    };
    let mut argv: Vec<std::ffi::OsString> = vec!["busnoop".into(), command.into()];
    argv.extend(extra.iter().map(Into::into));
    argv.push(a.source.clone().into());
    let mut cli = Cli::try_parse_from(argv).map_err(|e| Failure::Usage(e.to_string()))?;
    let capture = match &mut cli.command {
        Command::Sport(x) => &mut x.capture,
        Command::Sbus(x) => &mut x.capture,
        Command::Sab2(x) => &mut x.capture,
        _ => return Err(Failure::Internal("plot: not a protocol command".into())),
    };
    capture.output.plot = Some(crate::plot::PlotSpec {
        sensors: a.sensor.clone(),
        path: a.output.clone(),
        title: format!(
            "{} ({command})",
            a.source.file_name().map_or_else(
                || a.source.display().to_string(),
                |n| n.to_string_lossy().into_owned()
            )
        ),
    });
    run(cli)
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<(), Failure> {
    use crate::project::{self, File};
    let (protocol, capture) = match &cli.command {
        Command::Sport(a) => (&crate::sport::PROTOCOL, &a.capture),
        Command::Sbus(a) => (&crate::sbus::PROTOCOL, &a.capture),
        Command::Sab2(a) => (&crate::sab::PROTOCOL, &a.capture),
        Command::Ports => return list_ports(),
        Command::Detect(a) => return crate::detect::run(a),
        Command::Plot(a) => return plot(a),
        Command::Completions { shell } => return crate::manual::completions(*shell),
        Command::Man { dir } => return crate::manual::man(dir.as_deref()),
    };
    let file = File::load(&capture.select)?;
    let section = file
        .as_ref()
        .map(|(f, p)| (f.section(protocol.command), p.as_path()));
    let named = |pairs: &[(String, u8)]| -> Vec<String> {
        pairs.iter().map(|(n, a)| format!("{n}={a}")).collect()
    };
    match cli.command {
        Command::Sport(mut args) => {
            let sel = project::selection(&args.capture.select, protocol, section, &[], &[])?;
            prepare(&mut args.capture, section);
            run_capture(&args.capture, protocol, &sel, |_, _| {
                crate::sport::decoder()
            })
        }
        Command::Sbus(mut args) => {
            let sel = project::selection(
                &args.capture.select,
                protocol,
                section,
                &named(&args.stations),
                &[],
            )?;
            prepare(&mut args.capture, section);
            if args.timeout_ms.is_none() {
                args.timeout_ms = section.and_then(|s| s.0.timeout_ms);
            }
            args.stations = names_u8(&sel.names);
            run_capture(&args.capture, protocol, &sel, |kind, line| {
                crate::sbus::decoder(args.options(line.baud), kind)
            })
        }
        Command::Sab2(mut args) => {
            let mut commands = Vec::new();
            if let Some((s, path)) = section {
                for c in project::file_commands(s) {
                    commands.push(crate::sab::parse_command(&c).map_err(|e| {
                        Failure::Config(format!("{}: [sab2.commands] {e}", path.display()))
                    })?);
                }
            }
            commands.append(&mut args.command);
            args.command = commands;
            let sensors: Vec<String> = args.command.iter().map(|(n, _)| n.clone()).collect();
            let sel = project::selection(&args.capture.select, protocol, section, &[], &sensors)?;
            prepare(&mut args.capture, section);
            if args.timeout_ms.is_none() {
                args.timeout_ms = section.and_then(|s| s.0.timeout_ms);
            }
            let devices = names_u8(&sel.names);
            run_capture(&args.capture, protocol, &sel, |_, line| {
                let mut o = args.options(line.baud);
                o.devices = devices;
                crate::sab::decoder(o)
            })
        }
        Command::Ports
        | Command::Detect(_)
        | Command::Plot(_)
        | Command::Completions { .. }
        | Command::Man { .. } => {
            unreachable!("handled above")
        }
    }
}

/// The project file's defaults under the command line's options; `--stats-format` implies
/// `--stats`.
fn prepare(capture: &mut CaptureArgs, section: Option<(&crate::project::Section, &Path)>) {
    if let Some((s, _)) = section {
        crate::project::apply_defaults(s, &mut capture.output, &mut capture.live.baud);
    }
    if capture.output.stats_format.is_some() {
        capture.output.stats = true;
    }
}

/// Names whose IDs fit a byte (S-Bus stations, SAB addresses), for the decoders' statistics.
fn names_u8(names: &crate::filter::Names) -> Vec<(String, u8)> {
    names
        .pairs()
        .filter_map(|(n, id)| Some((n.to_owned(), u8::try_from(id).ok()?)))
        .collect()
}

/// The failure for an input of a kind `protocol` cannot read.
fn unusable(kind: Kind, protocol: &Protocol) -> Failure {
    let what = match kind {
        Kind::Pcap | Kind::Pcapng => "a pcap of network traffic",
        Kind::EdgeTxLog => "an EdgeTX/OpenTX S.Port log",
        Kind::Recording => "a busnoop recording",
        Kind::Raw | Kind::Serial => "raw serial data",
    };
    Failure::Input(format!(
        "this is {what}; {} captures are {}",
        protocol.name, protocol.accepts_text
    ))
}

/// Valid values of the millisecond options (`--timeout-ms`, `--gap-ms`): 1 ms to one hour.
pub const MS_RANGE: std::ops::RangeInclusive<u64> = 1..=3_600_000;

/// Valid line speeds for `--baud`: 0 would mean "hang up" on a real UART, and nothing on a
/// bus busnoop reads runs above 12 Mbaud (the fastest USB adapters, FT232H).
pub const BAUD_RANGE: std::ops::RangeInclusive<i64> = 50..=12_000_000;

/// `-` as a file name: standard input or output.
fn is_dash(p: &Path) -> bool {
    p.as_os_str() == "-"
}

/// Opens SOURCE (a device, a file or standard input), picks the reader for its kind, asks
/// `decoder_for` for the protocol decoder, decodes everything into the table and prints the
/// summary.
pub fn run_capture(
    args: &CaptureArgs,
    protocol: &Protocol,
    selection: &Selection,
    decoder_for: impl FnOnce(Kind, &Line) -> Box<dyn Decoder>,
) -> Result<(), Failure> {
    let record_to_stdout = args.live.record.as_deref().is_some_and(is_dash);
    if record_to_stdout && args.output.output_file().is_none() {
        return Err(Failure::Usage(
            "--record - needs -o FILE: standard output already carries the table".into(),
        ));
    }
    check_top(args, record_to_stdout)?;
    // The clash with the input first: the capture-name hint below would point at it again.
    let input = Input::parse(&args.source);
    check_distinct(
        &input,
        args.output.output_file(),
        args.live.record.as_deref(),
    )?;
    if let Some(p) = args.output.output_file()
        && p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
            ["pcap", "pcapng", "bin"]
                .iter()
                .any(|c| e.eq_ignore_ascii_case(c))
        })
    {
        return Err(Failure::Usage(format!(
            "-o writes the decoded table (pretty, tsv, csv or jsonl); to keep the bytes from the \
             wire use --record {}",
            p.display()
        )));
    }
    let stop = Stop::install()
        .map_err(|e| Failure::Internal(format!("cannot install signal handlers: {e}")))?;
    let mut line = protocol.line;
    if let Some(b) = args.live.baud {
        line.baud = b;
    }
    let serial = serial::SerialConfig {
        line,
        lines: args.live.dtr_rts,
    };
    // A capture reader hands on its input bytes for --record, and for the wrong-protocol check
    // after the run (which looks at the first megabytes only).
    let keep_input = args.live.record.is_some() || !matches!(input, Input::Device(_));
    let (kind, reader, progress) = open_source(input, &serial, args.live.reconnect, keep_input)?;
    tracing::info!("{}: {:?}", args.source.display(), kind);
    if !protocol.reads(kind) {
        return Err(unusable(kind, protocol));
    }
    for note in option_notes(&args.output, kind) {
        eprintln!("busnoop: note: {note}");
    }
    // Files and streams: keep their start, to tell a wrong protocol afterwards.
    let (reader, kept): (Box<dyn ChunkReader>, _) = if kind == Kind::Serial {
        (reader, None)
    } else {
        let (tee, kept) = crate::detect::Tee::new(reader);
        (Box::new(tee), Some(kept))
    };
    let mut decoder = decoder_for(kind, &line);

    let timed = matches!(kind, Kind::Serial | Kind::EdgeTxLog | Kind::Recording);
    let mut recorder = match &args.live.record {
        Some(_) if record_to_stdout => Some(Recorder::stdout(timed)),
        Some(p) => Some(Recorder::create(p, timed)?),
        None => None,
    };
    let out = &args.output;
    // With --top and no -o, the view is the only output.
    let mut table = match (out.top, out.output_file()) {
        (true, None) => None,
        (_, file) => {
            let output = match file {
                Some(p) => Output::create(p)
                    .map_err(|e| Failure::Output(format!("cannot create {}: {e}", p.display())))?,
                None => Output::stdout(),
            };
            let to_terminal = file.is_none() && std::io::stdout().is_terminal();
            let no_color_env = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
            let mut table = Table::new(
                output,
                out.table_options(to_terminal, no_color_env),
                decoder.columns(),
            );
            table.set_pretty_widths(protocol.pretty_widths);
            if let Some(p) = &out.plot {
                table.set_plot(p.clone());
            }
            if out.wide {
                let format = out.table_options(to_terminal, no_color_env).format;
                if !matches!(format, Format::Csv | Format::Tsv) {
                    return Err(Failure::Usage(
                        "--wide writes CSV or TSV; add -f csv (or -o FILE.csv)".into(),
                    ));
                }
                let step = match out.every {
                    Some(ms) => crate::sink::wide::Step::Every(ms * 1000),
                    None => crate::sink::wide::Step::PollCycle,
                };
                if out.raw || out.time == TimeMode::Abs {
                    eprintln!(
                        "busnoop: note: --wide has no Raw or Time column (--raw, --time abs); its \
                         Date and Time columns come with any source that has wall-clock time"
                    );
                }
                table.set_wide(step, kind == Kind::Serial);
            }
            Some(table)
        }
    };
    let live = kind == Kind::Serial;
    let speed = out.speed.unwrap_or(if out.top { 1.0 } else { 0.0 });
    let pacer = if live { None } else { Pacer::new(speed) };
    let rx = source::spawn(reader, progress);
    let source_name = args.source.display().to_string();
    let ctx = Context {
        stop: &stop,
        recorder: recorder.as_mut(),
        protocol: protocol.name,
        live,
        source: &source_name,
        selection,
    };
    if let Some(t) = &mut table {
        t.header().map_err(Failure::from)?;
    }
    let (result, rows) = if out.top {
        let info = Info {
            protocol: protocol.name.to_owned(),
            source: source_name.clone(),
            baud: live.then_some(line.baud),
            speed: pacer.as_ref().map(Pacer::speed),
            live,
        };
        let columns = decoder.columns().to_vec();
        let mut view = Top::open(table.as_mut(), &columns, info, pacer)
            .map_err(|e| Failure::Output(format!("cannot set up the terminal for --top: {e}")))?;
        let result = drive(decoder.as_mut(), &rx, &mut view, ctx);
        if result.is_ok() {
            view.hold();
        }
        let rows = view.rows();
        // Leaves the alternate screen and gives stderr back (with what was written to it).
        drop(view);
        (result, rows)
    } else {
        let table = table.as_mut().expect("a table without --top");
        let result = match pacer {
            Some(pacer) => drive(
                decoder.as_mut(),
                &rx,
                &mut Paced {
                    inner: table,
                    pacer,
                },
                ctx,
            ),
            None => drive(decoder.as_mut(), &rx, table, ctx),
        };
        (result, table.rows())
    };
    let stats = match (out.stats, out.stats_format) {
        (false, _) => None,
        (true, Some(StatsFormat::Json)) => Some(StatsFormat::Json),
        (true, _) => Some(StatsFormat::Text),
    };
    let hidden = table.as_ref().map_or(0, Table::skipped);
    report(
        decoder.as_ref(),
        stats,
        protocol.name,
        rows,
        hidden,
        &result,
    );
    // Frames that decoded: the table counts its frame rows, the decoder its valid frames.
    // (Rows a filter hid are not in the table's count; the decoder's count has them.)
    let frames = table
        .as_ref()
        .map_or(0, |t| t.frames())
        .max(decoder.valid_frames());
    // A clean run needs no second look; otherwise the start of the input is scored against
    // every protocol (`busnoop detect`'s scoring).
    if result.is_ok()
        && let Some(kept) = kept
        && (decoder.problems().line().is_some() || frames == 0)
        && let Ok(kept) = kept.lock()
    {
        use crate::detect::{Advice, advise};
        match advise(protocol, kind, &kept, frames, &args.source) {
            Advice::Fine => {}
            Advice::Note(n) => eprintln!("busnoop: {n}"),
            Advice::NothingDecoded(m) => return Err(Failure::NothingDecoded(m)),
        }
    }
    result
}

/// Notes on options that cannot do what they ask for this input or output: `--time abs` on a
/// source without times, `--utc` on times without a zone (or without `--time abs`), an `-o`
/// extension that names no format.
fn option_notes(out: &OutputArgs, kind: Kind) -> Vec<String> {
    let mut notes = Vec::new();
    if out.time == TimeMode::Abs && kind == Kind::Raw {
        notes.push(
            "--time abs: raw wire bytes carry no wall-clock time, so the Time column stays \
             empty (a recording made with --record FILE.pcap keeps the times)"
                .to_string(),
        );
    }
    if out.utc && out.time != TimeMode::Abs {
        notes.push("--utc has an effect only with --time abs".to_string());
    } else if out.utc && kind == Kind::EdgeTxLog {
        notes.push(
            "--utc: an EdgeTX log's times have no time zone; they are shown as logged".to_string(),
        );
    }
    if out.format.is_none()
        && let Some(p) = out.output_file()
        && let Some(ext) = p.extension()
        && Format::from_path(p).is_none()
    {
        notes.push(format!(
            "-o {}: .{} is not a format busnoop writes; the table is TSV (tab-separated). Use \
             .csv, .tsv, .jsonl or .txt, or --format",
            p.display(),
            ext.to_string_lossy()
        ));
    }
    notes
}

/// `--top` draws on standard output, which must be a terminal and carry nothing else.
fn check_top(args: &CaptureArgs, record_to_stdout: bool) -> Result<(), Failure> {
    if !args.output.top {
        return Ok(());
    }
    if args.output.output.as_deref().is_some_and(is_dash) {
        return Err(Failure::Usage(
            "--top draws on standard output; write the table with -o FILE".into(),
        ));
    }
    if record_to_stdout {
        return Err(Failure::Usage(
            "--top draws on standard output; record to a file (--record FILE.pcap)".into(),
        ));
    }
    if !std::io::stdout().is_terminal() {
        return Err(Failure::Usage(
            "--top needs a terminal on standard output; without one, write the table (drop \
             --top, or -o FILE)"
                .into(),
        ));
    }
    Ok(())
}

/// Opens SOURCE and returns its kind with the reader for it; `keep_input`: a capture's reader
/// also hands on its input bytes (for `--record`).
fn open_source(
    input: Input,
    cfg: &serial::SerialConfig,
    reconnect: bool,
    keep_input: bool,
) -> Result<source::Reading, Failure> {
    if let Input::Device(path) = &input {
        match serial::open(path, cfg) {
            Ok(port) => {
                if let Some(w) = serial::latency_warning(path, std::path::Path::new("/sys")) {
                    eprintln!("busnoop: note: {w}");
                }
                let reader = SerialReader::new(path, port, *cfg, reconnect);
                return Ok((Kind::Serial, Box::new(reader), None));
            }
            // A character device that is not a terminal (/dev/null, /dev/zero): read it as a file.
            Err(e) if serial::is_not_a_tty(&e) => {}
            Err(e) => return Err(serial::open_failure(path, &e)),
        }
    }
    let (opened, progress) = source::open(&input)?;
    let kind = opened.kind;
    let reader: Box<dyn ChunkReader> = match kind {
        Kind::EdgeTxLog => Box::new(source::edgetx::EdgeTxReader::new(opened)),
        Kind::Recording => Box::new(source::recording::RecordingReader::new(opened)),
        Kind::Pcap | Kind::Pcapng => {
            Box::new(source::capture::CaptureReader::new(opened, keep_input))
        }
        Kind::Raw | Kind::Serial => Box::new(source::RawReader::new(opened)),
    };
    Ok((kind, reader, Some(progress)))
}

/// What a file argument is, for telling whether two of them are one file.
#[derive(Debug, PartialEq, Eq)]
enum FileId {
    /// An existing regular file: device and inode (so symlinks and hard links compare equal).
    Inode(u64, u64),
    /// A file that does not exist yet: its absolute name, with the directory's links resolved.
    Name(PathBuf),
}

impl FileId {
    /// Regular files only: special files (/dev/null, a terminal, a pipe) may well be shared.
    fn of_metadata(m: &std::fs::Metadata) -> Option<FileId> {
        use std::os::unix::fs::MetadataExt;
        m.is_file().then(|| FileId::Inode(m.dev(), m.ino()))
    }

    fn of_path(p: &Path) -> Option<FileId> {
        match std::fs::metadata(p) {
            Ok(m) => FileId::of_metadata(&m),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                // A dangling symlink would be created at its target: no name to compare.
                if std::fs::symlink_metadata(p).is_ok() {
                    return None;
                }
                let name = p.file_name()?;
                let dir = match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                Some(FileId::Name(std::fs::canonicalize(dir).ok()?.join(name)))
            }
            Err(_) => None,
        }
    }

    /// The file behind an open descriptor (standard input or output).
    fn of_fd(fd: std::os::fd::BorrowedFd<'_>) -> Option<FileId> {
        let file = std::fs::File::from(fd.try_clone_to_owned().ok()?);
        FileId::of_metadata(&file.metadata().ok()?)
    }
}

/// Refuses, before anything is opened for writing, an output (`-o`, standard output) or a
/// recording that is the input file itself (by device and inode: symlinks, hard links and
/// `- < file` included), or an output and a recording that are one file.
fn check_distinct(
    input: &Input,
    output: Option<&Path>,
    record: Option<&Path>,
) -> Result<(), Failure> {
    use std::os::fd::AsFd;
    let stdout_id = || FileId::of_fd(std::io::stdout().as_fd());
    let (source, source_name) = match input {
        Input::Stdin => (
            FileId::of_fd(std::io::stdin().as_fd()),
            "standard input (the input)".to_string(),
        ),
        Input::File(p) => (FileId::of_path(p), format!("the input {}", p.display())),
        Input::Device(_) => (None, String::new()),
    };
    let (out, out_name) = match output {
        Some(p) => (FileId::of_path(p), format!("-o {}", p.display())),
        None => (stdout_id(), "standard output".to_string()),
    };
    let (rec, rec_name) = match record {
        Some(p) if is_dash(p) => (stdout_id(), "--record - (standard output)".to_string()),
        Some(p) => (FileId::of_path(p), format!("--record {}", p.display())),
        None => (None, String::new()),
    };
    let same = |a: &Option<FileId>, b: &Option<FileId>| a.is_some() && a == b;
    for (id, name) in [(&out, &out_name), (&rec, &rec_name)] {
        if same(&source, id) {
            return Err(Failure::Usage(format!(
                "{name} is the same file as {source_name}: writing it would destroy the \
                 capture; write somewhere else"
            )));
        }
    }
    if same(&out, &rec) {
        return Err(Failure::Usage(format!(
            "{out_name} and {rec_name} are the same file; give them different names"
        )));
    }
    Ok(())
}

/// `busnoop ports`.
fn list_ports() -> Result<(), Failure> {
    let ports = serial::list_ports();
    if ports.is_empty() {
        eprintln!("busnoop: no serial ports found");
        return Ok(());
    }
    let mut text = String::new();
    text.push_str("PORT\tTYPE\tVID:PID\tSERIAL\tMANUFACTURER\tPRODUCT\tBY-ID\n");
    for p in ports {
        let vid_pid = p
            .vid_pid
            .map_or(String::new(), |(v, pid)| format!("{v:04x}:{pid:04x}"));
        text.push_str(&format!(
            "{}\t{}\t{}\t{}\t{}\t{}\t{}\n",
            p.name,
            p.kind,
            vid_pid,
            p.serial_number.unwrap_or_default(),
            p.manufacturer.unwrap_or_default(),
            p.product.unwrap_or_default(),
            p.by_id.map(|b| b.display().to_string()).unwrap_or_default()
        ));
    }
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(Failure::BrokenPipe),
        Err(e) => Err(Failure::Output(format!(
            "cannot write to standard output: {e}"
        ))),
    }
}

/// The end-of-run summary on stderr: the full statistics with --stats, otherwise one line when
/// something went wrong.
fn report(
    decoder: &dyn Decoder,
    stats: Option<StatsFormat>,
    protocol: &str,
    rows: u64,
    hidden: u64,
    result: &Result<(), Failure>,
) {
    if matches!(result, Err(Failure::BrokenPipe)) {
        return;
    }
    if stats == Some(StatsFormat::Text) {
        if hidden > 0 {
            eprintln!(
                "{protocol} statistics ({rows} rows, {} shown, {hidden} hidden by filters)",
                rows - hidden
            );
        } else {
            eprintln!("{protocol} statistics ({rows} rows)");
        }
        eprintln!("{}", decoder.stats());
    }
    // When the output failed, the one line that matters is the write error (printed last).
    let problems = decoder.problems().line();
    if !matches!(result, Err(Failure::Output(_)))
        && stats != Some(StatsFormat::Json)
        && let Some(p) = &problems
    {
        eprintln!("busnoop: {p}");
    }
    if let Err(Failure::Signal(i)) = result {
        eprintln!(
            "busnoop: interrupted after {rows} rows; all decoded rows were written{}",
            i.input_note()
        );
    }
    if stats == Some(StatsFormat::Json) {
        let json = crate::stats_json::to_json(
            &decoder.stats(),
            protocol,
            rows,
            hidden,
            decoder.valid_frames(),
            problems.as_deref(),
        );
        eprintln!("{json}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(extra: &[&str]) -> OutputArgs {
        let mut argv = vec!["busnoop", "sport", "x"];
        argv.extend_from_slice(extra);
        match Cli::try_parse_from(argv).unwrap().command {
            Command::Sport(a) => a.capture.output,
            _ => unreachable!(),
        }
    }

    #[test]
    fn every_protocol_subcommand_is_in_the_protocol_table() {
        use clap::CommandFactory;
        let table: Vec<&str> = crate::protocols::PROTOCOLS
            .iter()
            .map(|p| p.command)
            .collect();
        let subcommands: Vec<String> = Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_owned())
            .filter(|n| !OTHER_COMMANDS.contains(&n.as_str()))
            .collect();
        assert_eq!(subcommands, table);
    }

    #[test]
    fn format_defaults() {
        assert_eq!(args(&[]).table_options(true, false).format, Format::Pretty);
        assert_eq!(args(&[]).table_options(false, false).format, Format::Tsv);
        assert_eq!(
            args(&["-o", "a.csv"]).table_options(false, false).format,
            Format::Csv
        );
        assert_eq!(
            args(&["-o", "a.bin"]).table_options(false, false).format,
            Format::Tsv
        );
        assert_eq!(
            args(&["-o", "a.csv", "-f", "jsonl"])
                .table_options(false, false)
                .format,
            Format::Jsonl
        );
    }

    #[test]
    fn colour_follows_terminal_no_color_and_the_option() {
        assert!(args(&[]).table_options(true, false).color);
        assert!(
            !args(&[]).table_options(true, true).color,
            "NO_COLOR turns auto off"
        );
        assert!(
            !args(&[]).table_options(false, false).color,
            "not a terminal"
        );
        assert!(
            args(&["-f", "pretty", "--color", "always"])
                .table_options(false, true)
                .color
        );
        assert!(!args(&["--color", "never"]).table_options(true, false).color);
        assert!(
            !args(&["-f", "tsv", "--color", "always"])
                .table_options(true, false)
                .color
        );
    }
}
