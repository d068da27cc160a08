//! The wide export (`--wide`): one row per time step, one column per sensor seen, the last value
//! held, as a radio's SD-card log writes it.
//!
//! A **time step** depends on the protocol:
//! * a poll cycle ([`Step::PollCycle`], protocols that poll, S.Port): it ends when a row's `ID`
//!   comes round again (the next poll of a physical ID); a row with numbers but no ID ends it
//!   at once;
//! * a frame ([`Step::Frame`], protocols without a poll cycle, S-Bus and SAB): one line per row
//!   that carries numbers, at its time;
//! * with `--every MS` ([`Step::Every`]), a fixed interval of capture time.
//!
//! A line is written for every step in which at least one row arrived; its time is the time of
//! the step's last row (with `--every`, the end of the interval), its cells the last value of
//! every column at that time. Steps before the first number (polls that nobody answered) write
//! no line.
//!
//! **Columns** come from the rows' [`Part`](crate::row::Part)s: every number of a row (an FLVSS
//! frame's cells, an S-Bus response's registers) is its own column, named `Name(unit)` as EdgeTX
//! names the columns of its logs (`RxBt(V)`, `Cell1(V)`; `SWR` has no unit). When two IDs send a
//! number of the same name and unit (two FLVSS), the columns carry the ID: `Cell1@1(V)`,
//! `Cell1@8(V)`. Columns are in order of first appearance, at most `--max-columns`
//! ([`MAX_COLUMNS`] unless told): the numbers of later columns are left out and counted.
//!
//! **Files** (and pipes) are read once and the table is written at the end, so that the header is
//! complete and every shared name carries its ID. Until then each line waits in the [`Spool`] as
//! what changed since the line before (its time and the cells whose value changed), so the spool
//! grows with the input, not with lines × columns; at the end the lines are rebuilt in order and
//! padded to every column (empty cells before a column's first value). **Live sources** (a serial
//! port) are written as they come: a column is added at the end when its sensor first appears,
//! and the header line is written again with the new column (earlier lines have fewer cells); a
//! number whose name is already taken by another ID gets the `@ID` form, the earlier column keeps
//! its plain name.
//!
//! Rows whose check failed, or that are flagged as corrupted, carry no numbers (see
//! [`crate::row::Row::parts`]), and error rows are passed over here all the same, so a corrupted
//! frame never enters the wide table.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io;

use chrono::{DateTime, Local};

use super::Format;
use super::spool::{self, Spool};
use crate::row::{Class, Row};
use crate::time::Anchor;

/// Columns of a wide table unless `--max-columns` says otherwise: far more than any radio
/// logs, few enough that a line stays readable and a hostile capture cannot make the table
/// grow with lines × columns beyond reason.
pub const MAX_COLUMNS: usize = 2000;

/// What identifies a column: the row's ID and port and the part's name and unit.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Key {
    pub id: Option<u32>,
    /// The row's port, as its number in [`Columns::ports`] (0 without ports).
    pub port: u32,
    pub name: String,
    pub unit: String,
}

/// The columns of a capture in order of first appearance, with their header labels.
#[derive(Clone, Debug, Default)]
pub struct Columns {
    keys: Vec<Key>,
    labels: Vec<String>,
    index: HashMap<Key, usize>,
    /// Lookup of a row's part without allocating: (id, name, unit) → column, via a reused key.
    probe: Key,
    /// The ports seen, in order (several sources).
    ports: Vec<String>,
}

impl Columns {
    /// The number of `port` in the labels' list.
    fn port(&mut self, port: &str) -> u32 {
        match self.ports.iter().position(|p| p == port) {
            Some(i) => i as u32,
            None => {
                self.ports.push(port.to_owned());
                (self.ports.len() - 1) as u32
            }
        }
    }

    /// The column of a part, if known.
    fn find(&mut self, id: Option<u32>, port: u32, name: &str, unit: &str) -> Option<usize> {
        self.probe.id = id;
        self.probe.port = port;
        self.probe.name.clear();
        self.probe.name.push_str(name);
        self.probe.unit.clear();
        self.probe.unit.push_str(unit);
        self.index.get(&self.probe).copied()
    }

    /// Adds a column, labelled by the live rule (files relabel at the end, [`Self::finalize`]).
    fn add(&mut self, key: Key) -> usize {
        let i = self.keys.len();
        let clash = clash(&self.keys, &key);
        self.labels.push(label(&key, clash, &self.ports));
        self.index.insert(key.clone(), i);
        self.keys.push(key);
        i
    }

    /// Relabels every column whose name and unit are shared by another ID (files: at the end,
    /// so that all of them carry their ID).
    fn finalize(&mut self) {
        // Columns by name and unit, so that a clash is looked for among those alone.
        let mut same: HashMap<(&str, &str), Vec<usize>> = HashMap::new();
        for (i, k) in self.keys.iter().enumerate() {
            same.entry((&k.name, &k.unit)).or_default().push(i);
        }
        for (i, k) in self.keys.iter().enumerate() {
            let group: Vec<Key> = same[&(k.name.as_str(), k.unit.as_str())]
                .iter()
                .map(|&j| self.keys[j].clone())
                .collect();
            self.labels[i] = label(k, clash(&group, k), &self.ports);
        }
    }

    pub fn labels(&self) -> &[String] {
        &self.labels
    }

    pub fn len(&self) -> usize {
        self.keys.len()
    }

    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// Index of a row's part, adding the column when it is new and fewer than `max` exist.
    /// `port`: its number, [`Columns::port`].
    pub fn column(
        &mut self,
        id: Option<u32>,
        port: u32,
        name: &str,
        unit: &str,
        max: usize,
    ) -> Option<usize> {
        match self.find(id, port, name, unit) {
            Some(i) => Some(i),
            None if self.keys.len() >= max => None,
            None => Some(self.add(Key {
                id,
                port,
                name: name.to_owned(),
                unit: unit.to_owned(),
            })),
        }
    }
}

/// Whether another column of `keys` has the name and unit of `key` with another ID, and with
/// another port.
fn clash(keys: &[Key], key: &Key) -> (bool, bool) {
    let same = keys
        .iter()
        .filter(|k| k.name == key.name && k.unit == key.unit);
    let (mut id, mut port) = (false, false);
    for k in same {
        id |= k.id != key.id && k.port == key.port;
        port |= k.port != key.port;
    }
    (id, port)
}

/// `Name(unit)`, `Name@ID(unit)` when another ID of its port has the same name and unit,
/// `Name@PORT(unit)` (or `Name@ID@PORT(unit)`) when another port has.
fn label(k: &Key, (with_id, with_port): (bool, bool), ports: &[String]) -> String {
    let mut s = k.name.clone();
    if with_id && let Some(id) = k.id {
        let _ = write!(s, "@{id}");
    }
    if with_port && let Some(p) = ports.get(k.port as usize) {
        let _ = write!(s, "@{p}");
    }
    if !k.unit.is_empty() {
        let _ = write!(s, "({})", k.unit);
    }
    s
}

/// How the wide table is cut into time steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// A step ends when a row's ID comes round again (protocols that poll).
    PollCycle,
    /// Every row that carries numbers is a step (protocols without a poll cycle).
    Frame,
    /// Fixed steps of this many microseconds.
    Every(u64),
}

/// Writes the wide table.
pub struct Wide {
    format: Format,
    step: Step,
    utc: bool,
    /// Write as rows come (live) rather than at the end.
    live: bool,
    cols: Columns,
    /// At most this many columns.
    max_columns: usize,
    /// Numbers left out since their column would have been beyond `max_columns`.
    left_out: u64,
    /// Live: columns in the header line written last.
    header_cols: Option<usize>,
    /// Held value text of every column.
    held: Vec<String>,
    /// Files: the columns whose value changed since the last line, each once.
    changed: Vec<u32>,
    is_changed: Vec<bool>,
    /// IDs seen in the current step (poll cycles), each with its port's number.
    seen: Vec<(u32, u32)>,
    /// Which extra cell of a row names its port (several sources).
    port_column: Option<usize>,
    /// Time of the last row of the current step; `None`: no row since the last written step.
    pending: Option<u64>,
    /// Current interval (`--every`).
    bucket: Option<u64>,
    /// Whether the time is Date and Time (wall clock) or Millis; decided at the first line.
    wall: Option<bool>,
    /// Files: the lines so far as what changed in each ([`Wide::emit`]); in bounded memory,
    /// then a temporary file.
    spool: Spool,
    line: String,
    /// A record for the spool, or one read back from it.
    record: Vec<u8>,
    /// Files, at the end: every column's value as the lines read back so far left it.
    replay: Vec<String>,
}

impl Wide {
    pub fn new(format: Format, step: Step, utc: bool, live: bool, max_columns: usize) -> Self {
        Self::with_memory(format, step, utc, live, max_columns, spool::MEMORY)
    }

    /// [`Wide::new`] keeping up to `memory` bytes of a file's lines in memory (tests lower it).
    fn with_memory(
        format: Format,
        step: Step,
        utc: bool,
        live: bool,
        max_columns: usize,
        memory: usize,
    ) -> Self {
        Wide {
            format,
            step,
            utc,
            live,
            cols: Columns::default(),
            max_columns,
            left_out: 0,
            header_cols: None,
            held: Vec::new(),
            changed: Vec::new(),
            is_changed: Vec::new(),
            seen: Vec::new(),
            port_column: None,
            pending: None,
            bucket: None,
            wall: None,
            spool: Spool::new(memory),
            line: String::new(),
            record: Vec::new(),
            replay: Vec::new(),
        }
    }

    /// Rows name their port in extra cell `column` ([`crate::row::PORT_COLUMN`]).
    pub fn port_column(&mut self, column: Option<usize>) {
        self.port_column = column;
    }

    /// Takes one row of the long table; writes the previous step (to `buf` when live) when this
    /// row starts a new one. An error is the temporary file's (files only).
    pub fn row(
        &mut self,
        row: &Row<'_>,
        anchor: Option<Anchor>,
        buf: &mut Vec<u8>,
    ) -> io::Result<()> {
        let Some(t) = row.micros else {
            return Ok(());
        };
        // An error row carries no number (Row::parts); none enters the table all the same.
        let numbered = !row.parts.is_empty() && row.class != Class::Error;
        let port = match self.port_column.and_then(|c| row.extra.get(c)) {
            Some(p) => self.cols.port(p),
            None => 0,
        };
        match self.step {
            Step::PollCycle => {
                if let Some(id) = row.id {
                    if self.seen.contains(&(port, id)) {
                        if let Some(at) = self.pending {
                            self.emit(at, anchor, buf)?;
                        }
                        self.seen.clear();
                    }
                    self.seen.push((port, id));
                }
            }
            Step::Frame => {}
            Step::Every(us) => {
                let b = t / us;
                if let Some(cur) = self.bucket
                    && b != cur
                    && self.pending.is_some()
                {
                    self.emit((cur + 1).saturating_mul(us), anchor, buf)?;
                }
                self.bucket = Some(b);
            }
        }
        if numbered {
            for p in row.parts {
                let Some(i) = self
                    .cols
                    .column(row.id, port, p.name, p.unit, self.max_columns)
                else {
                    self.left_out += 1;
                    continue;
                };
                if i >= self.held.len() {
                    self.held.resize(i + 1, String::new());
                    self.is_changed.resize(i + 1, false);
                }
                if self.held[i] != p.text {
                    self.held[i].clear();
                    self.held[i].push_str(p.text);
                    if !self.live && !self.is_changed[i] {
                        self.is_changed[i] = true;
                        self.changed.push(i as u32);
                    }
                }
            }
        }
        match self.step {
            // One line per row with numbers.
            Step::Frame if numbered => self.emit(t, anchor, buf)?,
            Step::Frame => {}
            // A row with numbers and no ID cannot come round again: it is a step of its own.
            Step::PollCycle if numbered && row.id.is_none() => {
                self.emit(t, anchor, buf)?;
                self.seen.clear();
            }
            _ => self.pending = Some(t),
        }
        Ok(())
    }

    /// Writes the open step and, for files, the header (end of input); the lines of a file
    /// follow with [`Wide::lines`]. An error is the temporary file's.
    pub fn finish(&mut self, anchor: Option<Anchor>, buf: &mut Vec<u8>) -> io::Result<()> {
        if let Some(at) = self.pending {
            let at = match (self.step, self.bucket) {
                (Step::Every(us), Some(b)) => (b + 1).saturating_mul(us),
                _ => at,
            };
            self.emit(at, anchor, buf)?;
        }
        if self.live {
            if self.header_cols.is_none() {
                self.header(anchor, buf);
            }
            return Ok(());
        }
        self.cols.finalize();
        self.header(anchor, buf);
        self.held = Vec::new();
        self.replay = vec![String::new(); self.cols.len()];
        self.spool.rewind()
    }

    /// Files, after [`Wide::finish`]: writes the next lines, padded to every column, until `buf`
    /// has grown by `budget` bytes, so that the output writes the table in pieces instead of
    /// holding all of it; whole lines only. Says whether lines remain. An error is the
    /// temporary file's.
    pub fn lines(&mut self, buf: &mut Vec<u8>, budget: usize) -> io::Result<bool> {
        let sep = self.sep() as u8;
        let eol = self.eol().as_bytes();
        let start = buf.len();
        while buf.len() - start < budget {
            if !self.spool.next(&mut self.record)? {
                break;
            }
            let time = replay(&self.record, &mut self.replay).ok_or_else(|| {
                io::Error::new(
                    io::ErrorKind::InvalidData,
                    "the temporary file holds what was not written to it",
                )
            })?;
            buf.extend_from_slice(time);
            for v in &self.replay {
                buf.push(sep);
                buf.extend_from_slice(v.as_bytes());
            }
            buf.extend_from_slice(eol);
        }
        Ok(self.spool.has_more())
    }

    /// Whether any row carried a number (the table has columns).
    pub fn has_columns(&self) -> bool {
        !self.cols.is_empty()
    }

    /// Numbers left out because the table had `--max-columns` columns already: (the cap, the
    /// count).
    pub fn left_out(&self) -> Option<(usize, u64)> {
        (self.left_out > 0).then_some((self.max_columns, self.left_out))
    }

    fn sep(&self) -> char {
        if self.format == Format::Csv {
            ','
        } else {
            '\t'
        }
    }

    fn eol(&self) -> &'static str {
        if self.format == Format::Csv {
            "\r\n"
        } else {
            "\n"
        }
    }

    fn header(&mut self, anchor: Option<Anchor>, buf: &mut Vec<u8>) {
        let wall = *self.wall.get_or_insert(anchor.is_some());
        let sep = self.sep();
        self.line.clear();
        if wall {
            self.line.push_str("Date");
            self.line.push(sep);
            self.line.push_str("Time");
        } else {
            self.line.push_str("Millis");
        }
        for l in self.cols.labels() {
            self.line.push(sep);
            push_cell(&mut self.line, l, self.format);
        }
        self.line.push_str(self.eol());
        buf.extend_from_slice(self.line.as_bytes());
        self.header_cols = Some(self.cols.len());
    }

    /// Ends a step at `at`: live, its line goes to `buf`; files, what changed since the line
    /// before goes to the spool.
    fn emit(&mut self, at: u64, anchor: Option<Anchor>, buf: &mut Vec<u8>) -> io::Result<()> {
        self.pending = None;
        if self.cols.is_empty() {
            // No number yet (polls only): a line of empty cells says nothing.
            return Ok(());
        }
        let wall = *self.wall.get_or_insert(anchor.is_some());
        if self.live && self.header_cols != Some(self.cols.len()) {
            self.header(anchor, buf);
        }
        let sep = self.sep();
        self.line.clear();
        match anchor.filter(|_| wall).map(|a| a.plus(at)) {
            Some(Some(t)) => {
                let (date, time) = match t {
                    Anchor::Naive(t) => (t.format("%Y-%m-%d"), t.format("%H:%M:%S%.3f")),
                    Anchor::Instant(i) if self.utc => {
                        let t = i.naive_utc();
                        (t.format("%Y-%m-%d"), t.format("%H:%M:%S%.3f"))
                    }
                    Anchor::Instant(i) => {
                        let l: DateTime<Local> = i.into();
                        let t = l.naive_local();
                        (t.format("%Y-%m-%d"), t.format("%H:%M:%S%.3f"))
                    }
                };
                let _ = write!(self.line, "{date}{sep}{time}");
            }
            // No anchor, or beyond the calendar (a corrupt time stamp): empty cells.
            _ if wall => self.line.push(sep),
            _ => {
                let _ = write!(self.line, "{}", at / 1000);
            }
        }
        if self.live {
            for v in &self.held {
                self.line.push(sep);
                self.line.push_str(v);
            }
            // Columns added in this step but never given a value yet are empty cells too.
            for _ in self.held.len()..self.cols.len() {
                self.line.push(sep);
            }
            self.line.push_str(self.eol());
            buf.extend_from_slice(self.line.as_bytes());
            return Ok(());
        }
        // The record: the time text, then (column, value) for every column that changed.
        self.record.clear();
        put_text(&mut self.record, self.line.as_bytes());
        for &i in &self.changed {
            put_varint(&mut self.record, i as usize);
            put_text(&mut self.record, self.held[i as usize].as_bytes());
            self.is_changed[i as usize] = false;
        }
        self.changed.clear();
        self.spool.push(&self.record)
    }
}

/// Appends `n` in 7-bit groups, the lowest first, the high bit set on all but the last
/// (LEB128): a column below 128 or a value's length take one byte.
fn put_varint(out: &mut Vec<u8>, mut n: usize) {
    while n >= 0x80 {
        out.push(n as u8 | 0x80);
        n >>= 7;
    }
    out.push(n as u8);
}

/// Reads what [`put_varint`] wrote.
fn take_varint(rest: &mut &[u8]) -> Option<usize> {
    let mut n = 0usize;
    for shift in (0..64).step_by(7) {
        let (&b, tail) = rest.split_first()?;
        *rest = tail;
        n |= ((b & 0x7F) as usize).checked_shl(shift)?;
        if b & 0x80 == 0 {
            return Some(n);
        }
    }
    None
}

/// Appends `text` with its length ([`put_varint`]) before it.
fn put_text(out: &mut Vec<u8>, text: &[u8]) {
    put_varint(out, text.len());
    out.extend_from_slice(text);
}

/// Applies a spooled record ([`Wide::emit`]) to `values`; returns its time text. `None`: the
/// record is not one the wide table wrote.
fn replay<'r>(record: &'r [u8], values: &mut [String]) -> Option<&'r [u8]> {
    fn take<'r>(rest: &mut &'r [u8], n: usize) -> Option<&'r [u8]> {
        let (a, b) = rest.split_at_checked(n)?;
        *rest = b;
        Some(a)
    }
    let mut rest = record;
    let n = take_varint(&mut rest)?;
    let time = take(&mut rest, n)?;
    while !rest.is_empty() {
        let col = take_varint(&mut rest)?;
        let n = take_varint(&mut rest)?;
        let text = std::str::from_utf8(take(&mut rest, n)?).ok()?;
        let v = values.get_mut(col)?;
        v.clear();
        v.push_str(text);
    }
    Some(time)
}

/// A header label as a cell: CSV quotes it when needed; TSV replaces control characters.
fn push_cell(out: &mut String, s: &str, format: Format) {
    if format == Format::Csv && s.contains([',', '"', '\n', '\r']) {
        out.push('"');
        out.push_str(&s.replace('"', "\"\""));
        out.push('"');
    } else {
        out.extend(s.chars().map(|c| if c.is_control() { ' ' } else { c }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::row::{Class, Part, Parts};

    fn row(micros: u64, id: u32, parts: &[Part<'static>]) -> Row<'static> {
        Row {
            stamp: 0,
            micros: Some(micros),
            id: Some(id),
            device: "",
            kind: "Data",
            class: Class::Plain,
            sensor_no: "",
            sensor: "",
            data: "",
            extra: &[],
            parts: Parts::List(parts.to_vec().leak()),
            raw: &[],
        }
    }

    fn part(name: &'static str, unit: &'static str, text: &'static str) -> Part<'static> {
        Part {
            name,
            unit,
            text,
            value: text.parse().unwrap(),
        }
    }

    /// Writes the table as [`super::super::Table::close`] does: the header, then the lines in
    /// pieces of `budget` bytes.
    fn finish(w: &mut Wide, buf: &mut Vec<u8>, budget: usize) {
        w.finish(None, buf).unwrap();
        while w.lines(buf, budget).unwrap() {}
    }

    fn feed(live: bool, step: Step) -> String {
        let mut w = Wide::new(Format::Csv, step, false, live, MAX_COLUMNS);
        let mut buf = Vec::new();
        let rows = [
            row(0, 1, &[]),
            row(10_000, 1, &[part("Cell1", "V", "4.122")]),
            row(20_000, 8, &[part("Cell1", "V", "4.138")]),
            row(
                30_000,
                1,
                &[part("Cell1", "V", "4.120"), part("Cell2", "V", "4.144")],
            ),
            row(40_000, 2, &[part("SWR", "", "16")]),
            row(50_000, 1, &[]),
        ];
        for r in &rows {
            w.row(r, None, &mut buf).unwrap();
        }
        finish(&mut w, &mut buf, 1);
        String::from_utf8(buf).unwrap().replace("\r\n", "\n")
    }

    #[test]
    fn files_get_one_complete_header_and_padded_lines() {
        assert_eq!(
            feed(false, Step::PollCycle),
            "Millis,Cell1@1(V),Cell1@8(V),Cell2(V),SWR\n\
             20,4.122,4.138,,\n\
             40,4.120,4.138,4.144,16\n\
             50,4.120,4.138,4.144,16\n"
        );
    }

    /// A long capture: the lines beyond the memory bound go to the temporary file, the memory
    /// held stays bounded, and the table is the same byte for byte as when all of it fits in
    /// memory, written in small pieces or in one.
    #[test]
    fn a_long_file_spills_to_a_temporary_file_with_the_same_table() {
        let table = |memory: usize, budget: usize| {
            let mut w = Wide::with_memory(
                Format::Tsv,
                Step::PollCycle,
                false,
                false,
                MAX_COLUMNS,
                memory,
            );
            let mut buf = Vec::new();
            let mut bound = 0;
            for i in 0..20_000u64 {
                // A second sensor appears halfway: earlier lines are padded at the end.
                let parts: &[Part<'static>] = match i % 3 {
                    0 => &[part("Cell1", "V", "4.122"), part("Cell2", "V", "4.138")],
                    1 if i > 10_000 => &[part("SWR", "", "16")],
                    _ => &[],
                };
                w.row(&row(i * 1000, (i % 3) as u32, parts), None, &mut buf)
                    .unwrap();
                bound = bound.max(w.spool.in_memory());
            }
            assert!(buf.is_empty(), "a file's table is written at the end");
            let spilled = w.spool.spilled();
            finish(&mut w, &mut buf, budget);
            (String::from_utf8(buf).unwrap(), bound, spilled)
        };
        let (whole, _, spilled) = table(spool::MEMORY, usize::MAX);
        assert!(!spilled);
        let (pieces, bound, spilled) = table(4096, 100);
        assert!(spilled);
        assert!(bound < 4096, "memory held: {bound} bytes");
        assert_eq!(pieces, whole);
        assert!(whole.starts_with("Millis\tCell1(V)\tCell2(V)\tSWR\n2\t4.122\t4.138\t\n"));
        assert!(whole.ends_with("\n19999\t4.122\t4.138\t16\n"));
        assert_eq!(whole.lines().count(), 1 + 6667);
    }

    /// The spool holds what changed, not every line padded to every column: 500 columns, then
    /// 20 000 lines in which one value changes take a few bytes each, and the table rebuilt from
    /// them is every column of every line.
    #[test]
    fn the_spool_grows_with_the_changes_not_with_the_columns() {
        let names: Vec<&'static str> = (0..500).map(|i| &*format!("N{i}").leak()).collect();
        let values: Vec<&'static str> = (0..20).map(|i| &*format!("{i}").leak()).collect();
        let mut w = Wide::with_memory(Format::Tsv, Step::Frame, false, false, MAX_COLUMNS, 4096);
        let mut buf = Vec::new();
        for (i, n) in names.iter().enumerate() {
            w.row(
                &row(i as u64 * 1000, 1, &[part(n, "", "1")]),
                None,
                &mut buf,
            )
            .unwrap();
        }
        let first = w.spool.total();
        for i in 0..20_000u64 {
            let p = part(names[i as usize % 500], "", values[i as usize % 20]);
            w.row(&row(1_000_000 + i * 1000, 1, &[p]), None, &mut buf)
                .unwrap();
        }
        let per_line = (w.spool.total() - first) / 20_000;
        assert!(per_line <= 16, "{per_line} bytes per line");
        finish(&mut w, &mut buf, 1000);
        let table = String::from_utf8(buf).unwrap();
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines.len(), 1 + 500 + 20_000);
        assert!(lines.iter().all(|l| l.split('\t').count() == 501));
        // The last line: every column's last value.
        let last: Vec<&str> = lines[20_500].split('\t').collect();
        assert_eq!(last[0], "20999");
        for c in 0..500 {
            let i = (0..20_000).rev().find(|i| i % 500 == c).unwrap();
            assert_eq!(last[1 + c], values[i % 20], "column {c}");
        }
        assert_eq!(lines[1], format!("0\t1{}", "\t".repeat(499)));
    }

    /// Beyond the cap, numbers of new columns are left out and counted; known columns go on.
    #[test]
    fn columns_beyond_the_cap_are_left_out_and_counted() {
        let mut w = Wide::new(Format::Csv, Step::Frame, false, false, 2);
        let mut buf = Vec::new();
        let rows = [
            row(
                0,
                1,
                &[part("A", "", "1"), part("B", "", "2"), part("C", "", "3")],
            ),
            row(1000, 2, &[part("A", "", "4")]),
            row(2000, 1, &[part("B", "", "5")]),
        ];
        for r in &rows {
            w.row(r, None, &mut buf).unwrap();
        }
        assert_eq!(w.left_out(), Some((2, 2)));
        finish(&mut w, &mut buf, 1);
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "Millis,A,B\r\n0,1,2\r\n1,1,2\r\n2,1,5\r\n"
        );
    }

    /// Frames step one line per row with numbers, error rows never enter.
    #[test]
    fn frames_step_one_line_per_row_with_numbers() {
        let mut w = Wide::new(Format::Csv, Step::Frame, false, false, MAX_COLUMNS);
        let mut buf = Vec::new();
        let mut bad = row(3000, 1, &[part("A", "", "9")]);
        bad.class = Class::Error;
        let rows = [
            row(0, 1, &[]),
            row(1000, 1, &[part("A", "", "1")]),
            row(2000, 2, &[part("A", "", "2")]),
            bad,
            row(4000, 2, &[]),
            row(5000, 1, &[part("A", "", "3")]),
        ];
        for r in &rows {
            w.row(r, None, &mut buf).unwrap();
        }
        finish(&mut w, &mut buf, 1);
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "Millis,A@1,A@2\r\n1,1,\r\n2,1,2\r\n5,3,2\r\n"
        );
    }

    #[test]
    fn live_columns_appear_as_sensors_appear() {
        // The first Cell1 keeps its plain name; the header is written again for new columns.
        assert_eq!(
            feed(true, Step::PollCycle),
            "Millis,Cell1(V),Cell1@8(V)\n\
             20,4.122,4.138\n\
             Millis,Cell1(V),Cell1@8(V),Cell2(V),SWR\n\
             40,4.120,4.138,4.144,16\n\
             50,4.120,4.138,4.144,16\n"
        );
    }

    #[test]
    fn every_cuts_fixed_steps_at_their_end() {
        assert_eq!(
            feed(false, Step::Every(25_000)),
            "Millis,Cell1@1(V),Cell1@8(V),Cell2(V),SWR\n\
             25,4.122,4.138,,\n\
             50,4.120,4.138,4.144,16\n\
             75,4.120,4.138,4.144,16\n"
        );
    }
}
