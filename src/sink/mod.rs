//! Sinks: the log table as pretty text, TSV, CSV or JSON Lines.

mod fit;
pub mod limit;
pub mod output;
pub(crate) use fit::fallback_size;
mod spool;
mod tap;
pub mod wide;

use chrono::{DateTime, Local};

use crate::fmt::push_hex_bytes;
use crate::row::RowOut;
use crate::row::line::W;
use crate::row::pretty::{BOLD, CYAN, DIMMED, PrettyLine, RED, YELLOW};
use crate::row::spans::Spans;
pub use crate::row::text::{Format, VALUE_COLUMN};
use crate::row::text::{NUMERIC_EXTRA, Text, is_json_number};
use crate::row::{BASE_COLUMNS, Class, Direct, Row};
use crate::time::Anchor;
pub use output::Output;
pub use tap::{Tap, Tapped};

use crate::row::{OutputError, RowResult};

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
    /// Number of the decoder's extra columns.
    n_extra: usize,
    /// What rows written as [`Row`]s and rows written straight by a decoder ([`Direct`])
    /// share: the Counter, the pretty widths, the JSON keys, the cells kept per stamp.
    text: Text,
    /// Rows counted but not written (filtered out).
    skipped: u64,
    anchor: Option<Anchor>,
    header_written: bool,
    /// Pretty output: a line above the column names (what the project file changes).
    preface: Option<String>,
    scratch: String,
    hex: Vec<u8>,
    error: Option<OutputError>,
    /// `--wide`: rows go to the wide table instead.
    wide: Option<wide::Wide>,
    /// `busnoop plot`: rows go to the plot, drawn at the end of the run ([`Table::take_plot`]).
    plot: Option<crate::plot::Plot>,
    /// The decoder's extra columns as last lent to it ([`Table::direct`]): the same slice
    /// as the table's own, checked once.
    direct_columns: Option<(usize, usize)>,
    /// The key of the extra columns last lent for when every condition of [`Table::direct`]
    /// but the room held, and holds until one of the setters that change them runs ((0, 0):
    /// check them all at the next row).
    lend: (usize, usize),
    /// Pretty output on a terminal: the width rows are fitted to ([`fit`]), asked again at
    /// every flush (the terminal may be resized).
    fit: Option<usize>,
    /// Which extra cell names a row's port (several sources, [`crate::row::PORT_COLUMN`]).
    port_column: Option<usize>,
}

/// Pretty-output column widths for the base columns, when the protocol gives none (see
/// [`crate::protocol::Protocol::pretty_widths`]).
const PRETTY_WIDTHS: [usize; 8] = [7, 8, 3, 10, 9, 8, 10, 30];

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
        let widths = columns
            .iter()
            .enumerate()
            .map(|(i, c)| PRETTY_WIDTHS.get(i).copied().unwrap_or(c.len().max(4)))
            .collect();
        let text = Text::new(opts.format, opts.color, opts.raw, extra, widths);
        Table {
            opts,
            out,
            columns,
            n_extra: extra.len(),
            text,
            skipped: 0,
            anchor: None,
            wide: None,
            plot: None,
            header_written: false,
            preface: None,
            scratch: String::new(),
            hex: Vec::new(),
            error: None,
            direct_columns: None,
            lend: (0, 0),
            fit: None,
            port_column: extra.iter().position(|c| *c == crate::row::PORT_COLUMN),
        }
    }

    /// Fits pretty rows to the terminal's width (its rows wrap Data and Note within their
    /// columns and cut names with `…`, never a number): for a pretty table on a terminal.
    pub fn fit_terminal(&mut self) {
        if self.opts.format == Format::Pretty {
            self.fit = Some(fit::terminal_width());
            self.lend = (0, 0);
        }
    }

    /// What may happen to each column of a fitted row.
    fn fit_kinds(&self) -> Vec<fit::Kind> {
        self.columns
            .iter()
            .enumerate()
            .map(|(i, c)| match (i, *c) {
                (0..=2, _) => fit::Kind::Right,
                (7, _) | (_, "Note") | (_, "Raw") => fit::Kind::Wrap,
                (5, _) | (_, "Time") | (_, "Unit") => fit::Kind::Keep,
                (_, c) if NUMERIC_EXTRA.contains(&c) => fit::Kind::Keep,
                _ => fit::Kind::Cut,
            })
            .collect()
    }

    /// Writes `lines` (one row) in `style`.
    fn fitted(&mut self, lines: &[String], style: Option<&'static [u8]>) {
        self.out.line(|w| {
            for l in lines {
                if let Some(s) = style {
                    w.put(s);
                }
                w.put(l.as_bytes());
                if style.is_some() {
                    w.put(crate::row::pretty::RESET);
                }
                w.byte(b'\n');
            }
        });
    }

    /// Sets the pretty widths of the first columns (the base columns and the protocol's extra
    /// columns, in order: the protocol descriptor's `pretty_widths`); never narrower than a
    /// column's name. Call before the header is written.
    pub fn set_pretty_widths(&mut self, widths: &[usize]) {
        for ((w, &new), name) in self.text.widths.iter_mut().zip(widths).zip(&self.columns) {
            *w = new.max(name.chars().count());
        }
    }

    /// Rows so far: written ones and skipped ones (the last Counter).
    pub fn rows(&self) -> u64 {
        self.text.counter
    }

    /// Rows of frames with a valid check written so far (polls, requests, answers, data; not
    /// errors, garbage, timeouts or notes): "did anything decode".
    pub fn frames(&self) -> u64 {
        self.text.frames
    }

    /// Counts a row a filter keeps out of the output, so that every row's Counter is its
    /// number in the unfiltered table.
    pub fn skip(&mut self) {
        self.text.count();
        self.skipped += 1;
    }

    /// Rows counted with [`Table::skip`].
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    pub fn set_anchor(&mut self, anchor: Option<Anchor>) {
        self.anchor = anchor;
        if let Some(p) = &mut self.plot {
            p.set_anchor(anchor);
        }
    }

    /// Writes the wide table ([`wide`]) instead of the long one: CSV and TSV only (the caller
    /// checks); `live`: write lines as they come rather than at the end.
    pub fn set_wide(&mut self, step: wide::Step, live: bool, max_columns: usize) {
        let mut w = wide::Wide::new(self.opts.format, step, self.opts.utc, live, max_columns);
        w.port_column(self.port_column);
        self.wide = Some(w);
        self.lend = (0, 0);
    }

    /// Collects the rows' numbers for `busnoop plot` instead of writing the table.
    pub fn set_plot(&mut self, spec: crate::plot::PlotSpec) {
        let mut plot = crate::plot::Plot::new(spec);
        plot.port_column(self.port_column);
        self.plot = Some(plot);
        self.lend = (0, 0);
    }

    /// The plot's numbers, to draw at the end of the run (`busnoop plot`).
    pub fn take_plot(&mut self) -> Option<crate::plot::Plot> {
        self.plot.take()
    }

    /// Whether a decoder's extra `columns` are the table's (the slice is remembered once it
    /// was found equal).
    #[inline]
    fn direct_columns(&mut self, columns: &'static [&'static str]) -> bool {
        let key = (columns.as_ptr() as usize, columns.len());
        if self.direct_columns == Some(key) {
            return true;
        }
        if columns == &self.text.extra[..] {
            self.direct_columns = Some(key);
            return true;
        }
        false
    }

    /// Pretty output: a line to write above the column names (TSV, CSV and JSON Lines are
    /// for programs, which read only the table).
    pub fn set_preface(&mut self, line: Option<String>) {
        self.preface = line;
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
            Format::Tsv => self.out.line(|w| {
                for (i, c) in cols.iter().enumerate() {
                    if i > 0 {
                        w.byte(b'\t');
                    }
                    w.put(c.as_bytes());
                }
                w.byte(b'\n');
            }),
            Format::Csv => self.out.line(|w| {
                for (i, c) in cols.iter().enumerate() {
                    if i > 0 {
                        w.byte(b',');
                    }
                    w.csv(c.as_bytes());
                }
                w.put(b"\r\n");
            }),
            Format::Pretty if self.fit.is_some() => {
                if self.text.widths.len() < cols.len() {
                    self.text.widths.resize(cols.len(), 4);
                }
                let kinds = self.fit_kinds();
                let lines = fit::lines(&cols, &self.text.widths, &kinds, self.fit.unwrap_or(80));
                self.fitted(&lines, self.opts.color.then_some(BOLD));
            }
            Format::Pretty => {
                if let Some(p) = &self.preface {
                    self.out.line(|w| {
                        w.put(p.as_bytes());
                        w.byte(b'\n');
                    });
                    self.out.row_done()?;
                }
                let style = self.opts.color.then_some(BOLD);
                if self.text.widths.len() < cols.len() {
                    self.text.widths.resize(cols.len(), 4);
                }
                let widths = &mut self.text.widths[..];
                self.out.line(|w| {
                    let mut line = PrettyLine::start(w, style);
                    for (i, c) in cols.iter().enumerate() {
                        line.cell(widths, i, c, false, i + 1 == cols.len());
                    }
                    line.finish();
                });
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
        self.text.count();
        if !row.raw.is_empty() && !matches!(row.class, Class::Error | Class::Info) {
            self.text.frames += 1;
        }
        if let Some(p) = &mut self.plot {
            p.row(row);
            return Ok(());
        }
        if let Some(w) = &mut self.wide {
            let anchor = self.anchor;
            let mut spooled = Ok(());
            self.out.append(|buf| spooled = w.row(row, anchor, buf));
            if let Err(e) = spooled {
                // The table would lack a line: [`Table::close`] writes none of it.
                self.wide = None;
                return Err(spool_error(e));
            }
            return self.out.row_done();
        }
        // The cells every format writes alike: the wall-clock time and the raw bytes.
        if self.opts.time_abs {
            self.wall_time(row.micros);
        }
        if self.opts.raw {
            self.hex.clear();
            push_hex_bytes(&mut self.hex, row.raw);
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
        if self.fit.is_some() {
            self.fit = Some(fit::terminal_width());
        }
        self.out.flush()
    }

    /// Flushes and closes the output.
    pub fn close(&mut self) -> Result<(), OutputError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        if let Some(mut w) = self.wide.take() {
            let anchor = self.anchor;
            let mut done = Ok(());
            self.out.append(|buf| done = w.finish(anchor, buf));
            done.map_err(spool_error)?;
            // A file's lines come back from the spool in pieces, written as they come: the
            // output never holds the whole table.
            loop {
                let mut more = Ok(false);
                self.out
                    .append(|buf| more = w.lines(buf, output::HIGH_WATER));
                let more = more.map_err(spool_error)?;
                self.out.row_done()?;
                if !more {
                    break;
                }
            }
            if !w.has_columns() {
                eprintln!(
                    "busnoop: note: --wide: no row carried a number, so the table has no columns"
                );
            }
            if let Some((max, n)) = w.left_out() {
                eprintln!(
                    "busnoop: note: --wide: the table keeps the first {max} columns; {n} {} of \
                     later columns left out (--max-columns N for more)",
                    if n == 1 { "number" } else { "numbers" }
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
        // Beyond the calendar (a corrupt time stamp): an empty cell.
        if let Some(at) = self.anchor.zip(micros).and_then(|(a, us)| a.plus(us)) {
            use std::fmt::Write as _;
            match at {
                Anchor::Naive(n) => {
                    let _ = write!(self.scratch, "{}", n.format("%Y-%m-%dT%H:%M:%S%.3f"));
                }
                Anchor::Instant(t) => {
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

    /// A TSV row (`CSV` false: tabs between the cells, control characters blanked) or a CSV
    /// row (`CSV` true: commas, RFC 4180 quoting, CRLF). `STAMPED`: the row has a stamp, and
    /// its cells ID to Sensor may come from [`Spans`]. The rows without a stamp have a copy of
    /// their own: with the span code in the same copy, they cost 2-4 % more instructions (SAB,
    /// S-Bus; the compiler laid the common code out differently).
    #[inline(always)]
    fn delimited<const CSV: bool, const STAMPED: bool>(&mut self, row: &Row<'_>) {
        let (sep, end): (u8, &[u8]) = if CSV { (b',', b"\r\n") } else { (b'\t', b"\n") };
        let cell = |w: &mut W<'_>, field: &[u8]| {
            if CSV { w.csv(field) } else { w.tsv(field) }
        };
        let (digits, opts, n_extra) = (&self.text.digits, &self.opts, self.n_extra);
        let (time, hex, spans) = (&self.scratch, &self.hex, &mut self.text.spans);
        self.out.line(|w| {
            w.put(digits.as_bytes());
            w.byte(sep);
            if let Some(us) = row.micros {
                w.dec_called(us / 1000);
            }
            if STAMPED {
                span(w, spans, row.stamp, |w| {
                    w.byte(sep);
                    if let Some(id) = row.id {
                        w.dec_called(id.into());
                    }
                    for field in [row.device, row.kind, row.sensor_no, row.sensor] {
                        w.byte(sep);
                        cell(w, field.as_bytes());
                    }
                });
                w.byte(sep);
                cell(w, row.data.as_bytes());
            } else {
                w.byte(sep);
                if let Some(id) = row.id {
                    w.dec_called(id.into());
                }
                for field in [row.device, row.kind, row.sensor_no, row.sensor, row.data] {
                    w.byte(sep);
                    cell(w, field.as_bytes());
                }
            }
            w.byte(sep);
            cell(w, row.value().as_bytes());
            for i in 0..n_extra {
                w.byte(sep);
                cell(w, row.extra.get(i).copied().unwrap_or("").as_bytes());
            }
            if opts.raw {
                // Hex digits and spaces: nothing to escape.
                w.byte(sep);
                w.put(hex);
            }
            if opts.time_abs {
                w.byte(sep);
                cell(w, time.as_bytes());
            }
            w.put(end);
        });
    }

    fn tsv(&mut self, row: &Row<'_>) {
        if row.stamp == 0 {
            self.delimited::<false, false>(row);
        } else {
            self.delimited::<false, true>(row);
        }
    }

    fn csv_row(&mut self, row: &Row<'_>) {
        if row.stamp == 0 {
            self.delimited::<true, false>(row);
        } else {
            self.delimited::<true, true>(row);
        }
    }

    fn jsonl(&mut self, row: &Row<'_>) {
        let (digits, opts, keys) = (&self.text.digits, &self.opts, &self.text.json_keys);
        let (time, hex, spans) = (&self.scratch, &self.hex, &mut self.text.spans);
        self.out.line(|w| {
            w.put(b"{\"counter\":");
            w.put(digits.as_bytes());
            w.put(b",\"millis\":");
            match row.micros {
                Some(us) => w.dec_called(us / 1000),
                None => w.put(b"null"),
            }
            span(w, spans, row.stamp, |w| {
                w.put(b",\"id\":");
                match row.id {
                    Some(id) => w.dec_called(id.into()),
                    None => w.put(b"null"),
                }
                w.put(b",\"device\":");
                w.json_str(row.device);
                w.put(b",\"type\":");
                w.json_str(row.kind);
                w.put(b",\"sensor_no\":");
                w.json_str(row.sensor_no);
                w.put(b",\"sensor\":");
                w.json_str(row.sensor);
            });
            w.put(b",\"data\":");
            w.json_str(row.data);
            w.put(b",\"value\":");
            match row.parts.first() {
                Some(p) => w.put(p.text.as_bytes()),
                None => w.put(b"null"),
            }
            for (i, (key, numeric)) in keys.iter().enumerate() {
                w.put(key);
                let v = row.extra.get(i).copied().unwrap_or("");
                if *numeric && is_json_number(v.as_bytes()) {
                    w.put(v.as_bytes());
                } else {
                    w.json_str(v);
                }
            }
            if !row.parts.is_empty() {
                w.json_parts(row.parts);
            }
            if opts.raw {
                w.put(b",\"raw\":\"");
                w.put(hex);
                w.byte(b'"');
            }
            if opts.time_abs {
                w.put(b",\"time\":");
                w.json_str(time);
            }
            w.put(b"}\n");
        });
    }

    fn pretty(&mut self, row: &Row<'_>) {
        let style = match row.class {
            Class::Plain => None,
            Class::Quiet => Some(DIMMED),
            Class::Warning => Some(YELLOW),
            Class::Error => Some(RED),
            Class::Info => Some(CYAN),
        };
        let style = style.filter(|_| self.opts.color);
        let mut ib = itoa::Buffer::new();
        let mut ib2 = itoa::Buffer::new();
        let millis = row.micros.map_or("", |us| ib.format(us / 1000));
        let id = row.id.map_or("", |i| ib2.format(i));
        // Hex digits and spaces only (and only with --raw: the check is not free).
        let raw = if self.opts.raw {
            std::str::from_utf8(&self.hex).unwrap_or("")
        } else {
            ""
        };
        let n = 8 + self.n_extra + usize::from(self.opts.raw) + usize::from(self.opts.time_abs);
        if self.text.widths.len() < n {
            self.text.widths.resize(n, 4);
        }
        if let Some(width) = self.fit {
            let mut cells: Vec<&str> = vec![
                std::str::from_utf8(self.text.digits.as_bytes()).unwrap_or(""),
                millis,
                id,
                row.device,
                row.kind,
                row.sensor_no,
                row.sensor,
                row.data,
            ];
            cells.extend((0..self.n_extra).map(|e| row.extra.get(e).copied().unwrap_or("")));
            if self.opts.raw {
                cells.push(raw);
            }
            if self.opts.time_abs {
                cells.push(&self.scratch);
            }
            for (i, c) in cells.iter().enumerate() {
                crate::row::pretty::fit(
                    &mut self.text.widths,
                    i,
                    c.chars().count(),
                    true,
                    i + 1 == n,
                );
            }
            let lines = fit::lines(&cells, &self.text.widths, &self.fit_kinds(), width);
            self.fitted(&lines, style);
            return;
        }
        let (digits, opts, n_extra) = (&self.text.digits, &self.opts, self.n_extra);
        let (time, spans) = (&self.scratch, &mut self.text.spans);
        let widths = &mut self.text.widths[..];
        // The cells ID to Sensor (columns 2 to 6; never the last column).
        let cells = |line: &mut PrettyLine<'_, '_>, widths: &mut [usize]| {
            line.digits(widths, 2, id.as_bytes());
            let base = [row.device, row.kind, row.sensor_no, row.sensor];
            for (i, text) in (3..).zip(base) {
                line.cell(widths, i, text, true, false);
            }
        };
        self.out.line(|w| {
            let mut line = PrettyLine::start(w, style);
            line.digits(widths, 0, digits.as_bytes());
            line.digits(widths, 1, millis.as_bytes());
            // Their text depends on the widths too, which only grow: their sum tells them apart.
            let span_widths = |widths: &[usize]| widths[2..7].iter().sum::<usize>() as u32;
            match spans.get(row.stamp, span_widths(widths)) {
                Some((bytes, blanks)) => {
                    let (at, owed) = (line.line.len(), line.blanks);
                    line.copy(bytes, blanks);
                    #[cfg(debug_assertions)]
                    {
                        let copied = (line.line.bytes()[at..].to_vec(), line.blanks);
                        line.line.truncate(at);
                        line.blanks = owed;
                        cells(&mut line, widths);
                        let written = (line.line.bytes()[at..].to_vec(), line.blanks);
                        assert_eq!(
                            copied, written,
                            "rows with stamp {:#x} differ in the cells ID to Sensor",
                            row.stamp
                        );
                    }
                    let _ = (at, owed);
                }
                None => {
                    let (at, owed) = (line.line.len(), line.blanks);
                    cells(&mut line, widths);
                    // Kept only when no blanks were owed before it, so that the span holds
                    // exactly its own cells.
                    if row.stamp != 0 && owed == 0 && !line.line.over() {
                        let bytes = &line.line.bytes()[at..];
                        spans.put(row.stamp, span_widths(widths), bytes, line.blanks);
                    }
                }
            }
            line.cell(widths, 7, row.data, true, 8 == n);
            for e in 0..n_extra {
                let i = 8 + e;
                let text = row.extra.get(e).copied().unwrap_or("");
                line.cell(widths, i, text, true, i + 1 == n);
            }
            let mut i = 8 + n_extra;
            if opts.raw {
                line.cell(widths, i, raw, true, i + 1 == n);
                i += 1;
            }
            if opts.time_abs {
                line.cell(widths, i, time, true, i + 1 == n);
            }
            line.finish();
        });
    }
}

/// Writes the cells ID to Sensor with `write`, or copies them from the row's stamp's span
/// ([`Spans`]) when they were written before; keeps what it wrote for the next rows.
#[inline(always)]
fn span(w: &mut W<'_>, spans: &mut Spans, stamp: u32, write: impl Fn(&mut W<'_>)) {
    if stamp == 0 {
        write(w);
        return;
    }
    if let Some((bytes, _)) = spans.get(stamp, 0) {
        w.put(bytes);
        #[cfg(debug_assertions)]
        check_span(w, bytes.len(), stamp, write);
        return;
    }
    let at = w.len();
    write(w);
    if !w.over() {
        spans.put(stamp, 0, &w.bytes()[at..], 0);
    }
}

/// Debug builds: writes the cells of a copied span again and compares (a decoder that gives
/// one stamp to rows whose cells differ fails every test that reaches it).
#[cfg(debug_assertions)]
fn check_span(w: &mut W<'_>, len: usize, stamp: u32, write: impl FnOnce(&mut W<'_>)) {
    let at = w.len();
    write(w);
    if !w.over() {
        let b = w.bytes();
        assert_eq!(
            String::from_utf8_lossy(&b[at - len..at]),
            String::from_utf8_lossy(&b[at..]),
            "rows with stamp {stamp:#x} differ in the cells ID to Sensor"
        );
    }
    w.truncate(at);
}

/// A failure of the wide table's temporary file (a full or unwritable `$TMPDIR`, a failed read
/// back) is a failed write of the table: named after the folder, the output's exit code.
fn spool_error(e: std::io::Error) -> OutputError {
    OutputError {
        path: Some(std::env::temp_dir()),
        error: std::io::Error::new(e.kind(), format!("--wide temporary file: {e}")),
    }
}

impl Table {
    /// Whether the table lends its output to a decoder with these extra `columns` (see
    /// [`RowOut::direct`]); remembers them when it does. Out of line: it runs once per decoder,
    /// and kept inline it made every row's `direct` save and restore six registers.
    #[cold]
    #[inline(never)]
    fn lend_to(&mut self, columns: &'static [&'static str]) -> bool {
        if self.wide.is_some()
            || self.plot.is_some()
            || self.fit.is_some()
            || self.opts.time_abs
            || !self.header_written
            || self.error.is_some()
            || !self.direct_columns(columns)
        {
            return false;
        }
        self.lend = (columns.as_ptr() as usize, columns.len());
        true
    }
}

impl RowOut for Table {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        self.write(row)
    }

    /// Lends the output for a row written straight from a decoded frame, when the table writes
    /// rows as they come in the long format with what [`Direct`] writes: not for `--wide`, a
    /// plot or `--time abs`, not before the header, not for a decoder with other extra columns
    /// than the table's; and not when enough is buffered to be written out (the next row goes
    /// as a [`Row`], whose write does that).
    /// The conditions are checked once for a decoder's columns (the key [`Table::lend`]), then
    /// only the room.
    #[inline]
    fn direct(&mut self, columns: &'static [&'static str]) -> Option<Direct<'_>> {
        let key = (columns.as_ptr() as usize, columns.len());
        if (key != self.lend || self.error.is_some()) && !self.lend_to(columns) {
            return None;
        }
        let (buf, len) = self.out.room()?;
        Some(Direct {
            text: &mut self.text,
            buf,
            len,
        })
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

#[cfg(test)]
mod tests;
