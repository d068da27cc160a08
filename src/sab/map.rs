//! The table mapping: reassembler events in, rows out. Pairs requests with responses, writes
//! the notes and keeps the statistics (`docs/sab.md` documents the columns and notes).

use super::config::{BITS_PER_BYTE, Options};
use super::detect::Reason;
use super::frame::{Event, EventKind, Framing};
use super::header::{self, Flags, NackCode};
use super::names::Names;
use super::pairing::{self, Answer, Expired, Lateness, Pairing, Why};
use super::stats::Stats;
use super::values::{Reading, Values};
use super::{hdlc, sync};
use crate::fmt::{hex_0x, push_0x, push_0x16, push_hex, push_ms, push_ms_short, push_u64};
use std::ops::Range;

use super::config::COLUMNS;
use crate::row::{Class, Part, Row};
use crate::row::{Latch, RowOut};

mod direct;
mod text;

use direct::{FrameRow, ScratchRow, TimeoutRow};
pub use text::push_payload;
#[cfg(test)]
use text::push_reading;
use text::{push_data, push_ms3};

/// Payload bytes shown at most in the Data column of an overlong frame.
const OVERLONG_DATA_MAX: usize = 64;

/// Scratch buffers reused for every row.
#[derive(Default)]
struct Scratch {
    data: String,
    resp: String,
    note: String,
    /// The row's number: its text (a declared reading's), or where it stands in `data` (the
    /// default reading's, written once).
    value: String,
    value_at: Option<Range<usize>>,
    /// The number's value, command and direction (ACK or request) when the row carries one;
    /// its name and unit are the command's ([`Names::part`], [`Values::declared`]).
    number: Option<(f64, u8, bool)>,
}

impl Scratch {
    fn clear(&mut self) {
        self.data.clear();
        self.resp.clear();
        self.note.clear();
        self.value.clear();
        self.value_at = None;
        self.number = None;
    }

    /// Starts a new part of the note.
    fn note(&mut self) -> &mut String {
        crate::row::note_part(&mut self.note)
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
    /// The row's stamp (`Row::stamp`), 0 for none: its ID, Device, Type, Sensor # and Sensor
    /// cells follow from the address, the command and the Type (the names are fixed for a
    /// run).
    stamp: u32,
}

/// Maps events onto rows, pairs requests with responses, keeps the statistics.
pub(super) struct Mapper {
    baud: u32,
    max_payload: usize,
    pub(super) names: Names,
    values: Values,
    pub(super) pairing: Pairing,
    pub(super) stats: Stats,
    scratch: Scratch,
    /// Said on the next row: how the framing was chosen.
    framing_note: Option<String>,
}

impl Mapper {
    pub(super) fn new(opts: &Options) -> Self {
        Mapper {
            baud: opts.baud.max(1),
            max_payload: opts.max_payload,
            names: Names::new(opts),
            values: Values::new(&opts.values),
            pairing: Pairing::new(opts.timeout_micros.saturating_mul(1000)),
            stats: Stats::default(),
            scratch: Scratch::default(),
            framing_note: None,
        }
    }

    // Pairing runs in nanoseconds so that reconstructed times (86.8 µs per byte at 115200
    // baud) give the same response time for the same exchange wherever it is in the capture;
    // rows show µs.

    /// Time of stream offset `pos` reconstructed from the baud rate (ns).
    pub(super) fn nanos_at(&self, pos: u64) -> u64 {
        const NS_PER_BIT_BYTE: u64 = BITS_PER_BYTE * 1_000_000_000;
        match pos.checked_mul(NS_PER_BIT_BYTE) {
            // The same quotient in 64 bits (the usual case: below 1.8 GB into the stream);
            // SAB's own baud rate as a constant divisor (a multiplication, not a division:
            // two per frame).
            Some(n) if self.baud == super::config::DEFAULT_BAUD => {
                n / super::config::DEFAULT_BAUD as u64
            }
            Some(n) => n / self.baud as u64,
            None => {
                let ns = pos as u128 * NS_PER_BIT_BYTE as u128 / self.baud as u128;
                ns.min(u64::MAX as u128) as u64
            }
        }
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

    pub(super) fn chosen(&mut self, framing: Framing, reason: Reason) {
        let mut note = String::new();
        reason.describe(framing, &mut note);
        self.framing_note = Some(note);
        self.stats.chose(framing, reason);
    }

    /// The note on how the framing was chosen, when not said yet: in front of the row's note.
    #[inline(always)]
    fn take_framing_note(&mut self) {
        if let Some(n) = self.framing_note.take() {
            let sc = &mut self.scratch;
            if sc.note.is_empty() {
                sc.note = n;
            } else {
                sc.note.insert_str(0, "; ");
                sc.note.insert_str(0, &n);
            }
        }
    }

    /// Writes one row; `out` is the decoder's [`Latch`], which keeps a write error. The
    /// mapper takes the latch by its type, not as a `dyn RowOut`: its check is inlined here
    /// and only the table's write remains a dynamic call.
    #[inline(always)]
    fn put(&mut self, p: RowParts<'_>, out: &mut Latch<'_>) {
        self.take_framing_note();
        let sc = &mut self.scratch;
        let (addr, device) = match p.id {
            Some(a) => (hex_0x(a), self.names.device(a)),
            None => ("", ""),
        };
        let (sensor_no, sensor) = match p.command {
            Some(c) => (hex_0x(c), self.names.command(c)),
            None => ("", ""),
        };
        let part;
        let mut unit = "";
        let parts: &[Part<'_>] = match sc.number {
            Some((value, command, ack)) => {
                if let Some(d) = self.values.declared(command, ack) {
                    unit = &d.unit;
                }
                part = [Part {
                    name: self.names.part(command, ack),
                    unit,
                    text: match &sc.value_at {
                        Some(at) => &sc.data[at.clone()],
                        None => &sc.value,
                    },
                    value,
                }];
                &part
            }
            None => &[],
        };
        if let Some(d) = out.direct(COLUMNS) {
            let row = ScratchRow {
                p: &p,
                sc,
                addr,
                device,
                sensor_no,
                sensor,
                unit,
                parts: parts.into(),
            };
            d.row(Some(p.micros), p.class, p.raw, &row);
            return;
        }
        let extra = [
            unit,
            addr,
            sc.resp.as_str(),
            p.framing.name(),
            sc.note.as_str(),
        ];
        let row = Row {
            stamp: p.stamp,
            micros: Some(p.micros),
            id: p.id.map(u32::from),
            device,
            kind: p.kind,
            class: p.class,
            sensor_no,
            sensor,
            data: &sc.data,
            extra: &extra,
            parts: parts.into(),
            raw: p.raw,
        };
        let _ = out.row(&row);
    }

    /// The number of a valid request or ACK (`docs/sab.md`, "Values"), its Data cell, and a
    /// note when a declared type does not fit the payload.
    fn number(values: &Values, sc: &mut Scratch, command: u8, flags: Flags, payload: &[u8]) {
        let ack = flags == Flags::Ack;
        let Some(declared) = values.declared(command, ack) else {
            // The default reading (`values::read_default`): the integer of 1, 2 or 4 bytes,
            // formatted once into the Data cell, which the Value column borrows.
            if let Some((at, unsigned)) = push_data(&mut sc.data, payload) {
                sc.value_at = Some(at);
                sc.number = Some((unsigned as f64, command, ack));
            }
            return;
        };
        match values.read(command, ack, payload, &mut sc.value) {
            Reading::Number(v) => {
                sc.number = Some((v, command, ack));
                // The declared reading instead of the integer one: `23 01 (2.91 m)`.
                push_hex(&mut sc.data, payload);
                sc.data.push_str(" (");
                sc.data.push_str(&sc.value);
                if !declared.unit.is_empty() {
                    sc.data.push(' ');
                    sc.data.push_str(&declared.unit);
                }
                sc.data.push(')');
            }
            Reading::WrongSize(ty, len) => {
                push_payload(&mut sc.data, payload);
                let n = sc.note();
                push_u64(n, len as u64);
                n.push_str(if len == 1 {
                    " payload byte"
                } else {
                    " payload bytes"
                });
                n.push_str(", --value declares ");
                n.push_str(ty.name());
                n.push_str(" (");
                push_u64(n, ty.size() as u64);
                n.push_str("): no value");
            }
            Reading::NotFinite => {
                push_payload(&mut sc.data, payload);
                sc.note().push_str("f32 NaN or infinite: no value");
            }
            Reading::None => push_payload(&mut sc.data, payload),
        }
    }

    pub(super) fn timeout_row(&mut self, x: &Expired, framing: Framing, out: &mut Latch<'_>) {
        let r = x.request;
        self.stats.timeouts += 1;
        self.stats.per[r.address as usize].timeouts += 1;
        let stamp = 1 << 30 | u32::from(r.address) << 16 | u32::from(r.command) << 8;
        if let (Why::NextRequest | Why::Retry | Why::End, None) = (x.why, &self.framing_note)
            && let Some(d) = out.direct(COLUMNS)
        {
            let row = TimeoutRow {
                stamp,
                addr: r.address,
                command: r.command,
                end: x.why == Why::End,
                waited: x.waited / 1000,
                framing,
                names: &self.names,
            };
            d.row(Some(x.at / 1000), Class::Warning, &[], &row);
            return;
        }
        let sc = &mut self.scratch;
        sc.clear();
        let n = sc.note();
        match x.why {
            Why::Deadline => {
                n.push_str("no response within ");
                push_ms_short(n, self.pairing.timeout() / 1000);
                n.push_str(" ms");
            }
            Why::NextRequest | Why::Retry => {
                n.push_str("no response before the next request (after ");
                push_ms(n, x.waited / 1000);
                n.push_str(" ms)");
            }
            Why::End => {
                n.push_str("no response before the end of the capture (after ");
                push_ms(n, x.waited / 1000);
                n.push_str(" ms)");
            }
            // Not from SAB's pairing (one request open at a time, nothing to give up).
            Why::Dropped | Why::Overflow => {
                n.push_str("given up (after ");
                push_ms(n, x.waited / 1000);
                n.push_str(" ms)");
            }
        }
        self.put(
            RowParts {
                micros: x.at / 1000,
                id: Some(r.address),
                command: Some(r.command),
                kind: crate::row::kind::TIMEOUT,
                class: Class::Warning,
                framing,
                raw: &[],
                stamp,
            },
            out,
        );
    }

    /// Handles one event of the active reassembler.
    pub(super) fn event(&mut self, ev: &Event<'_>, out: &mut Latch<'_>) {
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
    fn frame(&mut self, ev: &Event<'_>, start: u64, out: &mut Latch<'_>) {
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
        // A payload read by a declared type (its note first) goes as a `Row`; the rest may be
        // written straight, the Data cell formatted in place.
        let numbered = matches!(flags, Flags::Request | Flags::Ack);
        let declared = numbered && self.values.declared(command, flags == Flags::Ack).is_some();
        if declared {
            Self::number(&self.values, sc, command, flags, payload);
        }
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
        let stamp = 1 << 31 | u32::from(addr) << 16 | u32::from(command) << 8 | flags as u32;
        if !declared {
            if let Some(d) = out.direct(COLUMNS) {
                self.take_framing_note();
                let resp = match answer {
                    Some(Answer::Paired { micros, .. }) => Some(micros / 1000),
                    _ => None,
                };
                let row = FrameRow {
                    stamp,
                    addr,
                    command,
                    flags,
                    numbered,
                    payload,
                    resp,
                    framing: ev.framing,
                    names: &self.names,
                    note: &self.scratch.note,
                };
                d.row(Some(start / 1000), class, ev.wire, &row);
                return;
            }
            let sc = &mut self.scratch;
            if numbered {
                Self::number(&self.values, sc, command, flags, payload);
            } else {
                push_payload(&mut sc.data, payload);
            }
        }
        if let Some(Answer::Paired { micros, .. }) = answer {
            push_ms3(&mut self.scratch.resp, micros / 1000);
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
                stamp,
            },
            out,
        );
    }

    /// A frame whose check fails. Rare, like [`Self::broken`]'s rows: both stay out of the
    /// common path's code ([`Self::frame`]).
    #[cold]
    #[inline(never)]
    fn bad_crc(&mut self, ev: &Event<'_>, start: u64, out: &mut Latch<'_>) {
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
                kind: crate::row::kind::BAD_CRC,
                class: Class::Error,
                framing: ev.framing,
                raw: ev.wire,
                stamp: 0,
            },
            out,
        );
    }

    /// Garbage, truncated frames, runts, aborts, overlong frames.
    #[cold]
    #[inline(never)]
    fn broken(&mut self, ev: &Event<'_>, start: u64, out: &mut Latch<'_>) {
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
                crate::row::kind::GARBAGE
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
                crate::row::kind::TRUNCATED
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
                crate::row::kind::GARBAGE
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
                stamp: 0,
            },
            out,
        );
    }

    /// End of the capture at `now` (ns).
    pub(super) fn finish(&mut self, now: u64, framing: Framing, out: &mut Latch<'_>) {
        if let Some(x) = self.pairing.finish(now) {
            self.timeout_row(&x, framing, out);
        }
    }
}

#[cfg(test)]
mod tests;
