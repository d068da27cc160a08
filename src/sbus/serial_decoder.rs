//! The serial front end: the framer of the mode in use (auto mode tries both readings first),
//! the station table and the request/answer pairing; every telegram goes through the shared
//! mapper ([`super::map`]).

use std::fmt::Write as _;

use super::map::{Content, Mapper, put_content_row, put_row};
use super::pairing::{Outstanding, RequestKind, SerialPairing, TimeoutWhy};
use super::serial::{BreakFramer, CrcCheck, DataFramer, Event, Frame, Tele};
use super::stats::{self, StationStats, Totals};
use super::telegram::{self, CrcBasis};
use super::{COLUMNS, DETECT_BYTES, Mode, Options, default_gap_us, default_timeout_ms};
use crate::fmt::{push_hex, push_u64};
use crate::protocol::Decoder;
use crate::row::{Class, Latch, OutputError, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// What the serial decoder settled on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resolved {
    Data,
    Break,
    Parity,
}

/// Auto mode before the decision: the bytes so far and a trial framer for each reading.
struct Detect {
    segments: Vec<(Vec<u8>, Option<u64>)>,
    len: usize,
    trial: Box<DataFramer>,
    trial_break: Box<BreakFramer>,
    /// CRC-valid telegrams found by each reading: data mode, break mode.
    counts: [u32; 2],
    decided: Option<bool>,
}

/// What the trial framers are fed.
#[derive(Clone, Copy)]
enum Trial<'a> {
    Push(&'a [u8], Option<u64>),
    Idle(u64),
    Finish,
}

impl Detect {
    /// Feeds both readings; returns the valid telegrams each found (break mode counts only
    /// requests and responses: a lone ACK character proves little).
    fn trial(&mut self, what: Trial<'_>) -> [u32; 2] {
        let mut hit = [0u32; 2];
        let mut data = |ev: &Event<'_>| {
            if let Event::Frame(f) = ev
                && f.crc.ok()
            {
                hit[0] += 1;
            }
        };
        match what {
            Trial::Push(b, time) => self.trial.push(b, time, &mut data),
            Trial::Idle(now) => self.trial.idle(now, &mut data),
            Trial::Finish => self.trial.finish(&mut data),
        }
        let mut brk = |ev: &Event<'_>| {
            if let Event::Frame(f) = ev
                && f.crc.ok()
                && matches!(f.tele, Tele::Request { .. } | Tele::Response { .. })
            {
                hit[1] += 1;
            }
        };
        match what {
            Trial::Push(b, time) => self.trial_break.push(b, time, &mut brk),
            Trial::Idle(now) => self.trial_break.idle(now, &mut brk),
            Trial::Finish => self.trial_break.finish(&mut brk),
        }
        hit
    }

    /// Bytes while undecided: both readings are tried byte by byte so that the decision does
    /// not depend on how the input is chunked. Returns the decision (`true` = data mode).
    fn push(&mut self, data: &[u8], time: Option<u64>) -> Option<bool> {
        let take = data.len().min(DETECT_BYTES - self.len);
        for &b in &data[..take] {
            let hit = self.trial(Trial::Push(&[b], time));
            self.counts[0] += hit[0];
            self.counts[1] += hit[1];
            if self.decided.is_none() {
                self.decided = early_decision(self.counts);
            }
            if self.decided.is_some() {
                break;
            }
        }
        self.segments.push((data.to_vec(), time));
        self.len += take;
        match self.decided {
            Some(d) => Some(d),
            None if self.len >= DETECT_BYTES => Some(late_decision(self.counts)),
            None => None,
        }
    }

    /// A live line went quiet: decide with what was seen, if anything.
    fn idle(&mut self, now: u64) -> Option<bool> {
        let hit = self.trial(Trial::Idle(now));
        self.counts[0] += hit[0];
        self.counts[1] += hit[1];
        (self.counts[0] + self.counts[1] > 0).then(|| late_decision(self.counts))
    }

    /// The end of the input: decide now.
    fn finish(&mut self) -> bool {
        match self.decided {
            Some(d) => d,
            None => {
                let hit = self.trial(Trial::Finish);
                late_decision([self.counts[0] + hit[0], self.counts[1] + hit[1]])
            }
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

enum Framer {
    Detect(Box<Detect>),
    Data(Box<DataFramer>),
    Break(Box<BreakFramer>),
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
    map: Mapper,
    resolved: Option<Resolved>,
    timeout_override: Option<u64>,
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
            Mode::Auto => Framer::Detect(Box::new(Detect {
                segments: Vec::new(),
                len: 0,
                trial: Box::new(DataFramer::new(gap(10))),
                trial_break: Box::new(BreakFramer::new(false, gap(10), timeout(false))),
                counts: [0, 0],
                decided: None,
            })),
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
            map: Mapper::new(true),
            resolved: None,
            timeout_override: opts.timeout_ms.map(|t| t * 1000),
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
        &self.core.map.totals
    }

    pub fn station_stats(&self, station: u8) -> &StationStats {
        &self.core.per[station as usize]
    }

    fn settle(&mut self, data_mode: bool, out: &mut dyn RowOut) -> RowResult {
        let Framer::Detect(detect) = &mut self.framer else {
            return Ok(());
        };
        let segments = std::mem::take(&mut detect.segments);
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
            self.feed(Trial::Push(&bytes, time), out)?;
        }
        Ok(())
    }

    /// Feeds the framer of the mode settled on; its events become rows.
    fn feed(&mut self, what: Trial<'_>, out: &mut dyn RowOut) -> RowResult {
        let core = &mut self.core;
        let mut latch = Latch::new(out);
        let mut emit = |ev: &Event<'_>| {
            let _ = core.event(ev, &mut latch);
        };
        match (&mut self.framer, what) {
            (Framer::Data(f), Trial::Push(data, time)) => f.push(data, time, &mut emit),
            (Framer::Data(f), Trial::Idle(now)) => f.idle(now, &mut emit),
            (Framer::Data(f), Trial::Finish) => f.finish(&mut emit),
            (Framer::Break(f), Trial::Push(data, time)) => f.push(data, time, &mut emit),
            (Framer::Break(f), Trial::Idle(now)) => f.idle(now, &mut emit),
            (Framer::Break(f), Trial::Finish) => f.finish(&mut emit),
            (Framer::Detect(_), _) => {}
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
        time.unwrap_or_else(|| crate::protocol::untimed_micros(offset, self.bits, self.baud))
    }

    fn device(&self, station: Option<u8>) -> &str {
        device(&self.names, station)
    }

    fn event(&mut self, ev: &Event<'_>, out: &mut dyn RowOut) -> RowResult {
        match ev {
            Event::Frame(f) => self.frame(f, out),
            Event::Garbage(g) => {
                let t = self.micros(g.time, g.offset);
                self.expire(t, out)?;
                let m = &mut self.map;
                m.totals.garbage_bytes += g.bytes.len() as u64;
                m.totals.garbage_runs += 1;
                m.sc.clear();
                push_hex(&mut m.sc.data, g.bytes);
                m.sc.note_with(|n| {
                    push_u64(n, g.bytes.len() as u64);
                    n.push_str(if g.bytes.len() == 1 {
                        " byte"
                    } else {
                        " bytes"
                    });
                    n.push_str(" outside any telegram");
                });
                put_row(
                    out,
                    &mut m.sc,
                    t,
                    None,
                    "",
                    crate::row::kind::GARBAGE,
                    Class::Error,
                    "",
                    g.bytes,
                )
            }
        }
    }

    fn expire(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        if let Some(p) = self.pairing.expire(now) {
            let at = p.time.saturating_add(self.pairing.timeout);
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
        let station = p.info.station;
        self.map.timeout(
            p,
            why,
            at,
            self.pairing.timeout,
            device(&self.names, Some(station)),
            Some(&mut self.per[station as usize]),
            out,
        )
    }

    fn frame(&mut self, f: &Frame<'_>, out: &mut dyn RowOut) -> RowResult {
        let t = self.micros(f.time, f.offset);
        let timed = f.time.is_some();
        self.expire(t, out)?;
        let sc = &mut self.map.sc;
        sc.clear();
        // The telegram without framing, DLE pairs and CRC, for a sink that re-wraps it (the
        // Ether-S-Bus export).
        let bad_check = match f.crc {
            CrcCheck::Bad { got, .. } => Some(got),
            _ => None,
        };
        let checked = f.crc != CrcCheck::None;
        let (head, code);
        let content = match f.tele {
            Tele::Request { station, cmd, body } if checked => {
                head = [station, cmd];
                Some((telegram::AT_REQUEST, &head[..], body))
            }
            Tele::Response { data } if checked => Some((telegram::AT_RESPONSE, &[][..], data)),
            Tele::AckNak { code: c, .. } => {
                code = c.to_be_bytes();
                Some((telegram::AT_ACKNAK, &code[..], &[][..]))
            }
            _ => None,
        };
        let content = content.map(|(at, head, body)| Content {
            at,
            head,
            body,
            bad_check,
        });
        let content = content.as_ref();
        let seq = f.secure.map(|s| s.seq as u16);
        if let Some(s) = seq {
            sc.seq(s);
        }
        // Framing remarks first.
        let mut class = Class::Plain;
        if let Some(s) = f.secure {
            if !s.len_ok() {
                sc.note_with(|n| {
                    n.push_str("secure LEN ");
                    push_u64(n, s.len as u64);
                    n.push_str(", telegram has ");
                    push_u64(n, s.actual as u64);
                });
                class = Class::Warning;
            }
            if s.seq_unescaped {
                sc.note("SEQ 0xC5 sent without DLE (old firmware, SBC FAQ 101180)");
                class = Class::Warning;
            }
        } else if self.secure_mode && matches!(f.tele, Tele::Request { .. }) {
            sc.note("standard request in secure mode");
        }
        if f.break_before {
            sc.note("after a break (00)");
        }
        if let Some(p) = f.problem {
            sc.note(p);
            class = Class::Error;
        }
        match f.crc {
            CrcCheck::Ok(basis) => {
                if !matches!(f.tele, Tele::Broken) {
                    self.map.totals.valid += 1;
                }
                if f.wire.first() == Some(&telegram::FS) {
                    // The note in one piece (`CRC over the {basis.name()} bytes`).
                    let (i, note) = match basis {
                        CrcBasis::Escaped => (0, Some("CRC over the escaped bytes")),
                        CrcBasis::Unescaped => (1, Some("CRC over the unescaped bytes")),
                        CrcBasis::Both => (2, None),
                    };
                    self.map.totals.basis[i] += 1;
                    if let Some(note) = note {
                        self.map.sc.note(note);
                    }
                }
                self.good_frame(f, content, t, timed, seq, class, out)
            }
            CrcCheck::Bad {
                got,
                escaped,
                unescaped,
            } => {
                let other = (unescaped != escaped).then_some(unescaped);
                self.map.bad_crc(got, escaped, other);
                self.bad_frame(f, content, t, out)
            }
            CrcCheck::None => match f.tele {
                Tele::AckNak { .. } => {
                    self.map.totals.valid += 1;
                    self.good_frame(f, content, t, timed, seq, class, out)
                }
                _ => self.truncated_row(f.wire, t, out),
            },
        }
    }

    fn bad_frame(
        &mut self,
        f: &Frame<'_>,
        content: Option<&Content<'_>>,
        t: u64,
        out: &mut dyn RowOut,
    ) -> RowResult {
        let sc = &mut self.map.sc;
        let (id, sensor) = match f.tele {
            Tele::Request { station, cmd, body } => {
                telegram::describe_request(station, cmd, body, &mut sc.sensor_no, &mut sc.data);
                self.per[station as usize].crc_errors += 1;
                // It opens nothing: its station, command and address may be the broken bytes,
                // and an answer paired with it would show them as read (M3, issue 32).
                if let Some((p, why)) = self.pairing.bad_request() {
                    self.timeout_row(&p, why, t, out)?;
                }
                (Some(station), telegram::command_name(cmd))
            }
            Tele::Response { .. } | Tele::AckNak { .. } => {
                match f.tele {
                    Tele::Response { data } => push_hex(&mut sc.data, data),
                    Tele::AckNak { code, .. } => push_hex(&mut sc.data, &code.to_be_bytes()),
                    _ => {}
                }
                match self.pairing.pending().copied() {
                    Some(p) => {
                        if let Some(e) = p.info.elem {
                            super::commands::push_elem(
                                &mut sc.sensor_no,
                                e,
                                p.info.block,
                                p.info.addr,
                            );
                        }
                        self.per[p.info.station as usize].crc_errors += 1;
                        self.pairing.bad_answer();
                        sc.note(if matches!(f.tele, Tele::Response { .. }) {
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
                push_hex(&mut sc.data, payload);
                (None, "")
            }
            Tele::Broken => {
                push_hex(&mut sc.data, f.wire);
                (None, "")
            }
        };
        let device = device(&self.names, id);
        put_content_row(
            out,
            &mut self.map.sc,
            content,
            t,
            id.map(u32::from),
            device,
            crate::row::kind::BAD_CRC,
            Class::Error,
            sensor,
            f.wire,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn good_frame(
        &mut self,
        f: &Frame<'_>,
        content: Option<&Content<'_>>,
        t: u64,
        timed: bool,
        seq: Option<u16>,
        mut class: Class,
        out: &mut dyn RowOut,
    ) -> RowResult {
        let (id, kind, sensor) = match f.tele {
            Tele::Request { station, cmd, body } => {
                let st = &mut self.per[station as usize];
                let info = self.map.request(station, cmd, body, st, &mut class);
                let req = Outstanding::new(info, t, timed, seq);
                let kind = self.request(station, cmd, body, req, out)?;
                let st = &mut self.per[station as usize];
                let kind = self.map.request_kind(kind, timed, st, &mut class);
                (Some(station), kind, telegram::command_name(cmd))
            }
            Tele::Response { data } => {
                let info = self.answer(t, seq, timed, &mut class);
                let paired = info
                    .as_ref()
                    .map(|i| (i, &mut self.per[i.station as usize]));
                self.map.response(paired, data, &mut class);
                if info.is_some() && f.length_mismatch {
                    self.map.sc.note("found by its CRC");
                }
                (info.map(|i| i.station), "Response", name(&info))
            }
            Tele::AckNak { code, short } => {
                let info = self.answer(t, seq, timed, &mut class);
                let paired = info
                    .as_ref()
                    .map(|i| (i, &mut self.per[i.station as usize]));
                let kind = self.map.ack_nak(code, short, paired, &mut class);
                (info.map(|i| i.station), kind, name(&info))
            }
            Tele::Other { at, payload } => {
                push_hex(&mut self.map.sc.data, payload);
                self.map.sc.note_with(|n| {
                    let _ = write!(n, "unknown attribute 0x{at:02X}");
                });
                return put_row(
                    out,
                    &mut self.map.sc,
                    t,
                    None,
                    "",
                    "Unknown",
                    Class::Warning,
                    "",
                    f.wire,
                );
            }
            Tele::Broken => return self.truncated_row(f.wire, t, out),
        };
        let device = device(&self.names, id);
        let id = id.map(u32::from);
        put_content_row(
            out,
            &mut self.map.sc,
            content,
            t,
            id,
            device,
            kind,
            class,
            sensor,
            f.wire,
        )
    }

    /// A telegram cut short (or otherwise broken): its bytes, counted.
    fn truncated_row(&mut self, wire: &[u8], t: u64, out: &mut dyn RowOut) -> RowResult {
        self.map.totals.broken += 1;
        push_hex(&mut self.map.sc.data, wire);
        put_row(
            out,
            &mut self.map.sc,
            t,
            None,
            "",
            crate::row::kind::TRUNCATED,
            Class::Error,
            "",
            wire,
        )
    }

    /// A request becomes the outstanding one; the one it replaces, if unanswered, gets its
    /// Timeout row first.
    fn request(
        &mut self,
        station: u8,
        cmd: u8,
        body: &[u8],
        req: Outstanding,
        out: &mut dyn RowOut,
    ) -> Result<RequestKind, OutputError> {
        let expects = req.info.expect != super::commands::Expect::Nothing;
        let (kind, prev) = self.pairing.request([station, cmd], body, req, expects);
        if let Some((p, why)) = prev {
            self.timeout_row(&p, why, req.time, out)?;
        }
        Ok(kind)
    }

    /// Pairs an answer with the outstanding request (its counters, response time and notes).
    fn answer(
        &mut self,
        t: u64,
        seq: Option<u16>,
        timed: bool,
        class: &mut Class,
    ) -> Option<telegram::ReqInfo> {
        let answer = self.pairing.answer(t, seq);
        let per = &mut self.per;
        let timeout = self.pairing.timeout;
        self.map.answer(
            &answer,
            timed,
            timeout,
            move |i| &mut per[i.station as usize],
            class,
        )
    }

    fn finish(&mut self) {
        // A request still waiting at the end: its answer may simply not have been captured,
        // so it is counted, not reported as a timeout.
        if self.pairing.finish().is_some() {
            self.map.totals.unanswered_at_end += 1;
        }
    }
}

/// The Device column of a station: its `--station` name, or `PCD`.
fn device(names: &[Option<String>], station: Option<u8>) -> &str {
    match station.and_then(|s| names[s as usize].as_deref()) {
        Some(n) => n,
        None => "PCD",
    }
}

/// The command name of an answered request.
fn name(info: &Option<telegram::ReqInfo>) -> &'static str {
    info.as_ref().map_or("", |i| i.name())
}

impl Decoder for SerialDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        if let Framer::Detect(detect) = &mut self.framer {
            if let Some(d) = detect.push(data, time) {
                self.settle(d, out)?;
            }
            return Ok(());
        }
        self.feed(Trial::Push(data, time), out)
    }

    fn idle(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        // Auto mode on a live line that went quiet after a few telegrams: decide with what was
        // seen rather than wait for more.
        if let Framer::Detect(detect) = &mut self.framer {
            match detect.idle(now) {
                Some(d) => self.settle(d, out)?,
                None => return Ok(()),
            }
        }
        self.feed(Trial::Idle(now), out)?;
        self.core.expire(now, out)
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        if let Framer::Detect(detect) = &mut self.framer {
            let d = detect.finish();
            self.settle(d, out)?;
        }
        self.feed(Trial::Finish, out)?;
        self.core.finish();
        Ok(())
    }

    fn valid_frames(&self) -> u64 {
        self.core.map.totals.valid
    }

    fn stats(&self) -> Report {
        let c = &self.core;
        let mode = match c.resolved {
            Some(Resolved::Data) => "data mode",
            Some(Resolved::Break) => "break mode",
            Some(Resolved::Parity) => "parity mode",
            None => "mode not detected",
        };
        let rows = c.per.iter().enumerate().filter(|(_, st)| st.seen());
        stats::report(
            format!("{mode}, master timeout {} ms", c.pairing.timeout / 1000),
            rows.map(|(i, st)| (i.to_string(), c.device(Some(i as u8)), st)),
            &c.map.totals,
            false,
        )
    }

    fn problems(&self) -> Problems {
        stats::problems(&self.core.map.totals)
    }

    fn no_frames_hint(&self) -> &'static str {
        "check the baud rate (S-Bus ports default to 9600) and the mode (--mode data|break|parity)"
    }
}
