//! The live view's state: the table rows aggregated into one line per device, sensor and
//! number.
//!
//! Pure code: every function takes the current time (µs on the capture's clock) as an argument,
//! so that tests drive it with fixed times. A line's key is the row's `ID`, `Sensor #` and
//! `Sensor` columns (S.Port physical ID + app ID, S-Bus station + address + command, SAB
//! address + command) and the name of one of the row's numbers ([`Row::parts`]): a frame that
//! carries several numbers (an FLVSS frame's two cells, an S-Bus answer's registers) gives a
//! line for each, with its own last value, minimum and maximum, taken from the typed numbers
//! and never from the Data text. A row without numbers (a request, `R (run)`) gives its key a
//! line with its Data text. The view works for every protocol without knowing any of them, and
//! for rows without an ID.

use std::collections::{HashMap, VecDeque};

use crate::filter::Filter;
use crate::row::{Class, Row, kind};

/// At most this many lines are kept; rows of further keys are only counted.
pub const MAX_LINES: usize = 4096;
/// Frame times kept per line for the rate.
const RATE_TIMES: usize = 128;
/// The rate is the number of frames in this window (or since the line appeared).
pub const RATE_WINDOW: u64 = 5_000_000;
/// A changed value is highlighted this long.
pub const CHANGED_FOR: u64 = 1_000_000;
/// A line is stale (dimmed) after this long without a frame, or three of its usual intervals
/// when those are longer.
pub const STALE_AFTER: u64 = 3_000_000;
/// Error and event rows kept for the bottom of the screen.
pub const EVENTS: usize = 64;
/// Text fields are cut to this many characters (a line's Data text, an event's data).
const TEXT_MAX: usize = 200;
/// Row types remembered per line (for the `f` filter's `type=`).
const KINDS_MAX: usize = 8;

/// The row's columns that make a line's group (every number of a row shares them).
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct Group {
    id: Option<u32>,
    sensor_no: String,
    sensor: String,
    port: String,
}

/// What identifies a line.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Key {
    pub id: Option<u32>,
    pub sensor_no: String,
    pub sensor: String,
    /// The number's name (`Cell1`, `VFAS`, `R0`); empty for the line of a row's Data text.
    pub part: String,
    /// The row's port (several sources, [`crate::row::PORT_COLUMN`]), or "".
    pub port: String,
}

impl Key {
    fn group(&self) -> Group {
        Group {
            id: self.id,
            sensor_no: self.sensor_no.clone(),
            sensor: self.sensor.clone(),
            port: self.port.clone(),
        }
    }
}

/// A number with the text it was written as (the sensor's full wire precision).
#[derive(Clone, Debug, PartialEq)]
pub struct Number {
    pub value: f64,
    pub text: String,
}

/// One device/sensor/number.
#[derive(Clone, Debug)]
pub struct Track {
    pub key: Key,
    pub device: String,
    /// The number's text (`4.138`), or the Data text of a line without number.
    pub value: String,
    /// `value` is a number (never cut on the screen).
    pub numeric: bool,
    /// Whether `value` came from a request (a line of requests' Data hides behind the numbers
    /// of the answers, see [`Model::order`]).
    pub from_request: bool,
    pub unit: String,
    pub min: Option<Number>,
    pub max: Option<Number>,
    /// The types of the rows seen (`Data`, `Request`, `Response`), for the filter.
    pub kinds: Vec<String>,
    /// Rows of this line (for a number: the rows that carried it).
    pub frames: u64,
    /// Bad CRC and truncated frames of its group.
    pub crc_errors: u64,
    /// Timeouts, NAKs and NACKs of its group.
    pub timeouts: u64,
    pub first_seen: u64,
    pub last_seen: u64,
    /// When `value` last changed (not set by the first value).
    pub changed_at: Option<u64>,
    times: VecDeque<u64>,
    /// Marked by the user (space).
    pub marked: bool,
}

impl Track {
    fn new(key: Key, device: &str, now: u64) -> Track {
        Track {
            key,
            device: cut(device),
            value: String::new(),
            numeric: false,
            from_request: false,
            unit: String::new(),
            min: None,
            max: None,
            kinds: Vec::new(),
            frames: 0,
            crc_errors: 0,
            timeouts: 0,
            first_seen: now,
            last_seen: now,
            changed_at: None,
            times: VecDeque::new(),
            marked: false,
        }
    }

    /// Frames per second at `now`: the frames of the last [`RATE_WINDOW`] (or since the line
    /// appeared, when that is shorter), over that time. `None` while too young to tell.
    pub fn rate(&self, now: u64) -> Option<f64> {
        let since = now.saturating_sub(self.first_seen);
        let from = now.saturating_sub(RATE_WINDOW);
        let n = self.times.iter().rev().take_while(|&&t| t >= from).count();
        if n == self.times.len() && n == RATE_TIMES {
            // More frames than kept: the span of the kept ones.
            let span = now.saturating_sub(self.times[0]);
            return (span > 0).then(|| (n as f64) * 1e6 / span as f64);
        }
        let window = since.min(RATE_WINDOW);
        // One frame is no rate until the window has passed.
        if window < 500_000 || (self.frames < 2 && since < RATE_WINDOW) {
            return None;
        }
        Some(n as f64 * 1e6 / window as f64)
    }

    /// Microseconds since the last frame.
    pub fn age(&self, now: u64) -> u64 {
        now.saturating_sub(self.last_seen)
    }

    /// No frame for [`STALE_AFTER`] or three usual intervals, whichever is longer.
    pub fn stale(&self, now: u64) -> bool {
        let usual = match (self.times.front(), self.times.back()) {
            (Some(a), Some(b)) if self.times.len() > 1 => (b - a) / (self.times.len() as u64 - 1),
            _ => 0,
        };
        self.age(now) > STALE_AFTER.max(3 * usual)
    }

    /// The value changed less than [`CHANGED_FOR`] ago.
    pub fn changed(&self, now: u64) -> bool {
        self.changed_at
            .is_some_and(|t| now.saturating_sub(t) < CHANGED_FOR)
    }

    /// The number's name when it says more than the Sensor column (`Cels` → `Cell1`, `Volts`
    /// → `VFAS`), else empty.
    pub fn part_label(&self) -> &str {
        if self.key.part.eq_ignore_ascii_case(&self.key.sensor) {
            ""
        } else {
            &self.key.part
        }
    }

    /// A frame of the line at `now`.
    fn seen(&mut self, now: u64, kind: &str) {
        self.frames += 1;
        self.last_seen = now;
        if self.times.len() == RATE_TIMES {
            self.times.pop_front();
        }
        self.times.push_back(now);
        if self.kinds.len() < KINDS_MAX && !self.kinds.iter().any(|k| k == kind) {
            self.kinds.push(kind.to_owned());
        }
    }

    /// A new value (`number`: the typed number it is, if any).
    fn set(&mut self, text: &str, number: Option<f64>, now: u64) {
        if self.value != text {
            if !self.value.is_empty() {
                self.changed_at = Some(now);
            }
            self.value = cut(text);
        }
        self.numeric = number.is_some();
        if let Some(v) = number {
            let n = || Number {
                value: v,
                text: text.to_owned(),
            };
            if self.min.as_ref().is_none_or(|m| v < m.value) {
                self.min = Some(n());
            }
            if self.max.as_ref().is_none_or(|m| v > m.value) {
                self.max = Some(n());
            }
        }
    }

    /// The line as a row for the filter: its ID, Device, Sensor # and Sensor, its number's
    /// name, one of its row types, and class Warning when its group had errors (`errors`).
    fn matches(&self, filter: &Filter) -> bool {
        let part = [crate::row::Part {
            name: &self.key.part,
            unit: &self.unit,
            text: &self.value,
            value: 0.0,
        }];
        let class = if self.crc_errors + self.timeouts > 0 {
            Class::Warning
        } else {
            Class::Plain
        };
        let row = |kind: &str| -> bool {
            let row = Row {
                id: self.key.id,
                device: &self.device,
                kind,
                class,
                sensor_no: &self.key.sensor_no,
                sensor: &self.key.sensor,
                data: &self.value,
                parts: if self.key.part.is_empty() {
                    crate::row::Parts::NONE
                } else {
                    crate::row::Parts::List(&part)
                },
                ..Row::empty(None)
            };
            filter.keep(&row)
        };
        if self.kinds.is_empty() {
            row("Data")
        } else {
            self.kinds.iter().any(|k| row(k))
        }
    }
}

/// An error or event row for the bottom of the screen.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    pub micros: Option<u64>,
    pub class: Class,
    pub kind: String,
    pub id: Option<u32>,
    pub device: String,
    pub text: String,
    /// The row's port, or "".
    pub port: String,
}

/// How lines are ordered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sort {
    Id,
    Rate,
    Age,
    Name,
}

impl Sort {
    pub fn next(self) -> Sort {
        match self {
            Sort::Id => Sort::Rate,
            Sort::Rate => Sort::Age,
            Sort::Age => Sort::Name,
            Sort::Name => Sort::Id,
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Sort::Id => "ID",
            Sort::Rate => "rate",
            Sort::Age => "age",
            Sort::Name => "name",
        }
    }
}

/// Every line and the totals.
#[derive(Clone, Debug)]
pub struct Model {
    lines: Vec<Track>,
    index: HashMap<Key, usize>,
    /// The lines of each group.
    groups: HashMap<Group, Vec<usize>>,
    /// Index of the `Unit` column among the decoder's extra columns.
    unit_col: Option<usize>,
    /// Index of the `Port` column among the extra columns (several sources).
    port_col: Option<usize>,
    /// Rows of keys beyond [`MAX_LINES`].
    pub overflow_rows: u64,
    /// Every row taken in.
    pub rows: u64,
    /// Frame rows (everything but busnoop's own Info rows).
    pub frame_rows: u64,
    /// Frame rows of class Error (bad CRC, truncated, garbage).
    pub error_rows: u64,
    pub crc_errors: u64,
    pub timeouts: u64,
    /// Wire bytes of every row (each byte is in exactly one row).
    pub bytes: u64,
    byte_times: VecDeque<(u64, u64)>,
    pub events: VecDeque<Event>,
    pub first: Option<u64>,
    pub last: Option<u64>,
}

impl Model {
    /// `columns`: the decoder's extra columns (one named `Unit` gives the Data lines a unit).
    pub fn new(columns: &[&str]) -> Model {
        Model {
            lines: Vec::new(),
            index: HashMap::new(),
            groups: HashMap::new(),
            unit_col: columns.iter().position(|c| *c == "Unit"),
            port_col: columns.iter().position(|c| *c == crate::row::PORT_COLUMN),
            overflow_rows: 0,
            rows: 0,
            frame_rows: 0,
            error_rows: 0,
            crc_errors: 0,
            timeouts: 0,
            bytes: 0,
            byte_times: VecDeque::new(),
            events: VecDeque::new(),
            first: None,
            last: None,
        }
    }

    pub fn lines(&self) -> &[Track] {
        &self.lines
    }

    /// The line of `key`, opened when there is room (`None` past [`MAX_LINES`], counted).
    fn line(&mut self, key: Key, device: &str, now: u64) -> Option<usize> {
        if let Some(&i) = self.index.get(&key) {
            return Some(i);
        }
        if self.lines.len() >= MAX_LINES {
            self.overflow_rows += 1;
            return None;
        }
        let i = self.lines.len();
        self.groups.entry(key.group()).or_default().push(i);
        self.index.insert(key.clone(), i);
        self.lines.push(Track::new(key, device, now));
        Some(i)
    }

    /// Takes one table row in, at capture time `now` (the row's own time when it has one).
    pub fn row(&mut self, row: &Row<'_>, now: u64) {
        self.rows += 1;
        self.first.get_or_insert(now);
        self.last = Some(self.last.map_or(now, |l| l.max(now)));
        if !row.raw.is_empty() {
            self.bytes += row.raw.len() as u64;
            match self.byte_times.back_mut() {
                // One entry per 100 ms keeps the window small.
                Some((t, n)) if now.saturating_sub(*t) < 100_000 => *n += row.raw.len() as u64,
                _ => self.byte_times.push_back((now, row.raw.len() as u64)),
            }
            while self
                .byte_times
                .front()
                .is_some_and(|(t, _)| now.saturating_sub(*t) > RATE_WINDOW)
            {
                self.byte_times.pop_front();
            }
        }
        if row.class != Class::Info {
            self.frame_rows += 1;
        }
        let crc =
            row.class == Class::Error && (row.kind == kind::BAD_CRC || row.kind == kind::TRUNCATED);
        let timeout =
            row.kind == kind::TIMEOUT || row.kind.contains("NAK") || row.kind.contains("NACK");
        if row.class == Class::Error {
            self.error_rows += 1;
        }
        self.crc_errors += crc as u64;
        self.timeouts += timeout as u64;
        if matches!(row.class, Class::Error | Class::Warning | Class::Info) || timeout {
            self.event(row, now);
        }
        let port = self.port(row);
        let group = Group {
            id: row.id,
            sensor_no: row.sensor_no.to_owned(),
            sensor: row.sensor.to_owned(),
            port: port.to_owned(),
        };
        let keyed = !group.sensor_no.is_empty() || !group.sensor.is_empty();
        if crc || timeout || row.class == Class::Error {
            // Counted on the lines of its group, or (noise must not open lines) of its ID.
            let lines: Vec<usize> = match self.groups.get(&group) {
                Some(l) => l.clone(),
                None => self
                    .lines
                    .iter()
                    .position(|l| l.key.id == row.id && row.id.is_some() && l.key.port == port)
                    .into_iter()
                    .collect(),
            };
            for i in lines {
                let l = &mut self.lines[i];
                l.crc_errors += crc as u64;
                l.timeouts += timeout as u64;
            }
            return;
        }
        if !keyed {
            return;
        }
        let request = row.kind == "Request";
        let unit = self
            .unit_col
            .and_then(|c| row.extra.get(c))
            .copied()
            .unwrap_or("");
        if !row.parts.is_empty() {
            for p in row.parts {
                let key = Key {
                    id: row.id,
                    sensor_no: group.sensor_no.clone(),
                    sensor: group.sensor.clone(),
                    part: p.name.to_owned(),
                    port: group.port.clone(),
                };
                let Some(i) = self.line(key, row.device, now) else {
                    continue;
                };
                let l = &mut self.lines[i];
                l.seen(now, row.kind);
                if !row.device.is_empty() && l.device != row.device {
                    l.device = cut(row.device);
                }
                let number = p.value.is_finite().then_some(p.value);
                l.set(p.text, number, now);
                l.from_request = request;
                let unit = if p.unit.is_empty() { unit } else { p.unit };
                if !unit.is_empty() && l.unit != unit {
                    l.unit = cut(unit);
                }
            }
            return;
        }
        // A row without numbers: the line of its Data text, unless its group has numbers (a
        // write's `ACK (0x0000)` does not hide the value written; a read's request `R0..R3`
        // is said by the lines of the registers it brought).
        let has_numbers = self
            .groups
            .get(&group)
            .is_some_and(|l| l.iter().any(|&i| !self.lines[i].key.part.is_empty()));
        if has_numbers {
            return;
        }
        let key = Key {
            id: group.id,
            sensor_no: group.sensor_no,
            sensor: group.sensor,
            part: String::new(),
            port: group.port,
        };
        let Some(i) = self.line(key, row.device, now) else {
            return;
        };
        let l = &mut self.lines[i];
        l.seen(now, row.kind);
        if !row.device.is_empty() && l.device != row.device {
            l.device = cut(row.device);
        }
        if row.data.is_empty() || (request && !(l.value.is_empty() || l.from_request)) {
            return;
        }
        l.set(row.data, None, now);
        l.from_request = request;
        if !unit.is_empty() {
            l.unit = cut(unit);
        }
    }

    /// The row's port, or "".
    fn port<'r>(&self, row: &Row<'r>) -> &'r str {
        self.port_col
            .and_then(|c| row.extra.get(c))
            .copied()
            .unwrap_or("")
    }

    fn event(&mut self, row: &Row<'_>, now: u64) {
        if self.events.len() == EVENTS {
            self.events.pop_front();
        }
        let mut text = String::new();
        for part in [row.sensor_no, row.sensor, row.data] {
            if !part.is_empty() {
                if !text.is_empty() {
                    text.push(' ');
                }
                text.push_str(part);
            }
        }
        if let Some((_, note)) = row
            .extra
            .iter()
            .enumerate()
            .rev()
            .find(|&(i, s)| !s.is_empty() && Some(i) != self.port_col)
            && row.data.is_empty()
        {
            text.push_str(if text.is_empty() { "" } else { " " });
            text.push_str(note);
        }
        self.events.push_back(Event {
            micros: row.micros.or(Some(now)),
            class: row.class,
            kind: cut(row.kind),
            id: row.id,
            device: cut(row.device),
            text: cut(&text),
            port: self.port(row).to_owned(),
        });
    }

    /// Wire bytes per second over the last [`RATE_WINDOW`].
    pub fn bytes_per_second(&self, now: u64) -> Option<f64> {
        let first = self.first?;
        let from = now.saturating_sub(RATE_WINDOW);
        let n: u64 = self
            .byte_times
            .iter()
            .filter(|(t, _)| *t >= from)
            .map(|(_, n)| n)
            .sum();
        let window = now.saturating_sub(first).min(RATE_WINDOW);
        (window >= 500_000).then(|| n as f64 * 1e6 / window as f64)
    }

    /// Share of frame rows that were valid (not class Error), in percent.
    pub fn valid_percent(&self) -> Option<f64> {
        (self.frame_rows > 0)
            .then(|| 100.0 * (self.frame_rows - self.error_rows) as f64 / self.frame_rows as f64)
    }

    /// Whether line `i` is a request's Data text in a group whose answers brought numbers
    /// (`R0..R3` above the lines `R0` … `R3`): not shown.
    fn hidden(&self, i: usize) -> bool {
        let l = &self.lines[i];
        l.key.part.is_empty()
            && self
                .groups
                .get(&l.key.group())
                .is_some_and(|g| g.iter().any(|&j| !self.lines[j].key.part.is_empty()))
    }

    /// Lines shown without a filter.
    pub fn shown_lines(&self) -> usize {
        (0..self.lines.len()).filter(|&i| !self.hidden(i)).count()
    }

    /// Indexes of the lines the filter keeps (the command line's filters, see
    /// [`crate::filter`]), in the order of `sort` at `now`; marked lines first.
    pub fn order(&self, sort: Sort, filter: Option<&Filter>, now: u64) -> Vec<usize> {
        let mut v: Vec<usize> = (0..self.lines.len())
            .filter(|&i| !self.hidden(i))
            .filter(|&i| filter.is_none_or(|f| self.lines[i].matches(f)))
            .collect();
        let lines = &self.lines;
        v.sort_by(|&a, &b| {
            let (x, y) = (&lines[a], &lines[b]);
            y.marked.cmp(&x.marked).then_with(|| match sort {
                Sort::Id => x.key.cmp(&y.key),
                Sort::Rate => y
                    .rate(now)
                    .unwrap_or(0.0)
                    .total_cmp(&x.rate(now).unwrap_or(0.0))
                    .then_with(|| x.key.cmp(&y.key)),
                Sort::Age => x.age(now).cmp(&y.age(now)).then_with(|| x.key.cmp(&y.key)),
                Sort::Name => (x.device.to_lowercase(), x.key.sensor.to_lowercase())
                    .cmp(&(y.device.to_lowercase(), y.key.sensor.to_lowercase()))
                    .then_with(|| x.key.cmp(&y.key)),
            })
        });
        v
    }

    /// Marks or unmarks line `i`.
    pub fn toggle_mark(&mut self, i: usize) {
        if let Some(l) = self.lines.get_mut(i) {
            l.marked = !l.marked;
        }
    }
}

/// Cuts a text to [`TEXT_MAX`] characters.
fn cut(s: &str) -> String {
    match s.char_indices().nth(TEXT_MAX) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_owned(),
    }
}

#[cfg(test)]
mod tests;
