//! Stages in front of a sink (`--speed`, `--export`): a [`Tap`] sees every row first, and
//! [`Tapped`] forwards the [`Sink`] calls, so each tap holds only what it adds.

use super::Sink;
use crate::row::{OutputError, Row, RowOut, RowResult, Unframed};
use crate::time::Anchor;

/// A stage a row passes on its way into the sink it wraps (pacing, exporting): it sees every row
/// first and flushes its own output before the sink does. [`Tapped`] forwards the [`Sink`] calls,
/// so a tap writes only what it adds.
pub trait Tap {
    /// Runs before `inner` takes the row (and the frame's content, when the decoder handed it
    /// on: [`RowOut::row_unframed`]): may wait (flushing `inner` meanwhile) or write the row
    /// elsewhere. An error stops the run as a sink's would.
    fn before_row<S: Sink + ?Sized>(
        &mut self,
        row: &Row<'_>,
        frame: Option<&Unframed<'_>>,
        inner: &mut S,
    ) -> RowResult;
    /// Flushes what the tap writes; runs before the sink flushes or closes.
    fn flush(&mut self) -> Result<(), OutputError> {
        Ok(())
    }
    /// The wall-clock time of the capture's start became known (before the sink hears it).
    fn set_anchor(&mut self, _anchor: Option<Anchor>) {}
}

/// A sink with a [`Tap`] in front of it.
pub struct Tapped<'a, S: Sink + ?Sized, T: Tap> {
    pub inner: &'a mut S,
    pub tap: T,
}

impl<S: Sink + ?Sized, T: Tap> RowOut for Tapped<'_, S, T> {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        self.tap.before_row(row, None, self.inner)?;
        self.inner.row(row)
    }

    fn row_unframed(&mut self, row: &Row<'_>, frame: &Unframed<'_>) -> RowResult {
        self.tap.before_row(row, Some(frame), self.inner)?;
        self.inner.row_unframed(row, frame)
    }
}

impl<S: Sink + ?Sized, T: Tap> Sink for Tapped<'_, S, T> {
    fn flush(&mut self) -> Result<(), OutputError> {
        self.tap.flush()?;
        self.inner.flush()
    }
    fn close(&mut self) -> Result<(), OutputError> {
        self.tap.flush()?;
        self.inner.close()
    }
    fn set_anchor(&mut self, anchor: Option<Anchor>) {
        self.tap.set_anchor(anchor);
        self.inner.set_anchor(anchor)
    }
    fn quit(&self) -> bool {
        self.inner.quit()
    }
    fn skip(&mut self) {
        self.inner.skip()
    }
}
