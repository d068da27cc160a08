//! `--speed`: replays at the pace of the capture (1 = real time, 2 = twice as fast), for the
//! live view and for the table.
//!
//! Rows are held until their capture time is due on the wall clock, counted from the first
//! row. A silence longer than [`MAX_SILENCE`] of capture time is cut short (a log that paused
//! for an hour replays without the hour).

use std::time::{Duration, Instant};

use crate::row::{Row, RowResult, Unframed};
use crate::sink::{Sink, Tap, Tapped};

/// Longer silences of the capture are replayed as one second.
pub const MAX_SILENCE: u64 = 10_000_000;

/// Maps capture time onto the wall clock.
#[derive(Debug)]
pub struct Pacer {
    speed: f64,
    /// Capture time and the instant it is (or was) due.
    origin: Option<(u64, Instant)>,
    last: u64,
    held_since: Option<Instant>,
    off: bool,
}

impl Pacer {
    /// `None` for speed 0 (as fast as possible).
    pub fn new(speed: f64) -> Option<Pacer> {
        (speed > 0.0 && speed.is_finite()).then_some(Pacer {
            speed,
            origin: None,
            last: 0,
            held_since: None,
            off: false,
        })
    }

    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// How long to wait before capture time `micros` is due; `None` when it is due now (or
    /// pacing was turned off).
    pub fn due_in(&mut self, micros: u64, now: Instant) -> Option<Duration> {
        if self.off {
            return None;
        }
        if self.held_since.is_some() {
            // Held (paused): wait in steps until released.
            return Some(Duration::from_millis(50));
        }
        let (t0, at) = match self.origin {
            Some((t0, at)) if micros.saturating_sub(self.last) <= MAX_SILENCE => (t0, at),
            Some(_) => {
                // A long silence: go on one second after the previous row's due time.
                let prev = self.due(self.last);
                let at = prev + Duration::from_secs(1);
                self.origin = Some((micros, at));
                (micros, at)
            }
            None => {
                self.origin = Some((micros, now));
                (micros, now)
            }
        };
        self.last = self.last.max(micros);
        let due = at + Duration::from_secs_f64(micros.saturating_sub(t0) as f64 / 1e6 / self.speed);
        due.checked_duration_since(now).filter(|d| !d.is_zero())
    }

    fn due(&self, micros: u64) -> Instant {
        match self.origin {
            Some((t0, at)) => {
                at + Duration::from_secs_f64(micros.saturating_sub(t0) as f64 / 1e6 / self.speed)
            }
            None => Instant::now(),
        }
    }

    /// Pauses the replay: nothing is due until [`Pacer::release`].
    pub fn hold(&mut self, now: Instant) {
        self.held_since.get_or_insert(now);
    }

    /// Resumes the replay where it was held.
    pub fn release(&mut self, now: Instant) {
        if let Some(since) = self.held_since.take()
            && let Some((t0, at)) = self.origin
        {
            self.origin = Some((t0, at + now.saturating_duration_since(since)));
        }
    }

    /// Stops pacing for good (stopping, or the user quit): every row is due at once.
    pub fn turn_off(&mut self) {
        self.off = true;
    }
}

/// The table, paced (`--speed N` without `--top`): the pacer holds each row until it is due.
pub type Paced<'a, S> = Tapped<'a, S, Pacer>;

impl Tap for Pacer {
    fn before_row<S: Sink + ?Sized>(
        &mut self,
        row: &Row<'_>,
        _frame: Option<&Unframed<'_>>,
        inner: &mut S,
    ) -> RowResult {
        if let Some(t) = row.micros {
            while let Some(wait) = self.due_in(t, Instant::now()) {
                if crate::signal::Stop::received().is_some() {
                    self.turn_off();
                    break;
                }
                // What is due is visible while the next row waits.
                inner.flush()?;
                std::thread::sleep(wait.min(Duration::from_millis(50)));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_due_at_their_capture_time_over_the_speed() {
        let t = Instant::now();
        let mut p = Pacer::new(2.0).unwrap();
        assert_eq!(
            p.due_in(1_000_000, t),
            None,
            "the first row sets the origin"
        );
        assert_eq!(p.due_in(2_000_000, t), Some(Duration::from_millis(500)));
        assert_eq!(p.due_in(2_000_000, t + Duration::from_millis(500)), None);
        // Time going back (a log's clock): due at once.
        assert_eq!(p.due_in(500_000, t + Duration::from_millis(600)), None);
    }

    #[test]
    fn long_silences_are_cut_to_one_second() {
        let t = Instant::now();
        let mut p = Pacer::new(1.0).unwrap();
        p.due_in(0, t);
        assert_eq!(p.due_in(3_600_000_000, t), Some(Duration::from_secs(1)));
        assert_eq!(
            p.due_in(3_601_000_000, t),
            Some(Duration::from_secs(2)),
            "then the capture's pace again"
        );
    }

    #[test]
    fn holding_shifts_the_replay() {
        let t = Instant::now();
        let mut p = Pacer::new(1.0).unwrap();
        p.due_in(0, t);
        p.hold(t);
        assert!(p.due_in(0, t + Duration::from_secs(5)).is_some(), "held");
        p.release(t + Duration::from_secs(5));
        assert_eq!(
            p.due_in(1_000_000, t + Duration::from_secs(5)),
            Some(Duration::from_secs(1))
        );
        p.turn_off();
        assert_eq!(p.due_in(9_000_000, t), None);
        assert!(Pacer::new(0.0).is_none());
    }
}
