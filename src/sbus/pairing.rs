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

/// Per-conversation state of Ether-S-Bus pairing.
#[derive(Clone, Copy, Debug, Default)]
struct ConvState {
    last_seq: Option<u16>,
}

/// A sequence gap seen on a conversation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeqGap {
    /// Sequence numbers skipped (`None` when the sequence went backwards: a restart).
    pub missing: Option<u16>,
}

/// Ether-S-Bus pairing by (conversation, sequence).
#[derive(Debug)]
pub struct EtherPairing {
    map: FastMap<(u32, u16), Outstanding>,
    deadlines: VecDeque<(u64, u32, u16, u64)>,
    /// Recently timed-out requests, for late answers.
    late: VecDeque<((u32, u16), Outstanding)>,
    convs: Vec<ConvState>,
    pub timeout: u64,
}

/// Requests kept at most (older ones are reported as timed out).
const MAX_OUTSTANDING: usize = 1 << 16;
const LATE_KEPT: usize = 256;

impl EtherPairing {
    pub fn new(timeout: u64) -> Self {
        EtherPairing {
            map: FastMap::default(),
            deadlines: VecDeque::new(),
            late: VecDeque::new(),
            convs: Vec::new(),
            timeout,
        }
    }

    fn conv(&mut self, conv: u32) -> &mut ConvState {
        let i = conv as usize;
        if self.convs.len() <= i {
            self.convs.resize(i + 1, ConvState::default());
        }
        &mut self.convs[i]
    }

    /// A request on conversation `conv` with sequence `seq`.
    pub fn request(
        &mut self,
        conv: u32,
        seq: u16,
        req: Outstanding,
    ) -> (RequestKind, Option<SeqGap>) {
        let last = self.conv(conv).last_seq;
        self.conv(conv).last_seq = Some(seq);
        if last == Some(seq) {
            let prev = self.map.get(&(conv, seq)).copied().or_else(|| {
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
                self.insert(conv, seq, next);
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
        self.insert(conv, seq, req);
        (RequestKind::New, gap)
    }

    fn insert(&mut self, conv: u32, seq: u16, req: Outstanding) {
        if self.map.len() >= MAX_OUTSTANDING {
            // Forget the oldest entries (their deadlines are in order).
            while self.map.len() >= MAX_OUTSTANDING {
                match self.deadlines.pop_front() {
                    Some((_, c, s, _)) => {
                        self.map.remove(&(c, s));
                    }
                    None => {
                        self.map.clear();
                    }
                }
            }
        }
        self.map.insert((conv, seq), req);
        self.deadlines
            .push_back((req.time.saturating_add(self.timeout), conv, seq, req.time));
    }

    /// An answer on conversation `conv` with sequence `seq` at `time`.
    pub fn answer(&mut self, conv: u32, seq: u16, time: u64) -> Answer {
        let req = match self.map.remove(&(conv, seq)) {
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
        if let Some(r) = self.map.get_mut(&(conv, seq)) {
            r.bad_answer = true;
        }
    }

    /// Requests whose timeout passed at `now`, oldest first.
    pub fn expire(&mut self, now: u64, out: &mut Vec<Outstanding>) {
        while let Some(&(deadline, conv, seq, sent)) = self.deadlines.front() {
            if deadline >= now {
                break;
            }
            self.deadlines.pop_front();
            if let Some(r) = self.map.get(&(conv, seq))
                && r.time == sent
            {
                let mut r = self.map.remove(&(conv, seq)).expect("present");
                r.timeout_reported = true;
                if !r.bad_answer {
                    out.push(r);
                }
                if self.late.len() == LATE_KEPT {
                    self.late.pop_front();
                }
                self.late.push_back(((conv, seq), r));
            }
        }
    }

    /// End of input: every request still waiting, oldest first.
    pub fn finish(&mut self, out: &mut Vec<Outstanding>) {
        while let Some((_, conv, seq, sent)) = self.deadlines.pop_front() {
            if let Some(r) = self.map.get(&(conv, seq))
                && r.time == sent
            {
                if !r.bad_answer {
                    out.push(*r);
                }
                self.map.remove(&(conv, seq));
            }
        }
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
        let mut p = EtherPairing::new(1_000_000);
        let r = |t| Outstanding::new(info(75), t, true, None);
        assert_eq!(p.request(0, 1, r(0)), (RequestKind::New, None));
        assert_eq!(p.request(1, 1, r(10)), (RequestKind::New, None));
        assert!(matches!(
            p.answer(1, 1, 50),
            Answer::Paired { elapsed: 40, .. }
        ));
        assert_eq!(
            p.request(0, 1, r(500)),
            (RequestKind::Retry { n: 1, since: 500 }, None)
        );
        assert!(matches!(
            p.answer(0, 1, 600),
            Answer::Paired { elapsed: 100, .. }
        ));
        assert_eq!(p.answer(0, 1, 700), Answer::NoRequest);
        let (k, gap) = p.request(0, 5, r(800));
        assert_eq!(k, RequestKind::New);
        assert_eq!(gap, Some(SeqGap { missing: Some(3) }));
        let mut out = Vec::new();
        p.expire(1_000_000, &mut out);
        assert!(out.is_empty());
        p.expire(1_900_000, &mut out);
        assert_eq!(out.len(), 1);
        // late answer still pairs
        assert!(matches!(
            p.answer(0, 5, 2_000_000),
            Answer::Paired { late: true, .. }
        ));
    }
}
