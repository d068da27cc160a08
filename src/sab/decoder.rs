//! The SAB decoder: framing detection, the reassembler of the chosen framing with the other one
//! read in the background (see [`super::detect`]), and the [`Decoder`] implementation.

use super::config::{COLUMNS, FramingChoice, Options};
use super::detect::{self, Held, Reason};
use super::frame::{self, Event, Framing};
use super::map::Mapper;
use super::stats::Stats;
use super::{hdlc, sync};
use crate::protocol::Decoder;
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// Bytes into a reassembler (lets the detection loops be monomorphised per framing pair).
trait Stepper: Clone {
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>));
    fn push_bytes(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>));
}

impl Stepper for sync::Reassembler {
    #[inline]
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.step(b, time, emit);
    }
    #[inline]
    fn push_bytes(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.push(data, time, emit);
    }
}

impl Stepper for hdlc::Reassembler {
    #[inline]
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.step(b, time, emit);
    }
    #[inline]
    fn push_bytes(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.push(data, time, emit);
    }
}

impl Stepper for Reasm {
    #[inline]
    fn step_byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.step(b, time, emit);
    }
    #[inline]
    fn push_bytes(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        self.push(data, time, emit);
    }
}

/// Bytes the background framing reads ahead of the chosen one at a time (see [`shadowed`]).
const SHADOW_BLOCK: usize = 4096;

/// Feeds `data` to the active reassembler (rows) and the background one (counting its valid
/// frames since the active one's last). Returns the number of bytes consumed when a byte makes
/// the background framing win (busnoop switches after that byte), `None` when all were fed.
///
/// The outcome is that of feeding both one byte at a time, the active one first
/// ([`shadowed_bytes`]), but block by block: the background reassembler reads a block first
/// (from a copy of its state). When it finds no valid frame there, which is the usual case,
/// nothing in the block can change the count or make busnoop switch, so the active one reads
/// the block whole. Otherwise the background state goes back to the copy and the block is
/// read byte by byte.
#[allow(clippy::too_many_arguments)]
fn shadowed<A: Stepper, S: Stepper>(
    active: &mut A,
    shadow: &mut S,
    since: &mut u64,
    last: &mut Option<frame::OwnedEvent>,
    map: &mut Mapper,
    data: &[u8],
    time: Option<u64>,
    out: &mut Latch<'_>,
) -> Option<usize> {
    let mut done = 0;
    for block in data.chunks(SHADOW_BLOCK) {
        let before = shadow.clone();
        let mut found = false;
        shadow.push_bytes(block, time, &mut |e| found |= e.is_valid());
        if found {
            *shadow = before;
            if let Some(n) = shadowed_bytes(active, shadow, since, last, map, block, time, out) {
                return Some(done + n);
            }
        } else {
            let mut active_valid = false;
            active.push_bytes(block, time, &mut |e| {
                active_valid |= e.is_valid();
                map.event(e, out);
            });
            if active_valid {
                *since = 0;
            }
        }
        done += block.len();
    }
    None
}

/// [`shadowed`] one byte at a time: each byte goes to the active reassembler, then to the
/// background one.
#[allow(clippy::too_many_arguments)]
fn shadowed_bytes<A: Stepper, S: Stepper>(
    active: &mut A,
    shadow: &mut S,
    since: &mut u64,
    last: &mut Option<frame::OwnedEvent>,
    map: &mut Mapper,
    data: &[u8],
    time: Option<u64>,
    out: &mut Latch<'_>,
) -> Option<usize> {
    for (i, &b) in data.iter().enumerate() {
        let mut active_valid = false;
        active.step_byte(b, time, &mut |e| {
            active_valid |= e.is_valid();
            map.event(e, out);
        });
        if active_valid {
            *since = 0;
        }
        shadow.step_byte(b, time, &mut |e| {
            if e.is_valid() {
                *since += 1;
                match last {
                    Some(l) => l.set_from(e),
                    None => *last = Some(frame::OwnedEvent::from(e)),
                }
            }
        });
        if *since >= detect::SWITCH_FRAMES {
            return Some(i + 1);
        }
    }
    None
}

/// A reassembler of either framing.
#[derive(Clone, Debug)]
pub(super) enum Reasm {
    Sync(sync::Reassembler),
    Hdlc(hdlc::Reassembler),
}

impl Reasm {
    pub(super) fn new(framing: Framing, max_payload: usize) -> Self {
        match framing {
            Framing::Sync => Reasm::Sync(sync::Reassembler::new()),
            Framing::Hdlc => Reasm::Hdlc(hdlc::Reassembler::new(max_payload)),
        }
    }

    fn framing(&self) -> Framing {
        match self {
            Reasm::Sync(_) => Framing::Sync,
            Reasm::Hdlc(_) => Framing::Hdlc,
        }
    }

    pub(super) fn push(
        &mut self,
        data: &[u8],
        time: Option<u64>,
        emit: &mut impl FnMut(&Event<'_>),
    ) {
        match self {
            Reasm::Sync(r) => r.push(data, time, emit),
            Reasm::Hdlc(r) => r.push(data, time, emit),
        }
    }

    #[inline]
    fn step(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.step(b, time, emit),
            Reasm::Hdlc(r) => r.step(b, time, emit),
        }
    }

    pub(super) fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.finish(emit),
            Reasm::Hdlc(r) => r.finish(emit),
        }
    }

    fn reset(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => r.reset(emit),
            Reasm::Hdlc(r) => r.reset(emit),
        }
    }

    /// A quiet line: a SAB v1 frame held for the frames after it is emitted
    /// ([`sync::Reassembler::settle`]), then the garbage so far.
    fn flush_garbage(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        match self {
            Reasm::Sync(r) => {
                r.settle(emit);
                r.flush_garbage(emit)
            }
            Reasm::Hdlc(r) => r.flush_garbage(emit),
        }
    }
}

/// Detection in progress.
#[derive(Clone, Debug)]
struct Undecided {
    sync: sync::Reassembler,
    hdlc: hdlc::Reassembler,
    sync_valid: u64,
    hdlc_valid: u64,
    held: Held,
}

/// The other framing's reassembler, read in the background after the choice.
#[derive(Clone, Debug)]
struct Shadow {
    reasm: Reasm,
    /// Its valid frames since the active reassembler's last valid frame.
    since: u64,
    /// Its last valid frame (the one that makes busnoop switch is shown).
    last: Option<frame::OwnedEvent>,
}

enum Mode {
    Undecided(Box<Undecided>),
    Locked {
        active: Box<Reasm>,
        shadow: Option<Box<Shadow>>,
    },
}

/// The SAB decoder: framing detection + reassembly + table mapping + statistics.
pub struct SabDecoder {
    max_payload: usize,
    mode: Mode,
    map: Mapper,
    /// Bytes pushed so far.
    pos: u64,
    /// The last source time seen.
    last_time: Option<u64>,
}

impl SabDecoder {
    pub fn new(opts: Options) -> Self {
        let mut map = Mapper::new(&opts);
        let mode = match opts.framing {
            FramingChoice::Auto => Mode::Undecided(Box::new(Undecided {
                sync: sync::Reassembler::new(),
                hdlc: hdlc::Reassembler::new(opts.max_payload),
                sync_valid: 0,
                hdlc_valid: 0,
                held: Held::default(),
            })),
            FramingChoice::Sync | FramingChoice::Hdlc => {
                let framing = if opts.framing == FramingChoice::Sync {
                    Framing::Sync
                } else {
                    Framing::Hdlc
                };
                map.chosen(framing, Reason::Forced);
                Mode::Locked {
                    active: Box::new(Reasm::new(framing, opts.max_payload)),
                    shadow: None,
                }
            }
        };
        SabDecoder {
            max_payload: opts.max_payload,
            mode,
            map,
            pos: 0,
            last_time: None,
        }
    }

    /// The framing in use, once chosen.
    pub fn framing(&self) -> Option<Framing> {
        match &self.mode {
            Mode::Undecided(_) => None,
            Mode::Locked { active, .. } => Some(active.framing()),
        }
    }

    /// The counters (tests, tools).
    pub fn counters(&self) -> &Stats {
        &self.map.stats
    }

    /// The capture's current time in ns: the last source time, or the reconstructed time of
    /// the bytes read so far.
    fn now_ns(&self) -> u64 {
        match self.last_time {
            Some(us) => us.saturating_mul(1000),
            None => self.map.nanos_at(self.pos),
        }
    }

    /// Feeds one byte while detection is undecided.
    fn step(&mut self, b: u8, time: Option<u64>, out: &mut Latch<'_>) {
        self.pos += 1;
        match &mut self.mode {
            Mode::Undecided(u) => {
                u.held.push(b, time);
                let (sv, hv) = (&mut u.sync_valid, &mut u.hdlc_valid);
                u.sync.step(b, time, &mut |e| *sv += e.is_valid() as u64);
                u.hdlc.step(b, time, &mut |e| *hv += e.is_valid() as u64);
                let (s, h) = (u.sync_valid, u.hdlc_valid);
                let decision = match detect::lock(s, h) {
                    Some(f) => Some((f, Reason::Locked { sync: s, hdlc: h })),
                    None if u.held.len() >= detect::HOLD_BYTES => Some((
                        detect::majority(s, h),
                        Reason::HoldFull { sync: s, hdlc: h },
                    )),
                    None => None,
                };
                if let Some((f, reason)) = decision {
                    self.decide(f, reason, out);
                }
            }
            Mode::Locked { .. } => {}
        }
    }

    /// Feeds `data` to the chosen and the background reassembler; switches framing when the
    /// background one wins (see [`detect`]).
    fn push_shadowed(&mut self, data: &[u8], time: Option<u64>, out: &mut Latch<'_>) {
        let mut rest = data;
        while !rest.is_empty() {
            let Mode::Locked {
                active,
                shadow: Some(sh),
            } = &mut self.mode
            else {
                return;
            };
            let map = &mut self.map;
            let (since, last) = (&mut sh.since, &mut sh.last);
            let switched = match (active.as_mut(), &mut sh.reasm) {
                (Reasm::Sync(a), Reasm::Hdlc(s)) => {
                    shadowed(a, s, since, last, map, rest, time, out)
                }
                (Reasm::Hdlc(a), Reasm::Sync(s)) => {
                    shadowed(a, s, since, last, map, rest, time, out)
                }
                (a, s) => shadowed(a, s, since, last, map, rest, time, out),
            };
            let Some(n) = switched else {
                self.pos += rest.len() as u64;
                return;
            };
            self.pos += n as u64;
            rest = &rest[n..];
            // The old framing's unfinished frame held the bytes of the new framing's last
            // frame: forget it and show that frame instead.
            active.reset(&mut |e| map.event(e, out));
            std::mem::swap(active.as_mut(), &mut sh.reasm);
            sh.since = 0;
            map.chosen(active.framing(), Reason::Switched { at: self.pos });
            if let Some(l) = &sh.last {
                map.event(&l.as_event(), out);
            }
        }
    }

    /// Ends detection: replays the held bytes through the chosen framing.
    fn decide(&mut self, framing: Framing, reason: Reason, out: &mut Latch<'_>) {
        let mut active = Reasm::new(framing, self.max_payload);
        let placeholder = Mode::Locked {
            active: Box::new(Reasm::new(framing, self.max_payload)),
            shadow: None,
        };
        let u = match std::mem::replace(&mut self.mode, placeholder) {
            Mode::Undecided(u) => u,
            locked => {
                self.mode = locked;
                return;
            }
        };
        let map = &mut self.map;
        map.chosen(framing, reason);
        for seg in u.held.segments() {
            active.push(seg.bytes, seg.time, &mut |e| map.event(e, out));
        }
        let Undecided { sync, hdlc, .. } = *u;
        let other = match framing {
            Framing::Sync => Reasm::Hdlc(hdlc),
            Framing::Hdlc => Reasm::Sync(sync),
        };
        self.mode = Mode::Locked {
            active: Box::new(active),
            shadow: Some(Box::new(Shadow {
                reasm: other,
                since: 0,
                last: None,
            })),
        };
    }
}

impl Decoder for SabDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let mut latch = Latch::new(out);
        let out = &mut latch;
        if time.is_some() {
            self.last_time = time;
        }
        self.map.stats.bytes += data.len() as u64;
        match &mut self.mode {
            Mode::Locked {
                active,
                shadow: None,
            } => {
                let map = &mut self.map;
                active.push(data, time, &mut |e| map.event(e, out));
                self.pos += data.len() as u64;
            }
            Mode::Locked { .. } => self.push_shadowed(data, time, out),
            Mode::Undecided(_) => {
                for (i, &b) in data.iter().enumerate() {
                    self.step(b, time, out);
                    if !matches!(self.mode, Mode::Undecided(_)) {
                        // Decided: the rest goes the fast way.
                        self.push_shadowed(&data[i + 1..], time, out);
                        break;
                    }
                }
            }
        }
        latch.result()
    }

    fn idle(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        let mut latch = Latch::new(out);
        let out = &mut latch;
        if let Mode::Undecided(u) = &mut self.mode
            && !u.held.is_empty()
            && u.held
                .first_time()
                .is_some_and(|t| now.saturating_sub(t) >= detect::HOLD_MICROS)
        {
            // A SAB v1 frame held for the frames after it counts: nothing more is coming.
            let sv = &mut u.sync_valid;
            u.sync.settle(&mut |e| *sv += e.is_valid() as u64);
            let (s, h) = (u.sync_valid, u.hdlc_valid);
            self.decide(
                detect::majority(s, h),
                Reason::Quiet { sync: s, hdlc: h },
                out,
            );
        }
        if let Mode::Locked { active, .. } = &mut self.mode {
            let map = &mut self.map;
            let framing = active.framing();
            active.flush_garbage(&mut |e| map.event(e, out));
            if let Some(x) = map.pairing.advance(now.saturating_mul(1000)) {
                map.timeout_row(&x, framing, out);
            }
        }
        latch.result()
    }

    /// End of the input, or a gap in a live capture (the driver calls `push` again after a
    /// gap): decides the framing if still undecided, closes what is open, and reports the
    /// request still waiting for a response. Decoding goes on with the next `push`.
    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let mut latch = Latch::new(out);
        let out = &mut latch;
        if let Mode::Undecided(u) = &mut self.mode {
            // A SAB v1 frame held for the frames after it counts: the input ends.
            let sv = &mut u.sync_valid;
            u.sync.settle(&mut |e| *sv += e.is_valid() as u64);
            let (s, h) = (u.sync_valid, u.hdlc_valid);
            if self.pos == 0 {
                return latch.result();
            }
            self.decide(
                detect::majority(s, h),
                Reason::EndOfInput { sync: s, hdlc: h },
                out,
            );
        }
        let now = self.now_ns();
        if let Mode::Locked { active, shadow } = &mut self.mode {
            let map = &mut self.map;
            let framing = active.framing();
            active.finish(&mut |e| map.event(e, out));
            map.finish(now, framing, out);
            if let Some(sh) = shadow {
                sh.reasm.reset(&mut |_| {});
                sh.since = 0;
            }
        }
        latch.result()
    }

    fn valid_frames(&self) -> u64 {
        match &self.mode {
            Mode::Undecided(u) => u.sync_valid.max(u.hdlc_valid),
            Mode::Locked { .. } => self.map.stats.valid_frames,
        }
    }

    fn stats(&self) -> Report {
        let names = &self.map.names;
        let mut r = self.map.stats.report(|a| names.device(a).to_owned());
        if let Mode::Undecided(u) = &self.mode {
            r.head.insert(
                0,
                format!(
                    "framing: undecided ({} valid SAB v1 and {} valid SAB2 frames so far)",
                    u.sync_valid, u.hdlc_valid
                ),
            );
        }
        r
    }

    fn problems(&self) -> Problems {
        self.map.stats.problems()
    }

    fn no_frames_hint(&self) -> &'static str {
        "check the baud rate (modm SAB runs at 115200 8N1, normal levels) and the tap: on a CAN \
         transceiver bus read the RXD pin of a recessive transceiver, on a TTL bus tap master TX \
         and the slaves' combined TX (see docs/sab.md)"
    }
}
