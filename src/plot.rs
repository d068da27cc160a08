//! `busnoop plot`: the numbers of a capture as time series, one panel per unit, with the moments
//! of broken frames (bad CRC, truncated, garbage) marked, as SVG or PNG (plotters, pure Rust).
//!
//! The series are the rows' [`Part`](crate::row::Part)s, the same numbers as the wide table's
//! columns (`Cell1@8` when two IDs send the same name). A frame whose check failed carries no
//! number; its moment is a red vertical line in every panel.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::exit::Failure;
use crate::row::{Class, Row};

/// The DejaVu Sans font (Bitstream Vera licence, assets/DejaVuSans-LICENSE.txt) for the PNG's
/// text: the bitmap backend draws with it, without any font of the system.
const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// What to plot and where.
#[derive(Clone, Debug, Default)]
pub struct PlotSpec {
    /// Names of the numbers to plot as the user gave them (`Alt`, `Cell1`, `Cell1@8`, or a
    /// Sensor column name such as `Volts`); empty: every number.
    pub sensors: Vec<String>,
    /// The series names they select: each name, and for a sensor of the protocol's vocabulary
    /// the names of all its numbers (`Volts` → `VFAS`). Compared without case.
    pub wanted: Vec<String>,
    pub path: PathBuf,
    pub title: String,
}

/// The image formats `busnoop plot` writes, by the file's extension (any case).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ImageFormat {
    Svg,
    Png,
}

impl ImageFormat {
    fn of(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_str()?;
        if ext.eq_ignore_ascii_case("svg") {
            Some(ImageFormat::Svg)
        } else if ext.eq_ignore_ascii_case("png") {
            Some(ImageFormat::Png)
        } else {
            None
        }
    }
}

const IMAGE_NAMES: &str = "plot writes .svg or .png: name the file FLIGHT.svg or FLIGHT.png";

/// Checks the image's name before the capture is read: the image is drawn only at the end, and
/// finding then that it cannot be would waste the whole input (a pipe cannot be read twice). A
/// name without `.svg`/`.png` is a usage error (exit 2). Its folder is checked with the other
/// outputs' before the input is opened (`cli::run_capture`).
pub fn check(path: &Path) -> Result<(), Failure> {
    match ImageFormat::of(path) {
        Some(_) => Ok(()),
        None => Err(Failure::Usage(format!(
            "-o {}: {IMAGE_NAMES}",
            path.display()
        ))),
    }
}

/// The most points a series keeps, and the most broken-frame marks: the image is 1000 pixels
/// wide, so a plot of more says nothing more.
const MAX_POINTS: usize = 16_384;

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
struct Thinned {
    kept: Vec<(f64, f64)>,
}

impl Thinned {
    fn push(&mut self, t: f64, v: f64) {
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

    fn is_empty(&self) -> bool {
        self.kept.is_empty()
    }

    fn iter(&self) -> std::slice::Iter<'_, (f64, f64)> {
        self.kept.iter()
    }
}

/// One series: its label, unit and points (seconds, value).
#[derive(Debug, Default)]
struct Series {
    id: Option<u32>,
    name: String,
    unit: String,
    points: Thinned,
}

/// Collects the rows of a capture, then draws them.
pub struct Plot {
    spec: PlotSpec,
    series: Vec<Series>,
    errors: Thinned,
}

impl Plot {
    pub fn new(spec: PlotSpec) -> Self {
        Plot {
            spec,
            series: Vec::new(),
            errors: Thinned::default(),
        }
    }

    pub fn row(&mut self, row: &Row<'_>) {
        let Some(us) = row.micros else { return };
        let t = us as f64 / 1e6;
        if row.class == Class::Error {
            self.errors.push(t, 0.0);
        }
        for p in row.parts {
            if !p.value.is_finite() {
                continue;
            }
            let i = match self
                .series
                .iter()
                .position(|s| s.id == row.id && s.name == p.name && s.unit == p.unit)
            {
                Some(i) => i,
                None => {
                    self.series.push(Series {
                        id: row.id,
                        name: p.name.to_owned(),
                        unit: p.unit.to_owned(),
                        points: Thinned::default(),
                    });
                    self.series.len() - 1
                }
            };
            self.series[i].points.push(t, p.value);
        }
    }

    /// `Name`, or `Name@ID` when another ID has a series of that name and unit.
    fn label(&self, s: &Series) -> String {
        let shared = self
            .series
            .iter()
            .any(|o| o.name == s.name && o.unit == s.unit && o.id != s.id);
        match (shared, s.id) {
            (true, Some(id)) => format!("{}@{id}", s.name),
            _ => s.name.clone(),
        }
    }

    /// Draws the plot into the spec's file (`.svg` or `.png`). Nothing to draw is no failed
    /// write: a capture without numbers is [`Failure::NothingDecoded`] (exit 10), sensor names it
    /// does not have a usage error (exit 2, with the names it has); a drawing that cannot be
    /// written is [`Failure::Output`] (exit 8).
    pub fn draw(&self) -> Result<(), Failure> {
        let chosen: Vec<(String, &Series)> = self
            .series
            .iter()
            .map(|s| (self.label(s), s))
            .filter(|(l, s)| {
                self.spec.sensors.is_empty()
                    || self
                        .spec
                        .wanted
                        .iter()
                        .any(|w| w.eq_ignore_ascii_case(l) || w.eq_ignore_ascii_case(&s.name))
            })
            .collect();
        if chosen.is_empty() {
            let mut seen: Vec<String> = self.series.iter().map(|s| self.label(s)).collect();
            seen.dedup();
            return Err(if seen.is_empty() {
                Failure::NothingDecoded("no row of this capture carries a number to plot".into())
            } else {
                let near = self.spec.sensors.iter().find_map(|w| {
                    crate::protocol::vocab::did_you_mean(w, seen.iter().map(String::as_str))
                });
                Failure::Usage(format!(
                    "no number named {} in this capture{}; it has: {}",
                    self.spec.sensors.join(","),
                    near.map_or(String::new(), |n| format!(" (did you mean {n}?)")),
                    seen.join(",")
                ))
            });
        }
        let format = ImageFormat::of(&self.spec.path).ok_or_else(|| {
            Failure::Usage(format!("-o {}: {IMAGE_NAMES}", self.spec.path.display()))
        })?;
        // Both backends measure text with this font (the SVG names it, a viewer draws it).
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .map_err(|_| Failure::Internal("cannot load the embedded font".into()))?;
        let size = (1000, 300 * panels(&chosen).len() as u32 + 60);
        let r = match format {
            ImageFormat::Svg => {
                let root = SVGBackend::new(&self.spec.path, size).into_drawing_area();
                self.render(root, &chosen)
            }
            ImageFormat::Png => {
                let root = BitMapBackend::new(&self.spec.path, size).into_drawing_area();
                self.render(root, &chosen)
            }
        };
        r.map_err(|e| Failure::Output(format!("cannot draw {}: {e}", self.spec.path.display())))
    }

    fn render<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
        chosen: &[(String, &Series)],
    ) -> Result<(), Box<dyn std::error::Error + 'static>>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let root = root.titled(&self.spec.title, ("sans-serif", 22))?;
        let groups = panels(chosen);
        let areas = root.split_evenly((groups.len(), 1));
        let t_end = chosen
            .iter()
            .flat_map(|(_, s)| s.points.iter().map(|p| p.0))
            .chain(self.errors.iter().map(|p| p.0))
            .fold(0.0f64, f64::max)
            .max(1e-3);
        for ((unit, members), area) in groups.iter().zip(areas.iter()) {
            let (lo, hi) = members
                .iter()
                .flat_map(|(_, s)| s.points.iter().map(|p| p.1))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            let pad = ((hi - lo) * 0.05).max(hi.abs().max(1.0) * 1e-3);
            let (lo, hi) = (lo - pad, hi + pad);
            let mut chart = ChartBuilder::on(area)
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(0.0..t_end, lo..hi)?;
            let y_desc = if unit.is_empty() {
                members
                    .iter()
                    .map(|(l, _)| l.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            } else {
                format!("({unit})")
            };
            chart
                .configure_mesh()
                .x_desc("time since the capture's start (s)")
                .y_desc(y_desc)
                .label_style(("sans-serif", 14))
                .draw()?;
            for (k, (label, s)) in members.iter().enumerate() {
                let color = Palette99::pick(k).to_rgba();
                let name = if unit.is_empty() {
                    label.clone()
                } else {
                    format!("{label} ({unit})")
                };
                chart
                    .draw_series(LineSeries::new(
                        s.points.iter().copied(),
                        color.stroke_width(2),
                    ))?
                    .label(name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            }
            if !self.errors.is_empty() {
                chart
                    .draw_series(self.errors.iter().map(|&(t, _)| {
                        PathElement::new(vec![(t, lo), (t, hi)], RED.mix(0.6).stroke_width(1))
                    }))?
                    .label("broken frame (bad CRC, truncated)")
                    .legend(|(x, y)| PathElement::new(vec![(x, y - 6), (x, y + 6)], RED));
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .draw()?;
        }
        root.present()?;
        Ok(())
    }
}

/// The chosen series grouped by unit, in order of first appearance.
fn panels<'a>(chosen: &'a [(String, &'a Series)]) -> Vec<(String, Vec<&'a (String, &'a Series)>)> {
    let mut order: Vec<String> = Vec::new();
    let mut by: BTreeMap<String, Vec<&(String, &Series)>> = BTreeMap::new();
    for c in chosen {
        if !by.contains_key(&c.1.unit) {
            order.push(c.1.unit.clone());
        }
        by.entry(c.1.unit.clone()).or_default().push(c);
    }
    order
        .into_iter()
        .map(|u| {
            let v = by.remove(&u).unwrap_or_default();
            (u, v)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::row::Part;

    fn row(us: u64, class: Class, parts: &'static [Part<'static>]) -> Row<'static> {
        Row {
            stamp: 0,
            micros: Some(us),
            id: Some(0),
            device: "",
            kind: "",
            class,
            sensor_no: "",
            sensor: "",
            data: "",
            extra: &[],
            parts: parts.into(),
            raw: &[],
        }
    }

    const ALT1: &[Part<'static>] = &[Part {
        name: "Alt",
        unit: "m",
        text: "10",
        value: 10.0,
    }];
    const ALT2: &[Part<'static>] = &[Part {
        name: "Alt",
        unit: "m",
        text: "20",
        value: 20.0,
    }];

    /// A long or noisy capture: the points of a series and the broken frames' marks are thinned
    /// to at most [`MAX_POINTS`] each (the image is 1000 pixels wide). They used to be kept
    /// all: memory grew with the capture, and `busnoop plot /dev/urandom` drew an SVG of
    /// gigabytes, a red line per broken frame.
    #[test]
    fn long_captures_are_thinned_to_a_bounded_plot() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.svg");
        let mut p = Plot::new(PlotSpec {
            path: path.clone(),
            title: "t".into(),
            ..PlotSpec::default()
        });
        let n = 300_000u64;
        for i in 0..n {
            p.row(&row(i * 10_000, Class::Plain, ALT1));
            p.row(&row(i * 10_000 + 5_000, Class::Error, &[]));
        }
        let points = &p.series[0].points.kept;
        assert!(points.len() <= MAX_POINTS && points.len() > MAX_POINTS / 8);
        assert!(p.errors.kept.len() <= MAX_POINTS && p.errors.kept.len() > MAX_POINTS / 8);
        // Spread over the whole capture, in time order.
        assert_eq!(points[0].0, 0.0);
        assert!(points.last().unwrap().0 > (n - 100) as f64 * 0.01);
        assert!(points.windows(2).all(|w| w[0].0 < w[1].0));
        p.draw().unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        assert!(size < 8_000_000, "{size} bytes");
    }

    /// Thinning keeps what the eye looks for: a one-sample spike and dip in a long flat series,
    /// and a lone broken frame after a burst of them (every other point dropped would lose each
    /// of them half the time, or more).
    #[test]
    fn thinning_keeps_spikes_dips_and_lone_marks() {
        let mut s = Thinned::default();
        let mut marks = Thinned::default();
        let n = 1_000_000u64;
        let (spike, dip) = (123_457, 876_543);
        for i in 0..n {
            let t = i as f64 * 0.01;
            let v = match i {
                _ if i == spike => 100.0,
                _ if i == dip => -50.0,
                _ => (i % 7) as f64,
            };
            s.push(t, v);
            if i < n / 2 || i == n - 3 {
                marks.push(t, 0.0);
            }
        }
        assert!(s.kept.len() <= MAX_POINTS);
        assert!(s.kept.contains(&(spike as f64 * 0.01, 100.0)), "spike lost");
        assert!(s.kept.contains(&(dip as f64 * 0.01, -50.0)), "dip lost");
        // The envelope of the rest: its lowest and highest values are still there.
        assert!(s.kept.iter().any(|p| p.1 == 0.0) && s.kept.iter().any(|p| p.1 == 6.0));
        assert!(marks.kept.len() <= MAX_POINTS);
        assert!(
            marks.kept.contains(&((n - 3) as f64 * 0.01, 0.0)),
            "the lone mark was lost"
        );
    }

    /// Times out of order (a capture whose clock jumps back and forth) cannot be merged by cell,
    /// and the bound still holds.
    #[test]
    fn thinning_is_bounded_whatever_the_order_of_times() {
        let mut s = Thinned::default();
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            s.push((x % 1_000_000) as f64, (x >> 40) as f64);
            assert!(s.kept.len() <= MAX_POINTS);
        }
        assert!(s.kept.len() > MAX_POINTS / 8);
    }

    /// A broken frame's moment is a red vertical line across the panel.
    #[test]
    fn broken_frames_are_marked() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.svg");
        let mut p = Plot::new(PlotSpec {
            sensors: vec!["Alt".into()],
            wanted: vec!["Alt".into()],
            path: path.clone(),
            title: "t".into(),
        });
        p.row(&row(0, Class::Plain, ALT1));
        p.row(&row(1_000_000, Class::Error, &[]));
        p.row(&row(2_000_000, Class::Plain, ALT2));
        p.draw().unwrap();
        let svg = std::fs::read_to_string(path).unwrap();
        let series: Vec<&str> = svg
            .split("<polyline")
            .filter(|l| l.contains("stroke-width=\"2\""))
            .collect();
        assert_eq!(series.len(), 1);
        let xs: Vec<f64> = series[0]
            .split("points=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .split_whitespace()
            .map(|xy| xy.split(',').next().unwrap().parse().unwrap())
            .collect();
        let mid = (xs[0] + xs[1]) / 2.0;
        let red: Vec<&str> = svg
            .split("<polyline")
            .filter(|l| l.contains("stroke=\"#FF0000\""))
            .collect();
        assert!(
            red.iter().any(|l| {
                let pts = l
                    .split("points=\"")
                    .nth(1)
                    .unwrap()
                    .split('"')
                    .next()
                    .unwrap();
                let x: Vec<f64> = pts
                    .split_whitespace()
                    .map(|xy| xy.split(',').next().unwrap().parse().unwrap())
                    .collect();
                x.len() == 2 && x[0] == x[1] && (x[0] - mid).abs() <= 1.0
            }),
            "a red vertical line at t = 1 s: {red:?}"
        );
    }
}
