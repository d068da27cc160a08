//! The points of a series, bounded: thinned by time so that the picture stays the same.

/// The most points a series keeps, and the most broken-frame marks: the image is 1000 pixels
/// wide, so a plot of more says nothing more.
pub(super) const MAX_POINTS: usize = 16_384;

/// Cells of time a full [`Thinned`] is cut into: four per pixel of the 1000-pixel-wide image.
const CELLS: f64 = (MAX_POINTS / 4) as f64;

/// Points (time, value) of a growing sequence, at most [`MAX_POINTS`], thinned by time so that
/// the picture stays the same: when full, the span so far is cut into [`CELLS`] equal cells,
/// and each run of points in one cell keeps its lowest and its highest point, in their order.
/// A one-sample spike or dip and a lone mark survive however long the capture (dropping every
/// other point would lose them half the time or more). Without a bound, memory grew with the
/// capture, and a noisy one drew an SVG of gigabytes (a red line per broken frame). Broken
/// frames' marks are kept with the value 0: one mark per cell.
#[derive(Debug, Default)]
pub(super) struct Thinned {
    pub(super) kept: Vec<(f64, f64)>,
}

impl Thinned {
    pub(super) fn push(&mut self, t: f64, v: f64) {
        self.kept.push((t, v));
        if self.kept.len() >= MAX_POINTS {
            self.thin();
        }
    }

    /// Keeps each cell's extremes; when the times are too far out of order for runs in one
    /// cell to form (a clock jumping back and forth), every other point, so that the bound
    /// holds whatever the input.
    fn thin(&mut self) {
        let kept = &self.kept;
        let (first, last) = kept
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            });
        let width = (last - first) / CELLS;
        // `as` saturates: a width of 0 puts every point in cell 0.
        let cell = |t: f64| {
            if width > 0.0 {
                ((t - first) / width) as u64
            } else {
                0
            }
        };
        let mut out = Vec::with_capacity(MAX_POINTS);
        let mut i = 0;
        while i < kept.len() {
            let c = cell(kept[i].0);
            let (mut lo, mut hi, mut j) = (i, i, i + 1);
            while j < kept.len() && cell(kept[j].0) == c {
                if kept[j].1 < kept[lo].1 {
                    lo = j;
                }
                if kept[j].1 > kept[hi].1 {
                    hi = j;
                }
                j += 1;
            }
            out.push(kept[lo.min(hi)]);
            if lo != hi {
                out.push(kept[lo.max(hi)]);
            }
            i = j;
        }
        if out.len() > MAX_POINTS / 2 + 2 {
            let mut keep = false;
            out.retain(|_| {
                keep = !keep;
                keep
            });
        }
        self.kept = out;
    }

    pub(super) fn is_empty(&self) -> bool {
        self.kept.is_empty()
    }

    pub(super) fn iter(&self) -> std::slice::Iter<'_, (f64, f64)> {
        self.kept.iter()
    }
}
