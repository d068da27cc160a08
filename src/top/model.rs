//! The live view's state: the table rows aggregated into one line per device and sensor.
//!
//! Pure code: every function takes the current time (µs on the capture's clock) as an argument,
//! so that tests drive it with fixed times. A line's key is the row's `ID`, `Sensor #` and
//! `Sensor` columns (S.Port physical ID + app ID, S-Bus station + address + command, SAB
//! address + command), so the view works for every protocol without knowing any of them.

use std::collections::{HashMap, VecDeque};

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
/// Text fields are cut to this many characters (a line's value, an event's data).
const TEXT_MAX: usize = 200;

/// What identifies a line.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Key {
    pub id: Option<u32>,
    pub sensor_no: String,
    pub sensor: String,
}

/// One device/sensor.
#[derive(Clone, Debug)]
pub struct Track {
    pub key: Key,
    pub device: String,
    /// The `Data` column of the last row that carried a value.
    pub value: String,
    /// Whether `value` came from a request (kept only until an answer brings one).
    value_from_request: bool,
    /// The first number of `value`.
    pub number: Option<f64>,
    pub unit: String,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// Rows of this key (requests, answers, errors).
    pub frames: u64,
    /// Bad CRC and truncated frames.
    pub crc_errors: u64,
    /// Timeouts, NAKs and NACKs.
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
            value_from_request: false,
            number: None,
            unit: String::new(),
            min: None,
            max: None,
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
    /// Index of the `Unit` column among the decoder's extra columns.
    unit_col: Option<usize>,
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
    /// `columns`: the decoder's extra columns (one named `Unit` gives the lines their unit).
    pub fn new(columns: &[&str]) -> Model {
        Model {
            lines: Vec::new(),
            index: HashMap::new(),
            unit_col: columns.iter().position(|c| *c == "Unit"),
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
        let key = Key {
            id: row.id,
            sensor_no: row.sensor_no.to_owned(),
            sensor: row.sensor.to_owned(),
        };
        let keyed = !key.sensor_no.is_empty() || !key.sensor.is_empty();
        let i = match self.index.get(&key) {
            Some(&i) => i,
            // An error row whose key has no line: counted on a line of its ID, if any (noise
            // must not open lines).
            None if crc || row.class == Class::Error || !keyed => {
                if let Some(i) = self
                    .lines
                    .iter()
                    .position(|l| l.key.id == row.id && row.id.is_some())
                    && (crc || timeout)
                {
                    let l = &mut self.lines[i];
                    l.crc_errors += crc as u64;
                    l.timeouts += timeout as u64;
                }
                return;
            }
            None if self.lines.len() >= MAX_LINES => {
                self.overflow_rows += 1;
                return;
            }
            None => {
                self.lines.push(Track::new(key.clone(), row.device, now));
                self.index.insert(key, self.lines.len() - 1);
                self.lines.len() - 1
            }
        };
        let unit = self
            .unit_col
            .and_then(|c| row.extra.get(c))
            .copied()
            .unwrap_or("");
        let line = &mut self.lines[i];
        line.frames += 1;
        line.crc_errors += crc as u64;
        line.timeouts += timeout as u64;
        line.last_seen = now;
        if line.times.len() == RATE_TIMES {
            line.times.pop_front();
        }
        line.times.push_back(now);
        if !row.device.is_empty() && line.device != row.device {
            line.device = cut(row.device);
        }
        if crc || timeout || row.class == Class::Error || row.data.is_empty() {
            return;
        }
        let request = row.kind == "Request";
        if request && !(line.value.is_empty() || line.value_from_request) {
            return;
        }
        let number = first_number(row.data);
        // A write's answer (`ACK (0x0000)`) does not hide the value written.
        if !request && line.value_from_request && line.number.is_some() && number.is_none() {
            return;
        }
        if line.value != row.data {
            if !line.value.is_empty() {
                line.changed_at = Some(now);
            }
            line.value = cut(row.data);
        }
        line.value_from_request = request;
        if !unit.is_empty() {
            line.unit = cut(unit);
        }
        line.number = number;
        if let Some(n) = line.number {
            line.min = Some(line.min.map_or(n, |m| m.min(n)));
            line.max = Some(line.max.map_or(n, |m| m.max(n)));
        }
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
        if let Some(note) = row.extra.iter().rev().find(|s| !s.is_empty())
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

    /// Indexes of the lines that match `filter`, in the order of `sort` at `now`; marked lines
    /// first.
    pub fn order(&self, sort: Sort, filter: &str, now: u64) -> Vec<usize> {
        let filter = filter.to_lowercase();
        let mut v: Vec<usize> = (0..self.lines.len())
            .filter(|&i| filter.is_empty() || matches(&self.lines[i], &filter))
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

/// The filter (lower case) is a substring of the line's ID (decimal or 0x hex), device, sensor
/// number or sensor name.
fn matches(l: &Track, filter: &str) -> bool {
    let id = l
        .key
        .id
        .map_or(String::new(), |id| format!("{id} 0x{id:02x}"));
    [id.as_str(), &l.device, &l.key.sensor_no, &l.key.sensor]
        .iter()
        .any(|s| s.to_lowercase().contains(filter))
}

/// Cuts a text to [`TEXT_MAX`] characters.
fn cut(s: &str) -> String {
    match s.char_indices().nth(TEXT_MAX) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_owned(),
    }
}

/// The number a `Data` cell holds: the first one in parentheses (`23 01 (291)`: the bytes'
/// value), else the first word that is a number, or the part after `=` of a word
/// (`R0=305419896 R1=100`).
pub fn first_number(data: &str) -> Option<f64> {
    let parse = |w: &str| -> Option<f64> {
        let w = w.trim_matches(|c: char| matches!(c, '(' | ')' | ',' | ';'));
        if w.is_empty() || !w.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+') {
            return None;
        }
        w.parse::<f64>().ok().filter(|n| n.is_finite())
    };
    if let Some(open) = data.find('(')
        && let Some(n) = data[open + 1..]
            .split(|c: char| c.is_whitespace() || c == ',' || c == ')')
            .next()
            .and_then(parse)
    {
        return Some(n);
    }
    data.split_whitespace()
        .map(|w| w.rsplit_once('=').map_or(w, |(_, v)| v))
        .find_map(parse)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data<'a>(
        id: u32,
        no: &'a str,
        name: &'a str,
        value: &'a str,
        extra: &'a [&'a str],
    ) -> Row<'a> {
        Row {
            stamp: 0,
            id: Some(id),
            device: "FAS-40S",
            kind: "Data",
            sensor_no: no,
            sensor: name,
            data: value,
            extra,
            raw: &[0x10, 0, 0, 0, 0, 0, 0, 0],
            ..Row::empty(None)
        }
    }

    #[test]
    fn numbers_of_every_protocol() {
        assert_eq!(first_number("0.00"), Some(0.0));
        assert_eq!(first_number("-12.5"), Some(-12.5));
        assert_eq!(first_number("R0=305419896 R1=100"), Some(305419896.0));
        assert_eq!(first_number("23 01 (291)"), Some(291.0));
        assert_eq!(
            first_number("EF BE AD DE (3735928559, -559038737)"),
            Some(3735928559.0)
        );
        assert_eq!(first_number("R (run)"), None);
        assert_eq!(first_number("NAK, no reason specified (0x0001)"), None);
        assert_eq!(first_number("F1=0 F2=1"), Some(0.0));
        assert_eq!(first_number("R0..R3"), None);
        assert_eq!(first_number(""), None);
        assert_eq!(first_number("inf NaN"), None);
    }

    #[test]
    fn one_line_per_key_with_value_unit_min_max_and_rate() {
        let mut m = Model::new(&["Unit", "Note"]);
        let unit = ["V", ""];
        for (i, v) in ["12.1", "12.3", "11.9", "11.9"].iter().enumerate() {
            m.row(&data(2, "210", "Volts", v, &unit), i as u64 * 250_000);
        }
        m.row(&data(2, "200", "Amps", "1.5", &["A", ""]), 100_000);
        assert_eq!(m.lines().len(), 2);
        let l = &m.lines()[0];
        assert_eq!((l.value.as_str(), l.unit.as_str()), ("11.9", "V"));
        assert_eq!((l.min, l.max, l.frames), (Some(11.9), Some(12.3), 4));
        // Changed at 500 ms (12.3 -> 11.9), not at 750 ms (same value).
        assert_eq!(l.changed_at, Some(500_000));
        assert!(l.changed(1_000_000) && !l.changed(1_600_000));
        // 4 frames in the 1 s since the line appeared.
        assert_eq!(l.rate(1_000_000), Some(4.0));
        assert_eq!(l.rate(200_000), None, "too young");
        assert_eq!(l.age(1_000_000), 250_000);
        assert!(!l.stale(3_000_000) && l.stale(3_800_000));
        assert_eq!(m.bytes, 40);
    }

    #[test]
    fn requests_keep_their_value_only_until_an_answer_brings_one() {
        let mut m = Model::new(&[]);
        let req = Row {
            stamp: 0,
            kind: "Request",
            data: "R0..R3",
            ..data(10, "R0", "Read register(s)", "", &[])
        };
        let resp = Row {
            stamp: 0,
            kind: "Response",
            data: "R0=42 R1=1",
            ..req
        };
        m.row(&req, 0);
        assert_eq!(m.lines()[0].value, "R0..R3");
        m.row(&resp, 1000);
        m.row(&req, 2000);
        let l = &m.lines()[0];
        assert_eq!(
            (l.value.as_str(), l.number, l.frames),
            ("R0=42 R1=1", Some(42.0), 3)
        );
    }

    #[test]
    fn errors_count_on_their_line_and_become_events() {
        let mut m = Model::new(&[]);
        m.row(&data(5, "0x10", "", "01", &[]), 0);
        let bad = Row {
            stamp: 0,
            kind: kind::BAD_CRC,
            class: Class::Error,
            ..data(5, "0x10", "", "01", &[])
        };
        m.row(&bad, 10);
        // A bad frame of an unknown key opens no line but counts on its ID's line.
        m.row(
            &Row {
                stamp: 0,
                sensor_no: "0x99",
                ..bad
            },
            20,
        );
        let nak = Row {
            stamp: 0,
            kind: "NACK",
            ..data(5, "0x10", "", "02 (2)", &[])
        };
        m.row(&nak, 30);
        let timeout = Row {
            stamp: 0,
            kind: kind::TIMEOUT,
            class: Class::Warning,
            ..data(7, "0x11", "", "", &[])
        };
        m.row(&timeout, 40);
        assert_eq!(m.lines().len(), 2);
        let l = &m.lines()[0];
        assert_eq!((l.crc_errors, l.timeouts, l.value.as_str()), (2, 1, "01"));
        assert_eq!(m.lines()[1].timeouts, 1);
        assert_eq!((m.crc_errors, m.timeouts, m.error_rows), (2, 2, 2));
        assert_eq!(m.events.len(), 4);
        assert_eq!(m.events[0].kind, "BadCRC");
        assert_eq!(m.valid_percent(), Some(60.0));
    }

    #[test]
    fn rows_without_a_sensor_open_no_line() {
        let mut m = Model::new(&[]);
        m.row(
            &Row {
                stamp: 0,
                kind: "",
                ..data(26, "", "", "", &[])
            },
            0,
        );
        m.row(
            &Row {
                stamp: 0,
                kind: "Null",
                class: Class::Quiet,
                ..data(0, "", "", "", &[])
            },
            0,
        );
        assert!(m.lines().is_empty());
        assert_eq!(m.frame_rows, 2);
    }

    #[test]
    fn lines_are_capped_and_the_rest_counted() {
        let mut m = Model::new(&[]);
        for i in 0..MAX_LINES as u32 + 10 {
            let no = i.to_string();
            m.row(&data(i, &no, "x", "1", &[]), 0);
        }
        assert_eq!(m.lines().len(), MAX_LINES);
        assert_eq!(m.overflow_rows, 10);
    }

    #[test]
    fn memory_per_line_is_bounded() {
        let mut m = Model::new(&[]);
        let long = "9".repeat(10_000);
        for t in 0..10_000u64 {
            m.row(&data(1, "1", "x", &long, &[]), t * 1000);
        }
        let l = &m.lines()[0];
        assert!(l.times.len() <= RATE_TIMES);
        assert!(l.value.chars().count() <= TEXT_MAX + 1);
        // 1000 frames/s, more than the kept times cover.
        let r = l.rate(9_999_000).unwrap();
        assert!((r - 1000.0).abs() < 10.0, "{r}");
        assert!(m.byte_times.len() <= 51);
    }

    #[test]
    fn sort_filter_and_marks() {
        let mut m = Model::new(&[]);
        m.row(
            &Row {
                stamp: 0,
                device: "Vario",
                ..data(0, "100", "Alt", "1", &[])
            },
            0,
        );
        for t in 0..10 {
            m.row(
                &Row {
                    stamp: 0,
                    device: "FAS-40S",
                    ..data(2, "210", "Volts", "1", &[])
                },
                t * 100_000,
            );
        }
        m.row(
            &Row {
                stamp: 0,
                device: "GPS",
                ..data(3, "800", "Lat", "1", &[])
            },
            900_000,
        );
        let now = 1_000_000;
        assert_eq!(m.order(Sort::Id, "", now), [0, 1, 2]);
        assert_eq!(m.order(Sort::Rate, "", now)[0], 1);
        assert_eq!(m.order(Sort::Age, "", now), [1, 2, 0], "equal ages by key");
        assert_eq!(m.order(Sort::Name, "", now), [1, 2, 0]);
        assert_eq!(m.order(Sort::Id, "volt", now), [1]);
        assert_eq!(m.order(Sort::Id, "0x03", now), [2]);
        m.toggle_mark(2);
        assert_eq!(m.order(Sort::Id, "", now), [2, 0, 1]);
    }
}
