//! `busnoop plot`: the numbers of a capture as time series, as SVG or PNG (plotters, pure
//! Rust): panels by unit and by size (flags and counters apart from large values, at most
//! [`PER_PANEL`] series in one), each value drawn as a step held until the next sample with a
//! marker at every sample, the legend beside the data, the wall-clock time on the x axis where
//! the source has it, and the moments of broken frames (bad CRC, truncated, garbage) marked.
//!
//! The series are the rows' [`Part`](crate::row::Part)s, the same numbers as the wide table's
//! columns (`Cell1@8` when two IDs send the same name). A frame whose check failed carries no
//! number; its moment is a red vertical line in every panel.

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

use plotters::prelude::*;

use crate::exit::Failure;
use crate::row::{Class, Row};
use crate::time::Anchor;

mod image;
mod thin;

pub use image::check;
use image::{IMAGE_NAMES, ImageFormat, png, write_image};
use thin::Thinned;

/// The DejaVu Sans font (Bitstream Vera licence, assets/DejaVuSans-LICENSE.txt) for the PNG's
/// text: the bitmap backend draws with it, without any font of the system.
const FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// A moment of `--from`/`--to`: seconds since the capture's start, or a wall-clock time of day
/// (for sources that have one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum When {
    Seconds(f64),
    Clock(chrono::NaiveTime),
}

impl When {
    /// `90`, `1.5` (seconds since the start), `12:34:56` or `12:34:56.5` (time of day).
    pub fn parse(s: &str) -> Result<When, String> {
        let t = s.trim();
        if let Ok(v) = t.parse::<f64>()
            && v.is_finite()
            && v >= 0.0
        {
            return Ok(When::Seconds(v));
        }
        for f in ["%H:%M:%S%.f", "%H:%M"] {
            if let Ok(c) = chrono::NaiveTime::parse_from_str(t, f) {
                return Ok(When::Clock(c));
            }
        }
        Err(format!(
            "{s:?}: expected seconds since the capture's start (90, 1.5) or a time of day \
             (12:34:56)"
        ))
    }

    /// Seconds since the capture's start; a time of day needs the wall-clock time of the start
    /// (the first such moment after it).
    fn seconds(self, anchor: Option<Anchor>) -> Option<f64> {
        match self {
            When::Seconds(s) => Some(s),
            When::Clock(c) => {
                let start = local_start(anchor?);
                let mut at = start.date().and_time(c);
                if at < start {
                    at += chrono::Duration::days(1);
                }
                Some((at - start).num_microseconds()? as f64 / 1e6)
            }
        }
    }
}

/// The wall-clock time of the capture's start as shown: a radio's naive local time as logged,
/// an instant in local time.
fn local_start(anchor: Anchor) -> chrono::NaiveDateTime {
    match anchor {
        Anchor::Naive(n) => n,
        Anchor::Instant(t) => t.with_timezone(&chrono::Local).naive_local(),
    }
}

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
    /// The time range to draw (`--from`, `--to`).
    pub from: Option<When>,
    pub to: Option<When>,
}

/// One series: its label, unit and points (seconds, value).
#[derive(Debug, Default)]
struct Series {
    id: Option<u32>,
    /// The row's port (several sources), or "".
    port: String,
    name: String,
    unit: String,
    points: Thinned,
}

impl Series {
    /// The largest magnitude of its values (at least 1: values below one are one size).
    fn size(&self) -> f64 {
        self.points.iter().map(|p| p.1.abs()).fold(1.0f64, f64::max)
    }

    /// Only 0 and 1: a flag (a coil, an input, a status bit).
    fn is_flag(&self) -> bool {
        self.points.iter().all(|p| p.1 == 0.0 || p.1 == 1.0)
    }
}

/// At most this many series share a panel (a legend of more is not read).
pub const PER_PANEL: usize = 6;

/// The colours of a panel's series: strong and told apart (each panel starts again).
const COLORS: [RGBColor; PER_PANEL] = [
    RGBColor(0x1F, 0x77, 0xB4),
    RGBColor(0xD6, 0x27, 0x28),
    RGBColor(0x2C, 0xA0, 0x2C),
    RGBColor(0xFF, 0x7F, 0x0E),
    RGBColor(0x94, 0x67, 0xBD),
    RGBColor(0x3B, 0x3B, 0x3B),
];

/// Series in one panel differ in size by at most this factor: flags and counters (0, 1, 99)
/// do not share a panel with a register of 3.7e9, where they would be a flat line at zero.
const SIZE_SPREAD: f64 = 50.0;

/// The image's width, the width of the legend beside the panels, and a panel's height.
const WIDTH: u32 = 1200;
const LEGEND: u32 = 240;
const PANEL_HEIGHT: u32 = 280;
/// Font sizes of labels and of the title.
const LABEL_FONT: u32 = 14;
const TITLE_FONT: u32 = 22;
/// Markers are drawn at every sample when a series has at most this many points (more would be
/// a band of dots hiding the line).
const MARKERS_MAX: usize = 400;

/// The most series a plot draws: 64 lines are already more than a reader tells apart, and
/// each series keeps up to [`MAX_POINTS`](thin::MAX_POINTS) points. Without a bound, a crafted capture of
/// thousands of numbers took a minute (a linear search per number) and drew an SVG of tens of
/// megabytes.
pub const MAX_SERIES: usize = 64;

/// Collects the rows of a capture, then draws them.
pub struct Plot {
    spec: PlotSpec,
    series: Vec<Series>,
    /// Where each series is, by (ID, name, unit, port).
    index: HashMap<(Option<u32>, String, String, String), usize>,
    /// Lookup without allocating.
    probe: (Option<u32>, String, String, String),
    /// Numbers of series beyond [`MAX_SERIES`], left out.
    left_out: u64,
    /// Numbers `--sensor` did not ask for, in order of appearance (at most [`MAX_OTHERS`]), to
    /// name them when it asked for none the capture has.
    others: Vec<(Option<u32>, String, String)>,
    errors: Thinned,
    anchor: Option<Anchor>,
    /// Which extra cell of a row names its port (several sources).
    port_column: Option<usize>,
}

/// Numbers that `--sensor` did not ask for, kept to name them.
const MAX_OTHERS: usize = 256;

impl Plot {
    pub fn new(spec: PlotSpec) -> Self {
        Plot {
            spec,
            series: Vec::new(),
            index: HashMap::new(),
            probe: (None, String::new(), String::new(), String::new()),
            left_out: 0,
            others: Vec::new(),
            errors: Thinned::default(),
            anchor: None,
            port_column: None,
        }
    }

    /// Rows name their port in extra cell `column` ([`crate::row::PORT_COLUMN`]): each port's
    /// numbers are series of their own.
    pub fn port_column(&mut self, column: Option<usize>) {
        self.port_column = column;
    }

    /// The wall-clock time of the capture's start (the x axis shows times of day).
    pub fn set_anchor(&mut self, anchor: Option<Anchor>) {
        self.anchor = anchor;
    }

    /// The time range in seconds since the start, as far as it is known.
    fn range(&self) -> (f64, f64) {
        let from = self.spec.from.and_then(|w| w.seconds(self.anchor));
        let to = self.spec.to.and_then(|w| w.seconds(self.anchor));
        (
            from.unwrap_or(f64::NEG_INFINITY),
            to.unwrap_or(f64::INFINITY),
        )
    }

    /// Takes one row in. Not inlined into the table's `write`, whose long-table path stays as
    /// lean as without it.
    #[inline(never)]
    pub fn row(&mut self, row: &Row<'_>) {
        let Some(us) = row.micros else { return };
        let t = us as f64 / 1e6;
        let (from, to) = self.range();
        if t < from || t > to {
            return;
        }
        if row.class == Class::Error {
            self.errors.push(t, 0.0);
            // An error row carries no number (Row::parts); none is plotted all the same.
            return;
        }
        let port = self
            .port_column
            .and_then(|c| row.extra.get(c))
            .copied()
            .unwrap_or("");
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
            self.probe.3.clear();
            self.probe.3.push_str(port);
            let i = match self.index.get(&self.probe) {
                Some(&i) => i,
                None if self.series.len() >= MAX_SERIES => {
                    self.left_out += 1;
                    continue;
                }
                None => {
                    self.series.push(Series {
                        id: row.id,
                        port: port.to_owned(),
                        name: p.name.to_owned(),
                        unit: p.unit.to_owned(),
                        points: Thinned::default(),
                    });
                    self.index.insert(self.probe.clone(), self.series.len() - 1);
                    self.series.len() - 1
                }
            };
            self.series[i].points.push(t, p.value);
        }
    }

    /// Whether `--sensor` may ask for the number `name` of a row: by either of its names, or
    /// as a label (`Name@ID`, `Name@PORT`); [`Plot::chosen`] then keeps the exact ones.
    fn wanted(&self, _id: Option<u32>, name: &str) -> bool {
        self.spec.sensors.is_empty()
            || self.spec.wanted.iter().any(|w| {
                w.eq_ignore_ascii_case(name)
                    || w.split_once('@')
                        .is_some_and(|(n, _)| n.eq_ignore_ascii_case(name))
            })
    }

    /// Numbers left out because the plot had [`MAX_SERIES`] series already (tests).
    #[cfg(test)]
    pub fn left_out(&self) -> u64 {
        self.left_out
    }

    /// `Name`, or `Name@ID` when another ID of its port has a series of that name and unit,
    /// `Name@PORT` (or `Name@ID@PORT`) when another port has.
    fn label(&self, s: &Series) -> String {
        let same = || {
            self.series
                .iter()
                .filter(|o| o.name == s.name && o.unit == s.unit)
        };
        let by_id = same().any(|o| o.id != s.id && o.port == s.port);
        let by_port = same().any(|o| o.port != s.port);
        let mut label = s.name.clone();
        if by_id && let Some(id) = s.id {
            label.push_str(&format!("@{id}"));
        }
        if by_port {
            label.push('@');
            label.push_str(&s.port);
        }
        label
    }

    /// The series to draw, with their labels, in order of first appearance; a series without
    /// a point in a range given late (a time of day, known only once the anchor came) is left
    /// out.
    fn chosen(&self) -> Vec<(String, &Series)> {
        self.series
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
            .collect()
    }

    /// Draws the plot into the spec's file (`.svg` or `.png`). Nothing to draw is no failed
    /// write: a capture without numbers is [`Failure::NothingDecoded`] (exit 10), sensor names it
    /// does not have a usage error (exit 2, with the names it has); a drawing that cannot be
    /// written is [`Failure::Output`] (exit 8).
    pub fn draw(&mut self) -> Result<(), Failure> {
        // A signal that comes while drawing ends it (one that came before asked for the plot
        // of what was read so far).
        let before = crate::signal::Stop::received();
        self.draw_until(&|| crate::signal::Stop::received().filter(|s| Some(*s) != before))
    }

    /// [`Plot::draw`], given up without an image when `stop` names a signal (checked between
    /// the series).
    fn draw_until(&mut self, stop: &dyn Fn() -> Option<i32>) -> Result<(), Failure> {
        // A time of day given as the range: the points outside it, now that the start is known.
        let (from, to) = self.range();
        for s in &mut self.series {
            s.points.kept.retain(|p| p.0 >= from && p.0 <= to);
        }
        self.errors.kept.retain(|p| p.0 >= from && p.0 <= to);
        let chosen = self.chosen();
        if chosen.iter().all(|(_, s)| s.points.is_empty()) {
            let mut seen: Vec<String> = self.series.iter().map(|s| self.label(s)).collect();
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
            seen.dedup();
            return Err(if seen.is_empty() {
                Failure::NothingDecoded("no row of this capture carries a number to plot".into())
            } else if !chosen.is_empty() || self.spec.sensors.is_empty() {
                Failure::NothingDecoded(
                    "no number of this capture lies in the time range of --from/--to".into(),
                )
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
        let chosen: Vec<(String, &Series)> = chosen
            .into_iter()
            .filter(|(_, s)| !s.points.is_empty())
            .collect();
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
        let groups = panels(&chosen);
        let size = (WIDTH, PANEL_HEIGHT * groups.len() as u32 + 40);
        // Drawn in memory, then written whole ([`write_image`]).
        let drawn = match format {
            ImageFormat::Svg => {
                let mut svg = String::new();
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                self.render(root, &groups, stop).map(|()| svg.into_bytes())
            }
            ImageFormat::Png => {
                let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
                let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
                self.render(root, &groups, stop)
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
        groups: &[Panel<'_>],
        stop: &dyn Fn() -> Option<i32>,
    ) -> Result<(), Box<dyn std::error::Error + 'static>>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let title = fit(&self.spec.title, WIDTH as usize - 20, TITLE_FONT);
        let root = root.titled(&title, ("sans-serif", TITLE_FONT))?;
        let areas = root.split_evenly((groups.len(), 1));
        let all = groups.iter().flat_map(|g| g.members.iter());
        let (t0, t1) = all
            .flat_map(|(_, s)| s.points.iter().map(|p| p.0))
            .chain(self.errors.iter().map(|p| p.0))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                (a.min(t), b.max(t))
            });
        let (from, to) = self.range();
        let t0 = if from.is_finite() { from } else { t0.min(0.0) };
        let t1 = if to.is_finite() { to } else { t1 };
        let t1 = if t1 > t0 { t1 } else { t0 + 1e-3 };
        let anchor = self.anchor.map(local_start);
        let x_desc = match anchor {
            Some(a) => format!("time of day ({})", a.format("%Y-%m-%d")),
            None => "time since the capture's start (s)".to_string(),
        };
        let x_label = |t: &f64| match anchor {
            Some(a) => {
                let at = a + chrono::Duration::microseconds((*t * 1e6) as i64);
                if t1 - t0 < 10.0 {
                    at.format("%H:%M:%S%.3f").to_string()
                } else {
                    at.format("%H:%M:%S").to_string()
                }
            }
            None => number(*t, (t1 - t0) / 10.0),
        };
        for (panel, area) in groups.iter().zip(areas.iter()) {
            let (plot_area, legend) = area.split_horizontally(WIDTH - LEGEND);
            let (lo, hi) = panel
                .members
                .iter()
                .flat_map(|(_, s)| s.points.iter().map(|p| p.1))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            let pad = ((hi - lo) * 0.08).max(hi.abs().max(1.0) * 0.02);
            let (lo, hi) = (lo - pad, hi + pad);
            let step = (hi - lo) / 8.0;
            // The y labels as they will be written, to size their room.
            let widest = (0..=10)
                .map(|k| number(lo + (hi - lo) * k as f64 / 10.0, step).len())
                .max()
                .unwrap_or(4);
            let y_room = text_width(widest, LABEL_FONT) + 12;
            let mut chart = ChartBuilder::on(&plot_area)
                .margin(10)
                .x_label_area_size(42)
                .y_label_area_size(y_room as u32 + 24)
                .build_cartesian_2d(t0..t1, lo..hi)?;
            let y_desc = if panel.unit.is_empty() {
                "value".to_string()
            } else {
                format!("({})", panel.unit)
            };
            chart
                .configure_mesh()
                .x_desc(x_desc.as_str())
                .y_desc(y_desc)
                .x_labels(8)
                .y_labels(8)
                .x_label_formatter(&x_label)
                .y_label_formatter(&|v: &f64| number(*v, step))
                .label_style(("sans-serif", LABEL_FONT))
                .axis_desc_style(("sans-serif", LABEL_FONT))
                .draw()?;
            if !self.errors.is_empty() {
                chart.draw_series(self.errors.iter().map(|&(t, _)| {
                    PathElement::new(vec![(t, lo), (t, hi)], RED.mix(0.6).stroke_width(1))
                }))?;
            }
            let mut entries = Vec::new();
            for (color_at, (label, s)) in panel.members.iter().enumerate() {
                if stop().is_some() {
                    return Err("stopped by a signal".into());
                }
                let color = COLORS[color_at % COLORS.len()].to_rgba();
                // A step: each value held until the next sample.
                let mut steps = Vec::with_capacity(s.points.kept.len() * 2);
                for (k, &(t, v)) in s.points.iter().enumerate() {
                    if k > 0 {
                        let prev = steps.last().map_or(v, |p: &(f64, f64)| p.1);
                        steps.push((t, prev));
                    }
                    steps.push((t, v));
                }
                chart.draw_series(LineSeries::new(steps, color.stroke_width(2)))?;
                if s.points.kept.len() <= MARKERS_MAX {
                    chart
                        .draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
                }
                let name = if panel.unit.is_empty() {
                    label.clone()
                } else {
                    format!("{label} ({})", panel.unit)
                };
                entries.push((name, color));
            }
            // The legend beside the data, never on it.
            let line_h = 22;
            for (k, (name, color)) in entries.iter().enumerate() {
                let y = 30 + k as i32 * line_h;
                legend.draw(&PathElement::new(
                    vec![(8, y), (32, y)],
                    color.stroke_width(2),
                ))?;
                legend.draw(&Circle::new((20, y), 3, color.filled()))?;
                let text = fit(&short_port(name), (LEGEND - 50) as usize, LABEL_FONT);
                legend.draw(&Text::new(
                    text,
                    (40, y - 8),
                    ("sans-serif", LABEL_FONT).into_font(),
                ))?;
            }
            if !self.errors.is_empty() {
                let y = 30 + entries.len() as i32 * line_h;
                legend.draw(&PathElement::new(
                    vec![(20, y - 7), (20, y + 7)],
                    RED.stroke_width(1),
                ))?;
                legend.draw(&Text::new(
                    "broken frame",
                    (40, y - 8),
                    ("sans-serif", LABEL_FONT).into_font(),
                ))?;
            }
        }
        root.present()?;
        Ok(())
    }
}

/// The width in pixels of `chars` characters of the label font (DejaVu Sans: at most 0.62 of
/// the size for digits and most letters).
fn text_width(chars: usize, font: u32) -> usize {
    (chars as f64 * font as f64 * 0.62).ceil() as usize
}

/// A series name with its port shown by the port's file name (`Alt@/dev/serial/by-id/usb-…`
/// → `Alt@usb-…`): a legend has little room, and `--sensor` takes the full name.
fn short_port(name: &str) -> String {
    match name.rsplit_once("@/") {
        Some((head, path)) => {
            let (path, unit) = match path.rsplit_once(" (") {
                Some((p, u)) => (p, format!(" ({u}")),
                None => (path, String::new()),
            };
            let file = path.rsplit('/').next().unwrap_or(path);
            format!("{head}@{file}{unit}")
        }
        None => name.to_owned(),
    }
}

/// `text` cut with `…` in its middle to fit `pixels` at font size `font`: the start (the
/// number's name) and the end (a port's file name, `Alt@/tmp/…/odd.pcap`) stay.
fn fit(text: &str, pixels: usize, font: u32) -> String {
    let n = text.chars().count();
    let room = (pixels as f64 / (font as f64 * 0.62)) as usize;
    if n <= room {
        return text.to_owned();
    }
    let keep = room.saturating_sub(1);
    let head = keep - keep / 2;
    let mut s: String = text.chars().take(head).collect();
    s.push('…');
    s.extend(text.chars().skip(n - keep / 2));
    s
}

/// A tick label of `v` with as many decimals as ticks `step` apart need (`3735928559`, `4.12`,
/// `0.042`), never more than 6.
fn number(v: f64, step: f64) -> String {
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).clamp(0.0, 6.0) as usize
    } else {
        2
    };
    let s = format!("{v:.decimals$}");
    // No "-0".
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        return s.trim_start_matches('-').to_owned();
    }
    s
}

/// One panel: its unit and its series.
struct Panel<'a> {
    unit: String,
    members: Vec<&'a (String, &'a Series)>,
}

/// The chosen series grouped into panels: by unit (in order of first appearance), flags (only
/// 0 and 1) apart, then by size (series within [`SIZE_SPREAD`] of each other), at most
/// [`PER_PANEL`] to a panel.
fn panels<'a>(chosen: &'a [(String, &'a Series)]) -> Vec<Panel<'a>> {
    let mut order: Vec<String> = Vec::new();
    let mut by: BTreeMap<String, Vec<&(String, &Series)>> = BTreeMap::new();
    for c in chosen {
        if !by.contains_key(&c.1.unit) {
            order.push(c.1.unit.clone());
        }
        by.entry(c.1.unit.clone()).or_default().push(c);
    }
    let mut out = Vec::new();
    for unit in order {
        let members = by.remove(&unit).unwrap_or_default();
        let (flags, values): (Vec<_>, Vec<_>) = members.into_iter().partition(|c| c.1.is_flag());
        let mut bands: Vec<Vec<&(String, &Series)>> = Vec::new();
        if !flags.is_empty() {
            bands.push(flags);
        }
        // Sizes: the series sorted by size, a new band where one is too far above the band's
        // smallest; each band in the series' own order.
        let mut sized: Vec<(f64, usize)> = values
            .iter()
            .enumerate()
            .map(|(i, c)| (c.1.size(), i))
            .collect();
        sized.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut band: Vec<usize> = Vec::new();
        let mut smallest = 0.0;
        for (size, i) in sized {
            if !band.is_empty() && size > smallest * SIZE_SPREAD {
                band.sort_unstable();
                bands.push(band.iter().map(|&k| values[k]).collect());
                band.clear();
            }
            if band.is_empty() {
                smallest = size;
            }
            band.push(i);
        }
        if !band.is_empty() {
            band.sort_unstable();
            bands.push(band.iter().map(|&k| values[k]).collect());
        }
        for b in bands {
            for chunk in b.chunks(PER_PANEL) {
                out.push(Panel {
                    unit: unit.clone(),
                    members: chunk.to_vec(),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
