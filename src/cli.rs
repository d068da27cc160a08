//! Command line: argument parsing, wiring source → decoder → sink, messages and exit codes.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::decoder::Decoder;
use crate::exit::{Failure, code};
use crate::run::{Stop, drive};
use crate::sink::{Format, Output, Table, TableOptions};
use crate::source::{self, ChunkReader, Input, Kind};

#[derive(Parser, Debug)]
#[command(
    name = "busnoop",
    version,
    about = "Passive bus sniffer: reassembles FrSky S.Port frames from a capture or a pipe and \
             prints the S-Port_Snoop log table as coloured text, TSV, CSV or JSON Lines.",
    after_help = "Exit codes: 0 ok, 2 usage, 3 not found, 4 permission denied, 5 port busy, \
                  6 device error, 7 adapter disconnected, 8 output error, 9 input error, \
                  130 Ctrl-C, 141 output closed, 143 SIGTERM."
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
    /// FrSky S.Port: polls `7E id`, 8-byte responses, byte stuffing, sum CRC.
    Sport(SportArgs),
    /// Saia S-Bus (PCD controllers): serial data/secure/break/parity modes, and Ether-S-Bus
    /// (UDP 5050) from pcap/pcapng files or a `tcpdump -w -` pipe.
    Sbus(SbusArgs),
}

#[derive(Args, Debug)]
pub struct SbusArgs {
    /// Capture to read: a raw `.bin` of serial wire bytes, a pcap/pcapng file of Ether-S-Bus
    /// traffic, or `-` for standard input (`tcpdump -i IFACE -U -w - udp port 5050 | busnoop
    /// sbus -`). The kind is recognised by content.
    pub source: String,

    /// Serial mode; auto picks data/secure mode when the stream uses 0xB5 framing, break mode
    /// otherwise.
    #[arg(long, value_enum, default_value_t = crate::sbus::Mode::Auto)]
    pub mode: crate::sbus::Mode,

    /// Serial baud rate: the default master timeout and, for files without time, the time of
    /// each byte (10 bits per byte, 11 in parity mode) follow from it.
    #[arg(long, default_value_t = crate::sbus::DEFAULT_BAUD)]
    pub baud: u32,

    /// Master timeout in ms for Timeout rows and late answers [default: by mode and baud rate
    /// (375 ms data mode, 250 ms break/parity mode at 9600), 1000 ms for Ether-S-Bus].
    #[arg(long, value_name = "MS")]
    pub timeout_ms: Option<u64>,

    /// Serial sources with time: a silence longer than this ends a telegram [default: 20
    /// character times, at least 20 ms].
    #[arg(long, value_name = "MS")]
    pub gap_ms: Option<u64>,

    /// Name a station in the Device column (repeatable), e.g. `--station Boiler=10`.
    #[arg(long = "station", value_name = "NAME=ADDR", value_parser = crate::sbus::parse_station)]
    pub stations: Vec<(String, u8)>,

    /// Ether-S-Bus UDP port (datagrams to or from it are decoded).
    #[arg(long, default_value_t = crate::sbus::DEFAULT_PORT)]
    pub port: u16,

    #[command(flatten)]
    pub output: OutputArgs,
}

#[derive(Args, Debug)]
pub struct SportArgs {
    /// Capture to read: a raw `.bin` of wire bytes, an EdgeTX/OpenTX S.Port debug log, or `-`
    /// for standard input. The kind is recognised by content.
    pub source: String,

    #[command(flatten)]
    pub output: OutputArgs,
}

/// When to colour pretty output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColorChoice {
    /// Colour when writing to a terminal and NO_COLOR is not set.
    Auto,
    Always,
    Never,
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
    /// the format unless --format is given).
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

    /// `abs` adds a `Time` column with wall-clock times when the source has them.
    #[arg(long, value_enum, default_value_t = TimeMode::Rel)]
    pub time: TimeMode,

    /// With --time abs: print UTC instead of local time.
    #[arg(long)]
    pub utc: bool,
}

impl OutputArgs {
    fn table_options(&self, to_terminal: bool) -> TableOptions {
        let format = self.format.unwrap_or_else(|| match &self.output {
            Some(p) => Format::from_path(p).unwrap_or(Format::Tsv),
            None if to_terminal => Format::Pretty,
            None => Format::Tsv,
        });
        let no_color_env = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
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
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Sport(args) => {
            run_capture(&args.source, &args.output, "S.Port", |kind, opened| {
                let reader: Box<dyn ChunkReader> = match kind {
                    Kind::Raw => Box::new(source::RawReader::new(opened)),
                    Kind::EdgeTxLog => Box::new(source::edgetx::EdgeTxReader::new(opened)),
                    Kind::Pcap | Kind::Pcapng => {
                        return Err(Failure::Input(format!(
                            "{} is a pcap file; S.Port captures are raw .bin files or EdgeTX logs",
                            opened.name
                        )));
                    }
                };
                Ok(Plan {
                    decoder: Box::new(crate::sport::SportDecoder::new()),
                    reader,
                })
            })
        }
        Command::Sbus(args) => run_capture(&args.source, &args.output, "S-Bus", |kind, opened| {
            sbus_plan(&args, kind, opened)
        }),
    }
}

/// The S-Bus plan: serial decoder for raw bytes, Ether-S-Bus decoder for captures.
fn sbus_plan(args: &SbusArgs, kind: Kind, opened: source::Opened) -> Result<Plan, Failure> {
    let opts = crate::sbus::Options {
        mode: args.mode,
        baud: args.baud,
        timeout_ms: args.timeout_ms,
        gap_ms: args.gap_ms,
        stations: args.stations.clone(),
        port: args.port,
    };
    let decoder: Box<dyn Decoder> = match kind {
        Kind::Raw => Box::new(crate::sbus::SerialDecoder::new(opts)),
        Kind::Pcap | Kind::Pcapng => Box::new(crate::sbus::EtherDecoder::new(&opts)),
        Kind::EdgeTxLog => {
            return Err(Failure::Input(format!(
                "{} is an EdgeTX/OpenTX S.Port log; S-Bus captures are raw serial .bin files or \
                 pcap/pcapng files of Ether-S-Bus traffic",
                opened.name
            )));
        }
    };
    Ok(Plan {
        decoder,
        reader: Box::new(source::RawReader::new(opened)),
    })
}

/// What to run on an opened input: the protocol decoder and the reader for the input's kind.
pub struct Plan {
    pub decoder: Box<dyn Decoder>,
    pub reader: Box<dyn ChunkReader>,
}

/// Opens SOURCE, lets `plan` pick a decoder and a reader for its kind, decodes it into the
/// table and prints the summary.
pub fn run_capture(
    source_arg: &str,
    out: &OutputArgs,
    protocol: &str,
    plan: impl FnOnce(Kind, source::Opened) -> Result<Plan, Failure>,
) -> Result<(), Failure> {
    let stop = Stop::install()
        .map_err(|e| Failure::Internal(format!("cannot install signal handlers: {e}")))?;
    let input = Input::parse(source_arg);
    let opened = source::open(&input)?;
    tracing::info!("{}: detected {:?}", opened.name, opened.kind);
    let Plan {
        mut decoder,
        reader,
    } = plan(opened.kind, opened)?;

    let output = match &out.output {
        Some(p) => Output::create(p)
            .map_err(|e| Failure::Output(format!("cannot create {}: {e}", p.display())))?,
        None => Output::stdout(),
    };
    let to_terminal = out.output.is_none() && std::io::stdout().is_terminal();
    let mut table = Table::new(output, out.table_options(to_terminal), decoder.columns());
    let rx = source::spawn(reader);
    let result = table
        .header()
        .map_err(Failure::from)
        .and_then(|()| drive(decoder.as_mut(), &rx, &mut table, &stop));
    report(decoder.as_ref(), out.stats, protocol, table.rows(), &result);
    result
}

/// The end-of-run summary on stderr: the full statistics with --stats, otherwise one line when
/// something went wrong.
fn report(
    decoder: &dyn Decoder,
    stats: bool,
    protocol: &str,
    rows: u64,
    result: &Result<(), Failure>,
) {
    if matches!(result, Err(Failure::BrokenPipe)) {
        return;
    }
    if stats {
        eprintln!("{protocol} statistics ({rows} rows)");
        eprintln!("{}", decoder.stats());
    }
    if let Some(p) = decoder.problems() {
        eprintln!("busnoop: {p}");
    }
    if let Err(Failure::Signal(_)) = result {
        eprintln!("busnoop: interrupted after {rows} rows; all decoded rows were written");
    }
}
