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
