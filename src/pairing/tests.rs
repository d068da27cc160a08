use super::*;

const T: u64 = 1_000;

#[test]
fn deadline_expiry_once_and_untimed_never() {
    let mut o = Open::at('a', 100, true);
    assert_eq!(o.deadline(T), Some(1_100));
    assert_eq!(
        o.expire(1_100, T),
        None,
        "exactly at the deadline is in time"
    );
    assert_eq!(o.expire(1_101, T), Some(1_100));
    assert!(o.reported && !o.due());
    assert_eq!(o.expire(5_000, T), None, "reported once");
    let mut u = Open::at('b', 100, false);
    assert_eq!(u.deadline(T), None);
    assert_eq!(u.expire(u64::MAX, T), None);
    assert!(u.due(), "still waiting: it expires by another reason");
    // Deadlines saturate.
    assert_eq!(Open::at((), u64::MAX - 1, true).deadline(T), Some(u64::MAX));
}

#[test]
fn answers_spoiled_and_resends() {
    let mut o = Open::at((), 0, true);
    let r = o.answer(400, T);
    assert_eq!(
        r,
        Reply {
            elapsed: 400,
            overdue: false,
            repeat: false
        }
    );
    assert!(!o.due(), "answered in time: never expires");
    assert!(o.answer(500, T).repeat);
    // A first answer after the deadline: late, and the request still expires.
    let mut o = Open::at((), 0, true);
    assert!(o.answer(1_500, T).overdue);
    assert!(o.due() && o.answered_late);
    assert_eq!(o.expire(1_500, T), Some(T));
    // A spoiled request (unusable answer) never expires.
    let mut o = Open::at((), 0, true);
    o.spoiled = true;
    assert_eq!(o.expire(10 * T, T), None);
    // A resend keeps the first transmission.
    let first = Open::at((), 10, true);
    let mut second = Open::at((), 300, true);
    assert_eq!(second.resend_of(&first), Resend { n: 1, since: 290 });
    let mut third = Open::at((), 700, true);
    assert_eq!(third.resend_of(&second), Resend { n: 2, since: 690 });
    assert_eq!((third.first, third.sends), (10, 3));
}

#[test]
fn payload_fields_through_the_open_request() {
    #[derive(Clone, Copy)]
    struct P {
        tag: u32,
    }
    let mut o = Open::at(P { tag: 1 }, 0, true);
    o.tag = 7;
    assert_eq!(o.req.tag, 7);
}

fn open(t: u64) -> Open<u32> {
    Open::at(0, t, true)
}

#[test]
fn late_window_keeps_the_last_expiries_or_the_unanswered() {
    for keep in [Keep::Expiries, Keep::Unanswered] {
        let mut w = LateWindow::new(3, keep);
        for k in 1..=3u8 {
            w.push(k, open(k as u64), Reason::Deadline);
        }
        assert_eq!(w.find(2).map(|o| o.time), Some(2));
        assert_eq!(w.take(|k| *k == 2).map(|e| e.0.time), Some(2));
        assert_eq!(w.take(|k| *k == 2), None, "a late answer pairs once");
        w.push(4, open(4), Reason::NextRequest);
        // Expiries: 1 made room for 4 (2's place stays taken); Unanswered: 2's place was
        // freed, 1 stays.
        let kept_1 = keep == Keep::Unanswered;
        assert_eq!(w.find(1).is_some(), kept_1, "{keep:?}");
        assert_eq!(w.len(), 3);
        assert_eq!(w.take(|k| *k == 4).map(|e| e.1), Some(Reason::NextRequest));
        w.clear();
        assert!(w.is_empty());
    }
    // Newest first.
    let mut w = LateWindow::new(4, Keep::Unanswered);
    w.push(1, open(10), Reason::Deadline);
    w.push(1, open(20), Reason::Deadline);
    assert_eq!(w.find(1).map(|o| o.time), Some(20));
    // A window of none keeps nothing.
    let mut w = LateWindow::new(0, Keep::Expiries);
    w.push(1, open(10), Reason::Deadline);
    assert!(w.is_empty());
}

#[test]
fn table_expires_in_order_with_reasons_and_late_answers() {
    let mut t: Table<u8, u32> = Table::new(16, 8);
    let mut out = Vec::new();
    t.open(1, open(0), None, &mut out);
    t.open(2, open(100), None, &mut out);
    t.open(3, open(200), None, &mut out);
    t.get_mut(3, None).unwrap().spoiled = true;
    t.expire(T, T, &mut out);
    assert!(out.is_empty(), "exactly at the deadline is in time");
    t.expire(1_150, T, &mut out);
    assert_eq!(out.len(), 2);
    assert_eq!(
        (out[0].req.time, out[0].why, out[0].at),
        (0, Reason::Deadline, T)
    );
    assert_eq!((out[1].req.time, out[1].at), (100, 1_100));
    out.clear();
    // 3 is spoiled: it expires silently, yet a late answer still pairs with it.
    t.expire(5_000, T, &mut out);
    assert!(out.is_empty());
    let (o, reply, late) = t.answer(3, None, 5_000, T).unwrap();
    assert_eq!((o.time, reply.elapsed, late), (200, 4_800, true));
    // A late answer to 1 pairs once.
    assert!(t.answer(1, None, 5_100, T).is_some_and(|a| a.2));
    assert!(t.answer(1, None, 5_200, T).is_none());
    // An answer in time.
    t.open(4, open(6_000), None, &mut out);
    let (_, reply, late) = t.answer(4, None, 6_500, T).unwrap();
    assert_eq!((reply.elapsed, late), (500, false));
    // Retries find the previous transmission, open or expired.
    assert_eq!(t.previous(2, None).map(|o| o.time), Some(100));
    t.open(5, open(7_000), None, &mut out);
    assert_eq!(t.previous(5, None).map(|o| o.time), Some(7_000));
    // Forgotten requests are reported but never pair again.
    t.forget(5, None, Reason::Dropped, 7_100, &mut out);
    assert_eq!((out[0].why, out[0].at), (Reason::Dropped, 7_100));
    assert!(t.answer(5, None, 7_200, T).is_none());
    assert_eq!(t.finish(), 0);
}

#[test]
fn table_cap_gives_up_the_oldest() {
    let mut t: Table<u32, u32> = Table::new(3, 2);
    let mut out = Vec::new();
    for k in 0..3 {
        t.open(k, open(k as u64 * 10), None, &mut out);
    }
    t.get_mut(1, None).unwrap().spoiled = true;
    // The same key again replaces its request: nothing given up.
    t.open(2, open(25), None, &mut out);
    assert!(out.is_empty());
    t.open(3, open(30), None, &mut out);
    assert_eq!(out.len(), 1);
    assert_eq!(
        (out[0].req.time, out[0].why, out[0].at),
        (0, Reason::Overflow, 30)
    );
    // The spoiled one is given up silently, but counted.
    t.open(4, open(40), None, &mut out);
    assert_eq!(out.len(), 1);
    assert_eq!(t.given_up, 2);
    assert_eq!(t.sizes().open, 3);
    // Given-up requests still take late answers.
    assert!(t.answer(0, None, 50, T).is_some_and(|a| a.2));
    assert_eq!(t.finish(), 3);
    assert_eq!(
        t.sizes(),
        Sizes {
            open: 0,
            deadlines: 0,
            late: 1
        }
    );
}

#[test]
fn deadline_queue_stays_small_with_constant_times() {
    // Nothing ever comes due: answered and repeated requests leave stale deadlines, which
    // are compacted away.
    for hinted in [false, true] {
        let mut t: Table<u32, u32> = Table::new(1 << 16, 16);
        let mut hints = [Hint::default(); 7];
        let mut out = Vec::new();
        for i in 0..100_000u32 {
            // With hints: seven groups of keys (a key in one group only).
            let mut h = hinted.then(|| &mut hints[(i % 50 % 7) as usize]);
            t.open(i % 50, open(0), h.as_deref_mut(), &mut out);
            if i % 3 == 0 {
                t.answer(i % 50, h.as_deref(), 0, T);
            }
            t.expire(0, T, &mut out);
            let s = t.sizes();
            assert!(s.deadlines <= s.open + s.open / 4 + 1_025, "{s:?}");
        }
        assert!(out.is_empty());
    }
}

/// One step of a scripted exchange: `key` is opened (or answered) `dt` after the last step.
#[derive(Clone, Copy, Debug)]
struct Step {
    dt: u64,
    key: u8,
    answer: bool,
    ticks: u8,
}

/// Runs `steps`; with `ticks`, `expire` is also called at times between the steps (as a
/// live capture's idle calls would). Returns everything the table reported.
fn run(steps: &[Step], ticks: bool) -> Vec<String> {
    let mut t: Table<u8, u32> = Table::new(4, 2);
    let mut out = Vec::new();
    let mut log = Vec::new();
    let mut now = 0;
    for s in steps {
        if ticks {
            for i in 1..=s.ticks as u64 {
                t.expire(now + s.dt * i / (s.ticks as u64 + 1), T, &mut out);
            }
        }
        now += s.dt;
        t.expire(now, T, &mut out);
        if s.answer {
            log.push(format!("{:?}", t.answer(s.key, None, now, T)));
        } else {
            t.open(s.key, open(now), None, &mut out);
        }
        log.extend(out.drain(..).map(|e| format!("{e:?}")));
    }
    log.push(format!("finish {}", t.finish()));
    log
}

use proptest::prelude::*;

proptest! {
    #[test]
    fn expiry_does_not_depend_on_idle_calls(
        steps in prop::collection::vec(
            (0u64..1_500, 0u8..6, any::<bool>(), 0u8..4)
                .prop_map(|(dt, key, answer, ticks)| Step { dt, key, answer, ticks }),
            0..60,
        )
    ) {
        prop_assert_eq!(run(&steps, false), run(&steps, true));
    }

    /// With and without hints: `grouping` 0 keeps none (every request in the map), 1 one hint
    /// for every key, 2 a hint for each pair of keys, 3 one for each key.
    #[test]
    fn table_does_what_the_model_does(
        ops in prop::collection::vec((0u8..6, 0u8..6, 0u64..3_000), 0..120),
        grouping in 0u8..4,
    ) {
        let mut t: Table<u8, u32> = Table::new(4, 3);
        let mut m = Model::new(4, 3);
        let mut hints = [Hint::default(); 6];
        let group = |key: u8| match grouping {
            0 => None,
            1 => Some(0),
            2 => Some(usize::from(key / 2)),
            _ => Some(usize::from(key)),
        };
        let (mut got, mut want) = (Vec::new(), Vec::new());
        for (i, &(op, key, time)) in ops.iter().enumerate() {
            let payload = i as u32;
            let g = group(key);
            match op {
                0 | 1 => {
                    let o = Open::at(payload, time, true);
                    t.open(key, o, g.map(|g| &mut hints[g]), &mut got);
                    m.open(key, o, &mut want);
                }
                2 => prop_assert_eq!(
                    t.answer(key, g.map(|g| &hints[g]), time, T),
                    m.answer(key, time)
                ),
                3 => {
                    t.expire(time, T, &mut got);
                    m.expire(time, &mut want);
                }
                4 => {
                    t.forget(key, g.map(|g| &hints[g]), Reason::Dropped, time, &mut got);
                    m.forget(key, time, &mut want);
                }
                _ => {
                    if let Some(o) = t.get_mut(key, g.map(|g| &hints[g])) {
                        o.spoiled = true;
                    }
                    if let Some(o) = m.get_mut(key) {
                        o.spoiled = true;
                    }
                }
            }
            prop_assert_eq!(&got, &want);
            prop_assert_eq!(t.previous(key, g.map(|g| &hints[g])), m.previous(key));
            prop_assert_eq!((t.sizes().open, t.given_up), (m.open.len(), m.given_up));
            if grouping == 3 {
                prop_assert!(t.map.is_empty(), "a hint for each key: nothing in the map");
            }
        }
        prop_assert_eq!(t.finish(), m.finish());
    }
}

/// What [`Table`] does, the plain way: the open requests in the order of their latest
/// opening (its deadline queue without the stale entries), searched one by one.
struct Model {
    open: Vec<(u8, Open<u32>)>,
    cap: usize,
    late: LateWindow<u8, u32>,
    given_up: u64,
}

impl Model {
    fn new(cap: usize, late: usize) -> Self {
        Model {
            open: Vec::new(),
            cap,
            late: LateWindow::new(late, Keep::Unanswered),
            given_up: 0,
        }
    }

    fn take(&mut self, key: u8) -> Option<Open<u32>> {
        let i = self.open.iter().position(|e| e.0 == key)?;
        Some(self.open.remove(i).1)
    }

    fn get_mut(&mut self, key: u8) -> Option<&mut Open<u32>> {
        self.open.iter_mut().find(|e| e.0 == key).map(|e| &mut e.1)
    }

    fn previous(&self, key: u8) -> Option<&Open<u32>> {
        let open = self.open.iter().find(|e| e.0 == key).map(|e| &e.1);
        open.or_else(|| self.late.find(key))
    }

    fn expired(
        &mut self,
        key: u8,
        mut o: Open<u32>,
        why: Reason,
        at: u64,
        out: &mut Vec<Expired<u32>>,
    ) {
        o.reported = true;
        if !o.spoiled {
            out.push(Expired { req: o, why, at });
        }
        self.late.push(key, o, why);
    }

    fn open(&mut self, key: u8, o: Open<u32>, out: &mut Vec<Expired<u32>>) {
        if self.take(key).is_none() {
            while self.open.len() >= self.cap {
                let (k, r) = self.open.remove(0);
                self.given_up += 1;
                self.expired(k, r, Reason::Overflow, o.time.max(r.time), out);
            }
        }
        self.open.push((key, o));
    }

    fn answer(&mut self, key: u8, at: u64) -> Option<(Open<u32>, Reply, bool)> {
        let mut o = match self.take(key) {
            Some(o) => o,
            None => self.late.take(|k| *k == key)?.0,
        };
        let reply = o.answer(at, T);
        Some((o, reply, reply.elapsed > T || o.reported))
    }

    fn expire(&mut self, now: u64, out: &mut Vec<Expired<u32>>) {
        while let Some(&(k, r)) = self.open.first() {
            let at = r.time.saturating_add(T);
            if at >= now {
                break;
            }
            self.open.remove(0);
            self.expired(k, r, Reason::Deadline, at, out);
        }
    }

    fn forget(&mut self, key: u8, at: u64, out: &mut Vec<Expired<u32>>) {
        if let Some(mut r) = self.take(key) {
            r.reported = true;
            if !r.spoiled {
                out.push(Expired {
                    req: r,
                    why: Reason::Dropped,
                    at,
                });
            }
        }
    }

    fn finish(&mut self) -> u64 {
        self.open.drain(..).filter(|e| !e.1.spoiled).count() as u64
    }
}
