//! Pairing answers with requests, shared by the serial modes and Ether-S-Bus.
//!
//! Responses and ACK/NAKs carry no command, so the decoder remembers each request. A serial
//! line has one master, so the answer belongs to the last unanswered request (secure mode also
//! compares the 8-bit SEQ). Ether-S-Bus keys requests by (conversation, 16-bit sequence).
//! Both detect retries, report requests that got no answer (`Timeout`) and late answers.

use std::collections::{HashMap, VecDeque};
use std::hash::{BuildHasherDefault, Hasher};

use super::telegram::ReqInfo;

/// A small multiplicative hasher for the decoder's own keys (addresses, sequence numbers):
/// the maps are looked up for every packet, and SipHash's resistance to crafted keys buys
/// nothing here (keys only pick buckets; a collision costs time, never correctness).
#[derive(Default, Clone, Copy)]
pub struct FastHasher(u64);

impl Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }

    fn write_u8(&mut self, n: u8) {
        self.write_u64(n as u64);
    }

    fn write_u16(&mut self, n: u16) {
        self.write_u64(n as u64);
    }

    fn write_u32(&mut self, n: u32) {
        self.write_u64(n as u64);
    }

    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(5) ^ n).wrapping_mul(0x51_7C_C1_B7_27_22_0A_95);
    }

    fn write_usize(&mut self, n: usize) {
        self.write_u64(n as u64);
    }
}

/// `HashMap` with [`FastHasher`].
pub type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

/// A request waiting for its answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Outstanding {
    pub info: ReqInfo,
    /// Time of the latest transmission (µs since the capture started).
    pub time: u64,
    /// Time of the first transmission.
    pub first: u64,
    /// Whether the time is real (timeouts can be measured).
    pub timed: bool,
    /// Secure-mode SEQ or Ether-S-Bus sequence.
    pub seq: Option<u16>,
    /// Transmissions so far (1 + retries).
    pub sends: u8,
    /// A Timeout row was already written for it.
    pub timeout_reported: bool,
    /// An answer arrived but was unusable (bad CRC): no Timeout row for it.
    pub bad_answer: bool,
    /// Free for the decoder (Ether-S-Bus: the PLC's index).
    pub tag: u32,
}

impl Outstanding {
    pub fn new(info: ReqInfo, time: u64, timed: bool, seq: Option<u16>) -> Self {
        Outstanding {
            info,
            time,
            first: time,
            timed,
            seq,
            sends: 1,
            timeout_reported: false,
            bad_answer: false,
            tag: 0,
        }
    }
}

/// Why a request is reported as timed out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeoutWhy {
    /// The master timeout passed without an answer.
    Deadline,
    /// The next (different) request came first.
    NextRequest,
    /// The same request was sent again.
    Retry,
    /// The capture ended.
    End,
    /// Ether-S-Bus: its conversation was dropped (more than [`MAX_CONVERSATIONS`] at once).
    Dropped,
    /// Ether-S-Bus: given up (more than [`MAX_OUTSTANDING`] requests waiting).
    Overflow,
}

/// How a new request relates to the previous ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RequestKind {
    New,
    /// The same request again: `n` is the retry number (1 = second transmission), `since` the
    /// time since the first transmission (µs).
    Retry {
        n: u8,
        since: u64,
    },
}

/// What an answer was paired with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    Paired {
        req: Outstanding,
        /// Response time (µs) from the latest transmission.
        elapsed: u64,
        /// Arrived after the master timeout.
        late: bool,
    },
    /// Secure mode: the SEQ does not match the outstanding request's (a stale answer).
    SeqMismatch { req: Outstanding },
    /// No request is waiting.
    NoRequest,
}

/// Serial line pairing: one outstanding request.
#[derive(Clone, Debug)]
pub struct SerialPairing {
    pending: Option<Outstanding>,
    /// Logical bytes of the last request (to recognise retries).
    last: Vec<u8>,
    last_answered: bool,
    pub timeout: u64,
}

impl SerialPairing {
    pub fn new(timeout: u64) -> Self {
        SerialPairing {
            pending: None,
            last: Vec::with_capacity(300),
            last_answered: true,
            timeout,
        }
    }

    /// The request waiting for an answer.
    pub fn pending(&self) -> Option<&Outstanding> {
        self.pending.as_ref()
    }

    /// A new request `bytes` (station, command, body). Returns how it relates to the previous
    /// one and, when the previous one got no answer, that request for a Timeout row.
    pub fn request(
        &mut self,
        bytes: &[u8],
        req: Outstanding,
        expects_answer: bool,
    ) -> (RequestKind, Option<(Outstanding, TimeoutWhy)>) {
        let same = !self.last_answered && self.last == bytes;
        let prev = self.pending.take();
        let mut timed_out = None;
        let mut kind = RequestKind::New;
        let mut next = req;
        if let Some(p) = prev {
            if !p.timeout_reported && !p.bad_answer {
                let why = if same {
                    TimeoutWhy::Retry
                } else {
                    TimeoutWhy::NextRequest
                };
                timed_out = Some((p, why));
            }
            if same {
                kind = RequestKind::Retry {
                    n: p.sends,
                    since: req.time.saturating_sub(p.first),
                };
                next.first = p.first;
                next.sends = p.sends.saturating_add(1);
            }
        }
        self.last.clear();
        self.last.extend_from_slice(bytes);
        self.last_answered = !expects_answer;
        if expects_answer {
            self.pending = Some(next);
        }
        (kind, timed_out)
    }

    /// An answer at `time` (µs); `seq`: its secure SEQ, if it came in secure mode.
    pub fn answer(&mut self, time: u64, seq: Option<u16>) -> Answer {
        let Some(p) = self.pending else {
            return Answer::NoRequest;
        };
        if let (Some(a), Some(r)) = (seq, p.seq)
            && a != r
        {
            return Answer::SeqMismatch { req: p };
        }
        self.pending = None;
        self.last_answered = true;
        let elapsed = time.saturating_sub(p.time);
        Answer::Paired {
            req: p,
            elapsed,
            late: p.timed && elapsed > self.timeout,
        }
    }

    /// A broken answer (bad CRC) arrived for the pending request.
    pub fn bad_answer(&mut self) {
        if let Some(p) = self.pending.as_mut() {
            p.bad_answer = true;
        }
    }

    /// The pending request, if its timeout passed at `now` and was not reported yet.
    pub fn expire(&mut self, now: u64) -> Option<Outstanding> {
        let p = self.pending.as_mut()?;
        if p.timed && !p.timeout_reported && !p.bad_answer && now > p.time + self.timeout {
            p.timeout_reported = true;
            return Some(*p);
        }
        None
    }

    /// End of input: the pending request, unless already reported.
    pub fn finish(&mut self) -> Option<Outstanding> {
        let p = self.pending.take()?;
        (!p.timeout_reported && !p.bad_answer).then_some(p)
    }
}

/// A sequence gap seen on a conversation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeqGap {
    /// Sequence numbers skipped (`None` when the sequence went backwards: a restart).
    pub missing: Option<u16>,
}

/// Requests waiting for an answer kept at most: with more, the oldest is given up and
/// reported as a timeout ([`TimeoutWhy::Overflow`]).
pub const MAX_OUTSTANDING: usize = 1 << 16;
/// Conversations (client and server address pairs) kept at most: with more, the least recently
/// used one is dropped and its open request reported as a timeout ([`TimeoutWhy::Dropped`]).
pub const MAX_CONVERSATIONS: usize = 4_096;
/// A conversation without a packet for this long (µs, and at least twice the timeout) is
/// forgotten: its requests have timed out long ago; a later packet starts it afresh.
pub const CONVERSATION_IDLE: u64 = 60_000_000;
/// Timed-out requests remembered for late answers.
const LATE_KEPT: usize = 256;

/// A request given up, for a Timeout row at `at`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Expired {
    pub req: Outstanding,
    pub why: TimeoutWhy,
    pub at: u64,
}

/// What the Ether-S-Bus tables forgot, for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Forgotten {
    /// Conversations seen (each start, or restart after expiry, counts).
    pub conversations: u64,
    /// Conversations forgotten after [`CONVERSATION_IDLE`] without a packet.
    pub expired: u64,
    /// Conversations dropped at [`MAX_CONVERSATIONS`].
    pub dropped: u64,
    /// Requests given up at [`MAX_OUTSTANDING`].
    pub requests: u64,
}

/// One conversation.
#[derive(Clone, Copy, Debug)]
struct Conv {
    id: u32,
    tag: u32,
    /// Use stamp (for the least recently used order) and the time of the last packet.
    stamp: u64,
    time: u64,
    /// The stamp of its entry in the use queue (older than `stamp` when used since).
    queued: u64,
}

/// A deadline (the request's time + the timeout): `generation` tells whether the request it
/// was made for is still the one waiting.
#[derive(Clone, Copy, Debug)]
struct Deadline {
    key: (u32, u16),
    generation: u32,
}

/// Ether-S-Bus pairing by (conversation, sequence). Conversations are keyed by `K` (the client
/// and server addresses) and carry a tag for the decoder (the PLC's index). Every table is
/// bounded: see [`MAX_OUTSTANDING`], [`MAX_CONVERSATIONS`] and [`CONVERSATION_IDLE`].
#[derive(Debug)]
pub struct EtherPairing<K> {
    /// Waiting requests by (conversation, sequence): an index into `slots` (a compact map).
    map: FastMap<(u32, u16), u32>,
    /// The requests, with the generation of their deadline; `free` lists unused slots.
    slots: Vec<(Outstanding, u32)>,
    free: Vec<u32>,
    /// In the order of insertion; entries whose request was answered or sent again are stale
    /// and dropped lazily (and compacted when they outnumber the live ones).
    deadlines: VecDeque<Deadline>,
    /// Recently timed-out requests, for late answers.
    late: VecDeque<((u32, u16), Outstanding)>,
    convs: FastMap<K, Conv>,
    /// The last sequence of each conversation (by id; a cheaper key than the addresses).
    last_seq: FastMap<u32, u16>,
    /// Every conversation once, in order of use when queued; an entry whose conversation was
    /// used since is queued again when it reaches the front (so the front is the least
    /// recently used one).
    lru: VecDeque<(K, u64)>,
    /// Capture time of the next sweep for idle conversations.
    next_sweep: u64,
    next_conv: u32,
    stamp: u64,
    generation: u32,
    pub timeout: u64,
    pub forgotten: Forgotten,
}

/// Sizes of the tables (for tests of the bounds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TableSizes {
    pub conversations: usize,
    pub outstanding: usize,
    pub deadlines: usize,
    pub late: usize,
    pub plcs: usize,
}

impl<K: Copy + Eq + std::hash::Hash> EtherPairing<K> {
    pub fn new(timeout: u64) -> Self {
        EtherPairing {
            map: FastMap::default(),
            slots: Vec::new(),
            free: Vec::new(),
            deadlines: VecDeque::new(),
            late: VecDeque::new(),
            convs: FastMap::default(),
            last_seq: FastMap::default(),
            lru: VecDeque::new(),
            next_sweep: 0,
            next_conv: 0,
            stamp: 0,
            generation: 0,
            timeout,
            forgotten: Forgotten::default(),
        }
    }

    #[doc(hidden)]
    pub fn sizes(&self) -> TableSizes {
        TableSizes {
            conversations: self.convs.len().max(self.last_seq.len()),
            outstanding: self.map.len(),
            deadlines: self.deadlines.len(),
            late: self.late.len(),
            plcs: 0,
        }
    }

    fn get(&self, key: (u32, u16)) -> Option<&Outstanding> {
        self.map.get(&key).map(|&i| &self.slots[i as usize].0)
    }

    fn get_mut(&mut self, key: (u32, u16)) -> Option<&mut Outstanding> {
        let i = *self.map.get(&key)?;
        Some(&mut self.slots[i as usize].0)
    }

    fn remove(&mut self, key: (u32, u16)) -> Option<Outstanding> {
        let i = self.map.remove(&key)?;
        self.free.push(i);
        Some(self.slots[i as usize].0)
    }

    /// Whether deadline `d` belongs to the request waiting now.
    fn live(&self, d: &Deadline) -> bool {
        self.map
            .get(&d.key)
            .is_some_and(|&i| self.slots[i as usize].1 == d.generation)
    }

    fn idle_limit(&self) -> u64 {
        CONVERSATION_IDLE.max(self.timeout.saturating_mul(2))
    }

    /// The conversation `key` at `now`: its id and tag (`tag()` for a new one). When the table
    /// is full the least recently used conversation is dropped and its open request goes to
    /// `out`.
    pub fn conversation(
        &mut self,
        key: K,
        now: u64,
        tag: impl FnOnce() -> u32,
        out: &mut Vec<Expired>,
    ) -> (u32, u32) {
        self.stamp += 1;
        let stamp = self.stamp;
        if let Some(c) = self.convs.get_mut(&key) {
            c.stamp = stamp;
            c.time = now;
            return (c.id, c.tag);
        }
        while self.convs.len() >= MAX_CONVERSATIONS {
            let Some((k, s)) = self.lru.pop_front() else {
                break;
            };
            match self.convs.get_mut(&k) {
                Some(c) if c.queued == s && c.stamp != s => {
                    // Used since it was queued: not the least recently used one.
                    c.queued = c.stamp;
                    self.lru.push_back((k, c.stamp));
                }
                Some(c) if c.queued == s => {
                    self.forgotten.dropped += 1;
                    self.drop_conversation(k, now, TimeoutWhy::Dropped, out);
                }
                _ => {}
            }
        }
        let id = self.next_conv;
        self.next_conv = self.next_conv.wrapping_add(1);
        self.forgotten.conversations += 1;
        let c = Conv {
            id,
            tag: tag(),
            stamp,
            time: now,
            queued: stamp,
        };
        self.convs.insert(key, c);
        self.lru.push_back((key, stamp));
        (id, c.tag)
    }

    /// Sets the tag of conversation `key`.
    pub fn set_tag(&mut self, key: K, tag: u32) {
        if let Some(c) = self.convs.get_mut(&key) {
            c.tag = tag;
        }
    }

    /// Forgets a conversation; its last request, if still waiting, goes to `out`.
    fn drop_conversation(&mut self, key: K, now: u64, why: TimeoutWhy, out: &mut Vec<Expired>) {
        let Some(c) = self.convs.remove(&key) else {
            return;
        };
        if let Some(seq) = self.last_seq.remove(&c.id)
            && let Some(mut r) = self.remove((c.id, seq))
        {
            r.timeout_reported = true;
            if !r.bad_answer {
                out.push(Expired {
                    req: r,
                    why,
                    at: now,
                });
            }
        }
    }

    /// A request with sequence `seq` on conversation `conv` (an id from
    /// [`Self::conversation`], just now). When more than [`MAX_OUTSTANDING`] requests wait,
    /// the oldest go to `out`.
    pub fn request(
        &mut self,
        conv: u32,
        seq: u16,
        req: Outstanding,
        out: &mut Vec<Expired>,
    ) -> (RequestKind, Option<SeqGap>) {
        let last = self.last_seq.insert(conv, seq);
        if last == Some(seq) {
            let prev = self.get((conv, seq)).copied().or_else(|| {
                self.late
                    .iter()
                    .rev()
                    .find(|(k, _)| *k == (conv, seq))
                    .map(|e| e.1)
            });
            if let Some(p) = prev {
                let mut next = req;
                next.first = p.first;
                next.sends = p.sends.saturating_add(1);
                self.insert(conv, seq, next, out);
                return (
                    RequestKind::Retry {
                        n: p.sends,
                        since: req.time.saturating_sub(p.first),
                    },
                    None,
                );
            }
        }
        let gap = match last {
            Some(l) if seq != l.wrapping_add(1) && seq != l => {
                let d = seq.wrapping_sub(l);
                Some(SeqGap {
                    missing: (d < 0x8000).then(|| d - 1),
                })
            }
            _ => None,
        };
        self.insert(conv, seq, req, out);
        (RequestKind::New, gap)
    }

    fn insert(&mut self, conv: u32, seq: u16, req: Outstanding, out: &mut Vec<Expired>) {
        let key = (conv, seq);
        if !self.map.contains_key(&key) {
            while self.map.len() >= MAX_OUTSTANDING {
                // Give up the oldest request (deadlines are in order of insertion).
                let Some(d) = self.deadlines.pop_front() else {
                    break;
                };
                if self.live(&d) {
                    let mut r = self.remove(d.key).expect("live");
                    r.timeout_reported = true;
                    self.forgotten.requests += 1;
                    if !r.bad_answer {
                        out.push(Expired {
                            req: r,
                            why: TimeoutWhy::Overflow,
                            at: req.time.max(r.time),
                        });
                    }
                    self.remember_late(d.key, r);
                }
            }
        }
        self.generation = self.generation.wrapping_add(1);
        let entry = (req, self.generation);
        match self.map.get(&key) {
            Some(&i) => self.slots[i as usize] = entry,
            None => {
                let i = match self.free.pop() {
                    Some(i) => {
                        self.slots[i as usize] = entry;
                        i
                    }
                    None => {
                        self.slots.push(entry);
                        (self.slots.len() - 1) as u32
                    }
                };
                self.map.insert(key, i);
            }
        }
        self.deadlines.push_back(Deadline {
            key,
            generation: self.generation,
        });
        // Answered and repeated requests leave stale deadlines behind: drop them when they
        // outnumber a quarter of the live ones.
        if self.deadlines.len() > self.map.len() + self.map.len() / 4 + 1_024 {
            let mut deadlines = std::mem::take(&mut self.deadlines);
            deadlines.retain(|d| self.live(d));
            self.deadlines = deadlines;
        }
    }

    fn remember_late(&mut self, key: (u32, u16), r: Outstanding) {
        if self.late.len() == LATE_KEPT {
            self.late.pop_front();
        }
        self.late.push_back((key, r));
    }

    /// An answer on conversation `conv` with sequence `seq` at `time`.
    pub fn answer(&mut self, conv: u32, seq: u16, time: u64) -> Answer {
        let req = match self.remove((conv, seq)) {
            Some(r) => r,
            None => match self.late.iter().rposition(|(k, _)| *k == (conv, seq)) {
                Some(i) => self.late.remove(i).map(|e| e.1).expect("index in range"),
                None => return Answer::NoRequest,
            },
        };
        let elapsed = time.saturating_sub(req.time);
        Answer::Paired {
            req,
            elapsed,
            late: elapsed > self.timeout || req.timeout_reported,
        }
    }

    /// An answer with a bad CRC for (conversation, sequence): no Timeout row for that request.
    pub fn bad_answer(&mut self, conv: u32, seq: u16) {
        if let Some(r) = self.get_mut((conv, seq)) {
            r.bad_answer = true;
        }
    }

    /// Requests whose timeout passed at `now`, oldest first; conversations idle for longer
    /// than [`CONVERSATION_IDLE`] are forgotten.
    pub fn expire(&mut self, now: u64, out: &mut Vec<Expired>) {
        while let Some(&d) = self.deadlines.front() {
            if !self.live(&d) {
                self.deadlines.pop_front();
                continue;
            }
            let at = self
                .get(d.key)
                .expect("live")
                .time
                .saturating_add(self.timeout);
            if at >= now {
                break;
            }
            self.deadlines.pop_front();
            let mut r = self.remove(d.key).expect("live");
            r.timeout_reported = true;
            if !r.bad_answer {
                out.push(Expired {
                    req: r,
                    why: TimeoutWhy::Deadline,
                    at,
                });
            }
            self.remember_late(d.key, r);
        }
        if now < self.next_sweep {
            return;
        }
        let idle = self.idle_limit();
        self.next_sweep = now.saturating_add(idle / 8);
        while let Some(&(k, s)) = self.lru.front() {
            match self.convs.get_mut(&k) {
                Some(c) if c.queued == s => {
                    if c.time.saturating_add(idle) < now {
                        self.lru.pop_front();
                        self.forgotten.expired += 1;
                        self.drop_conversation(k, now, TimeoutWhy::Deadline, out);
                    } else if c.stamp != s {
                        c.queued = c.stamp;
                        let stamp = c.stamp;
                        self.lru.pop_front();
                        self.lru.push_back((k, stamp));
                    } else {
                        break;
                    }
                }
                _ => {
                    self.lru.pop_front();
                }
            }
        }
    }

    /// End of input: forgets every request still waiting; returns how many there were (not
    /// counting those whose answer came with a bad CRC).
    pub fn finish(&mut self) -> u64 {
        let mut n = 0;
        while let Some(d) = self.deadlines.pop_front() {
            if self.live(&d) {
                let r = self.remove(d.key).expect("live");
                n += u64::from(!r.bad_answer);
            }
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sbus::commands::Expect;

    fn info(station: u8) -> ReqInfo {
        ReqInfo {
            station,
            cmd: 6,
            addr: 0,
            block: 0,
            elem: None,
            count: 1,
            expect: Expect::Data(4),
        }
    }

    #[test]
    fn serial_retry_timeout_and_late() {
        let mut p = SerialPairing::new(375_000);
        let r = Outstanding::new(info(1), 0, true, None);
        assert_eq!(
            p.request(&[1, 6, 0, 0, 0], r, true),
            (RequestKind::New, None)
        );
        assert_eq!(p.expire(100_000), None);
        let t = p.expire(400_000).unwrap();
        assert_eq!(t.info.station, 1);
        assert_eq!(p.expire(500_000), None, "reported once");
        // the retry: no second Timeout row (already reported)
        let r2 = Outstanding::new(info(1), 400_000, true, None);
        let (kind, prev) = p.request(&[1, 6, 0, 0, 0], r2, true);
        assert_eq!(
            kind,
            RequestKind::Retry {
                n: 1,
                since: 400_000
            }
        );
        assert_eq!(prev, None);
        match p.answer(900_000, None) {
            Answer::Paired { elapsed, late, req } => {
                assert_eq!(elapsed, 500_000);
                assert!(late);
                assert_eq!(req.sends, 2);
            }
            a => panic!("{a:?}"),
        }
        assert_eq!(p.answer(950_000, None), Answer::NoRequest);
        // an answered request repeated is a new poll, not a retry
        let r3 = Outstanding::new(info(1), 1_000_000, true, None);
        assert_eq!(p.request(&[1, 6, 0, 0, 0], r3, true).0, RequestKind::New);
        // a different request before the answer: Timeout for the first
        let r4 = Outstanding::new(info(2), 1_100_000, true, None);
        let (_, prev) = p.request(&[2, 6, 0, 0, 0], r4, true);
        assert_eq!(prev.unwrap().1, TimeoutWhy::NextRequest);
    }

    #[test]
    fn secure_seq_must_match() {
        let mut p = SerialPairing::new(375_000);
        let r = Outstanding::new(info(5), 0, false, Some(3));
        p.request(&[5, 6, 0, 0, 0], r, true);
        assert!(matches!(p.answer(10, Some(2)), Answer::SeqMismatch { .. }));
        // a standard answer to a secure request is normal
        assert!(matches!(
            p.answer(20, None),
            Answer::Paired { late: false, .. }
        ));
    }

    #[test]
    fn ether_pairing_by_sequence() {
        let mut p: EtherPairing<u8> = EtherPairing::new(1_000_000);
        let mut out = Vec::new();
        let r = |t| Outstanding::new(info(75), t, true, None);
        let (c0, _) = p.conversation(0, 0, || 0, &mut out);
        assert_eq!(p.request(c0, 1, r(0), &mut out), (RequestKind::New, None));
        let (c1, _) = p.conversation(1, 10, || 0, &mut out);
        assert_eq!(p.request(c1, 1, r(10), &mut out), (RequestKind::New, None));
        assert!(matches!(
            p.answer(c1, 1, 50),
            Answer::Paired { elapsed: 40, .. }
        ));
        assert_eq!(
            p.request(c0, 1, r(500), &mut out),
            (RequestKind::Retry { n: 1, since: 500 }, None)
        );
        assert!(matches!(
            p.answer(c0, 1, 600),
            Answer::Paired { elapsed: 100, .. }
        ));
        assert_eq!(p.answer(c0, 1, 700), Answer::NoRequest);
        let (k, gap) = p.request(c0, 5, r(800), &mut out);
        assert_eq!(k, RequestKind::New);
        assert_eq!(gap, Some(SeqGap { missing: Some(3) }));
        p.expire(1_000_000, &mut out);
        assert!(out.is_empty());
        p.expire(1_900_000, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!((out[0].why, out[0].at), (TimeoutWhy::Deadline, 1_000_800));
        // late answer still pairs
        assert!(matches!(
            p.answer(c0, 5, 2_000_000),
            Answer::Paired { late: true, .. }
        ));
        // idle conversations are forgotten, and start afresh
        out.clear();
        p.expire(70_000_000, &mut out);
        assert_eq!(p.sizes().conversations, 0);
        assert_eq!(p.forgotten.expired, 2);
        let (c2, _) = p.conversation(0, 70_000_001, || 0, &mut out);
        assert_ne!(c2, c0);
        assert_eq!(p.request(c2, 9, r(70_000_001), &mut out).1, None);
        assert!(out.is_empty());
    }
}
