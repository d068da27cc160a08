//! When to stop before the input ends: after N frames (`-c`), after a stretch of capture time
//! (`--duration`), or when no frame came for a while (`--until-idle`), as candump and tshark
//! stop. A sink in front of the table: it passes rows until a condition holds, then asks the
//! driver to end ([`Sink::quit`]) and keeps what the decoder still flushes out of the table.

use std::time::{Duration, Instant};

use super::Sink;
use crate::row::{Direct, OutputError, Row, RowOut, RowResult, Unframed};

/// The stop conditions of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stops {
    /// Frames (rows with bytes from the wire) to write.
    pub count: Option<u64>,
    /// Capture time (a live line: time since the start).
    pub duration: Option<Duration>,
    /// The longest time without a frame.
    pub idle: Option<Duration>,
}

/// A sink that stops the run when one of the [`Stops`] holds.
pub struct Limit<'a> {
    inner: &'a mut dyn Sink,
    stops: Stops,
    /// A live line: the conditions also hold by the clock while nothing arrives.
    live: bool,
    frames: u64,
    started: Instant,
    last: Instant,
    last_micros: Option<u64>,
    done: bool,
    /// No stop condition and not done: the table's output may be lent ([`RowOut::direct`]).
    lend: bool,
}

impl<'a> Limit<'a> {
    pub fn new(inner: &'a mut dyn Sink, stops: Stops, live: bool) -> Self {
        let now = Instant::now();
        Limit {
            inner,
            stops,
            live,
            frames: 0,
            started: now,
            last: now,
            last_micros: None,
            done: false,
            lend: stops == Stops::default(),
        }
    }

    /// `inner` behind a limit (kept in `slot`) when `stops` has a condition; else `inner`
    /// itself: a limit without one passes everything on, and left out, the decoder's request
    /// for the table's output (every row) reaches the table one call sooner.
    pub fn around(
        slot: &'a mut Option<Limit<'a>>,
        inner: &'a mut dyn Sink,
        stops: Stops,
        live: bool,
    ) -> &'a mut dyn Sink {
        if stops == Stops::default() {
            return inner;
        }
        slot.insert(Limit::new(inner, stops, live))
    }

    /// Whether `row` may pass; false once a condition holds (and from then on).
    fn admit(&mut self, row: &Row<'_>) -> bool {
        if self.done {
            return false;
        }
        let frame = !row.raw.is_empty();
        if let Some(t) = row.micros {
            let past = |d: Duration| t >= d.as_micros() as u64;
            let quiet = |d: Duration, last: Option<u64>| {
                frame && last.is_some_and(|l| t.saturating_sub(l) >= d.as_micros() as u64)
            };
            if self.stops.duration.is_some_and(past)
                || self.stops.idle.is_some_and(|d| quiet(d, self.last_micros))
            {
                self.done = true;
                self.lend = false;
                return false;
            }
        }
        true
    }

    /// After `row` passed.
    fn passed(&mut self, row: &Row<'_>) {
        if row.raw.is_empty() {
            return;
        }
        self.frames += 1;
        // The clock only for a live line's `--until-idle` ([`Sink::quit`]): a read per row
        // took 12-23 % of a replay's time.
        if self.live && self.stops.idle.is_some() {
            self.last = Instant::now();
        }
        if row.micros.is_some() {
            self.last_micros = row.micros;
        }
        if self.stops.count.is_some_and(|n| self.frames >= n) {
            self.done = true;
            self.lend = false;
        }
    }
}

impl RowOut for Limit<'_> {
    /// Without a stop condition nothing here reads the rows: the table's output is lent (a
    /// condition needs each row, and gets it as a [`Row`]).
    #[inline]
    fn direct(&mut self, columns: &'static [&'static str]) -> Option<Direct<'_>> {
        if !self.lend {
            return None;
        }
        self.inner.direct(columns)
    }

    fn row(&mut self, row: &Row<'_>) -> RowResult {
        if !self.admit(row) {
            return Ok(());
        }
        self.inner.row(row)?;
        self.passed(row);
        Ok(())
    }

    fn row_unframed(&mut self, row: &Row<'_>, frame: &Unframed<'_>) -> RowResult {
        if !self.admit(row) {
            return Ok(());
        }
        self.inner.row_unframed(row, frame)?;
        self.passed(row);
        Ok(())
    }
}

impl Sink for Limit<'_> {
    fn flush(&mut self) -> Result<(), OutputError> {
        self.inner.flush()
    }
    fn close(&mut self) -> Result<(), OutputError> {
        self.inner.close()
    }
    fn set_anchor(&mut self, anchor: Option<crate::time::Anchor>) {
        self.inner.set_anchor(anchor)
    }
    fn quit(&self) -> bool {
        if self.done || self.inner.quit() {
            return true;
        }
        // A live line that went quiet sends no rows to look at: the clock decides.
        self.live
            && (self
                .stops
                .duration
                .is_some_and(|d| self.started.elapsed() >= d)
                || self.stops.idle.is_some_and(|d| self.last.elapsed() >= d))
    }
    fn skip(&mut self) {
        if !self.done {
            self.inner.skip()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::Output;
    use crate::sink::{Format, Table, TableOptions};

    fn table() -> Table {
        Table::new(
            Output::memory(),
            TableOptions {
                format: Format::Tsv,
                color: false,
                raw: false,
                time_abs: false,
                utc: false,
            },
            &[],
        )
    }

    fn frame(ms: u64) -> Row<'static> {
        Row {
            raw: &[0x7E, 0x1B],
            kind: "Poll",
            ..Row::empty(Some(ms * 1000))
        }
    }

    fn run(stops: Stops, rows: &[Row<'_>]) -> (u64, bool) {
        let mut t = table();
        let mut l = Limit::new(&mut t, stops, false);
        for r in rows {
            l.row(r).unwrap();
        }
        let quit = l.quit();
        (t.rows(), quit)
    }

    #[test]
    fn count_duration_and_idle() {
        let rows: Vec<Row> = [0, 10, 20, 30, 1000, 1010].map(frame).to_vec();
        let count = Stops {
            count: Some(3),
            ..Stops::default()
        };
        assert_eq!(run(count, &rows), (3, true));
        let duration = Stops {
            duration: Some(Duration::from_millis(25)),
            ..Stops::default()
        };
        assert_eq!(run(duration, &rows), (3, true));
        let idle = Stops {
            idle: Some(Duration::from_millis(500)),
            ..Stops::default()
        };
        assert_eq!(run(idle, &rows), (4, true));
        assert_eq!(run(Stops::default(), &rows), (6, false));
        // Rows without bytes (a timeout) do not count as frames.
        let note = Row {
            kind: "Timeout",
            ..Row::empty(Some(5000))
        };
        let mixed = [frame(0), note, frame(1)];
        assert_eq!(run(count, &mixed), (3, false));
    }

    /// Limit sits in front of the table in every run and did not lend the table's output, so
    /// no protocol wrote its rows straight from the command line (every row went as a Row).
    /// Without a stop condition it lends it; with one, each row comes as a Row to be counted.
    #[test]
    fn the_table_is_lent_for_direct_rows_without_a_stop_condition() {
        let mut t = table();
        let mut l = Limit::new(&mut t, Stops::default(), false);
        // The header goes with the first row.
        l.row(&frame(0)).unwrap();
        assert!(l.direct(&[]).is_some());
        let mut t = table();
        let count = Stops {
            count: Some(3),
            ..Stops::default()
        };
        let mut l = Limit::new(&mut t, count, false);
        l.row(&frame(0)).unwrap();
        assert!(l.direct(&[]).is_none());
    }

    /// `Limit::around` leaves the limit out without a stop condition (the rows reach the table
    /// itself) and puts it in front with one (it stops the rows after the count).
    #[test]
    fn around_puts_a_limit_in_front_only_for_a_stop_condition() {
        let rows: Vec<Row> = [0, 10, 20, 30].map(frame).to_vec();
        let count = Stops {
            count: Some(2),
            ..Stops::default()
        };
        for (stops, passed, limited) in [(Stops::default(), 4, false), (count, 2, true)] {
            let mut t = table();
            let at: *const Table = &t;
            let mut slot = None;
            let sink = Limit::around(&mut slot, &mut t, stops, false);
            // Without a condition, the table itself.
            assert_eq!(std::ptr::addr_eq(&*sink, at), !limited, "{stops:?}");
            for r in &rows {
                sink.row(r).unwrap();
            }
            assert_eq!(sink.quit(), limited, "{stops:?}");
            assert_eq!(t.rows(), passed, "{stops:?}");
        }
    }
}
