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
}
