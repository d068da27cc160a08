//! Capture time: microseconds since the capture started, and the wall-clock time of that start.

use chrono::{DateTime, NaiveDateTime, Utc};

/// The wall-clock time at the start of the capture (for `--time abs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// A real instant (live capture, pcap).
    Instant(DateTime<Utc>),
    /// A local time without zone, as logged by a radio.
    Naive(NaiveDateTime),
}

impl Anchor {
    /// The instant to stamp capture files with: a radio's naive local time is taken as UTC
    /// (the log does not say its zone; busnoop replays it to the same rows either way).
    pub fn as_utc(self) -> DateTime<Utc> {
        match self {
            Anchor::Instant(t) => t,
            Anchor::Naive(n) => n.and_utc(),
        }
    }

    /// The wall-clock time `micros` after the anchor; `None` when it falls outside the years 1
    /// to 9999 (a corrupt time stamp: the table's `Time` cell stays empty, never a panic).
    pub fn plus(self, micros: u64) -> Option<Anchor> {
        use chrono::Datelike;
        let delta = chrono::TimeDelta::microseconds(i64::try_from(micros).ok()?);
        let (t, year) = match self {
            Anchor::Instant(t) => {
                let t = t.checked_add_signed(delta)?;
                (Anchor::Instant(t), t.year())
            }
            Anchor::Naive(n) => {
                let n = n.checked_add_signed(delta)?;
                (Anchor::Naive(n), n.year())
            }
        };
        (1..=9999).contains(&year).then_some(t)
    }
}
