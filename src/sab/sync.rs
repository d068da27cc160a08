//! SAB v1 framing: `54 LEN HDR CMD DATA[LEN] CRC8`, the pure reassembler and an encoder.
//!
//! * LENGTH is the payload length, 0..=32; a receiver rejects anything larger.
//! * The CRC is CRC-8/MAXIM-DOW (AVR `_crc_ibutton_update`, init 0, no final XOR) over
//!   LENGTH, HEADER, COMMAND and DATA; SYNC is not covered.
//!
//! # Resynchronisation
//!
//! modm's receiver hunts for 0x54, reads LENGTH + 3 more bytes and starts hunting again after
//! them, so a stray 0x54 followed by a plausible length swallows up to 35 bytes and hides the
//! real frame behind it. This reassembler backtracks instead: it keeps the bytes of a candidate
//! and, when the candidate fails (bad LENGTH or bad CRC), rescans from the byte after its 0x54.
//!
//! The rule, which makes the output a function of the bytes alone:
//!
//! 1. A **frame** is accepted at the earliest position where a complete candidate passes its
//!    CRC, unless a valid frame starts inside it and reaches beyond its end, no valid frame
//!    starts right at its end, and one starts right at the later frame's end (or the input
//!    ends there): then the candidate is a damaged frame whose CRC-8 passed by chance (1 in
//!    256; its LENGTH was hit, and it swallowed the next frame's 0x54). It is handled as a
//!    failed candidate (rule 3: its 0x54 is garbage, scanning goes on with the next byte), so
//!    the later frame, and any frame inside, are found. (The traffic decides: it goes on
//!    cleanly after the true frame, so a frame whose payload holds a chance start keeps it.)
//! 2. A failed candidate whose span contains no valid frame start is a **bad frame**
//!    (`BadCrc`, or `Truncated` when the input ends inside it); its bytes are consumed.
//! 3. A failed candidate whose span contains the start of a valid frame was a **false SYNC**:
//!    only its 0x54 becomes garbage and scanning goes on with the next byte.
//! 4. Every other byte is **garbage**.
//!
//! Memory is bounded: at most three frame lengths (111 bytes) are held while a rejected
//! candidate waits for the candidates inside it to complete, or a valid one for the frames
//! after it and after the later frame inside it.

use super::frame::{Event, EventKind, Framing, find};

/// The first byte of every frame.
pub const SYNC: u8 = 0x54;
/// Largest payload (modm `maxPayloadLength`); a larger LENGTH is rejected.
pub const MAX_PAYLOAD: usize = 32;
/// SYNC, LENGTH, HEADER, COMMAND and CRC.
pub const OVERHEAD: usize = 5;
/// Longest frame on the wire.
pub const MAX_FRAME: usize = MAX_PAYLOAD + OVERHEAD;
/// Bytes held at most (see the module documentation).
pub const CAPACITY: usize = 3 * MAX_FRAME;
use crate::row::GARBAGE_ROW_MAX;

/// CRC-8/MAXIM-DOW (reflected polynomial 0x8C, init 0) tables: `CRC8[0]` by byte,
/// `CRC8[k][i]` the CRC of byte `i` followed by `k` zero bytes. A step of four bytes looks up
/// each in its own table, side by side: one dependent lookup for four bytes.
static CRC8: [[u8; 256]; 4] = {
    let mut t = [[0u8; 256]; 4];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u8;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 { (c >> 1) ^ 0x8C } else { c >> 1 };
            k += 1;
        }
        t[0][i] = c;
        i += 1;
    }
    let mut s = 1;
    while s < 4 {
        let mut i = 0;
        while i < 256 {
            t[s][i] = t[0][t[s - 1][i] as usize];
            i += 1;
        }
        s += 1;
    }
    t
};

/// CRC-8/MAXIM-DOW of `bytes` (LENGTH … DATA of a frame), four bytes a step (a frame's CRC
/// is checked up to three times: the candidate, then with and without its SYNC).
#[inline]
pub fn crc8(bytes: &[u8]) -> u8 {
    let t = &CRC8;
    let mut c = 0u8;
    let mut rest = bytes;
    while let [b0, b1, b2, b3, tail @ ..] = rest {
        c = t[3][usize::from(c ^ b0)]
            ^ t[2][usize::from(*b1)]
            ^ t[1][usize::from(*b2)]
            ^ t[0][usize::from(*b3)];
        rest = tail;
    }
    for &b in rest {
        c = t[0][usize::from(c ^ b)];
    }
    c
}

/// Appends a frame with a correct LENGTH and CRC.
///
/// # Panics
///
/// If `payload` is longer than [`MAX_PAYLOAD`].
pub fn encode(out: &mut Vec<u8>, header: u8, command: u8, payload: &[u8]) {
    assert!(
        payload.len() <= MAX_PAYLOAD,
        "SAB v1 payloads have at most 32 bytes"
    );
    let start = out.len();
    out.push(SYNC);
    out.push(payload.len() as u8);
    out.push(header);
    out.push(command);
    out.extend_from_slice(payload);
    let crc = crc8(&out[start + 1..]);
    out.push(crc);
}

/// What the candidate at the start of `bytes` (a 0x54) is, decided from `bytes` alone with
/// nothing held: the rule of the module documentation applied in place.
#[derive(Debug, PartialEq, Eq)]
enum InPlace {
    /// A valid frame, ending here (exclusive).
    Frame(usize),
    /// A LENGTH above 32: the 0x54 is garbage.
    BadLength,
    /// A valid frame starts inside the failed candidate: the 0x54 is garbage.
    FalseSync,
    /// A failed candidate with no valid frame start inside: a bad frame ending here.
    BadCrc(usize),
    /// `bytes` ends before the candidate (or one inside it) is decided.
    Undecided,
}

/// [`Reassembler::check`] on `bytes` alone, for the candidate at its start.
#[inline]
fn check_bytes(bytes: &[u8]) -> Check {
    if bytes.first() != Some(&SYNC) {
        return Check::Invalid;
    }
    let Some(&length) = bytes.get(1) else {
        return Check::Incomplete;
    };
    let length = length as usize;
    if length > MAX_PAYLOAD {
        return Check::Invalid;
    }
    let end = length + OVERHEAD;
    match bytes.get(..end) {
        None => Check::Incomplete,
        Some(frame) if crc8(&frame[1..end - 1]) == frame[end - 1] => Check::Valid(end),
        Some(_) => Check::Invalid,
    }
}

/// The end of the frame at the start of `bytes` when it is complete there and valid, and
/// whether a 0x54 stands in it after its SYNC (only then can a frame start inside it, which
/// [`overlap`] weighs): one pass computes both.
#[inline]
fn valid_frame(bytes: &[u8]) -> Option<(usize, bool)> {
    let (&SYNC, rest) = bytes.split_first()? else {
        return None;
    };
    let length = *rest.first()? as usize;
    if length > MAX_PAYLOAD {
        return None;
    }
    let end = length + OVERHEAD;
    let frame = bytes.get(..end)?;
    let (covered, crc) = (&frame[1..end - 1], frame[end - 1]);
    let (mut c, mut sync) = (0u8, crc == SYNC);
    for &b in covered {
        c = CRC8[0][usize::from(c ^ b)];
        sync |= b == SYNC;
    }
    (c == crc).then_some((end, sync))
}

/// For a valid frame ending at `end` at the start of `bytes`: whether it stands (rule 1 of
/// the module documentation). `Some(None)`: it stands; `Some(Some(q))`: its 0x54 is taken for
/// a false one (`q`: the valid frame start inside it that decided it); `None`: `bytes` ends
/// before that is decided (never at the end of the input, `eof`).
#[inline]
fn overlap(bytes: &[u8], end: usize, eof: bool) -> Option<Option<usize>> {
    // Only a frame with a valid frame start inside it is in doubt.
    let mut p = 1;
    let mut nested = None;
    while let Some(k) = find(SYNC, &bytes[p..end]) {
        p += k;
        match check_bytes(&bytes[p..]) {
            // One that reaches past its end: it would hide that frame's start. The traffic
            // decides: it takes the place when a valid frame starts right at its own end, and
            // none right at the frame's end (which it would hide in turn).
            Check::Valid(len) if p + len > end => {
                let frame_at = |at: usize| -> Option<bool> {
                    match check_bytes(bytes.get(at..).unwrap_or(&[])) {
                        Check::Valid(_) => Some(true),
                        Check::Incomplete if !eof => None,
                        _ if at >= bytes.len() && !eof => None,
                        _ => Some(false),
                    }
                };
                // (A stray 0x54 right at its end and a valid frame after it count as a valid
                // frame at its end: a lost byte's signature has the next frame's LENGTH there,
                // which is never 0x54.)
                if frame_at(end)? || (bytes.get(end) == Some(&SYNC) && frame_at(end + 1)?) {
                    return Some(None);
                }
                // Its 0x54 in the frame's CRC byte: the signature of a byte lost from the frame
                // (its LENGTH then reaches one byte into the next frame, whose 0x54 passed as
                // its CRC, 1 in 256); a real CRC byte of 0x54 starting a valid frame is 1 in 65 536.
                if p == end - 1 || frame_at(p + len)? {
                    return Some(Some(p));
                }
                // Neither: the frames counted below decide.
                nested.get_or_insert(p);
                break;
            }
            Check::Valid(_) => {
                nested.get_or_insert(p);
                p += 1;
            }
            Check::Incomplete if !eof => return None,
            _ => p += 1,
        }
    }
    let Some(q) = nested else {
        return Some(None);
    };
    // Frames inside it: the reading from the byte after its 0x54 wins when it finds more valid
    // frames, up to one frame length past its end (a LENGTH hit that made it swallow frames);
    // a tie keeps it (a payload holding a frame by chance, followed by noise).
    let horizon = end + MAX_FRAME;
    let (n, _) = chain(bytes, end, horizon, eof)?;
    let (m, _) = chain(bytes, 1, horizon, eof)?;
    Some((m > n + 1).then_some(q))
}

/// Valid frames read greedily (the earliest valid one, then on from its end) from `from`,
/// the ones that start before `horizon`: their number and their bytes before `horizon`.
/// `None` when `bytes` ends before that is decided (never at the end of the input, `eof`).
fn chain(bytes: &[u8], from: usize, horizon: usize, eof: bool) -> Option<(usize, usize)> {
    let (mut n, mut covered, mut p) = (0, 0, from);
    while p < horizon {
        if p >= bytes.len() {
            return eof.then_some((n, covered));
        }
        let to = horizon.min(bytes.len());
        let Some(k) = find(SYNC, &bytes[p..to]) else {
            p = to;
            continue;
        };
        p += k;
        match check_bytes(&bytes[p..]) {
            Check::Valid(len) => {
                n += 1;
                covered += (p + len).min(horizon) - p;
                p += len;
            }
            Check::Incomplete if !eof => return None,
            _ => p += 1,
        }
    }
    Some((n, covered))
}

/// Classifies the candidate at the start of `bytes` (which starts with 0x54). Out of line:
/// most candidates are valid frames, which [`valid_frame`] finds first.
#[inline(never)]
fn in_place(bytes: &[u8]) -> InPlace {
    let Some(&length) = bytes.get(1) else {
        return InPlace::Undecided;
    };
    if length as usize > MAX_PAYLOAD {
        return InPlace::BadLength;
    }
    match check_bytes(bytes) {
        Check::Valid(end) => return InPlace::Frame(end),
        Check::Incomplete => return InPlace::Undecided,
        Check::Invalid => {}
    }
    let full = length as usize + OVERHEAD;
    // Does a valid frame start inside the rejected candidate?
    let mut p = 1;
    while let Some(k) = find(SYNC, &bytes[p..full]) {
        p += k;
        match check_bytes(&bytes[p..]) {
            Check::Valid(_) => return InPlace::FalseSync,
            Check::Incomplete => return InPlace::Undecided,
            Check::Invalid => p += 1,
        }
    }
    InPlace::BadCrc(full)
}

enum Check {
    /// The candidate is complete and valid; the frame ends here (exclusive).
    Valid(usize),
    /// Not a frame start: no 0x54, a LENGTH above 32, or a failing CRC.
    Invalid,
    /// More bytes are needed to decide.
    Incomplete,
}

/// Garbage bytes collected for one row.
#[derive(Clone, Debug)]
struct Run {
    bytes: [u8; GARBAGE_ROW_MAX],
    len: usize,
    start_pos: u64,
    start_time: Option<u64>,
    end_time: Option<u64>,
    false_syncs: u32,
    bad_lengths: u32,
    before_first: bool,
}

/// Pure SAB v1 reassembler: bytes and times in, [`Event`]s out. The output does not depend on
/// how the input is split into chunks.
#[derive(Clone, Debug)]
pub struct Reassembler {
    buf: [u8; CAPACITY],
    times: Box<[Option<u64>; CAPACITY]>,
    len: usize,
    /// Stream offset of `buf[0]`.
    base: u64,
    /// No position in `buf[..known]` starts a valid frame.
    known: usize,
    /// End of the valid frame that starts at `known`, once found.
    valid: Option<usize>,
    run: Run,
    frames: u64,
}

impl Default for Reassembler {
    fn default() -> Self {
        Self::new()
    }
}

impl Reassembler {
    pub fn new() -> Self {
        Reassembler {
            buf: [0; CAPACITY],
            times: Box::new([None; CAPACITY]),
            len: 0,
            base: 0,
            known: 0,
            valid: None,
            run: Run {
                bytes: [0; GARBAGE_ROW_MAX],
                len: 0,
                start_pos: 0,
                start_time: None,
                end_time: None,
                false_syncs: 0,
                bad_lengths: 0,
                before_first: true,
            },
            frames: 0,
        }
    }

    /// Feeds `data` that arrived at `time`; calls `emit` for every completed event.
    ///
    /// The same as [`Self::step`] for every byte. While nothing is held (the usual case), the
    /// input is read in place: the bytes up to the next 0x54 go to the garbage run whole, and
    /// a candidate that `data` decides (a valid frame, a LENGTH above 32, a bad frame, a false
    /// 0x54: see [`in_place`]) is handled from `data` without passing through the buffer.
    /// Only a candidate that the end of `data` leaves undecided is handled byte by byte (the
    /// backtracking needs its bytes held).
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let mut i = 0;
        while i < data.len() {
            if self.len == 0 {
                let rest = &data[i..];
                let n = find(SYNC, rest).unwrap_or(rest.len());
                if n > 0 {
                    self.garbage_run(&rest[..n], time, emit);
                    i += n;
                    continue;
                }
                if let Some((end, inner_sync)) = valid_frame(rest) {
                    let stands = if inner_sync {
                        overlap(rest, end, false)
                    } else {
                        // No 0x54 inside: no frame starts in it, it stands.
                        Some(None)
                    };
                    match stands {
                        Some(None) => {
                            self.emit_in_place(&rest[..end], time, emit);
                            i += end;
                            continue;
                        }
                        Some(Some(_)) => {
                            // Rule 3: its 0x54 was a false one.
                            self.run_note(|r| r.false_syncs += 1);
                            self.garbage_byte(SYNC, time, emit);
                            i += 1;
                            continue;
                        }
                        // Decided byte by byte, with the bytes held.
                        None => {
                            self.step(data[i], time, emit);
                            i += 1;
                            continue;
                        }
                    }
                }
                match in_place(rest) {
                    // (valid_frame found every valid frame above)
                    InPlace::Frame(_) => {}
                    InPlace::BadLength => {
                        self.run_note(|r| r.bad_lengths += 1);
                        self.garbage_byte(SYNC, time, emit);
                        i += 1;
                        continue;
                    }
                    InPlace::FalseSync => {
                        self.run_note(|r| r.false_syncs += 1);
                        self.garbage_byte(SYNC, time, emit);
                        i += 1;
                        continue;
                    }
                    InPlace::BadCrc(end) => {
                        self.bad_in_place(&rest[..end], time, emit);
                        i += end;
                        continue;
                    }
                    InPlace::Undecided => {}
                }
            }
            self.step(data[i], time, emit);
            i += 1;
        }
    }

    /// The event of a frame (`SYNC LENGTH … CRC`) read in place at the stream position: its
    /// positions, times, length byte and body; the CRC is the caller's.
    #[inline(always)]
    fn in_place<'w>(&self, kind: EventKind, wire: &'w [u8], time: Option<u64>) -> Event<'w> {
        let n = wire.len();
        let mut ev = Event::new(kind, Framing::Sync, wire);
        ev.start_pos = self.base;
        ev.end_pos = self.base + n as u64;
        ev.start_time = time;
        ev.end_time = time;
        ev.length_byte = Some(wire[1]);
        ev.body = &wire[2..n - 1];
        ev
    }

    /// A bad frame read in place with nothing held: what [`Self::emit_span`] would emit for
    /// it.
    fn bad_in_place(&mut self, wire: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        let n = wire.len();
        let mut ev = self.in_place(EventKind::BadCrc, wire, time);
        ev.crc = Some((wire[n - 1] as u16, crc8(&wire[1..n - 1]) as u16));
        ev.crc_with_sync = crc8(&wire[..n - 1]) == wire[n - 1];
        emit(&ev);
        self.base += n as u64;
    }

    /// A valid frame read in place with nothing held: what [`Self::step`] would emit for its
    /// bytes. Inlined (the row of almost every frame starts here): the event is built in
    /// place.
    #[inline(always)]
    fn emit_in_place(&mut self, wire: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        let n = wire.len();
        let mut ev = self.in_place(EventKind::Frame, wire, time);
        let crc = wire[n - 1] as u16;
        ev.crc = Some((crc, crc));
        emit(&ev);
        self.frames += 1;
        self.base += n as u64;
    }

    /// Garbage bytes with nothing held (none of them 0x54), in rows of at most
    /// [`GARBAGE_ROW_MAX`]: [`Self::garbage_byte`] for each.
    fn garbage_run(&mut self, run: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let mut rest = run;
        while !rest.is_empty() {
            let r = &mut self.run;
            if r.len == 0 {
                r.start_pos = self.base;
                r.start_time = time;
                r.before_first = self.frames == 0;
            }
            let k = rest.len().min(GARBAGE_ROW_MAX - r.len);
            r.bytes[r.len..r.len + k].copy_from_slice(&rest[..k]);
            r.end_time = time;
            r.len += k;
            self.base += k as u64;
            rest = &rest[k..];
            if r.len == GARBAGE_ROW_MAX {
                self.flush_garbage(emit);
            }
        }
    }

    /// Feeds one byte.
    #[inline]
    pub fn step(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if self.len == 0 && b != SYNC {
            // Nothing held and no frame start: garbage, without going through the buffer.
            self.garbage_byte(b, time, emit);
            return;
        }
        if self.len == CAPACITY {
            // Cannot happen (see the module documentation); never panic on input, though.
            debug_assert!(false, "SAB v1 buffer overflow");
            self.known = self.known.max(1);
            self.garbage_front(emit);
        }
        self.buf[self.len] = b;
        self.times[self.len] = time;
        self.len += 1;
        self.process(false, emit);
    }

    /// End of input: decides every held byte (truncated candidates, garbage) and emits it.
    pub fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.process(true, emit);
        self.flush_garbage(emit);
    }

    /// A quiet line (or the end of detection's look): a valid frame held while the frames after
    /// it were awaited (rule 1) is emitted, since nothing is coming to take its place; then
    /// decoding goes on as before. Nothing else changes.
    pub fn settle(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if self.known == 0
            && let Some(end) = self.valid
        {
            self.emit_frame(end, emit);
            self.process(false, emit);
        }
    }

    /// A gap in the capture: emits the garbage collected so far and forgets the bytes of an
    /// unfinished candidate without reporting them.
    pub fn reset(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        self.base += self.len as u64;
        self.len = 0;
        self.known = 0;
        self.valid = None;
    }

    /// Emits the garbage collected so far as a row (a live source went quiet).
    #[inline]
    pub fn flush_garbage(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if self.run.len > 0 {
            self.emit_garbage(emit);
        }
    }

    /// [`Self::flush_garbage`] when there is garbage.
    fn emit_garbage(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        let r = &self.run;
        let mut ev = Event::new(EventKind::Garbage, Framing::Sync, &r.bytes[..r.len]);
        ev.start_pos = r.start_pos;
        ev.end_pos = r.start_pos + r.len as u64;
        ev.start_time = r.start_time;
        ev.end_time = r.end_time;
        ev.false_syncs = r.false_syncs;
        ev.bad_lengths = r.bad_lengths;
        ev.before_first = r.before_first;
        emit(&ev);
        self.run.len = 0;
        self.run.false_syncs = 0;
        self.run.bad_lengths = 0;
    }

    #[cfg(test)]
    /// Bytes held back while a candidate is undecided (for tests of the memory bound).
    pub fn held(&self) -> usize {
        self.len
    }

    fn check(&self, q: usize) -> Check {
        if self.buf[q] != SYNC {
            return Check::Invalid;
        }
        let Some(&length) = self.buf[..self.len].get(q + 1) else {
            return Check::Incomplete;
        };
        let length = length as usize;
        if length > MAX_PAYLOAD {
            return Check::Invalid;
        }
        let end = q + length + OVERHEAD;
        if end > self.len {
            return Check::Incomplete;
        }
        if crc8(&self.buf[q + 1..end - 1]) == self.buf[end - 1] {
            Check::Valid(end)
        } else {
            Check::Invalid
        }
    }

    fn process(&mut self, eof: bool, emit: &mut impl FnMut(&Event<'_>)) {
        while self.len > 0 {
            if self.known == 0 {
                if let Some(end) = self.valid {
                    match overlap(&self.buf[..self.len], end, eof) {
                        Some(None) => self.emit_frame(end, emit),
                        Some(Some(_)) => {
                            // Rule 3: its 0x54 was a false one.
                            self.valid = None;
                            self.run_note(|r| r.false_syncs += 1);
                            self.garbage_front(emit);
                        }
                        None => return,
                    }
                    continue;
                }
                match self.check(0) {
                    Check::Valid(end) => {
                        self.valid = Some(end);
                        continue;
                    }
                    Check::Incomplete if !eof => return,
                    _ => self.known = 1,
                }
            }
            // buf[0] does not start a valid frame.
            if self.buf[0] != SYNC {
                self.garbage_front(emit);
                continue;
            }
            if self.len < 2 {
                // Only at the end of the input: a lone 0x54.
                self.emit_span(EventKind::Truncated, 1, emit);
                continue;
            }
            let length = self.buf[1] as usize;
            if length > MAX_PAYLOAD {
                self.run_note(|r| r.bad_lengths += 1);
                self.garbage_front(emit);
                continue;
            }
            let full = length + OVERHEAD;
            // Shorter than `full` only at the end of the input.
            let span = full.min(self.len);
            // Does a valid frame start inside the rejected candidate?
            while self.valid.is_none() && self.known < span {
                match self.check(self.known) {
                    Check::Valid(end) => self.valid = Some(end),
                    Check::Incomplete if !eof => return,
                    _ => self.known += 1,
                }
            }
            if self.valid.is_some() && self.known < span {
                self.run_note(|r| r.false_syncs += 1);
                self.garbage_front(emit);
                continue;
            }
            let kind = if span < full {
                EventKind::Truncated
            } else {
                EventKind::BadCrc
            };
            self.emit_span(kind, span, emit);
        }
    }

    /// Notes something about the next garbage byte (the run may still be empty).
    fn run_note(&mut self, f: impl FnOnce(&mut Run)) {
        if self.run.len == 0 {
            self.run.false_syncs = 0;
            self.run.bad_lengths = 0;
        }
        f(&mut self.run);
    }

    /// Moves `buf[0]` into the garbage run.
    fn garbage_front(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        let (b, time) = (self.buf[0], self.times[0]);
        self.consume(1);
        self.base -= 1;
        self.garbage_byte(b, time, emit);
    }

    /// Appends the byte at stream offset `base` to the garbage run (and moves `base` past it).
    #[inline]
    fn garbage_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let r = &mut self.run;
        if r.len == 0 {
            r.start_pos = self.base;
            r.start_time = time;
            r.before_first = self.frames == 0;
        }
        r.bytes[r.len] = b;
        r.end_time = time;
        r.len += 1;
        self.base += 1;
        if r.len == GARBAGE_ROW_MAX {
            self.flush_garbage(emit);
        }
    }

    fn span_event(&self, kind: EventKind, n: usize) -> Event<'_> {
        let mut ev = Event::new(kind, Framing::Sync, &self.buf[..n]);
        ev.start_pos = self.base;
        ev.end_pos = self.base + n as u64;
        ev.start_time = self.times[0];
        ev.end_time = self.times[n - 1];
        ev.length_byte = self.buf[..n].get(1).copied();
        ev
    }

    fn emit_frame(&mut self, end: usize, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        let mut ev = self.span_event(EventKind::Frame, end);
        ev.body = &self.buf[2..end - 1];
        // (`check` found the CRC equal to the received one: not computed again)
        let crc = self.buf[end - 1] as u16;
        ev.crc = Some((crc, crc));
        emit(&ev);
        self.frames += 1;
        self.valid = None;
        self.consume(end);
    }

    fn emit_span(&mut self, kind: EventKind, n: usize, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        let mut ev = self.span_event(kind, n);
        if kind == EventKind::BadCrc {
            ev.body = &self.buf[2..n - 1];
            let computed = crc8(&self.buf[1..n - 1]);
            ev.crc = Some((self.buf[n - 1] as u16, computed as u16));
            ev.crc_with_sync = crc8(&self.buf[..n - 1]) == self.buf[n - 1];
        } else {
            ev.body = self.buf.get(2..n).unwrap_or(&[]);
        }
        emit(&ev);
        self.consume(n);
    }

    fn consume(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.times.copy_within(n..self.len, 0);
        self.len -= n;
        self.base += n as u64;
        self.known = self.known.saturating_sub(n);
        self.valid = self.valid.and_then(|e| e.checked_sub(n)).filter(|&e| e > 0);
    }
}

#[cfg(test)]
mod tests;
