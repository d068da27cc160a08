//! The one mapping of S-Bus telegrams onto the log table, shared by the serial front end
//! ([`super::serial_decoder`]) and the Ether-S-Bus one ([`super::ether_decoder`]): the row
//! being built, Timeout rows, requests and retries, answers (response time, late, unpaired),
//! responses, ACK/NAK, CRC errors, and the counters they touch. The columns are documented in
//! `docs/sbus.md`.

use std::fmt::Write as _;

use super::commands::{self, Expect};
use super::media::{FEW_PARTS, LazyWords, MAX_PARTS, MediaSpans, media_parts};
use super::pairing::{
    Answer, MAX_CONVERSATIONS, MAX_OUTSTANDING, Outstanding, RequestKind, TimeoutWhy,
};
use super::stats::{StationStats, Totals, nak_slot};
use super::telegram::{self, BROADCAST, ReqInfo};
use crate::digits::put_u32;
use crate::fmt::{push_fixed, push_hex, push_u64};
use crate::row::{Cells, Class, Fmt, Part, Parts, Row, RowOut, RowResult, Unframed, WriteRow};

/// Scratch buffers reused for every row.
#[derive(Default)]
pub(super) struct Scratch {
    pub sensor_no: String,
    pub data: String,
    /// The Resp ms text when it is not `resp_ms`.
    resp: String,
    /// The response time as whole milliseconds and tenths (the usual one, written as
    /// `ms.t`), or `None` (then `resp`).
    resp_ms: Option<(u32, u8)>,
    /// The Seq cell, or `None` (empty).
    seq: Option<u16>,
    note: String,
    /// The bytes of the row's [`Content`], made only for a row handed on as a [`Row`].
    unframed: Vec<u8>,
    /// Where the numbers of `data` stand, when it was written as a media list.
    media: MediaSpans,
}

impl Scratch {
    pub(super) fn clear(&mut self) {
        self.sensor_no.clear();
        self.data.clear();
        self.resp.clear();
        self.resp_ms = None;
        self.seq = None;
        self.note.clear();
        self.media.clear();
    }

    pub(super) fn note(&mut self, text: &str) {
        crate::row::note_part(&mut self.note).push_str(text);
    }

    pub(super) fn note_with(&mut self, f: impl FnOnce(&mut String)) {
        f(crate::row::note_part(&mut self.note));
    }

    pub(super) fn resp_time(&mut self, us: u64) {
        // (wrapping as the release build always did; no capture has such times)
        let tenths = (us as i64).wrapping_add(50) / 100;
        match u32::try_from(tenths / 10) {
            // what push_fixed(…, 1) writes, without its general path (see `resp_text`)
            Ok(ms) if tenths >= 0 => self.resp_ms = Some((ms, (tenths % 10) as u8)),
            _ => push_fixed(&mut self.resp, tenths, 1),
        }
    }

    pub(super) fn seq(&mut self, seq: u16) {
        self.seq = Some(seq);
    }

    /// The Resp ms text (written into `buf` when it is `resp_ms`).
    fn resp_text<'b>(&'b self, buf: &'b mut [u8; 16]) -> &'b str {
        match self.resp_ms {
            Some((ms, tenths)) => {
                let n = put_u32(buf, ms);
                buf[n] = b'.';
                buf[n + 1] = b'0' + tenths;
                std::str::from_utf8(&buf[..n + 2]).unwrap_or_default()
            }
            None => &self.resp,
        }
    }

    /// The Seq text (written into `buf`).
    fn seq_text<'b>(&self, buf: &'b mut [u8; 16]) -> &'b str {
        match self.seq {
            Some(seq) => {
                let n = put_u32(buf, seq.into());
                std::str::from_utf8(&buf[..n]).unwrap_or_default()
            }
            None => "",
        }
    }

    /// The cells Resp ms and Seq, written straight into the table.
    #[inline(always)]
    fn resp_seq_cells<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        match self.resp_ms {
            Some((ms, tenths)) => {
                c.begin();
                c.dec(ms.into());
                c.put_ascii(&[b'.', b'0' + tenths]);
                c.end();
            }
            None => c.text(&self.resp),
        }
        match self.seq {
            Some(seq) => {
                c.begin();
                c.dec(seq.into());
                c.end();
            }
            None => c.empty(),
        }
    }
}

/// A row's telegram re-read, for a sink that re-wraps it (the serial front end's rows of
/// telegrams): the attribute, then the telegram without framing, escaping and CRC (`head`,
/// then `body`), and the CRC as received when it failed (see [`Unframed`]). It borrows the
/// telegram: its bytes are made only for a row handed on as a [`Row`], never for one
/// written straight into the table (which has no use for them).
#[derive(Clone, Copy, Debug)]
pub(super) struct Content<'a> {
    pub at: u8,
    pub head: &'a [u8],
    pub body: &'a [u8],
    pub bad_check: Option<u16>,
}

/// One row, from the scratch buffers: straight into the table when it lends its output
/// ([`crate::row::Direct`]), else as a [`Row`] (a deferred media list written as text first).
#[allow(clippy::too_many_arguments)]
pub(super) fn put_row(
    out: &mut dyn RowOut,
    sc: &mut Scratch,
    micros: u64,
    id: Option<u32>,
    device: &str,
    kind: &str,
    class: Class,
    sensor: &str,
    raw: &[u8],
) -> RowResult {
    put_content_row(out, sc, None, micros, id, device, kind, class, sensor, raw)
}

/// [`put_row`] for a row of a telegram whose content a sink may want ([`Content`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn put_content_row(
    out: &mut dyn RowOut,
    sc: &mut Scratch,
    content: Option<&Content<'_>>,
    micros: u64,
    id: Option<u32>,
    device: &str,
    kind: &str,
    class: Class,
    sensor: &str,
    raw: &[u8],
) -> RowResult {
    if let Some(d) = out.direct(super::COLUMNS) {
        match sc.media.lazy {
            Some(list) => {
                let row = LazyRow {
                    sc,
                    list,
                    id,
                    device,
                    kind,
                    sensor,
                    class,
                };
                d.row(Some(micros), class, raw, &row);
            }
            None => with_parts(sc, class, |parts| {
                let row = ScratchRow {
                    sc,
                    id,
                    device,
                    kind,
                    sensor,
                    parts,
                };
                d.row(Some(micros), class, raw, &row);
            }),
        }
        return Ok(());
    }
    sc.media.settle(&mut sc.sensor_no, &mut sc.data);
    sc.unframed.clear();
    if let Some(c) = content {
        sc.unframed.push(c.at);
        sc.unframed.extend_from_slice(c.head);
        sc.unframed.extend_from_slice(c.body);
    }
    let bad_check = content.and_then(|c| c.bad_check);
    let sc = &*sc;
    with_parts(sc, class, |parts| {
        let (mut rb, mut sb) = ([0; 16], [0; 16]);
        let extra = [
            sc.resp_text(&mut rb),
            sc.seq_text(&mut sb),
            sc.note.as_str(),
        ];
        put(
            out,
            sc,
            bad_check,
            &Row {
                stamp: 0,
                micros: Some(micros),
                id,
                device,
                kind,
                class,
                sensor_no: &sc.sensor_no,
                sensor,
                data: &sc.data,
                extra: &extra,
                parts,
                raw,
            },
        )
    })
}

/// A row of the scratch buffers, written straight into the table: the cells the [`Row`] of
/// [`put_row`] has.
struct ScratchRow<'a> {
    sc: &'a Scratch,
    id: Option<u32>,
    device: &'a str,
    kind: &'a str,
    sensor: &'a str,
    parts: Parts<'a>,
}

impl WriteRow for ScratchRow<'_> {
    #[inline]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let sc = self.sc;
        if c.stamp(0) {
            c.id(self.id);
            c.text(self.device);
            c.text(self.kind);
            c.text(&sc.sensor_no);
            c.text(self.sensor);
            c.stamp_end();
        }
        c.text(&sc.data);
        c.value_text(first_text(self.parts));
        sc.resp_seq_cells(c);
        c.text(&sc.note);
        c.row_parts(self.parts);
    }
}

/// A row whose Data cell is a deferred media list ([`MediaSpans::lazy`]), written straight
/// into the table: the cells [`ScratchRow`] writes once the list is settled as text, the list
/// written in place (its numbers the row's parts, as [`with_parts`] finds them).
struct LazyRow<'a> {
    sc: &'a Scratch,
    list: LazyWords,
    id: Option<u32>,
    device: &'a str,
    kind: &'a str,
    sensor: &'a str,
    class: Class,
}

impl WriteRow for LazyRow<'_> {
    #[inline]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let sc = self.sc;
        let name = self.list.first_name();
        if c.stamp(0) {
            c.id(self.id);
            c.text(self.device);
            c.text(self.kind);
            self.list.sensor_cell(&name, &sc.sensor_no, c);
            c.text(self.sensor);
            c.stamp_end();
        }
        c.begin();
        let (first, list) = sc.media.write_lazy(&self.list, &name, c);
        c.end();
        // No parts for an error, nor for more numbers than a row carries (see `with_parts`).
        let parts =
            !self.list.range && self.class != Class::Error && self.list.count as usize <= MAX_PARTS;
        c.value(first.filter(|_| parts));
        sc.resp_seq_cells(c);
        c.text(&sc.note);
        if parts {
            c.pairs(list);
        }
    }
}

/// The text of the row's first number (the Value column): cut straight from the Data text
/// for a recorded media list (what `Parts::first` gives, without making the part).
#[inline(always)]
fn first_text(parts: Parts<'_>) -> Option<&str> {
    match parts {
        Parts::Spans { text, spans } => spans
            .first()
            .map(|s| text.get(s.eq as usize + 1..s.end as usize).unwrap_or("")),
        parts => parts.first().map(|p| p.text),
    }
}

/// Calls `f` with the numbers of the row in the scratch buffers.
#[inline]
fn with_parts<R>(sc: &Scratch, class: Class, f: impl FnOnce(Parts<'_>) -> R) -> R {
    if class == Class::Error {
        return f(Parts::NONE);
    }
    // A media list recorded while the Data cell was written: its numbers where they were
    // formatted (the same parts as reading the text back, see `media_parts`), made into parts
    // only by a reader that wants them all.
    if sc.media.len == Some(sc.data.len()) {
        let spans = &sc.media.spans;
        if spans.is_empty() || spans.len() > MAX_PARTS {
            return f(Parts::NONE);
        }
        return f(Parts::Spans {
            text: &sc.data,
            spans,
        });
    }
    // Only rows that list values pay for the parts' buffer, and most need a small one.
    if sc.data.as_bytes().contains(&b'=') {
        let tokens = 1 + sc.data.bytes().filter(|&b| b == b' ').count();
        if tokens <= FEW_PARTS {
            let mut buf = [Part::EMPTY; FEW_PARTS];
            let n = media_parts(&sc.data, &mut buf);
            return f(Parts::List(&buf[..n]));
        }
        let mut buf = [Part::EMPTY; MAX_PARTS];
        let n = media_parts(&sc.data, &mut buf);
        return f(Parts::List(&buf[..n]));
    }
    f(Parts::NONE)
}

/// Hands the row on, with the telegram's content when the decoder kept it (the export).
fn put(out: &mut dyn RowOut, sc: &Scratch, bad_check: Option<u16>, row: &Row<'_>) -> RowResult {
    if sc.unframed.is_empty() {
        out.row(row)
    } else {
        let frame = Unframed {
            bytes: &sc.unframed,
            bad_check,
        };
        out.row_unframed(row, &frame)
    }
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
    telegram::describe_response_media(
        req,
        data,
        &mut sc.sensor_no,
        &mut sc.data,
        Some(&mut sc.media),
    );
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
            push_u64(n, MAX_CONVERSATIONS as u64);
            n.push_str(" at once)");
        }
        TimeoutWhy::Overflow => {
            n.push_str("given up: more than ");
            push_u64(n, MAX_OUTSTANDING as u64);
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

/// The telegram-to-row mapper: the scratch of the row being built, the scratch of Timeout rows
/// (written while a row is being built) and the totals. The front ends choose the station or
/// PLC counters (`StationStats`) and the Device column; everything else is written here once.
pub(super) struct Mapper {
    pub sc: Scratch,
    tsc: Scratch,
    pub totals: Totals,
    /// Note an ACK to a request that expects data (the serial decoder does, the Ether one
    /// never did).
    ack_expect_note: bool,
}

impl Mapper {
    pub fn new(ack_expect_note: bool) -> Self {
        let mut sc = Scratch::default();
        sc.media.defer = true;
        Mapper {
            sc,
            tsc: Scratch::default(),
            totals: Totals::default(),
            ack_expect_note,
        }
    }

    /// The Timeout row of request `p` at `at` (counted, also in `st`); the row being built is
    /// left alone.
    #[allow(clippy::too_many_arguments)]
    pub fn timeout(
        &mut self,
        p: &Outstanding,
        why: TimeoutWhy,
        at: u64,
        timeout_us: u64,
        device: &str,
        st: Option<&mut StationStats>,
        out: &mut dyn RowOut,
    ) -> RowResult {
        self.totals.timeouts += 1;
        if let Some(st) = st {
            st.timeouts += 1;
        }
        let sc = &mut self.tsc;
        sc.clear();
        if let Some(e) = p.info.elem {
            super::commands::push_elem(&mut sc.sensor_no, e, p.info.block, p.info.addr);
        }
        if let Some(s) = p.seq {
            sc.seq(s);
        }
        timeout_note(sc, why, timeout_us);
        put_row(
            out,
            sc,
            at,
            Some(p.info.station as u32),
            device,
            crate::row::kind::TIMEOUT,
            Class::Warning,
            p.info.name(),
            &[],
        )
    }

    /// The Sensor and Data text of a request and its notes; counted in `st`. `class` becomes
    /// the request's own class unless it is already set.
    pub fn request(
        &mut self,
        station: u8,
        cmd: u8,
        body: &[u8],
        st: &mut StationStats,
        class: &mut Class,
    ) -> ReqInfo {
        let text = telegram::describe_request_media(
            station,
            cmd,
            body,
            &mut self.sc.sensor_no,
            &mut self.sc.data,
            Some(&mut self.sc.media),
        );
        let c = request_notes(&mut self.sc, &text);
        if *class == Class::Plain {
            *class = c;
        }
        st.requests += 1;
        if text.info.expect == Expect::Nothing {
            st.broadcasts += 1;
        }
        text.info
    }

    /// `Request`, or `Retry` (counted, with a note; `timed`: how long after the first).
    pub fn request_kind(
        &mut self,
        kind: RequestKind,
        timed: bool,
        st: &mut StationStats,
        class: &mut Class,
    ) -> &'static str {
        match kind {
            RequestKind::New => "Request",
            RequestKind::Retry { n, since } => {
                self.totals.retries += 1;
                st.retries += 1;
                self.sc.note_with(|s| {
                    s.push_str("retry ");
                    push_u64(s, n as u64);
                    if timed {
                        s.push_str(", ");
                        push_fixed(s, (since as i64 + 50) / 100, 1);
                        s.push_str(" ms after the first");
                    }
                });
                if *class == Class::Plain {
                    *class = Class::Warning;
                }
                "Retry"
            }
        }
    }

    /// The response time (`timed`) and the late or unpaired note of an answer; `stats` gives
    /// the counters of a paired request. Returns the request answered.
    pub fn answer<'s>(
        &mut self,
        answer: &Answer,
        timed: bool,
        timeout_us: u64,
        stats: impl FnOnce(&ReqInfo) -> &'s mut StationStats,
        class: &mut Class,
    ) -> Option<ReqInfo> {
        match *answer {
            Answer::Paired { req, elapsed, late } => {
                let st = stats(&req.info);
                if timed {
                    st.times.add(elapsed);
                    self.sc.resp_time(elapsed);
                }
                if late {
                    st.late += 1;
                    self.totals.late += 1;
                    self.sc.note_with(|n| {
                        n.push_str("late: after the ");
                        push_u64(n, timeout_us / 1000);
                        n.push_str(" ms timeout");
                    });
                    *class = Class::Warning;
                }
                Some(req.info)
            }
            Answer::SeqMismatch { req } => {
                self.totals.no_request += 1;
                self.sc.note_with(|n| {
                    n.push_str("SEQ does not match the pending request's SEQ ");
                    push_u64(n, req.seq.unwrap_or(0) as u64);
                    n.push_str(" (a stale answer)");
                });
                *class = Class::Warning;
                None
            }
            Answer::AfterBadRequest => {
                self.totals.no_request += 1;
                self.sc.note(
                    "answers a request that failed its CRC: not paired (its station and \
                     command are not known)",
                );
                *class = Class::Warning;
                None
            }
            Answer::NoRequest => {
                self.totals.no_request += 1;
                self.sc.note("no request");
                *class = Class::Warning;
                None
            }
        }
    }

    /// The Data text of a response (hex without a request); a length that does not fit the
    /// request is counted and noted.
    pub fn response(
        &mut self,
        paired: Option<(&ReqInfo, &mut StationStats)>,
        data: &[u8],
        class: &mut Class,
    ) {
        match paired {
            Some((req, st)) => {
                st.responses += 1;
                if !response_text(&mut self.sc, req, data) {
                    self.totals.mismatched += 1;
                    st.mismatched += 1;
                    *class = Class::Warning;
                }
            }
            None => push_hex(&mut self.sc.data, data),
        }
    }

    /// The text of an ACK or NAK (`short`: the single character, and whether a 00 followed);
    /// counted. Returns the row kind.
    pub fn ack_nak(
        &mut self,
        code: u16,
        short: Option<(u8, bool)>,
        paired: Option<(&ReqInfo, &mut StationStats)>,
        class: &mut Class,
    ) -> &'static str {
        let kind = ack_text(&mut self.sc, code, short);
        if let Some((req, st)) = paired {
            if let Some(e) = req.elem {
                super::commands::push_elem(&mut self.sc.sensor_no, e, req.block, req.addr);
            }
            if code == 0 {
                st.acks += 1;
                if self.ack_expect_note && req.expect != Expect::AckNak {
                    self.sc.note("ACK to a request that expects data");
                    *class = Class::Warning;
                }
            } else {
                st.naks[nak_slot(code, short.is_some())] += 1;
            }
        }
        if code != 0 {
            self.totals.naks += 1;
            if *class == Class::Plain {
                *class = Class::Warning;
            }
        }
        kind
    }

    /// A CRC error: counted and noted (`unescaped`: the other reading's CRC, when it differs).
    pub fn bad_crc(&mut self, got: u16, want: u16, unescaped: Option<u16>) {
        self.totals.crc_errors += 1;
        self.sc.note_with(|n| {
            let _ = write!(n, "CRC 0x{got:04X}, expected 0x{want:04X}");
            if let Some(u) = unescaped {
                let _ = write!(n, " (escaped) or 0x{u:04X} (unescaped)");
            }
        });
    }
}

#[cfg(test)]
mod tests;
