//! The F.Port decoder: the framing (given, or chosen by [`super::detect`]), its reassembler,
//! the table mapping and the statistics.

use super::detect::{self, HOLD_BYTES, HOLD_MICROS};
use super::frame::Event;
use super::map::Mapper;
use super::table::COLUMNS;
use super::v1::V1;
use super::v2::V2;
use super::{Framing, Options, Variant};
use crate::protocol::Decoder;
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// How the framing was chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// `--variant v1|v2|fbus`.
    Forced,
    /// The lock rule decided.
    Locked { v1: u64, v2: u64 },
    /// [`HOLD_BYTES`] bytes arrived without a decision: majority.
    HoldFull { v1: u64, v2: u64 },
    /// The input ended before a decision: majority.
    EndOfInput { v1: u64, v2: u64 },
    /// A live source stayed undecided for [`HOLD_MICROS`]: majority.
    Quiet { v1: u64, v2: u64 },
}

/// Reading both framings while undecided.
struct Undecided {
    v1: V1,
    v2: V2,
    v1_frames: u64,
    v2_frames: u64,
    held: Vec<u8>,
    /// `(index into held, time)`: the bytes from that index on arrived at that time.
    marks: Vec<(usize, Option<u64>)>,
    first_time: Option<u64>,
}

impl Undecided {
    fn new() -> Self {
        Undecided {
            v1: V1::new(),
            v2: V2::new(),
            v1_frames: 0,
            v2_frames: 0,
            held: Vec::new(),
            marks: Vec::new(),
            first_time: None,
        }
    }

    /// Holds one byte and reads it in both framings.
    fn byte(&mut self, b: u8, time: Option<u64>) {
        if self.marks.last().is_none_or(|&(_, t)| t != time) {
            self.marks.push((self.held.len(), time));
        }
        if self.held.is_empty() {
            self.first_time = time;
        }
        self.held.push(b);
        let (mut n1, mut n2) = (0, 0);
        let count = |framing, ev: Event<'_>, n: &mut u64| {
            if let Event::Frame(f) = ev
                && detect::known(framing, &f)
            {
                *n += 1;
            }
        };
        self.v1
            .push(&[b], time, &mut |ev| count(Framing::V1, ev, &mut n1));
        self.v2
            .push(&[b], time, &mut |ev| count(Framing::V2, ev, &mut n2));
        self.v1_frames += n1;
        self.v2_frames += n2;
    }

    fn finish(&mut self) {
        let (mut n1, mut n2) = (0, 0);
        let count = |framing, ev: Event<'_>, n: &mut u64| {
            if let Event::Frame(f) = ev
                && detect::known(framing, &f)
            {
                *n += 1;
            }
        };
        self.v1.finish(&mut |ev| count(Framing::V1, ev, &mut n1));
        self.v2.finish(&mut |ev| count(Framing::V2, ev, &mut n2));
        self.v1_frames += n1;
        self.v2_frames += n2;
    }
}

enum State {
    V1(V1),
    V2(Box<V2>),
    Undecided(Box<Undecided>),
}

/// The F.Port decoder.
pub struct FportDecoder {
    state: State,
    map: Mapper,
    variant: Variant,
    baud: u32,
    chosen: Option<(Framing, Reason)>,
}

impl FportDecoder {
    pub fn new(opts: Options) -> Self {
        let baud = opts.baud();
        let (state, chosen) = match opts.variant {
            Variant::Auto => (State::Undecided(Box::new(Undecided::new())), None),
            Variant::V1 => (State::V1(V1::new()), Some((Framing::V1, Reason::Forced))),
            Variant::V2 | Variant::Fbus => (
                State::V2(Box::new(V2::new())),
                Some((Framing::V2, Reason::Forced)),
            ),
        };
        FportDecoder {
            state,
            map: Mapper::new(baud),
            variant: opts.variant,
            baud,
            chosen,
        }
    }

    /// The framing in use, and why (`None` while undecided).
    pub fn chosen(&self) -> Option<(Framing, Reason)> {
        self.chosen
    }

    /// The name of what is decoded: "F.Port v1", "F.Port 2", "FBUS", or "F.Port" while the
    /// framing is undecided.
    pub fn label(&self) -> &'static str {
        match (self.variant, self.chosen) {
            (Variant::Fbus, _) => "FBUS",
            (_, Some((Framing::V1, _))) => "F.Port v1",
            (_, Some((Framing::V2, _))) if self.baud >= super::FBUS_BAUD => "FBUS",
            (_, Some((Framing::V2, _))) => "F.Port 2",
            (_, None) => "F.Port",
        }
    }

    /// Chooses `framing` and replays the held bytes through it.
    fn decide(&mut self, framing: Framing, reason: Reason, out: &mut Latch<'_>) {
        let State::Undecided(u) = std::mem::replace(&mut self.state, State::V1(V1::new())) else {
            return;
        };
        self.chosen = Some((framing, reason));
        self.state = match framing {
            Framing::V1 => State::V1(V1::new()),
            Framing::V2 => State::V2(Box::new(V2::new())),
        };
        for (k, &(start, time)) in u.marks.iter().enumerate() {
            let end = u.marks.get(k + 1).map_or(u.held.len(), |m| m.0);
            self.feed(&u.held[start..end], time, out);
        }
    }

    /// Bytes into the chosen framing.
    fn feed(&mut self, data: &[u8], time: Option<u64>, out: &mut Latch<'_>) {
        let map = &mut self.map;
        match &mut self.state {
            State::V1(r) => r.push(data, time, &mut |e| map.event(Framing::V1, e, out)),
            State::V2(r) => r.push(data, time, &mut |e| map.event(Framing::V2, e, out)),
            State::Undecided(_) => {}
        }
    }
}

impl Decoder for FportDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        if let State::Undecided(u) = &mut self.state {
            let mut decision = None;
            let mut used = data.len();
            for (i, &b) in data.iter().enumerate() {
                u.byte(b, time);
                let (v1, v2) = (u.v1_frames, u.v2_frames);
                if let Some(f) = detect::lock(v1, v2) {
                    decision = Some((f, Reason::Locked { v1, v2 }));
                } else if u.held.len() >= HOLD_BYTES {
                    decision = Some((detect::majority(v1, v2), Reason::HoldFull { v1, v2 }));
                }
                if decision.is_some() {
                    used = i + 1;
                    break;
                }
            }
            match decision {
                Some((framing, reason)) => self.decide(framing, reason, &mut out),
                None => return out.result(),
            }
            self.feed(&data[used..], time, &mut out);
        } else {
            self.feed(data, time, &mut out);
        }
        out.result()
    }

    fn idle(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        if let State::Undecided(u) = &self.state
            && u.first_time
                .is_some_and(|t| now.saturating_sub(t) >= HOLD_MICROS)
        {
            let (v1, v2) = (u.v1_frames, u.v2_frames);
            self.decide(detect::majority(v1, v2), Reason::Quiet { v1, v2 }, &mut out);
        }
        let map = &mut self.map;
        if let State::V1(r) = &mut self.state {
            r.idle(&mut |e| map.event(Framing::V1, e, &mut out));
        }
        out.result()
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        if let State::Undecided(u) = &mut self.state {
            u.finish();
            let (v1, v2) = (u.v1_frames, u.v2_frames);
            self.decide(
                detect::majority(v1, v2),
                Reason::EndOfInput { v1, v2 },
                &mut out,
            );
        }
        let map = &mut self.map;
        match &mut self.state {
            State::V1(r) => r.finish(&mut |e| map.event(Framing::V1, e, &mut out)),
            State::V2(r) => r.finish(&mut |e| map.event(Framing::V2, e, &mut out)),
            State::Undecided(_) => {}
        }
        out.result()
    }

    fn valid_frames(&self) -> u64 {
        self.map.stats.valid_frames
    }

    fn stats(&self) -> Report {
        let mut head = format!("variant: {}", self.label());
        match self.chosen {
            Some((_, Reason::Forced)) => head.push_str(" (--variant)"),
            Some((_, r)) => {
                let (v1, v2, how) = match r {
                    Reason::Locked { v1, v2 } => (v1, v2, "chosen by framing"),
                    Reason::HoldFull { v1, v2 } => (v1, v2, "undecided after 16 KiB, majority"),
                    Reason::EndOfInput { v1, v2 } => (v1, v2, "undecided at the end, majority"),
                    Reason::Quiet { v1, v2 } => (v1, v2, "undecided after 1 s, majority"),
                    Reason::Forced => (0, 0, ""),
                };
                head.push_str(&format!(
                    " ({how}: {v1} F.Port v1 frames, {v2} F.Port 2 frames)"
                ));
            }
            None => head.push_str(" (undecided)"),
        }
        self.map.stats.report(head)
    }

    fn problems(&self) -> Problems {
        self.map.stats.problems(self.label())
    }

    fn no_frames_hint(&self) -> &'static str {
        "wrong baud rate (F.Port and F.Port 2 run at 115200, FBUS at 460800) or the signal is \
         not inverted (F.Port is inverted on the wire: an inverting adapter or an FTDI with \
         inverted RX, see docs/fport.md)"
    }
}
