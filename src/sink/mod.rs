//! Sinks: the log table as pretty text, TSV, CSV or JSON Lines.

pub mod output;
pub mod wide;

use std::io::{self, Write as _};
use std::path::Path;

use chrono::{DateTime, Local};
use owo_colors::{OwoColorize, Style};

use crate::fmt::push_hex_bytes;
use crate::row::RowOut;
use crate::row::{BASE_COLUMNS, Class, Row};
use crate::time::Anchor;
pub use output::Output;

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
    /// Rows of whole frames (with wire bytes, not an error or a note).
    frames: u64,
    /// Rows counted but not written (filtered out).
    skipped: u64,
    anchor: Option<Anchor>,
    header_written: bool,
    csv: csv::Writer<SharedBuf>,
    csv_buf: SharedBuf,
    scratch: String,
    hex: Vec<u8>,
    error: Option<OutputError>,
    /// `--wide`: rows go to the wide table instead.
    wide: Option<wide::Wide>,
    /// `busnoop plot`: rows go to the plot, drawn at the end.
    plot: Option<crate::plot::Plot>,
}

/// A byte buffer shared between the csv writer and the table.
#[derive(Clone, Default)]
struct SharedBuf(std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

impl io::Write for SharedBuf {
    fn write(&mut self, data: &[u8]) -> io::Result<usize> {
        self.0.borrow_mut().extend_from_slice(data);
        Ok(data.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
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
        let csv_buf = SharedBuf::default();
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
            frames: 0,
            skipped: 0,
            anchor: None,
            wide: None,
            plot: None,
            header_written: false,
            csv: csv::WriterBuilder::new()
                .terminator(csv::Terminator::CRLF)
                .from_writer(csv_buf.clone()),
            csv_buf,
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
                let _ = self.csv.write_record(&cols);
                self.move_csv();
            }
            Format::Pretty => {
                let line = self.pretty_line(cols.iter().copied(), &[true; 3], false);
                let buf = self.out.buf();
                if self.opts.color {
                    let _ = writeln!(buf, "{}", line.bold());
                } else {
                    let _ = writeln!(buf, "{line}");
                }
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
                error: io::Error::other(e),
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
        let counter = self.counter;
        let time = if self.opts.time_abs {
            Some(self.wall_time(row.micros).to_owned())
        } else {
            None
        };
        let raw = self.opts.raw;
        let n_extra = self.n_extra;
        let buf = self.out.buf();
        let mut ib = itoa::Buffer::new();
        buf.extend_from_slice(ib.format(counter).as_bytes());
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
        let mut ib = itoa::Buffer::new();
        let _ = self.csv.write_field(ib.format(self.counter));
        match row.micros {
            Some(us) => self.csv.write_field(ib.format(us / 1000)),
            None => self.csv.write_field(""),
        }
        .ok();
        match row.id {
            Some(id) => self.csv.write_field(ib.format(id)),
            None => self.csv.write_field(""),
        }
        .ok();
        for field in [row.device, row.kind, row.sensor_no, row.sensor, row.data] {
            let _ = self.csv.write_field(field);
        }
        let _ = self.csv.write_field(row.value());
        for i in 0..self.n_extra {
            let _ = self
                .csv
                .write_field(row.extra.get(i).copied().unwrap_or(""));
        }
        if self.opts.raw {
            self.hex.clear();
            push_hex_bytes(&mut self.hex, row.raw);
            let _ = self.csv.write_field(&self.hex);
        }
        if self.opts.time_abs {
            let t = self.wall_time(row.micros).to_owned();
            let _ = self.csv.write_field(&t);
        }
        let _ = self.csv.write_record(None::<&[u8]>);
        self.move_csv();
    }

    fn move_csv(&mut self) {
        if let Err(e) = self.csv.flush() {
            // Flushing into a Vec cannot fail; keep the error if it ever does.
            self.error.get_or_insert(OutputError {
                path: None,
                error: e,
            });
        }
        let mut inner = self.csv_buf.0.borrow_mut();
        self.out.buf().extend_from_slice(&inner);
        inner.clear();
    }

    fn jsonl(&mut self, row: &Row<'_>) {
        let time = if self.opts.time_abs {
            Some(self.wall_time(row.micros).to_owned())
        } else {
            None
        };
        let counter = self.counter;
        let n_extra = self.n_extra;
        let columns = &self.columns;
        let buf = self.out.buf();
        let mut ib = itoa::Buffer::new();
        buf.extend_from_slice(b"{\"counter\":");
        buf.extend_from_slice(ib.format(counter).as_bytes());
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
            ("device", row.device),
            ("type", row.kind),
            ("sensor_no", row.sensor_no),
            ("sensor", row.sensor),
            ("data", row.data),
        ];
        for (k, v) in base {
            push_json_pair(buf, k, v);
        }
        buf.extend_from_slice(b",\"value\":");
        match row.parts.first() {
            Some(p) => buf.extend_from_slice(p.text.as_bytes()),
            None => buf.extend_from_slice(b"null"),
        }
        for (i, name) in columns[BASE_COLUMNS.len() + 1..][..n_extra]
            .iter()
            .enumerate()
        {
            push_json_key(buf, name);
            let v = row.extra.get(i).copied().unwrap_or("");
            if NUMERIC_EXTRA.contains(name) && is_json_number(v) {
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
            push_json_pair(buf, "time", &t);
        }
        buf.extend_from_slice(b"}\n");
    }

    fn pretty(&mut self, row: &Row<'_>) {
        let mut ib = itoa::Buffer::new();
        let counter = ib.format(self.counter).to_owned();
        let millis = row
            .micros
            .map_or(String::new(), |us| (us / 1000).to_string());
        let id = row.id.map_or(String::new(), |i| i.to_string());
        let raw = if self.opts.raw {
            let mut v = Vec::new();
            push_hex_bytes(&mut v, row.raw);
            Some(String::from_utf8(v).unwrap_or_default())
        } else {
            None
        };
        let time = if self.opts.time_abs {
            Some(self.wall_time(row.micros).to_owned())
        } else {
            None
        };
        let mut cells: Vec<&str> = vec![
            &counter,
            &millis,
            &id,
            row.device,
            row.kind,
            row.sensor_no,
            row.sensor,
            row.data,
        ];
        for i in 0..self.n_extra {
            cells.push(row.extra.get(i).copied().unwrap_or(""));
        }
        if let Some(r) = &raw {
            cells.push(r);
        }
        if let Some(t) = &time {
            cells.push(t);
        }
        let line = self.pretty_line(cells.into_iter(), &[true, true, true], true);
        let style = match row.class {
            Class::Plain => None,
            Class::Quiet => Some(Style::new().dimmed()),
            Class::Warning => Some(Style::new().yellow()),
            Class::Error => Some(Style::new().red()),
            Class::Info => Some(Style::new().cyan()),
        };
        let color = self.opts.color;
        let buf = self.out.buf();
        match style {
            Some(s) if color => {
                let _ = writeln!(buf, "{}", line.style(s));
            }
            _ => {
                let _ = writeln!(buf, "{line}");
            }
        }
    }

    /// Pads cells to the pretty widths; the first `right.len()` columns are right-aligned. With
    /// `grow`, a column whose value is longer than its width (up to [`PRETTY_GROW_MAX`]) widens
    /// for this row and every later one.
    fn pretty_line<'a>(
        &mut self,
        cells: impl Iterator<Item = &'a str>,
        right: &[bool],
        grow: bool,
    ) -> String {
        let mut line = String::new();
        let cells: Vec<&str> = cells.collect();
        let n = cells.len();
        for (i, cell) in cells.into_iter().enumerate() {
            let cell = sanitize(cell);
            if i > 0 {
                line.push_str("  ");
            }
            let last = i + 1 == n;
            let len = cell.chars().count();
            if i >= self.widths.len() {
                self.widths.push(4);
            }
            if grow && !last && len > self.widths[i] && len <= PRETTY_GROW_MAX {
                self.widths[i] = len;
            }
            let width = self.widths[i];
            if i < right.len() && right[i] {
                line.extend(std::iter::repeat_n(' ', width.saturating_sub(len)));
                line.push_str(&cell);
            } else {
                line.push_str(&cell);
                if !last {
                    line.extend(std::iter::repeat_n(' ', width.saturating_sub(len)));
                }
            }
        }
        let trimmed = line.trim_end().len();
        line.truncate(trimmed);
        line
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

/// Replaces control characters (tabs, newlines) that would break a TSV row with spaces.
fn push_tsv_field(buf: &mut Vec<u8>, field: &str) {
    let bytes = field.as_bytes();
    if bytes.iter().all(|&b| b >= 0x20) {
        buf.extend_from_slice(bytes);
    } else {
        buf.extend(bytes.iter().map(|&b| if b < 0x20 { b' ' } else { b }));
    }
}

fn sanitize(cell: &str) -> std::borrow::Cow<'_, str> {
    if cell.chars().any(char::is_control) {
        cell.chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect::<String>()
            .into()
    } else {
        cell.into()
    }
}

fn push_json_key(buf: &mut Vec<u8>, name: &str) {
    buf.extend_from_slice(b",\"");
    for c in name.chars() {
        match c {
            ' ' => buf.push(b'_'),
            '#' => buf.extend_from_slice(b"no"),
            c => {
                for l in c.to_lowercase() {
                    let mut tmp = [0u8; 4];
                    buf.extend_from_slice(l.encode_utf8(&mut tmp).as_bytes());
                }
            }
        }
    }
    buf.extend_from_slice(b"\":");
}

fn push_json_pair(buf: &mut Vec<u8>, key: &str, value: &str) {
    buf.extend_from_slice(b",\"");
    buf.extend_from_slice(key.as_bytes());
    buf.extend_from_slice(b"\":");
    push_json_str(buf, value);
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
    for &b in s.as_bytes() {
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
mod tests {
    use super::*;
    use crate::row::Part;

    fn sample_row() -> Row<'static> {
        Row {
            micros: Some(4_280_999),
            id: Some(0),
            device: "Vario",
            kind: "Data",
            class: Class::Plain,
            sensor_no: "100",
            sensor: "Alt",
            data: "65.43",
            extra: &["m", "a \"quoted\", note"],
            parts: &[Part {
                name: "Alt",
                unit: "m",
                text: "65.43",
                value: 65.43,
            }],
            raw: &[0x7E, 0x00],
        }
    }

    fn render(format: Format, raw: bool) -> String {
        let opts = TableOptions {
            format,
            color: false,
            raw,
            time_abs: false,
            utc: false,
        };
        let mut t = Table::new(Output::memory(), opts, &["Unit", "Note"]);
        t.write(&sample_row()).unwrap();
        t.flush().unwrap();
        String::from_utf8(t.output().memory_contents().to_vec()).unwrap()
    }

    #[test]
    fn tsv_has_header_and_fields() {
        let s = render(Format::Tsv, true);
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(
            lines[0],
            "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote\tRaw"
        );
        assert_eq!(
            lines[1],
            "1\t4280\t0\tVario\tData\t100\tAlt\t65.43\t65.43\tm\ta \"quoted\", note\t7E 00"
        );
    }

    #[test]
    fn csv_quotes() {
        let s = render(Format::Csv, false);
        let mut r = csv::Reader::from_reader(s.as_bytes());
        let headers = r.headers().unwrap().clone();
        assert_eq!(&headers[5], "Sensor #");
        let rec = r.records().next().unwrap().unwrap();
        assert_eq!(&headers[8], "Value");
        assert_eq!(&rec[10], "a \"quoted\", note");
        assert_eq!(&rec[7], "65.43");
        assert_eq!(&rec[8], "65.43");
    }

    #[test]
    fn jsonl_escapes() {
        let s = render(Format::Jsonl, true);
        assert_eq!(
            s.trim_end(),
            r#"{"counter":1,"millis":4280,"id":0,"device":"Vario","type":"Data","sensor_no":"100","sensor":"Alt","data":"65.43","value":65.43,"unit":"m","note":"a \"quoted\", note","parts":{"Alt":65.43},"raw":"7E 00"}"#
        );
    }

    #[test]
    fn pretty_aligns() {
        let s = render(Format::Pretty, false);
        let lines: Vec<&str> = s.lines().collect();
        assert!(lines[0].starts_with("Counter    Millis   ID  Device"));
        assert!(lines[1].starts_with("      1      4280    0  Vario"));
    }

    /// Where each column of a pretty line starts (after a run of two spaces).
    fn starts(line: &str) -> Vec<usize> {
        let b = line.as_bytes();
        (1..b.len())
            .filter(|&i| b[i] != b' ' && i >= 2 && b[i - 1] == b' ' && b[i - 2] == b' ')
            .collect()
    }

    #[test]
    fn pretty_columns_come_from_the_protocol_and_grow_for_long_values() {
        let opts = TableOptions {
            format: Format::Pretty,
            color: false,
            raw: false,
            time_abs: false,
            utc: false,
        };
        let mut t = Table::new(Output::memory(), opts, &["Resp ms", "Note"]);
        t.set_pretty_widths(&[7, 8, 3, 15, 9, 9, 12, 10, 3, 0]);
        t.header().unwrap();
        let row = |device: &'static str, data: &'static str| Row {
            micros: Some(1000),
            id: Some(10),
            device,
            kind: "Request",
            class: Class::Plain,
            sensor_no: "R0",
            sensor: "Read",
            data,
            extra: &["1.5", "note"],
            parts: &[],
            raw: &[],
        };
        t.write(&row("10.0.0.1:5050", "R0=1")).unwrap();
        // Longer than its column: the column grows, here and for every later row.
        t.write(&row("192.168.100.200:5050", "R0=1")).unwrap();
        t.write(&row("10.0.0.1:5050", "R0=12345678 R1=2")).unwrap();
        t.write(&row("10.0.0.1:5050", "R0=1")).unwrap();
        // Beyond the limit: this row overflows, the column keeps its width.
        let huge: &'static str = Box::leak("x".repeat(PRETTY_GROW_MAX + 1).into_boxed_str());
        t.write(&row("10.0.0.1:5050", huge)).unwrap();
        t.write(&row("10.0.0.1:5050", "R0=1")).unwrap();
        t.flush().unwrap();
        let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        // The protocol's widths ("Resp ms" is wider than its 3).
        assert_eq!(
            lines[0],
            "Counter    Millis   ID  Device           Type       Sensor #   Sensor        Data        Resp ms  Note"
        );
        // The starts of the seven left-aligned columns (Device to Note).
        let left = |l: &str| {
            let s = starts(l);
            s[s.len() - 7..].to_vec()
        };
        assert_eq!(left(lines[1]), left(lines[0]), "the header's widths");
        let grown = left(lines[2]);
        assert_eq!(grown[0], left(lines[1])[0], "Device starts where it did");
        assert_eq!(
            grown[1],
            left(lines[1])[1] + "192.168.100.200:5050".len() - 15,
            "Type moves by what Device grew"
        );
        let data_grown = left(lines[3]);
        assert_eq!(data_grown[..5], grown[..5]);
        assert_eq!(data_grown[5], grown[5] + "R0=12345678 R1=2".len() - 10);
        assert_eq!(
            left(lines[4]),
            data_grown,
            "later rows keep the grown widths"
        );
        assert_eq!(
            left(lines[6]),
            data_grown,
            "an overflow does not widen the column"
        );
    }

    #[test]
    fn json_numbers() {
        for ok in ["0", "12", "-1.50", "0.005", "18446744073709551615"] {
            assert!(is_json_number(ok), "{ok}");
        }
        for bad in ["", "-", "01", ".5", "1.", "1e3", "0x10", "1 2", "NaN"] {
            assert!(!is_json_number(bad), "{bad}");
        }
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(Format::from_path(Path::new("a.CSV")), Some(Format::Csv));
        assert_eq!(Format::from_path(Path::new("a.jsonl")), Some(Format::Jsonl));
        assert_eq!(Format::from_path(Path::new("a.bin")), None);
    }
}
