//! Pure reassemblers for serial S-Bus: bytes and times in, telegrams out, no I/O.
//!
//! * [`DataFramer`]: SM2 data mode and the secure data mode. A raw 0xB5 starts every telegram
//!   (inside a telegram B5 and C5 travel as the DLE pairs `C5 00` / `C5 01`). A telegram ends
//!   at the next raw B5, at a time gap, at the end of the input, or as soon as its length is
//!   known and its CRC checks (requests: the command table; ACK/NAK: 2 bytes; responses: the
//!   length the last request asked for; secure telegrams: their LEN byte).
//! * [`BreakFramer`]: SM0 break mode and SM1 parity mode, which have no framing bytes. The
//!   boundaries are found from what is known: the command table's request lengths, the response
//!   length the last request asked for, the CRC, the single-character ACK (06) / NAK (15), a
//!   leading 0x00 (a break as a raw-mode UART reports it) and time gaps when the source has
//!   timestamps. See `docs/sbus.md` for what cannot be recovered.
//!
//! Both framers track the last request themselves, so their output depends only on the bytes
//! and their times, never on how the input was split into chunks.

use super::commands::{self, Expect};
use super::telegram::{
    ACK_CHAR, AT_ACKNAK, AT_REQUEST, AT_RESPONSE, AT_SECURE_REQUEST, AT_SECURE_RESPONSE, BROADCAST,
    CrcBasis, DLE, FS, NAK_CHAR, crc_step, crc16,
};

/// Garbage is reported in runs of at most this many bytes.
pub const GARBAGE_ROW_MAX: usize = 64;
/// Longest data-mode telegram kept on the wire (longer ones are cut and reported).
pub const MAX_WIRE: usize = 1024;
/// Longest request body searched by CRC when the table does not know the length.
pub const MAX_SEARCH_BODY: usize = 255;

/// How a telegram's CRC turned out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrcCheck {
    /// Matched, over these bytes.
    Ok(CrcBasis),
    /// Matched neither reading: the CRC field and the values computed over the escaped and the
    /// unescaped bytes (equal without DLE pairs).
    Bad {
        got: u16,
        escaped: u16,
        unescaped: u16,
    },
    /// No CRC (single-character ACK/NAK), or too short to have one.
    None,
}

impl CrcCheck {
    pub fn ok(self) -> bool {
        matches!(self, CrcCheck::Ok(_))
    }
}

/// The secure data-mode header of a telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Secure {
    /// Outer AT: 0x10 request, 0x11 response.
    pub at: u8,
    pub len: u8,
    pub seq: u8,
    /// Logical length of the inner telegram actually received (a DLE pair counts once).
    pub actual: usize,
    /// SEQ 0xC5 sent without DLE escaping (old firmware, FAQ 101180).
    pub seq_unescaped: bool,
}

impl Secure {
    pub fn len_ok(&self) -> bool {
        self.len as usize == self.actual
    }
}

/// A telegram's meaning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tele<'a> {
    Request {
        station: u8,
        cmd: u8,
        body: &'a [u8],
    },
    Response {
        data: &'a [u8],
    },
    /// A data-mode ACK/NAK telegram (`code`), or a break/parity-mode character (`short`: the
    /// character, 06 or 15, and whether `00` followed it).
    AckNak {
        code: u16,
        short: Option<(u8, bool)>,
    },
    /// A data-mode telegram with an attribute busnoop does not know.
    Other {
        at: u8,
        payload: &'a [u8],
    },
    /// Too short to mean anything (a cut telegram).
    Broken,
}

/// One telegram as the framers deliver it.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// Arrival time of the first byte (µs since the capture started), when the source has times.
    pub time: Option<u64>,
    /// Position of the first byte in the stream.
    pub offset: u64,
    /// Bytes exactly as on the wire (secure header, DLE pairs, break character included).
    pub wire: &'a [u8],
    pub tele: Tele<'a>,
    pub crc: CrcCheck,
    pub secure: Option<Secure>,
    /// A framing problem: cut short, an invalid DLE pair, too long.
    pub problem: Option<&'static str>,
    /// Break/parity mode: a 0x00 (break) preceded the request.
    pub break_before: bool,
    /// Break/parity mode: a response whose length does not fit the request (found by CRC).
    pub length_mismatch: bool,
}

/// Bytes that belong to no telegram.
#[derive(Clone, Copy, Debug)]
pub struct Garbage<'a> {
    pub time: Option<u64>,
    pub offset: u64,
    pub bytes: &'a [u8],
}

/// What the framers emit.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    Frame(Frame<'a>),
    Garbage(Garbage<'a>),
}

/// Splits a standard telegram's logical bytes `AT payload CRC` into its meaning.
fn classify(at: u8, payload: &[u8]) -> Tele<'_> {
    match at {
        AT_REQUEST if payload.len() >= 2 => Tele::Request {
            station: payload[0],
            cmd: payload[1],
            body: &payload[2..],
        },
        AT_RESPONSE => Tele::Response { data: payload },
        AT_ACKNAK if payload.len() == 2 => Tele::AckNak {
            code: u16::from_be_bytes([payload[0], payload[1]]),
            short: None,
        },
        AT_REQUEST | AT_ACKNAK => Tele::Broken,
        _ => Tele::Other { at, payload },
    }
}

/// The answer a request expects, as the framers need it.
fn expect_of(station: u8, cmd: u8, body: &[u8]) -> Expect {
    if station == BROADCAST {
        return Expect::Nothing;
    }
    match commands::command(cmd) {
        Some(c) => commands::expected_data_len(&c, body),
        None => Expect::Unknown,
    }
}

/// Time-gap rule shared by both framers.
#[derive(Clone, Copy, Debug, Default)]
struct GapClock {
    gap: Option<u64>,
    last: Option<u64>,
}

impl GapClock {
    /// True when a byte at `time` follows the previous one after more than the gap.
    fn gap_before(&mut self, time: Option<u64>) -> bool {
        let Some(t) = time else { return false };
        let gap = match (self.gap, self.last) {
            (Some(g), Some(last)) => t > last.saturating_add(g),
            _ => false,
        };
        self.last = Some(t);
        gap
    }

    fn idle(&self, now: u64) -> bool {
        matches!((self.gap, self.last), (Some(g), Some(last)) if now > last.saturating_add(g))
    }
}

/// Garbage collector shared by both framers.
#[derive(Clone, Debug, Default)]
struct GarbageRun {
    bytes: Vec<u8>,
    time: Option<u64>,
    offset: u64,
}

impl GarbageRun {
    fn push(&mut self, b: u8, time: Option<u64>, offset: u64, emit: &mut impl FnMut(&Event<'_>)) {
        if self.bytes.is_empty() {
            self.time = time;
            self.offset = offset;
        }
        self.bytes.push(b);
        if self.bytes.len() == GARBAGE_ROW_MAX {
            self.flush(emit);
        }
    }

    fn flush(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if !self.bytes.is_empty() {
            emit(&Event::Garbage(Garbage {
                time: self.time,
                offset: self.offset,
                bytes: &self.bytes,
            }));
            self.bytes.clear();
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Outside a telegram: bytes are garbage until the next raw B5.
    Outside,
    /// After the FS: the next logical byte is the AT.
    At,
    SecLen,
    SecSeq,
    /// Secure header complete: the inner telegram's raw B5 must follow.
    InnerFs,
    /// Collecting the standard telegram's logical bytes (AT included).
    Body,
}

/// Pure SM2 / secure data-mode reassembler.
#[derive(Clone, Debug)]
pub struct DataFramer {
    phase: Phase,
    dle: bool,
    wire: Vec<u8>,
    /// Logical bytes of the standard telegram after its FS: AT, payload, CRC.
    tele: Vec<u8>,
    /// Offset in `wire` where each logical byte of `tele` starts.
    tele_at: Vec<u16>,
    /// Offset in `wire` of the standard telegram's FS (0, or after the secure header).
    tele_fs: usize,
    secure: Option<Secure>,
    problem: Option<&'static str>,
    /// A secure header was not followed by the inner telegram's B5.
    no_inner: bool,
    time: Option<u64>,
    offset: u64,
    pos: u64,
    garbage: GarbageRun,
    clock: GapClock,
    /// What the last request asked for (for responses, which carry no length).
    expect: Expect,
}

impl DataFramer {
    /// `gap`: a silence longer than this (µs) ends an open telegram (sources with time only).
    pub fn new(gap: Option<u64>) -> Self {
        DataFramer {
            phase: Phase::Outside,
            dle: false,
            wire: Vec::with_capacity(MAX_WIRE),
            tele: Vec::with_capacity(MAX_WIRE),
            tele_at: Vec::with_capacity(MAX_WIRE),
            tele_fs: 0,
            secure: None,
            problem: None,
            no_inner: false,
            time: None,
            offset: 0,
            pos: 0,
            garbage: GarbageRun::default(),
            clock: GapClock { gap, last: None },
            expect: Expect::Nothing,
        }
    }

    /// Feeds `data` that arrived at `time`.
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        for &b in data {
            if self.clock.gap_before(time) {
                self.close(emit);
                self.garbage.flush(emit);
            }
            self.byte(b, time, emit);
            self.pos += 1;
        }
    }

    /// Time passed without data: a silence longer than the gap ends an open telegram.
    pub fn idle(&mut self, now: u64, emit: &mut impl FnMut(&Event<'_>)) {
        if self.clock.idle(now) {
            self.close(emit);
            self.garbage.flush(emit);
        }
    }

    /// End of input.
    pub fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.close(emit);
        self.garbage.flush(emit);
    }

    fn start(&mut self, time: Option<u64>) {
        self.phase = Phase::At;
        self.dle = false;
        self.wire.clear();
        self.wire.push(FS);
        self.tele.clear();
        self.tele_at.clear();
        self.tele_fs = 0;
        self.secure = None;
        self.problem = None;
        self.no_inner = false;
        self.time = time;
        self.offset = self.pos;
    }

    fn byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if b == FS {
            if self.phase == Phase::InnerFs {
                self.inner_fs();
                return;
            }
            if self.dle && self.phase == Phase::SecSeq {
                // `C5 B5`: SEQ 0xC5 sent unescaped by old firmware (FAQ 101180).
                self.dle = false;
                if let Some(s) = self.secure.as_mut() {
                    s.seq = DLE;
                    s.seq_unescaped = true;
                }
                self.inner_fs();
                return;
            }
            if self.phase != Phase::Outside {
                if self.dle {
                    self.problem = Some("DLE (C5) at the end of the telegram");
                }
                self.close(emit);
            }
            self.garbage.flush(emit);
            self.start(time);
            return;
        }
        if self.phase == Phase::Outside {
            self.garbage.push(b, time, self.pos, emit);
            return;
        }
        if self.wire.len() >= MAX_WIRE {
            self.problem = Some("longer than any S-Bus telegram");
            self.close(emit);
            self.garbage.push(b, time, self.pos, emit);
            return;
        }
        let at = self.wire.len();
        self.wire.push(b);
        if self.dle {
            self.dle = false;
            match b {
                0x00 => self.logical(FS, at - 1, emit),
                0x01 => self.logical(DLE, at - 1, emit),
                _ => {
                    self.problem = Some("invalid DLE pair (C5 not followed by 00 or 01)");
                    self.logical(DLE, at - 1, emit);
                    if self.phase == Phase::Outside {
                        return;
                    }
                    if b == DLE {
                        self.dle = true;
                    } else {
                        self.logical(b, at, emit);
                    }
                }
            }
        } else if b == DLE {
            self.dle = true;
        } else {
            self.logical(b, at, emit);
        }
    }

    fn inner_fs(&mut self) {
        self.wire.push(FS);
        self.tele_fs = self.wire.len() - 1;
        self.phase = Phase::Body;
        // The inner AT follows; `tele` starts with it.
        self.tele.clear();
        self.tele_at.clear();
    }

    fn logical(&mut self, v: u8, wire_at: usize, emit: &mut impl FnMut(&Event<'_>)) {
        match self.phase {
            Phase::Outside => {}
            Phase::At => {
                if v == AT_SECURE_REQUEST || v == AT_SECURE_RESPONSE {
                    self.secure = Some(Secure {
                        at: v,
                        len: 0,
                        seq: 0,
                        actual: 0,
                        seq_unescaped: false,
                    });
                    self.phase = Phase::SecLen;
                } else {
                    self.phase = Phase::Body;
                    self.push_tele(v, wire_at, emit);
                }
            }
            Phase::SecLen => {
                if let Some(s) = self.secure.as_mut() {
                    s.len = v;
                }
                self.phase = Phase::SecSeq;
            }
            Phase::SecSeq => {
                if let Some(s) = self.secure.as_mut() {
                    s.seq = v;
                }
                self.phase = Phase::InnerFs;
            }
            Phase::InnerFs => {
                // The secure header is not followed by a telegram: keep the bytes and report
                // the frame as broken when it ends.
                self.problem = Some(NO_INNER_TELEGRAM);
                self.no_inner = true;
                self.phase = Phase::Body;
                self.tele_fs = wire_at;
                self.push_tele(v, wire_at, emit);
            }
            Phase::Body => self.push_tele(v, wire_at, emit),
        }
    }

    fn push_tele(&mut self, v: u8, wire_at: usize, emit: &mut impl FnMut(&Event<'_>)) {
        self.tele.push(v);
        self.tele_at.push(wire_at as u16);
        if self.complete_len() == Some(self.tele.len())
            && (self.secure.is_some() || self.crc_check().ok())
        {
            self.close(emit);
        }
    }

    /// The logical length (AT … CRC) the open telegram must have, when known.
    fn complete_len(&self) -> Option<usize> {
        if let Some(s) = &self.secure {
            // LEN counts the inner FS too.
            return (s.len as usize).checked_sub(1).filter(|&n| n > 0);
        }
        let t = &self.tele;
        match *t.first()? {
            AT_ACKNAK => Some(1 + 2 + 2),
            AT_REQUEST => {
                if t.len() < 3 {
                    return None;
                }
                let cmd = commands::command(t[2])?;
                let body = &t[3..];
                match cmd.layout.body_len(body)? {
                    Ok(n) => Some(1 + 2 + n + 2),
                    Err(_) => None,
                }
            }
            AT_RESPONSE => match self.expect {
                Expect::Data(n) => Some(1 + n + 2),
                Expect::LengthPrefixed => t.get(1).map(|&n| 1 + 1 + n as usize + 2),
                _ => None,
            },
            _ => None,
        }
    }

    /// Checks the CRC of the open standard telegram both ways.
    fn crc_check(&self) -> CrcCheck {
        let n = self.tele.len();
        if n < 3 {
            return CrcCheck::None;
        }
        let got = u16::from_be_bytes([self.tele[n - 2], self.tele[n - 1]]);
        let mut d = super::telegram::CRC.digest();
        d.update(&[FS]);
        d.update(&self.tele[..n - 2]);
        let unescaped = d.finalize();
        let crc_wire = self.tele_at[n - 2] as usize;
        let escaped = crc16(&self.wire[self.tele_fs..crc_wire]);
        if got == escaped && got == unescaped {
            CrcCheck::Ok(CrcBasis::Both)
        } else if got == escaped {
            CrcCheck::Ok(CrcBasis::Escaped)
        } else if got == unescaped {
            CrcCheck::Ok(CrcBasis::Unescaped)
        } else {
            CrcCheck::Bad {
                got,
                escaped,
                unescaped,
            }
        }
    }

    /// Ends the open telegram (if any) and emits it.
    fn close(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if self.phase == Phase::Outside {
            return;
        }
        let mut problem = self.problem;
        if self.dle {
            problem = problem.or(Some("DLE (C5) at the end of the telegram"));
        }
        let mut secure = self.secure;
        if let Some(s) = secure.as_mut() {
            s.actual = if self.phase == Phase::Body {
                self.tele.len() + 1
            } else {
                0
            };
            if !s.len_ok() && problem.is_none() {
                problem = Some(if s.actual < s.len as usize {
                    "secure telegram shorter than its LEN"
                } else {
                    "secure telegram longer than its LEN"
                });
            }
        }
        // A secure header without the inner telegram's B5 is malformed, whatever a CRC over an
        // assumed B5 would say: it is shown as broken, never as a telegram.
        let (tele, crc) = if self.phase == Phase::Body && self.tele.len() >= 3 && !self.no_inner {
            let n = self.tele.len();
            let crc = self.crc_check();
            (classify(self.tele[0], &self.tele[1..n - 2]), crc)
        } else {
            problem = problem.or(Some("cut short"));
            (Tele::Broken, CrcCheck::None)
        };
        if crc.ok() {
            match tele {
                Tele::Request { station, cmd, body } => {
                    self.expect = expect_of(station, cmd, body);
                }
                Tele::Response { .. } | Tele::AckNak { .. } => self.expect = Expect::Nothing,
                _ => {}
            }
        }
        emit(&Event::Frame(Frame {
            time: self.time,
            offset: self.offset,
            wire: &self.wire,
            tele,
            crc,
            secure,
            problem,
            break_before: false,
            length_mismatch: false,
        }));
        self.phase = Phase::Outside;
        self.dle = false;
    }
}

/// The problem noted when a secure header is not followed by a telegram.
const NO_INNER_TELEGRAM: &str = "secure header not followed by a telegram (B5)";

/// What the break/parity framer waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Await {
    /// A request (nothing outstanding).
    Request,
    /// The answer to the last request.
    Answer(Expect),
}

/// Result of testing one reading of the buffered bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Cand<T> {
    Match(T),
    No,
    More,
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

/// Lengths tried when a response does not fit the request and is looked for by its CRC:
/// what the command table's replies can be (1-16 bytes, 26, and whole registers up to 32).
fn plausible_response_len(n: usize) -> bool {
    n <= 16 || n == 26 || (n.is_multiple_of(4) && n <= 128)
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
}

impl BreakFramer {
    /// `parity`: SM1 (no break characters); `gap`: silence (µs) that ends a telegram;
    /// `timeout`: the master timeout (µs).
    pub fn new(parity: bool, gap: Option<u64>, timeout: Option<u64>) -> Self {
        BreakFramer {
            timeout,
            req_time: None,
            breaks_seen: false,
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
        // Feed byte by byte so that decisions never see more bytes than the shortest
        // chunking would have given them (they do not depend on it, but this keeps the
        // buffer small and the work per byte bounded).
        for &b in data {
            self.compact();
            self.buf.push(b);
            self.times.push(time);
            self.resolve(false, emit);
        }
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
        let mut order: [Option<Step>; 8] = [None; 8];
        use Step::*;
        // After the master timeout a new request (with its break) is read first; without
        // breaks (parity mode) a request and a late response cannot be told apart by their
        // CRC, so the answer reading stays first (docs/sbus.md).
        let expired = self.breaks_seen
            && matches!(
                (self.timeout, self.req_time, self.times.get(self.head)),
                (Some(to), Some(rt), Some(Some(t))) if *t > rt.saturating_add(to)
            );
        let answer = |n| {
            if expired {
                [
                    Some(ReqBreak),
                    Some(Resp(n)),
                    Some(AckStrict),
                    self.fresh.then_some(OtherResp(n)),
                    Some(BadReq),
                    Some(AckBreak),
                    Some(BadResp(n)),
                    Some(AckRelaxed),
                ]
            } else {
                [
                    Some(Resp(n)),
                    Some(AckStrict),
                    Some(Req),
                    self.fresh.then_some(OtherResp(n)),
                    Some(AckBreak),
                    Some(BadResp(n)),
                    Some(AckRelaxed),
                    Some(BadReq),
                ]
            }
        };
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
        match awaiting {
            Await::Request | Await::Answer(Expect::Nothing) => {
                order[..3].copy_from_slice(&[Some(Req), Some(BadReq), Some(StrayAck)]);
            }
            Await::Answer(Expect::AckNak) => {
                order[..3].copy_from_slice(&[Some(AckRelaxed), Some(Req), Some(BadReq)]);
            }
            Await::Answer(Expect::Data(n)) => order = answer(n),
            Await::Answer(Expect::LengthPrefixed) => {
                let Some(&n) = b.first() else {
                    return Cand::More;
                };
                order = answer(1 + n as usize);
            }
            Await::Answer(Expect::Unknown) => {
                order[..5].copy_from_slice(&[
                    Some(AckStrict),
                    Some(Req),
                    self.fresh.then_some(AnyResp),
                    Some(AckRelaxed),
                    Some(BadReq),
                ]);
            }
        }
        for step in order.into_iter().flatten() {
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
                Resp(n) => match resp_at(b, 0, n, at_end) {
                    // (parity mode: a 00 after a telegram is no break, see tail_dominated)
                    Cand::Match(()) if !self.parity => Cand::Match(Found::Response {
                        len: n,
                        crc_ok: true,
                        mismatch: false,
                    }),
                    Cand::Match(()) => match tail_dominated(b, n + 2, at_end) {
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
                OtherResp(n) => map(self.clean_search(b, at_end, Some(n)), |len| {
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
                BadResp(n) => {
                    if b.len() < n + 2 {
                        if at_end { Cand::No } else { Cand::More }
                    } else {
                        let ok = match self.boundary(b, n + 2, at_end) {
                            Cand::Match(()) => self.clean_inside(b, n + 2, at_end),
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
            match request_len(b, k + skip, at_end) {
                Cand::Match((body, true)) => {
                    match zero_dominated(b, k + skip, at_end) {
                        Cand::Match(()) => continue,
                        Cand::More => return Cand::More,
                        Cand::No => {}
                    }
                    if searched(b, k + skip) {
                        // A CRC-16 with init 0 has residue 0 over a whole telegram, so a
                        // search can also check across complete telegrams: refuse that.
                        match self.clean_inside(&b[k + skip..], 2 + body + 2, at_end) {
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
            match request_len(b, skip, at_end) {
                Cand::Match((body, false)) => {
                    let r = ReqAt {
                        skip,
                        body,
                        crc_ok: false,
                    };
                    // (the boundary first: it is cheap and rules out most garbage)
                    let ok = match self.boundary(b, r.total(), at_end) {
                        Cand::Match(()) => self.clean_inside(b, r.total(), at_end),
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
                        && let Cand::Match(_) = request_len(b, e + skip, at_end)
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
    fn clean_inside(&self, b: &[u8], end: usize, at_end: bool) -> Cand<()> {
        // Only requests of known length count here, which keeps the work bounded (no search
        // inside a search).
        for j in 1..end {
            if searched(b, j) {
                continue;
            }
            match request_len(b, j, at_end) {
                Cand::Match((_, true)) => match zero_dominated(b, j, at_end) {
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
                Cand::Match(()) => map(self.clean_inside(b, len + 2, at_end), |()| len),
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
    Resp(usize),
    OtherResp(usize),
    AnyResp,
    BadResp(usize),
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

fn map<T, U>(c: Cand<T>, f: impl FnOnce(T) -> U) -> Cand<U> {
    match c {
        Cand::Match(t) => Cand::Match(f(t)),
        Cand::No => Cand::No,
        Cand::More => Cand::More,
    }
}

fn crc_of(got: u16, want: u16) -> CrcCheck {
    if got == want {
        CrcCheck::Ok(CrcBasis::Both)
    } else {
        CrcCheck::Bad {
            got,
            escaped: want,
            unescaped: want,
        }
    }
}

/// A response of `n` data bytes + CRC at `k` with a good CRC.
fn resp_at(b: &[u8], k: usize, n: usize, at_end: bool) -> Cand<()> {
    if b.len() < k + n + 2 {
        return if at_end { Cand::No } else { Cand::More };
    }
    let got = u16::from_be_bytes([b[k + n], b[k + n + 1]]);
    if crc16(&b[k..k + n]) == got {
        Cand::Match(())
    } else {
        Cand::No
    }
}

/// A valid request reading `00 X …` at `s` is dominated by a valid reading at `s + 1`: a
/// CRC-16 with init 0 ignores a leading zero, and a telegram whose CRC ends in 00 also checks
/// one byte earlier when a 00 (a break, or the previous telegram's last byte) precedes it.
fn zero_dominated(b: &[u8], s: usize, at_end: bool) -> Cand<()> {
    if b.get(s) != Some(&0) {
        return Cand::No;
    }
    match request_len(b, s + 1, at_end) {
        Cand::Match((_, true)) => Cand::Match(()),
        Cand::More => Cand::More,
        _ => Cand::No,
    }
}

/// Parity mode: a response reading of `0..end` is dominated by a request reading of
/// `0..end + 1` when the next byte is 00. A telegram whose CRC ends in 00 also checks without
/// that byte (and any telegram followed by 00 checks with it): without breaks, a 00 there is
/// more likely the CRC's last byte than a station-0 request.
fn tail_dominated(b: &[u8], end: usize, at_end: bool) -> Cand<()> {
    match b.get(end) {
        None => {
            if at_end {
                Cand::No
            } else {
                Cand::More
            }
        }
        Some(0) => match request_len(b, 0, at_end) {
            Cand::Match((body, true)) if 2 + body + 2 == end + 1 => Cand::Match(()),
            Cand::More => Cand::More,
            _ => Cand::No,
        },
        Some(_) => Cand::No,
    }
}

/// Whether the request at `s` has a command whose length the table does not know.
fn searched(b: &[u8], s: usize) -> bool {
    b.get(s + 1)
        .and_then(|&c| commands::command(c))
        .is_some_and(|c| c.layout.body_len(&[]).is_none())
}

/// The body length of a request starting at `s` and whether its CRC checks. Known lengths
/// come from the command table; commands without a known layout are searched by CRC.
fn request_len(b: &[u8], s: usize, at_end: bool) -> Cand<(usize, bool)> {
    let more = if at_end { Cand::No } else { Cand::More };
    let Some(&cmd) = b.get(s + 1) else {
        return more;
    };
    let Some(command) = commands::command(cmd) else {
        return Cand::No;
    };
    let body = b.get(s + 2..).unwrap_or(&[]);
    match command.layout.body_len(body) {
        Some(Ok(n)) => {
            if b.len() < s + 2 + n + 2 {
                return more;
            }
            let got = u16::from_be_bytes([b[s + 2 + n], b[s + 3 + n]]);
            Cand::Match((n, crc16(&b[s..s + 2 + n]) == got))
        }
        Some(Err(_)) => more,
        None => {
            let mut crc = crc_step(crc_step(0, b[s]), cmd);
            for n in 0..=MAX_SEARCH_BODY {
                if n > 0 {
                    match b.get(s + 1 + n) {
                        Some(&x) => crc = crc_step(crc, x),
                        None => return more,
                    }
                }
                match (b.get(s + 2 + n), b.get(s + 3 + n)) {
                    (Some(&h), Some(&l)) => {
                        if u16::from_be_bytes([h, l]) == crc {
                            return Cand::Match((n, true));
                        }
                    }
                    _ => return more,
                }
            }
            Cand::No
        }
    }
}
