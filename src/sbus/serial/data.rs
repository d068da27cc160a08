//! The SM2 data mode and secure data-mode framer. A raw 0xB5 starts every telegram (inside a
//! telegram B5 and C5 travel as the DLE pairs `C5 00` / `C5 01`). A telegram ends at the next
//! raw B5, at a time gap, at the end of the input, or as soon as its length is known and its CRC
//! checks (requests: the command table; ACK/NAK: 2 bytes; responses: the length the last request
//! asked for; secure telegrams: their LEN byte).

use super::{CrcCheck, Event, Frame, GapClock, GarbageRun, Secure, Tele, classify, expect_of};
use crate::sbus::commands::{self, Expect};
use crate::sbus::telegram::{
    AT_ACKNAK, AT_REQUEST, AT_RESPONSE, AT_SECURE_REQUEST, AT_SECURE_RESPONSE, CrcBasis, DLE, FS,
    crc16,
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
        let mut d = crate::sbus::telegram::CRC.digest();
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
