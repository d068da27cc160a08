//! The command line's options (clap stays here and in `project.rs`): one subcommand per
//! protocol, the options every capture shares, and the ranges numeric options accept.

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use super::{is_dash, project};
use crate::sink::{Format, TableOptions};
use crate::source::serial;

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
                  11 detect: no known protocol, 12 bad project file, 129 hangup, 130 Ctrl-C, 141 output closed, 143 SIGTERM."
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
    #[command(
        mut_arg("source", |a| a.help(SBUS_SOURCE)),
        mut_arg("record", |a| a.help(SBUS_RECORD))
    )]
    Sbus(SbusArgs),
    /// modm SAB / SAB2: both framings (0x54 + CRC-8, 0x7E + CRC-16) auto-detected,
    /// requests paired with responses.
    #[command(visible_alias = "sab", mut_arg("source", |a| a.help(SAB_SOURCE)))]
    Sab2(SabArgs),
    /// Which protocol is on this wire? Tries every protocol (S-Bus modes, SAB framings) on a
    /// file's first megabytes, or on a serial port at the usual baud rates, and prints the
    /// verdict, the evidence and the command to run.
    Detect(DetectArgs),
    /// Plot a capture's numbers as time series: one panel per unit, broken frames marked, as
    /// SVG or PNG (`busnoop plot flight.log --sensor Alt,VFAS -o flight.svg`).
    Plot(PlotArgs),
    /// List the serial ports of this machine (type, USB VID:PID, serial number, names).
    Ports,
    /// Wireshark extcap interface: lets Wireshark capture an S.Port or SAB bus live (install:
    /// docs/wireshark.md). Wireshark runs it; by hand, `busnoop extcap --extcap-interfaces`.
    Extcap(super::extcap::ExtcapArgs),
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
#[cfg(test)]
pub const OTHER_COMMANDS: &[&str] = &["detect", "plot", "ports", "extcap", "completions", "man"];

/// `busnoop plot`.
#[derive(Args, Debug, Clone)]
pub struct PlotArgs {
    /// The capture to plot: a file (raw wire bytes, an EdgeTX/OpenTX log, a pcap) or `-` (a
    /// pipe, like a FIFO, needs --protocol: it can be read only once).
    pub source: PathBuf,
    /// The numbers to plot, by their names in the wide table without unit (`Alt`, `VFAS`,
    /// `Cell1`, `Cell1@8`), comma-separated [default: every number].
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub sensor: Vec<String>,
    /// The image to write: FILE.svg or FILE.png.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// The protocol [default: detected as by `busnoop detect`; required for `-` and FIFOs].
    #[arg(long, value_name = "NAME", value_parser = ["sport", "sbus", "sab2"])]
    pub protocol: Option<String>,
}

/// `SOURCE` in `busnoop sport --help`: only what S.Port reads.
const SPORT_SOURCE: &str = "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), \
     a capture file (raw wire bytes, an EdgeTX/OpenTX S.Port debug log, a busnoop .pcap or \
     .pcapng recording) or `-` for standard input. File kinds are recognised by content.";
/// `SOURCE` in `busnoop sbus --help`.
const SBUS_SOURCE: &str = "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), \
     a capture file (raw wire bytes, a busnoop .pcap or .pcapng recording, a pcap/pcapng capture of \
     Ether-S-Bus traffic) or `-` for standard input (also a `tcpdump -U -w -` pipe). File kinds \
     are recognised by content; `--baud` also sets the byte times of raw files.";
/// `--record` in every protocol's help (a macro, so that sbus's can extend it with `concat!`).
macro_rules! record_help {
    () => {
        "Keep what came off the wire while decoding: FILE.pcap or FILE.pcapng with arrival times \
         (busnoop replays both with the original Millis; Wireshark opens them; pcapng also names \
         the device and baud and comments reconnect gaps), FILE.bin or FILE.raw: the raw bytes; \
         `-`: the raw bytes on standard output (with -o FILE only). Other names are refused"
    };
}
/// `--record` in `busnoop sbus --help`: a network capture is recorded as its packets.
const SBUS_RECORD: &str = concat!(
    record_help!(),
    ". A pcap/pcapng capture of Ether-S-Bus is recorded as its packets (its link type, times, \
     bytes): FILE.pcap, FILE.pcapng, or `-` as pcap; raw names are refused for it"
);
/// `SOURCE` in `busnoop sab2 --help`.
const SAB_SOURCE: &str = "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), \
     a capture file (raw wire bytes, a busnoop .pcap or .pcapng recording) or `-` for standard \
     input. File kinds are recognised by content; `--baud` also sets the byte times of raw files.";

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
    pub(super) fn options(&self, baud: u32) -> crate::sbus::Options {
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

    /// Read a command's payloads as numbers of a type (repeatable): `--value distance=u16*0.01:m`,
    /// `--value 0x34=f32:deg`. TYPE: u8 i8 u16 i16 u32 i32 f32 (little endian); SCALE multiplies
    /// (a plain decimal); UNIT goes to the Unit column. CMD is a code or a --command name, with
    /// `.req` or `.ack` for one direction only. Undeclared payloads of 1, 2 or 4 bytes are
    /// unsigned integers.
    #[arg(long, value_name = "CMD=TYPE[*SCALE][:UNIT]")]
    pub value: Vec<String>,

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
    pub(super) fn options(&self, baud: u32) -> crate::sab::Options {
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
            values: Vec::new(),
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
    pub select: project::SelectArgs,
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

    // The help is `record_help!` (sbus extends it for network captures).
    #[arg(long, value_name = "FILE", help = record_help!())]
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
    #[arg(long, value_name = "MS", requires = "wide",
          value_parser = clap::value_parser!(u64).range(1..=3_600_000))]
    pub every: Option<u64>,

    /// With --wide: at most N columns, the first N numbers to appear; the numbers of later
    /// columns are left out, counted in a note [default: 2000].
    #[arg(long, value_name = "N", requires = "wide",
          value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub max_columns: Option<u32>,

    /// `busnoop plot`: rows go to a plot instead.
    #[arg(skip)]
    pub plot: Option<crate::plot::PlotSpec>,
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

/// Valid values of the millisecond options (`--timeout-ms`, `--gap-ms`): 1 ms to one hour.
pub const MS_RANGE: std::ops::RangeInclusive<u64> = 1..=3_600_000;

/// Valid line speeds for `--baud`: 0 would mean "hang up" on a real UART, and nothing on a
/// bus busnoop reads runs above 12 Mbaud (the fastest USB adapters, FT232H).
pub const BAUD_RANGE: std::ops::RangeInclusive<i64> = 50..=12_000_000;

/// `busnoop detect`.
#[derive(Args, Debug)]
pub struct DetectArgs {
    /// What to examine: a capture file (raw wire bytes, an EdgeTX S.Port log, a busnoop .pcap
    /// recording, a pcap/pcapng capture), `-` for standard input, or a serial device, which is
    /// listened to (passively, read-only) at each baud rate in turn.
    pub source: PathBuf,

    /// Serial devices: how long to listen at each baud rate.
    #[arg(long, value_name = "MS", default_value_t = 1500,
          value_parser = clap::value_parser!(u64).range(10..=60_000))]
    pub listen_ms: u64,

    /// Serial devices: the baud rates to try, comma-separated [default: 9600, 19200, 38400,
    /// 57600, 100000, 115200, 230400, 400000, 420000].
    #[arg(long = "baud", value_name = "BAUD", value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(BAUD_RANGE))]
    pub bauds: Vec<u32>,

    /// Serial devices: DTR and RTS, as for the protocol commands.
    #[arg(long, value_enum, value_name = "MODE", default_value_t)]
    pub dtr_rts: crate::source::serial::ModemLines,
}

impl DetectArgs {
    pub fn options(&self) -> crate::detect::Options {
        crate::detect::Options {
            source: self.source.clone(),
            listen_ms: self.listen_ms,
            bauds: self.bauds.clone(),
            dtr_rts: self.dtr_rts,
        }
    }
}
