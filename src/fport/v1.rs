//! The F.Port v1 reassembler: `7E [len][type][data][crc] 7E`, byte-stuffed.
//!
//! 0x7E never occurs inside a frame (stuffing), so every 0x7E ends whatever is open: a frame
//! cut short by it is `Truncated` and the next frame is read from that 0x7E on, never lost.
//! A frame is whole when `len + 2` unstuffed bytes (length, type, data, checksum) arrived.
//!
//! Receivers send `7E frame 7E`; flight controllers answer without delimiters (Betaflight and
//! ArduPilot write `08 81 payload crc` right after the receiver's closing 0x7E, ArduPilot
//! optionally after a 0xFF pad byte). So after a frame, a segment that starts with the
//! telemetry length 0x08 (or 0x19, or 0xFF then one of them) is read as a frame too. A frame
//! that began with 0x7E takes the 0x7E right after it as its closing delimiter, which is why it
//! comes out with the next byte (or at [`V1::finish`]).

use super::frame::{Check, Event, Frame, Role, Run};
use super::wire::{
    ESCAPE, START, V1_CONTROL, V1_CONTROL_LEN, V1_DOWNLINK, V1_MAX_LEN, V1_TELEMETRY_LEN,
    V1_UPLINK, check_ok,
};

/// ArduPilot's optional padding byte before an uplink frame.
const PAD: u8 = 0xFF;
/// Most wire bytes a frame can take: a leading extra 0x7E, the opening 0x7E or the pad, the
/// stuffed body (every byte doubled) and the closing 0x7E.
const MAX_RAW: usize = 3 + 2 * (V1_MAX_LEN as usize + 2);

/// The F.Port v1 reassembler: bytes and times in, [`Event`]s out, the same whatever the split.
#[derive(Clone, Debug)]
pub struct V1 {
    /// Stream offset of the next byte.
    pos: u64,
    /// A frame is being collected in `raw`/`body`.
    open: bool,
    /// It began with 0x7E.
    opened: bool,
    /// A whole frame that began with 0x7E, waiting to see whether a closing 0x7E follows.
    pending: Option<Check>,
    /// The event before was a frame: an undelimited answer may follow.
    after_frame: bool,
    escaped: bool,
    unusual: bool,
    pad: bool,
    time: Option<u64>,
    offset: u64,
    raw: Vec<u8>,
    body: Vec<u8>,
    garbage: Run,
}

impl Default for V1 {
    fn default() -> Self {
        V1 {
            pos: 0,
            open: false,
            opened: false,
            pending: None,
            after_frame: false,
            escaped: false,
            unusual: false,
            pad: false,
            time: None,
            offset: 0,
            raw: Vec::with_capacity(MAX_RAW),
            body: Vec::with_capacity(V1_MAX_LEN as usize + 2),
            garbage: Run::default(),
        }
    }
}

impl V1 {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds `data` that arrived at `time`; calls `emit` for every completed event.
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        for &b in data {
            self.byte(b, time, emit);
            self.pos += 1;
        }
    }

    /// End of input (or a gap): a waiting frame comes out without its closing delimiter, an
    /// open one as `Truncated`, then the garbage.
    pub fn finish(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        if let Some(check) = self.pending.take() {
            self.emit_frame(check, emit);
        } else if self.open {
            if self.body.is_empty() {
                self.drop_segment(emit);
            } else {
                self.emit_frame(Check::Cut, emit);
            }
        }
        self.garbage.flush(emit);
        self.after_frame = false;
    }

    /// A live line went quiet: a frame waiting for its closing delimiter comes out.
    pub fn idle(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        if let Some(check) = self.pending.take() {
            self.emit_frame(check, emit);
        }
    }

    #[inline]
    fn byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        if let Some(check) = self.pending.take() {
            if b == START {
                self.raw.push(b);
                self.emit_frame(check, emit);
                return;
            }
            self.emit_frame(check, emit);
        }
        if b == START {
            self.start(b, time, emit);
            return;
        }
        if !self.open {
            if self.after_frame && matches!(b, V1_TELEMETRY_LEN | V1_CONTROL_LEN | PAD) {
                self.begin(false, time);
                if b == PAD {
                    self.pad = true;
                    self.raw.push(b);
                    return;
                }
                self.raw.push(b);
                self.body.push(b);
                return;
            }
            self.after_frame = false;
            self.garbage.push(b, time, self.pos, emit);
            return;
        }
        self.raw.push(b);
        let u = if self.escaped {
            self.escaped = false;
            if !matches!(b, 0x5E | 0x5D) {
                self.unusual = true;
            }
            b ^ 0x20
        } else if b == ESCAPE {
            self.escaped = true;
            return;
        } else {
            b
        };
        self.body.push(u);
        if self.body.len() == 1 {
            let known = matches!(u, V1_TELEMETRY_LEN | V1_CONTROL_LEN);
            if u == 0 || u > V1_MAX_LEN || (!self.opened && !known) {
                // Not a frame: the segment is garbage up to the next 0x7E.
                self.drop_segment(emit);
                return;
            }
        }
        let len = self.body[0] as usize;
        if self.body.len() == len + 2 {
            let check = if check_ok(&self.body) {
                Check::Ok
            } else {
                Check::Bad
            };
            if self.opened {
                self.pending = Some(check);
            } else {
                self.emit_frame(check, emit);
            }
        }
    }

    /// A 0x7E: ends what is open and starts a frame.
    fn start(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        if self.open {
            if !self.body.is_empty() {
                self.emit_frame(Check::Cut, emit);
            } else if self.opened && !self.pad && self.raw.len() == 1 {
                // `7E 7E`: the first one is a closing delimiter nothing claimed (an answer that
                // ended with one); it stays with the frame that follows.
                self.raw.push(b);
                return;
            } else {
                self.drop_segment(emit);
            }
        }
        self.begin(true, time);
        self.raw.push(b);
    }

    fn begin(&mut self, opened: bool, time: Option<u64>) {
        self.open = true;
        self.opened = opened;
        self.escaped = false;
        self.unusual = false;
        self.pad = false;
        self.time = time;
        self.offset = self.pos;
        self.raw.clear();
        self.body.clear();
    }

    /// The open segment's bytes become garbage; bytes up to the next 0x7E follow them there.
    fn drop_segment(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        let (time, offset) = (self.time, self.offset);
        for (i, &b) in self.raw.iter().enumerate() {
            self.garbage.push(b, time, offset + i as u64, emit);
        }
        self.open = false;
        self.after_frame = false;
        self.raw.clear();
        self.body.clear();
    }

    fn emit_frame(&mut self, check: Check, emit: &mut impl FnMut(Event<'_>)) {
        self.garbage.flush(emit);
        let role = match self.body.get(1) {
            Some(&V1_CONTROL) => Role::Control,
            Some(&V1_DOWNLINK) => Role::Downlink,
            Some(&V1_UPLINK) => Role::Uplink,
            _ => Role::Unknown,
        };
        emit(Event::Frame(Frame {
            time: self.time,
            offset: self.offset,
            raw: &self.raw,
            body: &self.body,
            check,
            role,
            guessed: false,
            unusual_escape: self.unusual,
            pad: self.pad,
            ota_resized: false,
        }));
        self.open = false;
        self.after_frame = check != Check::Cut;
        self.raw.clear();
        self.body.clear();
    }
}
