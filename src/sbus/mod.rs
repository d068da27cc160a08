//! Saia S-Bus: serial modes (data, secure data, break, parity) and Ether-S-Bus over UDP.
//!
//! The pure reassemblers are in [`serial`] (serial line) and [`crate::pcap`] + [`ether`]
//! (captures); [`commands`] is the command table, [`telegram`] the CRC, encoders and content
//! decoding, [`pairing`] matches answers with requests. This module maps telegrams onto the
//! log table and keeps the statistics; the mapping is documented in `docs/sbus.md`.

pub mod commands;
pub mod ether;
pub mod pairing;
pub mod serial;
pub mod telegram;

use std::fmt::Write as _;
use std::net::SocketAddr;

use crate::fmt::{push_fixed, push_hex, push_u64};
use crate::pcap::{PcapError, PcapStream};
use crate::protocol::{Decoder, Kind, Line, Protocol};
use crate::row::{Class, Row};
use crate::row::{Latch, RowOut, RowResult};
use commands::Expect;
use pairing::{
    Answer, EtherPairing, Expired, Outstanding, RequestKind, SerialPairing, TableSizes, TimeoutWhy,
};
use serial::{BreakFramer, CrcCheck, DataFramer, Event, Frame, Tele};
use telegram::{BROADCAST, CrcBasis, ReqInfo};

/// Default serial speed of S-Bus ports.
pub const DEFAULT_BAUD: u32 = 9600;
/// What the shared command-line code needs to know: name and serial line format (8N1; a
/// parity-mode line has a 9th bit that a standard UART cannot follow, see docs/sbus.md).
pub const PROTOCOL: Protocol = Protocol {
    name: "S-Bus",
    command: "sbus",
    line: Line::n81(DEFAULT_BAUD),
    accepts: &[
        Kind::Raw,
        Kind::Serial,
        Kind::Recording,
        Kind::Pcap,
        Kind::Pcapng,
    ],
    accepts_text: "raw serial bytes, busnoop recordings or pcap/pcapng files of Ether-S-Bus traffic",
    // Counter Millis ID Device(IP:port) Type Sensor#(DB4000[2]) Sensor(command) Data | Resp ms
    // Seq Note
    pretty_widths: &[7, 8, 3, 15, 9, 9, 22, 40, 7, 5, 0],
};

/// Ether-S-Bus server port.
pub const DEFAULT_PORT: u16 = 5050;
/// Default Ether-S-Bus timeout (ms): no standard value is documented; 1 s is our choice.
pub const DEFAULT_ETHER_TIMEOUT_MS: u64 = 1000;
/// Ether-S-Bus PLCs with their own `--stats` row; the rest share one row (`other PLCs (N)`).
pub const MAX_PLCS: usize = 256;
/// Addresses of PLCs beyond [`MAX_PLCS`] remembered to count them once.
const MERGED_PLCS_KEPT: usize = 4_096;
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
pub fn decoder(opts: Options, kind: Kind) -> Box<dyn Decoder> {
    match kind {
        Kind::Pcap | Kind::Pcapng => Box::new(EtherDecoder::new(&opts)),
        Kind::Raw | Kind::Serial | Kind::Recording | Kind::EdgeTxLog => {
            Box::new(SerialDecoder::new(opts))
        }
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

// ---------------------------------------------------------------------------------------------
// Statistics
// ---------------------------------------------------------------------------------------------

/// NAK reasons counted separately: codes 1-4, the single NAK character, other codes.
const NAK_SLOTS: usize = 6;

fn nak_slot(code: u16, short: bool) -> usize {
    if short {
        return 4;
    }
    match code {
        1..=4 => code as usize - 1,
        _ => 5,
    }
}

const NAK_LABELS: [&str; NAK_SLOTS] = [
    "0x0001 no reason",
    "0x0002 password",
    "0x0003 PGU port reduced",
    "0x0004 PGU port used",
    "NAK character",
    "other code",
];

/// Counters per station (serial) or per PLC (Ether-S-Bus).
#[derive(Clone, Debug, Default)]
pub struct StationStats {
    pub requests: u64,
    pub broadcasts: u64,
    pub responses: u64,
    pub acks: u64,
    pub naks: [u64; NAK_SLOTS],
    pub retries: u64,
    pub timeouts: u64,
    pub crc_errors: u64,
    pub late: u64,
    pub mismatched: u64,
    pub seq_gaps: u64,
    pub seq_missing: u64,
    /// Response times in µs (bounded: exact up to a cap, then a histogram).
    pub times: crate::summary::Times,
}

impl StationStats {
    fn seen(&self) -> bool {
        self.requests + self.responses + self.acks + self.nak_total() + self.crc_errors > 0
    }

    pub fn nak_total(&self) -> u64 {
        self.naks.iter().sum()
    }

    fn time(&mut self, us: u64) {
        self.times.add(us);
    }

    /// (min, median, max) response time in µs; the median is the upper one for an even count
    /// and `false` when it comes from the histogram (three significant digits).
    pub fn response_times(&self) -> Option<(u64, (u64, bool), u64)> {
        let median = self.times.median_upper()?;
        Some((self.times.min, median, self.times.max))
    }
}

/// Counters for the whole capture.
#[derive(Clone, Debug, Default)]
pub struct Totals {
    pub valid: u64,
    pub crc_errors: u64,
    pub broken: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    pub timeouts: u64,
    pub retries: u64,
    pub naks: u64,
    pub no_request: u64,
    pub mismatched: u64,
    pub late: u64,
    /// CRC basis counts for data-mode telegrams: escaped, unescaped, both.
    pub basis: [u64; 3],
    /// Ether-S-Bus: packets read, UDP datagrams on the port, fragments skipped, packets that
    /// did not parse, other link types.
    pub packets: u64,
    pub datagrams: u64,
    pub fragments: u64,
    pub malformed: u64,
    pub not_sbus: u64,
    pub other_links: u64,
    pub seq_gaps: u64,
    /// Requests still waiting for an answer when the input ended.
    pub unanswered_at_end: u64,
    /// Ether-S-Bus conversations seen, forgotten after a minute without a packet, dropped at
    /// the cap ([`pairing::MAX_CONVERSATIONS`]); requests given up at
    /// [`pairing::MAX_OUTSTANDING`]; PLCs beyond [`MAX_PLCS`] counted in one row.
    pub conversations: u64,
    pub conversations_expired: u64,
    pub conversations_dropped: u64,
    pub requests_dropped: u64,
    pub plcs_merged: u64,
    /// The capture container itself is broken (message).
    pub pcap_error: Option<String>,
}

fn ms_text(us: u64) -> String {
    let mut s = String::new();
    push_fixed(&mut s, (us.min(i64::MAX as u64 - 50) as i64 + 50) / 100, 1);
    s
}

fn stats_table(rows: &[(String, String, &StationStats)], ether: bool) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "{:>4}  {:<22} {:>8} {:>8} {:>6} {:>6} {:>6} {:>7} {:>6} {:>5}",
        "ID", "Device", "Requests", "Response", "ACK", "NAK", "Retry", "Timeout", "BadCRC", "Late"
    );
    if ether {
        let _ = write!(s, " {:>6}", "SeqGap");
    }
    let _ = writeln!(s, " {:>8} {:>8} {:>8}", "Min ms", "Med ms", "Max ms");
    for (id, name, st) in rows {
        let _ = write!(
            s,
            "{:>4}  {:<22} {:>8} {:>8} {:>6} {:>6} {:>6} {:>7} {:>6} {:>5}",
            id,
            name,
            st.requests,
            st.responses,
            st.acks,
            st.nak_total(),
            st.retries,
            st.timeouts,
            st.crc_errors,
            st.late
        );
        if ether {
            let _ = write!(s, " {:>6}", st.seq_gaps);
        }
        match st.response_times() {
            Some((a, (m, exact), b)) => {
                let m = if exact {
                    ms_text(m)
                } else {
                    format!("~{}", ms_text(m))
                };
                let _ = writeln!(s, " {:>8} {:>8} {:>8}", ms_text(a), m, ms_text(b));
            }
            None => {
                let _ = writeln!(s, " {:>8} {:>8} {:>8}", "-", "-", "-");
            }
        }
        if st.nak_total() > 0 {
            let mut parts = Vec::new();
            for (i, &n) in st.naks.iter().enumerate() {
                if n > 0 {
                    parts.push(format!("{} ×{n}", NAK_LABELS[i]));
                }
            }
            let _ = writeln!(s, "      NAK reasons: {}", parts.join(", "));
        }
        if st.mismatched > 0 || st.broadcasts > 0 || st.seq_missing > 0 {
            let _ = writeln!(
                s,
                "      length mismatches {}, broadcasts {}, sequence numbers skipped {}",
                st.mismatched, st.broadcasts, st.seq_missing
            );
        }
    }
    s
}

fn totals_line(t: &Totals, ether: bool) -> String {
    let mut s = format!(
        "valid telegrams {}, CRC errors {}, cut/broken {}, garbage {} bytes in {} runs, \
         retries {}, timeouts {}, NAKs {}, answers without request {}, length mismatches {}, late {}, \
         unanswered at the end {}",
        t.valid,
        t.crc_errors,
        t.broken,
        t.garbage_bytes,
        t.garbage_runs,
        t.retries,
        t.timeouts,
        t.naks,
        t.no_request,
        t.mismatched,
        t.late,
        t.unanswered_at_end
    );
    if ether {
        let _ = write!(
            s,
            "\npackets {}, S-Bus datagrams {}, not S-Bus on the port {}, IP fragments skipped {}, \
             unparsable packets {}, other link types {}, sequence gaps {}",
            t.packets, t.datagrams, t.not_sbus, t.fragments, t.malformed, t.other_links, t.seq_gaps
        );
        let _ = write!(
            s,
            "\nconversations {}, forgotten after {} s idle {}, dropped at the cap of {} {}, \
             requests given up at the cap of {} {}, PLCs beyond {} counted together {}",
            t.conversations,
            pairing::CONVERSATION_IDLE / 1_000_000,
            t.conversations_expired,
            pairing::MAX_CONVERSATIONS,
            t.conversations_dropped,
            pairing::MAX_OUTSTANDING,
            t.requests_dropped,
            MAX_PLCS,
            t.plcs_merged
        );
    } else {
        let _ = write!(
            s,
            "\nCRC basis of data-mode telegrams: escaped {}, unescaped {}, both (no DLE pair) {}",
            t.basis[0], t.basis[1], t.basis[2]
        );
    }
    if let Some(e) = &t.pcap_error {
        let _ = write!(s, "\ncapture error: {e}");
    }
    s
}

fn problems_line(t: &Totals) -> Option<String> {
    let mut parts = Vec::new();
    let plural = crate::exit::count;
    if t.crc_errors > 0 {
        parts.push(plural(t.crc_errors, "CRC error", "CRC errors"));
    }
    if t.broken > 0 {
        parts.push(plural(t.broken, "cut telegram", "cut telegrams"));
    }
    if t.garbage_bytes > 0 {
        parts.push(format!(
            "{} skipped ({})",
            plural(t.garbage_bytes, "garbage byte", "garbage bytes"),
            plural(t.garbage_runs, "run", "runs")
        ));
    }
    if t.timeouts > 0 {
        parts.push(plural(t.timeouts, "timeout", "timeouts"));
    }
    if t.retries > 0 {
        parts.push(plural(t.retries, "retry", "retries"));
    }
    if t.naks > 0 {
        parts.push(plural(t.naks, "NAK", "NAKs"));
    }
    if t.conversations_dropped > 0 {
        parts.push(format!(
            "{} dropped (more than {} at once)",
            plural(t.conversations_dropped, "conversation", "conversations"),
            pairing::MAX_CONVERSATIONS
        ));
    }
    if t.requests_dropped > 0 {
        parts.push(format!(
            "{} given up (more than {} waiting)",
            plural(t.requests_dropped, "request", "requests"),
            pairing::MAX_OUTSTANDING
        ));
    }
    if t.not_sbus > 0 {
        parts.push(plural(
            t.not_sbus,
            "datagram on the port that is not S-Bus",
            "datagrams on the port that are not S-Bus",
        ));
    }
    if t.fragments > 0 {
        parts.push(plural(
            t.fragments,
            "IP fragment skipped",
            "IP fragments skipped",
        ));
    }
    if t.malformed > 0 {
        parts.push(plural(
            t.malformed,
            "unparsable packet",
            "unparsable packets",
        ));
    }
    if t.other_links > 0 {
        parts.push(plural(
            t.other_links,
            "packet of a link type that is not network traffic skipped",
            "packets of a link type that is not network traffic skipped",
        ));
    }
    if let Some(e) = &t.pcap_error {
        parts.push(format!("capture error: {e}"));
    }
    if parts.is_empty() {
        None
    } else {
        Some(format!(
            "S-Bus: {} in {} valid telegrams",
            parts.join(", "),
            t.valid
        ))
    }
}

// ---------------------------------------------------------------------------------------------
// Row text shared by the serial and Ether decoders
// ---------------------------------------------------------------------------------------------

/// Scratch buffers reused for every row.
#[derive(Default)]
struct Scratch {
    sensor_no: String,
    data: String,
    resp: String,
    seq: String,
    note: String,
    raw: Vec<u8>,
}

impl Scratch {
    fn clear(&mut self) {
        self.sensor_no.clear();
        self.data.clear();
        self.resp.clear();
        self.seq.clear();
        self.note.clear();
    }

    fn note(&mut self, text: &str) {
        if !self.note.is_empty() {
            self.note.push_str("; ");
        }
        self.note.push_str(text);
    }

    fn note_with(&mut self, f: impl FnOnce(&mut String)) {
        if !self.note.is_empty() {
            self.note.push_str("; ");
        }
        f(&mut self.note);
    }

    fn resp_time(&mut self, us: u64) {
        push_fixed(&mut self.resp, (us as i64 + 50) / 100, 1);
    }

    fn seq(&mut self, seq: u16) {
        push_u64(&mut self.seq, seq as u64);
    }
}

/// One row, from the scratch buffers.
#[allow(clippy::too_many_arguments)]
fn put_row(
    out: &mut dyn RowOut,
    sc: &Scratch,
    micros: u64,
    id: Option<u32>,
    device: &str,
    kind: &str,
    class: Class,
    sensor: &str,
    raw: &[u8],
) -> RowResult {
    let extra = [sc.resp.as_str(), sc.seq.as_str(), sc.note.as_str()];
    out.row(&Row {
        micros: Some(micros),
        id,
        device,
        kind,
        class,
        sensor_no: &sc.sensor_no,
        sensor,
        data: &sc.data,
        extra: &extra,
        raw,
    })
}

/// Notes for a request: layout problems, broadcast, security-relevant commands.
fn request_notes(sc: &mut Scratch, t: &telegram::RequestText) -> Class {
    let mut class = Class::Plain;
    if let Some(p) = t.layout_problem {
        sc.note(p);
        class = Class::Warning;
    }
    let info = &t.info;
    if info.station == BROADCAST {
        sc.note("broadcast");
        if !matches!(info.cmd, 0x30 | 0x39 | 0x44) {
            sc.note("only run/stop/restart cold ALL may be broadcast");
            class = Class::Warning;
        }
    }
    if info.cmd == 0x51 {
        sc.note("password write (0x51 write bytes can carry a login hash, CVE-2022-30320)");
        class = Class::Warning;
    }
    if let Some(c) = info.command()
        && c.pgu_change
    {
        sc.note("PGU command");
        class = Class::Warning;
    }
    class
}

/// Response text for a paired request; returns whether the length fits.
fn response_text(sc: &mut Scratch, req: &ReqInfo, data: &[u8]) -> bool {
    let fits = req.expect.fits(data);
    telegram::describe_response(req, data, &mut sc.sensor_no, &mut sc.data);
    if !fits {
        sc.note_with(|n| {
            n.push_str("length ");
            push_u64(n, data.len() as u64);
            match req.expect {
                Expect::Data(e) => {
                    n.push_str(" does not fit the request (expects ");
                    push_u64(n, e as u64);
                    n.push(')');
                }
                Expect::AckNak => n.push_str(": the request expects an ACK/NAK"),
                Expect::Nothing => n.push_str(": a broadcast expects no answer"),
                _ => n.push_str(" does not fit the request"),
            }
        });
    }
    fits
}

fn timeout_note(sc: &mut Scratch, why: TimeoutWhy, timeout_us: u64) {
    sc.note_with(|n| match why {
        TimeoutWhy::Deadline => {
            n.push_str("no answer within ");
            push_u64(n, timeout_us / 1000);
            n.push_str(" ms");
        }
        TimeoutWhy::NextRequest => n.push_str("no answer before the next request"),
        TimeoutWhy::Retry => n.push_str("no answer before the retry"),
        TimeoutWhy::End => n.push_str("no answer before the end of the capture"),
        TimeoutWhy::Dropped => {
            n.push_str("given up: conversation dropped (more than ");
            push_u64(n, pairing::MAX_CONVERSATIONS as u64);
            n.push_str(" at once)");
        }
        TimeoutWhy::Overflow => {
            n.push_str("given up: more than ");
            push_u64(n, pairing::MAX_OUTSTANDING as u64);
            n.push_str(" requests waiting");
        }
    });
}

fn ack_text(sc: &mut Scratch, code: u16, short: Option<(u8, bool)>) -> &'static str {
    match short {
        Some((ch, two)) => {
            sc.data.push_str(if ch == telegram::ACK_CHAR {
                "ACK"
            } else {
                "NAK"
            });
            if two {
                sc.note("sent as 2 bytes (character + 00)");
            }
        }
        None => {
            sc.data.push_str(commands::ack_nak_name(code));
            sc.data.push_str(" (0x");
            let mut b = [0u8; 2];
            b.copy_from_slice(&code.to_be_bytes());
            for x in b {
                const HEX: &[u8; 16] = b"0123456789ABCDEF";
                sc.data.push(HEX[(x >> 4) as usize] as char);
                sc.data.push(HEX[(x & 15) as usize] as char);
            }
            sc.data.push(')');
        }
    }
    if code == 0 { "ACK" } else { "NAK" }
}

// ---------------------------------------------------------------------------------------------
// Serial decoder
// ---------------------------------------------------------------------------------------------

enum Framer {
    /// Auto mode before the decision: the bytes so far and a trial data-mode framer.
    Detect {
        segments: Vec<(Vec<u8>, Option<u64>)>,
        len: usize,
        trial: Box<DataFramer>,
        trial_break: Box<BreakFramer>,
        /// CRC-valid telegrams found by each reading: data mode, break mode.
        counts: [u32; 2],
        decided: Option<bool>,
    },
    Data(Box<DataFramer>),
    Break(Box<BreakFramer>),
}

/// What the serial decoder settled on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resolved {
    Data,
    Break,
    Parity,
}

/// The serial S-Bus decoder (data, secure, break and parity modes).
pub struct SerialDecoder {
    opts: Options,
    framer: Framer,
    core: SerialCore,
}

struct SerialCore {
    secure_mode: bool,
    bits: u32,
    baud: u32,
    names: Vec<Option<String>>,
    pairing: SerialPairing,
    per: Vec<StationStats>,
    totals: Totals,
    sc: Scratch,
    /// Scratch for Timeout rows, written while `sc` holds the current row.
    tsc: Scratch,
    resolved: Option<Resolved>,
    timeout_override: Option<u64>,
    last_micros: u64,
}

impl SerialDecoder {
    pub fn new(opts: Options) -> Self {
        let gap = |bits| {
            Some(
                opts.gap_ms
                    .map_or(default_gap_us(opts.baud, bits), |g| g * 1000),
            )
        };
        let timeout = |data_mode| {
            Some(
                opts.timeout_ms
                    .map_or(default_timeout_ms(opts.baud, data_mode), |t| t)
                    * 1000,
            )
        };
        let framer = match opts.mode {
            Mode::Auto => Framer::Detect {
                segments: Vec::new(),
                len: 0,
                trial: Box::new(DataFramer::new(gap(10))),
                trial_break: Box::new(BreakFramer::new(false, gap(10), timeout(false))),
                counts: [0, 0],
                decided: None,
            },
            Mode::Data | Mode::Secure => Framer::Data(Box::new(DataFramer::new(gap(10)))),
            Mode::Break => {
                Framer::Break(Box::new(BreakFramer::new(false, gap(10), timeout(false))))
            }
            Mode::Parity => {
                Framer::Break(Box::new(BreakFramer::new(true, gap(11), timeout(false))))
            }
        };
        let mut names = vec![None; 256];
        for (n, a) in &opts.stations {
            names[*a as usize] = Some(n.clone());
        }
        let mut core = SerialCore {
            secure_mode: opts.mode == Mode::Secure,
            bits: 10,
            baud: opts.baud.max(1),
            names,
            pairing: SerialPairing::new(0),
            per: vec![StationStats::default(); 256],
            totals: Totals::default(),
            sc: Scratch::default(),
            tsc: Scratch::default(),
            resolved: None,
            timeout_override: opts.timeout_ms.map(|t| t * 1000),
            last_micros: 0,
        };
        match opts.mode {
            Mode::Data | Mode::Secure => core.resolve(Resolved::Data),
            Mode::Break => core.resolve(Resolved::Break),
            Mode::Parity => core.resolve(Resolved::Parity),
            Mode::Auto => {}
        }
        SerialDecoder { opts, framer, core }
    }

    /// The mode in use (`None` while auto mode is still looking).
    pub fn resolved(&self) -> Option<Resolved> {
        self.core.resolved
    }

    pub fn totals(&self) -> &Totals {
        &self.core.totals
    }

    pub fn station_stats(&self, station: u8) -> &StationStats {
        &self.core.per[station as usize]
    }

    fn settle(&mut self, data_mode: bool, out: &mut dyn RowOut) -> RowResult {
        let Framer::Detect { segments, .. } = &mut self.framer else {
            return Ok(());
        };
        let segments = std::mem::take(segments);
        let gap = Some(
            self.opts
                .gap_ms
                .map_or(default_gap_us(self.opts.baud, 10), |g| g * 1000),
        );
        if data_mode {
            self.framer = Framer::Data(Box::new(DataFramer::new(gap)));
            self.core.resolve(Resolved::Data);
        } else {
            self.core.resolve(Resolved::Break);
            let timeout = Some(self.core.pairing.timeout);
            self.framer = Framer::Break(Box::new(BreakFramer::new(false, gap, timeout)));
        }
        for (bytes, time) in segments {
            self.feed(&bytes, time, out)?;
        }
        Ok(())
    }

    fn feed(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let core = &mut self.core;
        let mut latch = Latch::new(out);
        let mut emit = |ev: &Event<'_>| {
            let _ = core.event(ev, &mut latch);
        };
        match &mut self.framer {
            Framer::Data(f) => f.push(data, time, &mut emit),
            Framer::Break(f) => f.push(data, time, &mut emit),
            Framer::Detect { .. } => unreachable!("feed after settle"),
        }
        latch.result()
    }
}

impl SerialCore {
    fn resolve(&mut self, r: Resolved) {
        self.resolved = Some(r);
        self.bits = if r == Resolved::Parity { 11 } else { 10 };
        let timeout = self
            .timeout_override
            .unwrap_or(default_timeout_ms(self.baud, r == Resolved::Data) * 1000);
        self.pairing.timeout = timeout;
    }

    fn micros(&self, time: Option<u64>, offset: u64) -> u64 {
        time.unwrap_or_else(|| {
            (offset as u128 * self.bits as u128 * 1_000_000 / self.baud as u128) as u64
        })
    }

    fn device(&self, station: Option<u8>) -> &str {
        match station.and_then(|s| self.names[s as usize].as_deref()) {
            Some(n) => n,
            None => "PCD",
        }
    }

    fn event(&mut self, ev: &Event<'_>, out: &mut dyn RowOut) -> RowResult {
        match ev {
            Event::Frame(f) => self.frame(f, out),
            Event::Garbage(g) => {
                let t = self.micros(g.time, g.offset);
                self.expire(t, out)?;
                self.last_micros = t;
                self.totals.garbage_bytes += g.bytes.len() as u64;
                self.totals.garbage_runs += 1;
                self.sc.clear();
                push_hex(&mut self.sc.data, g.bytes);
                self.sc.note_with(|n| {
                    push_u64(n, g.bytes.len() as u64);
                    n.push_str(" bytes outside any telegram");
                });
                put_row(
                    out,
                    &self.sc,
                    t,
                    None,
                    "",
                    "Garbage",
                    Class::Error,
                    "",
                    g.bytes,
                )
            }
        }
    }

    fn expire(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        if let Some(p) = self.pairing.expire(now) {
            let at = p.time + self.pairing.timeout;
            self.timeout_row(&p, TimeoutWhy::Deadline, at, out)?;
        }
        Ok(())
    }

    fn timeout_row(
        &mut self,
        p: &Outstanding,
        why: TimeoutWhy,
        at: u64,
        out: &mut dyn RowOut,
    ) -> RowResult {
        self.totals.timeouts += 1;
        self.per[p.info.station as usize].timeouts += 1;
        let sc = &mut self.tsc;
        sc.clear();
        if let Some(e) = p.info.elem {
            telegram::push_elem(&mut sc.sensor_no, e, p.info.block, p.info.addr);
        }
        if let Some(s) = p.seq {
            sc.seq(s);
        }
        timeout_note(sc, why, self.pairing.timeout);
        let device = self.names[p.info.station as usize]
            .as_deref()
            .unwrap_or("PCD");
        put_row(
            out,
            &self.tsc,
            at,
            Some(p.info.station as u32),
            device,
            "Timeout",
            Class::Warning,
            p.info.name(),
            &[],
        )
    }

    fn frame(&mut self, f: &Frame<'_>, out: &mut dyn RowOut) -> RowResult {
        let t = self.micros(f.time, f.offset);
        let timed = f.time.is_some();
        self.expire(t, out)?;
        self.last_micros = t;
        self.sc.clear();
        let seq = f.secure.map(|s| s.seq as u16);
        if let Some(s) = seq {
            self.sc.seq(s);
        }
        // Framing remarks first.
        let mut class = Class::Plain;
        if let Some(s) = f.secure {
            if !s.len_ok() {
                self.sc.note_with(|n| {
                    n.push_str("secure LEN ");
                    push_u64(n, s.len as u64);
                    n.push_str(", telegram has ");
                    push_u64(n, s.actual as u64);
                });
                class = Class::Warning;
            }
            if s.seq_unescaped {
                self.sc
                    .note("SEQ 0xC5 sent without DLE (old firmware, SBC FAQ 101180)");
                class = Class::Warning;
            }
        } else if self.secure_mode && matches!(f.tele, Tele::Request { .. }) {
            self.sc.note("standard request in secure mode");
        }
        if f.break_before {
            self.sc.note("after a break (00)");
        }
        if let Some(p) = f.problem {
            self.sc.note(p);
            class = Class::Error;
        }
        match f.crc {
            CrcCheck::Ok(basis) => {
                if !matches!(f.tele, Tele::Broken) {
                    self.totals.valid += 1;
                }
                if f.wire.first() == Some(&telegram::FS) {
                    let i = match basis {
                        CrcBasis::Escaped => 0,
                        CrcBasis::Unescaped => 1,
                        CrcBasis::Both => 2,
                    };
                    self.totals.basis[i] += 1;
                    if basis != CrcBasis::Both {
                        self.sc.note_with(|n| {
                            n.push_str("CRC over the ");
                            n.push_str(basis.name());
                            n.push_str(" bytes");
                        });
                    }
                }
                self.good_frame(f, t, timed, seq, class, out)
            }
            CrcCheck::Bad {
                got,
                escaped,
                unescaped,
            } => {
                self.totals.crc_errors += 1;
                self.sc.note_with(|n| {
                    let _ = write!(n, "CRC 0x{got:04X}, expected 0x{escaped:04X}");
                    if unescaped != escaped {
                        let _ = write!(n, " (escaped) or 0x{unescaped:04X} (unescaped)");
                    }
                });
                self.bad_frame(f, t, timed, seq, out)
            }
            CrcCheck::None => match f.tele {
                Tele::AckNak { .. } => {
                    self.totals.valid += 1;
                    self.good_frame(f, t, timed, seq, class, out)
                }
                _ => self.truncated_row(f.wire, t, out),
            },
        }
    }

    fn bad_frame(
        &mut self,
        f: &Frame<'_>,
        t: u64,
        timed: bool,
        seq: Option<u16>,
        out: &mut dyn RowOut,
    ) -> RowResult {
        let (id, sensor) = match f.tele {
            Tele::Request { station, cmd, body } => {
                let text = telegram::describe_request(
                    station,
                    cmd,
                    body,
                    &mut self.sc.sensor_no,
                    &mut self.sc.data,
                );
                self.per[station as usize].crc_errors += 1;
                // Keep it as the outstanding request: the slave may have read it correctly.
                let expects = text.info.expect != Expect::Nothing;
                let req = Outstanding::new(text.info, t, timed, seq);
                let (_, prev) = self.pairing_request(station, cmd, body, req, expects);
                if let Some((p, why)) = prev {
                    self.timeout_row(&p, why, t, out)?;
                }
                (Some(station), telegram::command_name(cmd))
            }
            Tele::Response { .. } | Tele::AckNak { .. } => {
                match f.tele {
                    Tele::Response { data } => push_hex(&mut self.sc.data, data),
                    Tele::AckNak { code, .. } => push_hex(&mut self.sc.data, &code.to_be_bytes()),
                    _ => {}
                }
                match self.pairing.pending().copied() {
                    Some(p) => {
                        if let Some(e) = p.info.elem {
                            telegram::push_elem(
                                &mut self.sc.sensor_no,
                                e,
                                p.info.block,
                                p.info.addr,
                            );
                        }
                        self.per[p.info.station as usize].crc_errors += 1;
                        self.pairing.bad_answer();
                        self.sc.note(if matches!(f.tele, Tele::Response { .. }) {
                            "response"
                        } else {
                            "ACK/NAK"
                        });
                        (Some(p.info.station), p.info.name())
                    }
                    None => (None, ""),
                }
            }
            Tele::Other { payload, .. } => {
                push_hex(&mut self.sc.data, payload);
                (None, "")
            }
            Tele::Broken => {
                push_hex(&mut self.sc.data, f.wire);
                (None, "")
            }
        };
        let device = self.device(id);
        put_row(
            out,
            &self.sc,
            t,
            id.map(u32::from),
            device,
            "BadCRC",
            Class::Error,
            sensor,
            f.wire,
        )
    }

    fn good_frame(
        &mut self,
        f: &Frame<'_>,
        t: u64,
        timed: bool,
        seq: Option<u16>,
        mut class: Class,
        out: &mut dyn RowOut,
    ) -> RowResult {
        match f.tele {
            Tele::Request { station, cmd, body } => {
                let text = telegram::describe_request(
                    station,
                    cmd,
                    body,
                    &mut self.sc.sensor_no,
                    &mut self.sc.data,
                );
                let c = request_notes(&mut self.sc, &text);
                if c != Class::Plain && class == Class::Plain {
                    class = c;
                }
                let st = &mut self.per[station as usize];
                st.requests += 1;
                let expects = text.info.expect != Expect::Nothing;
                if !expects {
                    st.broadcasts += 1;
                }
                let req = Outstanding::new(text.info, t, timed, seq);
                let (kind, prev) = self.pairing_request(station, cmd, body, req, expects);
                if let Some((p, why)) = prev {
                    // The Timeout row goes before this request's row.
                    self.timeout_row(&p, why, t, out)?;
                }
                let kind_name = match kind {
                    RequestKind::New => "Request",
                    RequestKind::Retry { n, since } => {
                        self.totals.retries += 1;
                        self.per[station as usize].retries += 1;
                        self.sc.note_with(|s| {
                            s.push_str("retry ");
                            push_u64(s, n as u64);
                            if timed {
                                s.push_str(", ");
                                push_fixed(s, (since as i64 + 50) / 100, 1);
                                s.push_str(" ms after the first");
                            }
                        });
                        if class == Class::Plain {
                            class = Class::Warning;
                        }
                        "Retry"
                    }
                };
                let device = self.device(Some(station));
                put_row(
                    out,
                    &self.sc,
                    t,
                    Some(station as u32),
                    device,
                    kind_name,
                    class,
                    telegram::command_name(cmd),
                    f.wire,
                )
            }
            Tele::Response { data } => {
                let answer = self.pairing.answer(t, seq);
                let (id, sensor) = self.answer_common(&answer, timed, &mut class);
                match answer {
                    Answer::Paired { req, .. } => {
                        self.per[req.info.station as usize].responses += 1;
                        if !response_text(&mut self.sc, &req.info, data) {
                            self.totals.mismatched += 1;
                            self.per[req.info.station as usize].mismatched += 1;
                            class = Class::Warning;
                        }
                        if f.length_mismatch {
                            self.sc.note("found by its CRC");
                        }
                    }
                    _ => push_hex(&mut self.sc.data, data),
                }
                let device = self.device(id);
                put_row(
                    out,
                    &self.sc,
                    t,
                    id.map(u32::from),
                    device,
                    "Response",
                    class,
                    sensor,
                    f.wire,
                )
            }
            Tele::AckNak { code, short } => {
                let answer = self.pairing.answer(t, seq);
                let (id, sensor) = self.answer_common(&answer, timed, &mut class);
                let kind = ack_text(&mut self.sc, code, short);
                if let Answer::Paired { req, .. } = answer {
                    if let Some(e) = req.info.elem {
                        telegram::push_elem(
                            &mut self.sc.sensor_no,
                            e,
                            req.info.block,
                            req.info.addr,
                        );
                    }
                    let st = &mut self.per[req.info.station as usize];
                    if code == 0 {
                        st.acks += 1;
                        if req.info.expect != Expect::AckNak {
                            self.sc.note("ACK to a request that expects data");
                            class = Class::Warning;
                        }
                    } else {
                        st.naks[nak_slot(code, short.is_some())] += 1;
                    }
                }
                if code != 0 {
                    self.totals.naks += 1;
                    if class == Class::Plain {
                        class = Class::Warning;
                    }
                }
                let device = self.device(id);
                put_row(
                    out,
                    &self.sc,
                    t,
                    id.map(u32::from),
                    device,
                    kind,
                    class,
                    sensor,
                    f.wire,
                )
            }
            Tele::Other { at, payload } => {
                push_hex(&mut self.sc.data, payload);
                self.sc.note_with(|n| {
                    let _ = write!(n, "unknown attribute 0x{at:02X}");
                });
                put_row(
                    out,
                    &self.sc,
                    t,
                    None,
                    "",
                    "Unknown",
                    Class::Warning,
                    "",
                    f.wire,
                )
            }
            Tele::Broken => self.truncated_row(f.wire, t, out),
        }
    }

    /// A telegram cut short (or otherwise broken): its bytes, counted.
    fn truncated_row(&mut self, wire: &[u8], t: u64, out: &mut dyn RowOut) -> RowResult {
        self.totals.broken += 1;
        push_hex(&mut self.sc.data, wire);
        put_row(
            out,
            &self.sc,
            t,
            None,
            "",
            "Truncated",
            Class::Error,
            "",
            wire,
        )
    }

    fn pairing_request(
        &mut self,
        station: u8,
        cmd: u8,
        body: &[u8],
        req: Outstanding,
        expects: bool,
    ) -> (RequestKind, Option<(Outstanding, TimeoutWhy)>) {
        let mut key = std::mem::take(&mut self.sc.raw);
        key.clear();
        key.push(station);
        key.push(cmd);
        key.extend_from_slice(body);
        let r = self.pairing.request(&key, req, expects);
        self.sc.raw = key;
        r
    }

    /// Response time, late and unpaired notes for an answer; returns its station and the
    /// command name of its request.
    fn answer_common(
        &mut self,
        answer: &Answer,
        timed: bool,
        class: &mut Class,
    ) -> (Option<u8>, &'static str) {
        match *answer {
            Answer::Paired { req, elapsed, late } => {
                let st = &mut self.per[req.info.station as usize];
                if timed {
                    st.time(elapsed);
                    self.sc.resp_time(elapsed);
                }
                if late {
                    st.late += 1;
                    self.totals.late += 1;
                    self.sc.note_with(|n| {
                        n.push_str("late: after the ");
                        push_u64(n, self.pairing.timeout / 1000);
                        n.push_str(" ms timeout");
                    });
                    *class = Class::Warning;
                }
                (Some(req.info.station), req.info.name())
            }
            Answer::SeqMismatch { req } => {
                self.totals.no_request += 1;
                self.sc.note_with(|n| {
                    n.push_str("SEQ does not match the pending request's SEQ ");
                    push_u64(n, req.seq.unwrap_or(0) as u64);
                    n.push_str(" (a stale answer)");
                });
                *class = Class::Warning;
                (None, "")
            }
            Answer::NoRequest => {
                self.totals.no_request += 1;
                self.sc.note("no request");
                *class = Class::Warning;
                (None, "")
            }
        }
    }

    fn finish(&mut self) {
        // A request still waiting at the end: its answer may simply not have been captured,
        // so it is counted, not reported as a timeout.
        if self.pairing.finish().is_some() {
            self.totals.unanswered_at_end += 1;
        }
    }
}

/// Auto mode settles early when one reading clearly wins: at least 4 valid telegrams and
/// more than twice as many as the other reading. `Some(true)` = data mode.
fn early_decision(counts: [u32; 2]) -> Option<bool> {
    let [d, b] = counts;
    if d >= 4 && d > 2 * b {
        Some(true)
    } else if b >= 4 && b > 2 * d {
        Some(false)
    } else {
        None
    }
}

/// After [`DETECT_BYTES`] or at the end: the reading with more valid telegrams (data mode on a
/// tie with at least one).
fn late_decision(counts: [u32; 2]) -> bool {
    counts[0] > 0 && counts[0] >= counts[1]
}

impl Decoder for SerialDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        if let Framer::Detect {
            segments,
            len,
            trial,
            trial_break,
            counts,
            decided,
        } = &mut self.framer
        {
            // Both readings are tried byte by byte so that the decision does not depend on
            // how the input is chunked.
            let take = data.len().min(DETECT_BYTES - *len);
            for &b in &data[..take] {
                let mut hit = [0u32; 2];
                trial.push(&[b], time, &mut |ev| {
                    if let Event::Frame(f) = ev
                        && f.crc.ok()
                    {
                        hit[0] += 1;
                    }
                });
                trial_break.push(&[b], time, &mut |ev| {
                    if let Event::Frame(f) = ev
                        && f.crc.ok()
                        && matches!(f.tele, Tele::Request { .. } | Tele::Response { .. })
                    {
                        hit[1] += 1;
                    }
                });
                counts[0] += hit[0];
                counts[1] += hit[1];
                if decided.is_none() {
                    *decided = early_decision(*counts);
                }
                if decided.is_some() {
                    break;
                }
            }
            segments.push((data.to_vec(), time));
            *len += take;
            if let Some(d) = *decided {
                return self.settle(d, out);
            }
            if *len >= DETECT_BYTES {
                let d = late_decision(*counts);
                return self.settle(d, out);
            }
            return Ok(());
        }
        self.feed(data, time, out)
    }

    fn idle(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        // Auto mode on a live line that went quiet after a few telegrams: decide with what was
        // seen rather than wait for more.
        if let Framer::Detect {
            trial,
            trial_break,
            counts,
            ..
        } = &mut self.framer
        {
            let mut hit = [0u32; 2];
            trial.idle(now, &mut |ev| {
                if let Event::Frame(f) = ev
                    && f.crc.ok()
                {
                    hit[0] += 1;
                }
            });
            trial_break.idle(now, &mut |ev| {
                if let Event::Frame(f) = ev
                    && f.crc.ok()
                    && matches!(f.tele, Tele::Request { .. } | Tele::Response { .. })
                {
                    hit[1] += 1;
                }
            });
            counts[0] += hit[0];
            counts[1] += hit[1];
            if counts[0] + counts[1] == 0 {
                return Ok(());
            }
            let d = late_decision(*counts);
            self.settle(d, out)?;
        }
        let core = &mut self.core;
        let mut latch = Latch::new(out);
        let mut emit = |ev: &Event<'_>| {
            let _ = core.event(ev, &mut latch);
        };
        match &mut self.framer {
            Framer::Data(f) => f.idle(now, &mut emit),
            Framer::Break(f) => f.idle(now, &mut emit),
            Framer::Detect { .. } => {}
        }
        latch.result()?;
        self.core.expire(now, out)
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        if let Framer::Detect {
            trial,
            trial_break,
            counts,
            decided,
            ..
        } = &mut self.framer
        {
            let d = match *decided {
                Some(d) => d,
                None => {
                    let mut hit = [0u32; 2];
                    trial.finish(&mut |ev| {
                        if let Event::Frame(f) = ev
                            && f.crc.ok()
                        {
                            hit[0] += 1;
                        }
                    });
                    trial_break.finish(&mut |ev| {
                        if let Event::Frame(f) = ev
                            && f.crc.ok()
                            && matches!(f.tele, Tele::Request { .. } | Tele::Response { .. })
                        {
                            hit[1] += 1;
                        }
                    });
                    late_decision([counts[0] + hit[0], counts[1] + hit[1]])
                }
            };
            self.settle(d, out)?;
        }
        let core = &mut self.core;
        let mut latch = Latch::new(out);
        let mut emit = |ev: &Event<'_>| {
            let _ = core.event(ev, &mut latch);
        };
        match &mut self.framer {
            Framer::Data(f) => f.finish(&mut emit),
            Framer::Break(f) => f.finish(&mut emit),
            Framer::Detect { .. } => {}
        }
        latch.result()?;
        self.core.finish();
        Ok(())
    }

    fn valid_frames(&self) -> u64 {
        self.core.totals.valid
    }

    fn stats(&self) -> String {
        let c = &self.core;
        let mut rows = Vec::new();
        for (i, st) in c.per.iter().enumerate() {
            if st.seen() {
                rows.push((i.to_string(), c.device(Some(i as u8)).to_owned(), st));
            }
        }
        let mode = match c.resolved {
            Some(Resolved::Data) => "data mode",
            Some(Resolved::Break) => "break mode",
            Some(Resolved::Parity) => "parity mode",
            None => "mode not detected",
        };
        format!(
            "{mode}, master timeout {} ms\n{}{}",
            c.pairing.timeout / 1000,
            stats_table(&rows, false),
            totals_line(&c.totals, false)
        )
    }

    fn problems(&self) -> Option<String> {
        problems_line(&self.core.totals)
    }

    fn no_frames_hint(&self) -> &'static str {
        "check the baud rate (S-Bus ports default to 9600) and the mode (--mode data|break|parity)"
    }
}

// ---------------------------------------------------------------------------------------------
// Ether-S-Bus decoder
// ---------------------------------------------------------------------------------------------

struct Plc {
    name: String,
    stats: StationStats,
}

/// The Ether-S-Bus decoder: pcap/pcapng bytes in, rows out.
pub struct EtherDecoder {
    pcap: PcapStream,
    core: EtherCore,
}

struct EtherCore {
    port: u16,
    first_ts: Option<i64>,
    /// Conversations are keyed by (client, server); their tag is the PLC's index.
    pairing: EtherPairing<(SocketAddr, SocketAddr)>,
    /// At most [`MAX_PLCS`] + 1 (the last one: every other PLC).
    plcs: Vec<Plc>,
    plc_index: pairing::FastMap<SocketAddr, usize>,
    /// PLCs beyond [`MAX_PLCS`] (at most [`MERGED_PLCS_KEPT`], to count them once).
    merged: pairing::FastMap<SocketAddr, ()>,
    /// The Device column for a PLC beyond [`MAX_PLCS`].
    device: String,
    totals: Totals,
    sc: Scratch,
    expired: Vec<Expired>,
    last_micros: u64,
    /// Packets whose link type is a serial recording: reported once.
    serial_link_noted: bool,
    failed: bool,
}

impl EtherDecoder {
    pub fn new(opts: &Options) -> Self {
        EtherDecoder {
            pcap: PcapStream::new(),
            core: EtherCore {
                port: opts.port,
                first_ts: None,
                pairing: EtherPairing::new(
                    opts.timeout_ms.unwrap_or(DEFAULT_ETHER_TIMEOUT_MS) * 1000,
                ),
                plcs: Vec::new(),
                plc_index: pairing::FastMap::default(),
                merged: pairing::FastMap::default(),
                device: String::new(),
                totals: Totals::default(),
                sc: Scratch::default(),
                expired: Vec::new(),
                last_micros: 0,
                serial_link_noted: false,
                failed: false,
            },
        }
    }

    pub fn totals(&self) -> &Totals {
        &self.core.totals
    }

    /// Sizes of the decoder's tables (for tests of the bounds).
    #[doc(hidden)]
    pub fn table_sizes(&self) -> TableSizes {
        TableSizes {
            plcs: self.core.plcs.len(),
            ..self.core.pairing.sizes()
        }
    }

    /// (PLC name, statistics) for every PLC seen.
    pub fn plc_stats(&self) -> impl Iterator<Item = (&str, &StationStats)> {
        self.core.plcs.iter().map(|p| (p.name.as_str(), &p.stats))
    }

    fn pcap_failed(&mut self, e: PcapError, out: &mut dyn RowOut) -> RowResult {
        let c = &mut self.core;
        c.failed = true;
        c.totals.pcap_error = Some(e.to_string());
        c.sc.clear();
        c.sc.note(&e.to_string());
        put_row(
            out,
            &c.sc,
            c.last_micros,
            None,
            "",
            "Truncated",
            Class::Error,
            "",
            &[],
        )
    }
}

impl EtherCore {
    fn plc(&mut self, addr: SocketAddr) -> usize {
        if let Some(&i) = self.plc_index.get(&addr) {
            return i;
        }
        if self.plc_index.len() < MAX_PLCS {
            let i = self.plcs.len();
            self.plcs.push(Plc {
                name: addr.to_string(),
                stats: StationStats::default(),
            });
            self.plc_index.insert(addr, i);
            return i;
        }
        // Every further PLC shares one statistics row.
        if self.plcs.len() == MAX_PLCS {
            self.plcs.push(Plc {
                name: String::new(),
                stats: StationStats::default(),
            });
        }
        let new = if self.merged.len() < MERGED_PLCS_KEPT {
            self.merged.insert(addr, ()).is_none()
        } else {
            !self.merged.contains_key(&addr)
        };
        if new {
            self.totals.plcs_merged += 1;
            let other = &mut self.plcs[MAX_PLCS].name;
            other.clear();
            let _ = write!(other, "other PLCs ({})", self.totals.plcs_merged);
        }
        MAX_PLCS
    }

    /// The Device column for PLC `plc` (`server`: the name of a PLC beyond [`MAX_PLCS`]).
    fn device<'a>(&'a self, plc: usize, server: &'a str) -> &'a str {
        if plc < MAX_PLCS {
            &self.plcs[plc].name
        } else {
            server
        }
    }

    /// The conversation of `client` and `server` at `t`: its id and PLC. The open request of a
    /// conversation dropped to make room gets its Timeout row here.
    fn conv(
        &mut self,
        client: SocketAddr,
        server: SocketAddr,
        t: u64,
        out: &mut dyn RowOut,
    ) -> Result<(u32, usize), crate::row::OutputError> {
        let mut expired = std::mem::take(&mut self.expired);
        let mut fresh = false;
        let (conv, tag) = self.pairing.conversation(
            (client, server),
            t,
            || {
                fresh = true;
                u32::MAX
            },
            &mut expired,
        );
        let plc = if fresh {
            let i = self.plc(server);
            self.pairing.set_tag((client, server), i as u32);
            i
        } else {
            tag as usize
        };
        let r = self.timeout_rows(&expired, out);
        expired.clear();
        self.expired = expired;
        r.map(|_| (conv, plc))
    }

    fn timeout_rows(&mut self, expired: &[Expired], out: &mut dyn RowOut) -> RowResult {
        for e in expired {
            self.timeout_row(&e.req, e.why, e.at, out)?;
        }
        Ok(())
    }

    fn sync_forgotten(&mut self) {
        let f = self.pairing.forgotten;
        let t = &mut self.totals;
        t.conversations = f.conversations;
        t.conversations_expired = f.expired;
        t.conversations_dropped = f.dropped;
        t.requests_dropped = f.requests;
    }

    fn packet(&mut self, p: crate::pcap::Packet<'_>, out: &mut dyn RowOut) -> RowResult {
        self.totals.packets += 1;
        let first = *self.first_ts.get_or_insert_with(|| {
            if let Some(t) = chrono::DateTime::from_timestamp_micros(p.ts_micros) {
                out.anchor(crate::time::Anchor::Instant(t));
            }
            p.ts_micros
        });
        let t = p.ts_micros.saturating_sub(first).max(0) as u64;
        self.expire(t, out)?;
        self.last_micros = t;
        match ether::extract(p.link_type, p.data) {
            ether::Extract::Udp(u) => {
                if u.src.port() != self.port && u.dst.port() != self.port {
                    return Ok(());
                }
                self.datagram(u, t, out)
            }
            ether::Extract::Fragment { src, dst, ports } => {
                self.totals.fragments += 1;
                match ports {
                    Some((sp, dp)) if sp == self.port || dp == self.port => {
                        self.sc.clear();
                        self.sc.note_with(|n| {
                            let _ = write!(
                                n,
                                "fragmented IP datagram {src}:{sp} -> {dst}:{dp} skipped (not reassembled)"
                            );
                        });
                        put_row(
                            out,
                            &self.sc,
                            t,
                            None,
                            "",
                            "Fragment",
                            Class::Warning,
                            "",
                            &[],
                        )
                    }
                    _ => Ok(()),
                }
            }
            ether::Extract::Other => Ok(()),
            ether::Extract::Malformed => {
                self.totals.malformed += 1;
                Ok(())
            }
            ether::Extract::UnsupportedLink(lt) => {
                self.totals.other_links += 1;
                if !self.serial_link_noted {
                    self.serial_link_noted = true;
                    self.sc.clear();
                    self.sc.note_with(|n| {
                        let _ = write!(
                            n,
                            "packets with link type {lt} are not network traffic; busnoop sbus reads Ethernet, Linux cooked, raw IP and loopback captures"
                        );
                    });
                    return put_row(
                        out,
                        &self.sc,
                        t,
                        None,
                        "",
                        "Skipped",
                        Class::Warning,
                        "",
                        &[],
                    );
                }
                Ok(())
            }
        }
    }

    fn expire(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        let mut expired = std::mem::take(&mut self.expired);
        self.pairing.expire(now, &mut expired);
        let r = self.timeout_rows(&expired, out);
        expired.clear();
        self.expired = expired;
        r
    }

    fn timeout_row(
        &mut self,
        p: &Outstanding,
        why: TimeoutWhy,
        at: u64,
        out: &mut dyn RowOut,
    ) -> RowResult {
        self.totals.timeouts += 1;
        let plc = p.tag as usize;
        self.sc.clear();
        if let Some(e) = p.info.elem {
            telegram::push_elem(&mut self.sc.sensor_no, e, p.info.block, p.info.addr);
        }
        if let Some(s) = p.seq {
            self.sc.seq(s);
        }
        timeout_note(&mut self.sc, why, self.pairing.timeout);
        let name = match self.plcs.get_mut(plc) {
            Some(pl) => {
                pl.stats.timeouts += 1;
                pl.name.as_str()
            }
            None => "",
        };
        put_row(
            out,
            &self.sc,
            at,
            Some(p.info.station as u32),
            name,
            "Timeout",
            Class::Warning,
            p.info.name(),
            &[],
        )
    }

    fn datagram(&mut self, u: ether::Udp<'_>, t: u64, out: &mut dyn RowOut) -> RowResult {
        self.sc.clear();
        let tele = match ether::parse(u.payload) {
            Ok(tele) => tele,
            Err(why) => {
                self.totals.not_sbus += 1;
                let kind = match why {
                    ether::NotSbus::Truncated { .. } => {
                        self.totals.broken += 1;
                        "Truncated"
                    }
                    _ => "Garbage",
                };
                push_hex(&mut self.sc.data, u.payload);
                self.sc.note_with(|n| {
                    n.push_str(why.text());
                    let _ = write!(n, " ({} -> {})", u.src, u.dst);
                });
                return put_row(
                    out,
                    &self.sc,
                    t,
                    None,
                    "",
                    kind,
                    Class::Error,
                    "",
                    u.payload,
                );
            }
        };
        self.totals.datagrams += 1;
        self.sc.seq(tele.seq);
        let mut class = Class::Plain;
        if tele.version != 0 || tele.proto != 0 {
            self.sc.note_with(|n| {
                let _ = write!(n, "version {}, protocol type {}", tele.version, tele.proto);
            });
        }
        // The PLC is the server: the destination of a request, the source of an answer.
        let (client, server) = if tele.at == telegram::AT_REQUEST {
            (u.src, u.dst)
        } else {
            (u.dst, u.src)
        };
        let (conv, plc) = self.conv(client, server, t, out)?;
        if plc >= MAX_PLCS {
            self.device.clear();
            let _ = write!(self.device, "{server}");
        }
        if !tele.crc_ok() {
            self.totals.crc_errors += 1;
            self.plcs[plc].stats.crc_errors += 1;
            if tele.at != telegram::AT_REQUEST {
                // The client got an unusable answer: it retries; no Timeout row.
                self.pairing.bad_answer(conv, tele.seq);
            }
            self.sc.note_with(|n| {
                let _ = write!(
                    n,
                    "CRC 0x{:04X}, expected 0x{:04X}",
                    tele.crc_got, tele.crc_want
                );
            });
            let (id, sensor) = match tele.at {
                telegram::AT_REQUEST if tele.telegram.len() >= 2 => {
                    let tg = tele.telegram;
                    telegram::describe_request(
                        tg[0],
                        tg[1],
                        &tg[2..],
                        &mut self.sc.sensor_no,
                        &mut self.sc.data,
                    );
                    (Some(tg[0] as u32), telegram::command_name(tg[1]))
                }
                _ => {
                    push_hex(&mut self.sc.data, tele.telegram);
                    (None, "")
                }
            };
            return put_row(
                out,
                &self.sc,
                t,
                id,
                self.device(plc, &self.device),
                "BadCRC",
                Class::Error,
                sensor,
                u.payload,
            );
        }
        let broken = match tele.at {
            telegram::AT_REQUEST => tele.telegram.len() < 2,
            telegram::AT_ACKNAK => tele.telegram.len() != 2,
            _ => false,
        };
        if !broken {
            self.totals.valid += 1;
        }
        match tele.at {
            telegram::AT_REQUEST => {
                if tele.telegram.len() < 2 {
                    self.totals.broken += 1;
                    push_hex(&mut self.sc.data, tele.telegram);
                    self.sc.note("request without station and command");
                    return put_row(
                        out,
                        &self.sc,
                        t,
                        None,
                        self.device(plc, &self.device),
                        "Truncated",
                        Class::Error,
                        "",
                        u.payload,
                    );
                }
                let tg = tele.telegram;
                let (station, cmd) = (tg[0], tg[1]);
                let text = telegram::describe_request(
                    station,
                    cmd,
                    &tg[2..],
                    &mut self.sc.sensor_no,
                    &mut self.sc.data,
                );
                let c = request_notes(&mut self.sc, &text);
                if c != Class::Plain {
                    class = c;
                }
                let info = text.info;
                let st = &mut self.plcs[plc].stats;
                st.requests += 1;
                if info.expect == Expect::Nothing {
                    st.broadcasts += 1;
                }
                let mut req = Outstanding::new(info, t, true, Some(tele.seq));
                req.tag = plc as u32;
                let mut expired = std::mem::take(&mut self.expired);
                let (kind, gap) = self.pairing.request(conv, tele.seq, req, &mut expired);
                let r = self.timeout_rows(&expired, out);
                expired.clear();
                self.expired = expired;
                r?;
                if let Some(g) = gap {
                    let st = &mut self.plcs[plc].stats;
                    st.seq_gaps += 1;
                    self.totals.seq_gaps += 1;
                    match g.missing {
                        Some(m) => {
                            st.seq_missing += m as u64;
                            self.sc.note_with(|n| {
                                n.push_str("sequence gap: ");
                                push_u64(n, m as u64);
                                n.push_str(" skipped");
                            });
                        }
                        None => self.sc.note("sequence went backwards (client restart?)"),
                    }
                }
                let kind_name = match kind {
                    RequestKind::New => "Request",
                    RequestKind::Retry { n, since } => {
                        self.totals.retries += 1;
                        self.plcs[plc].stats.retries += 1;
                        self.sc.note_with(|s| {
                            s.push_str("retry ");
                            push_u64(s, n as u64);
                            s.push_str(", ");
                            push_fixed(s, (since as i64 + 50) / 100, 1);
                            s.push_str(" ms after the first");
                        });
                        if class == Class::Plain {
                            class = Class::Warning;
                        }
                        "Retry"
                    }
                };
                put_row(
                    out,
                    &self.sc,
                    t,
                    Some(station as u32),
                    self.device(plc, &self.device),
                    kind_name,
                    class,
                    telegram::command_name(cmd),
                    u.payload,
                )
            }
            at => {
                let answer = self.pairing.answer(conv, tele.seq, t);
                let (id, sensor) = match answer {
                    Answer::Paired { req, elapsed, late } => {
                        let st = &mut self.plcs[plc].stats;
                        st.time(elapsed);
                        self.sc.resp_time(elapsed);
                        if late {
                            st.late += 1;
                            self.totals.late += 1;
                            self.sc.note_with(|n| {
                                n.push_str("late: after the ");
                                push_u64(n, self.pairing.timeout / 1000);
                                n.push_str(" ms timeout");
                            });
                            class = Class::Warning;
                        }
                        (Some(req), req.info.name())
                    }
                    _ => {
                        self.totals.no_request += 1;
                        self.sc.note("no request");
                        class = Class::Warning;
                        (None, "")
                    }
                };
                let info = id.map(|r| r.info);
                let kind = if at == telegram::AT_RESPONSE {
                    let st = &mut self.plcs[plc].stats;
                    match info {
                        Some(i) => {
                            st.responses += 1;
                            if !response_text(&mut self.sc, &i, tele.telegram) {
                                self.totals.mismatched += 1;
                                self.plcs[plc].stats.mismatched += 1;
                                class = Class::Warning;
                            }
                        }
                        None => push_hex(&mut self.sc.data, tele.telegram),
                    }
                    "Response"
                } else if tele.telegram.len() == 2 {
                    let code = u16::from_be_bytes([tele.telegram[0], tele.telegram[1]]);
                    let kind = ack_text(&mut self.sc, code, None);
                    if let Some(i) = info {
                        if let Some(e) = i.elem {
                            telegram::push_elem(&mut self.sc.sensor_no, e, i.block, i.addr);
                        }
                        let st = &mut self.plcs[plc].stats;
                        if code == 0 {
                            st.acks += 1;
                        } else {
                            st.naks[nak_slot(code, false)] += 1;
                        }
                    }
                    if code != 0 {
                        self.totals.naks += 1;
                        if class == Class::Plain {
                            class = Class::Warning;
                        }
                    }
                    kind
                } else {
                    self.totals.broken += 1;
                    push_hex(&mut self.sc.data, tele.telegram);
                    self.sc.note("ACK/NAK telegram without a 2-byte code");
                    class = Class::Error;
                    "Truncated"
                };
                put_row(
                    out,
                    &self.sc,
                    t,
                    info.map(|i| i.station as u32),
                    self.device(plc, &self.device),
                    kind,
                    class,
                    sensor,
                    u.payload,
                )
            }
        }
    }
}

impl Decoder for EtherDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], _time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        if self.core.failed {
            return Ok(());
        }
        let core = &mut self.core;
        let mut latch = Latch::new(out);
        let r = self.pcap.push(data, &mut |p| {
            let _ = core.packet(p, &mut latch);
        });
        core.sync_forgotten();
        latch.result()?;
        if let Err(e) = r {
            self.pcap_failed(e, out)?;
        }
        Ok(())
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        if !self.core.failed
            && let Err(e) = self.pcap.finish()
        {
            self.pcap_failed(e, out)?;
        }
        let c = &mut self.core;
        c.totals.unanswered_at_end += c.pairing.finish();
        c.sync_forgotten();
        Ok(())
    }

    fn valid_frames(&self) -> u64 {
        self.core.totals.valid
    }

    fn stats(&self) -> String {
        let c = &self.core;
        let rows: Vec<(String, String, &StationStats)> = c
            .plcs
            .iter()
            .map(|p| (String::from("-"), p.name.clone(), &p.stats))
            .collect();
        format!(
            "Ether-S-Bus on UDP port {}, timeout {} ms\n{}{}",
            c.port,
            c.pairing.timeout / 1000,
            stats_table(&rows, true),
            totals_line(&c.totals, true)
        )
    }

    fn problems(&self) -> Option<String> {
        problems_line(&self.core.totals)
    }

    fn no_frames_hint(&self) -> &'static str {
        "no Ether-S-Bus datagram yet: check the UDP port (--udp-port) and the tcpdump filter"
    }
}

#[cfg(test)]
mod tests;
