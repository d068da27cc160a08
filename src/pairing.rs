//! Pairing answers with requests: the protocol-independent core.
//!
//! A request is *open* from its start until its answer comes or it *expires*: its deadline
//! (start + the master's timeout) passes, a new request supersedes it, a table is full, or the
//! input ends. Every expiry carries a [`Reason`]. An answer to a request that has already
//! expired is *late*; it still pairs while the request is in the [`LateWindow`].
//!
//! The core knows no protocol: which answer belongs to which request is the protocol's rule.
//! `sbus::pairing` (one request at a time on a serial line, by secure SEQ; by conversation and
//! sequence on Ether-S-Bus) and `sab::pairing` (by address and command) wrap these pieces:
//!
//! * [`Open`]: an open request (its payload, start, retries, whether it was answered or its
//!   expiry reported) with its deadline, expiry and answer rules;
//! * [`LateWindow`]: the requests that expired recently, for late answers;
//! * [`Table`]: many open requests by key, with a deadline queue, a cap and a late window,
//!   every part bounded.
//!
//! Pure: times in, decisions out. Times are in the caller's unit (µs or ns) since the capture
//! started; nothing here reads a clock, so the result does not depend on how often or when
//! [`Table::expire`] is called, only on the times it is given.

use std::collections::{HashMap, VecDeque};
use std::hash::{BuildHasherDefault, Hash, Hasher};
use std::ops::{Deref, DerefMut};

/// Why an open request expired (a `Timeout` row).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// Its deadline passed without an answer.
    Deadline,
    /// A new (different) request came first: the master stopped waiting.
    NextRequest,
    /// The same request was sent again.
    Retry,
    /// The input ended (or had a gap) before its deadline.
    End,
    /// Its conversation was dropped (the table of conversations was full).
    Dropped,
    /// Given up: the table of open requests was full (`Table`'s cap).
    Overflow,
}

/// An open request: the protocol's payload `R` and the pairing state. It reads like its
/// payload (`open.field` reaches `R`'s fields).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Open<R> {
    pub req: R,
    /// Start of the latest transmission.
    pub time: u64,
    /// Start of the first transmission (retries keep it).
    pub first: u64,
    /// Whether the time is real: only then has the request a deadline.
    pub timed: bool,
    /// Transmissions so far (1 + retries).
    pub sends: u8,
    /// Answers paired with it so far.
    pub answers: u32,
    /// Its expiry was reported.
    pub reported: bool,
    /// An answer came but was unusable (a bad CRC): the master retries, no expiry is reported.
    pub spoiled: bool,
    /// Its first answer came after the deadline: it expires all the same (not reported yet).
    pub answered_late: bool,
}

/// A repeated request: `n` is the retry number (1 = second transmission), `since` the time
/// since the first transmission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resend {
    pub n: u8,
    pub since: u64,
}

/// What [`Open::answer`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reply {
    /// Response time: from the latest transmission to the answer.
    pub elapsed: u64,
    /// The answer came after the deadline.
    pub overdue: bool,
    /// Not the first answer to this request.
    pub repeat: bool,
}

impl<R> Open<R> {
    /// A request sent at `time` (`timed`: the time is real).
    pub fn at(req: R, time: u64, timed: bool) -> Self {
        Open {
            req,
            time,
            first: time,
            timed,
            sends: 1,
            answers: 0,
            reported: false,
            spoiled: false,
            answered_late: false,
        }
    }

    /// Start + `timeout`, when the time is real.
    pub fn deadline(&self, timeout: u64) -> Option<u64> {
        self.timed.then(|| self.time.saturating_add(timeout))
    }

    /// It expires (or has expired) without a usable answer in time, and that was not reported.
    pub fn due(&self) -> bool {
        !self.reported && !self.spoiled && (self.answers == 0 || self.answered_late)
    }

    /// At `now`: when it is due and its deadline passed, it is reported now; returns the
    /// deadline (the time of its expiry).
    pub fn expire(&mut self, now: u64, timeout: u64) -> Option<u64> {
        let deadline = self.deadline(timeout)?;
        if !self.due() || now <= deadline {
            return None;
        }
        self.reported = true;
        Some(deadline)
    }

    /// This request repeats `prev`: it keeps `prev`'s first transmission and counts one more.
    pub fn resend_of(&mut self, prev: &Open<R>) -> Resend {
        self.first = prev.first;
        self.sends = prev.sends.saturating_add(1);
        Resend {
            n: prev.sends,
            since: self.time.saturating_sub(prev.first),
        }
    }

    /// An answer at `at` pairs with it.
    pub fn answer(&mut self, at: u64, timeout: u64) -> Reply {
        self.answers = self.answers.saturating_add(1);
        let overdue = self.deadline(timeout).is_some_and(|d| at > d);
        if overdue && self.answers == 1 && !self.reported {
            self.answered_late = true;
        }
        Reply {
            elapsed: at.saturating_sub(self.time),
            overdue,
            repeat: self.answers > 1,
        }
    }
}

impl<R> Deref for Open<R> {
    type Target = R;
    fn deref(&self) -> &R {
        &self.req
    }
}

impl<R> DerefMut for Open<R> {
    fn deref_mut(&mut self) -> &mut R {
        &mut self.req
    }
}

/// A request that expired: a `Timeout` row at `at`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Expired<R> {
    pub req: Open<R>,
    pub why: Reason,
    pub at: u64,
}

/// What a [`LateWindow`] of `n` holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Keep {
    /// The last `n` expiries: an answered one leaves its place empty.
    Expiries,
    /// The last `n` expiries still without an answer.
    Unanswered,
}

/// Requests that expired recently, keyed by `K`, for late answers. Bounded: the oldest goes
/// when a new one comes to a full window. Lookups go newest first.
#[derive(Clone, Debug)]
pub struct LateWindow<K, R> {
    entries: VecDeque<Option<(K, Open<R>, Reason)>>,
    cap: usize,
    keep: Keep,
}

impl<K: Copy + Eq, R: Copy> LateWindow<K, R> {
    pub fn new(cap: usize, keep: Keep) -> Self {
        LateWindow {
            entries: VecDeque::new(),
            cap,
            keep,
        }
    }

    /// Remembers `open`, which expired for `why`.
    pub fn push(&mut self, key: K, open: Open<R>, why: Reason) {
        if self.cap == 0 {
            return;
        }
        if self.entries.len() == self.cap {
            self.entries.pop_front();
        }
        self.entries.push_back(Some((key, open, why)));
    }

    fn position(&self, mut hit: impl FnMut(&K) -> bool) -> Option<usize> {
        self.entries
            .iter()
            .rposition(|e| e.as_ref().is_some_and(|(k, _, _)| hit(k)))
    }

    /// The latest request remembered for `key`.
    pub fn find(&self, key: K) -> Option<&Open<R>> {
        let i = self.position(|k| *k == key)?;
        self.entries[i].as_ref().map(|e| &e.1)
    }

    /// Takes the latest request remembered under a key that `hit` accepts (a late answer
    /// pairs with it once), with the reason it expired.
    pub fn take(&mut self, hit: impl FnMut(&K) -> bool) -> Option<(Open<R>, Reason)> {
        let i = self.position(hit)?;
        let e = match self.keep {
            Keep::Expiries => self.entries[i].take(),
            Keep::Unanswered => self.entries.remove(i).flatten(),
        };
        e.map(|(_, open, why)| (open, why))
    }

    /// Forgets everything.
    #[cfg(test)]
    pub fn clear(&mut self) {
        self.entries.clear();
    }

    /// Places in use (empty ones included).
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// A small multiplicative hasher for the pairing keys (addresses, sequence numbers): the maps
/// are looked up for every packet, and SipHash's resistance to crafted keys buys nothing here
/// (keys only pick buckets; a collision costs time, never correctness).
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

/// `HashMap` with `FastHasher`.
pub type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

/// A request's place: its slot and that request's generation (the slot may have been freed or
/// taken by a later request since). The deadline queue and [`Hint`]s hold places.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Place {
    slot: u32,
    generation: u32,
}

/// A caller's note of the latest request it opened in a group of keys (an Ether-S-Bus
/// conversation): that request is found through the note, not through [`Table`]'s map, so a
/// request answered before the group's next one is never hashed. The caller keeps one hint
/// per group and gives the same hint for every key of that group (a key is in one group
/// only); `None` keeps no note (every request in the map).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Hint(Option<Place>);

/// A place in [`Table`]'s slots: the request, its key and the generation of its deadline;
/// `live`: it holds an open request; `mapped`: its key is in the map (else only a hint finds
/// it).
#[derive(Clone, Copy, Debug)]
struct Slot<K, R> {
    open: Open<R>,
    key: K,
    generation: u32,
    live: bool,
    mapped: bool,
}

/// Sizes of a [`Table`]'s parts (for tests of the bounds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sizes {
    pub open: usize,
    pub deadlines: usize,
    pub late: usize,
}

/// Many open requests by key `K`, each with a deadline (start + the timeout the caller
/// gives; a table's times are taken as real whatever [`Open::timed`] says). Bounded: at most
/// `cap` open requests (a new one gives up the oldest, [`Reason::Overflow`]), a deadline queue
/// at most a quarter (+ 1,024) longer than the open requests, and a late window of its own
/// size ([`Keep::Unanswered`]).
///
/// Deadlines are queued in the order of the requests, so with one timeout they come due in
/// that order; answered and repeated requests leave stale entries that are dropped lazily
/// (at the front) or all at once when there are too many (so a capture with constant times,
/// where nothing ever comes due, keeps the queue small too). A deadline names its request's
/// place, so the queue is checked (every packet looks at its front) without a lookup.
///
/// The latest request of a group of keys is found through the group's [`Hint`]; the map
/// holds the others (an earlier request of the group still open when the next one came,
/// and every request opened without a hint). Usual traffic, where each request is answered
/// before its group's next one, never touches the map.
#[derive(Debug)]
pub struct Table<K, R> {
    /// Open requests not found through a hint, by key: an index into `slots`.
    map: FastMap<K, u32>,
    /// The requests; `free` lists the slots not `live`.
    slots: Vec<Slot<K, R>>,
    free: Vec<u32>,
    deadlines: VecDeque<Place>,
    generation: u32,
    cap: usize,
    late: LateWindow<K, R>,
    /// Requests given up at the cap (reported or not).
    pub given_up: u64,
}

impl<K: Copy + Eq + Hash, R: Copy> Table<K, R> {
    /// At most `cap` open requests and `late` expired ones kept for late answers.
    pub fn new(cap: usize, late: usize) -> Self {
        Table {
            map: FastMap::default(),
            slots: Vec::new(),
            free: Vec::new(),
            deadlines: VecDeque::new(),
            generation: 0,
            cap: cap.max(1),
            late: LateWindow::new(late, Keep::Unanswered),
            given_up: 0,
        }
    }

    pub fn sizes(&self) -> Sizes {
        Sizes {
            open: self.open_count(),
            deadlines: self.deadlines.len(),
            late: self.late.len(),
        }
    }

    /// Open requests: the slots that are not free.
    fn open_count(&self) -> usize {
        self.slots.len() - self.free.len()
    }

    /// The slot of the request at `p` when it is still the one open there.
    fn at(&self, p: Place) -> Option<&Slot<K, R>> {
        self.slots
            .get(p.slot as usize)
            .filter(|s| s.live && s.generation == p.generation)
    }

    /// The slot of the request open under `key`: the hint's, or else the map's.
    #[inline]
    fn find(&self, key: K, hint: Option<&Hint>) -> Option<u32> {
        if let Some(p) = hint.and_then(|h| h.0)
            && self.at(p).is_some_and(|s| s.key == key)
        {
            return Some(p.slot);
        }
        if self.map.is_empty() {
            return None;
        }
        self.map.get(&key).copied()
    }

    /// The request open under `key`.
    pub fn get(&self, key: K, hint: Option<&Hint>) -> Option<&Open<R>> {
        let i = self.find(key, hint)?;
        self.slots.get(i as usize).map(|s| &s.open)
    }

    pub fn get_mut(&mut self, key: K, hint: Option<&Hint>) -> Option<&mut Open<R>> {
        let i = self.find(key, hint)?;
        self.slots.get_mut(i as usize).map(|s| &mut s.open)
    }

    /// The latest request under `key`, open or expired (to recognise a retry).
    pub fn previous(&self, key: K, hint: Option<&Hint>) -> Option<&Open<R>> {
        self.get(key, hint).or_else(|| self.late.find(key))
    }

    /// Frees slot `i` (live): out of the map when it is there; a hint to it goes stale.
    fn take(&mut self, i: u32) -> Option<(K, Open<R>)> {
        let s = self.slots.get_mut(i as usize)?;
        s.live = false;
        let (key, open, mapped) = (s.key, s.open, s.mapped);
        if mapped {
            self.map.remove(&key);
        }
        self.free.push(i);
        Some((key, open))
    }

    /// Expires `open` for `why` at `at`: reported unless spoiled, then kept for late answers.
    fn expired(
        &mut self,
        key: K,
        mut open: Open<R>,
        why: Reason,
        at: u64,
        out: &mut Vec<Expired<R>>,
    ) {
        open.reported = true;
        if !open.spoiled {
            out.push(Expired { req: open, why, at });
        }
        self.late.push(key, open, why);
    }

    /// Opens `open` under `key` (a request sent again replaces the one open); it becomes the
    /// one `hint` notes, and the request noted before, if still open, goes to the map. When
    /// `cap` requests are open, the oldest are given up into `out`.
    pub fn open(
        &mut self,
        key: K,
        open: Open<R>,
        mut hint: Option<&mut Hint>,
        out: &mut Vec<Expired<R>>,
    ) {
        self.generation = self.generation.wrapping_add(1);
        let generation = self.generation;
        let slot = if let Some(i) = self.find(key, hint.as_deref()) {
            // Sent again: in its slot, found as before (a hint to it follows it).
            if let Some(s) = self.slots.get_mut(i as usize) {
                s.open = open;
                s.generation = generation;
            }
            if let Some(h) = hint.as_deref_mut()
                && h.0.is_some_and(|p| p.slot == i)
            {
                h.0 = Some(Place {
                    slot: i,
                    generation,
                });
            }
            i
        } else {
            while self.open_count() >= self.cap {
                let Some(d) = self.deadlines.pop_front() else {
                    break;
                };
                if self.at(d).is_none() {
                    continue;
                }
                if let Some((k, r)) = self.take(d.slot) {
                    self.given_up += 1;
                    let at = open.time.max(r.time);
                    self.expired(k, r, Reason::Overflow, at, out);
                }
            }
            let entry = Slot {
                open,
                key,
                generation,
                live: true,
                mapped: hint.is_none(),
            };
            let i = match self.free.pop() {
                Some(i) => i,
                None => {
                    self.slots.push(entry);
                    (self.slots.len() - 1) as u32
                }
            };
            match hint {
                Some(h) => {
                    // The group's request before, still open, is found through the map now.
                    if let Some(p) = h.0
                        && let Some(s) = self.slots.get_mut(p.slot as usize)
                        && s.live
                        && s.generation == p.generation
                        && !s.mapped
                    {
                        s.mapped = true;
                        self.map.insert(s.key, p.slot);
                    }
                    h.0 = Some(Place {
                        slot: i,
                        generation,
                    });
                }
                None => {
                    self.map.insert(key, i);
                }
            }
            if let Some(s) = self.slots.get_mut(i as usize) {
                *s = entry;
            }
            i
        };
        self.deadlines.push_back(Place { slot, generation });
        let open = self.open_count();
        if self.deadlines.len() > open + open / 4 + 1_024 {
            let mut deadlines = std::mem::take(&mut self.deadlines);
            deadlines.retain(|&d| self.at(d).is_some());
            self.deadlines = deadlines;
        }
    }

    /// An answer under `key` at `at`: the open request, or else one in the late window.
    /// `late`: after the deadline, or after the request's expiry was reported.
    pub fn answer(
        &mut self,
        key: K,
        hint: Option<&Hint>,
        at: u64,
        timeout: u64,
    ) -> Option<(Open<R>, Reply, bool)> {
        let found = self.find(key, hint).and_then(|i| self.take(i));
        let mut open = match found {
            Some((_, r)) => r,
            None => self.late.take(|k| *k == key)?.0,
        };
        let reply = open.answer(at, timeout);
        let late = reply.elapsed > timeout || open.reported;
        Some((open, reply, late))
    }

    /// Requests whose deadline passed at `now` go to `out`, oldest first, at their deadline.
    pub fn expire(&mut self, now: u64, timeout: u64, out: &mut Vec<Expired<R>>) {
        while let Some(&d) = self.deadlines.front() {
            let Some(s) = self.at(d) else {
                self.deadlines.pop_front();
                continue;
            };
            if s.open.time.saturating_add(timeout) >= now {
                break;
            }
            self.deadlines.pop_front();
            if let Some((key, r)) = self.take(d.slot) {
                let at = r.time.saturating_add(timeout);
                self.expired(key, r, Reason::Deadline, at, out);
            }
        }
    }

    /// Forgets the request open under `key` for good (no late answer will pair with it); it
    /// goes to `out` for `why` at `at` unless spoiled.
    pub fn forget(
        &mut self,
        key: K,
        hint: Option<&Hint>,
        why: Reason,
        at: u64,
        out: &mut Vec<Expired<R>>,
    ) {
        if let Some((_, mut r)) = self.find(key, hint).and_then(|i| self.take(i)) {
            r.reported = true;
            if !r.spoiled {
                out.push(Expired { req: r, why, at });
            }
        }
    }

    /// End of input: forgets every open request; returns how many were due (not spoiled).
    pub fn finish(&mut self) -> u64 {
        let mut n = 0;
        while let Some(d) = self.deadlines.pop_front() {
            if self.at(d).is_some()
                && let Some((_, r)) = self.take(d.slot)
            {
                n += u64::from(!r.spoiled);
            }
        }
        n
    }
}

#[cfg(test)]
mod tests;
