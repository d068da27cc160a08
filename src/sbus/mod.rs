//! Saia S-Bus: serial modes (data, secure data, break, parity) and Ether-S-Bus over UDP.
//!
//! * `serial` (serial line) and [`crate::pcap`] + [`ether`] (captures): the pure
//!   reassemblers;
//! * [`commands`]: the command table; [`telegram`]: the CRC, encoders and content decoding;
//!   `pairing`: answers matched with requests;
//! * `map.rs`: the one mapping of telegrams onto the log table (documented in `docs/sbus.md`),
//!   used by both front ends; `stats.rs`: the counters, the `--stats` report and the problems
//!   line;
//! * `serial_decoder.rs` ([`SerialDecoder`]: mode detection, framer events to rows) and
//!   `ether_decoder.rs` ([`EtherDecoder`]: packets, conversations and PLCs to rows).

mod args;
pub mod commands;
pub mod ether;
mod ether_decoder;
mod export;
mod map;
mod media;
pub(crate) mod pairing;
pub(crate) mod serial;
mod serial_decoder;
mod stats;
pub mod telegram;
mod vocab;

pub use ether_decoder::EtherDecoder;
pub use serial_decoder::{Resolved, SerialDecoder};
pub use stats::{MAX_PLCS, StationStats, Totals};

use crate::protocol::{Decoder, Export, Front, InputKind, Line, Probe, Protocol, Variant};

/// Default serial speed of S-Bus ports.
pub const DEFAULT_BAUD: u32 = 9600;
/// Saia S-Bus: serial lines at 9600 baud 8N1 (a parity-mode line has a 9th bit that a standard
/// UART cannot follow, see docs/sbus.md), and Ether-S-Bus captures.
pub const PROTOCOL: Protocol = Protocol {
    name: "S-Bus",
    command: "sbus",
    aliases: &[],
    summary: "Saia S-Bus (PCD controllers): serial data/secure/break/parity modes, and Ether-S-Bus \
              (UDP 5050) captures; not Futaba SBUS, which is `busnoop futaba`",
    about: "Saia S-Bus, the bus of Saia PCD controllers: serial data, secure data, break and parity \
            modes (9600 baud by default; the mode is detected or set with --mode), and Ether-S-Bus \
            (UDP 5050) from pcap/pcapng files or a `tcpdump -U -w -` pipe. Requests are paired \
            with their answers and timed. Futaba SBUS, the RC receiver bus of a similar name, is \
            `busnoop futaba`.",
    examples: "Examples:\n  busnoop sbus /dev/ttyUSB0 --baud 19200\n  busnoop sbus plant.pcap \
               --name Boiler=10\n  tcpdump -U -w - udp port 5050 | busnoop sbus -",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, a busnoop .pcap or .pcapng recording, a pcap/pcapng \
                  capture of Ether-S-Bus traffic) or `-` for standard input (also a `tcpdump -U -w \
                  -` pipe). File kinds are recognised by content; `--baud` also sets the byte \
                  times of raw files.",
    line: Line::n81(DEFAULT_BAUD),
    inverted: false,
    rates: &[DEFAULT_BAUD, 19_200, 38_400, 57_600, 115_200],
    accepts: &[
        InputKind::Raw,
        InputKind::Serial,
        InputKind::Recording,
        InputKind::Pcap,
        InputKind::Pcapng,
    ],
    accepts_text: "raw serial bytes, busnoop recordings or pcap/pcapng files of Ether-S-Bus traffic",
    // Counter Millis ID Device(IP:port) Type Sensor#(DB4000[2]) Sensor(command) Data | Resp ms
    // Seq Note
    pretty_widths: &[7, 8, 3, 15, 9, 9, 22, 40, 7, 5, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[("timeout-ms", "master timeouts")],
    export: Some(Export {
        linktype: crate::pcap::linktype::RAW,
        linktype_name: "RAW",
        dissector: "sbus (Wireshark's own)",
        extcap: "Saia S-Bus, serial (busnoop)",
        wrap: Some(wrap),
    }),
};

fn wrap() -> Box<dyn crate::protocol::Wrap> {
    Box::<export::SbusWrap>::default()
}

/// `detect` tries each serial mode on a byte stream, Ether-S-Bus on a network capture (scored
/// on the capture's bytes: the pcap reader runs inside).
fn variants(probe: &Probe) -> Vec<Variant> {
    let opts = |mode| Options {
        mode,
        baud: probe.line.baud,
        ..Options::default()
    };
    match probe.input {
        InputKind::Pcap | InputKind::Pcapng => vec![Variant {
            label: "Ether-S-Bus",
            args: &[],
            decoder: Box::new(crate::protocol::PcapBytes::new(EtherDecoder::new(&opts(
                Mode::Auto,
            )))),
        }],
        input => [
            ("S-Bus data mode", &[][..], Mode::Data),
            ("S-Bus break mode", &[][..], Mode::Break),
            ("S-Bus parity mode", &["--mode", "parity"][..], Mode::Parity),
        ]
        .into_iter()
        .map(|(label, args, mode)| Variant {
            label,
            args,
            decoder: decoder(opts(mode), input),
        })
        .collect(),
    }
}

/// Ether-S-Bus server port.
pub const DEFAULT_PORT: u16 = 5050;
/// Default Ether-S-Bus timeout (ms): no standard value is documented; 1 s is our choice.
pub const DEFAULT_ETHER_TIMEOUT_MS: u64 = 1000;
/// Bytes an auto-detecting decoder looks at for a data-mode telegram before it settles on
/// break/parity mode.
pub const DETECT_BYTES: usize = 4096;

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Resp ms", "Seq", "Note"];

/// Serial mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
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

/// Decoder settings (from the command line).
#[derive(Clone, Debug)]
pub struct Options {
    pub mode: Mode,
    pub baud: u32,
    /// Master timeout; `None` = the default for the mode and baud rate.
    pub timeout_ms: Option<u64>,
    /// Silence that ends a serial telegram (sources with time); `None` = the default.
    pub gap_ms: Option<u64>,
    /// Names for stations (`--station NAME=ADDR`).
    pub stations: Vec<(String, u8)>,
    /// Ether-S-Bus UDP port.
    pub port: u16,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            mode: Mode::Auto,
            baud: DEFAULT_BAUD,
            timeout_ms: None,
            gap_ms: None,
            stations: Vec::new(),
            port: DEFAULT_PORT,
        }
    }
}

/// The S-Bus decoder for an input of `kind` (one that [`PROTOCOL`] accepts): serial bytes
/// (raw files, devices, busnoop recordings) or Ether-S-Bus captures (pcap, pcapng).
pub fn decoder(opts: Options, kind: InputKind) -> Box<dyn Decoder> {
    match kind {
        InputKind::Pcap | InputKind::Pcapng => Box::new(EtherDecoder::new(&opts)),
        InputKind::Raw
        | InputKind::Serial
        | InputKind::Recording
        | InputKind::EdgeTxLog
        | InputKind::Trace => Box::new(SerialDecoder::new(opts)),
    }
}

/// Default master timeout (ms) for a baud rate (M739E §3): data mode, or parity/break mode.
pub fn default_timeout_ms(baud: u32, data_mode: bool) -> u64 {
    const TABLE: [(u32, u64, u64); 10] = [
        (110, 15000, 15000),
        (150, 9000, 15000),
        (300, 5000, 7500),
        (600, 3000, 4500),
        (1200, 2000, 3000),
        (2400, 1000, 1500),
        (4800, 500, 750),
        (9600, 250, 375),
        (19200, 200, 300),
        (38400, 200, 300),
    ];
    let mut row = TABLE[0];
    for r in TABLE {
        if baud >= r.0 {
            row = r;
        }
    }
    if data_mode { row.2 } else { row.1 }
}

/// Default gap (µs) that ends a serial telegram: 20 character times, at least 20 ms (USB
/// adapters deliver bytes in bursts).
pub fn default_gap_us(baud: u32, bits: u32) -> u64 {
    let char_us = bits as u64 * 1_000_000 / baud.max(1) as u64;
    (20 * char_us).max(20_000)
}

/// Parses `NAME=ADDR` for `--station`.
pub fn parse_station(s: &str) -> Result<(String, u8), String> {
    let (name, addr) = s
        .rsplit_once('=')
        .ok_or_else(|| format!("expected NAME=ADDR, got {s:?}"))?;
    let addr: u8 = addr
        .trim()
        .parse()
        .map_err(|_| format!("station address must be 0-255, got {addr:?}"))?;
    if name.is_empty() {
        return Err("the station name is empty".into());
    }
    Ok((name.to_owned(), addr))
}

#[cfg(test)]
mod tests;
