//! Sinks: the log table as pretty text, TSV, CSV or JSON Lines.

pub mod output;
mod tap;
pub mod wide;

use std::io::Write as _;
use std::path::Path;

use chrono::{DateTime, Local};

use crate::fmt::push_hex_bytes;
use crate::row::RowOut;
use crate::row::{BASE_COLUMNS, Class, Row};
use crate::time::Anchor;
pub use output::Output;
pub use tap::{Tap, Tapped};

use crate::row::{OutputError, RowResult};

/// Output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Aligned, coloured columns for a terminal.
    Pretty,
    /// Tab-separated values with a header row.
    Tsv,
    /// Comma-separated values (RFC 4180) with a header row.
    Csv,
    /// One JSON object per row.
    Jsonl,
}

impl Format {
    /// Format implied by a file name's extension, if any.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "csv" => Format::Csv,
            "tsv" | "tab" => Format::Tsv,
            "jsonl" | "ndjson" | "json" => Format::Jsonl,
            "txt" | "log" => Format::Pretty,
            _ => return None,
        })
    }
}

/// How the table is written.
#[derive(Clone, Debug)]
pub struct TableOptions {
    pub format: Format,
    pub color: bool,
    /// Add a `Raw` column with the on-wire bytes.
    pub raw: bool,
    /// Add a `Time` column with wall-clock times.
    pub time_abs: bool,
    /// Print wall-clock times in UTC instead of local time.
    pub utc: bool,
}

/// Writes rows in the chosen format, numbering them (`Counter`).
pub struct Table {
    opts: TableOptions,
    out: Output,
    columns: Vec<&'static str>,
    /// Pretty output: the width of each column now (they only grow).
    widths: Vec<usize>,
    /// Number of the decoder's extra columns.
    n_extra: usize,
    counter: u64,
    /// The Counter's decimal digits, incremented in place with `counter`.
    digits: Digits,
    /// JSON Lines: the key of each extra column (`,"resp_ms":`), built once, and whether
    /// its cells are numbers.
    json_keys: Vec<(Vec<u8>, bool)>,
    /// Rows of whole frames (with wire bytes, not an error or a note).
    frames: u64,
    /// Rows counted but not written (filtered out).
    skipped: u64,
    anchor: Option<Anchor>,
    header_written: bool,
    scratch: String,
    hex: Vec<u8>,
    error: Option<OutputError>,
    /// `--wide`: rows go to the wide table instead.
    wide: Option<wide::Wide>,
    /// `busnoop plot`: rows go to the plot, drawn at the end.
    plot: Option<crate::plot::Plot>,
}

/// A row counter as decimal digits, incremented in place (no division per row).
#[derive(Clone, Debug)]
struct Digits {
    buf: [u8; 20],
    start: usize,
}

impl Digits {
    fn zero() -> Self {
        let mut buf = [b'0'; 20];
        buf[19] = b'0';
        Digits { buf, start: 19 }
    }

    fn increment(&mut self) {
        let mut i = self.buf.len();
        while i > 0 {
            i -= 1;
            if self.buf[i] == b'9' {
                self.buf[i] = b'0';
            } else {
                self.buf[i] += 1;
                self.start = self.start.min(i);
                return;
            }
        }
    }

    fn as_bytes(&self) -> &[u8] {
        &self.buf[self.start..]
    }

    fn as_str(&self) -> &str {
        // Only ASCII digits are ever stored.
        std::str::from_utf8(self.as_bytes()).unwrap_or("")
    }
}

/// The column after `Data` in TSV, CSV and JSON Lines (not in pretty output, where Data says
/// the same): the row's first number ([`Row::value`]).
pub const VALUE_COLUMN: &str = "Value";

/// Extra columns whose cells are numbers (JSON writes them as numbers).
const NUMERIC_EXTRA: [&str; 2] = ["Resp ms", "Seq"];

/// Pretty-output column widths for the base columns, when the protocol gives none (see
/// [`crate::protocol::Protocol::pretty_widths`]).
const PRETTY_WIDTHS: [usize; 8] = [7, 8, 3, 10, 9, 8, 10, 30];

/// A pretty column grows to fit a longer value (and stays that wide, so later rows stay
/// aligned with each other) up to this many characters; a longer value overflows its row only.
pub const PRETTY_GROW_MAX: usize = 60;

impl Table {
    pub fn new(out: Output, opts: TableOptions, extra: &[&'static str]) -> Self {
        let mut columns: Vec<&'static str> = BASE_COLUMNS.to_vec();
        if opts.format != Format::Pretty {
            columns.push(VALUE_COLUMN);
        }
        columns.extend_from_slice(extra);
        if opts.raw {
            columns.push("Raw");
        }
        if opts.time_abs {
            columns.push("Time");
        }
        let json_keys = extra
            .iter()
            .map(|name| (json_key(name), NUMERIC_EXTRA.contains(name)))
            .collect();
        let widths = columns
            .iter()
            .enumerate()
            .map(|(i, c)| PRETTY_WIDTHS.get(i).copied().unwrap_or(c.len().max(4)))
            .collect();
        Table {
            opts,
            out,
            columns,
            widths,
            n_extra: extra.len(),
            counter: 0,
            digits: Digits::zero(),
            json_keys,
            frames: 0,
            skipped: 0,
            anchor: None,
            wide: None,
            plot: None,
            header_written: false,
            scratch: String::new(),
            hex: Vec::new(),
            error: None,
        }
    }

    /// Sets the pretty widths of the first columns (the base columns and the protocol's extra
    /// columns, in order: the protocol descriptor's `pretty_widths`); never narrower than a
    /// column's name. Call before the header is written.
    pub fn set_pretty_widths(&mut self, widths: &[usize]) {
        for ((w, &new), name) in self.widths.iter_mut().zip(widths).zip(&self.columns) {
            *w = new.max(name.chars().count());
        }
    }

    /// Rows so far: written ones and skipped ones (the last Counter).
    pub fn rows(&self) -> u64 {
        self.counter
    }

    /// Rows of frames with a valid check written so far (polls, requests, answers, data; not
    /// errors, garbage, timeouts or notes): "did anything decode".
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Counts a row a filter keeps out of the output, so that every row's Counter is its
    /// number in the unfiltered table.
    pub fn skip(&mut self) {
        self.counter += 1;
        self.digits.increment();
        self.skipped += 1;
    }

    /// Rows counted with [`Table::skip`].
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    pub fn set_anchor(&mut self, anchor: Option<Anchor>) {
        self.anchor = anchor;
    }

    /// Writes the wide table ([`wide`]) instead of the long one: CSV and TSV only (the caller
    /// checks); `live`: write lines as they come rather than at the end.
    pub fn set_wide(&mut self, step: wide::Step, live: bool) {
        self.wide = Some(wide::Wide::new(self.opts.format, step, self.opts.utc, live));
    }

    /// Collects the rows' numbers for `busnoop plot` instead of writing the table.
    pub fn set_plot(&mut self, spec: crate::plot::PlotSpec) {
        self.plot = Some(crate::plot::Plot::new(spec));
    }

    /// Writes the header row (TSV, CSV, pretty); JSON Lines has none.
    pub fn header(&mut self) -> Result<(), OutputError> {
        if self.header_written {
            return Ok(());
        }
        self.header_written = true;
        if self.wide.is_some() || self.plot.is_some() {
            // The wide table writes its own header.
            return Ok(());
        }
        let cols = self.columns.clone();
        match self.opts.format {
            Format::Tsv => {
                let buf = self.out.buf();
                for (i, c) in cols.iter().enumerate() {
                    if i > 0 {
                        buf.push(b'\t');
                    }
                    buf.extend_from_slice(c.as_bytes());
                }
                buf.push(b'\n');
            }
            Format::Csv => {
                let buf = self.out.buf();
                for (i, c) in cols.iter().enumerate() {
                    if i > 0 {
                        buf.push(b',');
                    }
                    push_csv_field(buf, c.as_bytes());
                }
                buf.extend_from_slice(b"\r\n");
            }
            Format::Pretty => {
                let color = self.opts.color;
                let buf = self.out.buf();
                let mut line = PrettyLine::start(buf, color.then_some(BOLD));
                for (i, c) in cols.iter().enumerate() {
                    line.cell(&mut self.widths, i, c, false, i + 1 == cols.len());
                }
                line.finish();
            }
            Format::Jsonl => {}
        }
        self.out.row_done()
    }

    /// Writes one row.
    pub fn write(&mut self, row: &Row<'_>) -> Result<(), OutputError> {
        if !self.header_written {
            self.header()?;
        }
        self.counter += 1;
        self.digits.increment();
        if !row.raw.is_empty() && !matches!(row.class, Class::Error | Class::Info) {
            self.frames += 1;
        }
        if let Some(p) = &mut self.plot {
            p.row(row);
            return Ok(());
        }
        if let Some(w) = &mut self.wide {
            w.row(row, self.anchor, self.out.buf());
            return self.out.row_done();
        }
        match self.opts.format {
            Format::Tsv => self.tsv(row),
            Format::Csv => self.csv_row(row),
            Format::Pretty => self.pretty(row),
            Format::Jsonl => self.jsonl(row),
        }
        self.out.row_done()
    }

    /// Writes everything buffered (live output after each chunk; end of run).
    pub fn flush(&mut self) -> Result<(), OutputError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.out.flush()
    }

    /// Flushes and closes the output.
    pub fn close(&mut self) -> Result<(), OutputError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        if let Some(p) = self.plot.take() {
            p.draw().map_err(|e| OutputError {
                path: Some(p.path().to_owned()),
                error: std::io::Error::other(e),
            })?;
        }
        if let Some(mut w) = self.wide.take() {
            w.finish(self.anchor, self.out.buf());
            if !w.has_columns() {
                eprintln!(
                    "busnoop: note: --wide: no row carried a number, so the table has no columns"
                );
            }
        }
        self.out.close()
    }

    /// The output (tests read memory outputs back).
    #[cfg(test)]
    pub fn output(&self) -> &Output {
        &self.out
    }

    fn wall_time(&mut self, micros: Option<u64>) -> &str {
        self.scratch.clear();
        if let (Some(anchor), Some(us)) = (self.anchor, micros) {
            let delta = chrono::Duration::microseconds(us as i64);
            use std::fmt::Write as _;
            match anchor {
                Anchor::Naive(n) => {
                    let _ = write!(
                        self.scratch,
                        "{}",
                        (n + delta).format("%Y-%m-%dT%H:%M:%S%.3f")
                    );
                }
                Anchor::Instant(t) => {
                    let t = t + delta;
                    if self.opts.utc {
                        let _ = write!(self.scratch, "{}", t.format("%Y-%m-%dT%H:%M:%S%.3fZ"));
                    } else {
                        let local: DateTime<Local> = t.into();
                        let _ =
                            write!(self.scratch, "{}", local.format("%Y-%m-%dT%H:%M:%S%.3f%:z"));
                    }
                }
            }
        }
        &self.scratch
    }

    fn tsv(&mut self, row: &Row<'_>) {
        if self.opts.time_abs {
            self.wall_time(row.micros);
        }
        let time = self.opts.time_abs.then_some(self.scratch.as_str());
        let raw = self.opts.raw;
        let n_extra = self.n_extra;
        let buf = self.out.buf();
        let mut ib = itoa::Buffer::new();
        buf.extend_from_slice(self.digits.as_bytes());
        buf.push(b'\t');
        if let Some(us) = row.micros {
            buf.extend_from_slice(ib.format(us / 1000).as_bytes());
        }
        buf.push(b'\t');
        if let Some(id) = row.id {
            buf.extend_from_slice(ib.format(id).as_bytes());
        }
        for field in [row.device, row.kind, row.sensor_no, row.sensor, row.data] {
            buf.push(b'\t');
            push_tsv_field(buf, field);
        }
        buf.push(b'\t');
        buf.extend_from_slice(row.value().as_bytes());
        for i in 0..n_extra {
            buf.push(b'\t');
            push_tsv_field(buf, row.extra.get(i).copied().unwrap_or(""));
        }
        if raw {
            buf.push(b'\t');
            push_hex_bytes(buf, row.raw);
        }
        if let Some(t) = time {
            buf.push(b'\t');
            buf.extend_from_slice(t.as_bytes());
        }
        buf.push(b'\n');
    }

    fn csv_row(&mut self, row: &Row<'_>) {
        if self.opts.time_abs {
            self.wall_time(row.micros);
        }
        let time = self.opts.time_abs.then_some(self.scratch.as_str());
        let buf = self.out.buf();
        let mut ib = itoa::Buffer::new();
        buf.extend_from_slice(self.digits.as_bytes());
        buf.push(b',');
        if let Some(us) = row.micros {
            buf.extend_from_slice(ib.format(us / 1000).as_bytes());
        }
        buf.push(b',');
        if let Some(id) = row.id {
            buf.extend_from_slice(ib.format(id).as_bytes());
        }
        for field in [row.device, row.kind, row.sensor_no, row.sensor, row.data] {
            buf.push(b',');
            push_csv_field(buf, field.as_bytes());
        }
        buf.push(b',');
        push_csv_field(buf, row.value().as_bytes());
        for i in 0..self.n_extra {
            buf.push(b',');
            push_csv_field(buf, row.extra.get(i).copied().unwrap_or("").as_bytes());
        }
        if self.opts.raw {
            // Hex digits and spaces: never quoted.
            buf.push(b',');
            push_hex_bytes(buf, row.raw);
        }
        if let Some(t) = time {
            buf.push(b',');
            push_csv_field(buf, t.as_bytes());
        }
        buf.extend_from_slice(b"\r\n");
    }

    fn jsonl(&mut self, row: &Row<'_>) {
        if self.opts.time_abs {
            self.wall_time(row.micros);
        }
        let time = self.opts.time_abs.then_some(self.scratch.as_str());
        let buf = self.out.buf();
        let mut ib = itoa::Buffer::new();
        buf.extend_from_slice(b"{\"counter\":");
        buf.extend_from_slice(self.digits.as_bytes());
        buf.extend_from_slice(b",\"millis\":");
        match row.micros {
            Some(us) => buf.extend_from_slice(ib.format(us / 1000).as_bytes()),
            None => buf.extend_from_slice(b"null"),
        }
        buf.extend_from_slice(b",\"id\":");
        match row.id {
            Some(id) => buf.extend_from_slice(ib.format(id).as_bytes()),
            None => buf.extend_from_slice(b"null"),
        }
        let base = [
            (&b",\"device\":"[..], row.device),
            (b",\"type\":", row.kind),
            (b",\"sensor_no\":", row.sensor_no),
            (b",\"sensor\":", row.sensor),
            (b",\"data\":", row.data),
        ];
        for (k, v) in base {
            buf.extend_from_slice(k);
            push_json_str(buf, v);
        }
        buf.extend_from_slice(b",\"value\":");
        match row.parts.first() {
            Some(p) => buf.extend_from_slice(p.text.as_bytes()),
            None => buf.extend_from_slice(b"null"),
        }
        for (i, (key, numeric)) in self.json_keys.iter().enumerate() {
            buf.extend_from_slice(key);
            let v = row.extra.get(i).copied().unwrap_or("");
            if *numeric && is_json_number(v) {
                buf.extend_from_slice(v.as_bytes());
            } else {
                push_json_str(buf, v);
            }
        }
        if !row.parts.is_empty() {
            buf.extend_from_slice(b",\"parts\":{");
            for (i, p) in row.parts.iter().enumerate() {
                if i > 0 {
                    buf.push(b',');
                }
                push_json_str(buf, p.name);
                buf.push(b':');
                buf.extend_from_slice(p.text.as_bytes());
            }
            buf.push(b'}');
        }
        if self.opts.raw {
            buf.extend_from_slice(b",\"raw\":\"");
            push_hex_bytes(buf, row.raw);
            buf.push(b'"');
        }
        if let Some(t) = time {
            buf.extend_from_slice(b",\"time\":");
            push_json_str(buf, t);
        }
        buf.extend_from_slice(b"}\n");
    }

    fn pretty(&mut self, row: &Row<'_>) {
        if self.opts.time_abs {
            self.wall_time(row.micros);
        }
        if self.opts.raw {
            self.hex.clear();
            push_hex_bytes(&mut self.hex, row.raw);
        }
        let style = match row.class {
            Class::Plain => None,
            Class::Quiet => Some(DIMMED),
            Class::Warning => Some(YELLOW),
            Class::Error => Some(RED),
            Class::Info => Some(CYAN),
        };
        let mut ib = itoa::Buffer::new();
        let mut ib2 = itoa::Buffer::new();
        let millis = row.micros.map_or("", |us| ib.format(us / 1000));
        let id = row.id.map_or("", |i| ib2.format(i));
        // Hex digits and spaces only.
        let raw = std::str::from_utf8(&self.hex).unwrap_or("");
        let n = 8 + self.n_extra + usize::from(self.opts.raw) + usize::from(self.opts.time_abs);
        let widths = &mut self.widths;
        let mut line = PrettyLine::start(self.out.buf(), style.filter(|_| self.opts.color));
        let base = [
            self.digits.as_str(),
            millis,
            id,
            row.device,
            row.kind,
            row.sensor_no,
            row.sensor,
            row.data,
        ];
        let mut i = 0;
        let mut cell = |line: &mut PrettyLine<'_>, text: &str| {
            line.cell(widths, i, text, true, i + 1 == n);
            i += 1;
        };
        for text in base {
            cell(&mut line, text);
        }
        for e in 0..self.n_extra {
            cell(&mut line, row.extra.get(e).copied().unwrap_or(""));
        }
        if self.opts.raw {
            cell(&mut line, raw);
        }
        if self.opts.time_abs {
            cell(&mut line, &self.scratch);
        }
        line.finish();
    }
}

/// SGR codes of the row classes and the header, as owo-colors writes them.
const BOLD: &[u8] = b"\x1b[1m";
const DIMMED: &[u8] = b"\x1b[2m";
const YELLOW: &[u8] = b"\x1b[33m";
const RED: &[u8] = b"\x1b[31m";
const CYAN: &[u8] = b"\x1b[36m";
const RESET: &[u8] = b"\x1b[0m";

/// One pretty line written straight into the output buffer: cells padded to the column widths
/// (the first three right-aligned), trailing blanks trimmed, optionally wrapped in a colour.
struct PrettyLine<'b> {
    buf: &'b mut Vec<u8>,
    style: Option<&'static [u8]>,
    /// Where the line's text starts (after the colour code).
    start: usize,
}

impl<'b> PrettyLine<'b> {
    fn start(buf: &'b mut Vec<u8>, style: Option<&'static [u8]>) -> Self {
        if let Some(s) = style {
            buf.extend_from_slice(s);
        }
        let start = buf.len();
        PrettyLine { buf, style, start }
    }

    /// Cell `i`; with `grow`, a column whose value is longer than its width (up to
    /// [`PRETTY_GROW_MAX`]) widens for this row and every later one.
    fn cell(&mut self, widths: &mut Vec<usize>, i: usize, cell: &str, grow: bool, last: bool) {
        let buf = &mut *self.buf;
        if i > 0 {
            buf.extend_from_slice(b"  ");
        }
        if i >= widths.len() {
            widths.push(4);
        }
        // Printable ASCII: one column per byte, copied whole. Otherwise control characters
        // become spaces and every char is one column.
        let bytes = cell.as_bytes();
        let ascii = bytes.iter().all(|&b| (0x20..0x7F).contains(&b));
        let len = if ascii {
            bytes.len()
        } else {
            cell.chars().count()
        };
        if grow && !last && len > widths[i] && len <= PRETTY_GROW_MAX {
            widths[i] = len;
        }
        let pad = widths[i].saturating_sub(len);
        let right = i < 3;
        if right {
            buf.resize(buf.len() + pad, b' ');
        }
        if ascii {
            buf.extend_from_slice(bytes);
        } else {
            for c in cell.chars() {
                let c = if c.is_control() { ' ' } else { c };
                let mut tmp = [0u8; 4];
                buf.extend_from_slice(c.encode_utf8(&mut tmp).as_bytes());
            }
        }
        if !right && !last {
            buf.resize(buf.len() + pad, b' ');
        }
    }

    /// Trims the line's trailing whitespace (as `str::trim_end`), closes the colour, ends
    /// the line.
    fn finish(self) {
        let text = &self.buf[self.start..];
        let keep = match std::str::from_utf8(text) {
            Ok(t) => t.trim_end().len(),
            Err(_) => text.len(),
        };
        self.buf.truncate(self.start + keep);
        if self.style.is_some() {
            self.buf.extend_from_slice(RESET);
        }
        self.buf.push(b'\n');
    }
}

impl RowOut for Table {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        self.write(row)
    }
}

/// Where the driver writes rows: the table, or the live view (which may also write the table).
pub trait Sink: RowOut {
    /// Writes everything buffered; called after every batch and on every idle tick.
    fn flush(&mut self) -> Result<(), OutputError>;
    /// Flushes and closes the output at the end of the run.
    fn close(&mut self) -> Result<(), OutputError>;
    /// The wall-clock time of the capture's start became known.
    fn set_anchor(&mut self, anchor: Option<crate::time::Anchor>);
    /// The user asked to stop (the live view's `q`): the driver ends as at the end of the input.
    fn quit(&self) -> bool {
        false
    }
    /// A row a filter keeps out: counted (so that every row's Counter is its number in the
    /// unfiltered table), not shown.
    fn skip(&mut self);
}

impl Sink for Table {
    fn flush(&mut self) -> Result<(), OutputError> {
        Table::flush(self)
    }
    fn close(&mut self) -> Result<(), OutputError> {
        Table::close(self)
    }
    fn set_anchor(&mut self, anchor: Option<crate::time::Anchor>) {
        Table::set_anchor(self, anchor)
    }
    fn skip(&mut self) {
        Table::skip(self)
    }
}

/// Copies a TSV field, control characters (tabs, newlines) that would break the row replaced
/// with spaces in the same pass over the copy.
fn push_tsv_field(buf: &mut Vec<u8>, field: &str) {
    let at = buf.len();
    buf.extend_from_slice(field.as_bytes());
    for b in &mut buf[at..] {
        if *b < 0x20 {
            *b = b' ';
        }
    }
}

/// A CSV field (RFC 4180): as it is, or in double quotes with inner quotes doubled when it
/// holds a comma, a quote, CR or LF (what the csv crate's `QuoteStyle::Necessary` does).
fn push_csv_field(buf: &mut Vec<u8>, field: &[u8]) {
    if !field
        .iter()
        .any(|&b| matches!(b, b',' | b'"' | b'\r' | b'\n'))
    {
        buf.extend_from_slice(field);
        return;
    }
    buf.push(b'"');
    let mut rest = field;
    while let Some(q) = rest.iter().position(|&b| b == b'"') {
        buf.extend_from_slice(&rest[..=q]);
        buf.push(b'"');
        rest = &rest[q + 1..];
    }
    buf.extend_from_slice(rest);
    buf.push(b'"');
}

/// The JSON key of a column, with its comma and colon: `,"sensor_no":` for `Sensor #`.
fn json_key(name: &str) -> Vec<u8> {
    let mut key = b",\"".to_vec();
    for c in name.chars() {
        match c {
            ' ' => key.push(b'_'),
            '#' => key.extend_from_slice(b"no"),
            c => {
                for l in c.to_lowercase() {
                    let mut tmp = [0u8; 4];
                    key.extend_from_slice(l.encode_utf8(&mut tmp).as_bytes());
                }
            }
        }
    }
    key.extend_from_slice(b"\":");
    key
}

/// A plain decimal JSON accepts as a number (`12`, `-1.50`, `0.5`; not `01`, `.5`, `1.`).
fn is_json_number(s: &str) -> bool {
    let b = s.strip_prefix('-').unwrap_or(s).as_bytes();
    let (int, frac) = match b.iter().position(|&c| c == b'.') {
        Some(i) => (&b[..i], Some(&b[i + 1..])),
        None => (b, None),
    };
    let digits = |d: &[u8]| !d.is_empty() && d.iter().all(u8::is_ascii_digit);
    digits(int) && (int.len() == 1 || int[0] != b'0') && frac.is_none_or(digits)
}

/// A JSON string, or `null` for an empty cell.
fn push_json_str(buf: &mut Vec<u8>, s: &str) {
    if s.is_empty() {
        buf.extend_from_slice(b"null");
        return;
    }
    buf.push(b'"');
    let bytes = s.as_bytes();
    let needs = |b: u8| b < 0x20 || b == b'"' || b == b'\\';
    // Copied whole up to the first byte that needs escaping (usually the whole string).
    let clean = bytes.iter().position(|&b| needs(b)).unwrap_or(bytes.len());
    buf.extend_from_slice(&bytes[..clean]);
    for &b in &bytes[clean..] {
        match b {
            b'"' => buf.extend_from_slice(b"\\\""),
            b'\\' => buf.extend_from_slice(b"\\\\"),
            b'\n' => buf.extend_from_slice(b"\\n"),
            b'\r' => buf.extend_from_slice(b"\\r"),
            b'\t' => buf.extend_from_slice(b"\\t"),
            0..=0x1F => {
                let _ = write!(buf, "\\u{b:04x}");
            }
            _ => buf.push(b),
        }
    }
    buf.push(b'"');
}

#[cfg(test)]
mod tests;
