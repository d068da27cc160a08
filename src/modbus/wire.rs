//! The pure Modbus RTU reassembler: bytes and times in, frames and broken bytes out, no I/O.
//!
//! RTU marks frames by 3.5 characters of silence, which a USB-serial adapter destroys (it
//! hands bytes over in transfers of 16-64 bytes, after a latency timer), so busnoop never
//! frames by silence. A frame is found by its content:
//!
//! * at each place, the frame's length is read twice: as a request and as a response
//!   ([`function::frame_len`]: fixed lengths, byte counts, Read Device Identification's
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
//! ended). Times are a hint only: a frame with the same bytes as the request before it (the
//! echo of a write) is its response, unless it came after the master timeout (then it is the
//! request sent again).

use std::collections::VecDeque;

use crc::{CRC_16_MODBUS, Crc, Table};

use super::function::{Dir, Len, MAX_FRAME, MIN_FRAME, frame_len};
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
#[derive(Clone, Copy, Debug)]
pub(super) struct Expecting {
    expect: Option<Expect>,
    /// Master timeout (µs): an echo after it is the request sent again.
    timeout: u64,
}

impl Expecting {
    pub(super) fn new(timeout: u64) -> Self {
        Expecting {
            expect: None,
            timeout,
        }
    }

    /// The response waited for, and whether a frame at `time` comes after the timeout.
    fn at(&self, time: Option<u64>) -> Option<(Expect, bool)> {
        self.expect.map(|e| {
            let late =
                matches!((e.time, time), (Some(r), Some(t)) if t.saturating_sub(r) > self.timeout);
            (e, late)
        })
    }

    /// A frame was given out: after a request (not a broadcast), its response is expected.
    pub(super) fn after(&mut self, kind: Kind, frame: &[u8], time: Option<u64>) {
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
        let expected = self
            .at(time)
            .filter(|(e, _)| e.addr == b[0] && (fc == e.fc || fc == e.fc | 0x80));
        match (is_req, is_resp) {
            (true, true) if expected.is_some_and(|(_, late)| !late) => {
                Some((answer_kind(fc), true))
            }
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
    /// A frame of `len` bytes.
    Take {
        len: usize,
        kind: Kind,
        ambiguous: bool,
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

/// Whether the reading of `n` bytes checks only because zero bytes follow a shorter request
/// reading that checks (the stray-byte trap).
fn implied(b: &[u8], n: usize, req: Len) -> bool {
    match req {
        Len::Known(m) if m < n => crc_ok(&b[..m]) && b[m..n].iter().all(|&x| x == 0),
        _ => false,
    }
}

/// Judges the place where `b` starts. `expect`: the response the pairing waits for, and
/// whether the time since its request is past the timeout. `fin`: no more bytes will come.
fn judge(b: &[u8], fin: bool, expect: Option<(Expect, bool)>) -> Verdict {
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
    let expected = expect.filter(|(e, _)| e.addr == addr && (fc == e.fc || fc == e.fc | 0x80));
    if let Some((e, late)) = expected {
        let want = if fc & 0x80 != 0 { Some(5) } else { e.len };
        if let (Some(n), Len::Known(m)) = (want, resp)
            && n == m
        {
            if n > b.len() {
                if !fin {
                    return Verdict::Wait;
                }
            } else if crc_ok(&b[..n]) && !implied(b, n, req) {
                let both = req == Len::Known(n);
                let kind = if both && late {
                    Kind::Request
                } else {
                    answer_kind(fc)
                };
                return Verdict::Take {
                    len: n,
                    kind,
                    ambiguous: both,
                };
            }
        }
    }
    let mut lens = [req, resp].map(|l| match l {
        Len::Known(n) => n,
        _ => usize::MAX,
    });
    lens.sort_unstable();
    for (i, &n) in lens.iter().enumerate() {
        if n == usize::MAX || (i == 1 && n == lens[0]) {
            continue;
        }
        if n > b.len() {
            if fin {
                continue;
            }
            return Verdict::Wait;
        }
        if crc_ok(&b[..n]) {
            let (is_req, is_resp) = (req == Len::Known(n), resp == Len::Known(n));
            let kind = match (is_req, is_resp) {
                (true, true) if expected.is_some_and(|(_, late)| !late) => answer_kind(fc),
                (true, _) => Kind::Request,
                _ => answer_kind(fc),
            };
            return Verdict::Take {
                len: n,
                kind,
                ambiguous: is_req && is_resp,
            };
        }
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
///   readings give, with at most [`STRAY_MAX`] stray bytes after each: `BadCRC` (and the
///   strays `Garbage`); bytes before the run are garbage or a cut frame (below);
/// * else a frame that starts within the first [`STRAY_MAX`] bytes and is longer than what is
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
    // ok[i]: a run of bad frames from i reaches n; (frame length, strays after it).
    ok[n] = Some((0, 0));
    for i in (0..n).rev() {
        let ls = lengths(&j[i..]);
        'place: for s in 0..=STRAY_MAX {
            for l in ls.into_iter().flatten().flatten() {
                let next = i + l + s;
                if next <= n && ok[next].is_some() {
                    ok[i] = Some((l as u16, s as u8));
                    break 'place;
                }
            }
        }
    }
    let run = (0..n).find(|&i| ok[i].is_some());
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
            ok: Vec::new(),
            pieces: Vec::new(),
        }
    }

    /// Bytes held (for tests of the bounds).
    pub fn held(&self) -> usize {
        self.buf.len() - self.head
    }

    /// Feeds bytes that arrived at `time`; every frame they complete is given to `emit`.
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
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
            let expect = self.expect.at(time);
            let b = &self.buf[self.head + at..];
            match judge(b, fin, expect) {
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
                    }
                }
                Verdict::Take {
                    len,
                    kind,
                    ambiguous,
                } => {
                    if at > 0 {
                        self.junk(at, false, emit);
                    }
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
                at += m;
            }
        }
    }
}

#[cfg(test)]
mod tests;
