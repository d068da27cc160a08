//! The wide export (`--wide`): one row per time step, one column per sensor seen, the last value
//! held, as a radio's SD-card log writes it.
//!
//! A **time step** is a poll cycle: it ends when a row's `ID` comes round again (S.Port: the next
//! poll of a physical ID; S-Bus: the next telegram of a station; SAB: the next frame of an
//! address), or, with `--every MS`, a fixed interval of capture time. A line is written for every
//! step in which at least one row arrived; its time is the time of the step's last row (with
//! `--every`, the end of the interval), its cells the last value of every column at that time.
//! Steps before the first number (polls that nobody answered) write no line.
//!
//! **Columns** come from the rows' [`Part`](crate::row::Part)s: every number of a row (an FLVSS
//! frame's cells, an S-Bus response's registers) is its own column, named `Name(unit)` as EdgeTX
//! names the columns of its logs (`RxBt(V)`, `Cell1(V)`; `SWR` has no unit). When two IDs send a
//! number of the same name and unit (two FLVSS), the columns carry the ID: `Cell1@1(V)`,
//! `Cell1@8(V)`. With several sources (a `Port` column), each port's numbers are its own
//! columns, and a name two ports share carries the port: `RxBt@/dev/ttyUSB1(V)` (after the ID,
//! when that is shared too); a poll cycle ends when an ID comes round again on its own port.
//! Columns are in order of first appearance.
//!
//! **Files** (and pipes) are read once and the table is written at the end, so that the header is
//! complete and every shared name carries its ID: lines of steps before a column appeared have an
//! empty cell there. **Live sources** (a serial port) are written as they come: a column is added
//! at the end when its sensor first appears, and the header line is written again with the new
//! column (earlier lines have fewer cells); a number whose name is already taken by another ID
//! gets the `@ID` form, the earlier column keeps its plain name.
//!
//! Rows whose check failed carry no numbers (see [`crate::row::Row::parts`]), so a corrupted frame
//! never enters the wide table.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io;

use chrono::{DateTime, Local};

use super::Format;
use super::spool::{self, Spool};
use crate::row::Row;
use crate::time::Anchor;

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
        for i in 0..self.keys.len() {
            let k = &self.keys[i];
            let clash = clash(&self.keys, k);
            self.labels[i] = label(k, clash, &self.ports);
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

    /// Index of a row's part (`port`: its number, [`Columns::port`]), adding the column when it
    /// is new.
    pub fn column(&mut self, id: Option<u32>, port: u32, name: &str, unit: &str) -> usize {
        match self.find(id, port, name, unit) {
            Some(i) => i,
            None => self.add(Key {
                id,
                port,
                name: name.to_owned(),
                unit: unit.to_owned(),
            }),
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
    /// A step ends when a row's ID comes round again.
    PollCycle,
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
    /// Live: columns in the header line written last.
    header_cols: Option<usize>,
    /// Held value text of every column.
    held: Vec<String>,
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
    /// Files: the lines written so far (without their end), each with its cell count; in
    /// bounded memory, then a temporary file.
    spool: Spool,
    line: String,
    /// A line read back from the spool.
    back: Vec<u8>,
}

impl Wide {
    pub fn new(format: Format, step: Step, utc: bool, live: bool) -> Self {
        Self::with_memory(format, step, utc, live, spool::MEMORY)
    }

    /// [`Wide::new`] keeping up to `memory` bytes of a file's lines in memory (tests lower it).
    fn with_memory(format: Format, step: Step, utc: bool, live: bool, memory: usize) -> Self {
        Wide {
            format,
            step,
            utc,
            live,
            cols: Columns::default(),
            header_cols: None,
            held: Vec::new(),
            seen: Vec::new(),
            port_column: None,
            pending: None,
            bucket: None,
            wall: None,
            spool: Spool::new(memory),
            line: String::new(),
            back: Vec::new(),
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
        for p in row.parts {
            let i = self.cols.column(row.id, port, p.name, p.unit);
            if i >= self.held.len() {
                self.held.resize(i + 1, String::new());
            }
            self.held[i].clear();
            self.held[i].push_str(p.text);
        }
        self.pending = Some(t);
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
        self.spool.rewind()
    }

    /// Files, after [`Wide::finish`]: writes the next lines, padded to every column, until `buf`
    /// has grown by `budget` bytes, so that the output writes the table in pieces instead of
    /// holding all of it; whole lines only. Says whether lines remain. An error is the
    /// temporary file's.
    pub fn lines(&mut self, buf: &mut Vec<u8>, budget: usize) -> io::Result<bool> {
        let n = self.cols.len();
        let sep = self.sep() as u8;
        let eol = self.eol().as_bytes();
        let start = buf.len();
        while buf.len() - start < budget {
            let Some(cells) = self.spool.next(&mut self.back)? else {
                break;
            };
            buf.extend_from_slice(&self.back);
            buf.extend(std::iter::repeat_n(sep, n.saturating_sub(cells)));
            buf.extend_from_slice(eol);
        }
        Ok(self.spool.has_more())
    }

    /// Whether any row carried a number (the table has columns).
    pub fn has_columns(&self) -> bool {
        !self.cols.is_empty()
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
        match anchor {
            Some(a) if wall => {
                let delta = chrono::Duration::microseconds(at.min(i64::MAX as u64) as i64);
                let (date, time) = match a {
                    Anchor::Naive(n) => {
                        let t = n + delta;
                        (t.format("%Y-%m-%d"), t.format("%H:%M:%S%.3f"))
                    }
                    Anchor::Instant(i) if self.utc => {
                        let t = (i + delta).naive_utc();
                        (t.format("%Y-%m-%d"), t.format("%H:%M:%S%.3f"))
                    }
                    Anchor::Instant(i) => {
                        let l: DateTime<Local> = (i + delta).into();
                        let t = l.naive_local();
                        (t.format("%Y-%m-%d"), t.format("%H:%M:%S%.3f"))
                    }
                };
                let _ = write!(self.line, "{date}{sep}{time}");
            }
            _ if wall => self.line.push(sep),
            _ => {
                let _ = write!(self.line, "{}", at / 1000);
            }
        }
        for v in &self.held {
            self.line.push(sep);
            self.line.push_str(v);
        }
        // Columns added in this step but never given a value yet are empty cells too.
        for _ in self.held.len()..self.cols.len() {
            self.line.push(sep);
        }
        if self.live {
            self.line.push_str(self.eol());
            buf.extend_from_slice(self.line.as_bytes());
            Ok(())
        } else {
            self.spool.push(self.cols.len(), self.line.as_bytes())
        }
    }
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
        let mut w = Wide::new(Format::Csv, step, false, live);
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
            let mut w = Wide::with_memory(Format::Tsv, Step::PollCycle, false, false, memory);
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
