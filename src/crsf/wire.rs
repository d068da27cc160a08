//! CRSF wire format: `[addr][len][type][payload][crc]`, the two CRC-8s, channel packing, and the
//! pure reassembler (shared with GHST, which has the same frame shape and CRC).
//!
//! * `addr`: a device address, the serial sync byte 0xC8 or the broadcast address 0x00.
//! * `len`: the bytes after it (type, payload, CRC), 2..=62; a frame is at most 64 bytes.
//! * CRC-8 with polynomial 0xD5 (DVB-S2), init 0, not reflected, over `type` and `payload`.
//! * Command frames (type 0x32) carry a second CRC-8, polynomial 0xBA, over type … command data,
//!   just before the frame CRC.
//!
//! # Resynchronisation
//!
//! There is no byte stuffing and no gap between frames, so a frame starts wherever a plausible
//! address is followed by a plausible length and a passing CRC. The rule, which makes the output
//! a function of the bytes alone (however they are split into chunks):
//!
//! 1. A **frame** is accepted at the earliest position where a complete candidate (plausible
//!    address, length 2..=62) passes its CRC.
//! 2. A failed candidate whose span holds no valid frame start is a **bad frame** (`BadCrc`, or
//!    `Truncated` when the input ends inside it); its bytes are consumed.
//! 3. A failed candidate whose span holds the start of a valid frame was a **false start**: only
//!    its first byte becomes garbage, and scanning goes on with the next byte. A bad candidate
//!    therefore costs one byte, never the good frame after it.
//! 4. Every other byte is **garbage**, in runs of at most [`GARBAGE_ROW_MAX`] bytes.
//!
//! Memory is bounded: at most two frame lengths ([`CAPACITY`] bytes) are held while a failed
//! candidate waits for a candidate inside it to complete.

use crate::row::GARBAGE_ROW_MAX;

/// Shortest `len` byte: type and CRC.
pub const MIN_LEN: u8 = 2;
/// Longest `len` byte (a 64-byte frame).
pub const MAX_LEN: u8 = 62;
/// Longest frame on the wire.
pub const MAX_FRAME: usize = MAX_LEN as usize + 2;
/// Longest payload (after the type byte).
pub const MAX_PAYLOAD: usize = MAX_FRAME - 4;
/// Bytes held at most (see the module documentation).
pub const CAPACITY: usize = 2 * MAX_FRAME;

/// A CRC-8 table for `poly` (init 0, not reflected, no final XOR).
const fn crc_table(poly: u8) -> [u8; 256] {
    let mut t = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u8;
        let mut k = 0;
        while k < 8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ poly
            } else {
                c << 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
}

const CRC_D5: [u8; 256] = crc_table(0xD5);
const CRC_BA: [u8; 256] = crc_table(0xBA);

/// `SLICES[k][b]`: the CRC-8/DVB-S2 register `b` after `k + 1` zero bytes. The CRC is linear
/// (no init, no final XOR), so eight bytes fold into the register at once:
/// `SLICES[7][c ^ x0] ^ SLICES[6][x1] ^ … ^ SLICES[0][x7]`.
const SLICES: [[u8; 256]; 8] = {
    let mut t = [CRC_D5; 8];
    let mut k = 1;
    while k < 8 {
        let mut b = 0;
        while b < 256 {
            t[k][b] = CRC_D5[t[k - 1][b] as usize];
            b += 1;
        }
        k += 1;
    }
    t
};

/// CRC-8/DVB-S2 (polynomial 0xD5) of `bytes`: the frame CRC, over type and payload. Eight
/// bytes a step (`SLICES`), then byte by byte.
#[inline]
pub fn crc8(bytes: &[u8]) -> u8 {
    let mut c = 0u8;
    let mut eights = bytes.chunks_exact(8);
    for x in &mut eights {
        c = SLICES[7][usize::from(c ^ x[0])]
            ^ SLICES[6][usize::from(x[1])]
            ^ SLICES[5][usize::from(x[2])]
            ^ SLICES[4][usize::from(x[3])]
            ^ SLICES[3][usize::from(x[4])]
            ^ SLICES[2][usize::from(x[5])]
            ^ SLICES[1][usize::from(x[6])]
            ^ SLICES[0][usize::from(x[7])];
    }
    eights
        .remainder()
        .iter()
        .fold(c, |c, &b| CRC_D5[usize::from(c ^ b)])
}

/// CRC-8 with polynomial 0xBA of `bytes`: the command frames' inner CRC, over type …
/// command data.
pub fn command_crc8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |c, &b| CRC_BA[(c ^ b) as usize])
}

/// Which bytes may start a frame: a table over all 256 byte values.
pub type Addresses = [bool; 256];

/// A table of the bytes in `list`.
pub const fn addresses(list: &[u8]) -> Addresses {
    let mut t = [false; 256];
    let mut i = 0;
    while i < list.len() {
        t[list[i] as usize] = true;
        i += 1;
    }
    t
}

/// The CRSF start bytes: the sync byte, broadcast, and every device address of the TBS text
/// (reserved ones included) and ExpressLRS's Lua address 0xEF. The dynamic NAT range 0x20-0x7F
/// is left out: too many noise bytes would start candidates.
pub const CRSF_ADDRESSES: Addresses = addresses(&[
    0x00, 0x0E, 0x10, 0x12, 0x13, 0x14, 0x80, 0x8A, 0x90, 0x91, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97,
    0xB0, 0xB2, 0xC0, 0xC2, 0xC4, 0xC8, 0xCA, 0xCC, 0xCE, 0xEA, 0xEC, 0xEE, 0xEF, 0xF0, 0xF2,
]);

/// Appends a frame `[addr][len][ty][payload][crc]` with a correct length and CRC.
///
/// # Panics
///
/// If `payload` is longer than [`MAX_PAYLOAD`].
pub fn encode(out: &mut Vec<u8>, addr: u8, ty: u8, payload: &[u8]) {
    assert!(
        payload.len() <= MAX_PAYLOAD,
        "a CRSF payload has at most 60 bytes"
    );
    let start = out.len();
    out.push(addr);
    out.push(payload.len() as u8 + 2);
    out.push(ty);
    out.extend_from_slice(payload);
    let crc = crc8(&out[start + 2..]);
    out.push(crc);
}

/// Appends an extended frame (type 0x28 and up): `dest` and `origin` before `payload`.
pub fn encode_ext(out: &mut Vec<u8>, addr: u8, ty: u8, dest: u8, origin: u8, payload: &[u8]) {
    let mut p = Vec::with_capacity(payload.len() + 2);
    p.extend_from_slice(&[dest, origin]);
    p.extend_from_slice(payload);
    encode(out, addr, ty, &p);
}

/// Appends a command frame (0x32): `dest origin command sub data`, the inner CRC (0xBA) over
/// type … data, then the frame CRC.
pub fn encode_command(
    out: &mut Vec<u8>,
    addr: u8,
    dest: u8,
    origin: u8,
    command: u8,
    sub: u8,
    data: &[u8],
) {
    let mut p = vec![dest, origin, command, sub];
    p.extend_from_slice(data);
    let mut covered = vec![COMMAND];
    covered.extend_from_slice(&p);
    p.push(command_crc8(&covered));
    encode(out, addr, COMMAND, &p);
}

/// The command frame type.
pub const COMMAND: u8 = 0x32;

/// Reads `count` little-endian bit fields of `bits` bits each from `bytes` (RC channels: 16 × 11
/// bits, as S.Bus); fields past the end of `bytes` read as the bits that are there (zeros).
pub fn unpack_bits(bytes: &[u8], bits: u32, count: usize, out: &mut [u16]) {
    let mask = (1u32 << bits) - 1;
    let mut acc = 0u32;
    let mut have = 0u32;
    let mut i = 0;
    for slot in out.iter_mut().take(count) {
        while have < bits {
            acc |= u32::from(bytes.get(i).copied().unwrap_or(0)) << have;
            i += 1;
            have += 8;
        }
        *slot = (acc & mask) as u16;
        acc >>= bits;
        have -= bits;
    }
}

/// Packs `values` as little-endian bit fields of `bits` bits each (the inverse of
/// [`unpack_bits`]); the last byte is padded with zeros.
pub fn pack_bits(values: &[u16], bits: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let mut acc = 0u32;
    let mut have = 0u32;
    for &v in values {
        acc |= (u32::from(v) & ((1 << bits) - 1)) << have;
        have += bits;
        while have >= 8 {
            out.push(acc as u8);
            acc >>= 8;
            have -= 8;
        }
    }
    if have > 0 {
        out.push(acc as u8);
    }
    out
}

/// What a reassembler emits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A frame whose CRC passed.
    Frame,
    /// A complete candidate whose CRC failed, with no valid frame starting inside it.
    BadCrc,
    /// A candidate cut by the end of the input (or a gap), with no valid frame inside it.
    Truncated,
    /// Bytes that belong to no frame.
    Garbage,
}

/// One event of the reassembler, borrowed from it (or from the input: nothing is copied for a
/// frame that lies whole in one chunk).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Event<'a> {
    pub kind: Kind,
    /// The bytes exactly as on the wire.
    pub wire: &'a [u8],
    /// Stream offset of the first byte (bytes since the start, for time reconstruction).
    pub offset: u64,
    /// Arrival time of the first byte, when the source has times.
    pub time: Option<u64>,
    /// Garbage: candidates in this run that a valid frame starting inside them proved false.
    pub false_starts: u32,
    /// Garbage: before the first valid frame of the input.
    pub before_first: bool,
}

impl<'a> Event<'a> {
    /// The address byte (frames, bad and truncated frames).
    pub fn addr(&self) -> u8 {
        self.wire.first().copied().unwrap_or(0)
    }

    /// The type byte, when the wire has it.
    pub fn ty(&self) -> Option<u8> {
        self.wire.get(2).copied()
    }

    /// The payload of a frame or bad frame: the bytes between type and CRC.
    pub fn payload(&self) -> &'a [u8] {
        let n = self.wire.len();
        if n < 4 { &[] } else { &self.wire[3..n - 1] }
    }

    /// The CRC byte as received and the CRC of type and payload (frames and bad frames).
    pub fn crcs(&self) -> Option<(u8, u8)> {
        let n = self.wire.len();
        (n >= 4).then(|| (self.wire[n - 1], crc8(&self.wire[2..n - 1])))
    }
}

/// What the candidate at the start of some bytes is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Check {
    /// No plausible address, or a length outside 2..=62.
    NotStart,
    /// More bytes are needed to decide.
    Incomplete,
    /// A complete candidate passing its CRC, ending here (exclusive).
    Valid(usize),
    /// A complete candidate failing its CRC, ending here.
    Bad(usize),
}

#[inline]
fn check(addrs: &Addresses, bytes: &[u8]) -> Check {
    let Some(&a) = bytes.first() else {
        return Check::Incomplete;
    };
    if !addrs[a as usize] {
        return Check::NotStart;
    }
    let Some(&len) = bytes.get(1) else {
        return Check::Incomplete;
    };
    if !(MIN_LEN..=MAX_LEN).contains(&len) {
        return Check::NotStart;
    }
    let end = len as usize + 2;
    match bytes.get(..end) {
        None => Check::Incomplete,
        Some(f) if crc8(&f[2..end - 1]) == f[end - 1] => Check::Valid(end),
        Some(_) => Check::Bad(end),
    }
}

/// Garbage bytes collected for one row.
#[derive(Clone, Debug)]
struct Run {
    bytes: [u8; GARBAGE_ROW_MAX],
    len: usize,
    offset: u64,
    time: Option<u64>,
    false_starts: u32,
    before_first: bool,
}

/// The pure reassembler: bytes and times in, [`Event`]s out; the output does not depend on how
/// the input is split into chunks.
#[derive(Clone, Debug)]
pub struct Reassembler {
    addrs: &'static Addresses,
    buf: [u8; CAPACITY],
    times: [Option<u64>; CAPACITY],
    len: usize,
    /// Stream offset of `buf[0]`.
    base: u64,
    /// `buf[0]` is a complete failed candidate ending here (decided once, kept until it goes).
    head_bad: Option<usize>,
    /// No position in `buf[1..known]` starts a valid frame.
    known: usize,
    /// A valid frame starts at `buf[valid_at]` (1 or more).
    valid_at: Option<usize>,
    run: Run,
    frames: u64,
}

impl Reassembler {
    /// A reassembler for frames starting with the bytes of `addrs`.
    pub fn new(addrs: &'static Addresses) -> Self {
        Reassembler {
            addrs,
            buf: [0; CAPACITY],
            times: [None; CAPACITY],
            len: 0,
            base: 0,
            head_bad: None,
            known: 0,
            valid_at: None,
            run: Run {
                bytes: [0; GARBAGE_ROW_MAX],
                len: 0,
                offset: 0,
                time: None,
                false_starts: 0,
                before_first: true,
            },
            frames: 0,
        }
    }

    /// Valid frames emitted so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Bytes held back while a candidate is undecided.
    pub fn held(&self) -> usize {
        self.len
    }

    /// Feeds `data` that arrived at `time`; calls `emit` for every event it completes. While
    /// nothing is held, a frame that lies whole in `data` is emitted from `data` in place and
    /// bytes that start no candidate go straight to the garbage run; everything else goes
    /// through the buffer byte by byte (the same decisions, see [`Self::step`]).
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let mut i = 0;
        while i < data.len() {
            if self.len == 0 {
                match check(self.addrs, &data[i..]) {
                    Check::Valid(end) => {
                        self.flush_garbage(emit);
                        emit(&Event {
                            kind: Kind::Frame,
                            wire: &data[i..i + end],
                            offset: self.base,
                            time,
                            false_starts: 0,
                            before_first: false,
                        });
                        self.frames += 1;
                        self.base += end as u64;
                        i += end;
                        continue;
                    }
                    Check::NotStart => {
                        self.garbage_byte(data[i], time, emit);
                        i += 1;
                        continue;
                    }
                    Check::Bad(_) | Check::Incomplete => {}
                }
            }
            self.step(data[i], time, emit);
            i += 1;
        }
    }

    /// Feeds one byte through the buffer.
    pub fn step(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if self.len == CAPACITY {
            // Cannot happen (see the module documentation); never panic on input, though.
            debug_assert!(false, "CRSF reassembler buffer overflow");
            self.garbage_front(emit);
        }
        self.buf[self.len] = b;
        self.times[self.len] = time;
        self.len += 1;
        self.process(false, emit);
    }

    /// End of the input, or a gap: decides every held byte (truncated candidates, garbage),
    /// emits it and the garbage run. More bytes may follow (after a gap).
    pub fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.process(true, emit);
        self.flush_garbage(emit);
    }

    /// Emits the garbage collected so far as a row (a live line went quiet).
    pub fn flush_garbage(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if self.run.len == 0 {
            return;
        }
        let r = &self.run;
        emit(&Event {
            kind: Kind::Garbage,
            wire: &r.bytes[..r.len],
            offset: r.offset,
            time: r.time,
            false_starts: r.false_starts,
            before_first: r.before_first,
        });
        self.run.len = 0;
        self.run.false_starts = 0;
    }

    fn process(&mut self, eof: bool, emit: &mut impl FnMut(&Event<'_>)) {
        while self.len > 0 {
            let (span, cut) = match self.head_bad {
                Some(end) => (end, false),
                None => match check(self.addrs, &self.buf[..self.len]) {
                    Check::Valid(end) => {
                        self.emit_span(Kind::Frame, end, emit);
                        continue;
                    }
                    Check::NotStart => {
                        self.garbage_front(emit);
                        continue;
                    }
                    Check::Incomplete if !eof => return,
                    Check::Incomplete => (self.len, true),
                    Check::Bad(end) => {
                        self.head_bad = Some(end);
                        (end, false)
                    }
                },
            };
            // buf[..span] is a failed candidate: does a valid frame start inside it?
            if self.valid_at.is_none() {
                let mut q = self.known.max(1);
                while q < span {
                    match check(self.addrs, &self.buf[q..self.len]) {
                        Check::Valid(_) => {
                            self.valid_at = Some(q);
                            break;
                        }
                        Check::Incomplete if !eof => {
                            self.known = q;
                            return;
                        }
                        _ => q += 1,
                    }
                }
                self.known = self.known.max(q);
            }
            if self.valid_at.is_some_and(|v| v < span) {
                self.note_false_start();
                self.garbage_front(emit);
                continue;
            }
            let kind = if cut { Kind::Truncated } else { Kind::BadCrc };
            self.emit_span(kind, span, emit);
        }
    }

    /// Counts a false start against the next garbage byte's run.
    fn note_false_start(&mut self) {
        if self.run.len == 0 {
            self.run.false_starts = 0;
        }
        self.run.false_starts += 1;
    }

    /// Emits `buf[..n]` as one event of `kind` and consumes it.
    fn emit_span(&mut self, kind: Kind, n: usize, emit: &mut impl FnMut(&Event<'_>)) {
        self.flush_garbage(emit);
        emit(&Event {
            kind,
            wire: &self.buf[..n],
            offset: self.base,
            time: self.times[0],
            false_starts: 0,
            before_first: false,
        });
        if kind == Kind::Frame {
            self.frames += 1;
        }
        self.consume(n);
    }

    /// Moves `buf[0]` into the garbage run.
    fn garbage_front(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        let (b, time) = (self.buf[0], self.times[0]);
        self.consume(1);
        self.base -= 1;
        self.garbage_byte(b, time, emit);
    }

    /// Appends the byte at stream offset `base` to the garbage run (and moves `base` past it).
    fn garbage_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        let r = &mut self.run;
        if r.len == 0 {
            r.offset = self.base;
            r.time = time;
            r.before_first = self.frames == 0;
        }
        r.bytes[r.len] = b;
        r.len += 1;
        self.base += 1;
        if r.len == GARBAGE_ROW_MAX {
            self.flush_garbage(emit);
        }
    }

    fn consume(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.times.copy_within(n..self.len, 0);
        self.len -= n;
        self.base += n as u64;
        self.head_bad = None;
        self.known = self.known.saturating_sub(n);
        self.valid_at = self
            .valid_at
            .and_then(|v| v.checked_sub(n))
            .filter(|&v| v > 0);
    }
}

#[cfg(test)]
mod tests;
