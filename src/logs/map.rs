//! Lines of a telemetry log onto the log table, and the statistics.
//!
//! A radio's SD-card CSV: one row per line, Type `Log`, Millis from its Date and Time (the
//! first line at 0), every field in Data as `name=text`, every number as a part named as the
//! column (`RSSI`, `Cell 1`, `RxBt` with the unit of `RxBt(V)`). An S-Port_Snoop table: one row
//! per line with its cells as they are (Millis, ID, Device, Type, Sensor #, Sensor, Data), the
//! Data (or busnoop's Value) as a number named as the Sensor column. A line that does not fit
//! its header is a `Garbage` row saying why.

use std::collections::BTreeMap;

use chrono::{NaiveDate, NaiveDateTime, NaiveTime};

use super::wire::{Event, Format};
use crate::fmt::push_hex;
use crate::row::{Class, Part, Parts, Row, RowOut, RowResult, kind};
use crate::stats::{Column, Problems, Report};

/// The Type of a radio log's lines.
pub const LOG_TYPE: &str = "Log";

/// The extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Note"];

/// The most columns (of a CSV) or sensors (of a table) the statistics keep apart; the rest are
/// counted together.
const MAX_TRACKED: usize = 1024;

/// The most fields of a line (a wider header is cut here).
const MAX_FIELDS: usize = 512;

/// One column's or sensor's numbers.
#[derive(Clone, Debug)]
struct Track {
    unit: String,
    count: u64,
    min: f64,
    max: f64,
    last: String,
}

/// The counters of a run.
#[derive(Clone, Debug, Default)]
pub struct Stats {
    pub lines: u64,
    pub bad_lines: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    /// Per column name (CSV) or sensor (table).
    tracks: BTreeMap<String, Track>,
    untracked: u64,
}

impl Stats {
    fn number(&mut self, name: &str, unit: &str, text: &str, value: f64) {
        if let Some(t) = self.tracks.get_mut(name) {
            t.count += 1;
            t.min = t.min.min(value);
            t.max = t.max.max(value);
            t.last.clear();
            t.last.push_str(text);
        } else if self.tracks.len() < MAX_TRACKED {
            self.tracks.insert(
                name.to_owned(),
                Track {
                    unit: unit.to_owned(),
                    count: 1,
                    min: value,
                    max: value,
                    last: text.to_owned(),
                },
            );
        } else {
            self.untracked += 1;
        }
    }
}

/// Turns events into rows.
#[derive(Default)]
pub struct Mapper {
    format: Option<Format>,
    /// The header's column names (the unit cut off for a CSV) and units.
    names: Vec<String>,
    units: Vec<String>,
    /// A table's columns: where Value, Unit and Note are.
    value_at: Option<usize>,
    unit_at: Option<usize>,
    note_at: Option<usize>,
    /// CSV: the time of the first line.
    start: Option<NaiveDateTime>,
    data: String,
    last_garbage: bool,
    pub stats: Stats,
}

impl Mapper {
    pub fn event(&mut self, e: Event<'_>, out: &mut dyn RowOut) -> RowResult {
        let garbage = matches!(e, Event::Garbage(_));
        let r = match e {
            Event::Header { text } => {
                self.header(text);
                Ok(())
            }
            Event::Line { text, raw } => self.line(text, raw, out),
            Event::Garbage(bytes) => {
                self.stats.garbage_bytes += bytes.len() as u64;
                if !self.last_garbage {
                    self.stats.garbage_runs += 1;
                }
                self.data.clear();
                push_hex(&mut self.data, bytes);
                let note = match self.format {
                    None => "before the header line of a telemetry log",
                    Some(_) => "a line too long, or not text",
                };
                out.row(&Row {
                    stamp: 0,
                    kind: kind::GARBAGE,
                    class: Class::Error,
                    data: &self.data,
                    extra: &["", note],
                    raw: bytes,
                    ..Row::empty(None)
                })
            }
        };
        self.last_garbage = garbage;
        r
    }

    fn header(&mut self, text: &str) {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let format = Format::of_header(text).unwrap_or(Format::RadioCsv);
        self.format = Some(format);
        self.names.clear();
        self.units.clear();
        for (i, field) in text.split(format.separator()).take(MAX_FIELDS).enumerate() {
            let field = field.trim();
            let (name, unit) = match (format, field.strip_suffix(')')) {
                (Format::RadioCsv, Some(f)) => match f.rsplit_once('(') {
                    Some((n, u)) if !n.trim().is_empty() => (n.trim(), u.trim()),
                    _ => (field, ""),
                },
                _ => (field, ""),
            };
            self.names.push(name.to_owned());
            self.units.push(unit.to_owned());
            if format == Format::SnoopTable {
                match name {
                    "Value" => self.value_at = Some(i),
                    "Unit" => self.unit_at = Some(i),
                    "Note" => self.note_at = Some(i),
                    _ => {}
                }
            }
        }
    }

    fn line(&mut self, text: &str, raw: &[u8], out: &mut dyn RowOut) -> RowResult {
        match self.format {
            Some(Format::RadioCsv) => self.csv_line(text, raw, out),
            Some(Format::SnoopTable) => self.table_line(text, raw, out),
            None => Ok(()),
        }
    }

    /// A line that does not fit the header: a Garbage row saying why.
    fn bad(&mut self, raw: &[u8], why: &str, out: &mut dyn RowOut) -> RowResult {
        self.stats.bad_lines += 1;
        self.data.clear();
        self.data.push_str(why);
        out.row(&Row {
            stamp: 0,
            kind: kind::GARBAGE,
            class: Class::Error,
            data: &self.data,
            extra: &["", "a line that does not fit the header"],
            raw,
            ..Row::empty(None)
        })
    }

    fn csv_line(&mut self, text: &str, raw: &[u8], out: &mut dyn RowOut) -> RowResult {
        let fields: Vec<&str> = text.split(',').take(MAX_FIELDS).collect();
        if fields.len() != self.names.len() {
            let why = format!(
                "{} fields, the header has {}",
                fields.len(),
                self.names.len()
            );
            return self.bad(raw, &why, out);
        }
        let Some(at) = date_time(fields[0], fields[1]) else {
            let why = format!("no date and time: {:?} {:?}", fields[0], fields[1]);
            return self.bad(raw, &why, out);
        };
        let start = *self.start.get_or_insert(at);
        let micros = (at - start).num_microseconds().unwrap_or(0).max(0) as u64;
        self.stats.lines += 1;
        self.data.clear();
        let mut parts = Vec::with_capacity(fields.len());
        for (i, f) in fields.iter().enumerate().skip(2) {
            let f = f.trim();
            if f.is_empty() {
                continue;
            }
            if !self.data.is_empty() {
                self.data.push(' ');
            }
            self.data.push_str(&self.names[i]);
            self.data.push('=');
            self.data.push_str(f);
            if let Some(v) = number(f) {
                parts.push(Part {
                    name: &self.names[i],
                    unit: &self.units[i],
                    text: f,
                    value: v,
                });
            }
        }
        for p in &parts {
            self.stats.number(p.name, p.unit, p.text, p.value);
        }
        out.row(&Row {
            stamp: 0,
            micros: Some(micros),
            kind: LOG_TYPE,
            class: Class::Plain,
            data: &self.data,
            extra: &["", ""],
            parts: Parts::List(&parts),
            raw,
            ..Row::empty(None)
        })
    }

    fn table_line(&mut self, text: &str, raw: &[u8], out: &mut dyn RowOut) -> RowResult {
        let fields: Vec<&str> = text.split('\t').take(MAX_FIELDS).collect();
        let cell = |i: usize| fields.get(i).map_or("", |f| f.trim());
        let Ok(millis) = cell(1).parse::<u64>() else {
            let why = format!("Millis {:?} is not a number", cell(1));
            return self.bad(raw, &why, out);
        };
        let id = match cell(2) {
            "" => None,
            s => match crate::filter::parse_number(s) {
                Some(id) => Some(id),
                None => {
                    let why = format!("ID {s:?} is not a number");
                    return self.bad(raw, &why, out);
                }
            },
        };
        self.stats.lines += 1;
        let (device, kind, sensor_no, sensor, data) = (cell(3), cell(4), cell(5), cell(6), cell(7));
        let class = match kind {
            "Null" => Class::Quiet,
            kind::BAD_CRC | kind::TRUNCATED | kind::GARBAGE => Class::Error,
            kind::LINK_DOWN | kind::LINK_UP | kind::TIME_JUMP => Class::Info,
            _ => Class::Plain,
        };
        let unit = self.unit_at.map_or("", cell);
        let note = self.note_at.map_or("", cell);
        // busnoop's own TSV has the number in Value; S-Port_Snoop's is Data.
        let text = match self.value_at {
            Some(i) => cell(i),
            None => data,
        };
        let name = if sensor.is_empty() { sensor_no } else { sensor };
        let part = match (class, number(text)) {
            (Class::Plain, Some(v)) if !name.is_empty() => Some(Part {
                name,
                unit,
                text,
                value: v,
            }),
            _ => None,
        };
        if let Some(p) = &part {
            let key = match id {
                Some(id) => format!("{id} {}", p.name),
                None => p.name.to_owned(),
            };
            self.stats.number(&key, p.unit, p.text, p.value);
        }
        let parts = part.as_slice();
        out.row(&Row {
            stamp: 0,
            micros: Some(millis.saturating_mul(1000)),
            id,
            device,
            kind,
            class,
            sensor_no,
            sensor,
            data,
            extra: &[unit, note],
            parts: Parts::List(parts),
            raw,
        })
    }

    pub fn report(&self) -> Report {
        let s = &self.stats;
        let mut r = Report::new(&[
            Column::left("Number", 16),
            Column::left("Unit", 5),
            Column::right("Values", 7),
            Column::right("Min", 10),
            Column::right("Max", 10),
            Column::right("Last", 10).gap(2),
        ]);
        r.head.push(match self.format {
            Some(Format::RadioCsv) => "a radio's SD-card log (CSV): every number column".into(),
            Some(Format::SnoopTable) => "an S-Port_Snoop table: every sensor (ID and name)".into(),
            None => "no telemetry log header found".into(),
        });
        for (name, t) in &s.tracks {
            r.row(vec![
                name.clone(),
                t.unit.clone(),
                t.count.to_string(),
                short(t.min),
                short(t.max),
                t.last.clone(),
            ]);
        }
        let mut totals = format!(
            "lines {}, lines not fitting the header {}, garbage {}",
            s.lines,
            s.bad_lines,
            crate::stats::garbage(s.garbage_bytes, s.garbage_runs)
        );
        if s.untracked > 0 {
            totals.push_str(&format!(
                ", {} values beyond the first {MAX_TRACKED} numbers",
                s.untracked
            ));
        }
        r.totals.push(totals);
        r
    }

    pub fn problems(&self) -> Problems {
        let s = &self.stats;
        let mut p = Problems::new("telemetry log");
        p.count(
            "bad_lines",
            s.bad_lines,
            "line that does not fit the header",
            "lines that do not fit the header",
        )
        .garbage(s.garbage_bytes, s.garbage_runs)
        .in_valid(s.lines, "line", "lines");
        p
    }
}

/// A plain decimal number (`4.12`, `-5`, ` 0.00`); not `2000-00-00` or `002.0000-`.
fn number(s: &str) -> Option<f64> {
    let t = s.trim();
    let digits = t.strip_prefix('-').unwrap_or(t);
    let ok = !digits.is_empty()
        && digits.bytes().all(|b| b.is_ascii_digit() || b == b'.')
        && digits.bytes().filter(|&b| b == b'.').count() <= 1
        && digits.bytes().any(|b| b.is_ascii_digit());
    if ok { t.parse().ok() } else { None }
}

/// `2014-07-11` and `22:41:00.570`.
fn date_time(date: &str, time: &str) -> Option<NaiveDateTime> {
    let d = NaiveDate::parse_from_str(date.trim(), "%Y-%m-%d").ok()?;
    let t = NaiveTime::parse_from_str(time.trim(), "%H:%M:%S%.f").ok()?;
    Some(d.and_time(t))
}

/// A number for the statistics table (at most 10 characters).
fn short(v: f64) -> String {
    let s = format!("{v}");
    if s.len() <= 10 { s } else { format!("{v:.4e}") }
}
