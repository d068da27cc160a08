//! The F.Port 2 / FBUS reassembler: `[len][type][data][crc]`, no delimiters, no stuffing.
//!
//! Frames are recognised by their first two bytes and checked by their checksum:
//!
//! * control: `0D|18|23 FF` (8, 16 or 24 channels), OTA control `18|20 F0|F1|F2`;
//! * telemetry: `08 [physical ID]`, a downlink right after a control frame, an uplink right
//!   after a downlink (INAV accepts a downlink only there). Elsewhere an `08` frame is taken
//!   only when its checksum passes and its physical ID byte has valid S.Port check bits, and
//!   its direction is guessed.
//!
//! Resynchronisation: a control frame (or an expected telemetry frame) whose checksum fails
//! may be a frame cut short with the next one inside its length. The bytes it spans are
//! searched for a frame start whose whole frame passes its checksum; if one is found, the
//! broken frame is `Truncated` there and the found frame follows, so the good frame after a
//! bad one is never lost. Only then is it `BadCRC`. The search waits for the bytes it needs
//! (at most two frames' worth are ever held), so the result does not depend on the split.

use super::frame::{Check, Event, Frame, Role, Run};
use super::wire::{
    OTA_START, OTA_STOP, V2_CHANNELS, V2_CONTROL_8, V2_CONTROL_16, V2_CONTROL_24, V2_OTA_LEN,
    V2_TELEMETRY_LEN, check_ok,
};
use crate::sport::wire::header_ok;

/// What the frame before was (what an `08` frame now is).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ctx {
    /// Nothing known (start, after garbage or a cut frame of unknown kind).
    None,
    Control,
    Downlink,
    Uplink,
}

impl Ctx {
    fn after(role: Role) -> Ctx {
        match role {
            Role::Control => Ctx::Control,
            Role::Downlink => Ctx::Downlink,
            Role::Uplink => Ctx::Uplink,
            Role::Unknown => Ctx::None,
        }
    }
}

/// What starts at a position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Cand {
    /// No frame starts here.
    No,
    /// A frame may start here; more bytes are needed to tell. `strong`: its first bytes are a
    /// frame start by themselves (a cut frame if the input ends).
    More { strong: bool, role: Role },
    Frame {
        total: usize,
        ok: bool,
        role: Role,
        guessed: bool,
        resized: bool,
    },
}

/// The F.Port 2 reassembler: bytes and times in, [`Event`]s out, the same whatever the split.
#[derive(Clone, Debug)]
pub struct V2 {
    /// Bytes not yet consumed start at `head`.
    buf: Vec<u8>,
    head: usize,
    /// `(index into buf, time)`: the bytes from that index on arrived at that time.
    marks: Vec<(usize, Option<u64>)>,
    /// Stream offset of `buf[0]`.
    base: u64,
    ctx: Ctx,
    garbage: Run,
}

impl Default for V2 {
    fn default() -> Self {
        V2 {
            buf: Vec::new(),
            head: 0,
            marks: Vec::new(),
            base: 0,
            ctx: Ctx::None,
            garbage: Run::default(),
        }
    }
}

impl V2 {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds `data` that arrived at `time`; calls `emit` for every completed event.
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        if data.is_empty() {
            return;
        }
        self.marks.push((self.buf.len(), time));
        self.buf.extend_from_slice(data);
        self.run(false, emit);
        self.compact();
    }

    /// End of input (or a gap): what is held comes out (cut frames, garbage).
    pub fn finish(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        self.run(true, emit);
        self.garbage.flush(emit);
        self.compact();
        self.ctx = Ctx::None;
    }

    fn compact(&mut self) {
        if self.head == 0 {
            return;
        }
        let head = self.head;
        self.buf.drain(..head);
        self.base += head as u64;
        self.head = 0;
        // The mark in force at `head` moves to 0; the ones after it shift.
        let keep = self
            .marks
            .partition_point(|&(i, _)| i <= head)
            .saturating_sub(1);
        self.marks.drain(..keep);
        for m in &mut self.marks {
            m.0 = m.0.saturating_sub(head);
        }
        if self.buf.is_empty() {
            self.marks.clear();
        }
    }

    fn time_at(&self, i: usize) -> Option<u64> {
        let n = self.marks.partition_point(|&(at, _)| at <= i);
        n.checked_sub(1).and_then(|k| self.marks[k].1)
    }

    fn run(&mut self, eof: bool, emit: &mut impl FnMut(Event<'_>)) {
        while self.head < self.buf.len() {
            let head = self.head;
            match self.candidate(head, self.ctx, eof) {
                Cand::No => self.garbage_byte(emit),
                Cand::More { strong, role } => {
                    if !eof {
                        return;
                    }
                    if !strong {
                        self.garbage_byte(emit);
                        continue;
                    }
                    // Cut by the end of the input; a whole frame inside it comes out after it.
                    let end = self.buf.len() - head;
                    let ctx = Ctx::after(role);
                    let at = self.inner(head, end, ctx, true).unwrap_or(None);
                    self.frame(at.unwrap_or(end), Check::Cut, role, false, false, emit);
                    self.ctx = ctx;
                }
                Cand::Frame {
                    total,
                    ok: true,
                    role,
                    guessed,
                    resized,
                } => {
                    self.frame(total, Check::Ok, role, guessed, resized, emit);
                    self.ctx = Ctx::after(role);
                }
                Cand::Frame {
                    total,
                    ok: false,
                    role,
                    ..
                } => {
                    let ctx = Ctx::after(role);
                    match self.inner(head, total, ctx, eof) {
                        None => return,
                        Some(Some(q)) => self.frame(q, Check::Cut, role, false, false, emit),
                        Some(None) => self.frame(total, Check::Bad, role, false, false, emit),
                    }
                    self.ctx = ctx;
                }
            }
        }
    }

    /// The first position `head + q` (`0 < q < span`) where a frame passing its checksum
    /// starts: `Some(Some(q))`, `Some(None)` when there is none, `None` when more bytes are
    /// needed to know.
    fn inner(&self, head: usize, span: usize, ctx: Ctx, eof: bool) -> Option<Option<usize>> {
        for q in 1..span {
            match self.candidate(head + q, ctx, eof) {
                Cand::Frame { ok: true, .. } => return Some(Some(q)),
                Cand::More { .. } if !eof => return None,
                _ => {}
            }
        }
        Some(None)
    }

    fn garbage_byte(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        let i = self.head;
        let (b, time, offset) = (self.buf[i], self.time_at(i), self.base + i as u64);
        self.garbage.push(b, time, offset, emit);
        self.head += 1;
        self.ctx = Ctx::None;
    }

    fn frame(
        &mut self,
        len: usize,
        check: Check,
        role: Role,
        guessed: bool,
        ota_resized: bool,
        emit: &mut impl FnMut(Event<'_>),
    ) {
        self.garbage.flush(emit);
        let i = self.head;
        let bytes = &self.buf[i..i + len];
        emit(Event::Frame(Frame {
            time: self.time_at(i),
            offset: self.base + i as u64,
            raw: bytes,
            body: bytes,
            check,
            role,
            guessed,
            unusual_escape: false,
            pad: false,
            ota_resized,
        }));
        self.head += len;
    }

    /// What starts at `buf[p]` when the frame before was `ctx`.
    fn candidate(&self, p: usize, ctx: Ctx, eof: bool) -> Cand {
        let buf = &self.buf;
        let weak = Cand::More {
            strong: false,
            role: Role::Unknown,
        };
        let Some(&b0) = buf.get(p) else {
            return weak;
        };
        if !matches!(
            b0,
            V2_CONTROL_8 | V2_CONTROL_16 | V2_CONTROL_24 | V2_OTA_LEN | V2_TELEMETRY_LEN
        ) {
            return Cand::No;
        }
        let Some(&b1) = buf.get(p + 1) else {
            return weak;
        };
        let whole = |total: usize| buf.get(p + 1..p + total).map(check_ok);
        let (total, role, strong, guessed) = match (b0, b1) {
            (V2_CONTROL_8 | V2_CONTROL_16 | V2_CONTROL_24, V2_CHANNELS) => {
                (b0 as usize + 3, Role::Control, true, false)
            }
            (V2_CONTROL_16 | V2_OTA_LEN, OTA_START..=OTA_STOP) => {
                // Sized by the length byte; INAV sizes by the type (32 data bytes for OTA
                // data, 24 for start and stop): the other size is taken when only it checks.
                let total = b0 as usize + 3;
                let other = if b0 == V2_OTA_LEN {
                    V2_CONTROL_16
                } else {
                    V2_OTA_LEN
                } as usize
                    + 3;
                return match (whole(total), whole(other)) {
                    (Some(true), _) => frame(total, true, Role::Control, false, false),
                    (Some(false), Some(true)) => frame(other, true, Role::Control, false, true),
                    (Some(false), Some(false)) => frame(total, false, Role::Control, false, false),
                    (Some(false), None) if eof => frame(total, false, Role::Control, false, false),
                    _ => Cand::More {
                        strong: true,
                        role: Role::Control,
                    },
                };
            }
            (V2_TELEMETRY_LEN, _) => match ctx {
                Ctx::Control => (10, Role::Downlink, true, false),
                Ctx::Downlink => (10, Role::Uplink, true, false),
                _ if header_ok(b1) => {
                    // No control frame before it: an answer carries data or a reply, a
                    // poll or a request anything else.
                    let role = match buf.get(p + 2) {
                        Some(0x10 | 0x32) => Role::Uplink,
                        _ => Role::Downlink,
                    };
                    (10, role, false, true)
                }
                _ => return Cand::No,
            },
            _ => return Cand::No,
        };
        match whole(total) {
            None => Cand::More { strong, role },
            Some(ok) if ok || strong => frame(total, ok, role, guessed, false),
            Some(_) => Cand::No,
        }
    }
}

fn frame(total: usize, ok: bool, role: Role, guessed: bool, resized: bool) -> Cand {
    Cand::Frame {
        total,
        ok,
        role,
        guessed,
        resized,
    }
}
