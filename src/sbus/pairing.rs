//! Pairing answers with requests, shared by the serial modes and Ether-S-Bus: the S-Bus
//! matching rules on top of the core in `crate::pairing`.
//!
//! Responses and ACK/NAKs carry no command, so the decoder remembers each request. A serial
//! line has one master, so the answer belongs to the last unanswered request (secure mode also
//! compares the 8-bit SEQ). Ether-S-Bus keys requests by (conversation, 16-bit sequence).
//! Both detect retries, report requests that got no answer (`Timeout`) and late answers.

use std::collections::VecDeque;

use crate::pairing::{Hint, Open, Table};

pub use crate::pairing::{FastMap, Reason as TimeoutWhy};

use super::telegram::ReqInfo;

/// What S-Bus keeps of a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    pub info: ReqInfo,
    /// Secure-mode SEQ or Ether-S-Bus sequence.
    pub seq: Option<u16>,
    /// Free for the decoder (Ether-S-Bus: the PLC's index).
    pub tag: u32,
}

/// A request waiting for its answer (`time`: its latest transmission, µs since the capture
/// started); it reads like its [`Request`].
pub type Outstanding = Open<Request>;

impl Open<Request> {
    /// A request sent at `time`; `timed`: the time is real (timeouts can be measured).
    pub fn new(info: ReqInfo, time: u64, timed: bool, seq: Option<u16>) -> Self {
        Open::at(Request { info, seq, tag: 0 }, time, timed)
    }
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

impl RequestKind {
    fn resend(next: &mut Outstanding, prev: &Outstanding) -> Self {
        let r = next.resend_of(prev);
        RequestKind::Retry {
            n: r.n,
            since: r.since,
        }
    }
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
    /// The request before it failed its CRC: it opened nothing (its station and command may
    /// be the broken bytes), so the answer is not paired.
    AfterBadRequest,
}

/// Serial line pairing: one outstanding request.
#[derive(Clone, Debug)]
pub struct SerialPairing {
    pending: Option<Outstanding>,
    /// Logical bytes of the last request (to recognise retries).
    last: Vec<u8>,
    last_answered: bool,
    /// The last request failed its CRC and nothing answered it yet.
    after_bad: bool,
    pub timeout: u64,
}

impl SerialPairing {
    pub fn new(timeout: u64) -> Self {
        SerialPairing {
            pending: None,
            last: Vec::with_capacity(300),
            last_answered: true,
            after_bad: false,
            timeout,
        }
    }

    /// The request waiting for an answer.
    pub fn pending(&self) -> Option<&Outstanding> {
        self.pending.as_ref()
    }

    /// A new request: `head` (station, command) and `body`, taken apart so that the caller
    /// need not join them first. Returns how it relates to the previous one and, when the
    /// previous one got no answer, that request for a Timeout row.
    pub fn request(
        &mut self,
        head: [u8; 2],
        body: &[u8],
        req: Outstanding,
        expects_answer: bool,
    ) -> (RequestKind, Option<(Outstanding, TimeoutWhy)>) {
        let same = !self.last_answered
            && self.last.len() == 2 + body.len()
            && self.last[..2] == head
            && self.last[2..] == *body;
        let mut timed_out = None;
        let mut kind = RequestKind::New;
        let mut next = req;
        if let Some(p) = self.pending.take() {
            if p.due() {
                let why = if same {
                    TimeoutWhy::Retry
                } else {
                    TimeoutWhy::NextRequest
                };
                timed_out = Some((p, why));
            }
            if same {
                kind = RequestKind::resend(&mut next, &p);
            }
        }
        self.after_bad = false;
        self.last.clear();
        self.last.extend_from_slice(&head);
        self.last.extend_from_slice(body);
        self.last_answered = !expects_answer;
        if expects_answer {
            self.pending = Some(next);
        }
        (kind, timed_out)
    }

    /// An answer at `time` (µs); `seq`: its secure SEQ, if it came in secure mode. Late is
    /// judged by the answer's time alone (a serial line has no late window: the request
    /// stays pending after its timeout).
    pub fn answer(&mut self, time: u64, seq: Option<u16>) -> Answer {
        let Some(mut p) = self.pending else {
            return match std::mem::take(&mut self.after_bad) {
                true => Answer::AfterBadRequest,
                false => Answer::NoRequest,
            };
        };
        if let (Some(a), Some(r)) = (seq, p.seq)
            && a != r
        {
            return Answer::SeqMismatch { req: p };
        }
        self.pending = None;
        self.last_answered = true;
        let reply = p.answer(time, self.timeout);
        Answer::Paired {
            req: p,
            elapsed: reply.elapsed,
            late: reply.overdue,
        }
    }

    /// A request that failed its CRC: it opens nothing, since its station, command and
    /// address may be the broken bytes, and the next answer is shown unpaired. The request
    /// waiting before it is over (the master sent something else): returned for its Timeout
    /// row when it got no answer.
    pub fn bad_request(&mut self) -> Option<(Outstanding, TimeoutWhy)> {
        self.after_bad = true;
        self.last.clear();
        self.last_answered = true;
        self.pending
            .take()
            .filter(Open::due)
            .map(|p| (p, TimeoutWhy::NextRequest))
    }

    /// A broken answer (bad CRC) arrived for the pending request.
    pub fn bad_answer(&mut self) {
        if let Some(p) = self.pending.as_mut() {
            p.spoiled = true;
        }
    }

    /// The pending request, if its timeout passed at `now` and was not reported yet.
    pub fn expire(&mut self, now: u64) -> Option<Outstanding> {
        let p = self.pending.as_mut()?;
        p.expire(now, self.timeout).map(|_| *p)
    }

    /// End of input: the pending request, unless already reported.
    pub fn finish(&mut self) -> Option<Outstanding> {
        self.pending.take().filter(Open::due)
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
pub type Expired = crate::pairing::Expired<Request>;

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
    /// The sequence of its last request (see [`EtherPairing::conversation`]).
    last_seq: Option<u16>,
    /// Its place in [`EtherPairing::hints`].
    hint: u32,
}

/// A conversation as [`EtherPairing::conversation`] finds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Conversation {
    pub id: u32,
    pub tag: u32,
    /// The sequence of its last request before this packet (for [`EtherPairing::request`]).
    pub last_seq: Option<u16>,
    /// Its place in [`EtherPairing::hints`].
    hint: u32,
}

/// Ether-S-Bus pairing by (conversation, sequence). Conversations are keyed by `K` (the client
/// and server addresses) and carry a tag for the decoder (the PLC's index). Every table is
/// bounded: see [`MAX_OUTSTANDING`], [`MAX_CONVERSATIONS`] and [`CONVERSATION_IDLE`].
#[derive(Debug)]
pub struct EtherPairing<K> {
    /// Waiting requests by (conversation, sequence).
    table: Table<(u32, u16), Request>,
    convs: FastMap<K, Conv>,
    /// Each conversation's [`Hint`] to its latest request, so that the answer to it is found
    /// without the table's map; `free_hints` lists the places of dropped conversations.
    hints: Vec<Hint>,
    free_hints: Vec<u32>,
    /// Every conversation once, in order of use when queued; an entry whose conversation was
    /// used since is queued again when it reaches the front (so the front is the least
    /// recently used one).
    lru: VecDeque<(K, u64)>,
    /// Capture time of the next sweep for idle conversations.
    next_sweep: u64,
    next_conv: u32,
    stamp: u64,
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
            table: Table::new(MAX_OUTSTANDING, LATE_KEPT),
            convs: FastMap::default(),
            hints: Vec::new(),
            free_hints: Vec::new(),
            lru: VecDeque::new(),
            next_sweep: 0,
            next_conv: 0,
            stamp: 0,
            timeout,
            forgotten: Forgotten::default(),
        }
    }

    #[doc(hidden)]
    pub fn sizes(&self) -> TableSizes {
        let t = self.table.sizes();
        TableSizes {
            conversations: self.convs.len(),
            outstanding: t.open,
            deadlines: t.deadlines,
            late: t.late,
            plcs: 0,
        }
    }

    fn idle_limit(&self) -> u64 {
        CONVERSATION_IDLE.max(self.timeout.saturating_mul(2))
    }

    /// The conversation `key` at `now`: its id, its tag (`tag()` for a new one) and the
    /// sequence of its last request. `request`: the sequence of this packet when it is a request
    /// that [`Self::request`] will open next; it becomes the conversation's last one here, so
    /// that the request needs no second lookup. When the table is full the least recently used
    /// conversation is dropped and its open request goes to `out`.
    pub fn conversation(
        &mut self,
        key: K,
        now: u64,
        request: Option<u16>,
        tag: impl FnOnce() -> u32,
        out: &mut Vec<Expired>,
    ) -> Conversation {
        self.stamp += 1;
        let stamp = self.stamp;
        if let Some(c) = self.convs.get_mut(&key) {
            c.stamp = stamp;
            c.time = now;
            let last_seq = c.last_seq;
            if request.is_some() {
                c.last_seq = request;
            }
            return Conversation {
                id: c.id,
                tag: c.tag,
                last_seq,
                hint: c.hint,
            };
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
        let hint = match self.free_hints.pop() {
            Some(h) => h,
            None => {
                self.hints.push(Hint::default());
                (self.hints.len() - 1) as u32
            }
        };
        let c = Conv {
            id,
            tag: tag(),
            stamp,
            time: now,
            queued: stamp,
            last_seq: request,
            hint,
        };
        self.convs.insert(key, c);
        self.lru.push_back((key, stamp));
        Conversation {
            id,
            tag: c.tag,
            last_seq: None,
            hint,
        }
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
        let hint = self.hints.get_mut(c.hint as usize).map(std::mem::take);
        self.free_hints.push(c.hint);
        if let Some(seq) = c.last_seq {
            self.table.forget((c.id, seq), hint.as_ref(), why, now, out);
        }
    }

    /// A request with sequence `seq` on conversation `conv`, as [`Self::conversation`] found
    /// it just now (given `Some(seq)`). When more than [`MAX_OUTSTANDING`] requests wait, the
    /// oldest go to `out`.
    pub fn request(
        &mut self,
        conv: Conversation,
        seq: u16,
        req: Outstanding,
        out: &mut Vec<Expired>,
    ) -> (RequestKind, Option<SeqGap>) {
        let (last, hint, conv) = (conv.last_seq, conv.hint, conv.id);
        if last == Some(seq)
            && let Some(p) = self
                .table
                .previous((conv, seq), self.hints.get(hint as usize))
                .copied()
        {
            let mut next = req;
            let kind = RequestKind::resend(&mut next, &p);
            self.open((conv, seq), hint, next, out);
            return (kind, None);
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
        self.open((conv, seq), hint, req, out);
        (RequestKind::New, gap)
    }

    fn open(&mut self, key: (u32, u16), hint: u32, req: Outstanding, out: &mut Vec<Expired>) {
        let hint = self.hints.get_mut(hint as usize);
        self.table.open(key, req, hint, out);
        self.forgotten.requests = self.table.given_up;
    }

    /// An answer on conversation `conv` with sequence `seq` at `time`.
    pub fn answer(&mut self, conv: &Conversation, seq: u16, time: u64) -> Answer {
        let hint = self.hints.get(conv.hint as usize);
        match self.table.answer((conv.id, seq), hint, time, self.timeout) {
            Some((req, reply, late)) => Answer::Paired {
                req,
                elapsed: reply.elapsed,
                late,
            },
            None => Answer::NoRequest,
        }
    }

    /// An answer with a bad CRC for (conversation, sequence): no Timeout row for that request.
    pub fn bad_answer(&mut self, conv: &Conversation, seq: u16) {
        let hint = self.hints.get(conv.hint as usize);
        if let Some(r) = self.table.get_mut((conv.id, seq), hint) {
            r.spoiled = true;
        }
    }

    /// Requests whose timeout passed at `now`, oldest first; conversations idle for longer
    /// than [`CONVERSATION_IDLE`] are forgotten.
    pub fn expire(&mut self, now: u64, out: &mut Vec<Expired>) {
        self.table.expire(now, self.timeout, out);
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
        self.table.finish()
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
            p.request([1, 6], &[0, 0, 0], r, true),
            (RequestKind::New, None)
        );
        assert_eq!(p.expire(100_000), None);
        let t = p.expire(400_000).unwrap();
        assert_eq!(t.info.station, 1);
        assert_eq!(p.expire(500_000), None, "reported once");
        // the retry: no second Timeout row (already reported)
        let r2 = Outstanding::new(info(1), 400_000, true, None);
        let (kind, prev) = p.request([1, 6], &[0, 0, 0], r2, true);
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
        assert_eq!(p.request([1, 6], &[0, 0, 0], r3, true).0, RequestKind::New);
        // a different request before the answer: Timeout for the first
        let r4 = Outstanding::new(info(2), 1_100_000, true, None);
        let (_, prev) = p.request([2, 6], &[0, 0, 0], r4, true);
        assert_eq!(prev.unwrap().1, TimeoutWhy::NextRequest);
    }

    #[test]
    fn secure_seq_must_match() {
        let mut p = SerialPairing::new(375_000);
        let r = Outstanding::new(info(5), 0, false, Some(3));
        p.request([5, 6], &[0, 0, 0], r, true);
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
        // A request on conversation `key` at `t`: its conversation's id, how it relates.
        let req = |p: &mut EtherPairing<u8>, key, t, seq, out: &mut Vec<_>| {
            let c = p.conversation(key, t, Some(seq), || 0, out);
            (c, p.request(c, seq, r(t), out))
        };
        let (c0, k) = req(&mut p, 0, 0, 1, &mut out);
        assert_eq!(k, (RequestKind::New, None));
        let (c1, k) = req(&mut p, 1, 10, 1, &mut out);
        assert_eq!(k, (RequestKind::New, None));
        assert!(matches!(
            p.answer(&c1, 1, 50),
            Answer::Paired { elapsed: 40, .. }
        ));
        let (c, k) = req(&mut p, 0, 500, 1, &mut out);
        assert_eq!(
            (c.id, k),
            (c0.id, (RequestKind::Retry { n: 1, since: 500 }, None))
        );
        assert!(matches!(
            p.answer(&c0, 1, 600),
            Answer::Paired { elapsed: 100, .. }
        ));
        assert_eq!(p.answer(&c0, 1, 700), Answer::NoRequest);
        let (_, (k, gap)) = req(&mut p, 0, 800, 5, &mut out);
        assert_eq!(k, RequestKind::New);
        assert_eq!(gap, Some(SeqGap { missing: Some(3) }));
        p.expire(1_000_000, &mut out);
        assert!(out.is_empty());
        p.expire(1_900_000, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!((out[0].why, out[0].at), (TimeoutWhy::Deadline, 1_000_800));
        // late answer still pairs
        assert!(matches!(
            p.answer(&c0, 5, 2_000_000),
            Answer::Paired { late: true, .. }
        ));
        // idle conversations are forgotten, and start afresh
        out.clear();
        p.expire(70_000_000, &mut out);
        assert_eq!(p.sizes().conversations, 0);
        assert_eq!(p.forgotten.expired, 2);
        let (c2, (_, gap)) = req(&mut p, 0, 70_000_001, 9, &mut out);
        assert_ne!(c2.id, c0.id);
        assert_eq!(gap, None);
        assert!(out.is_empty());
    }
}
