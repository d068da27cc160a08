//! What the two reassemblers emit: one [`Event`] type for both framings.

use super::header::{self, Flags};

/// Bytes a search looks at itself before it hands the rest to `memchr`: runs inside frames
/// are short (a few bytes, cheaper without its setup), runs of noise or of the other
/// framing's traffic long. The head is read eight bytes at a time ([`zero_bytes`]).
const SCAN_HEAD: usize = 16;

/// `0x01` in every byte of a word.
const LOW_BITS: u64 = 0x0101_0101_0101_0101;

/// The bytes of `word` that are zero, as their high bits; a zero byte's borrow can also mark
/// bytes above it, so only the lowest mark is exact (the first zero byte of a little-endian
/// word), which is all the searches use.
#[inline(always)]
fn zero_bytes(word: u64) -> u64 {
    word.wrapping_sub(LOW_BITS) & !word & (LOW_BITS << 7)
}

/// Searches the head of `hay` for the bytes that `is` accepts: the first byte alone (the
/// usual answer: a 0x54 right after a SAB v1 frame, a flag right after a SAB2 frame's closing
/// one), then a word at a time (`marks` flags the same bytes in a word, see [`zero_bytes`]),
/// and byte by byte when fewer than eight bytes are left. `Ok` is the answer (the index of
/// the first match, or none in a short `hay`); `Err(i)`: no match in the first `i` bytes, the
/// rest (past [`SCAN_HEAD`]) is the caller's.
#[inline(always)]
fn scan_head(
    hay: &[u8],
    marks: impl Fn(u64) -> u64,
    is: impl Fn(u8) -> bool,
) -> Result<Option<usize>, usize> {
    match hay.first() {
        None => return Ok(None),
        Some(&b) if is(b) => return Ok(Some(0)),
        Some(_) => {}
    }
    let mut i = 0;
    while i < SCAN_HEAD {
        let Some(word) = hay[i..].first_chunk::<8>() else {
            return Ok(hay[i..].iter().position(|&b| is(b)).map(|k| k + i));
        };
        let m = marks(u64::from_le_bytes(*word));
        if m != 0 {
            return Ok(Some(i + (m.trailing_zeros() / 8) as usize));
        }
        i += 8;
    }
    Err(i)
}

/// The index of the first `needle` in `hay`.
#[inline(always)]
pub(super) fn find(needle: u8, hay: &[u8]) -> Option<usize> {
    let n = LOW_BITS * needle as u64;
    match scan_head(hay, |w| zero_bytes(w ^ n), |b| b == needle) {
        Ok(found) => found,
        Err(head) => find_tail(needle, &hay[head..]).map(|i| i + head),
    }
}

/// [`find`] past its head (out of line: keeps the callers' short searches tight).
#[inline(never)]
fn find_tail(needle: u8, hay: &[u8]) -> Option<usize> {
    memchr::memchr(needle, hay)
}

/// The index of the first `a` or `b` in `hay`.
#[inline(always)]
pub(super) fn find2(a: u8, b: u8, hay: &[u8]) -> Option<usize> {
    let (na, nb) = (LOW_BITS * a as u64, LOW_BITS * b as u64);
    let marks = |w: u64| zero_bytes(w ^ na) | zero_bytes(w ^ nb);
    match scan_head(hay, marks, |x| x == a || x == b) {
        Ok(found) => found,
        Err(head) => find2_tail(a, b, &hay[head..]).map(|i| i + head),
    }
}

/// [`find2`] past its head.
#[inline(never)]
fn find2_tail(a: u8, b: u8, hay: &[u8]) -> Option<usize> {
    memchr::memchr2(a, b, hay)
}

/// The two SAB framings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Framing {
    /// SAB v1 (`modm:communication:sab`, and modm's documentation page of SAB2):
    /// `54 LEN HDR CMD DATA CRC8`.
    Sync,
    /// SAB2 as modm's code sends it (`modm:communication:sab2`):
    /// `7E HDR CMD DATA CRClo CRChi 7E`, byte-stuffed.
    Hdlc,
}

impl Framing {
    /// The value of the `Framing` column and of `--framing`.
    pub const fn name(self) -> &'static str {
        match self {
            Framing::Sync => "sync",
            Framing::Hdlc => "hdlc",
        }
    }

    /// A description for notes and statistics.
    pub const fn long_name(self) -> &'static str {
        match self {
            Framing::Sync => "SAB v1 framing (0x54 SYNC, LENGTH, CRC-8/MAXIM-DOW)",
            Framing::Hdlc => "SAB2 framing (0x7E flags, byte stuffing, CRC-16/MODBUS)",
        }
    }

    /// The short protocol name.
    pub const fn protocol(self) -> &'static str {
        match self {
            Framing::Sync => "SAB v1",
            Framing::Hdlc => "SAB2",
        }
    }

    pub const fn other(self) -> Framing {
        match self {
            Framing::Sync => Framing::Hdlc,
            Framing::Hdlc => Framing::Sync,
        }
    }
}

/// What an event is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EventKind {
    /// A complete frame with a valid check.
    Frame,
    /// A complete frame whose check fails.
    BadCrc,
    /// A frame cut by the end of the input.
    Truncated,
    /// Bytes that belong to no frame.
    Garbage,
    /// SAB2: 1 to 3 bytes between two flags (a frame has at least 4).
    Runt,
    /// SAB2: `7D 7E`, an escape followed by a flag.
    Abort,
    /// SAB2: more bytes between two flags than a frame can have, with a failing check (or too
    /// long to check).
    Overlong,
}

/// One event of a reassembler. Slices borrow the reassembler's buffers: handle the event in
/// the callback and copy what must be kept.
#[derive(Clone, Copy, Debug)]
pub struct Event<'a> {
    pub kind: EventKind,
    pub framing: Framing,
    /// The bytes as they were on the wire, delimiters and escapes included. For a very long
    /// SAB2 run only the first bytes are kept: see `wire_len`.
    pub wire: &'a [u8],
    /// Length on the wire.
    pub wire_len: u64,
    /// Unescaped `HEADER COMMAND DATA` of a frame (`Frame`, `BadCrc`, SAB2 `Overlong`); for
    /// other kinds the unescaped bytes that were received after the start (may be empty).
    pub body: &'a [u8],
    /// `(received, computed)` check values of `Frame` and `BadCrc` (CRC-8 in the low byte for
    /// SAB v1; CRC-16 for SAB2).
    pub crc: Option<(u16, u16)>,
    /// Stream offsets of the first byte and one past the last byte (bytes since the start).
    pub start_pos: u64,
    pub end_pos: u64,
    /// Source times of the first and the last byte.
    pub start_time: Option<u64>,
    pub end_time: Option<u64>,
    /// SAB v1: the LENGTH byte of a frame, bad frame or truncated frame.
    pub length_byte: Option<u8>,
    /// SAB v1 garbage: 0x54 bytes whose candidate frame overlapped a valid frame (rescanned).
    pub false_syncs: u32,
    /// SAB v1 garbage: 0x54 bytes followed by a LENGTH above 32.
    pub bad_lengths: u32,
    /// Garbage that came before the first frame (or flag) of the capture.
    pub before_first: bool,
    /// SAB2: escapes that were not `7D 5E` / `7D 5D` (accepted as modm does).
    pub odd_escapes: u32,
    /// SAB2: unescaped bytes between the flags (counted beyond what is kept in `body`).
    pub body_len: u64,
    /// SAB v1 bad CRC: the check would pass if SYNC were covered too (not modm's rule).
    pub crc_with_sync: bool,
}

impl<'a> Event<'a> {
    /// An event with every optional field empty.
    pub fn new(kind: EventKind, framing: Framing, wire: &'a [u8]) -> Event<'a> {
        Event {
            kind,
            framing,
            wire,
            wire_len: wire.len() as u64,
            body: &[],
            crc: None,
            start_pos: 0,
            end_pos: 0,
            start_time: None,
            end_time: None,
            length_byte: None,
            false_syncs: 0,
            bad_lengths: 0,
            before_first: false,
            odd_escapes: 0,
            body_len: 0,
            crc_with_sync: false,
        }
    }

    /// The header byte, when the body has one.
    pub fn header(&self) -> Option<u8> {
        self.body.first().copied()
    }

    /// The command byte, when the body has one.
    pub fn command(&self) -> Option<u8> {
        self.body.get(1).copied()
    }

    /// The payload (body after header and command).
    pub fn payload(&self) -> &'a [u8] {
        self.body.get(2..).unwrap_or(&[])
    }

    pub fn flags(&self) -> Option<Flags> {
        self.header().map(Flags::of)
    }

    pub fn address(&self) -> Option<u8> {
        self.header().map(header::address)
    }

    /// True for a frame whose check passed.
    pub fn is_valid(&self) -> bool {
        self.kind == EventKind::Frame
    }
}

/// An owned copy of an [`Event`] (tests, tools, events kept across calls).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OwnedEvent {
    pub kind: EventKind,
    pub framing: Framing,
    pub wire: Vec<u8>,
    pub wire_len: u64,
    pub body: Vec<u8>,
    pub crc: Option<(u16, u16)>,
    pub start_pos: u64,
    pub end_pos: u64,
    pub start_time: Option<u64>,
    pub end_time: Option<u64>,
    pub length_byte: Option<u8>,
    pub false_syncs: u32,
    pub bad_lengths: u32,
    pub before_first: bool,
    pub odd_escapes: u32,
    pub body_len: u64,
    pub crc_with_sync: bool,
}

impl OwnedEvent {
    /// Overwrites this copy with `e`, reusing its buffers.
    pub fn set_from(&mut self, e: &Event<'_>) {
        let mut wire = std::mem::take(&mut self.wire);
        let mut body = std::mem::take(&mut self.body);
        wire.clear();
        wire.extend_from_slice(e.wire);
        body.clear();
        body.extend_from_slice(e.body);
        *self = OwnedEvent {
            wire,
            body,
            ..OwnedEvent::from(&Event {
                wire: &[],
                body: &[],
                ..*e
            })
        };
    }

    /// The event again, borrowing from this copy.
    pub fn as_event(&self) -> Event<'_> {
        Event {
            kind: self.kind,
            framing: self.framing,
            wire: &self.wire,
            wire_len: self.wire_len,
            body: &self.body,
            crc: self.crc,
            start_pos: self.start_pos,
            end_pos: self.end_pos,
            start_time: self.start_time,
            end_time: self.end_time,
            length_byte: self.length_byte,
            false_syncs: self.false_syncs,
            bad_lengths: self.bad_lengths,
            before_first: self.before_first,
            odd_escapes: self.odd_escapes,
            body_len: self.body_len,
            crc_with_sync: self.crc_with_sync,
        }
    }
}

impl From<&Event<'_>> for OwnedEvent {
    fn from(e: &Event<'_>) -> Self {
        OwnedEvent {
            kind: e.kind,
            framing: e.framing,
            wire: e.wire.to_vec(),
            wire_len: e.wire_len,
            body: e.body.to_vec(),
            crc: e.crc,
            start_pos: e.start_pos,
            end_pos: e.end_pos,
            start_time: e.start_time,
            end_time: e.end_time,
            length_byte: e.length_byte,
            false_syncs: e.false_syncs,
            bad_lengths: e.bad_lengths,
            before_first: e.before_first,
            odd_escapes: e.odd_escapes,
            body_len: e.body_len,
            crc_with_sync: e.crc_with_sync,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Haystacks of every length up to 48 with needles, their neighbours and bytes whose
    /// subtraction borrows (0x00, 0x01, 0x80, 0xFF) at every place, and xorshift noise.
    fn haystacks(a: u8, b: u8) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let fill = [0x00, 0x01, 0x80, 0xFF, a ^ 1, b ^ 0x80, a.wrapping_add(1)];
        for len in 0..48 {
            for &f in &fill {
                out.push(vec![f; len]);
                for at in 0..len {
                    for &x in &[a, b, 0x00, 0x01, 0x80, 0xFF, a.wrapping_sub(1)] {
                        let mut h = vec![f; len];
                        h[at] = x;
                        out.push(h.clone());
                        if at + 1 < len {
                            h[at + 1] = b;
                            out.push(h);
                        }
                    }
                }
            }
        }
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for i in 0..20_000 {
            let len = i % 70;
            out.push(
                (0..len)
                    .map(|_| {
                        x ^= x << 13;
                        x ^= x >> 7;
                        x ^= x << 17;
                        // Few distinct values, so needles turn up often.
                        [a, b, 0x00, 0x80, 0xFF, a ^ 1, x as u8][(x >> 32) as usize % 7]
                    })
                    .collect(),
            );
        }
        out
    }

    #[test]
    fn word_searches_are_byte_searches() {
        for (a, b) in [
            (0x7E, 0x7D),
            (0x54, 0x54),
            (0x00, 0xFF),
            (0x80, 0x7F),
            (0x01, 0x00),
        ] {
            for hay in haystacks(a, b) {
                assert_eq!(
                    find(a, &hay),
                    hay.iter().position(|&x| x == a),
                    "find {a:#04x} in {hay:02x?}"
                );
                assert_eq!(
                    find2(a, b, &hay),
                    hay.iter().position(|&x| x == a || x == b),
                    "find2 {a:#04x} {b:#04x} in {hay:02x?}"
                );
            }
        }
    }
}
