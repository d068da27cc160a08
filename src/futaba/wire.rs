//! Futaba SBUS / SBUS2 wire format and the pure reassembler.
//!
//! A frame is 25 bytes: `0F`, 22 bytes holding 16 channels of 11 bits packed little-endian
//! (channel 1 in the lowest bits of byte 1), a flags byte (bit 0 CH17, bit 1 CH18, bit 2 frame
//! lost, bit 3 failsafe) and an end byte: `00` for SBUS, `04`/`14`/`24`/`34` for SBUS2, which
//! names the group of telemetry slots that follows (slots 0-7, 8-15, 16-23, 24-31), or `08`
//! (INAV: an SBUS2 receiver at its fast frame pace, no slots). After an SBUS2 frame, up to
//! eight sensors answer in 3-byte slots `[slot id][value hi][value lo]`.
//!
//! There is no checksum: a frame is recognised by its start byte, its length and its end
//! byte, a slot by its slot id (every id has the low bits `011`, so none is `0F`). See
//! `docs/futaba.md` for the sources and the choices made where the wire is ambiguous.

use crate::row::GARBAGE_ROW_MAX;

/// First byte of every frame.
pub const START: u8 = 0x0F;
/// Bytes in a frame.
pub const FRAME_LEN: usize = 25;
/// Bytes in a telemetry slot.
pub const SLOT_LEN: usize = 3;
/// Slots after one SBUS2 frame.
pub const SLOTS_PER_GROUP: u8 = 8;
/// Channels carried as 11-bit numbers.
pub const CHANNELS: usize = 16;
/// End byte of an SBUS frame.
pub const END_SBUS: u8 = 0x00;
/// End byte of INAV's SBUS2 fast frame pace (no slots follow).
pub const END_FAST: u8 = 0x08;
/// Flag bits of byte 23.
pub const FLAG_CH17: u8 = 1 << 0;
pub const FLAG_CH18: u8 = 1 << 1;
pub const FLAG_FRAME_LOST: u8 = 1 << 2;
pub const FLAG_FAILSAFE: u8 = 1 << 3;

/// Default line: 100000 baud, 8 data bits, even parity, 2 stop bits, inverted.
pub const BAUD: u32 = 100_000;
/// Bits of one character on the wire (start, 8 data, parity, 2 stop).
pub const BITS_PER_CHAR: u32 = 12;

/// The slot group an end byte announces (0 for slots 0-7 … 3 for 24-31), or `None` for an end
/// byte that announces no slots (`00`, `08`) or is no end byte at all.
pub const fn slot_group(end: u8) -> Option<u8> {
    match end {
        0x04 | 0x14 | 0x24 | 0x34 => Some(end >> 4),
        _ => None,
    }
}

/// Whether `end` ends a frame.
pub const fn end_ok(end: u8) -> bool {
    matches!(end, END_SBUS | END_FAST) || slot_group(end).is_some()
}

/// Reverses the low five bits.
const fn rev5(v: u8) -> u8 {
    ((v & 1) << 4) | ((v & 2) << 2) | (v & 4) | ((v & 8) >> 2) | ((v & 16) >> 4)
}

/// The id byte of slot `n` (0..=31): the slot number bit-reversed into the top five bits, then
/// `011` (slot 0 `03`, slot 1 `83`, slot 8 `13`, slot 31 `FB`).
pub const fn slot_id(n: u8) -> u8 {
    rev5(n & 0x1F) << 3 | 0x03
}

/// The slot number of an id byte, or `None` when the byte is no slot id.
pub const fn slot_number(id: u8) -> Option<u8> {
    if id & 0x07 == 0x03 {
        Some(rev5(id >> 3))
    } else {
        None
    }
}

/// The 16 channels of a frame, as the 11-bit numbers on the wire.
#[inline]
pub fn channels(frame: &[u8; FRAME_LEN]) -> [u16; CHANNELS] {
    // Channel i's 11 bits start at bit 11 i of the data bytes (frame[1..23]); three bytes from
    // there hold them (the last channel's third byte is the flags byte, masked off).
    std::array::from_fn(|i| {
        let bit = 11 * i;
        let at = 1 + bit / 8;
        let three = u32::from_le_bytes([frame[at], frame[at + 1], frame[at + 2], 0]);
        ((three >> (bit % 8)) & 0x7FF) as u16
    })
}

/// Betaflight's microseconds for an 11-bit channel value: `5 * x / 8 + 880`, in integers as
/// Betaflight computes it (`sbusChannelsReadRawRC`): 200 → 1005, 1000 → 1505, 1800 → 2005.
pub const fn micros(raw: u16) -> u16 {
    (5 * raw as u32 / 8 + 880) as u16
}

/// Encodes a frame (for tests and generators): channels (only the low 11 bits are used), flags
/// and end byte.
pub fn encode_frame(out: &mut Vec<u8>, channels: &[u16; CHANNELS], flags: u8, end: u8) {
    out.push(START);
    let mut acc: u32 = 0;
    let mut bits = 0;
    let mut n = 0;
    for &c in channels {
        acc |= u32::from(c & 0x7FF) << bits;
        bits += 11;
        while bits >= 8 {
            out.push(acc as u8);
            acc >>= 8;
            bits -= 8;
            n += 1;
        }
    }
    debug_assert_eq!((n, bits), (22, 0));
    out.push(flags);
    out.push(end);
}

/// Encodes a telemetry slot answer.
pub fn encode_slot(out: &mut Vec<u8>, slot: u8, value: u16) {
    out.push(slot_id(slot));
    out.extend_from_slice(&value.to_be_bytes());
}

/// Why bytes are not a frame or slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Broken {
    /// A `0F` whose 25th byte is no end byte, with a frame starting at a later `0F` before
    /// that byte: the frame was cut short (bytes lost). The bytes up to that frame.
    Cut,
    /// A `0F` and 24 more bytes whose last one is no end byte, with no frame starting among
    /// them.
    WrongEnd,
    /// A frame or slot cut by the end of the input (or a gap).
    AtEnd,
    /// A slot answer cut short by the start of a frame.
    SlotCut,
    /// Bytes that belong to no frame and no slot.
    Garbage,
}

/// What the reassembler found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event<'a> {
    Frame {
        /// Position of the start byte in the stream.
        offset: u64,
        /// Arrival time of the start byte, when the source has times.
        time: Option<u64>,
        bytes: &'a [u8; FRAME_LEN],
    },
    Slot {
        offset: u64,
        time: Option<u64>,
        /// Borrowed like a frame's: a copy of three single bytes, read back as a word by the
        /// mapper, stalled the load (no store forwarding from narrower stores).
        bytes: &'a [u8; SLOT_LEN],
        /// The group the frame before announced (0..=3).
        group: u8,
        /// Position in the group's run of answers (0..8).
        index: u8,
    },
    Broken {
        offset: u64,
        time: Option<u64>,
        why: Broken,
        bytes: &'a [u8],
    },
}

/// The buffer never holds more than this: enough for a slot, the frame that might start
/// inside it, and a garbage run.
const CAP: usize = 128;

/// Longest look-ahead a decision needs: a frame with a wrong end byte, and a frame that may
/// start at its last byte but one (24 + 25).
const LOOKAHEAD: usize = 2 * FRAME_LEN - 1;

/// The pure reassembler: bytes and times in, [`Event`]s out. Identical events however the
/// input is split (each byte keeps the time of the push it came with).
#[derive(Debug, Default)]
pub struct Reassembler {
    buf: Vec<u8>,
    times: Vec<Option<u64>>,
    /// Stream position of `buf[0]`.
    offset: u64,
    /// After an SBUS2 frame: its slot group and the answers seen so far.
    slots: Option<(u8, u8)>,
}

impl Reassembler {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds bytes that arrived at `time`. They are read where they are; only the few at the
    /// end that need more bytes for a decision are kept (with the time of each).
    pub fn push(&mut self, mut data: &[u8], time: Option<u64>, emit: &mut dyn FnMut(Event<'_>)) {
        // Bytes kept from before: completed from the new ones until what is left came with
        // these (then read in place).
        while !self.buf.is_empty() && !data.is_empty() {
            let old = self.buf.len();
            let n = (CAP - old).min(data.len());
            self.buf.extend_from_slice(&data[..n]);
            self.times.extend(std::iter::repeat_n(time, n));
            let used = self.run(false, emit);
            if used >= old {
                self.buf.clear();
                self.times.clear();
                data = &data[used - old..];
                break;
            }
            data = &data[n..];
        }
        if self.buf.is_empty() && !data.is_empty() {
            let used = run_on(data, self.offset, |_| time, &mut self.slots, false, emit);
            self.offset += used as u64;
            let rest = &data[used..];
            self.buf.extend_from_slice(rest);
            self.times.extend(std::iter::repeat_n(time, rest.len()));
        }
    }

    /// End of input (or a gap): whatever is open comes out; ready for more bytes after it.
    pub fn finish(&mut self, emit: &mut dyn FnMut(Event<'_>)) {
        self.run(true, emit);
        self.slots = None;
    }

    /// Consumes what can be decided of the bytes kept, and returns how many. Without `end`,
    /// stops where more bytes are needed.
    fn run(&mut self, end: bool, emit: &mut dyn FnMut(Event<'_>)) -> usize {
        let times = &self.times;
        let used = run_on(
            &self.buf,
            self.offset,
            |i| times[i],
            &mut self.slots,
            end,
            emit,
        );
        self.buf.drain(..used);
        self.times.drain(..used);
        self.offset += used as u64;
        used
    }
}

/// Consumes what can be decided of `buf` (stream position `offset`, the time of byte `i` is
/// `time(i)`; `slots`: the open slot group and the answers seen so far), and returns how
/// many bytes. Without `end`, stops where more bytes are needed.
#[inline]
fn run_on(
    buf: &[u8],
    offset: u64,
    time: impl Fn(usize) -> Option<u64>,
    slots: &mut Option<(u8, u8)>,
    end: bool,
    emit: &mut dyn FnMut(Event<'_>),
) -> usize {
    let mut used = 0;
    while used < buf.len() {
        let Some((n, ev)) = step(&buf[used..], slots.is_some(), end) else {
            break;
        };
        let offset = offset + used as u64;
        let time = time(used);
        let bytes = &buf[used..used + n];
        match ev {
            Step::Frame => {
                let frame: &[u8; FRAME_LEN] = match bytes.try_into() {
                    Ok(f) => f,
                    Err(_) => unreachable!("a frame step is 25 bytes"),
                };
                *slots = slot_group(frame[24]).map(|g| (g, 0));
                emit(Event::Frame {
                    offset,
                    time,
                    bytes: frame,
                });
            }
            Step::Slot => {
                let (group, index) = slots.unwrap_or((0, 0));
                let next = index + 1;
                *slots = (next < SLOTS_PER_GROUP).then_some((group, next));
                let slot: &[u8; SLOT_LEN] = match bytes.try_into() {
                    Ok(b) => b,
                    Err(_) => unreachable!("a slot step is 3 bytes"),
                };
                emit(Event::Slot {
                    offset,
                    time,
                    bytes: slot,
                    group,
                    index,
                });
            }
            Step::Broken(why) => {
                *slots = None;
                emit(Event::Broken {
                    offset,
                    time,
                    why,
                    bytes,
                });
            }
        }
        used += n;
    }
    used
}

/// What starts at `b[0]`, and how many bytes it takes (`slots`: a slot group is open); `None`
/// when more bytes are needed.
#[inline]
fn step(b: &[u8], slots: bool, end: bool) -> Option<(usize, Step)> {
    let first = b[0];
    if first == START {
        if b.len() < FRAME_LEN {
            // A 0F among the first bytes may be a channel byte: only the 25th byte tells.
            if !end {
                return None;
            }
            return Some(match next_start(b, b.len()) {
                Some(i) => (i, Step::Broken(Broken::Cut)),
                None => (b.len(), Step::Broken(Broken::AtEnd)),
            });
        }
        if end_ok(b[FRAME_LEN - 1]) {
            return Some((FRAME_LEN, Step::Frame));
        }
        // A wrong end byte: cut short if a frame starts at a later 0F among its bytes (a
        // byte was lost), otherwise 25 bytes that are no frame.
        let mut from = 1;
        while let Some(q) = next_start(&b[from - 1..], FRAME_LEN - from + 1) {
            let q = q + from - 1;
            if b.len() < q + FRAME_LEN {
                if !end {
                    return None;
                }
                break;
            }
            if end_ok(b[q + FRAME_LEN - 1]) {
                return Some((q, Step::Broken(Broken::Cut)));
            }
            from = q + 1;
        }
        return Some((FRAME_LEN, Step::Broken(Broken::WrongEnd)));
    }
    if slots && slot_number(first).is_some() {
        // A value byte may be 0F. The slot is cut short only when a frame starts at that
        // 0F and none starts right after the three bytes read as a slot.
        if b.len() < SLOT_LEN {
            return end.then_some((b.len(), Step::Broken(Broken::AtEnd)));
        }
        if !b[1..SLOT_LEN].contains(&START) {
            return Some((SLOT_LEN, Step::Slot));
        }
        if b.len() < SLOT_LEN + FRAME_LEN && !end {
            return None;
        }
        let frame_at = |i: usize| {
            b.get(i) == Some(&START) && b.get(i + FRAME_LEN - 1).is_some_and(|&e| end_ok(e))
        };
        let slot_fits = b.len() == SLOT_LEN || frame_at(SLOT_LEN);
        if !slot_fits && let Some(i) = (1..SLOT_LEN).find(|&i| frame_at(i)) {
            return Some((i, Step::Broken(Broken::SlotCut)));
        }
        return Some((SLOT_LEN, Step::Slot));
    }
    // Garbage up to the next 0F, at most GARBAGE_ROW_MAX bytes.
    let limit = GARBAGE_ROW_MAX.min(b.len());
    match next_start(b, limit) {
        Some(i) => Some((i, Step::Broken(Broken::Garbage))),
        None if limit == GARBAGE_ROW_MAX || end => Some((limit, Step::Broken(Broken::Garbage))),
        None => None,
    }
}

/// What [`step`] decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Frame,
    Slot,
    Broken(Broken),
}

/// The first `0F` in `b[1..limit]`.
fn next_start(b: &[u8], limit: usize) -> Option<usize> {
    b[1..limit].iter().position(|&x| x == START).map(|i| i + 1)
}

const _: () = assert!(CAP >= LOOKAHEAD + GARBAGE_ROW_MAX);

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(ch: [u16; CHANNELS], flags: u8, end: u8) -> Vec<u8> {
        let mut v = Vec::new();
        encode_frame(&mut v, &ch, flags, end);
        v
    }

    /// What the reassembler finds, as (kind, offset, length).
    fn events(chunks: &[&[u8]]) -> Vec<(String, u64, usize)> {
        let mut re = Reassembler::new();
        let mut out = Vec::new();
        let mut take = |e: Event<'_>| {
            out.push(match e {
                Event::Frame { offset, .. } => ("frame".to_string(), offset, FRAME_LEN),
                Event::Slot {
                    offset,
                    group,
                    index,
                    ..
                } => (format!("slot g{group} i{index}"), offset, SLOT_LEN),
                Event::Broken {
                    offset, why, bytes, ..
                } => (format!("{why:?}"), offset, bytes.len()),
            })
        };
        for c in chunks {
            re.push(c, None, &mut take);
        }
        re.finish(&mut take);
        out
    }

    #[test]
    fn slot_ids_are_the_public_table() {
        // INAV telemetry/sbus2.c, sbus2SlotIds.
        let table = [
            0x03, 0x83, 0x43, 0xC3, 0x23, 0xA3, 0x63, 0xE3, 0x13, 0x93, 0x53, 0xD3, 0x33, 0xB3,
            0x73, 0xF3, 0x0B, 0x8B, 0x4B, 0xCB, 0x2B, 0xAB, 0x6B, 0xEB, 0x1B, 0x9B, 0x5B, 0xDB,
            0x3B, 0xBB, 0x7B, 0xFB,
        ];
        for (n, &id) in table.iter().enumerate() {
            assert_eq!(slot_id(n as u8), id, "slot {n}");
            assert_eq!(slot_number(id), Some(n as u8));
        }
        assert_eq!(slot_number(START), None);
        assert_eq!(
            (0..=255u8).filter(|&b| slot_number(b).is_some()).count(),
            32
        );
    }

    #[test]
    fn channels_round_trip_and_the_scale_is_betaflights() {
        let ch: [u16; CHANNELS] = std::array::from_fn(|i| (i as u16 * 131 + 7) & 0x7FF);
        let f = frame(ch, 0, 0);
        assert_eq!(f.len(), FRAME_LEN);
        assert_eq!(channels(f.as_slice().try_into().unwrap()), ch);
        assert_eq!(
            (micros(200), micros(1000), micros(1800)),
            (1005, 1505, 2005)
        );
        assert_eq!((micros(173), micros(1812)), (988, 2012));
        // Channel 1 in the low bits of byte 1: 0x3FF and 0x001 in channel 2.
        let mut ch = [0u16; CHANNELS];
        ch[0] = 0x3FF;
        ch[1] = 1;
        let f = frame(ch, 0, 0);
        assert_eq!(&f[1..4], &[0xFF, 0x0B, 0x00]);
    }

    #[test]
    fn frames_slots_and_resync() {
        let ch = [1000u16; CHANNELS];
        let mut s = frame(ch, 0, 0x14);
        encode_slot(&mut s, 8, 0x0F0F); // value bytes 0F: still a slot
        encode_slot(&mut s, 9, 0x1234);
        s.extend(frame(ch, 0, 0));
        s.extend([0x55, 0x03, 0x83]); // garbage after an SBUS frame (no slots)
        let mut cut = frame(ch, 0, 0);
        cut.truncate(10);
        s.extend(&cut);
        s.extend(frame(ch, FLAG_FAILSAFE, 0x04));
        s.extend(frame(ch, 0, 0x34)); // no slots answered
        let mut wrong = frame(ch, 0, 0);
        wrong[24] = 0x99;
        s.extend(&wrong);
        s.extend(frame(ch, 0, 0));
        s.extend(&frame(ch, 0, 0)[..5]);
        let want: Vec<(String, u64, usize)> = [
            ("frame", 0, 25),
            ("slot g1 i0", 25, 3),
            ("slot g1 i1", 28, 3),
            ("frame", 31, 25),
            ("Garbage", 56, 3),
            ("Cut", 59, 10),
            ("frame", 69, 25),
            ("frame", 94, 25),
            ("WrongEnd", 119, 25),
            ("frame", 144, 25),
            ("AtEnd", 169, 5),
        ]
        .iter()
        .map(|&(k, o, n)| (k.to_string(), o, n))
        .collect();
        let whole = events(&[&s]);
        assert_eq!(whole, want);
        let bytes: Vec<&[u8]> = s.chunks(1).collect();
        assert_eq!(events(&bytes), want);
    }

    #[test]
    fn a_slot_cut_by_a_frame_and_a_frame_after_a_dropped_byte() {
        let ch = [992u16; CHANNELS];
        let mut s = frame(ch, 0, 0x04);
        s.push(slot_id(0)); // the slot's value never came
        s.extend(frame(ch, 0, 0));
        // A frame with a byte dropped: the next frame's 0F arrives at its 25th place.
        let mut short = frame(ch, 0, 0);
        short.remove(5);
        s.extend(&short);
        s.extend(frame(ch, 0, 0));
        let got = events(&[&s]);
        let kinds: Vec<&str> = got.iter().map(|e| e.0.as_str()).collect();
        assert_eq!(
            kinds,
            ["frame", "SlotCut", "frame", "Cut", "frame"],
            "{got:?}"
        );
        assert_eq!(got[3].2, 24);
    }

    #[test]
    fn eight_slots_at_most_then_garbage() {
        let mut s = frame([1000; CHANNELS], 0, 0x24);
        for n in 16..25u8 {
            encode_slot(&mut s, n, u16::from(n));
        }
        let got = events(&[&s]);
        let kinds: Vec<&str> = got.iter().map(|e| e.0.as_str()).collect();
        assert_eq!(kinds[..9].len(), 9);
        assert_eq!(kinds[8], "slot g2 i7");
        assert_eq!(kinds[9], "Garbage");
    }

    #[test]
    fn garbage_runs_are_bounded_and_bytes_all_accounted() {
        let noise = crate::testing::noise(1000, 3);
        let mut re = Reassembler::new();
        let mut total = 0;
        let mut longest = 0;
        let mut take = |e: Event<'_>| {
            let n = match e {
                Event::Frame { .. } => FRAME_LEN,
                Event::Slot { .. } => SLOT_LEN,
                Event::Broken { bytes, .. } => bytes.len(),
            };
            total += n;
            longest = longest.max(n);
        };
        re.push(&noise, None, &mut take);
        re.finish(&mut take);
        assert_eq!(total, 1000);
        assert!(longest <= GARBAGE_ROW_MAX);
    }
}
