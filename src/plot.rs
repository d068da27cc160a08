//! `busnoop plot`: the numbers of a capture as time series, one panel per unit, with the moments
//! of broken frames (bad CRC, truncated, garbage) marked, as SVG or PNG (plotters, pure Rust).
//!
//! The series are the rows' [`Part`](crate::row::Part)s, the same numbers as the wide table's
//! columns (`Cell1@8` when two IDs send the same name). A frame whose check failed carries no
//! number; its moment is a red vertical line in every panel.

use std::collections::{BTreeMap, HashMap};
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
    /// Names of the numbers to plot (`Alt`, `Cell1`, `Cell1@8`); empty: every number.
    pub sensors: Vec<String>,
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
    if ImageFormat::of(path).is_none() {
        return Err(Failure::Usage(format!(
            "-o {}: {IMAGE_NAMES}",
            path.display()
        )));
    }
    // The image goes to a temporary file beside it, renamed over it at the end: the folder must
    // take a new file, and an image already there must be writable (a FIFO, a device: written
    // directly). Found only after decoding, the whole input was wasted.
    if special(path) {
        return Ok(());
    }
    let cannot =
        |e: std::io::Error| Failure::Output(format!("cannot create {}: {e}", path.display()));
    if std::fs::symlink_metadata(path).is_ok() {
        std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(cannot)?;
    }
    let (probe, _) = temporary(path).map_err(cannot)?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// A FIFO, a device or another file that is not a regular file (or a link to one): written
/// directly, never replaced.
fn special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file())
}

/// A new file beside `path` for the image (`.NAME.busnoop-PID-N.tmp`), created exclusively;
/// renamed over `path` once whole.
fn temporary(path: &Path) -> std::io::Result<(PathBuf, std::fs::File)> {
    use std::os::unix::fs::OpenOptionsExt;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map_or_else(|| "plot".into(), |n| n.to_string_lossy().into_owned());
    let mut n = 0u32;
    loop {
        let tmp = dir.join(format!(".{name}.busnoop-{}-{n}.tmp", std::process::id()));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o644)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 1000 => n += 1,
            Err(e) => return Err(e),
        }
    }
}

/// Writes the finished image to `path`: a regular file (or a new name) through a temporary file
/// beside it, renamed over it, so that a full disk or a kill leaves the old image whole and no
/// cut one; a FIFO or device directly, opened so that SIGINT/SIGTERM end the wait for a FIFO's
/// reader ([`crate::sink::create_file`]).
fn write_image(path: &Path, bytes: &[u8]) -> Result<(), Failure> {
    use std::io::Write;
    let failed =
        |e: std::io::Error| Failure::Output(format!("cannot write {}: {e}", path.display()));
    if special(path) {
        let mut f = crate::sink::create_file(path)
            .map_err(|e| Failure::from_create(&format!("cannot create {}", path.display()), &e))?;
        return f.write_all(bytes).map_err(failed);
    }
    let (tmp, mut f) = temporary(path)
        .map_err(|e| Failure::Output(format!("cannot create {}: {e}", path.display())))?;
    let written = f
        .write_all(bytes)
        .and_then(|()| f.sync_all())
        .and_then(|()| std::fs::rename(&tmp, path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(failed(e));
    }
    Ok(())
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

/// The most series a plot draws: 64 lines are already more than a reader tells apart, and
/// each series keeps up to [`MAX_POINTS`] points. Without a bound, a crafted capture of
/// thousands of numbers took a minute (a linear search per number) and drew an SVG of tens of
/// megabytes.
pub const MAX_SERIES: usize = 64;

/// Collects the rows of a capture, then draws them.
pub struct Plot {
    spec: PlotSpec,
    series: Vec<Series>,
    /// (ID, name, unit) → index in `series`.
    index: HashMap<(Option<u32>, String, String), usize>,
    /// Series per name and unit: more than one is a name shared by several IDs (`Name@ID`).
    names: HashMap<(String, String), u32>,
    /// Lookup without allocating.
    probe: (Option<u32>, String, String),
    /// Numbers of series beyond [`MAX_SERIES`], left out.
    left_out: u64,
    /// Numbers `--sensor` did not ask for, in order of appearance (at most [`MAX_OTHERS`]), to
    /// name them when it asked for none the capture has.
    others: Vec<(Option<u32>, String, String)>,
    errors: Thinned,
}

/// Numbers that `--sensor` did not ask for, kept to name them.
const MAX_OTHERS: usize = 256;

impl Plot {
    pub fn new(spec: PlotSpec) -> Self {
        Plot {
            spec,
            series: Vec::new(),
            index: HashMap::new(),
            names: HashMap::new(),
            probe: (None, String::new(), String::new()),
            left_out: 0,
            others: Vec::new(),
            errors: Thinned::default(),
        }
    }

    pub fn row(&mut self, row: &Row<'_>) {
        let Some(us) = row.micros else { return };
        let t = us as f64 / 1e6;
        if row.class == Class::Error {
            self.errors.push(t, 0.0);
            // An error row carries no number (Row::parts); none is plotted all the same.
            return;
        }
        for p in row.parts {
            if !p.value.is_finite() {
                continue;
            }
            if !self.wanted(row.id, p.name) {
                let key = (row.id, p.name, p.unit);
                if self.others.len() < MAX_OTHERS
                    && !self.others.iter().any(|o| (o.0, &*o.1, &*o.2) == key)
                {
                    self.others
                        .push((row.id, p.name.to_owned(), p.unit.to_owned()));
                }
                continue;
            }
            self.probe.0 = row.id;
            self.probe.1.clear();
            self.probe.1.push_str(p.name);
            self.probe.2.clear();
            self.probe.2.push_str(p.unit);
            let i = match self.index.get(&self.probe) {
                Some(&i) => i,
                None if self.series.len() >= MAX_SERIES => {
                    self.left_out += 1;
                    continue;
                }
                None => {
                    self.series.push(Series {
                        id: row.id,
                        name: p.name.to_owned(),
                        unit: p.unit.to_owned(),
                        points: Thinned::default(),
                    });
                    self.index.insert(self.probe.clone(), self.series.len() - 1);
                    *self
                        .names
                        .entry((p.name.to_owned(), p.unit.to_owned()))
                        .or_insert(0) += 1;
                    self.series.len() - 1
                }
            };
            self.series[i].points.push(t, p.value);
        }
    }

    /// Whether `--sensor` asks for the number `name` of `id` (by its name, or as `name@ID`).
    fn wanted(&self, id: Option<u32>, name: &str) -> bool {
        let sensors = &self.spec.sensors;
        sensors.is_empty()
            || sensors.iter().any(|w| {
                w == name
                    || w.split_once('@').is_some_and(|(n, i)| {
                        n == name && id.is_some_and(|id| i.parse::<u32>() == Ok(id))
                    })
            })
    }

    /// Numbers left out because the plot had [`MAX_SERIES`] series already (tests).
    #[cfg(test)]
    pub fn left_out(&self) -> u64 {
        self.left_out
    }

    /// `Name`, or `Name@ID` when another ID has a series of that name and unit.
    fn label(&self, s: &Series) -> String {
        let shared = self
            .names
            .get(&(s.name.clone(), s.unit.clone()))
            .is_some_and(|&n| n > 1);
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
        // A signal that comes while drawing ends it (one that came before asked for the plot
        // of what was read so far).
        let before = crate::signal::Stop::received();
        self.draw_until(&|| crate::signal::Stop::received().filter(|s| Some(*s) != before))
    }

    /// [`Plot::draw`], given up without an image when `stop` names a signal (checked between
    /// the series).
    fn draw_until(&self, stop: &dyn Fn() -> Option<i32>) -> Result<(), Failure> {
        let chosen: Vec<(String, &Series)> = self
            .series
            .iter()
            .map(|s| (self.label(s), s))
            .filter(|(l, s)| {
                self.spec.sensors.is_empty()
                    || self.spec.sensors.iter().any(|w| w == l || *w == s.name)
            })
            .collect();
        if chosen.is_empty() {
            let mut seen: Vec<String> = Vec::new();
            for (id, name, unit) in &self.others {
                let shared = self
                    .others
                    .iter()
                    .any(|o| o.1 == *name && o.2 == *unit && o.0 != *id);
                let label = match (shared, id) {
                    (true, Some(id)) => format!("{name}@{id}"),
                    _ => name.clone(),
                };
                if !seen.contains(&label) {
                    seen.push(label);
                }
            }
            return Err(if seen.is_empty() {
                Failure::NothingDecoded("no row of this capture carries a number to plot".into())
            } else {
                Failure::Usage(format!(
                    "no number named {} in this capture; it has: {}",
                    self.spec.sensors.join(","),
                    seen.join(",")
                ))
            });
        }
        let format = ImageFormat::of(&self.spec.path).ok_or_else(|| {
            Failure::Usage(format!("-o {}: {IMAGE_NAMES}", self.spec.path.display()))
        })?;
        if self.left_out > 0 {
            eprintln!(
                "busnoop: note: plot: the first {MAX_SERIES} series are drawn; {} {} of other \
                 series left out (choose with --sensor NAME,…)",
                self.left_out,
                if self.left_out == 1 {
                    "number"
                } else {
                    "numbers"
                }
            );
        }
        // Both backends measure text with this font (the SVG names it, a viewer draws it).
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .map_err(|_| Failure::Internal("cannot load the embedded font".into()))?;
        let size = (1000, 300 * panels(&chosen).len() as u32 + 60);
        // Drawn in memory, then written whole ([`write_image`]).
        let drawn = match format {
            ImageFormat::Svg => {
                let mut svg = String::new();
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                self.render(root, &chosen, stop).map(|()| svg.into_bytes())
            }
            ImageFormat::Png => {
                let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
                let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
                self.render(root, &chosen, stop)
                    .and_then(|()| png(&rgb, size).map_err(Into::into))
            }
        };
        if let Some(sig) = stop() {
            return Err(Failure::Signal(crate::exit::Interrupt::new(sig)));
        }
        let bytes = drawn.map_err(|e| {
            Failure::Internal(format!("cannot draw {}: {e}", self.spec.path.display()))
        })?;
        write_image(&self.spec.path, &bytes)
    }

    fn render<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
        chosen: &[(String, &Series)],
        stop: &dyn Fn() -> Option<i32>,
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
                if stop().is_some() {
                    return Err("stopped by a signal".into());
                }
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

/// A PNG of an RGB image of `size` pixels.
fn png(rgb: &[u8], size: (u32, u32)) -> Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, size.0, size.1);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header()?;
    w.write_image_data(rgb)?;
    w.finish()?;
    Ok(out)
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
            sensors: vec![],
            path: path.clone(),
            title: "t".into(),
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

    /// M2 (issue 32): at most MAX_SERIES series, found through a map; the numbers of the rest
    /// are counted; labels still carry the ID when a name is shared.
    #[test]
    fn series_are_capped_and_counted() {
        let mut p = Plot::new(PlotSpec::default());
        let names: Vec<&'static [Part<'static>]> = (0..200)
            .map(|i| {
                let name: &'static str = format!("N{}", i % 100).leak();
                &*vec![Part {
                    name,
                    unit: "V",
                    text: "1",
                    value: 1.0,
                }]
                .leak()
            })
            .collect();
        for round in 0..3u64 {
            for (i, parts) in names.iter().enumerate() {
                let mut r = row(round * 1000 + i as u64, Class::Plain, parts);
                r.id = Some((i / 100) as u32);
                p.row(&r);
            }
        }
        assert_eq!(p.series.len(), MAX_SERIES);
        assert_eq!(p.left_out(), 3 * (200 - MAX_SERIES as u64));
        assert!(p.series.iter().all(|s| s.points.kept.len() == 3));
        assert_eq!(p.label(&p.series[0]), "N0");
        // An error row carries no number into the plot.
        let mut bad = row(5000, Class::Error, ALT1);
        bad.id = Some(0);
        p.row(&bad);
        assert!(!p.series.iter().any(|s| s.name == "Alt"));
    }

    /// A signal while drawing gives the drawing up: no image, the signal's failure.
    #[test]
    fn a_signal_while_drawing_leaves_no_image() {
        let dir = tempfile::tempdir().unwrap();
        for (k, name) in ["p.svg", "p.png"].into_iter().enumerate() {
            let path = dir.path().join(name);
            let mut p = Plot::new(PlotSpec {
                sensors: vec![],
                path: path.clone(),
                title: "t".into(),
            });
            p.row(&row(0, Class::Plain, ALT1));
            p.row(&row(1_000_000, Class::Plain, ALT2));
            let r = p.draw_until(&|| Some(libc::SIGTERM));
            assert!(matches!(r, Err(Failure::Signal(ref i)) if i.signal == libc::SIGTERM));
            assert!(!path.exists());
            assert_eq!(
                std::fs::read_dir(dir.path()).unwrap().count(),
                k,
                "no temporary file"
            );
            p.draw_until(&|| None).unwrap();
            assert!(path.exists());
        }
    }

    /// A broken frame's moment is a red vertical line across the panel.
    #[test]
    fn broken_frames_are_marked() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.svg");
        let mut p = Plot::new(PlotSpec {
            sensors: vec!["Alt".into()],
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
