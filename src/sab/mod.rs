//! modm SAB and SAB2 (Sensor Actuator Bus): both framings, auto-detection, request/response
//! pairing, the log table mapping and statistics.
//!
//! * [`sync`]: SAB v1 framing `54 LEN HDR CMD DATA CRC8` (backtracking reassembler).
//! * [`hdlc`]: SAB2 framing `7E HDR CMD DATA CRC16 7E` as modm's code sends it.
//! * [`detect`]: which of the two is on the line.
//! * [`header`]: flags, address, NACK codes; [`pairing`]: responses to requests, timeouts.
//!
//! The table mapping, the timing rules and the options are documented in `docs/sab.md`.

pub mod args;
pub mod detect;
pub mod frame;
pub mod hdlc;
pub mod header;
pub mod pairing;
pub mod sample;
pub mod stats;
pub mod sync;

use std::io;

use crate::decoder::{Decoder, RowOut};
use crate::fmt::{push_fixed, push_hex, push_i64, push_u64};
use crate::row::{Class, Row};
pub use args::SabArgs;
use detect::{Held, Reason};
use frame::{Event, EventKind, Framing};
use header::{ADDRESSES, Flags, NackCode};
use pairing::{Answer, Expired, Lateness, Pairing, Why};
use stats::Stats;

/// SAB runs at 115200 baud 8N1.
pub const DEFAULT_BAUD: u32 = 115_200;

/// What the shared command-line code needs to know about SAB.
pub const PROTOCOL: crate::cli::Protocol = crate::cli::Protocol {
    name: "SAB",
    serial: crate::source::serial::SerialConfig {
        baud: DEFAULT_BAUD,
        data_bits: serialport::DataBits::Eight,
        parity: serialport::Parity::None,
        stop_bits: serialport::StopBits::One,
        lines: crate::source::serial::ModemLines::Low,
    },
};

/// modm's `sab::Master` waits 10 ms for a response.
pub const DEFAULT_TIMEOUT_MS: u64 = 10;
/// Bits per byte on the wire (8N1: start, 8 data, stop), for time reconstruction.
pub const BITS_PER_BYTE: u64 = 10;
/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Addr", "Resp ms", "Framing", "Note"];
/// Payload bytes shown at most in the Data column of an overlong frame.
const OVERLONG_DATA_MAX: usize = 64;

/// `--framing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FramingChoice {
    /// Detect the framing from the stream (and say which one was chosen).
    Auto,
    /// SAB v1: `54 LEN HDR CMD DATA CRC8` (what modm's documentation describes).
    #[value(alias = "sab1", alias = "v1")]
    Sync,
    /// SAB2: `7E HDR CMD DATA CRC16 7E`, byte-stuffed (what modm's SAB2 code sends).
    #[value(alias = "sab2")]
    Hdlc,
}

/// Decoder settings.
#[derive(Clone, Debug)]
pub struct Options {
    pub framing: FramingChoice,
    /// Baud rate, used to reconstruct time for sources without time.
    pub baud: u32,
    /// Master timeout in µs.
    pub timeout_micros: u64,
    /// SAB2 payload limit (modm's template parameter `N`).
    pub max_payload: usize,
    /// `(name, address)` pairs for the Device column.
    pub devices: Vec<(String, u8)>,
    /// `(name, command)` pairs for the Sensor column.
    pub commands: Vec<(String, u8)>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            framing: FramingChoice::Auto,
            baud: DEFAULT_BAUD,
            timeout_micros: DEFAULT_TIMEOUT_MS * 1000,
            max_payload: hdlc::DEFAULT_MAX_PAYLOAD,
            devices: Vec::new(),
            commands: Vec::new(),
        }
    }
}

/// Appends a byte as two upper-case hex digits.
pub(crate) fn push_hex_u8(out: &mut String, b: u8) {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    out.push(HEX[(b >> 4) as usize] as char);
    out.push(HEX[(b & 0x0F) as usize] as char);
}

/// Appends `0xNN`.
fn push_0x(out: &mut String, b: u8) {
    out.push_str("0x");
    push_hex_u8(out, b);
}

/// Appends `0xNNNN`.
fn push_0x16(out: &mut String, v: u16) {
    out.push_str("0x");
    let [hi, lo] = v.to_be_bytes();
    push_hex_u8(out, hi);
    push_hex_u8(out, lo);
}

/// Appends µs as milliseconds with three decimals.
fn push_ms(out: &mut String, micros: u64) {
    push_fixed(out, micros.min(i64::MAX as u64) as i64, 3);
}

/// Appends a duration in ms without useless decimals (`10`, `2.5`).
fn push_ms_short(out: &mut String, micros: u64) {
    if micros.is_multiple_of(1000) {
        push_u64(out, micros / 1000);
    } else {
        push_ms(out, micros);
        while out.ends_with('0') {
            out.pop();
        }
    }
}

/// Appends the payload in hex plus its little-endian integer reading for 1, 2 or 4 bytes
/// (`AA BA (47786)`; with the signed reading when the top bit is set: `FF FF (65535, -1)`).
pub fn push_payload(out: &mut String, payload: &[u8]) {
    push_hex(out, payload);
    let (unsigned, signed) = match *payload {
        [a] => (a as u64, a as i8 as i64),
        [a, b] => {
            let v = u16::from_le_bytes([a, b]);
            (v as u64, v as i16 as i64)
        }
        [a, b, c, d] => {
            let v = u32::from_le_bytes([a, b, c, d]);
            (v as u64, v as i32 as i64)
        }
        _ => return,
    };
    out.push_str(" (");
    push_u64(out, unsigned);
    if signed < 0 {
        out.push_str(", ");
        push_i64(out, signed);
    }
    out.push(')');
}

/// Names from `--device` and `--command`.
#[derive(Clone, Debug)]
struct Names {
    devices: Vec<String>,
    commands: Vec<String>,
}

impl Names {
    fn new(opts: &Options) -> Self {
        let mut devices = vec![String::new(); ADDRESSES];
        let mut commands = vec![String::new(); 256];
        for (name, addr) in &opts.devices {
            if let Some(slot) = devices.get_mut(*addr as usize) {
                slot.clone_from(name);
            }
        }
        for (name, code) in &opts.commands {
            commands[*code as usize].clone_from(name);
        }
        Names { devices, commands }
    }

    fn device(&self, addr: u8) -> &str {
        self.devices.get(addr as usize).map_or("", String::as_str)
    }

    fn command(&self, code: u8) -> &str {
        &self.commands[code as usize]
    }
}

/// Scratch buffers reused for every row.
#[derive(Default)]
struct Scratch {
    sensor_no: String,
    data: String,
    addr: String,
    resp: String,
    note: String,
}

impl Scratch {
    fn clear(&mut self) {
        self.sensor_no.clear();
        self.data.clear();
        self.addr.clear();
        self.resp.clear();
        self.note.clear();
    }

    /// Starts a new part of the note.
    fn note(&mut self) -> &mut String {
        if !self.note.is_empty() {
            self.note.push_str("; ");
        }
        &mut self.note
    }
}

/// What a row is made of besides the scratch strings.
struct RowParts<'a> {
    micros: u64,
    id: Option<u8>,
    /// Command for Sensor # and Sensor.
    command: Option<u8>,
    kind: &'a str,
    class: Class,
    framing: Framing,
    raw: &'a [u8],
}

/// Maps events onto rows, pairs requests with responses, keeps the statistics.
struct Mapper {
    baud: u32,
    max_payload: usize,
    names: Names,
    pairing: Pairing,
    stats: Stats,
    scratch: Scratch,
    /// Said on the next row: how the framing was chosen.
    framing_note: Option<String>,
    /// First output error; later rows are dropped.
    error: Option<io::Error>,
}

impl Mapper {
    fn new(opts: &Options) -> Self {
        Mapper {
            baud: opts.baud.max(1),
            max_payload: opts.max_payload,
            names: Names::new(opts),
            pairing: Pairing::new(opts.timeout_micros.saturating_mul(1000)),
            stats: Stats::default(),
            scratch: Scratch::default(),
            framing_note: None,
            error: None,
        }
    }

    // Pairing runs in nanoseconds so that reconstructed times (86.8 µs per byte at 115200
    // baud) give the same response time for the same exchange wherever it is in the capture;
    // rows show µs.

    /// Time of stream offset `pos` reconstructed from the baud rate (ns).
    fn nanos_at(&self, pos: u64) -> u64 {
        let ns = pos as u128 * BITS_PER_BYTE as u128 * 1_000_000_000 / self.baud as u128;
        ns.min(u64::MAX as u128) as u64
    }

    fn start_ns(&self, ev: &Event<'_>) -> u64 {
        match ev.start_time {
            Some(us) => us.saturating_mul(1000),
            None => self.nanos_at(ev.start_pos),
        }
    }

    fn end_ns(&self, ev: &Event<'_>) -> u64 {
        match ev.end_time {
            Some(us) => us.saturating_mul(1000),
            None => self.nanos_at(ev.end_pos),
        }
    }

    fn chosen(&mut self, framing: Framing, reason: Reason) {
        let mut note = String::new();
        reason.describe(framing, &mut note);
        self.framing_note = Some(note);
        self.stats.framings.push((framing, reason));
    }

    fn take_error(&mut self) -> io::Result<()> {
        match self.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn put(&mut self, p: RowParts<'_>, out: &mut dyn RowOut) {
        if self.error.is_some() {
            return;
        }
        let sc = &mut self.scratch;
        if let Some(n) = self.framing_note.take() {
            if sc.note.is_empty() {
                sc.note = n;
            } else {
                sc.note.insert_str(0, "; ");
                sc.note.insert_str(0, &n);
            }
        }
        let device = match p.id {
            Some(a) => {
                sc.addr.clear();
                push_0x(&mut sc.addr, a);
                self.names.device(a)
            }
            None => "",
        };
        sc.sensor_no.clear();
        let sensor = match p.command {
            Some(c) => {
                push_0x(&mut sc.sensor_no, c);
                self.names.command(c)
            }
            None => "",
        };
        let extra = [
            sc.addr.as_str(),
            sc.resp.as_str(),
            p.framing.name(),
            sc.note.as_str(),
        ];
        let row = Row {
            micros: Some(p.micros),
            id: p.id.map(u32::from),
            device,
            kind: p.kind,
            class: p.class,
            sensor_no: &sc.sensor_no,
            sensor,
            data: &sc.data,
            extra: &extra,
            raw: p.raw,
        };
        if let Err(e) = out.row(&row) {
            self.error = Some(e);
        }
    }

    fn timeout_row(&mut self, x: &Expired, framing: Framing, out: &mut dyn RowOut) {
        let r = x.request;
        self.stats.timeouts += 1;
        self.stats.per[r.address as usize].timeouts += 1;
        let sc = &mut self.scratch;
        sc.clear();
        let n = sc.note();
        match x.why {
            Why::Deadline => {
                n.push_str("no response within ");
                push_ms_short(n, self.pairing.timeout() / 1000);
                n.push_str(" ms");
            }
            Why::NextRequest => {
                n.push_str("no response before the next request (after ");
                push_ms(n, x.waited / 1000);
                n.push_str(" ms)");
            }
            Why::EndOfCapture => {
                n.push_str("no response before the end of the capture (after ");
                push_ms(n, x.waited / 1000);
                n.push_str(" ms)");
            }
        }
        self.put(
            RowParts {
                micros: x.at / 1000,
                id: Some(r.address),
                command: Some(r.command),
                kind: "Timeout",
                class: Class::Warning,
                framing,
                raw: &[],
            },
            out,
        );
    }

    /// Handles one event of the active reassembler.
    fn event(&mut self, ev: &Event<'_>, out: &mut dyn RowOut) {
        let start = self.start_ns(ev);
        if let Some(x) = self.pairing.advance(start) {
            self.timeout_row(&x, ev.framing, out);
        }
        match ev.kind {
            EventKind::Frame => self.frame(ev, start, out),
            EventKind::BadCrc => self.bad_crc(ev, start / 1000, out),
            _ => self.broken(ev, start / 1000, out),
        }
    }

    /// A valid frame; `start` in ns.
    fn frame(&mut self, ev: &Event<'_>, start: u64, out: &mut dyn RowOut) {
        let (Some(header), Some(command)) = (ev.header(), ev.command()) else {
            return self.broken(ev, start / 1000, out);
        };
        let flags = Flags::of(header);
        let addr = header::address(header);
        let payload = ev.payload();
        let st = &mut self.stats;
        st.valid_frames += 1;
        let mut class = Class::Plain;
        let mut answer = None;
        if flags.is_response() {
            // A late response's Timeout row comes once the time passes the deadline.
            answer = Some(self.pairing.response(addr, command, self.end_ns(ev)));
        } else if let Some(x) = self.pairing.request(pairing::Request {
            address: addr,
            command,
            start,
        }) {
            self.timeout_row(&x, ev.framing, out);
        }

        let st = &mut self.stats;
        let per = &mut st.per[addr as usize];
        let sc = &mut self.scratch;
        sc.clear();
        push_payload(&mut sc.data, payload);
        match flags {
            Flags::Request => per.requests += 1,
            Flags::Reserved => {
                per.reserved += 1;
                class = Class::Warning;
                sc.note()
                    .push_str("reserved flag bits 01 (never sent by modm; handled as a request)");
            }
            Flags::Ack => per.acks += 1,
            Flags::Nack => {
                class = Class::Warning;
                st.nacks += 1;
                let n = sc.note();
                match payload.first() {
                    Some(&code) => {
                        per.nack(code);
                        n.push_str("NACK ");
                        NackCode::of(code).push_description(n);
                        if payload.len() > 1 {
                            n.push_str("; ");
                            push_u64(n, payload.len() as u64);
                            n.push_str(" payload bytes (modm sends 1)");
                        }
                    }
                    None => {
                        per.nacks += 1;
                        n.push_str("NACK without an error code (modm sends 1 byte)");
                    }
                }
            }
        }
        match answer {
            Some(Answer::Paired {
                request,
                micros,
                late,
                repeat,
                ..
            }) => {
                let micros = micros / 1000;
                push_ms(&mut sc.resp, micros);
                if repeat {
                    st.repeats += 1;
                    per.repeats += 1;
                    class = Class::Warning;
                    sc.note().push_str(
                        "repeated response to the same request (two slaves on one address?)",
                    );
                } else {
                    per.times.add(micros);
                }
                match late {
                    Lateness::OnTime => {}
                    Lateness::AfterTimeout => {
                        st.late += 1;
                        per.late += 1;
                        class = Class::Warning;
                        let n = sc.note();
                        n.push_str("late: after the master's ");
                        push_ms_short(n, self.pairing.timeout() / 1000);
                        n.push_str(" ms timeout");
                    }
                    Lateness::AfterNextRequest => {
                        st.late += 1;
                        per.late += 1;
                        class = Class::Warning;
                        let n = sc.note();
                        n.push_str("late: after the master's next request (request at ");
                        push_ms(n, request.start / 1000);
                        n.push_str(" ms)");
                    }
                }
            }
            Some(Answer::Unpaired { open }) => {
                st.unpaired += 1;
                per.unpaired += 1;
                class = Class::Warning;
                let n = sc.note();
                n.push_str("no matching request");
                if let Some(o) = open {
                    n.push_str(" (the master waits for address ");
                    push_u64(n, o.address as u64);
                    n.push_str(" command ");
                    push_0x(n, o.command);
                    n.push(')');
                }
            }
            None => {}
        }
        if ev.framing == Framing::Hdlc && payload.len() > self.max_payload {
            st.overlong += 1;
            class = Class::Warning;
            let n = sc.note();
            n.push_str("overlong: ");
            push_u64(n, payload.len() as u64);
            n.push_str("-byte payload, more than --max-payload ");
            push_u64(n, self.max_payload as u64);
            n.push_str(" (a modm receiver with N = ");
            push_u64(n, self.max_payload as u64);
            n.push_str(" drops it)");
        }
        if ev.odd_escapes > 0 {
            st.odd_escapes += ev.odd_escapes as u64;
            if class == Class::Plain {
                class = Class::Warning;
            }
            sc.note().push_str(
                "unusual escape (0x7D not followed by 0x5E or 0x5D), decoded as modm does",
            );
        }
        self.put(
            RowParts {
                micros: start / 1000,
                id: Some(addr),
                command: Some(command),
                kind: flags.type_name(),
                class,
                framing: ev.framing,
                raw: ev.wire,
            },
            out,
        );
    }

    fn bad_crc(&mut self, ev: &Event<'_>, start: u64, out: &mut dyn RowOut) {
        let st = &mut self.stats;
        st.bad_crc += 1;
        let sc = &mut self.scratch;
        sc.clear();
        let addr = ev.address();
        if let Some(a) = addr {
            st.per[a as usize].bad_crc += 1;
        }
        push_payload(&mut sc.data, ev.payload());
        let n = sc.note();
        if let Some((received, computed)) = ev.crc {
            match ev.framing {
                Framing::Sync => {
                    n.push_str("CRC-8 ");
                    push_0x(n, received as u8);
                    n.push_str(", expected ");
                    push_0x(n, computed as u8);
                }
                Framing::Hdlc => {
                    n.push_str("CRC-16 ");
                    push_0x16(n, received);
                    n.push_str(", expected ");
                    push_0x16(n, computed);
                }
            }
        }
        if let Some(flags) = ev.flags() {
            n.push_str("; read as ");
            n.push_str(flags.type_name());
        }
        if ev.crc_with_sync {
            n.push_str("; the CRC matches if SYNC is covered too (not modm's rule)");
        }
        if ev.odd_escapes > 0 {
            st.odd_escapes += ev.odd_escapes as u64;
            n.push_str("; unusual escape");
        }
        self.put(
            RowParts {
                micros: start,
                id: addr,
                command: ev.command(),
                kind: "BadCRC",
                class: Class::Error,
                framing: ev.framing,
                raw: ev.wire,
            },
            out,
        );
    }

    /// Garbage, truncated frames, runts, aborts, overlong frames.
    fn broken(&mut self, ev: &Event<'_>, start: u64, out: &mut dyn RowOut) {
        let st = &mut self.stats;
        let sc = &mut self.scratch;
        sc.clear();
        let mut id = None;
        let mut command = None;
        let kind = match ev.kind {
            EventKind::Garbage => {
                st.garbage_bytes += ev.wire.len() as u64;
                st.garbage_runs += 1;
                st.false_syncs += ev.false_syncs as u64;
                st.bad_lengths += ev.bad_lengths as u64;
                push_hex(&mut sc.data, ev.wire);
                let n = sc.note();
                push_u64(n, ev.wire.len() as u64);
                n.push_str(if ev.wire.len() == 1 {
                    " byte"
                } else {
                    " bytes"
                });
                n.push_str(match (ev.before_first, ev.framing) {
                    (true, Framing::Hdlc) => " before the first 0x7E",
                    (true, Framing::Sync) => " before the first frame",
                    (false, _) => " between frames",
                });
                if ev.false_syncs > 0 {
                    n.push_str("; ");
                    push_u64(n, ev.false_syncs as u64);
                    n.push_str(" false 0x54 (the frame it announced overlapped a valid frame)");
                }
                if ev.bad_lengths > 0 {
                    n.push_str("; ");
                    push_u64(n, ev.bad_lengths as u64);
                    n.push_str(" 0x54 followed by a LENGTH above 32");
                }
                "Garbage"
            }
            EventKind::Truncated => {
                st.truncated += 1;
                id = ev.address();
                command = ev.command();
                push_hex(&mut sc.data, ev.wire);
                let n = sc.note();
                n.push_str("the input ended inside a frame after ");
                push_u64(n, ev.wire_len);
                n.push_str(" bytes");
                if let (Framing::Sync, Some(len)) = (ev.framing, ev.length_byte) {
                    n.push_str(" of ");
                    push_u64(n, len as u64 + sync::OVERHEAD as u64);
                }
                "Truncated"
            }
            EventKind::Runt => {
                st.runts += 1;
                push_hex(&mut sc.data, ev.body);
                let n = sc.note();
                push_u64(n, ev.body_len);
                n.push_str(if ev.body_len == 1 {
                    " byte between flags"
                } else {
                    " bytes between flags"
                });
                n.push_str(" (a frame has at least 4), ignored by modm");
                "Runt"
            }
            EventKind::Abort => {
                st.aborts += 1;
                push_hex(&mut sc.data, ev.body);
                let n = sc.note();
                n.push_str("0x7D 0x7E: escape followed by a flag, frame aborted after ");
                push_u64(n, ev.body_len);
                n.push_str(if ev.body_len == 1 { " byte" } else { " bytes" });
                "Abort"
            }
            EventKind::Overlong => {
                st.overlong += 1;
                id = ev.address();
                command = ev.command();
                let shown = ev.body.len().min(OVERLONG_DATA_MAX);
                push_hex(&mut sc.data, &ev.body[..shown]);
                if shown < ev.body.len() || (ev.body.len() as u64) < ev.body_len {
                    sc.data.push_str(" …");
                }
                let n = sc.note();
                push_u64(n, ev.body_len);
                n.push_str(" bytes between flags, more than the ");
                push_u64(n, (self.max_payload + hdlc::OVERHEAD) as u64);
                n.push_str(" of a ");
                push_u64(n, self.max_payload as u64);
                n.push_str("-byte payload");
                if ev.body_len > hdlc::STORE_MAX as u64 {
                    n.push_str(" (too long to check)");
                } else {
                    n.push_str(", CRC fails");
                }
                "Overlong"
            }
            EventKind::Frame | EventKind::BadCrc => {
                // Only reached for a frame too short to have a command (cannot happen).
                push_hex(&mut sc.data, ev.wire);
                "Garbage"
            }
        };
        self.put(
            RowParts {
                micros: start,
                id,
                command,
                kind,
                class: Class::Error,
                framing: ev.framing,
                raw: ev.wire,
            },
            out,
        );
    }

    /// End of the capture at `now` (ns).
    fn finish(&mut self, now: u64, framing: Framing, out: &mut dyn RowOut) {
        if let Some(x) = self.pairing.finish(now) {
            self.timeout_row(&x, framing, out);
        }
    }
}

/// One byte into a reassembler (lets the detection loops be monomorphised per framing pair).
trait Stepper {
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>));
}

impl Stepper for sync::Reassembler {
    #[inline]
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.step(b, time, emit);
    }
}

impl Stepper for hdlc::Reassembler {
    #[inline]
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.step(b, time, emit);
    }
}

impl Stepper for Reasm {
    #[inline]
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.step(b, time, emit);
    }
}

/// Feeds `data` to the active reassembler (rows) and the background one (counting its valid
/// frames since the active one's last). Returns the number of bytes consumed when a byte makes
/// the background framing win (busnoop switches after that byte), `None` when all were fed.
#[allow(clippy::too_many_arguments)]
fn shadowed<A: Stepper, S: Stepper>(
    active: &mut A,
    shadow: &mut S,
    since: &mut u64,
    last: &mut Option<frame::OwnedEvent>,
    map: &mut Mapper,
    data: &[u8],
    time: Option<u64>,
    out: &mut dyn RowOut,
) -> Option<usize> {
    for (i, &b) in data.iter().enumerate() {
        let mut active_valid = false;
        active.step_byte(b, time, &mut |e| {
            active_valid |= e.is_valid();
            map.event(e, out);
        });
        if active_valid {
            *since = 0;
        }
        shadow.step_byte(b, time, &mut |e| {
            if e.is_valid() {
                *since += 1;
                match last {
                    Some(l) => l.set_from(e),
                    None => *last = Some(frame::OwnedEvent::from(e)),
                }
            }
        });
        if *since >= detect::SWITCH_FRAMES {
            return Some(i + 1);
        }
    }
    None
}

/// A reassembler of either framing.
#[derive(Clone, Debug)]
enum Reasm {
    Sync(sync::Reassembler),
    Hdlc(hdlc::Reassembler),
}

impl Reasm {
    fn new(framing: Framing, max_payload: usize) -> Self {
        match framing {
            Framing::Sync => Reasm::Sync(sync::Reassembler::new()),
            Framing::Hdlc => Reasm::Hdlc(hdlc::Reassembler::new(max_payload)),
        }
    }

    fn framing(&self) -> Framing {
        match self {
            Reasm::Sync(_) => Framing::Sync,
            Reasm::Hdlc(_) => Framing::Hdlc,
        }
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.push(data, time, emit),
            Reasm::Hdlc(r) => r.push(data, time, emit),
        }
    }

    #[inline]
    fn step(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.step(b, time, emit),
            Reasm::Hdlc(r) => r.step(b, time, emit),
        }
    }

    fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.finish(emit),
            Reasm::Hdlc(r) => r.finish(emit),
        }
    }

    fn reset(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.reset(emit),
            Reasm::Hdlc(r) => r.reset(emit),
        }
    }

    fn flush_garbage(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.flush_garbage(emit),
            Reasm::Hdlc(r) => r.flush_garbage(emit),
        }
    }
}

/// Detection in progress.
#[derive(Clone, Debug)]
struct Undecided {
    sync: sync::Reassembler,
    hdlc: hdlc::Reassembler,
    sync_valid: u64,
    hdlc_valid: u64,
    held: Held,
}

/// The other framing's reassembler, read in the background after the choice.
#[derive(Clone, Debug)]
struct Shadow {
    reasm: Reasm,
    /// Its valid frames since the active reassembler's last valid frame.
    since: u64,
    /// Its last valid frame (the one that makes busnoop switch is shown).
    last: Option<frame::OwnedEvent>,
}

enum Mode {
    Undecided(Box<Undecided>),
    Locked {
        active: Box<Reasm>,
        shadow: Option<Box<Shadow>>,
    },
}

/// The SAB decoder: framing detection + reassembly + table mapping + statistics.
pub struct SabDecoder {
    max_payload: usize,
    mode: Mode,
    map: Mapper,
    /// Bytes pushed so far.
    pos: u64,
    /// The last source time seen.
    last_time: Option<u64>,
}

impl SabDecoder {
    pub fn new(opts: Options) -> Self {
        let mut map = Mapper::new(&opts);
        let mode = match opts.framing {
            FramingChoice::Auto => Mode::Undecided(Box::new(Undecided {
                sync: sync::Reassembler::new(),
                hdlc: hdlc::Reassembler::new(opts.max_payload),
                sync_valid: 0,
                hdlc_valid: 0,
                held: Held::default(),
            })),
            FramingChoice::Sync | FramingChoice::Hdlc => {
                let framing = if opts.framing == FramingChoice::Sync {
                    Framing::Sync
                } else {
                    Framing::Hdlc
                };
                map.chosen(framing, Reason::Forced);
                Mode::Locked {
                    active: Box::new(Reasm::new(framing, opts.max_payload)),
                    shadow: None,
                }
            }
        };
        SabDecoder {
            max_payload: opts.max_payload,
            mode,
            map,
            pos: 0,
            last_time: None,
        }
    }

    /// The framing in use, once chosen.
    pub fn framing(&self) -> Option<Framing> {
        match &self.mode {
            Mode::Undecided(_) => None,
            Mode::Locked { active, .. } => Some(active.framing()),
        }
    }

    /// The counters (tests, tools).
    pub fn counters(&self) -> &Stats {
        &self.map.stats
    }

    /// The capture's current time in ns: the last source time, or the reconstructed time of
    /// the bytes read so far.
    fn now_ns(&self) -> u64 {
        match self.last_time {
            Some(us) => us.saturating_mul(1000),
            None => self.map.nanos_at(self.pos),
        }
    }

    /// Feeds one byte while detection is undecided.
    fn step(&mut self, b: u8, time: Option<u64>, out: &mut dyn RowOut) {
        self.pos += 1;
        match &mut self.mode {
            Mode::Undecided(u) => {
                u.held.push(b, time);
                let (sv, hv) = (&mut u.sync_valid, &mut u.hdlc_valid);
                u.sync.step(b, time, &mut |e| *sv += e.is_valid() as u64);
                u.hdlc.step(b, time, &mut |e| *hv += e.is_valid() as u64);
                let (s, h) = (u.sync_valid, u.hdlc_valid);
                let decision = match detect::lock(s, h) {
                    Some(f) => Some((f, Reason::Locked { sync: s, hdlc: h })),
                    None if u.held.len() >= detect::HOLD_BYTES => Some((
                        detect::majority(s, h),
                        Reason::HoldFull { sync: s, hdlc: h },
                    )),
                    None => None,
                };
                if let Some((f, reason)) = decision {
                    self.decide(f, reason, out);
                }
            }
            Mode::Locked { .. } => {}
        }
    }

    /// Feeds `data` to the chosen and the background reassembler; switches framing when the
    /// background one wins (see [`detect`]).
    fn push_shadowed(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) {
        let mut rest = data;
        while !rest.is_empty() {
            let Mode::Locked {
                active,
                shadow: Some(sh),
            } = &mut self.mode
            else {
                return;
            };
            let map = &mut self.map;
            let (since, last) = (&mut sh.since, &mut sh.last);
            let switched = match (active.as_mut(), &mut sh.reasm) {
                (Reasm::Sync(a), Reasm::Hdlc(s)) => {
                    shadowed(a, s, since, last, map, rest, time, out)
                }
                (Reasm::Hdlc(a), Reasm::Sync(s)) => {
                    shadowed(a, s, since, last, map, rest, time, out)
                }
                (a, s) => shadowed(a, s, since, last, map, rest, time, out),
            };
            let Some(n) = switched else {
                self.pos += rest.len() as u64;
                return;
            };
            self.pos += n as u64;
            rest = &rest[n..];
            // The old framing's unfinished frame held the bytes of the new framing's last
            // frame: forget it and show that frame instead.
            active.reset(&mut |e| map.event(e, out));
            std::mem::swap(active.as_mut(), &mut sh.reasm);
            sh.since = 0;
            map.chosen(active.framing(), Reason::Switched { at: self.pos });
            if let Some(l) = &sh.last {
                map.event(&l.as_event(), out);
            }
        }
    }

    /// Ends detection: replays the held bytes through the chosen framing.
    fn decide(&mut self, framing: Framing, reason: Reason, out: &mut dyn RowOut) {
        let mut active = Reasm::new(framing, self.max_payload);
        let placeholder = Mode::Locked {
            active: Box::new(Reasm::new(framing, self.max_payload)),
            shadow: None,
        };
        let u = match std::mem::replace(&mut self.mode, placeholder) {
            Mode::Undecided(u) => u,
            locked => {
                self.mode = locked;
                return;
            }
        };
        let map = &mut self.map;
        map.chosen(framing, reason);
        for seg in u.held.segments() {
            active.push(seg.bytes, seg.time, &mut |e| map.event(e, out));
        }
        let Undecided { sync, hdlc, .. } = *u;
        let other = match framing {
            Framing::Sync => Reasm::Hdlc(hdlc),
            Framing::Hdlc => Reasm::Sync(sync),
        };
        self.mode = Mode::Locked {
            active: Box::new(active),
            shadow: Some(Box::new(Shadow {
                reasm: other,
                since: 0,
                last: None,
            })),
        };
    }
}

impl Decoder for SabDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> io::Result<()> {
        if time.is_some() {
            self.last_time = time;
        }
        self.map.stats.bytes += data.len() as u64;
        match &mut self.mode {
            Mode::Locked {
                active,
                shadow: None,
            } => {
                let map = &mut self.map;
                active.push(data, time, &mut |e| map.event(e, out));
                self.pos += data.len() as u64;
            }
            Mode::Locked { .. } => self.push_shadowed(data, time, out),
            Mode::Undecided(_) => {
                for (i, &b) in data.iter().enumerate() {
                    self.step(b, time, out);
                    if !matches!(self.mode, Mode::Undecided(_)) {
                        // Decided: the rest goes the fast way.
                        self.push_shadowed(&data[i + 1..], time, out);
                        break;
                    }
                }
            }
        }
        self.map.take_error()
    }

    fn idle(&mut self, now: u64, out: &mut dyn RowOut) -> io::Result<()> {
        if let Mode::Undecided(u) = &self.mode
            && !u.held.is_empty()
            && u.held
                .first_time()
                .is_some_and(|t| now.saturating_sub(t) >= detect::HOLD_MICROS)
        {
            let (s, h) = (u.sync_valid, u.hdlc_valid);
            self.decide(
                detect::majority(s, h),
                Reason::Quiet { sync: s, hdlc: h },
                out,
            );
        }
        if let Mode::Locked { active, .. } = &mut self.mode {
            let map = &mut self.map;
            let framing = active.framing();
            active.flush_garbage(&mut |e| map.event(e, out));
            if let Some(x) = map.pairing.advance(now.saturating_mul(1000)) {
                map.timeout_row(&x, framing, out);
            }
        }
        self.map.take_error()
    }

    /// End of the input, or a gap in a live capture (the driver calls `push` again after a
    /// gap): decides the framing if still undecided, closes what is open, and reports the
    /// request still waiting for a response. Decoding goes on with the next `push`.
    fn finish(&mut self, out: &mut dyn RowOut) -> io::Result<()> {
        if let Mode::Undecided(u) = &self.mode {
            let (s, h) = (u.sync_valid, u.hdlc_valid);
            if self.pos == 0 {
                return self.map.take_error();
            }
            self.decide(
                detect::majority(s, h),
                Reason::EndOfInput { sync: s, hdlc: h },
                out,
            );
        }
        let now = self.now_ns();
        if let Mode::Locked { active, shadow } = &mut self.mode {
            let map = &mut self.map;
            let framing = active.framing();
            active.finish(&mut |e| map.event(e, out));
            map.finish(now, framing, out);
            if let Some(sh) = shadow {
                sh.reasm.reset(&mut |_| {});
                sh.since = 0;
            }
        }
        self.map.take_error()
    }

    fn valid_frames(&self) -> u64 {
        match &self.mode {
            Mode::Undecided(u) => u.sync_valid.max(u.hdlc_valid),
            Mode::Locked { .. } => self.map.stats.valid_frames,
        }
    }

    fn stats(&self) -> String {
        let names = &self.map.names;
        let mut s = self.map.stats.report(|a| names.device(a).to_owned());
        if let Mode::Undecided(u) = &self.mode {
            s.insert_str(
                0,
                &format!(
                    "framing: undecided ({} valid SAB v1 and {} valid SAB2 frames so far)\n",
                    u.sync_valid, u.hdlc_valid
                ),
            );
        }
        s
    }

    fn problems(&self) -> Option<String> {
        self.map.stats.problems()
    }

    fn no_frames_hint(&self) -> &'static str {
        "check the baud rate (modm SAB runs at 115200 8N1, normal levels) and the tap: on a CAN \
         transceiver bus read the RXD pin of a recessive transceiver, on a TTL bus tap master TX \
         and the slaves' combined TX (see docs/sab.md)"
    }
}

#[cfg(test)]
mod tests;
