//! The SM0 break mode and SM1 parity mode framer. These modes have no framing bytes: the
//! boundaries are found from what is known: the command table's request lengths, the response
//! length the last request asked for, the CRC, the single-character ACK (06) / NAK (15), a
//! leading 0x00 (a break as a raw-mode UART reports it) and time gaps when the source has
//! timestamps. See `docs/sbus.md` for what cannot be recovered.

use super::readings::{
    Cand, Memo, SearchMemo, crc_of, map, plausible_response_len, request_len, resp_at, searched,
    tail_dominated, zero_dominated,
};
use super::{CrcCheck, Event, Frame, GapClock, GarbageRun, Tele, expect_of};
use crate::sbus::commands::Expect;
use crate::sbus::telegram::{ACK_CHAR, NAK_CHAR, crc_step, crc16};

/// What the break/parity framer waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Await {
    /// A request (nothing outstanding).
    Request,
    /// The answer to the last request.
    Answer(Expect),
}

/// A request found at some position: break bytes skipped and body length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct ReqAt {
    skip: usize,
    body: usize,
    crc_ok: bool,
}

impl ReqAt {
    fn total(&self) -> usize {
        self.skip + 2 + self.body + 2
    }
}

/// Found telegram kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Found {
    Request(ReqAt),
    Response {
        len: usize,
        crc_ok: bool,
        mismatch: bool,
    },
    Ack {
        two: bool,
    },
}

/// Pure SM0 (break) / SM1 (parity) reassembler.
#[derive(Clone, Debug)]
pub struct BreakFramer {
    /// SM1: no break characters precede requests.
    parity: bool,
    buf: Vec<u8>,
    times: Vec<Option<u64>>,
    /// Index of the first unconsumed byte in `buf`.
    head: usize,
    /// Stream position of `buf[head]`.
    base: u64,
    awaiting: Await,
    /// The answer has not been searched for yet at this position (other-length responses
    /// are only looked for right after the request).
    fresh: bool,
    garbage: GarbageRun,
    clock: GapClock,
    /// Master timeout (µs): with times, bytes that start after it are read as a new request
    /// first (a request and a response of the same length check the same way).
    timeout: Option<u64>,
    /// Time of the last request.
    req_time: Option<u64>,
    /// Requests were seen after break characters: a bad-CRC reading is then only confirmed by
    /// a request that has its break too.
    breaks_seen: bool,
    /// The CRC searches of requests without a known length, kept while the bytes arrive.
    memo: SearchMemo,
}

impl BreakFramer {
    /// `parity`: SM1 (no break characters); `gap`: silence (µs) that ends a telegram;
    /// `timeout`: the master timeout (µs).
    pub fn new(parity: bool, gap: Option<u64>, timeout: Option<u64>) -> Self {
        BreakFramer {
            timeout,
            req_time: None,
            breaks_seen: false,
            memo: SearchMemo::default(),
            parity,
            buf: Vec::with_capacity(4096),
            times: Vec::with_capacity(4096),
            head: 0,
            base: 0,
            awaiting: Await::Request,
            fresh: false,
            garbage: GarbageRun::default(),
            clock: GapClock { gap, last: None },
        }
    }

    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if data.is_empty() {
            return;
        }
        if self.clock.gap_before(time) {
            self.resolve(true, emit);
            self.garbage.flush(emit);
        }
        // The whole chunk, then the decisions it allows: a decision does not depend on how
        // many bytes follow what it needs (the chunking tests feed every cut, down to single
        // bytes), so deciding once per chunk instead of once per byte gives the same rows.
        self.compact();
        self.buf.extend_from_slice(data);
        self.times.resize(self.buf.len(), time);
        self.resolve(false, emit);
    }

    pub fn idle(&mut self, now: u64, emit: &mut impl FnMut(&Event<'_>)) {
        if self.clock.idle(now) {
            self.resolve(true, emit);
            self.garbage.flush(emit);
        }
    }

    pub fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.resolve(true, emit);
        self.garbage.flush(emit);
    }

    fn compact(&mut self) {
        if self.head > 2048 {
            self.buf.drain(..self.head);
            self.times.drain(..self.head);
            self.head = 0;
        }
    }

    fn avail(&self) -> &[u8] {
        &self.buf[self.head..]
    }

    /// The search memo for readings of [`Self::avail`] (which starts at stream position `base`).
    fn memo(&self) -> Memo<'_> {
        Memo {
            table: &self.memo,
            origin: self.base,
        }
    }

    /// Decides as much as the buffered bytes allow; `at_end`: no byte follows them (gap or end
    /// of input), so every reading that needs more bytes fails.
    fn resolve(&mut self, at_end: bool, emit: &mut impl FnMut(&Event<'_>)) {
        while self.head < self.buf.len() {
            match self.decide(at_end) {
                Cand::More => return,
                Cand::Match(found) => self.take(found, emit),
                Cand::No => {
                    let b = self.buf[self.head];
                    let t = self.times[self.head];
                    self.garbage.push(b, t, self.base, emit);
                    self.head += 1;
                    self.base += 1;
                    self.fresh = false;
                }
            }
        }
    }

    fn decide(&self, at_end: bool) -> Cand<Found> {
        let b = self.avail();
        use Step::*;
        // Long after the timeout (3×) nothing is awaited any more.
        let lapsed = matches!(
            (self.timeout, self.req_time, self.times.get(self.head)),
            (Some(to), Some(rt), Some(Some(t))) if *t > rt.saturating_add(to.saturating_mul(3))
        );
        let awaiting = if lapsed {
            Await::Request
        } else {
            self.awaiting
        };
        // The readings in order of preference (`n`: the answer's length, for `Resp`,
        // `OtherResp` and `BadResp`); `OtherResp` and `AnyResp` only right after the request.
        let (order, n): (&[Step], usize) = match awaiting {
            Await::Request | Await::Answer(Expect::Nothing) => (&[Req, BadReq, StrayAck], 0),
            Await::Answer(Expect::AckNak) => (&[AckRelaxed, Req, BadReq], 0),
            Await::Answer(Expect::Data(n)) => (self.answer_order(), n),
            Await::Answer(Expect::LengthPrefixed) => {
                let Some(&n) = b.first() else {
                    return Cand::More;
                };
                (self.answer_order(), 1 + n as usize)
            }
            Await::Answer(Expect::Unknown) => (&[AckStrict, Req, AnyResp, AckRelaxed, BadReq], 0),
        };
        for &step in order {
            let r = match step {
                Req => map(self.req_at(b, 0, at_end, true), Found::Request),
                ReqBreak => match self.req_at(b, 0, at_end, true) {
                    // only a request of known length after its break beats the answer reading
                    Cand::Match(r) if r.skip == 0 || searched(b, r.skip) => Cand::No,
                    other => map(other, Found::Request),
                },
                BadReq => map(self.bad_req_at(b, at_end), Found::Request),
                StrayAck | AckStrict => map(self.ack_at(b, 0, at_end, Relax::No), |two| {
                    Found::Ack { two }
                }),
                AckRelaxed => map(self.ack_at(b, 0, at_end, Relax::Any), |two| Found::Ack {
                    two,
                }),
                AckBreak if self.breaks_seen => {
                    map(self.ack_at(b, 0, at_end, Relax::Break), |two| Found::Ack {
                        two,
                    })
                }
                AckBreak => Cand::No,
                OtherResp | AnyResp if !self.fresh => Cand::No,
                Resp => match resp_at(b, 0, n, at_end) {
                    // (parity mode: a 00 after a telegram is no break, see tail_dominated)
                    Cand::Match(()) if !self.parity => Cand::Match(Found::Response {
                        len: n,
                        crc_ok: true,
                        mismatch: false,
                    }),
                    Cand::Match(()) => match tail_dominated(b, n + 2, at_end, self.memo()) {
                        Cand::Match(()) => Cand::No,
                        Cand::More => Cand::More,
                        Cand::No => Cand::Match(Found::Response {
                            len: n,
                            crc_ok: true,
                            mismatch: false,
                        }),
                    },
                    other => map(other, |()| Found::Response {
                        len: n,
                        crc_ok: true,
                        mismatch: false,
                    }),
                },
                OtherResp => map(self.clean_search(b, at_end, Some(n)), |len| {
                    Found::Response {
                        len,
                        crc_ok: true,
                        mismatch: true,
                    }
                }),
                AnyResp => map(self.clean_search(b, at_end, None), |len| Found::Response {
                    len,
                    crc_ok: true,
                    mismatch: false,
                }),
                BadResp => {
                    if b.len() < n + 2 {
                        if at_end { Cand::No } else { Cand::More }
                    } else {
                        let ok = match self.boundary(b, n + 2, at_end) {
                            Cand::Match(()) => self.clean_inside(b, n + 2, at_end, self.memo()),
                            other => other,
                        };
                        map(ok, |()| Found::Response {
                            len: n,
                            crc_ok: false,
                            mismatch: false,
                        })
                    }
                }
            };
            match r {
                Cand::No => continue,
                other => return other,
            }
        }
        Cand::No
    }

    /// The readings while an answer of known length is awaited. After the master timeout a
    /// new request (with its break) is read first; without breaks (parity mode) a request and
    /// a late response cannot be told apart by their CRC, so the answer reading stays first
    /// (docs/sbus.md).
    fn answer_order(&self) -> &'static [Step] {
        use Step::*;
        let expired = self.breaks_seen
            && matches!(
                (self.timeout, self.req_time, self.times.get(self.head)),
                (Some(to), Some(rt), Some(Some(t))) if *t > rt.saturating_add(to)
            );
        if expired {
            &[
                ReqBreak, Resp, AckStrict, OtherResp, BadReq, AckBreak, BadResp, AckRelaxed,
            ]
        } else {
            &[
                Resp, AckStrict, Req, OtherResp, AckBreak, BadResp, AckRelaxed, BadReq,
            ]
        }
    }

    /// Break characters tried before a request, in order of preference. In SM0 a request
    /// follows a break (one 0x00 from a raw-mode UART, sometimes two). A CRC-16 with init 0
    /// ignores leading zero bytes, so when `00 00 st cmd …` checks with two break characters
    /// it also checks as station 0 with one (when the lengths agree): the reading that skips
    /// the most zeros wins, which makes station-0 requests need their own CRC to decide.
    fn skips(&self, allow_break: bool) -> &'static [usize] {
        if self.parity || !allow_break {
            &[0]
        } else {
            &[2, 1, 0]
        }
    }

    /// A request at `k` (after up to two break characters in SM0).
    fn req_at(&self, b: &[u8], k: usize, at_end: bool, allow_break: bool) -> Cand<ReqAt> {
        for &skip in self.skips(allow_break) {
            if skip > 0 {
                match b.get(k..k + skip) {
                    Some(z) if z.iter().all(|&x| x == 0) => {}
                    Some(_) => continue,
                    None => {
                        if at_end {
                            continue;
                        }
                        return Cand::More;
                    }
                }
            }
            match request_len(b, k + skip, at_end, self.memo()) {
                Cand::Match((body, true)) => {
                    match zero_dominated(b, k + skip, at_end, self.memo()) {
                        Cand::Match(()) => continue,
                        Cand::More => return Cand::More,
                        Cand::No => {}
                    }
                    if searched(b, k + skip) {
                        // A CRC-16 with init 0 has residue 0 over a whole telegram, so a
                        // search can also check across complete telegrams: refuse that.
                        match self.clean_inside(
                            &b[k + skip..],
                            2 + body + 2,
                            at_end,
                            self.memo().at(k + skip),
                        ) {
                            Cand::Match(()) => {}
                            Cand::More => return Cand::More,
                            Cand::No => continue,
                        }
                    }
                    return Cand::Match(ReqAt {
                        skip,
                        body,
                        crc_ok: true,
                    });
                }
                Cand::More => return Cand::More,
                _ => {}
            }
        }
        Cand::No
    }

    /// A request of known length whose CRC fails, accepted when a telegram (or silence)
    /// follows right after it.
    fn bad_req_at(&self, b: &[u8], at_end: bool) -> Cand<ReqAt> {
        for &skip in self.skips(true) {
            match b.get(..skip) {
                Some(z) if z.iter().all(|&x| x == 0) => {}
                Some(_) => continue,
                None => {
                    if at_end {
                        continue;
                    }
                    return Cand::More;
                }
            }
            match request_len(b, skip, at_end, self.memo()) {
                Cand::Match((body, false)) => {
                    let r = ReqAt {
                        skip,
                        body,
                        crc_ok: false,
                    };
                    // (the boundary first: it is cheap and rules out most garbage)
                    let ok = match self.boundary(b, r.total(), at_end) {
                        Cand::Match(()) => self.clean_inside(b, r.total(), at_end, self.memo()),
                        other => other,
                    };
                    match ok {
                        Cand::Match(()) => return Cand::Match(r),
                        Cand::More => return Cand::More,
                        Cand::No => {}
                    }
                }
                Cand::More => return Cand::More,
                _ => {}
            }
        }
        Cand::No
    }

    /// A single-character ACK/NAK at `k` (optionally followed by 00), accepted when silence
    /// or the next request follows it: a data byte 06/15 is not taken for an answer.
    /// `relaxed`: a following request with a bad CRC (a bit error) also confirms it
    /// (`Relax::Break`: only one after a break character).
    fn ack_at(&self, b: &[u8], k: usize, at_end: bool, relaxed: Relax) -> Cand<bool> {
        match b.get(k) {
            Some(&ACK_CHAR) | Some(&NAK_CHAR) => {}
            Some(_) => return Cand::No,
            None => return if at_end { Cand::No } else { Cand::More },
        }
        let passes: &[Relax] = match relaxed {
            Relax::No => &[Relax::No],
            Relax::Break => &[Relax::No, Relax::Break],
            Relax::Any => &[Relax::No, Relax::Any],
        };
        // `06 00` first: with the 00 kept for the request, `00 st cmd …` could check as
        // station 0 only because the CRC ignores leading zeros (see `skips`).
        if b.len() == k + 1 && !at_end {
            return Cand::More;
        }
        // In break mode the 00 is the next request's break (the request reading skips it).
        let order: &[usize] = if self.parity { &[2, 1] } else { &[1, 2] };
        for &pass in passes {
            for &n in order {
                if n == 2 && b.get(k + 1) != Some(&0) {
                    continue;
                }
                match self.follow(b, k + n, at_end, pass) {
                    Cand::Match(()) => return Cand::Match(n == 2),
                    Cand::More => return Cand::More,
                    Cand::No => {}
                }
            }
        }
        Cand::No
    }

    /// What may follow an answer at `e`: silence, a request, or (relaxed) a request of known
    /// length whose CRC fails.
    fn follow(&self, b: &[u8], e: usize, at_end: bool, relaxed: Relax) -> Cand<()> {
        match self.next_request(b, e, at_end) {
            Cand::No if relaxed != Relax::No => {
                for &skip in self.skips(true) {
                    if relaxed == Relax::Break && skip == 0 {
                        continue;
                    }
                    if b.get(e..e + skip)
                        .is_some_and(|z| z.iter().all(|&x| x == 0))
                        && let Cand::Match(_) = request_len(b, e + skip, at_end, self.memo())
                    {
                        return Cand::Match(());
                    }
                }
                Cand::No
            }
            other => other,
        }
    }

    /// Silence (the end of the buffered bytes at a gap or the end of input) or a request at `e`.
    fn next_request(&self, b: &[u8], e: usize, at_end: bool) -> Cand<()> {
        if b.len() == e {
            return if at_end { Cand::Match(()) } else { Cand::More };
        }
        map(self.req_at(b, e, at_end, true), |_| ())
    }

    /// Whether the end of a bad-CRC reading at `e` is confirmed: silence after it, or a
    /// request (with its break, once breaks were seen) or an ACK/NAK starting there.
    fn boundary(&self, b: &[u8], e: usize, at_end: bool) -> Cand<()> {
        if b.len() == e {
            return if at_end { Cand::Match(()) } else { Cand::More };
        }
        match self.req_at(b, e, at_end, true) {
            Cand::Match(r) if r.skip == 0 && self.breaks_seen => Cand::No,
            Cand::Match(_) => Cand::Match(()),
            Cand::More => Cand::More,
            Cand::No => map(self.ack_at(b, e, at_end, Relax::No), |_| ()),
        }
    }

    /// A bad-CRC reading of `0..end` is only taken when no valid request starts inside it.
    /// (`memo`: for `b`, which may start after [`Self::avail`].)
    fn clean_inside(&self, b: &[u8], end: usize, at_end: bool, memo: Memo<'_>) -> Cand<()> {
        // Only requests of known length count here, which keeps the work bounded (no search
        // inside a search).
        for j in 1..end {
            if searched(b, j) {
                continue;
            }
            match request_len(b, j, at_end, memo) {
                Cand::Match((_, true)) => match zero_dominated(b, j, at_end, memo) {
                    Cand::Match(()) => {}
                    Cand::More => return Cand::More,
                    Cand::No => return Cand::No,
                },
                Cand::More => return Cand::More,
                _ => {}
            }
        }
        Cand::Match(())
    }

    /// [`Self::search_resp`], refusing a length that spans a valid request, and taking it only
    /// when a boundary (silence, a request, an ACK/NAK) follows: a CRC found by searching
    /// needs that second confirmation.
    fn clean_search(&self, b: &[u8], at_end: bool, expected: Option<usize>) -> Cand<usize> {
        match self.search_resp(b, at_end, expected) {
            Cand::Match(len) => match self.boundary(b, len + 2, at_end) {
                Cand::Match(()) => {
                    map(self.clean_inside(b, len + 2, at_end, self.memo()), |()| len)
                }
                other => map(other, |()| len),
            },
            other => other,
        }
    }

    /// A response found by its CRC alone: the shortest plausible length (or any length up to
    /// 256 when `expected` is `None`) other than `expected`.
    fn search_resp(&self, b: &[u8], at_end: bool, expected: Option<usize>) -> Cand<usize> {
        let max = if expected.is_some() { 128 } else { 256 };
        let mut crc = 0u16;
        for len in 1..=max {
            let Some(&byte) = b.get(len - 1) else {
                return if at_end { Cand::No } else { Cand::More };
            };
            crc = crc_step(crc, byte);
            if Some(len) == expected || (expected.is_some() && !plausible_response_len(len)) {
                continue;
            }
            match (b.get(len), b.get(len + 1)) {
                (Some(&h), Some(&l)) => {
                    if u16::from_be_bytes([h, l]) == crc {
                        return Cand::Match(len);
                    }
                }
                _ => return if at_end { Cand::No } else { Cand::More },
            }
        }
        Cand::No
    }

    fn take(&mut self, found: Found, emit: &mut impl FnMut(&Event<'_>)) {
        self.garbage.flush(emit);
        let start = self.head;
        let time = self.times[start];
        let offset = self.base;
        let (total, frame) = {
            let b = &self.buf[start..];
            match found {
                Found::Request(r) => {
                    let s = r.skip;
                    let covered = &b[s..s + 2 + r.body];
                    let got = u16::from_be_bytes([b[s + 2 + r.body], b[s + 3 + r.body]]);
                    let want = crc16(covered);
                    let tele = Tele::Request {
                        station: b[s],
                        cmd: b[s + 1],
                        body: &b[s + 2..s + 2 + r.body],
                    };
                    (
                        r.total(),
                        Frame {
                            time,
                            offset,
                            wire: &b[..r.total()],
                            tele,
                            crc: crc_of(got, want),
                            secure: None,
                            problem: None,
                            break_before: s > 0,
                            length_mismatch: false,
                        },
                    )
                }
                Found::Response {
                    len,
                    crc_ok: _,
                    mismatch,
                } => {
                    let got = u16::from_be_bytes([b[len], b[len + 1]]);
                    let want = crc16(&b[..len]);
                    (
                        len + 2,
                        Frame {
                            time,
                            offset,
                            wire: &b[..len + 2],
                            tele: Tele::Response { data: &b[..len] },
                            crc: crc_of(got, want),
                            secure: None,
                            problem: None,
                            break_before: false,
                            length_mismatch: mismatch,
                        },
                    )
                }
                Found::Ack { two } => {
                    let n = if two { 2 } else { 1 };
                    (
                        n,
                        Frame {
                            time,
                            offset,
                            wire: &b[..n],
                            tele: Tele::AckNak {
                                code: if b[0] == ACK_CHAR { 0 } else { 1 },
                                short: Some((b[0], two)),
                            },
                            crc: CrcCheck::None,
                            secure: None,
                            problem: None,
                            break_before: false,
                            length_mismatch: false,
                        },
                    )
                }
            }
        };
        emit(&Event::Frame(frame));
        if let Found::Request(r) = found {
            self.req_time = time;
            if r.skip > 0 {
                self.breaks_seen = true;
            }
        }
        self.awaiting = match frame.tele {
            Tele::Request { station, cmd, body } => match expect_of(station, cmd, body) {
                Expect::Nothing => Await::Request,
                e => Await::Answer(e),
            },
            _ => Await::Request,
        };
        self.fresh = matches!(self.awaiting, Await::Answer(_));
        self.head += total;
        self.base += total as u64;
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Req,
    ReqBreak,
    BadReq,
    StrayAck,
    AckStrict,
    AckRelaxed,
    AckBreak,
    Resp,
    OtherResp,
    AnyResp,
    BadResp,
}

/// How an ACK/NAK character's end is confirmed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Relax {
    /// Silence or a request with a good CRC.
    No,
    /// Also a request of known length with a bad CRC after a break character.
    Break,
    /// Also any request of known length with a bad CRC.
    Any,
}

#[cfg(test)]
mod tests;
