//! FlySky iBUS wire format, the pure framer and the pairing of polls with answers.
//!
//! Every frame is `[len][cmd][payload …][checksum lo][checksum hi]`: `len` counts the whole
//! frame, the checksum is `0xFFFF` minus the sum of the bytes before it. Two kinds of traffic use
//! it (`docs/ibus.md`):
//!
//! * the servo line: RC frames `20 40` + 14 channels LE16 (µs) + checksum, every ~7.7 ms;
//! * the sensor bus: the receiver polls `04 [cmd<<4 | addr] chk` (cmd 8 discover, 9 type
//!   query, A measurement) and the sensor at `addr` answers: the same 4 bytes (discover),
//!   `06 9a [type][size] chk` (type), `06 Aa [LE16] chk` or `08 Aa [LE32] chk` (measurement).

use crate::row::GARBAGE_ROW_MAX;

/// Shortest frame: length, command, checksum.
pub const MIN_LEN: usize = 4;
/// Longest frame (an RC frame).
pub const MAX_LEN: usize = 32;
/// Length and command byte of an RC frame.
pub const RC_LEN: u8 = 0x20;
pub const RC_CMD: u8 = 0x40;
/// Channels in the 14 16-bit slots of an RC frame; four more in their high nibbles.
pub const RC_SLOTS: usize = 14;
pub const RC_CHANNELS_MAX: usize = 18;
/// Sensor bus commands (the high nibble of the command byte).
pub const CMD_DISCOVER: u8 = 0x8;
pub const CMD_TYPE: u8 = 0x9;
pub const CMD_MEASURE: u8 = 0xA;

/// Default line: 115200 baud 8N1, not inverted.
pub const BAUD: u32 = 115_200;
/// Bits of one character on the wire (start, 8 data, stop).
pub const BITS_PER_CHAR: u32 = 10;

/// The checksum of the bytes before it.
pub fn checksum(bytes: &[u8]) -> u16 {
    let sum = bytes
        .iter()
        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)));
    0xFFFF - sum
}

/// The checksum a frame carries (its last two bytes, little-endian).
pub fn carried(frame: &[u8]) -> u16 {
    let n = frame.len();
    u16::from_le_bytes([frame[n - 2], frame[n - 1]])
}

/// Whether a whole frame's checksum is right.
pub fn check_ok(frame: &[u8]) -> bool {
    frame.len() >= MIN_LEN && checksum(&frame[..frame.len() - 2]) == carried(frame)
}

/// Appends `len cmd payload checksum`.
pub fn encode(out: &mut Vec<u8>, cmd: u8, payload: &[u8]) {
    let start = out.len();
    out.push((payload.len() + MIN_LEN) as u8);
    out.push(cmd);
    out.extend_from_slice(payload);
    let sum = checksum(&out[start..]);
    out.extend_from_slice(&sum.to_le_bytes());
}

/// Appends a poll `04 [cmd<<4 | addr] chk`.
pub fn encode_poll(out: &mut Vec<u8>, cmd: u8, addr: u8) {
    encode(out, cmd << 4 | (addr & 0x0F), &[]);
}

/// Appends an RC frame of 14 channel slots (values in µs; channels 15-18, when given, in the
/// high nibbles as newer receivers send them).
pub fn encode_rc(out: &mut Vec<u8>, channels: &[u16]) {
    let mut slots = [0u16; RC_SLOTS];
    for (s, &c) in slots.iter_mut().zip(channels) {
        *s = c & 0x0FFF;
    }
    for (k, &c) in channels.iter().skip(RC_SLOTS).take(4).enumerate() {
        for j in 0..3 {
            let nibble = (c >> (4 * j)) & 0xF;
            slots[3 * k + j] |= nibble << 12;
        }
    }
    let mut payload = [0u8; 2 * RC_SLOTS];
    for (i, s) in slots.iter().enumerate() {
        payload[2 * i..2 * i + 2].copy_from_slice(&s.to_le_bytes());
    }
    encode(out, RC_CMD, &payload);
}

/// The channels of an RC frame as Betaflight reads them (`rx/ibus.c`): 14 from the low 12 bits
/// of each slot, and channels 15-18 from the high nibbles of slots 1-3, 4-6, 7-9 and 10-12.
/// Returns the 18 values and whether any high nibble is set (an 18-channel receiver).
#[inline]
pub fn rc_channels(frame: &[u8]) -> ([u16; RC_CHANNELS_MAX], bool) {
    let mut ch = [0u16; RC_CHANNELS_MAX];
    let slot = |i: usize| u16::from_le_bytes([frame[2 + 2 * i], frame[3 + 2 * i]]);
    let mut high = false;
    for (i, c) in ch.iter_mut().take(RC_SLOTS).enumerate() {
        let s = slot(i);
        *c = s & 0x0FFF;
        high |= s >> 12 != 0;
    }
    for k in 0..4 {
        ch[RC_SLOTS + k] =
            (slot(3 * k) >> 12) | (slot(3 * k + 1) >> 12) << 4 | (slot(3 * k + 2) >> 12) << 8;
    }
    (ch, high)
}

/// Whether `len cmd` can start a frame busnoop knows: an RC frame (`20 40` from receivers,
/// `20 00` in Betaflight's unit test, which reads any second byte), a poll or an answer.
pub fn known_header(len: u8, cmd: u8) -> bool {
    match len {
        RC_LEN => matches!(cmd, RC_CMD | 0x00),
        4 => cmd >> 4 >= CMD_DISCOVER,
        6 | 8 => matches!(cmd >> 4, CMD_TYPE | CMD_MEASURE),
        _ => false,
    }
}

/// Whether a frame is a poll: 4 bytes whose command is a sensor bus command (8 and above).
pub fn is_poll(frame: &[u8]) -> bool {
    frame.len() == MIN_LEN && frame[1] >> 4 >= CMD_DISCOVER
}

/// Whether `answer` answers `poll`: the same four bytes for a discovery, six bytes with the
/// same command byte for a type query, six or more for a measurement or another command.
pub fn answers(poll: &[u8; MIN_LEN], answer: &[u8]) -> bool {
    match poll[1] >> 4 {
        CMD_DISCOVER => answer == poll,
        CMD_TYPE => answer.len() == 6 && answer[1] == poll[1],
        _ => answer.len() > MIN_LEN && answer[1] == poll[1],
    }
}

/// Why bytes are not a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Broken {
    /// A frame of a known kind whose checksum is wrong.
    BadCheck,
    /// A known header, and a valid frame starts before its end: cut short.
    Cut,
    /// A known header cut by the end of the input (or a gap).
    AtEnd,
    /// Bytes that start no frame.
    Garbage,
}

/// What the framer and the pairing found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event<'a> {
    /// A poll and its answer (`None`: the next thing on the wire was no answer to it).
    Exchange {
        poll: Located<'a>,
        answer: Option<Located<'a>>,
    },
    /// A frame that is no poll and answers none (an RC frame, an answer whose poll was not
    /// seen, an unknown frame).
    Frame(Located<'a>),
    Broken {
        at: Located<'a>,
        why: Broken,
    },
}

/// Bytes with their place in the stream and the arrival time of the first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Located<'a> {
    pub offset: u64,
    pub time: Option<u64>,
    pub bytes: &'a [u8],
}

/// The buffer never holds more than this: a frame's worth of look-ahead after a broken frame
/// (up to 2 × 32 bytes) and a garbage run.
const CAP: usize = 192;
const _: () = assert!(CAP >= 2 * MAX_LEN + GARBAGE_ROW_MAX);

/// A poll waiting for what follows it.
#[derive(Clone, Copy, Debug)]
struct Pending {
    bytes: [u8; MIN_LEN],
    offset: u64,
    time: Option<u64>,
}

/// The pure reassembler: bytes and times in, [`Event`]s out, identical however the input is
/// split (each byte keeps the time of the push it came with).
#[derive(Debug, Default)]
pub struct Reassembler {
    buf: Vec<u8>,
    /// The arrival times of the bytes in `buf`, as runs: `(stream offset of the run's first
    /// byte, time)`, in order; the first run starts at or before `offset`.
    times: Vec<(u64, Option<u64>)>,
    offset: u64,
    pending: Option<Pending>,
}

/// Whether a valid frame starts at `b[0]`: `Some(len)`, `None` when more bytes could tell, or
/// `Some(0)` when it cannot.
fn frame_at(b: &[u8]) -> Option<usize> {
    let len = usize::from(b[0]);
    if !(MIN_LEN..=MAX_LEN).contains(&len) {
        return Some(0);
    }
    if b.len() < len {
        return None;
    }
    Some(if check_ok(&b[..len]) { len } else { 0 })
}

/// What the framer decided at a position.
#[derive(Clone, Copy, Debug)]
enum Step {
    Frame,
    Broken(Broken),
}

impl Reassembler {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds bytes that arrived at `time`.
    pub fn push(&mut self, mut data: &[u8], time: Option<u64>, emit: &mut dyn FnMut(Event<'_>)) {
        while !data.is_empty() {
            let n = (CAP - self.buf.len()).min(data.len());
            self.buf.extend_from_slice(&data[..n]);
            let at = self.offset + self.buf.len() as u64 - n as u64;
            if self.times.last().is_none_or(|&(_, t)| t != time) {
                self.times.push((at, time));
            }
            data = &data[n..];
            self.run(false, emit);
        }
    }

    /// End of input (or a gap): a cut frame, trailing garbage and a poll still waiting come out.
    pub fn finish(&mut self, emit: &mut dyn FnMut(Event<'_>)) {
        self.run(true, emit);
        self.flush(emit);
    }

    /// A waiting poll comes out unanswered.
    fn flush(&mut self, emit: &mut dyn FnMut(Event<'_>)) {
        if let Some(p) = self.pending.take() {
            emit(Event::Exchange {
                poll: Located {
                    offset: p.offset,
                    time: p.time,
                    bytes: &p.bytes,
                },
                answer: None,
            });
        }
    }

    fn run(&mut self, end: bool, emit: &mut dyn FnMut(Event<'_>)) {
        let mut used = 0;
        while used < self.buf.len() {
            let Some((n, step)) = self.step(used, end) else {
                break;
            };
            let at = Located {
                offset: self.offset + used as u64,
                time: self.time_at(self.offset + used as u64),
                bytes: &self.buf[used..used + n],
            };
            match step {
                Step::Frame => {
                    if let Some(p) = self.pending.take() {
                        let poll = Located {
                            offset: p.offset,
                            time: p.time,
                            bytes: &p.bytes,
                        };
                        if answers(&p.bytes, at.bytes) {
                            emit(Event::Exchange {
                                poll,
                                answer: Some(at),
                            });
                            used += n;
                            continue;
                        }
                        emit(Event::Exchange { poll, answer: None });
                    }
                    if is_poll(at.bytes) {
                        let mut bytes = [0u8; MIN_LEN];
                        bytes.copy_from_slice(at.bytes);
                        self.pending = Some(Pending {
                            bytes,
                            offset: at.offset,
                            time: at.time,
                        });
                    } else {
                        emit(Event::Frame(at));
                    }
                }
                Step::Broken(why) => {
                    if let Some(p) = self.pending.take() {
                        emit(Event::Exchange {
                            poll: Located {
                                offset: p.offset,
                                time: p.time,
                                bytes: &p.bytes,
                            },
                            answer: None,
                        });
                    }
                    emit(Event::Broken { at, why });
                }
            }
            used += n;
        }
        self.buf.drain(..used);
        // The runs wholly before the new start go (the run holding it stays).
        let start = self.offset + used as u64;
        let keep = self.times.partition_point(|&(at, _)| at <= start).max(1) - 1;
        self.times.drain(..keep);
        self.offset += used as u64;
    }

    /// The arrival time of the byte at stream offset `at` (in the buffer).
    #[inline]
    fn time_at(&self, at: u64) -> Option<u64> {
        match self.times.as_slice() {
            [(_, t)] => *t,
            runs => runs[runs.partition_point(|&(a, _)| a <= at).max(1) - 1].1,
        }
    }

    /// What starts at `at` and how many bytes it takes; `None` when more bytes are needed.
    fn step(&self, at: usize, end: bool) -> Option<(usize, Step)> {
        let b = &self.buf[at..];
        match frame_at(b) {
            Some(0) => {}
            Some(len) => return Some((len, Step::Frame)),
            None if !end => return None,
            None => {
                // Fewer bytes than the length says, and the input ended.
                if b.len() >= 2 && known_header(b[0], b[1]) {
                    return Some(match first_frame(b, 1, b.len(), true)? {
                        Some(q) => (q, Step::Broken(Broken::Cut)),
                        None => (b.len(), Step::Broken(Broken::AtEnd)),
                    });
                }
            }
        }
        let len = usize::from(b[0]);
        if b.len() >= len && len >= MIN_LEN && known_header(b[0], b[1]) {
            // A known header with a wrong checksum: cut short if a frame starts inside it.
            return Some(match first_frame(b, 1, len, end)? {
                Some(q) => (q, Step::Broken(Broken::Cut)),
                None => (len, Step::Broken(Broken::BadCheck)),
            });
        }
        // Garbage up to the next frame or known header, at most GARBAGE_ROW_MAX bytes.
        let limit = GARBAGE_ROW_MAX.min(b.len());
        for i in 1..limit {
            match frame_at(&b[i..]) {
                Some(0) => {}
                Some(_) => return Some((i, Step::Broken(Broken::Garbage))),
                None if !end => return None,
                None => {}
            }
            // (At the buffer's last byte, a header length made `frame_at` wait above.)
            if i + 1 < b.len() && known_header(b[i], b[i + 1]) {
                return Some((i, Step::Broken(Broken::Garbage)));
            }
        }
        if limit == GARBAGE_ROW_MAX || end {
            Some((limit, Step::Broken(Broken::Garbage)))
        } else {
            None
        }
    }
}

/// The first position in `from..to` where a valid frame starts: `Some(Some(q))`, `Some(None)`
/// when there is none, `None` when more bytes are needed to tell (never at the end).
fn first_frame(b: &[u8], from: usize, to: usize, end: bool) -> Option<Option<usize>> {
    for q in from..to {
        match frame_at(&b[q..]) {
            Some(0) => {}
            Some(_) => return Some(Some(q)),
            None if !end => return None,
            None => {}
        }
    }
    Some(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmt::parse_hex;

    fn h(s: &str) -> Vec<u8> {
        parse_hex(s).unwrap()
    }

    /// Events as short strings.
    fn events(chunks: &[&[u8]]) -> Vec<String> {
        let mut re = Reassembler::new();
        let mut out = Vec::new();
        let mut take = |e: Event<'_>| {
            out.push(match e {
                Event::Exchange { poll, answer } => format!(
                    "{} -> {}",
                    crate::fmt::hex(poll.bytes),
                    answer.map_or("-".into(), |a| crate::fmt::hex(a.bytes))
                ),
                Event::Frame(f) => format!("frame {}", crate::fmt::hex(f.bytes)),
                Event::Broken { at, why } => format!("{why:?} {}", crate::fmt::hex(at.bytes)),
            })
        };
        for c in chunks {
            re.push(c, None, &mut take);
        }
        re.finish(&mut take);
        out
    }

    #[test]
    fn betaflight_unit_test_frames_check() {
        // telemetry_ibus_unittest.cc: polls and answers; rx_ibus_unittest.cc-style RC frame.
        for s in [
            "04 81 7A FF",
            "04 91 6A FF",
            "06 91 03 02 63 FF",
            "04 A1 5A FF",
            "06 A1 64 00 F4 FE",
            "06 A2 84 03 D0 FE",
            "06 A3 00 00 56 FF",
            "04 83 78 FF",
            "04 96 65 FF",
        ] {
            assert!(check_ok(&h(s)), "{s}");
        }
        assert!(!check_ok(&h("04 81 00 00")));
        let mut p = Vec::new();
        encode_poll(&mut p, CMD_MEASURE, 1);
        assert_eq!(p, h("04 A1 5A FF"));
    }

    #[test]
    fn rc_channels_15_to_18_from_the_high_nibbles() {
        let ch: Vec<u16> = (0..18).map(|i| 1000 + 50 * i).collect();
        let mut f = Vec::new();
        encode_rc(&mut f, &ch);
        assert_eq!(f.len(), 32);
        assert_eq!(&f[..2], &[0x20, 0x40]);
        assert!(check_ok(&f));
        let (got, high) = rc_channels(&f);
        assert_eq!(got.to_vec(), ch);
        assert!(high);
        let mut f = Vec::new();
        encode_rc(&mut f, &ch[..14]);
        let (got, high) = rc_channels(&f);
        assert_eq!(&got[..14], &ch[..14]);
        assert_eq!(&got[14..], &[0, 0, 0, 0]);
        assert!(!high);
    }

    #[test]
    fn polls_pair_with_their_answers() {
        let s = h("04 81 7A FF 04 81 7A FF \
                   04 91 6A FF 06 91 03 02 63 FF \
                   04 83 78 FF \
                   04 A1 5A FF 06 A1 64 00 F4 FE \
                   04 A2 59 FF 04 A3 58 FF 06 A3 00 00 56 FF \
                   06 A2 84 03 D0 FE");
        let want = [
            "04 81 7A FF -> 04 81 7A FF",
            "04 91 6A FF -> 06 91 03 02 63 FF",
            "04 83 78 FF -> -",
            "04 A1 5A FF -> 06 A1 64 00 F4 FE",
            "04 A2 59 FF -> -",
            "04 A3 58 FF -> 06 A3 00 00 56 FF",
            "frame 06 A2 84 03 D0 FE",
        ];
        assert_eq!(events(&[&s]), want);
        let bytes: Vec<&[u8]> = s.chunks(1).collect();
        assert_eq!(events(&bytes), want);
    }

    #[test]
    fn the_power_up_command_f_is_a_poll_nobody_answers() {
        // The FS-iA6B's first bytes in the iBus2PPM capture: `04 F0 0B FF` ten times.
        let s = h("04 F0 0B FF 04 F0 0B FF 04 81 7A FF 04 81 7A FF");
        assert_eq!(
            events(&[&s]),
            [
                "04 F0 0B FF -> -",
                "04 F0 0B FF -> -",
                "04 81 7A FF -> 04 81 7A FF"
            ]
        );
    }

    #[test]
    fn bad_checksums_cut_frames_and_garbage() {
        let s = h("55 AA 04 A1 5A FF 06 A1 64 00 F4 00 \
                   04 A2 59 FF 06 A2 84 04 A3 58 FF 06 A3 00 00 56 FF 04 A1");
        assert_eq!(
            events(&[&s]),
            [
                "Garbage 55 AA",
                "04 A1 5A FF -> -",
                "BadCheck 06 A1 64 00 F4 00",
                "04 A2 59 FF -> -",
                "Cut 06 A2 84",
                "04 A3 58 FF -> 06 A3 00 00 56 FF",
                "AtEnd 04 A1",
            ]
        );
    }

    #[test]
    fn noise_is_bounded_rows_and_every_byte_is_in_one() {
        let noise = crate::testing::noise(3000, 11);
        let mut re = Reassembler::new();
        let mut total = 0;
        let mut longest = 0;
        let mut take = |e: Event<'_>| {
            let n = match e {
                Event::Exchange { poll, answer } => {
                    poll.bytes.len() + answer.map_or(0, |a| a.bytes.len())
                }
                Event::Frame(f) => f.bytes.len(),
                Event::Broken { at, .. } => at.bytes.len(),
            };
            total += n;
            longest = longest.max(n);
        };
        re.push(&noise, None, &mut take);
        re.finish(&mut take);
        assert_eq!(total, noise.len());
        assert!(longest <= GARBAGE_ROW_MAX);
    }
}
