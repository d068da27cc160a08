//! The software UART: a channel's level changes in, characters with their exact start times
//! out. Pure (no I/O, no clock): the same edges give the same characters however they are
//! handed in.
//!
//! * **Sampling.** A character starts at an edge from the idle level to the active level
//!   (`Hunt`). Every bit is read once, in its middle: bit `k` (0 = start bit) at
//!   `start + (k + ½) · bit time`, computed exactly in ticks (no drift over a character). A start
//!   bit that is back at the idle level in its middle is a glitch ("false start") and is
//!   ignored, as a hardware UART does.
//! * **Errors.** Only the first stop bit is checked (as hardware does; a second one only adds
//!   idle time): active there = framing error. A parity bit that does not fit = parity error.
//!   The character is delivered either way, flagged.
//! * **Breaks.** A character that is all active (start, data, parity and stop bits) is a break:
//!   the line is held active. It is delivered as one 0x00 character (as a Linux tty reads a
//!   break) with the break's duration, when the line goes back to idle (or at the end).
//! * **Resynchronisation.** After a character the receiver hunts for the next idle-to-active
//!   edge from the middle of the stop bit on; after a framing error with the line held active
//!   that is the first edge after it goes back to idle.
//!
//! Time is counted in the trace's ticks ([`TimeBase`]: a sample of a sigrok session, a VCD time
//! unit, a picosecond of a Saleae export).

use crate::protocol::{Line, Parity};

/// The length of a trace's tick: `num / den` seconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimeBase {
    pub num: u64,
    pub den: u64,
}

impl TimeBase {
    /// Ticks of `1 / rate` seconds (a sample rate in Hz).
    pub const fn rate(hz: u64) -> Self {
        TimeBase { num: 1, den: hz }
    }

    /// Picoseconds.
    pub const PICOS: TimeBase = TimeBase::rate(1_000_000_000_000);

    /// µs since tick 0 (rounded down; saturates).
    pub fn micros(&self, tick: u64) -> u64 {
        let us = u128::from(tick) * u128::from(self.num) * 1_000_000 / u128::from(self.den.max(1));
        u64::try_from(us).unwrap_or(u64::MAX)
    }

    /// Ticks per second.
    pub fn per_second(&self) -> f64 {
        self.den as f64 / self.num.max(1) as f64
    }

    /// Ticks in `k / 2` bit times at `baud` (rounded down).
    fn half_bits(&self, k: u64, baud: u32) -> u64 {
        let t = u128::from(k) * u128::from(self.den)
            / (2 * u128::from(baud.max(1)) * u128::from(self.num.max(1)));
        u64::try_from(t).unwrap_or(u64::MAX)
    }
}

/// What the receiver read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// A character; `tick` is the start of its start bit.
    Char {
        tick: u64,
        value: u8,
        /// The stop bit was active.
        framing: bool,
        /// The parity bit did not fit.
        parity: bool,
    },
    /// The line was held active from `tick` to `end` (read as a 0x00 character).
    Break { tick: u64, end: u64 },
}

impl Event {
    #[cfg(test)]
    pub fn tick(&self) -> u64 {
        match *self {
            Event::Char { tick, .. } | Event::Break { tick, .. } => tick,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Waiting for the level to go from idle to active.
    Hunt,
    /// Inside a character that started at `start`; `k` is the next bit to read.
    Char { start: u64, k: usize, bits: u16 },
    /// A break that started at `start`: waiting for the idle level.
    Break { start: u64 },
}

/// The receiver of one channel.
#[derive(Clone, Debug)]
pub struct Uart {
    /// Offsets of the bit middles from the start edge, in ticks: start bit, data bits, parity
    /// bit (if any), first stop bit.
    middles: Vec<u64>,
    data_bits: usize,
    parity: Parity,
    /// The physical level of the idle line (true: high, the normal UART; false: inverted).
    idle_high: bool,
    /// The current logical level (true: idle, "mark"); `None` before the first edge.
    level: Option<bool>,
    state: State,
    /// Start bits that were back at the idle level in their middle (glitches).
    pub false_starts: u64,
}

impl Uart {
    /// A receiver for `line` at `baud` (the line's own speed is not used), on a line whose idle
    /// level is `idle_high`.
    pub fn new(line: &Line, baud: u32, base: TimeBase, idle_high: bool) -> Self {
        let data_bits = usize::from(line.data_bits.clamp(5, 8));
        let bits = 1 + data_bits + usize::from(line.parity != Parity::None) + 1;
        let middles = (0..bits as u64)
            .map(|k| base.half_bits(2 * k + 1, baud))
            .collect();
        Uart {
            middles,
            data_bits,
            parity: line.parity,
            idle_high,
            level: None,
            state: State::Hunt,
            false_starts: 0,
        }
    }

    /// The channel is at physical level `high` from `tick` on (its first level, or a change).
    /// Characters whose last bit middle lies before `tick` come out first.
    pub fn edge(&mut self, tick: u64, high: bool, emit: &mut impl FnMut(Event)) {
        let mark = high == self.idle_high;
        let Some(level) = self.level else {
            self.level = Some(mark);
            return;
        };
        self.run(tick, level, emit);
        if mark == level {
            return;
        }
        self.level = Some(mark);
        match self.state {
            State::Hunt if !mark => {
                self.state = State::Char {
                    start: tick,
                    k: 0,
                    bits: 0,
                }
            }
            State::Break { start } if mark => {
                emit(Event::Break {
                    tick: start,
                    end: tick,
                });
                self.state = State::Hunt;
            }
            _ => {}
        }
    }

    /// Nothing changed before `now`: reads the bit middles before it.
    pub fn advance(&mut self, now: u64, emit: &mut impl FnMut(Event)) {
        if let Some(level) = self.level {
            self.run(now, level, emit);
        }
    }

    /// The trace ends at `end`: a break still held comes out; a character cut short before
    /// its stop bit is dropped (returns true then).
    pub fn finish(&mut self, end: u64, emit: &mut impl FnMut(Event)) -> bool {
        self.advance(end, emit);
        let cut = match self.state {
            State::Break { start } => {
                emit(Event::Break { tick: start, end });
                false
            }
            State::Char { .. } => true,
            State::Hunt => false,
        };
        self.state = State::Hunt;
        cut
    }

    /// Reads the bit middles before `until`, where the line is at logical `level`.
    fn run(&mut self, until: u64, level: bool, emit: &mut impl FnMut(Event)) {
        while let State::Char { start, k, bits } = self.state {
            let at = start.saturating_add(self.middles[k]);
            if at >= until {
                return;
            }
            if k == 0 && level {
                // Back at idle in the middle of the start bit: a glitch.
                self.false_starts += 1;
                self.state = State::Hunt;
                return;
            }
            let bits = bits | (u16::from(level) << k);
            if k + 1 < self.middles.len() {
                self.state = State::Char {
                    start,
                    k: k + 1,
                    bits,
                };
                continue;
            }
            // The first stop bit: the character is complete.
            let data = (bits >> 1) & ((1 << self.data_bits) - 1);
            let ones = data.count_ones() + u32::from(bits >> (1 + self.data_bits) & 1 == 1);
            let parity = match self.parity {
                Parity::None => false,
                Parity::Even => !ones.is_multiple_of(2),
                Parity::Odd => ones.is_multiple_of(2),
            };
            let stop = level;
            if bits == 0 && !stop {
                // Every bit active: the line is held, a break.
                self.state = State::Break { start };
                return;
            }
            emit(Event::Char {
                tick: start,
                value: data as u8,
                framing: !stop,
                parity,
            });
            self.state = State::Hunt;
        }
    }
}

/// Baud rates a line is usually set to; a measured rate this close (2.5 %) to one is taken as
/// that one.
pub const USUAL_RATES: &[u32] = &[
    110, 300, 600, 1200, 2400, 4800, 9600, 14_400, 19_200, 28_800, 38_400, 57_600, 62_500, 76_800,
    100_000, 115_200, 125_000, 128_000, 153_600, 200_000, 230_400, 250_000, 256_000, 400_000,
    416_666, 420_000, 460_800, 500_000, 921_600, 1_000_000, 1_500_000, 2_000_000, 3_000_000,
];

/// How far (relative) a measured rate may lie from a usual one to be snapped to it.
const SNAP: f64 = 0.025;

/// The usual rate within 2.5 % of `baud`, if any.
pub fn snap(baud: f64) -> Option<u32> {
    USUAL_RATES
        .iter()
        .copied()
        .map(|r| (r, (baud / f64::from(r) - 1.0).abs()))
        .filter(|&(_, d)| d <= SNAP)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(r, _)| r)
}

/// A baud rate measured from a channel's pulses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// The rate the pulse widths give.
    pub baud: f64,
    /// The pulses it was measured from.
    pub pulses: usize,
}

/// Fewest pulses to measure a rate from.
pub const MIN_PULSES: usize = 16;

/// The bit rate of a channel from the widths of its pulses (`edges`: ticks of consecutive level
/// changes). The bit time is the shortest width that several pulses share (a lone shorter
/// pulse is a glitch), refined over every pulse up to 12 bits long by its whole number of bits.
pub fn measure(edges: &[u64], base: TimeBase) -> Option<Measured> {
    let mut widths: Vec<u64> = edges
        .windows(2)
        .map(|w| w[1].saturating_sub(w[0]))
        .filter(|&w| w > 0)
        .collect();
    if widths.len() < MIN_PULSES {
        return None;
    }
    widths.sort_unstable();
    // Enough pulses to count as a bit time rather than noise: 2 % of them, at least 3.
    let need = (widths.len() / 50).max(3);
    let mut bit = None;
    for (i, &w) in widths.iter().enumerate() {
        // Widths within 30 % above this one (the list is sorted).
        let hi = w.saturating_add(w / 10 * 3);
        let n = widths[i..].partition_point(|&x| x <= hi);
        if n >= need {
            // The cluster's median.
            bit = Some(widths[i + n / 2] as f64);
            break;
        }
    }
    let mut bit = bit?;
    // Refine: every pulse of 1..=12 bits counts with its whole number of bits, twice over.
    for _ in 0..2 {
        let (mut sum, mut bits, mut n) = (0.0, 0.0, 0usize);
        for &w in &widths {
            let m = (w as f64 / bit).round();
            if (1.0..=12.0).contains(&m) && (w as f64 / bit - m).abs() < 0.3 {
                sum += w as f64;
                bits += m;
                n += 1;
            }
        }
        if n < MIN_PULSES / 2 || bits == 0.0 {
            return None;
        }
        bit = sum / bits;
    }
    Some(Measured {
        baud: base.per_second() / bit,
        pulses: widths.len(),
    })
}

/// How well a reading of a channel's first edges goes: characters, and line errors (framing
/// and parity errors, breaks, glitches).
fn trial(
    line: &Line,
    baud: u32,
    base: TimeBase,
    idle_high: bool,
    edges: &[(u64, bool)],
    end: u64,
) -> (u64, u64) {
    let mut u = Uart::new(line, baud, base, idle_high);
    let (mut chars, mut errors) = (0u64, 0u64);
    let mut count = |e: Event| {
        chars += 1;
        errors += u64::from(match e {
            Event::Char {
                framing, parity, ..
            } => framing || parity,
            Event::Break { .. } => true,
        });
    };
    for &(t, high) in edges {
        u.edge(t, high, &mut count);
    }
    u.finish(end, &mut count);
    (chars, errors + u.false_starts)
}

/// The physical idle level of a channel from its first edges (`(tick, level from then on)`,
/// up to `end`): the reading (normal or inverted) with the smaller share of line errors;
/// `None` when both read no character or do equally well.
///
/// The idle level alone (the level of the longest run, [`idle_level`]) is not enough: an
/// RS-485 bus without fail-safe bias rests low between frames while the driver is off, and
/// idles high only while a node drives it (sigrok-dumps' `wizmodbus.sr`, channel `BA+`).
pub fn polarity(
    line: &Line,
    baud: u32,
    base: TimeBase,
    edges: &[(u64, bool)],
    end: u64,
) -> Option<bool> {
    let rate = |(chars, errors): (u64, u64)| (chars > 0).then(|| errors as f64 / chars as f64);
    let normal = rate(trial(line, baud, base, true, edges, end));
    let inverted = rate(trial(line, baud, base, false, edges, end));
    match (normal, inverted) {
        (Some(n), Some(i)) if n < i => Some(true),
        (Some(n), Some(i)) if i < n => Some(false),
        (Some(_), None) => Some(true),
        (None, Some(_)) => Some(false),
        _ => None,
    }
}

/// The physical idle level of a channel: the level of its longest run (a UART line idles
/// between characters; a character has at most 10 bits of one level). `levels`: the level from
/// each tick of `edges` on; `end`: where the trace read so far ends. `None` without a level.
pub fn idle_level(edges: &[u64], levels: &[bool], end: u64) -> Option<bool> {
    let mut best: Option<(u64, bool)> = None;
    for (i, (&t, &level)) in edges.iter().zip(levels).enumerate() {
        let next = edges.get(i + 1).copied().unwrap_or(end.max(t));
        let run = next - t;
        if best.is_none_or(|(b, _)| run > b) {
            best = Some((run, level));
        }
    }
    best.map(|(_, level)| level)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edges of `bytes` sent back to back (with `gap` idle bits after each) at `bit` ticks
    /// per bit, on a normal line, starting at tick 100; 8 data bits, `parity`, 1 stop bit.
    fn wave(bytes: &[u8], bit: u64, gap: u64, parity: Parity) -> Vec<(u64, bool)> {
        let mut levels = vec![true; 100];
        for &b in bytes {
            let mut bits = vec![false];
            bits.extend((0..8).map(|i| b >> i & 1 == 1));
            let ones = b.count_ones();
            match parity {
                Parity::None => {}
                Parity::Even => bits.push(ones % 2 == 1),
                Parity::Odd => bits.push(ones.is_multiple_of(2)),
            }
            bits.push(true);
            bits.extend(std::iter::repeat_n(true, gap as usize));
            for v in bits {
                levels.extend(std::iter::repeat_n(v, bit as usize));
            }
        }
        levels.extend(std::iter::repeat_n(true, 20 * bit as usize));
        let mut edges = vec![(0, levels[0])];
        for (i, w) in levels.windows(2).enumerate() {
            if w[0] != w[1] {
                edges.push((i as u64 + 1, w[1]));
            }
        }
        edges.push((levels.len() as u64, !levels[levels.len() - 1]));
        edges
    }

    fn decode(edges: &[(u64, bool)], line: Line, baud: u32, base: TimeBase) -> Vec<Event> {
        let mut u = Uart::new(&line, baud, base, true);
        let mut out = Vec::new();
        let (last, rest) = edges.split_last().unwrap();
        for &(t, l) in rest {
            u.edge(t, l, &mut |e| out.push(e));
        }
        u.finish(last.0, &mut |e| out.push(e));
        out
    }

    fn chars(events: &[Event]) -> Vec<u8> {
        events
            .iter()
            .map(|e| match e {
                Event::Char { value, .. } => *value,
                Event::Break { .. } => 0,
            })
            .collect()
    }

    #[test]
    fn reads_characters_with_their_start_ticks() {
        let bytes = [0x7E, 0x00, 0xFF, 0x55, 0xA1];
        let edges = wave(&bytes, 10, 0, Parity::None);
        // 10 ticks per bit: 1 MHz ticks at 100 kbaud.
        let ev = decode(
            &edges,
            Line::n81(100_000),
            100_000,
            TimeBase::rate(1_000_000),
        );
        assert_eq!(chars(&ev), bytes);
        let starts: Vec<u64> = ev.iter().map(Event::tick).collect();
        assert_eq!(starts, [100, 200, 300, 400, 500]);
        assert!(ev.iter().all(|e| matches!(
            e,
            Event::Char {
                framing: false,
                parity: false,
                ..
            }
        )));
    }

    #[test]
    fn parity_errors_are_flagged() {
        let line = Line {
            parity: Parity::Even,
            ..Line::n81(100_000)
        };
        let good = wave(&[0x01, 0x03], 10, 1, Parity::Even);
        let ev = decode(&good, line, 100_000, TimeBase::rate(1_000_000));
        assert!(
            ev.iter()
                .all(|e| matches!(e, Event::Char { parity: false, .. }))
        );
        let bad = wave(&[0x01, 0x03], 10, 1, Parity::Odd);
        let ev = decode(&bad, line, 100_000, TimeBase::rate(1_000_000));
        assert_eq!(chars(&ev), [0x01, 0x03]);
        assert!(
            ev.iter()
                .all(|e| matches!(e, Event::Char { parity: true, .. }))
        );
    }

    #[test]
    fn a_held_line_is_a_break_and_a_short_glitch_no_character() {
        // Idle, a glitch of 3 ticks (less than half a bit), idle, a break of 30 bits, a byte.
        let mut e = vec![
            (0, true),
            (50, false),
            (53, true),
            (200, false),
            (500, true),
        ];
        let tail = wave(&[0x42], 10, 0, Parity::None);
        e.extend(tail.iter().skip(1).map(|&(t, l)| (t + 600, l)));
        let mut u = Uart::new(
            &Line::n81(100_000),
            100_000,
            TimeBase::rate(1_000_000),
            true,
        );
        let mut out = Vec::new();
        for &(t, l) in &e[..e.len() - 1] {
            u.edge(t, l, &mut |x| out.push(x));
        }
        u.finish(e[e.len() - 1].0, &mut |x| out.push(x));
        assert_eq!(u.false_starts, 1);
        assert_eq!(
            out,
            [
                Event::Break {
                    tick: 200,
                    end: 500
                },
                Event::Char {
                    tick: 700,
                    value: 0x42,
                    framing: false,
                    parity: false
                }
            ]
        );
    }

    #[test]
    fn an_active_stop_bit_is_a_framing_error_and_the_next_character_is_kept() {
        // 0x0F with its stop bit pulled low (the line goes idle only 2 bits later), then 0x10.
        let e = vec![
            (0, true),
            (100, false), // start
            (110, true),  // data 1111
            (150, false), // data 0000, stop bit held low
            (210, true),  // back to idle after the stop bit
            (300, false), // 0x10: start + 0000
            (350, true),  // 1
            (360, false), // 000
            (390, true),  // stop
            (1000, true),
        ];
        let ev = decode(&e, Line::n81(100_000), 100_000, TimeBase::rate(1_000_000));
        assert_eq!(
            ev,
            [
                Event::Char {
                    tick: 100,
                    value: 0x0F,
                    framing: true,
                    parity: false
                },
                Event::Char {
                    tick: 300,
                    value: 0x10,
                    framing: false,
                    parity: false
                }
            ]
        );
    }

    #[test]
    fn the_split_of_the_edges_does_not_matter() {
        let bytes: Vec<u8> = (0..=255).collect();
        let edges = wave(&bytes, 7, 2, Parity::None);
        let whole = decode(&edges, Line::n81(1), 1, TimeBase { num: 1, den: 7 });
        assert_eq!(chars(&whole), bytes);
        // The same with an advance() between every two edges.
        let mut u = Uart::new(&Line::n81(1), 1, TimeBase { num: 1, den: 7 }, true);
        let mut out = Vec::new();
        for w in edges.windows(2) {
            u.edge(w[0].0, w[0].1, &mut |x| out.push(x));
            u.advance((w[0].0 + w[1].0) / 2, &mut |x| out.push(x));
        }
        u.finish(edges.last().unwrap().0, &mut |x| out.push(x));
        assert_eq!(out, whole);
    }

    #[test]
    fn snaps_to_usual_rates() {
        assert_eq!(snap(9_650.0), Some(9600));
        assert_eq!(snap(115_000.0), Some(115_200));
        assert_eq!(snap(57_000.0), Some(57_600));
        assert_eq!(snap(70_000.0), None);
        assert_eq!(snap(419_000.0), Some(420_000));
    }

    #[test]
    fn measures_the_bit_time_despite_a_glitch() {
        let bytes: Vec<u8> = (0..64u8).map(|i| i.wrapping_mul(37)).collect();
        let mut edges: Vec<u64> = wave(&bytes, 104, 3, Parity::None)
            .iter()
            .map(|e| e.0)
            .collect();
        edges.insert(1, 20); // a 1-tick pulse
        edges.insert(1, 19);
        let m = measure(&edges[..edges.len() - 1], TimeBase::rate(1_000_000)).unwrap();
        assert!((m.baud - 1e6 / 104.0).abs() < 10.0, "{m:?}");
        assert_eq!(snap(m.baud), Some(9600));
    }

    #[test]
    fn the_idle_level_is_the_longest_run() {
        assert_eq!(
            idle_level(&[0, 10, 12], &[true, false, true], 50),
            Some(true)
        );
        assert_eq!(
            idle_level(&[0, 40, 42], &[false, true, false], 50),
            Some(false)
        );
        assert_eq!(idle_level(&[], &[], 50), None);
    }
}
