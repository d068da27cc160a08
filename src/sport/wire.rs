//! S.Port wire format: framing, byte stuffing, CRC, and the pure reassembler.
//!
//! A slot on the wire is `7E hdr` (a poll) optionally followed by 8 stuffed bytes
//! `type idL idH v0 v1 v2 v3 crc`. Every 0x7E starts a new slot; 0x7D escapes the next byte
//! (XOR 0x20). See `docs/sport.md` for the sources.

/// Start of every poll/frame.
pub const START: u8 = 0x7E;
/// Escape byte.
pub const ESCAPE: u8 = 0x7D;
/// Unstuffed frame length after the header: type, app ID (2), value (4), CRC.
pub const BODY_LEN: usize = 8;
/// Longest slot on the wire: 7E, header, 8 bytes each possibly stuffed.
pub const MAX_WIRE: usize = 2 + 2 * BODY_LEN;
use crate::row::GARBAGE_ROW_MAX;

/// Header byte for a physical ID (0..31): ID in bits 0-4 plus three check bits.
pub const fn header_for(phys: u8) -> u8 {
    let id = phys & 0x1F;
    let (b0, b1, b2, b3, b4) = (
        id & 1,
        (id >> 1) & 1,
        (id >> 2) & 1,
        (id >> 3) & 1,
        (id >> 4) & 1,
    );
    let bit5 = b0 ^ b1 ^ b2;
    let bit6 = b2 ^ b3 ^ b4;
    let bit7 = b0 ^ b2 ^ b4;
    id | bit5 << 5 | bit6 << 6 | bit7 << 7
}

/// The header of every physical ID, [`header_for`] worked out once.
const HEADERS: [u8; 32] = {
    let mut t = [0u8; 32];
    let mut i = 0;
    while i < 32 {
        t[i] = header_for(i as u8);
        i += 1;
    }
    t
};

/// True when the header's check bits match its physical ID.
pub const fn header_ok(header: u8) -> bool {
    HEADERS[(header & 0x1F) as usize] == header
}

/// End-around-carry sum of `bytes` (the S.Port checksum arithmetic). The carries are folded
/// back at the end instead of after every byte: end-around-carry addition is ones'-complement
/// addition, so the order does not matter, and both give 0 only when every byte is 0.
#[inline]
pub fn carry_sum(bytes: &[u8]) -> u8 {
    fold(byte_sum(bytes))
}

/// The plain sum of `bytes`, eight at a time (F.Port checks every frame with [`carry_sum`],
/// some twice while resynchronising).
#[inline]
fn byte_sum(bytes: &[u8]) -> u64 {
    let mut words = bytes.chunks_exact(8);
    let mut s = 0u64;
    for word in &mut words {
        s += word_sum(u64::from_le_bytes(word.try_into().unwrap_or_default()));
    }
    s + words.remainder().iter().map(|&b| u64::from(b)).sum::<u64>()
}

/// The plain sum of the eight bytes of `w`: neighbours into four 16-bit lanes (each at most
/// 510), then the four lanes by one multiplication into the top lane (at most 2040: no lane
/// carries into the next).
#[inline(always)]
fn word_sum(w: u64) -> u64 {
    const LOW_BYTES: u64 = 0x00FF_00FF_00FF_00FF;
    let pairs = (w & LOW_BYTES) + ((w >> 8) & LOW_BYTES);
    pairs.wrapping_mul(0x0001_0001_0001_0001) >> 48
}

/// Folds the carries of a plain sum of bytes back into one byte (end-around carry).
#[inline]
fn fold(mut s: u64) -> u8 {
    while s > 0xFF {
        s = (s & 0xFF) + (s >> 8);
    }
    s as u8
}

/// CRC byte for the 7 bytes type..v3.
pub fn crc(body7: &[u8]) -> u8 {
    0xFF - carry_sum(body7)
}

/// True when the 8 unstuffed bytes (type..crc) pass the check: their [`carry_sum`] is 0xFF.
/// Every frame is checked, so the eight bytes are added as one word instead of one by one
/// (`word_sum`).
#[inline]
pub fn crc_ok(body: &[u8; BODY_LEN]) -> bool {
    // At most 2040: two folds (no loop to mispredict) leave one byte, as `fold` would (a fold
    // of a byte leaves it as it is).
    let s = word_sum(u64::from_le_bytes(*body));
    let s = (s & 0xFF) + (s >> 8);
    (s & 0xFF) + (s >> 8) == 0xFF
}

/// Appends `byte` to `out`, stuffed if needed.
pub fn push_stuffed(out: &mut Vec<u8>, byte: u8) {
    if byte == START || byte == ESCAPE {
        out.push(ESCAPE);
        out.push(byte ^ 0x20);
    } else {
        out.push(byte);
    }
}

/// Encodes a poll `7E hdr`.
pub fn encode_poll(out: &mut Vec<u8>, header: u8) {
    out.push(START);
    out.push(header);
}

/// Encodes a whole frame `7E hdr` + stuffed body with a correct CRC.
pub fn encode_frame(out: &mut Vec<u8>, header: u8, kind: u8, app_id: u16, value: u32) {
    let mut body = [0u8; BODY_LEN];
    body[0] = kind;
    body[1..3].copy_from_slice(&app_id.to_le_bytes());
    body[3..7].copy_from_slice(&value.to_le_bytes());
    body[7] = crc(&body[..7]);
    encode_raw(out, header, &body);
}

/// Encodes `7E hdr` + the 8 given body bytes (CRC not recomputed), stuffed.
pub fn encode_raw(out: &mut Vec<u8>, header: u8, body: &[u8; BODY_LEN]) {
    encode_poll(out, header);
    for &b in body {
        push_stuffed(out, b);
    }
}

/// What followed a poll in its slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Body {
    /// Nothing before the next 0x7E: an unanswered poll.
    None,
    /// All 8 bytes (type..crc), unstuffed.
    Complete([u8; BODY_LEN]),
    /// Cut short by the next 0x7E, a 0x7D right before it, or the end of input.
    Truncated { bytes: [u8; BODY_LEN], len: u8 },
}

/// One poll slot: `7E hdr` and its response, if any.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    /// Arrival time of the 0x7E (µs since the capture started), when the source has times.
    pub time: Option<u64>,
    /// Number of this slot since the start, from 0 (the bus schedule for untimed sources).
    pub index: u64,
    pub header: u8,
    pub body: Body,
    /// An escape was followed by a byte other than 0x5E/0x5D.
    pub unusual_escape: bool,
    wire: [u8; MAX_WIRE],
    wire_len: u8,
}

impl Slot {
    /// The slot's bytes exactly as they were on the wire.
    pub fn wire(&self) -> &[u8] {
        &self.wire[..self.wire_len as usize]
    }

    /// Physical ID, 0-based (`header & 0x1F`).
    pub fn phys(&self) -> u8 {
        self.header & 0x1F
    }
}

/// Bytes that belong to no slot: before the first 0x7E, after a complete frame, or a 0x7E
/// without a header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Garbage {
    /// Arrival time of the first byte.
    pub time: Option<u64>,
    /// Index of the slot these bytes followed (`None` before the first slot).
    pub after_slot: Option<u64>,
    bytes: [u8; GARBAGE_ROW_MAX],
    len: u8,
}

impl Garbage {
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len as usize]
    }
}

/// What the reassembler emits: borrowed from the reassembler, so nothing is copied per frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event<'a> {
    Slot(&'a Slot),
    Garbage(&'a Garbage),
}

/// True when none of the 8 bytes in `v` is 0x7E or 0x7D (a byte equals `x` when `v ^ x` has a
/// zero byte; the test below finds a zero byte exactly).
#[inline]
fn plain(v: u64) -> bool {
    const ONES: u64 = 0x0101_0101_0101_0101;
    const HIGHS: u64 = 0x8080_8080_8080_8080;
    let has_zero = |x: u64| x.wrapping_sub(ONES) & !x & HIGHS != 0;
    !has_zero(v ^ (START as u64 * ONES)) && !has_zero(v ^ (ESCAPE as u64 * ONES))
}

/// A whole body at the start of `data` with stuffed bytes (one frame in eight or so): the 8
/// unstuffed bytes and the wire bytes they took, exactly as the byte loop would take them.
/// `None` (and the byte loop takes over) when a 0x7E comes first, an escape is unusual (not
/// followed by 0x5E/0x5D: the byte loop flags it) or the chunk ends before the body does.
#[inline]
fn stuffed_body(data: &[u8]) -> Option<([u8; BODY_LEN], &[u8])> {
    let mut body = [0u8; BODY_LEN];
    let mut j = 0;
    for out in &mut body {
        *out = match *data.get(j)? {
            START => return None,
            ESCAPE => match *data.get(j + 1)? {
                e @ (0x5E | 0x5D) => {
                    j += 1;
                    e ^ 0x20
                }
                _ => return None,
            },
            b => b,
        };
        j += 1;
    }
    Some((body, data.get(..j)?))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Outside any slot (before the first 0x7E, or after a complete frame).
    Outside,
    /// Saw 0x7E, waiting for the header.
    Header,
    /// Collecting the body.
    Body,
}

/// Pure S.Port reassembler: bytes and times in, [`Event`]s out. The output does not depend on
/// how the input is split into chunks.
#[derive(Clone, Debug)]
pub struct Reassembler {
    state: State,
    escaped: bool,
    next_index: u64,
    cur: Slot,
    body: [u8; BODY_LEN],
    body_len: usize,
    garbage: Garbage,
    last_slot: Option<u64>,
}

impl Default for Reassembler {
    fn default() -> Self {
        Self::new()
    }
}

const EMPTY_SLOT: Slot = Slot {
    time: None,
    index: 0,
    header: 0,
    body: Body::None,
    unusual_escape: false,
    wire: [0; MAX_WIRE],
    wire_len: 0,
};

const EMPTY_GARBAGE: Garbage = Garbage {
    time: None,
    after_slot: None,
    bytes: [0; GARBAGE_ROW_MAX],
    len: 0,
};

impl Reassembler {
    pub fn new() -> Self {
        Reassembler {
            state: State::Outside,
            escaped: false,
            next_index: 0,
            cur: EMPTY_SLOT,
            body: [0; BODY_LEN],
            body_len: 0,
            garbage: EMPTY_GARBAGE,
            last_slot: None,
        }
    }

    /// Feeds `data` that arrived at `time`; calls `emit` for every completed event.
    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        let mut i = 0;
        while let Some(&b) = data.get(i) {
            if b != START {
                self.byte(b, time, emit);
                i += 1;
                continue;
            }
            // A slot starts: take its header, and a whole body without a 0x7E or 0x7D (almost
            // every frame) in one step, exactly as the byte loop would take them.
            self.start(time, emit);
            i += 1;
            let Some(&header) = data.get(i).filter(|&&h| h != START) else {
                continue;
            };
            self.header(header);
            i += 1;
            if let Some(body) = data.get(i..i + BODY_LEN)
                && let Ok(body) = <[u8; BODY_LEN]>::try_from(body)
                && plain(u64::from_le_bytes(body))
            {
                self.whole_body(body, &body, emit);
                i += BODY_LEN;
            } else if let Some(rest) = data.get(i..)
                && let Some((body, wire)) = stuffed_body(rest)
            {
                self.whole_body(body, wire, emit);
                i += wire.len();
            }
        }
    }

    /// The 8 body bytes of the open slot (the slot holds `7E hdr` so far) and the `wire` bytes
    /// they came from (8 to 16: [`plain`] bodies or [`stuffed_body`]'s).
    #[inline]
    fn whole_body(&mut self, body: [u8; BODY_LEN], wire: &[u8], emit: &mut impl FnMut(Event<'_>)) {
        let end = 2 + wire.len();
        self.cur.wire[2..end].copy_from_slice(wire);
        self.cur.wire_len = end as u8;
        self.body = body;
        self.body_len = BODY_LEN;
        self.cur.body = Body::Complete(body);
        emit(Event::Slot(&self.cur));
        self.state = State::Outside;
    }

    /// End of input: emits an open slot (as unanswered or truncated) and pending garbage.
    pub fn finish(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        match self.state {
            State::Outside => {}
            State::Header => self.lone_start(emit),
            State::Body => self.close_slot(emit),
        }
        self.flush_garbage(emit);
        self.state = State::Outside;
        self.escaped = false;
    }

    /// Slots started so far.
    pub fn slots(&self) -> u64 {
        self.next_index
    }

    #[inline]
    fn byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        if b == START {
            self.start(time, emit);
            return;
        }
        match self.state {
            State::Outside => self.garbage_byte(b, time, emit),
            State::Header => self.header(b),
            State::Body => {
                self.cur.wire[self.cur.wire_len as usize] = b;
                self.cur.wire_len += 1;
                if self.escaped {
                    self.escaped = false;
                    if b != 0x5E && b != 0x5D {
                        self.cur.unusual_escape = true;
                    }
                    self.body_byte(b ^ 0x20, emit);
                } else if b == ESCAPE {
                    self.escaped = true;
                } else {
                    self.body_byte(b, emit);
                }
            }
        }
    }

    /// A 0x7E: ends the open slot and pending garbage, opens a slot.
    #[inline]
    fn start(&mut self, time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        match self.state {
            State::Outside => {}
            State::Header => self.lone_start(emit),
            State::Body => self.close_slot(emit),
        }
        self.flush_garbage(emit);
        self.cur.time = time;
        self.cur.index = self.next_index;
        self.cur.unusual_escape = false;
        self.cur.wire[0] = START;
        self.cur.wire_len = 1;
        self.escaped = false;
        self.body_len = 0;
        self.state = State::Header;
    }

    /// The header byte (not 0x7E) of the slot just opened.
    #[inline]
    fn header(&mut self, b: u8) {
        self.cur.header = b;
        self.cur.wire[1] = b;
        self.cur.wire_len = 2;
        self.next_index += 1;
        self.last_slot = Some(self.cur.index);
        self.state = State::Body;
    }

    #[inline]
    fn body_byte(&mut self, b: u8, emit: &mut impl FnMut(Event<'_>)) {
        self.body[self.body_len] = b;
        self.body_len += 1;
        if self.body_len == BODY_LEN {
            self.cur.body = Body::Complete(self.body);
            emit(Event::Slot(&self.cur));
            self.state = State::Outside;
        }
    }

    /// The open slot ends before its 8 bytes arrived.
    fn close_slot(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        self.cur.body = if self.body_len == 0 && !self.escaped {
            Body::None
        } else {
            Body::Truncated {
                bytes: self.body,
                len: self.body_len as u8,
            }
        };
        emit(Event::Slot(&self.cur));
        self.state = State::Outside;
    }

    /// A 0x7E that was not followed by a header byte.
    fn lone_start(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        self.state = State::Outside;
        self.garbage_byte(START, self.cur.time, emit);
    }

    fn garbage_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(Event<'_>)) {
        if self.garbage.len == 0 {
            self.garbage.time = time;
            self.garbage.after_slot = self.last_slot;
        }
        self.garbage.bytes[self.garbage.len as usize] = b;
        self.garbage.len += 1;
        if self.garbage.len as usize == GARBAGE_ROW_MAX {
            self.flush_garbage(emit);
        }
    }

    fn flush_garbage(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        if self.garbage.len > 0 {
            emit(Event::Garbage(&self.garbage));
            self.garbage.len = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmt::parse_hex;

    /// Owned copies of the events, for assertions.
    #[derive(Debug, PartialEq)]
    enum Owned {
        Slot(Slot),
        Garbage(Garbage),
    }

    /// The events of `data` pushed whole.
    fn events(data: &[u8]) -> Vec<Owned> {
        events_in_chunks(data, data.len().max(1))
    }

    #[test]
    fn header_table_matches_reference() {
        // sport.md §2.1
        let table = [
            0x00, 0xA1, 0x22, 0x83, 0xE4, 0x45, 0xC6, 0x67, 0x48, 0xE9, 0x6A, 0xCB, 0xAC, 0x0D,
            0x8E, 0x2F, 0xD0, 0x71, 0xF2, 0x53, 0x34, 0x95, 0x16, 0xB7, 0x98, 0x39, 0xBA, 0x1B,
            0x7C, 0xDD, 0x5E, 0xFF,
        ];
        for (phys, &h) in table.iter().enumerate() {
            assert_eq!(header_for(phys as u8), h, "phys {phys}");
            assert!(header_ok(h));
        }
        assert!(!header_ok(0x18));
        assert!(!header_ok(0x1C));
        assert!(!header_ok(0xA2));
    }

    #[test]
    fn carry_sum_folds_like_byte_by_byte() {
        let step = |bytes: &[u8]| {
            let mut s: u16 = 0;
            for &b in bytes {
                s += b as u16;
                s = (s & 0xFF) + (s >> 8);
            }
            s as u8
        };
        let mut x = 0x1234_5678u32;
        for len in 0..40 {
            for _ in 0..200 {
                let bytes: Vec<u8> = (0..len)
                    .map(|_| {
                        x ^= x << 13;
                        x ^= x >> 17;
                        x ^= x << 5;
                        // Many 0x00 and 0xFF bytes: the edge cases of the fold.
                        match x % 4 {
                            0 => 0,
                            1 => 0xFF,
                            _ => (x >> 8) as u8,
                        }
                    })
                    .collect();
                assert_eq!(carry_sum(&bytes), step(&bytes), "{bytes:02X?}");
            }
        }
        assert_eq!(carry_sum(&[0xFF; 8]), 0xFF);
        assert_eq!(carry_sum(&[0; 8]), 0);
    }

    /// The word-wise check agrees with the byte sum on every kind of frame: random bodies, bodies
    /// of 0x00 and 0xFF (the fold's edges), and every CRC byte of each (passing and failing).
    #[test]
    fn crc_ok_matches_carry_sum() {
        let mut x = 0x9E37_79B9u32;
        for n in 0..20_000 {
            let mut body = [0u8; BODY_LEN];
            for b in &mut body[..7] {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                *b = match (x >> 3) % 4 {
                    0 if n % 2 == 0 => 0,
                    1 if n % 2 == 0 => 0xFF,
                    _ => (x >> 8) as u8,
                };
            }
            let crcs: Vec<u8> = if n < 200 {
                (0..=255).collect()
            } else {
                vec![crc(&body[..7]), (x >> 24) as u8, 0, 0xFF]
            };
            for c in crcs {
                body[7] = c;
                assert_eq!(crc_ok(&body), carry_sum(&body) == 0xFF, "{body:02X?}");
            }
        }
        for body in [[0u8; 8], [0xFF; 8], [0xFE; 8], [0x01; 8]] {
            assert_eq!(crc_ok(&body), carry_sum(&body) == 0xFF, "{body:02X?}");
        }
    }

    /// The events of `data` pushed in chunks of `size` bytes (1: never the one-step bodies).
    fn events_in_chunks(data: &[u8], size: usize) -> Vec<Owned> {
        let mut r = Reassembler::new();
        let mut out = Vec::new();
        let mut keep = |e: Event<'_>| {
            out.push(match e {
                Event::Slot(s) => Owned::Slot(*s),
                Event::Garbage(g) => Owned::Garbage(*g),
            })
        };
        for chunk in data.chunks(size) {
            r.push(chunk, None, &mut keep);
        }
        r.finish(&mut keep);
        out
    }

    /// Bodies taken in one step (plain and stuffed) give the events of the byte loop: frames
    /// full of 0x7E, 0x7D, 0x5E and 0x5D (stuffed or not, usual escapes and unusual ones,
    /// escapes at a body's end, frames cut short), pushed whole and in chunks of every size.
    #[test]
    fn one_step_bodies_match_the_byte_loop() {
        let mut x = 0x2545_F491u32;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        for _ in 0..3000 {
            let mut data = Vec::new();
            for _ in 0..(next() % 6) {
                let r = next();
                match r % 8 {
                    0 => encode_poll(&mut data, (r >> 8) as u8),
                    1 => data.push((r >> 8) as u8),
                    2 => {
                        // Raw bytes biased to the special ones, after a slot start.
                        data.extend([START, (r >> 8) as u8 & 0x1F]);
                        for k in 0..(r >> 16) % 20 {
                            let v = next();
                            data.push(match v % 6 {
                                0 => START,
                                1 => ESCAPE,
                                2 => 0x5E,
                                3 => 0x5D,
                                _ => (v >> 8) as u8 ^ k as u8,
                            });
                        }
                    }
                    _ => {
                        let v = next();
                        let special = [START, ESCAPE, 0x5E, 0x5D, 0x20, 0];
                        let value = u32::from_le_bytes([
                            special[(v % 6) as usize],
                            (v >> 8) as u8,
                            special[((v >> 16) % 6) as usize],
                            (v >> 24) as u8,
                        ]);
                        let kind = if r & 0x100 == 0 { 0x10 } else { START };
                        encode_frame(&mut data, header_for(r as u8), kind, r as u16, value);
                    }
                }
            }
            let whole = events(&data);
            for size in [1, 2, 3, 7, 9, 11, 17] {
                assert_eq!(
                    events_in_chunks(&data, size),
                    whole,
                    "{data:02X?} in {size}s"
                );
            }
        }
    }

    #[test]
    fn crc_worked_examples() {
        // sport.md §4.2
        assert_eq!(crc(&[0x10, 0x00, 0x03, 0x30, 0x0D, 0x88, 0x81]), 0xA5);
        assert_eq!(crc(&[0x10, 0x00, 0x03, 0x32, 0x34, 0x08, 0x00]), 0x7E);
        assert_eq!(crc(&[0; 7]), 0xFF);
        assert!(crc_ok(&[0, 0, 0, 0, 0, 0, 0, 0xFF]));
    }

    #[test]
    fn stuffed_crc_is_unstuffed() {
        let wire = parse_hex("7E A1 10 00 03 32 34 08 00 7D 5E").unwrap();
        let ev = events(&wire);
        assert_eq!(ev.len(), 1);
        let Owned::Slot(s) = &ev[0] else { panic!() };
        assert_eq!(s.body, Body::Complete([0x10, 0, 3, 0x32, 0x34, 8, 0, 0x7E]));
        assert_eq!(s.wire(), &wire[..]);
        assert!(!s.unusual_escape);
    }

    #[test]
    fn polls_truncation_and_garbage() {
        let wire =
            parse_hex("55 66 7E 00 7E A1 10 00 7E 22 10 00 02 00 00 00 00 ED AA 7E 7E 83 7D")
                .unwrap();
        let ev = events(&wire);
        let kinds: Vec<String> = ev
            .iter()
            .map(|e| match e {
                Owned::Garbage(g) => format!("garbage {}", crate::fmt::hex(g.bytes())),
                Owned::Slot(s) => match s.body {
                    Body::None => format!("poll {}", s.phys()),
                    Body::Complete(_) => format!("frame {}", s.phys()),
                    Body::Truncated { len, .. } => format!("trunc {} {len}", s.phys()),
                },
            })
            .collect();
        assert_eq!(
            kinds,
            [
                "garbage 55 66",
                "poll 0",
                "trunc 1 2",
                "frame 2",
                "garbage AA",
                "garbage 7E",
                "trunc 3 0"
            ]
        );
    }

    #[test]
    fn encoder_round_trip() {
        let mut wire = Vec::new();
        encode_frame(&mut wire, 0x1B, 0x10, 0x7D7E, 0x7E7D_7E7D);
        let ev = events(&wire);
        let Owned::Slot(s) = &ev[0] else { panic!() };
        let Body::Complete(b) = s.body else { panic!() };
        assert!(crc_ok(&b));
        assert_eq!(u16::from_le_bytes([b[1], b[2]]), 0x7D7E);
        assert_eq!(u32::from_le_bytes([b[3], b[4], b[5], b[6]]), 0x7E7D_7E7D);
    }
}
