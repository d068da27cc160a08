//! The SM2 data mode and secure data-mode framer. A raw 0xB5 starts every telegram (inside a
//! telegram B5 and C5 travel as the DLE pairs `C5 00` / `C5 01`). A telegram ends at the next
//! raw B5, at a time gap, at the end of the input, or as soon as its length is known and its CRC
//! checks (requests: the command table; ACK/NAK: 2 bytes; responses: the length the last request
//! asked for; secure telegrams: their LEN byte).

use super::{CrcCheck, Event, Frame, GapClock, GarbageRun, Secure, Tele, classify, expect_of};
use crate::sbus::commands::{self, Expect};
use crate::sbus::telegram::{
    AT_ACKNAK, AT_REQUEST, AT_RESPONSE, AT_SECURE_REQUEST, AT_SECURE_RESPONSE, CrcBasis, DLE, FS,
    crc_step, crc16, crc16_from,
};

/// Longest data-mode telegram kept on the wire (longer ones are cut and reported).
pub const MAX_WIRE: usize = 1024;

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

/// The logical length (AT … CRC) the open telegram must have, as far as its bytes tell yet.
/// Worked out once it is knowable and kept: it never changes while the telegram grows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Known {
    /// Not yet: more bytes tell (a request's command or its length byte).
    NotYet,
    /// Never: the telegram ends at the next B5, a gap or the end of the input.
    Never,
    Len(usize),
}

/// Pure SM2 / secure data-mode reassembler.
#[derive(Clone, Debug)]
pub struct DataFramer {
    phase: Phase,
    dle: bool,
    wire: Vec<u8>,
    /// Logical bytes of the standard telegram after its FS: AT, payload, CRC.
    tele: Vec<u8>,
    /// Offsets in `wire` where the last two logical bytes of `tele` start (the one before
    /// last, the last): the CRC check needs where the CRC field starts on the wire.
    tele_at: [usize; 2],
    /// Offset in `wire` of the standard telegram's FS (0, or after the secure header).
    tele_fs: usize,
    /// The logical bytes (AT … CRC) of the telegram [`Self::whole_telegram`] reads.
    logical: Box<[u8; MAX_WIRE]>,
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
    /// The open telegram's length, once known.
    known: Known,
}

impl DataFramer {
    /// `gap`: a silence longer than this (µs) ends an open telegram (sources with time only).
    pub fn new(gap: Option<u64>) -> Self {
        DataFramer {
            phase: Phase::Outside,
            dle: false,
            wire: Vec::with_capacity(MAX_WIRE),
            tele: Vec::with_capacity(MAX_WIRE),
            tele_at: [0; 2],
            tele_fs: 0,
            logical: Box::new([0; MAX_WIRE]),
            secure: None,
            problem: None,
            no_inner: false,
            time: None,
            offset: 0,
            pos: 0,
            garbage: GarbageRun::default(),
            clock: GapClock { gap, last: None },
            expect: Expect::Nothing,
            known: Known::NotYet,
        }
    }

    /// Feeds `data` that arrived at `time`.
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let mut i = 0;
        while i < data.len() {
            if self.clock.gap_before(time) {
                self.close(emit);
                self.garbage.flush(emit);
            }
            // Inside a telegram, a run of bytes that are neither B5 nor C5 is taken whole (the
            // gap rule cannot end it: every byte of `data` arrived at the same time).
            let n = self.plain_run(&data[i..]);
            if n > 0 {
                self.take_run(&data[i..i + n], emit);
                i += n;
                self.pos += n as u64;
                continue;
            }
            self.byte(data[i], time, emit);
            self.pos += 1;
            i += 1;
            if data[i - 1] == FS && self.phase == Phase::At {
                // A telegram just started: take it whole if it is all in `data`.
                let n = self.whole_telegram(&data[i - 1..], emit);
                i += n;
                self.pos += n as u64;
            }
        }
    }

    /// The fast path for the usual telegram: a standard one (no secure header) whose bytes
    /// after the FS are all in `framed` (its FS first), with no raw B5, no invalid DLE pair, a
    /// known length and a CRC that checks. Its logical bytes are unescaped into
    /// [`Self::logical`] in one loop (eight wire bytes a step between DLE pairs), without the
    /// byte-by-byte state machine, and it is emitted as [`Self::close_checked`] would emit it;
    /// returns how many bytes after the FS it took. Anything else (the end of `framed` first,
    /// a raw B5, an unknown length, a bad CRC, a secure header, [`MAX_WIRE`]) takes nothing
    /// and leaves the telegram as [`Self::start`] opened it, for [`Self::byte`] to read again
    /// from its first byte after the FS: so the events are those of the byte-by-byte path,
    /// however the input is split (the gap rule cannot end the telegram either: every byte of
    /// `framed` arrived at the same time).
    fn whole_telegram(&mut self, framed: &[u8], emit: &mut impl FnMut(&Event<'_>)) -> usize {
        debug_assert!(self.wire.len() == 1 && self.tele.is_empty() && self.secure.is_none());
        let data = framed.get(1..).unwrap_or_default();
        let data = &data[..data.len().min(MAX_WIRE - 1)];
        let buf = &mut *self.logical;
        // `n` logical bytes in `buf` from `j` wire bytes of `data`. The header, one logical
        // byte at a time until the length `k` is known.
        let (mut n, mut j) = (0, 0);
        let k = loop {
            let Some((v, w)) = logical_at(data, j) else {
                return 0;
            };
            if n == 0 && (v == AT_SECURE_REQUEST || v == AT_SECURE_RESPONSE) {
                return 0;
            }
            // n <= j < data.len() < MAX_WIRE
            let Some(slot) = buf.get_mut(n) else {
                return 0;
            };
            *slot = v;
            n += 1;
            j += w;
            match standard_len(&buf[..n], self.expect) {
                Known::NotYet => {}
                // (a telegram has at least as many wire bytes as logical ones)
                Known::Len(k) if k >= n && k >= 3 && k <= data.len() => break k,
                _ => return 0,
            }
        };
        // The rest: eight wire bytes a step copied whole, as many of them taken as come before
        // a B5 or a C5 (and the telegram's end; the bytes after those in `buf` are written
        // over or never read); a DLE pair, and the last bytes, one at a time.
        while n < k {
            if let (Some(src), Some(dst)) = (data.get(j..j + 8), buf.get_mut(n..n + 8)) {
                let x = u64::from_le_bytes(src.try_into().unwrap_or([0; 8]));
                dst.copy_from_slice(&x.to_le_bytes());
                let p = plain_prefix(x).min(k - n);
                if p > 0 {
                    n += p;
                    j += p;
                    continue;
                }
            }
            let (Some((v, w)), Some(slot)) = (logical_at(data, j), buf.get_mut(n)) else {
                return 0;
            };
            *slot = v;
            n += 1;
            j += w;
        }
        let tele = &buf[..k];
        let got = u16::from_be_bytes([tele[k - 2], tele[k - 1]]);
        let unescaped = crc16_from(crc_step(0, FS), &tele[..k - 2]);
        // The escaped reading: over the wire bytes before the CRC field (the same bytes when
        // no DLE pair came before it).
        let e = crc_field_at(data, j);
        let escaped = if e == k - 2 {
            unescaped
        } else {
            crc16_from(crc_step(0, FS), data.get(..e).unwrap_or_default())
        };
        let basis = match (got == escaped, got == unescaped) {
            (true, true) => CrcBasis::Both,
            (true, false) => CrcBasis::Escaped,
            (false, true) => CrcBasis::Unescaped,
            (false, false) => return 0,
        };
        // What `close_checked` emits for it.
        let t = classify(tele[0], &tele[1..k - 2]);
        match t {
            Tele::Request { station, cmd, body } => self.expect = expect_of(station, cmd, body),
            Tele::Response { .. } | Tele::AckNak { .. } => self.expect = Expect::Nothing,
            _ => {}
        }
        emit(&Event::Frame(Frame {
            time: self.time,
            offset: self.offset,
            wire: &framed[..1 + j],
            tele: t,
            crc: CrcCheck::Ok(basis),
            secure: None,
            problem: None,
            break_before: false,
            length_mismatch: false,
        }));
        self.phase = Phase::Outside;
        self.dle = false;
        j
    }

    /// How many of the first bytes of `data` can be taken as one run of logical bytes: inside a
    /// standard telegram's body, no DLE pending, whose length is settled (known or known never
    /// to be); neither B5 nor C5; within [`MAX_WIRE`]; and not past the byte that completes
    /// the known length (its CRC is checked then). 0: take the next byte alone.
    fn plain_run(&self, data: &[u8]) -> usize {
        if self.phase != Phase::Body || self.dle {
            return 0;
        }
        let mut limit = MAX_WIRE.saturating_sub(self.wire.len()).min(data.len());
        match self.known {
            Known::NotYet => return 0,
            Known::Len(k) if k > self.tele.len() => limit = limit.min(k - self.tele.len()),
            _ => {}
        }
        let data = &data[..limit];
        data.iter()
            .position(|&b| b == FS || b == DLE)
            .unwrap_or(data.len())
    }

    /// Takes a run found by [`Self::plain_run`]: what [`Self::byte`] does for each of its
    /// bytes.
    fn take_run(&mut self, run: &[u8], emit: &mut impl FnMut(&Event<'_>)) {
        let at = self.wire.len();
        self.wire.extend_from_slice(run);
        self.tele.extend_from_slice(run);
        let end = at + run.len();
        self.tele_at = if run.len() >= 2 {
            [end - 2, end - 1]
        } else {
            [self.tele_at[1], at]
        };
        self.check_known(emit);
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
        self.tele_at = [0; 2];
        self.tele_fs = 0;
        self.secure = None;
        self.problem = None;
        self.no_inner = false;
        self.time = time;
        self.offset = self.pos;
        self.known = Known::NotYet;
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
        self.tele_at = [0; 2];
        self.known = Known::NotYet;
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
        self.tele_at = [self.tele_at[1], wire_at];
        if self.known == Known::NotYet {
            self.known = self.complete_len();
        }
        self.check_known(emit);
    }

    /// Closes the telegram when its known length is reached (a standard one only if its CRC
    /// checks).
    fn check_known(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if self.known == Known::Len(self.tele.len()) {
            if self.secure.is_some() {
                self.close(emit);
            } else {
                let crc = self.crc_check();
                if crc.ok() {
                    self.close_checked(Some(crc), emit);
                }
            }
        }
    }

    /// The logical length (AT … CRC) the open telegram must have, as far as its bytes tell.
    fn complete_len(&self) -> Known {
        use Known::{Len, Never};
        if let Some(s) = &self.secure {
            // LEN counts the inner FS too.
            return match (s.len as usize).checked_sub(1).filter(|&n| n > 0) {
                Some(n) => Len(n),
                None => Never,
            };
        }
        standard_len(&self.tele, self.expect)
    }

    /// Checks the CRC of the open standard telegram both ways.
    fn crc_check(&self) -> CrcCheck {
        let n = self.tele.len();
        if n < 3 {
            return CrcCheck::None;
        }
        let got = u16::from_be_bytes([self.tele[n - 2], self.tele[n - 1]]);
        let unescaped = crate::sbus::telegram::crc16_from(
            crate::sbus::telegram::crc_step(0, FS),
            &self.tele[..n - 2],
        );
        let crc_wire = self.tele_at[0];
        // Both readings in one pass when no DLE pair was undone before the CRC (the usual
        // case): the wire then holds the same bytes as the logical telegram.
        let escaped = if self.wire[self.tele_fs] == FS && crc_wire - self.tele_fs == n - 1 {
            unescaped
        } else {
            crc16(&self.wire[self.tele_fs..crc_wire])
        };
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
        self.close_checked(None, emit);
    }

    /// [`Self::close`] with the CRC check of the open telegram when it is already done.
    fn close_checked(&mut self, checked: Option<CrcCheck>, emit: &mut impl FnMut(&Event<'_>)) {
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
            let crc = checked.unwrap_or_else(|| self.crc_check());
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

/// The logical length (AT … CRC) a standard telegram must have, as far as its logical bytes
/// `t` (AT first) tell; `expect`: what the last request asked for.
fn standard_len(t: &[u8], expect: Expect) -> Known {
    use Known::{Len, Never, NotYet};
    let Some(&at) = t.first() else {
        return NotYet;
    };
    match at {
        AT_ACKNAK => Len(1 + 2 + 2),
        AT_REQUEST => {
            if t.len() < 3 {
                return NotYet;
            }
            let Some(cmd) = commands::command(t[2]) else {
                return Never;
            };
            match cmd.layout.body_len(&t[3..]) {
                Some(Ok(n)) => Len(1 + 2 + n + 2),
                Some(Err(_)) => NotYet,
                None => Never,
            }
        }
        AT_RESPONSE => match expect {
            Expect::Data(n) => Len(1 + n + 2),
            Expect::LengthPrefixed => match t.get(1) {
                Some(&n) => Len(1 + 1 + n as usize + 2),
                None => NotYet,
            },
            _ => Never,
        },
        _ => Never,
    }
}

/// How many of the eight bytes of `x` (little-endian: its first byte lowest) come before the
/// first B5 or C5 in it (8: none). A byte of `x ^ b` is 0 where `x` has `b`, and
/// `(y - 0x01…) & !y & 0x80…` marks the lowest zero byte of `y` exactly (a borrow can mark
/// a byte above it, never one below).
fn plain_prefix(x: u64) -> usize {
    const ONES: u64 = u64::from_ne_bytes([0x01; 8]);
    const HIGH: u64 = u64::from_ne_bytes([0x80; 8]);
    let zero = |y: u64| y.wrapping_sub(ONES) & !y & HIGH;
    let hit = zero(x ^ (ONES * u64::from(FS))) | zero(x ^ (ONES * u64::from(DLE)));
    (hit.trailing_zeros() / 8) as usize
}

/// Where the CRC field (the last two logical bytes) of a telegram read from the first `end`
/// bytes of `data` (after its FS) starts: a logical byte is one wire byte, or a DLE pair.
/// A C5 in a telegram read whole always starts a pair (its second byte is 00 or 01), so a
/// C5 two bytes before where a logical byte ends is that byte's pair.
fn crc_field_at(data: &[u8], end: usize) -> usize {
    let mut e = end;
    for _ in 0..2 {
        let w = if e >= 2 && data.get(e - 2) == Some(&DLE) {
            2
        } else {
            1
        };
        e = e.saturating_sub(w);
    }
    e
}

/// The logical byte at `data[j]` (after a standard telegram's FS) and how many wire bytes it
/// takes (2 for a DLE pair); `None` at the end of `data`, at a raw B5 and at a C5 not followed
/// by 00 or 01 (or by nothing yet): where [`DataFramer::whole_telegram`] gives up.
fn logical_at(data: &[u8], j: usize) -> Option<(u8, usize)> {
    match *data.get(j)? {
        FS => None,
        DLE => match *data.get(j + 1)? {
            0x00 => Some((FS, 2)),
            0x01 => Some((DLE, 2)),
            _ => None,
        },
        b => Some((b, 1)),
    }
}

/// The problem noted when a secure header is not followed by a telegram.
const NO_INNER_TELEGRAM: &str = "secure header not followed by a telegram (B5)";

#[cfg(test)]
mod tests;
