//! SAB2 framing as modm's code sends it: `7E HDR CMD DATA CRClo CRChi 7E`, the pure
//! reassembler and an encoder.
//!
//! * Every 0x7E or 0x7D between the flags is sent as `7D, byte ^ 0x20`.
//! * The CRC is CRC-16/MODBUS (AVR `_crc16_update`, init 0xFFFF, no final XOR) over the
//!   unescaped HEADER, COMMAND and DATA, sent low byte first.
//! * A frame has at least 4 unescaped bytes; the payload has at most `N` bytes, `N` being a
//!   template parameter of `modm::sab2::Interface` (32 unless the application changes it).
//!
//! The receiver follows modm's rules: **every 0x7E ends the current frame and starts a new
//! one**; `7D 7E` aborts the frame; nothing between two flags is normal (back-to-back frames
//! look like `7E … 7E 7E … 7E`); 1 to 3 bytes between flags are a runt. Unlike modm it reports
//! runts, aborts and overlong frames instead of dropping them silently, and it decodes a frame
//! longer than the configured maximum when its CRC is valid (a device built with a larger `N`).

use crc::{CRC_16_MODBUS, Crc, Table};

use super::frame::{Event, EventKind, Framing, find, find2};

/// Frame delimiter.
pub const FLAG: u8 = 0x7E;
/// Escape byte.
pub const ESCAPE: u8 = 0x7D;
/// HEADER, COMMAND and the two CRC bytes.
pub const OVERHEAD: usize = 4;
/// modm's default payload limit (`Interface<Device, N = 32>`).
pub const DEFAULT_MAX_PAYLOAD: usize = 32;
/// Unescaped bytes kept whole at most (a payload of up to 255 bytes). Longer runs between
/// flags are reported as overlong without a CRC check.
pub const STORE_MAX: usize = OVERHEAD + 255;
/// Wire bytes kept at most for a row.
pub const WIRE_MAX: usize = 2 + 2 * STORE_MAX;
use crate::row::GARBAGE_ROW_MAX;
/// Bytes between flags that [`Reassembler::unescape_run`] takes one by one (a usual frame's);
/// longer runs go stretch by stretch.
const SHORT_RUN: usize = 16;

/// Slice-by-16 tables: every byte between two flags of either framing's traffic goes through
/// this CRC (the background framing of the detection checks SAB v1 data with it too).
static CRC16: Crc<u16, Table<16>> = Crc::<u16, Table<16>>::new(&CRC_16_MODBUS);

/// Bytes up to which [`crc16`] goes a byte at a time: a frame's usual body (header,
/// command, a few payload bytes) is shorter than the slice-by-16 loop's stride, and the call
/// into it costs more than the bytes.
const SHORT_CRC: usize = 16;

/// CRC-16/MODBUS by byte (reflected polynomial 0xA001): the table of [`crc16`]'s short path.
static CRC16_BYTE: [u16; 256] = {
    let mut t = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u16;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xA001
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// CRC-16/MODBUS of `bytes` (HEADER … DATA of a frame).
#[inline]
pub fn crc16(bytes: &[u8]) -> u16 {
    if bytes.len() <= SHORT_CRC {
        let mut c = 0xFFFFu16;
        for &b in bytes {
            c = (c >> 8) ^ CRC16_BYTE[usize::from((c as u8) ^ b)];
        }
        return c;
    }
    CRC16.checksum(bytes)
}

/// Appends `byte`, escaped if it is a flag or an escape.
pub fn push_escaped(out: &mut Vec<u8>, byte: u8) {
    if byte == FLAG || byte == ESCAPE {
        out.push(ESCAPE);
        out.push(byte ^ 0x20);
    } else {
        out.push(byte);
    }
}

/// Appends a frame as modm sends it: opening flag, escaped body and CRC, closing flag.
pub fn encode(out: &mut Vec<u8>, header: u8, command: u8, payload: &[u8]) {
    let mut crc = CRC16.digest();
    crc.update(&[header, command]);
    crc.update(payload);
    let crc = crc.finalize();
    out.push(FLAG);
    push_escaped(out, header);
    push_escaped(out, command);
    for &b in payload {
        push_escaped(out, b);
    }
    let [lo, hi] = crc.to_le_bytes();
    push_escaped(out, lo);
    push_escaped(out, hi);
    out.push(FLAG);
}

/// Pure SAB2 reassembler: bytes and times in, [`Event`]s out. The output does not depend on
/// how the input is split into chunks.
#[derive(Clone, Debug)]
pub struct Reassembler {
    max_payload: usize,
    /// A flag was seen: bytes belong to a frame.
    in_frame: bool,
    escaped: bool,
    body: Box<[u8; STORE_MAX]>,
    body_len: u64,
    wire: Box<[u8; WIRE_MAX]>,
    wire_len: u64,
    odd_escapes: u32,
    start_pos: u64,
    start_time: Option<u64>,
    pos: u64,
    /// Time of the last byte pushed.
    last_time: Option<u64>,
    garbage: [u8; GARBAGE_ROW_MAX],
    garbage_len: usize,
    garbage_pos: u64,
    garbage_start: Option<u64>,
    garbage_end: Option<u64>,
    frames: u64,
}

impl Default for Reassembler {
    fn default() -> Self {
        Self::new(DEFAULT_MAX_PAYLOAD)
    }
}

impl Reassembler {
    /// A reassembler for payloads of up to `max_payload` bytes (modm's `N`). Longer frames are
    /// still decoded when their CRC passes, and reported as overlong.
    pub fn new(max_payload: usize) -> Self {
        Reassembler {
            max_payload,
            in_frame: false,
            escaped: false,
            body: Box::new([0; STORE_MAX]),
            body_len: 0,
            wire: Box::new([0; WIRE_MAX]),
            wire_len: 0,
            odd_escapes: 0,
            start_pos: 0,
            start_time: None,
            pos: 0,
            last_time: None,
            garbage: [0; GARBAGE_ROW_MAX],
            garbage_len: 0,
            garbage_pos: 0,
            garbage_start: None,
            garbage_end: None,
            frames: 0,
        }
    }

    /// Feeds `data` that arrived at `time`; calls `emit` for every completed event.
    ///
    /// The same as [`Self::step`] for every byte, a run at a time: the bytes up to the next
    /// flag are copied whole into the garbage run, or into the frame's wire and body buffers.
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let mut rest = data;
        while !rest.is_empty() {
            let n = find(FLAG, rest).unwrap_or(rest.len());
            if n > 0 {
                let run = &rest[..n];
                if self.in_frame {
                    self.frame_run(run);
                } else {
                    self.garbage_run(run, time, emit);
                }
                self.pos += n as u64;
                self.last_time = time;
            }
            if n == rest.len() {
                break;
            }
            self.step(FLAG, time, emit);
            // Frames that open and close in `data` without an escape are read in place.
            let mut open = data.len() - rest.len() + n;
            while let Some(close) = self.close_in_place(data, open, time, emit) {
                open = close;
            }
            rest = &data[open + 1..];
        }
    }

    /// Bytes of an open frame, none of them a flag (what [`Self::step`] does with each).
    fn frame_run(&mut self, run: &[u8]) {
        self.keep_wire_run(run);
        self.unescape_run(run);
    }

    /// The body bytes of `run` (no flag among them): [`Self::step_body`] for each, runs
    /// without an escape copied whole when `run` is long.
    fn unescape_run(&mut self, run: &[u8]) {
        if run.len() <= SHORT_RUN {
            // A frame's body with an escape: byte by byte costs less than a search and a
            // copy for each stretch between escapes.
            for &b in run {
                self.step_body(b);
            }
            return;
        }
        let mut rest = run;
        while let Some((&first, tail)) = rest.split_first() {
            if self.escaped {
                // `step`'s escape rules, one byte at a time.
                self.step_body(first);
                rest = tail;
                continue;
            }
            let n = find(ESCAPE, rest).unwrap_or(rest.len());
            self.keep_body_run(&rest[..n]);
            if n < rest.len() {
                self.escaped = true;
                rest = &rest[n + 1..];
            } else {
                break;
            }
        }
    }

    /// One byte of an open frame that is not a flag: escapes and the body.
    #[inline]
    fn step_body(&mut self, b: u8) {
        if b == ESCAPE {
            // modm: an escape after an escape only re-arms the escape.
            if self.escaped {
                self.odd_escapes += 1;
            }
            self.escaped = true;
        } else if self.escaped {
            self.escaped = false;
            if b != 0x5E && b != 0x5D {
                self.odd_escapes += 1;
            }
            self.keep_body(b ^ 0x20);
        } else {
            self.keep_body(b);
        }
    }

    /// Garbage bytes (no flag among them), in rows of at most [`GARBAGE_ROW_MAX`].
    fn garbage_run(&mut self, run: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let mut rest = run;
        let mut pos = self.pos;
        while !rest.is_empty() {
            if self.garbage_len == 0 {
                self.garbage_pos = pos;
                self.garbage_start = time;
            }
            let k = rest.len().min(GARBAGE_ROW_MAX - self.garbage_len);
            self.garbage[self.garbage_len..self.garbage_len + k].copy_from_slice(&rest[..k]);
            self.garbage_len += k;
            self.garbage_end = time;
            pos += k as u64;
            rest = &rest[k..];
            if self.garbage_len == GARBAGE_ROW_MAX {
                self.flush_garbage(emit);
            }
        }
    }

    /// Feeds one byte.
    #[inline]
    pub fn step(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if b == FLAG {
            self.flush_garbage(emit);
            if self.in_frame {
                self.keep_wire(b);
                self.close(true, time, emit);
            }
            self.open(time);
        } else if !self.in_frame {
            self.garbage_byte(b, time, emit);
        } else {
            self.keep_wire(b);
            self.step_body(b);
        }
        self.pos += 1;
        self.last_time = time;
    }

    /// End of input: a frame still open is reported as truncated (unless nothing followed its
    /// flag), garbage is flushed.
    pub fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        if self.in_frame {
            self.close(false, None, emit);
        }
        self.in_frame = false;
    }

    /// A gap in the capture: forgets an open frame without reporting it and waits for the
    /// next flag.
    pub fn reset(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        self.in_frame = false;
        self.escaped = false;
    }

    /// Emits the garbage collected so far as a row (a live source went quiet).
    #[inline]
    pub fn flush_garbage(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if self.garbage_len > 0 {
            self.emit_garbage(emit);
        }
    }

    /// [`Self::flush_garbage`] when there is garbage.
    fn emit_garbage(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        let mut ev = Event::new(
            EventKind::Garbage,
            Framing::Hdlc,
            &self.garbage[..self.garbage_len],
        );
        ev.start_pos = self.garbage_pos;
        ev.end_pos = self.garbage_pos + self.garbage_len as u64;
        ev.start_time = self.garbage_start;
        ev.end_time = self.garbage_end;
        ev.before_first = self.frames == 0;
        emit(&ev);
        self.garbage_len = 0;
    }

    fn open(&mut self, time: Option<u64>) {
        self.in_frame = true;
        self.escaped = false;
        self.body_len = 0;
        self.odd_escapes = 0;
        self.wire[0] = FLAG;
        self.wire_len = 1;
        self.start_pos = self.pos;
        self.start_time = time;
    }

    #[inline]
    fn keep_wire(&mut self, b: u8) {
        if let Some(slot) = self.wire.get_mut(self.wire_len as usize) {
            *slot = b;
        }
        self.wire_len += 1;
    }

    fn keep_wire_run(&mut self, run: &[u8]) {
        let at = (self.wire_len as usize).min(WIRE_MAX);
        let k = run.len().min(WIRE_MAX - at);
        self.wire[at..at + k].copy_from_slice(&run[..k]);
        self.wire_len += run.len() as u64;
    }

    fn keep_body_run(&mut self, run: &[u8]) {
        let at = (self.body_len as usize).min(STORE_MAX);
        let k = run.len().min(STORE_MAX - at);
        self.body[at..at + k].copy_from_slice(&run[..k]);
        self.body_len += run.len() as u64;
    }

    #[inline]
    fn keep_body(&mut self, b: u8) {
        if let Some(slot) = self.body.get_mut(self.body_len as usize) {
            *slot = b;
        }
        self.body_len += 1;
    }

    /// Ends the open frame. `closed` = at a flag (already in `wire`), otherwise at the end of
    /// the input.
    fn close(&mut self, closed: bool, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let stored = (self.body_len as usize).min(STORE_MAX);
        let wire_kept = (self.wire_len as usize).min(WIRE_MAX);
        let run = Run {
            closed,
            escaped: self.escaped,
            max_payload: self.max_payload,
            body: &self.body[..stored],
            body_len: self.body_len,
            wire: &self.wire[..wire_kept],
            wire_len: self.wire_len,
            odd_escapes: self.odd_escapes,
            start_pos: self.start_pos,
            end_pos: if closed { self.pos + 1 } else { self.pos },
            start_time: self.start_time,
            end_time: if closed { time } else { self.last_time },
        };
        if run.emit(emit) {
            self.frames += 1;
        }
        self.in_frame = false;
    }

    /// The frame just opened by the flag at `data[open]`, when the next flag of `data` closes
    /// it with no escape in between: emitted from `data` in place (no copy into the wire and
    /// body buffers), and the frame after it opened, as [`Self::step`] would do for each byte.
    /// Returns the closing flag's index.
    fn close_in_place(
        &mut self,
        data: &[u8],
        open: usize,
        time: Option<u64>,
        emit: &mut impl FnMut(&Event<'_>),
    ) -> Option<usize> {
        debug_assert_eq!(self.start_time, time, "opened by the flag at data[open]");
        let after = &data[open + 1..];
        let j = find2(FLAG, ESCAPE, after)?;
        if j == 0 && after[0] == FLAG {
            // Back-to-back flags (between two frames): nothing to report, a frame opens.
            self.open(time);
            self.pos += 1;
            self.last_time = time;
            return Some(open + 1);
        }
        if after[j] != FLAG {
            return self.close_escaped_in_place(data, open, j, time, emit);
        }
        let body = &after[..j];
        let wire = &data[open..open + j + 2];
        // The closing flag's position.
        self.pos += j as u64;
        let run = Run {
            closed: true,
            escaped: false,
            max_payload: self.max_payload,
            body: &body[..j.min(STORE_MAX)],
            body_len: j as u64,
            wire: &wire[..wire.len().min(WIRE_MAX)],
            wire_len: wire.len() as u64,
            odd_escapes: 0,
            start_pos: self.start_pos,
            end_pos: self.pos + 1,
            // The frame opened in `data`, at `time`: `self.start_time`, which `open` has just
            // stored in two halves, read back whole would stall on the store buffer.
            start_time: time,
            end_time: time,
        };
        if run.emit(emit) {
            self.frames += 1;
        }
        self.open(time);
        self.pos += 1;
        self.last_time = time;
        Some(open + j + 1)
    }

    /// [`Self::close_in_place`] for a frame with an escape at `after[escape]` (`after` being
    /// the bytes after the opening flag): when a flag of `data` closes it, the body is
    /// unescaped into the body buffer and the wire bytes are read in place (what
    /// [`Self::frame_run`] and [`Self::step`] at the flag would do). Returns the closing
    /// flag's index.
    fn close_escaped_in_place(
        &mut self,
        data: &[u8],
        open: usize,
        escape: usize,
        time: Option<u64>,
        emit: &mut impl FnMut(&Event<'_>),
    ) -> Option<usize> {
        debug_assert_eq!(self.start_time, time, "opened by the flag at data[open]");
        let after = &data[open + 1..];
        let close = escape + find(FLAG, &after[escape..])?;
        self.unescape_run(&after[..close]);
        let wire = &data[open..open + close + 2];
        // The closing flag's position.
        self.pos += close as u64;
        let stored = (self.body_len as usize).min(STORE_MAX);
        let run = Run {
            closed: true,
            escaped: self.escaped,
            max_payload: self.max_payload,
            body: &self.body[..stored],
            body_len: self.body_len,
            wire: &wire[..wire.len().min(WIRE_MAX)],
            wire_len: wire.len() as u64,
            odd_escapes: self.odd_escapes,
            start_pos: self.start_pos,
            end_pos: self.pos + 1,
            // The frame opened in `data`, at `time`: `self.start_time`, which `open` has just
            // stored in two halves, read back whole would stall on the store buffer.
            start_time: time,
            end_time: time,
        };
        if run.emit(emit) {
            self.frames += 1;
        }
        self.open(time);
        self.pos += 1;
        self.last_time = time;
        Some(open + close + 1)
    }

    /// A body with its CRC field (at least 2 bytes): whether the CRC checks, the received CRC
    /// and the CRC computed over the body, in one pass. (CRC-16/MODBUS has no final XOR, so
    /// the CRC over the body and its little-endian CRC is 0 exactly when the two are equal.)
    #[inline]
    fn crc_of(body_and_crc: &[u8]) -> (bool, u16, u16) {
        let n = body_and_crc.len();
        let received = u16::from_le_bytes([body_and_crc[n - 2], body_and_crc[n - 1]]);
        let computed = crc16(&body_and_crc[..n - 2]);
        (computed == received, received, computed)
    }

    fn garbage_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if self.garbage_len == 0 {
            self.garbage_pos = self.pos;
            self.garbage_start = time;
        }
        self.garbage[self.garbage_len] = b;
        self.garbage_len += 1;
        self.garbage_end = time;
        if self.garbage_len == GARBAGE_ROW_MAX {
            self.flush_garbage(emit);
        }
    }
}

/// The bytes of a run between flags that ended, and what [`Reassembler::close`] needs to
/// report it.
struct Run<'a> {
    /// Ended at a flag (otherwise at the end of the input).
    closed: bool,
    escaped: bool,
    max_payload: usize,
    /// The unescaped bytes kept (at most [`STORE_MAX`]) and how many there were.
    body: &'a [u8],
    body_len: u64,
    /// The wire bytes kept (at most [`WIRE_MAX`]) and how many there were.
    wire: &'a [u8],
    wire_len: u64,
    odd_escapes: u32,
    start_pos: u64,
    end_pos: u64,
    start_time: Option<u64>,
    end_time: Option<u64>,
}

impl Run<'_> {
    /// Emits the run's event, if it is one; true for a valid frame. Inlined into its three
    /// callers: the event is then built in place and its unread fields are never written.
    #[inline(always)]
    fn emit(&self, emit: &mut impl FnMut(&Event<'_>)) -> bool {
        let n = self.body_len;
        let stored = self.body.len();
        // The check of a run that can be a frame, computed once.
        let mut check = None;
        let kind = if !self.closed {
            if n == 0 && !self.escaped {
                // Only the closing flag of the last frame.
                return false;
            }
            EventKind::Truncated
        } else if self.escaped {
            EventKind::Abort
        } else if n == 0 {
            // Back-to-back flags: normal.
            return false;
        } else if n < OVERHEAD as u64 {
            EventKind::Runt
        } else if n > STORE_MAX as u64 {
            EventKind::Overlong
        } else if check.insert(Reassembler::crc_of(self.body)).0 {
            EventKind::Frame
        } else if n > (self.max_payload + OVERHEAD) as u64 {
            EventKind::Overlong
        } else {
            EventKind::BadCrc
        };
        let mut ev = Event::new(kind, Framing::Hdlc, self.wire);
        ev.wire_len = self.wire_len;
        ev.start_pos = self.start_pos;
        ev.end_pos = self.end_pos;
        ev.start_time = self.start_time;
        ev.end_time = self.end_time;
        ev.odd_escapes = self.odd_escapes;
        ev.body_len = n;
        match (kind, check) {
            (EventKind::Frame | EventKind::BadCrc, Some((_, received, computed))) => {
                ev.body = &self.body[..stored - 2];
                ev.crc = Some((received, computed));
            }
            _ => ev.body = self.body,
        }
        emit(&ev);
        kind == EventKind::Frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmt::{hex, parse_hex};
    use crate::sab::frame::OwnedEvent;

    fn events_with(max: usize, data: &[u8]) -> Vec<OwnedEvent> {
        let mut r = Reassembler::new(max);
        let mut out = Vec::new();
        r.push(data, None, &mut |e| out.push(OwnedEvent::from(e)));
        r.finish(&mut |e| out.push(OwnedEvent::from(e)));
        out
    }

    fn events(data: &[u8]) -> Vec<OwnedEvent> {
        events_with(DEFAULT_MAX_PAYLOAD, data)
    }

    fn kinds(evs: &[OwnedEvent]) -> Vec<(EventKind, String)> {
        evs.iter().map(|e| (e.kind, hex(&e.wire))).collect()
    }

    #[test]
    fn crc_catalogue_check_value() {
        assert_eq!(crc16(b"123456789"), 0x4B37);
    }

    #[test]
    fn modm_example_frame() {
        // examples/stm32f4_discovery/sab2/main.cpp: address 1, REQUEST, command 2, payload 0x55.
        let mut out = Vec::new();
        encode(&mut out, 0x01, 0x02, &[0x55]);
        assert_eq!(out, parse_hex("7E 01 02 55 E1 5F 7E").unwrap());
        let ev = events(&out);
        assert_eq!(ev.len(), 1);
        assert_eq!(ev[0].kind, EventKind::Frame);
        assert_eq!(ev[0].body, [0x01, 0x02, 0x55]);
        assert_eq!(ev[0].crc, Some((0x5FE1, 0x5FE1)));
        assert_eq!((ev[0].start_pos, ev[0].end_pos), (0, 7));
    }

    #[test]
    fn escaping_round_trip() {
        let mut out = Vec::new();
        encode(&mut out, 0x02, 0x7E, &[0x7D, 0x7E, 0x20]);
        assert_eq!(
            out,
            parse_hex("7E 02 7D 5E 7D 5D 7D 5E 20 F5 88 7E").unwrap()
        );
        let ev = events(&out);
        assert_eq!(ev[0].kind, EventKind::Frame);
        assert_eq!(ev[0].body, [0x02, 0x7E, 0x7D, 0x7E, 0x20]);
        assert_eq!(ev[0].odd_escapes, 0);
    }

    #[test]
    fn back_to_back_and_shared_flags() {
        let mut wire = Vec::new();
        encode(&mut wire, 0x01, 0x02, &[]);
        encode(&mut wire, 0xC1, 0x02, &[9]);
        // Shared flag: drop the second frame's opening flag.
        let mut shared = wire.clone();
        shared.remove(6);
        for w in [&wire, &shared] {
            let ev = events(w);
            assert_eq!(ev.len(), 2, "{}", hex(w));
            assert!(ev.iter().all(|e| e.kind == EventKind::Frame));
        }
    }

    #[test]
    fn runts_aborts_garbage_truncation() {
        let wire = parse_hex("11 22 7E 7E 01 02 7E 01 7D 7E 01 02 81 E1 7E 05 06").unwrap();
        let ev = events(&wire);
        assert_eq!(
            kinds(&ev),
            [
                (EventKind::Garbage, "11 22".into()),
                (EventKind::Runt, "7E 01 02 7E".into()),
                (EventKind::Abort, "7E 01 7D 7E".into()),
                (EventKind::Frame, "7E 01 02 81 E1 7E".into()),
                (EventKind::Truncated, "7E 05 06".into()),
            ]
        );
        assert!(ev[0].before_first);
    }

    #[test]
    fn bad_crc() {
        let ev = events(&parse_hex("7E 01 02 81 E2 7E").unwrap());
        assert_eq!(ev[0].kind, EventKind::BadCrc);
        assert_eq!(ev[0].crc, Some((0xE281, 0xE181)));
    }

    #[test]
    fn a_frame_checks_exactly_when_its_crc_field_is_the_bodys_crc() {
        // The CRC is computed once per frame; every bit error in body or CRC field is a bad
        // CRC reporting the received and the computed value.
        let body = [0x01, 0x02, 0x30, 0x41];
        let crc = crc16(&body);
        let mut frame = body.to_vec();
        frame.extend_from_slice(&crc.to_le_bytes());
        for bit in 0..frame.len() * 8 {
            let mut f = frame.clone();
            f[bit / 8] ^= 1 << (bit % 8);
            let mut wire = vec![FLAG];
            for &b in &f {
                push_escaped(&mut wire, b);
            }
            wire.push(FLAG);
            let ev = events(&wire);
            assert_eq!(ev.len(), 1, "{bit}");
            assert_eq!(ev[0].kind, EventKind::BadCrc, "{bit}");
            let n = f.len();
            let received = u16::from_le_bytes([f[n - 2], f[n - 1]]);
            assert_eq!(ev[0].crc, Some((received, crc16(&f[..n - 2]))), "{bit}");
        }
        let mut wire = vec![FLAG];
        for &b in &frame {
            push_escaped(&mut wire, b);
        }
        wire.push(FLAG);
        let ev = events(&wire);
        assert_eq!(ev[0].kind, EventKind::Frame);
        assert_eq!(ev[0].crc, Some((crc, crc)));
    }

    #[test]
    fn odd_escapes_follow_modm() {
        // 7D 7D 5E: modm drops the first escape and reads 0x7E.
        let mut body = vec![0x01, 0x7E];
        let crc = crc16(&body);
        body.extend_from_slice(&crc.to_le_bytes());
        let mut wire = vec![FLAG, 0x01, ESCAPE, ESCAPE, 0x5E];
        for &b in &body[2..] {
            push_escaped(&mut wire, b);
        }
        wire.push(FLAG);
        let ev = events(&wire);
        assert_eq!(ev[0].kind, EventKind::Frame, "{}", hex(&wire));
        assert_eq!(ev[0].body, [0x01, 0x7E]);
        assert_eq!(ev[0].odd_escapes, 1);
    }

    #[test]
    fn overlong_frames() {
        // A valid 40-byte payload: decoded, but longer than modm's default N = 32.
        let payload: Vec<u8> = (0..40).collect();
        let mut wire = Vec::new();
        encode(&mut wire, 0xC1, 0x02, &payload);
        let ev = events(&wire);
        assert_eq!(ev[0].kind, EventKind::Frame);
        assert_eq!(ev[0].body.len(), 42);
        let ev = events_with(64, &wire);
        assert_eq!(ev[0].kind, EventKind::Frame);
        // The same with a broken CRC is overlong, not a bad CRC.
        let n = wire.len();
        wire[n - 2] ^= 1;
        assert_eq!(events(&wire)[0].kind, EventKind::Overlong);
        assert_eq!(events_with(64, &wire)[0].kind, EventKind::BadCrc);
        // Longer than anything kept: overlong, wire cut, length counted.
        let mut long = vec![FLAG];
        long.extend(std::iter::repeat_n(0x11, 1000));
        long.push(FLAG);
        let ev = events(&long);
        assert_eq!(ev.len(), 1);
        assert_eq!(ev[0].kind, EventKind::Overlong);
        assert_eq!(ev[0].wire_len, 1002);
        assert_eq!(ev[0].wire.len(), WIRE_MAX);
        assert_eq!((ev[0].start_pos, ev[0].end_pos), (0, 1002));
    }
}
