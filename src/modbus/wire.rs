//! The pure Modbus RTU reassembler: bytes and times in, frames and broken bytes out, no I/O.
//!
//! RTU marks frames by 3.5 characters of silence, which a USB-serial adapter destroys (it
//! hands bytes over in transfers of 16-64 bytes, after a latency timer), so busnoop never
//! frames by silence. A frame is found by its content:
//!
//! * at each place, the frame's length is read twice: as a request and as a response
//!   ([`frame_len`]: fixed lengths, byte counts, Read Device Identification's
//!   objects). Requests and responses of functions 1-4 cannot be told apart by their first
//!   bytes, so both readings are tried;
//! * a reading is a frame when its CRC-16/MODBUS checks. When the pairing waits for a response
//!   of a known length from this slave and function, that reading is tried first; otherwise the
//!   shortest reading whose CRC checks wins. A longer reading that checks only because zero
//!   bytes follow a shorter one that checks is no evidence (the CRC of a frame followed by
//!   `00` bytes checks too: the stray-byte trap);
//! * when no reading checks, the place holds no frame; the bytes up to the next frame are
//!   sorted out ([`classify`]): a bad frame whose length reaches exactly the next frame (or
//!   up to three stray bytes before it) is `BadCRC`, a frame cut short by the next one is
//!   `Truncated`, and everything else is `Garbage`. A good frame is never lost to the bytes
//!   before it.
//!
//! Decisions depend only on the bytes and their times, never on how they were split into
//! chunks: a place is judged when every byte its readings need has arrived (or the input
//! ended). Times are a hint only, and only long ones count: a frame with the same bytes as the
//! request before it (the echo of a write) is its response, unless it came after the master
//! timeout (then it is the request sent again); and a silence of [`SETTLE_MIN`] (or 40
//! characters, at slow rates) settles whatever is held, as the end of the input would (no frame
//! pauses that long; a live line needs no more bytes to show a cut frame or a stray byte at its
//! end). Without times, nothing settles before the end.

use std::collections::VecDeque;

use crc::{CRC_16_MODBUS, Crc, Table};

use super::function::{Dir, Len, MAX_FRAME, MIN_FRAME, frame_len, plausible};
use crate::row::GARBAGE_ROW_MAX;

static CRC16: Crc<u16, Table<16>> = Crc::<u16, Table<16>>::new(&CRC_16_MODBUS);

/// CRC-16/MODBUS (reflected polynomial 0xA001, init 0xFFFF) of `bytes`.
pub fn crc16(bytes: &[u8]) -> u16 {
    CRC16.checksum(bytes)
}

/// Whether `frame`, its CRC included (low byte first), checks.
pub fn crc_ok(frame: &[u8]) -> bool {
    frame.len() >= 3 && CRC16.checksum(frame) == 0
}

/// Appends the CRC of `frame` (low byte first).
pub fn push_crc(frame: &mut Vec<u8>) {
    let c = crc16(frame);
    frame.extend_from_slice(&c.to_le_bytes());
}

/// What a checked frame is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Request,
    Response,
    /// A response with the function code's high bit set.
    Exception,
    /// A frame whose check passes but whose length no reading gives (ASCII framing only: an
    /// RTU frame is found by its length).
    Unknown,
}

/// What bytes that are no checked frame are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Broken {
    /// A frame of the right length whose CRC fails.
    BadCrc,
    /// The start of a frame, cut short by the next frame or the end of the input.
    Truncated,
    /// Bytes that belong to no frame (a turnaround byte, noise).
    Garbage,
}

/// A frame whose CRC checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame<'a> {
    /// The whole frame as on the wire: address, function code, data, CRC.
    pub bytes: &'a [u8],
    /// Its content without the check: address, function code, data.
    pub pdu: &'a [u8],
    pub kind: Kind,
    /// Offset of its first byte in the stream.
    pub offset: u64,
    /// Arrival time of its first byte (µs), when the source has times.
    pub time: Option<u64>,
    /// Both readings had this length (and so the same CRC): told apart by the pairing.
    pub ambiguous: bool,
}

/// Bytes that are no checked frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Junk<'a> {
    pub bytes: &'a [u8],
    pub what: Broken,
    pub offset: u64,
    pub time: Option<u64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event<'a> {
    Frame(Frame<'a>),
    Junk(Junk<'a>),
}

/// The response the reassembler waits for after a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Expect {
    addr: u8,
    fc: u8,
    time: Option<u64>,
    /// Its length, when the request tells it.
    len: Option<usize>,
}

/// What the reassembler knows of the exchange in progress (shared with the ASCII framing):
/// the response it waits for after a request, and the master timeout.
#[derive(Clone, Debug)]
pub(super) struct Expecting {
    expect: Option<Expect>,
    /// The waiting request's bytes (CRC included).
    req: Vec<u8>,
    /// Master timeout (µs): an echo after it is the request sent again.
    timeout: u64,
}

impl Expecting {
    pub(super) fn new(timeout: u64) -> Self {
        Expecting {
            expect: None,
            req: Vec::with_capacity(MAX_FRAME),
            timeout,
        }
    }

    /// The response waited for, and whether a frame at `time` comes after the timeout.
    fn at(&self, time: Option<u64>) -> Option<Waiting<'_>> {
        self.expect.map(|e| Waiting {
            e,
            late: matches!((e.time, time), (Some(r), Some(t)) if t.saturating_sub(r) > self.timeout),
            req: &self.req,
        })
    }

    /// A frame was given out: after a request (not a broadcast), its response is expected.
    pub(super) fn after(&mut self, kind: Kind, frame: &[u8], time: Option<u64>) {
        self.req.clear();
        if kind == Kind::Request {
            self.req.extend_from_slice(frame);
        }
        self.expect = match kind {
            Kind::Request if frame[0] != 0 => Some(Expect {
                addr: frame[0],
                fc: frame[1],
                time,
                len: response_len(frame),
            }),
            _ => None,
        };
    }

    pub(super) fn forget(&mut self) {
        self.expect = None;
    }

    /// Whether `junk` holds the awaited answer's slave and function: a broken answer went by.
    fn answer_in(&self, junk: &[u8]) -> bool {
        self.expect.is_some_and(|e| {
            junk.windows(2)
                .any(|w| w[0] == e.addr && (w[1] == e.fc || w[1] == e.fc | 0x80))
        })
    }

    /// Broken bytes went by: if they begin as the awaited answer (its slave and function), they
    /// were that answer, broken, and nothing is awaited any more (as the pairing has it).
    pub(super) fn broken(&mut self, bytes: &[u8]) {
        if let (Some(e), [a, f, ..]) = (self.expect, bytes)
            && *a == e.addr
            && (*f == e.fc || *f == e.fc | 0x80)
        {
            self.expect = None;
        }
    }

    /// What a whole frame `b` (its check included, `rtu_len` bytes as an RTU frame) at `time`
    /// is, by its readings and the exchange in progress: `None` when no reading has its
    /// length. The bool: both readings had it.
    pub(super) fn kind_of(
        &self,
        b: &[u8],
        rtu_len: usize,
        time: Option<u64>,
    ) -> Option<(Kind, bool)> {
        let (req, resp) = (frame_len(b, Dir::Request), frame_len(b, Dir::Response));
        let (is_req, is_resp) = (req == Len::Known(rtu_len), resp == Len::Known(rtu_len));
        let fc = *b.get(1)?;
        let awaited = self
            .at(time)
            .is_some_and(|w| !w.late && w.e.addr == b[0] && (fc == w.e.fc || fc == w.e.fc | 0x80));
        match (is_req, is_resp) {
            (true, true) if awaited => Some((answer_kind(fc), true)),
            (true, both) => Some((Kind::Request, both)),
            (false, true) => Some((answer_kind(fc), false)),
            (false, false) => None,
        }
    }
}

/// The length of the response to `req` (a checked request frame), when the request tells it.
pub fn response_len(req: &[u8]) -> Option<usize> {
    let word = |i: usize| -> Option<usize> {
        Some(u16::from_be_bytes([*req.get(i)?, *req.get(i + 1)?]) as usize)
    };
    let n = match *req.get(1)? {
        1 | 2 => 5 + word(4)?.div_ceil(8),
        3 | 4 | 23 => 5 + 2 * word(4)?,
        5 | 6 | 8 | 11 | 15 | 16 => 8,
        7 => 5,
        22 => 10,
        21 => req.len(),
        _ => return None,
    };
    (n <= MAX_FRAME).then_some(n)
}

/// What a place in the stream holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Verdict {
    /// A frame of `len` bytes. `weak`: found among bytes that hold no frame and outside the
    /// specification's limits (a request for 0 registers …): it counts only if no frame within
    /// limits starts inside it.
    Take {
        len: usize,
        kind: Kind,
        ambiguous: bool,
        weak: bool,
    },
    /// Bytes a reading needs have not arrived yet.
    Wait,
    /// No frame starts here.
    NotStart,
}

fn answer_kind(fc: u8) -> Kind {
    if fc & 0x80 != 0 {
        Kind::Exception
    } else {
        Kind::Response
    }
}

/// The response waited for as [`judge`] sees it: whether the frame comes after the master
/// timeout, and the request's bytes (its CRC included).
#[derive(Clone, Copy, Debug)]
struct Waiting<'a> {
    e: Expect,
    late: bool,
    req: &'a [u8],
}

/// Whether the `n`-byte response reading of `b` is the waiting request sent again: its first
/// `m` bytes are that request (CRC included) and zero bytes fill the rest (a request followed
/// by a turnaround byte checks as an answer one byte longer).
fn is_retry(b: &[u8], n: usize, req: Len, waiting: &[u8]) -> bool {
    match req {
        Len::Known(m) if m < n => b[..m] == *waiting && b[m..n].iter().all(|&x| x == 0),
        _ => false,
    }
}

/// Judges the place where `b` starts. `waiting`: the response the exchange in progress waits
/// for. `fin`: no more bytes will come. `clean`: the place follows a frame (or starts the
/// input); within bytes that hold no frame, a reading must also be
/// [`plausible`] to count, so that bytes that check by chance
/// there (one place in 65,536) rarely take a good frame's first bytes.
///
/// A frame followed by zero bytes checks as a longer frame too, and a frame whose CRC ends in
/// `00` has a prefix one byte shorter that checks. So when the shorter reading checks and zero
/// bytes follow it up to the longer one's length, both readings check, and neither CRC can
/// tell them apart: the response is taken when one is awaited from this slave, the request
/// otherwise (a turnaround `00` after a request, a request whose CRC ends in `00`).
fn judge(b: &[u8], fin: bool, clean: bool, waiting: Option<Waiting<'_>>) -> Verdict {
    match b {
        [] => {
            return if fin {
                Verdict::NotStart
            } else {
                Verdict::Wait
            };
        }
        [a, ..] if *a > super::function::MAX_SLAVE => return Verdict::NotStart,
        [_] => {
            return if fin {
                Verdict::NotStart
            } else {
                Verdict::Wait
            };
        }
        _ => {}
    }
    let (addr, fc) = (b[0], b[1]);
    let req = frame_len(b, Dir::Request);
    let resp = frame_len(b, Dir::Response);
    let expected = waiting.filter(|w| w.e.addr == addr && (fc == w.e.fc || fc == w.e.fc | 0x80));
    let answer_awaited = expected.is_some_and(|w| !w.late);
    // A reading of `n` bytes found among bytes that hold no frame, outside the limits.
    let weak = |n: usize| {
        let within = (req == Len::Known(n) && plausible(&b[..n], Dir::Request))
            || (resp == Len::Known(n) && plausible(&b[..n], Dir::Response));
        !clean && !within
    };
    if let Some(w) = expected {
        let want = if fc & 0x80 != 0 { Some(5) } else { w.e.len };
        if let (Some(n), Len::Known(m)) = (want, resp)
            && n == m
        {
            if n > b.len() {
                if !fin {
                    return Verdict::Wait;
                }
            } else if crc_ok(&b[..n]) && !is_retry(b, n, req, w.req) {
                let both = req == Len::Known(n);
                let kind = if both && w.late {
                    Kind::Request
                } else {
                    answer_kind(fc)
                };
                return Verdict::Take {
                    len: n,
                    kind,
                    ambiguous: both,
                    weak: weak(n),
                };
            }
        }
    }
    let known = |l: Len| match l {
        Len::Known(n) => n,
        _ => usize::MAX,
    };
    let (r, a) = (known(req), known(resp));
    let (short, long) = (r.min(a), r.max(a));
    for (i, n) in [short, long].into_iter().enumerate() {
        if n == usize::MAX || (i == 1 && long == short) {
            continue;
        }
        if n > b.len() {
            if fin {
                continue;
            }
            return Verdict::Wait;
        }
        if !crc_ok(&b[..n]) {
            continue;
        }
        if i == 0 && long != usize::MAX && long != short {
            let end = long.min(b.len());
            if b[n..end].iter().all(|&x| x == 0) {
                if long > b.len() {
                    if !fin {
                        return Verdict::Wait;
                    }
                } else {
                    // Both check: see above.
                    let retry = expected.is_some_and(|w| is_retry(b, a, req, w.req));
                    let (len, kind) = if answer_awaited && !retry {
                        (a, answer_kind(fc))
                    } else {
                        (r, Kind::Request)
                    };
                    return Verdict::Take {
                        len,
                        kind,
                        ambiguous: true,
                        weak: weak(len),
                    };
                }
            }
        }
        let (is_req, is_resp) = (r == n, a == n);
        let kind = match (is_req, is_resp) {
            (true, true) if answer_awaited => answer_kind(fc),
            (true, _) => Kind::Request,
            _ => answer_kind(fc),
        };
        return Verdict::Take {
            len: n,
            kind,
            ambiguous: is_req && is_resp,
            weak: weak(n),
        };
    }
    if !fin && (req == Len::Need || resp == Len::Need) {
        return Verdict::Wait;
    }
    Verdict::NotStart
}

/// Bytes that hold no frame for this long are given up as garbage in rows of
/// [`GARBAGE_ROW_MAX`] (bounded memory; a good frame needs at most [`MAX_FRAME`] more).
pub const JUNK_MAX: usize = 512;

/// Stray bytes allowed between two bad frames of a run, or before the next good frame.
const STRAY_MAX: usize = 3;

/// The frame lengths the readings at the start of `b` give (both directions), at least
/// [`MIN_FRAME`] each; `None` for a length field beyond `b` (a frame longer than `b`).
fn lengths(b: &[u8]) -> [Option<Option<usize>>; 2] {
    [Dir::Request, Dir::Response].map(|d| match frame_len(b, d) {
        Len::Known(n) if n >= MIN_FRAME => Some(Some(n)),
        Len::Need => Some(None),
        _ => None,
    })
}

/// Sorts out bytes `j` that hold no checked frame and end where the next frame starts (or
/// where the input ends, `at_end`) into pieces `(start, len, what)`, in order:
///
/// * a run of bad frames that reaches the end exactly, each frame of a length its own
///   readings give, with at most `STRAY_MAX` stray bytes after each: `BadCRC` (and the
///   strays `Garbage`); bytes before the run are garbage or a cut frame (below);
/// * else a frame that starts within the first `STRAY_MAX` bytes and is longer than what is
///   left (at least 4 bytes left, 2 at the end of the input): `Truncated`;
/// * everything else: `Garbage`.
///
/// `ok` is scratch (one entry per byte, the piece chosen at each place).
pub fn classify(
    j: &[u8],
    at_end: bool,
    ok: &mut Vec<Option<(u16, u8)>>,
    out: &mut Vec<(usize, usize, Broken)>,
) {
    let n = j.len();
    ok.clear();
    ok.resize(n + 1, None);
    // ok[i]: a run of bad frames from i reaches n: (frame length, strays after it, strays in
    // the rest of the run); the fewest strays win, then the fewest.
    let mut strays = vec![0usize; n + 1];
    ok[n] = Some((0, 0));
    for i in (0..n).rev() {
        let mut best: Option<(usize, u16, u8)> = None;
        for l in lengths(&j[i..]).into_iter().flatten().flatten() {
            for s in 0..=STRAY_MAX {
                let next = i + l + s;
                if next <= n && ok[next].is_some() {
                    let cost = s + strays[next];
                    if best.is_none_or(|b| cost < b.0) {
                        best = Some((cost, l as u16, s as u8));
                    }
                }
            }
        }
        if let Some((cost, l, s)) = best {
            ok[i] = Some((l, s));
            strays[i] = cost;
        }
    }
    // The run that leaves the fewest bytes outside frames (garbage before it and strays in it).
    let run = (0..n)
        .filter(|&i| ok[i].is_some())
        .min_by_key(|&i| (i + strays[i], i));
    let head = run.unwrap_or(n);
    cut_or_garbage(&j[..head], at_end && run.is_none(), out);
    let mut i = head;
    while i < n {
        let Some((l, s)) = ok[i] else { break };
        let (l, s) = (l as usize, s as usize);
        out.push((i, l, Broken::BadCrc));
        if s > 0 {
            out.push((i + l, s, Broken::Garbage));
        }
        i += l + s;
    }
}

/// A cut frame near the start of `j` (see [`classify`]), or garbage.
fn cut_or_garbage(j: &[u8], at_end: bool, out: &mut Vec<(usize, usize, Broken)>) {
    let n = j.len();
    if n == 0 {
        return;
    }
    let least = if at_end { 2 } else { MIN_FRAME };
    for r in 0..=STRAY_MAX.min(n - 1) {
        let left = n - r;
        if left < least {
            break;
        }
        let cut = lengths(&j[r..])
            .into_iter()
            .flatten()
            .any(|l| l.is_none_or(|l| l > left));
        if cut {
            if r > 0 {
                out.push((0, r, Broken::Garbage));
            }
            out.push((r, left, Broken::Truncated));
            return;
        }
    }
    out.push((0, n, Broken::Garbage));
}

/// The shortest silence that settles the bytes held (µs): no frame pauses this long, USB
/// latency timers included.
pub const SETTLE_MIN: u64 = 100_000;

/// Bytes fed in one step at most, so that a huge chunk never makes the buffer huge.
const STEP: usize = 4096;

/// The reassembler. Feed it with [`Framer::push`]; [`Framer::finish`] at the end of the input
/// (or a gap) gives out what is left.
#[derive(Debug)]
pub struct Framer {
    /// Bytes from stream offset `base`; `buf[head..]` is not given out yet.
    buf: Vec<u8>,
    base: u64,
    head: usize,
    /// Bytes at `head` known to start no frame (the junk so far).
    scan: usize,
    /// (stream offset, time) where each chunk began.
    marks: VecDeque<(u64, Option<u64>)>,
    expect: Expecting,
    /// The junk at `head` holds the awaited answer's header ([`Expecting::answer_in`]), as far
    /// as its first `seen_upto` bytes were looked at.
    answer_seen: bool,
    seen_upto: usize,
    /// A silence this long (µs) settles the bytes held.
    settle: u64,
    /// The time of the latest bytes.
    last: Option<u64>,
    ok: Vec<Option<(u16, u8)>>,
    pieces: Vec<(usize, usize, Broken)>,
}

impl Framer {
    /// A reassembler for a master timeout of `timeout` µs.
    pub fn new(timeout: u64) -> Self {
        Framer {
            buf: Vec::new(),
            base: 0,
            head: 0,
            scan: 0,
            marks: VecDeque::new(),
            expect: Expecting::new(timeout),
            answer_seen: false,
            seen_upto: 0,
            settle: SETTLE_MIN,
            last: None,
            ok: Vec::new(),
            pieces: Vec::new(),
        }
    }

    /// Bytes held (for tests of the bounds).
    pub fn held(&self) -> usize {
        self.buf.len() - self.head
    }

    /// The arrival time of the first byte held, when bytes are held (a frame in progress, or
    /// bytes still to be sorted out): nothing they become is earlier.
    pub fn held_since(&self) -> Option<u64> {
        (self.held() > 0)
            .then(|| self.time_at(self.base + self.head as u64))
            .flatten()
    }

    /// Feeds bytes that arrived at `time`; every frame they complete is given to `emit`.
    /// A reassembler whose held bytes settle after a silence of `settle` µs (at least
    /// [`SETTLE_MIN`]).
    pub fn settling_after(mut self, settle: u64) -> Self {
        self.settle = settle.max(SETTLE_MIN);
        self
    }

    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if data.is_empty() {
            return;
        }
        if let (Some(t), Some(last)) = (time, self.last)
            && t > last.saturating_add(self.settle)
        {
            self.run(true, emit);
            self.compact();
        }
        if time.is_some() {
            self.last = time;
        }
        for piece in data.chunks(STEP) {
            let at = self.base + self.buf.len() as u64;
            match self.marks.back() {
                Some(&(_, t)) if t == time => {}
                _ => self.marks.push_back((at, time)),
            }
            self.buf.extend_from_slice(piece);
            self.run(false, emit);
            self.compact();
        }
    }

    /// Time passed on a live line without bytes: after a silence that settles them, the bytes
    /// held come out (as they would when the next bytes came).
    pub fn idle(&mut self, now: u64, emit: &mut impl FnMut(&Event<'_>)) {
        if self.held() > 0
            && self
                .last
                .is_some_and(|last| now > last.saturating_add(self.settle))
        {
            self.run(true, emit);
            self.compact();
        }
    }

    /// The end of the input (or a gap): everything held comes out, and the reassembler starts
    /// afresh (no response is expected across a gap).
    pub fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.run(true, emit);
        self.compact();
        self.expect.forget();
    }

    fn time_at(&self, offset: u64) -> Option<u64> {
        let i = self.marks.partition_point(|m| m.0 <= offset);
        i.checked_sub(1).and_then(|i| self.marks[i].1)
    }

    fn compact(&mut self) {
        if self.head > 0 && (self.head == self.buf.len() || self.head >= STEP) {
            self.buf.drain(..self.head);
            self.base += self.head as u64;
            self.head = 0;
        }
        let first = self.base + self.head as u64;
        while self.marks.len() > 1 && self.marks[1].0 <= first {
            self.marks.pop_front();
        }
    }

    fn run(&mut self, fin: bool, emit: &mut impl FnMut(&Event<'_>)) {
        loop {
            let pending = self.buf.len() - self.head;
            let at = self.scan;
            if at >= pending {
                if fin && at > 0 {
                    self.junk(at, true, emit);
                }
                return;
            }
            let offset = self.base + (self.head + at) as u64;
            let time = self.time_at(offset);
            // Bytes holding no frame that hold the awaited answer's header: it came, broken.
            // (Looked for in the bytes added since the last look.)
            if !self.answer_seen && at >= 2 {
                let from = self.head + self.seen_upto.saturating_sub(1);
                self.answer_seen = self.expect.answer_in(&self.buf[from..self.head + at]);
            }
            self.seen_upto = at;
            let expect = if self.answer_seen {
                None
            } else {
                self.expect.at(time)
            };
            let b = &self.buf[self.head + at..];
            let mut verdict = judge(b, fin, at == 0, expect);
            if let Verdict::Take {
                len, weak: true, ..
            } = verdict
            {
                // A frame within limits that starts inside it wins (or is still to be seen).
                for r in 1..len {
                    match judge(&b[r..], fin, false, expect) {
                        Verdict::Take { weak: false, .. } => {
                            verdict = Verdict::NotStart;
                            break;
                        }
                        Verdict::Wait => {
                            verdict = Verdict::Wait;
                            break;
                        }
                        _ => {}
                    }
                }
            }
            match verdict {
                Verdict::Wait => return,
                Verdict::NotStart => {
                    self.scan += 1;
                    if self.scan >= JUNK_MAX {
                        let n = GARBAGE_ROW_MAX;
                        self.pieces.clear();
                        self.pieces.push((0, n, Broken::Garbage));
                        self.give_pieces(emit);
                        self.head += n;
                        self.scan -= n;
                        (self.answer_seen, self.seen_upto) = (false, 0);
                    }
                }
                Verdict::Take {
                    len,
                    kind,
                    ambiguous,
                    ..
                } => {
                    if at > 0 {
                        self.junk(at, false, emit);
                    }
                    (self.answer_seen, self.seen_upto) = (false, 0);
                    let start = self.head;
                    let bytes = &self.buf[start..start + len];
                    emit(&Event::Frame(Frame {
                        bytes,
                        pdu: &bytes[..len - 2],
                        kind,
                        offset,
                        time,
                        ambiguous,
                    }));
                    self.expect.after(kind, bytes, time);
                    self.head += len;
                }
            }
        }
    }

    /// The `n` bytes at `head` hold no frame: sorted out and given out.
    fn junk(&mut self, n: usize, at_end: bool, emit: &mut impl FnMut(&Event<'_>)) {
        let j = &self.buf[self.head..self.head + n];
        self.pieces.clear();
        classify(j, at_end, &mut self.ok, &mut self.pieces);
        self.give_pieces(emit);
        self.head += n;
        self.scan = 0;
        (self.answer_seen, self.seen_upto) = (false, 0);
    }

    /// Gives out `pieces` (relative to `head`), garbage in rows of at most
    /// [`GARBAGE_ROW_MAX`] bytes.
    fn give_pieces(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        for k in 0..self.pieces.len() {
            let (start, len, what) = self.pieces[k];
            let step = if what == Broken::Garbage {
                GARBAGE_ROW_MAX
            } else {
                len.max(1)
            };
            let mut at = start;
            while at < start + len {
                let m = step.min(start + len - at);
                let offset = self.base + (self.head + at) as u64;
                let time = self.time_at(offset);
                let bytes = &self.buf[self.head + at..self.head + at + m];
                emit(&Event::Junk(Junk {
                    bytes,
                    what,
                    offset,
                    time,
                }));
                if what != Broken::Garbage {
                    self.expect.broken(bytes);
                }
                at += m;
            }
        }
    }
}

#[cfg(test)]
mod tests;
