//! Rows written straight from a decoded frame into the table's output, without a [`Row`].
//!
//! A [`Row`] is what every stage after the decoder understands (filters, names, `--wide`,
//! plots, `--top`, exports, the pacer): the decoder formats its cells into scratch strings and
//! its numbers into [`super::Parts`], and the table copies them into the output. When nothing
//! but the plain table reads the rows, that is work twice over. Then the table lends the
//! decoder a [`Direct`] ([`super::RowOut::direct`]), and the decoder writes its row's cells in
//! order into [`Cells`], which puts each one into the output line in the table's format (TSV,
//! CSV, JSON Lines, pretty), with the same escaping, quoting, padding, Counter, stamps' copied
//! cells and raw bytes as the table writes for a [`Row`]. Anything else in between (a filter, a
//! wrapper) lends no `Direct`, and the decoder builds its `Row` as always.
//!
//! One mechanism for every protocol: a decoder implements [`WriteRow`] for the rows it writes
//! straight (usually its common rows; the rest go as [`Row`]s), asks `out.direct(COLUMNS)` for
//! each row and, when it gets one, calls [`Direct::row`]. [`WriteRow::write`] is compiled once
//! per format ([`Fmt`]), so that each cell's format is decided by the compiler, not per cell.
//!
//! A row's cells, in order: Counter and Millis (written by [`Direct::row`]); ID to Sensor,
//! inside [`Cells::stamp`] (copied from the last row with the same stamp, when there was one);
//! Data; [`Cells::value`]; one cell per extra column; optionally [`Cells::part`]s (JSON
//! `parts`); then the raw bytes and the line's end (written by [`Direct::row`]). A cell is
//! either a text ([`Cells::text`]) or written in place between [`Cells::begin`] and
//! [`Cells::end`] with [`Cells::str`], [`Cells::put_ascii`], [`Cells::dec`], [`Cells::fixed`]
//! …, which take only UTF-8 (strings, ASCII, digits), so no cell is checked for UTF-8 (text a
//! decoder builds from tables of digits and letters goes as ASCII bytes, without making a
//! `&str` of it first); a cell known to hold a comma besides such pieces (a reading with its
//! signed twin) is begun with [`Cells::begin_listed`], so that CSV opens its quote first
//! instead of moving the cell at its end. A member of `parts` named by a literal or a `static`
//! table is best written with [`Cells::part_static`] (its key found by the name's address). A
//! cell that turns out to need quoting or escaping (a comma in CSV, a quote in JSON, a control
//! character, a character that is not printable ASCII in pretty text) is written again from a
//! copy, exactly as the table writes a [`Row`]'s cell. Tests compare both ways of every
//! protocol that writes rows straight, over every fixture and fuzz corpus, byte for byte
//! (`testing::assert_direct_rows_match`).
//!
//! [`Row`]: super::Row

use std::marker::PhantomData;

use super::Class;
use super::line;
pub use super::line::Mark;
use super::part_keys::PartNames;
use super::pretty::{CYAN, DIMMED, PrettyLine, RED, YELLOW};
use super::text::{Format, Text};

mod parts;
mod pieces;

/// The table's output buffer and its text state, lent for one row: `buf[..*len]` holds the
/// rows not yet written out, the rest is room for the next line.
pub struct Direct<'a> {
    pub(crate) text: &'a mut Text,
    pub(crate) buf: &'a mut Vec<u8>,
    pub(crate) len: &'a mut usize,
}

/// A decoder's row, written straight into the table (see the module's text for the order of
/// the cells). `write` may run more than once for one row (a line longer than the output's
/// room is written again into more room), so it only reads.
pub trait WriteRow {
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>);
}

/// A format as a type: [`WriteRow::write`] is compiled once for each.
pub trait Fmt: sealed::Sealed {
    const FORMAT: Format;
}

mod sealed {
    pub trait Sealed {}
}

macro_rules! formats {
    ($($(#[$doc:meta])* $name:ident;)*) => {$(
        $(#[$doc])*
        pub enum $name {}
        impl sealed::Sealed for $name {}
        impl Fmt for $name {
            const FORMAT: Format = Format::$name;
        }
    )*};
}

formats! {
    /// Tab-separated values.
    Tsv;
    /// Comma-separated values (RFC 4180).
    Csv;
    /// JSON Lines.
    Jsonl;
    /// Pretty text.
    Pretty;
}

/// The keys of the base columns and of Value in JSON Lines, by column.
const JSON_KEYS: [&[u8]; 9] = [
    b"{\"counter\":",
    b",\"millis\":",
    b",\"id\":",
    b",\"device\":",
    b",\"type\":",
    b",\"sensor_no\":",
    b",\"sensor\":",
    b",\"data\":",
    b",\"value\":",
];

impl Direct<'_> {
    /// Writes one row: Counter, Millis (from `micros`), the cells `row` writes, the raw bytes
    /// (with `--raw`), the end of the line. `class` styles a pretty line in colour; a row with
    /// `raw` bytes that is not an error or a note counts as a frame, as in the table.
    #[inline]
    pub fn row(self, micros: Option<u64>, class: Class, raw: &[u8], row: &impl WriteRow) {
        self.text.count();
        if !raw.is_empty() && !matches!(class, Class::Error | Class::Info) {
            self.text.frames += 1;
        }
        match self.text.format {
            Format::Tsv => self.run::<Tsv>(micros, class, raw, row),
            Format::Csv => self.run::<Csv>(micros, class, raw, row),
            Format::Jsonl => self.run::<Jsonl>(micros, class, raw, row),
            Format::Pretty => self.run::<Pretty>(micros, class, raw, row),
        }
    }

    #[inline(always)]
    fn run<F: Fmt>(self, micros: Option<u64>, class: Class, raw: &[u8], row: &impl WriteRow) {
        let text = self.text;
        let style = if F::FORMAT == Format::Pretty && text.color {
            match class {
                Class::Plain => None,
                Class::Quiet => Some(DIMMED),
                Class::Warning => Some(YELLOW),
                Class::Error => Some(RED),
                Class::Info => Some(CYAN),
            }
        } else {
            None
        };
        if F::FORMAT == Format::Pretty {
            let n = 8 + text.extra.len() + usize::from(text.raw);
            if text.widths.len() < n {
                text.widths.resize(n, 4);
            }
        }
        // Pretty text's last column (not padded), the same for every cell of the row.
        let last_col = 7 + text.extra.len() + usize::from(text.raw);
        *self.len += line::write_once(self.buf, *self.len, |w| {
            let mut c = Cells::<F> {
                p: PrettyLine::start(w, style),
                t: &mut *text,
                col: 0,
                cell: (0, 0, 0),
                plain: false,
                listed: false,
                wide: 0,
                last_col,
                span: (0, 0, 0),
                rewritten: None,
                parts: 0,
                _f: PhantomData,
            };
            c.head(micros);
            row.write(&mut c);
            c.finish(raw);
        });
    }
}

/// The line of one row being written, in format `F`: the decoder's [`WriteRow`] writes its
/// cells through it.
pub struct Cells<'b, 'l, F: Fmt> {
    /// The line (and, in pretty text, the blanks owed and where the text starts).
    p: PrettyLine<'b, 'l>,
    t: &'b mut Text,
    /// The next column.
    col: usize,
    /// The cell being written in place: where its text starts, and (pretty text) where the
    /// line was before its blanks, and the blanks owed then.
    cell: (usize, usize, usize),
    /// The cell written in place has only pieces with nothing to quote or escape in any
    /// format (numbers, hex, [`Cells::put_ascii`]) so far: no format needs to look at it
    /// again (pretty text: it is printable ASCII, one column a byte).
    plain: bool,
    /// The cell written in place was begun with [`Cells::begin_listed`]: it holds a comma, and
    /// (in CSV) its opening quote is written.
    listed: bool,
    /// Bytes of the cell written in place beyond its width in pretty text: the bytes after the
    /// first of each character of [`Cells::put_glyphs`] pieces (0 in a cell of ASCII).
    wide: usize,
    /// Pretty text's last column ([`Cells::last`]), worked out once a row rather than per cell.
    last_col: usize,
    /// The cells ID to Sensor being written: where they start, the blanks owed before them,
    /// and the stamp (0: not kept).
    span: (usize, usize, u32),
    /// The Data cell was written again (quoted, escaped) from its first text, kept in
    /// `t.data_copy`: where that text started in the line and its length (marks in it point
    /// into the copy).
    rewritten: Option<(u32, u32)>,
    /// JSON members of `parts` written so far.
    parts: usize,
    _f: PhantomData<F>,
}

impl<F: Fmt> Cells<'_, '_, F> {
    const SEP: u8 = if matches!(F::FORMAT, Format::Csv) {
        b','
    } else {
        b'\t'
    };

    /// Counter and Millis.
    #[inline(always)]
    fn head(&mut self, micros: Option<u64>) {
        let t = &mut *self.t;
        match F::FORMAT {
            Format::Tsv | Format::Csv => {
                let w = &mut *self.p.line;
                t.digits.put(w);
                w.byte(Self::SEP);
                if let Some(us) = micros {
                    w.dec(us / 1000);
                }
            }
            Format::Jsonl => {
                let w = &mut *self.p.line;
                w.put(JSON_KEYS[0]);
                t.digits.put(w);
                w.put(JSON_KEYS[1]);
                match micros {
                    Some(us) => w.dec(us / 1000),
                    None => w.put(b"null"),
                }
            }
            Format::Pretty => {
                self.p.digits(&mut t.widths, 0, t.digits.as_bytes());
                let mut ib = itoa::Buffer::new();
                let millis = micros.map_or("", |us| ib.format(us / 1000));
                self.p.digits(&mut t.widths, 1, millis.as_bytes());
            }
        }
        self.col = 2;
    }

    /// Whether pretty column `i` is the line's last (not padded).
    #[inline(always)]
    fn last(&self, i: usize) -> bool {
        i == self.last_col
    }

    /// The cells ID to Sensor: copied from the last row with the same non-zero `stamp` when
    /// there was one (see [`super::Row::stamp`]: the decoder promises that rows with one stamp
    /// have the same cells ID to Sensor), and then `false`; `true`: write them now (an
    /// [`Cells::id`] and four cells), then call [`Cells::stamp_end`]. Debug builds write them
    /// again after every copy and compare.
    #[inline(always)]
    pub fn stamp(&mut self, stamp: u32) -> bool {
        debug_assert_eq!(self.col, 2, "the cells ID to Sensor come first");
        let widths = if F::FORMAT == Format::Pretty {
            span_widths(&self.t.widths)
        } else {
            0
        };
        if stamp != 0
            && let Some((slot, len, blanks)) = self.t.spans.get_slot(stamp, widths)
        {
            let at = self.p.line.len();
            if F::FORMAT == Format::Pretty {
                let owed = self.p.blanks;
                self.p.copy(&slot[..len], blanks);
                if cfg!(debug_assertions) {
                    // Written again in the copy's place, then compared (`stamp_end`).
                    let blanks = self.p.blanks;
                    let t = &mut *self.t;
                    t.check.clear();
                    t.check.extend_from_slice(&self.p.line.bytes()[at..]);
                    t.check.extend_from_slice(&blanks.to_le_bytes());
                    self.p.line.truncate(at);
                    self.p.blanks = owed;
                    self.span = (at, usize::MAX, stamp);
                    return true;
                }
            } else {
                self.p.line.put_span(slot, len);
                if cfg!(debug_assertions) {
                    let t = &mut *self.t;
                    t.check.clear();
                    t.check.extend_from_slice(&self.p.line.bytes()[at..]);
                    self.p.line.truncate(at);
                    self.span = (at, usize::MAX, stamp);
                    return true;
                }
            }
            self.col = 7;
            return false;
        }
        self.span = (self.p.line.len(), self.p.blanks, stamp);
        true
    }

    /// The cells ID to Sensor are written ([`Cells::stamp`]): kept for the next rows with the
    /// stamp (pretty text: only when no blanks were owed before them, so that the span holds
    /// exactly its own cells), or (debug builds) compared with the copy.
    #[inline(always)]
    pub fn stamp_end(&mut self) {
        debug_assert_eq!(self.col, 7, "an ID and four cells");
        let (at, owed, stamp) = self.span;
        if stamp == 0 || self.p.line.over() {
            return;
        }
        if owed == usize::MAX {
            // Debug builds: the cells were copied, then written again.
            let written = self.p.line.bytes()[at..].to_vec();
            let mut copied = self.t.check.clone();
            if F::FORMAT == Format::Pretty {
                let n = std::mem::size_of::<usize>();
                let tail = copied.split_off(copied.len().saturating_sub(n));
                let blanks = usize::from_le_bytes(tail.try_into().unwrap_or_default());
                assert_eq!(
                    (String::from_utf8_lossy(&copied), blanks),
                    (String::from_utf8_lossy(&written), self.p.blanks),
                    "rows with stamp {stamp:#x} differ in the cells ID to Sensor"
                );
            } else {
                assert_eq!(
                    String::from_utf8_lossy(&copied),
                    String::from_utf8_lossy(&written),
                    "rows with stamp {stamp:#x} differ in the cells ID to Sensor"
                );
            }
            return;
        }
        if F::FORMAT == Format::Pretty {
            if owed == 0 {
                let widths = span_widths(&self.t.widths);
                let bytes = &self.p.line.bytes()[at..];
                self.t.spans.put(stamp, widths, bytes, self.p.blanks);
            }
        } else {
            self.t.spans.put(stamp, 0, &self.p.line.bytes()[at..], 0);
        }
    }

    /// The ID cell (column 2).
    #[inline(always)]
    pub fn id(&mut self, id: Option<u32>) {
        debug_assert_eq!(self.col, 2);
        match F::FORMAT {
            Format::Tsv | Format::Csv => {
                let w = &mut *self.p.line;
                w.byte(Self::SEP);
                if let Some(id) = id {
                    w.dec(id.into());
                }
            }
            Format::Jsonl => {
                let w = &mut *self.p.line;
                w.put(JSON_KEYS[2]);
                match id {
                    Some(id) => w.dec(id.into()),
                    None => w.put(b"null"),
                }
            }
            Format::Pretty => {
                let mut ib = itoa::Buffer::new();
                let id = id.map_or("", |i| ib.format(i));
                self.p.digits(&mut self.t.widths, 2, id.as_bytes());
            }
        }
        self.col = 3;
    }

    /// The next cell, from a text.
    #[inline(always)]
    pub fn text(&mut self, s: &str) {
        let i = self.col;
        self.col += 1;
        match F::FORMAT {
            Format::Tsv => {
                let w = &mut *self.p.line;
                w.byte(b'\t');
                w.tsv(s.as_bytes());
            }
            Format::Csv => {
                let w = &mut *self.p.line;
                w.byte(b',');
                w.csv(s.as_bytes());
            }
            Format::Jsonl => {
                let (key, numeric) = json_key(self.t, i);
                let w = &mut *self.p.line;
                if numeric && super::text::is_json_number(s.as_bytes()) {
                    w.put(key);
                    w.put(s.as_bytes());
                } else {
                    w.json_key_str(key, s);
                }
            }
            Format::Pretty => {
                // Pretty text has no Value column: the extra columns come one earlier.
                let i = if i > 8 { i - 1 } else { i };
                let last = self.last(i);
                self.p.cell(&mut self.t.widths, i, s, true, last);
            }
        }
    }

    /// An empty cell.
    #[inline(always)]
    pub fn empty(&mut self) {
        self.text("");
    }

    /// Every cell left empty, from the next (Data, Value or an extra column) to the last
    /// extra column: as [`Cells::empty`] for each (and [`Cells::value`] with `None` for
    /// Value), in one piece.
    #[inline(always)]
    pub fn empty_to_end(&mut self) {
        debug_assert!(self.col >= 7, "after the cells ID to Sensor");
        let last = 9 + self.t.extra.len();
        match F::FORMAT {
            Format::Tsv | Format::Csv => {
                const SEPS: [[u8; 16]; 2] = [[b'\t'; 16], [b','; 16]];
                let seps = &SEPS[usize::from(F::FORMAT == Format::Csv)];
                let n = last.saturating_sub(self.col);
                if n <= seps.len() {
                    self.p.line.put_prefix(seps, n);
                } else {
                    for _ in 0..n {
                        self.p.line.byte(Self::SEP);
                    }
                }
                self.col = self.col.max(last);
            }
            Format::Jsonl => {
                let (text, at) = &self.t.json_nulls;
                let from = at.get(self.col - 7).copied().unwrap_or(text.len());
                self.p.line.put(text.get(from..).unwrap_or_default());
                self.col = self.col.max(last);
            }
            Format::Pretty => {
                while self.col < last {
                    if self.col == 8 {
                        self.value(None);
                    } else {
                        self.empty();
                    }
                }
            }
        }
    }

    /// The next cell is written in place (Data from column 7, or an extra column) until
    /// [`Cells::end`].
    #[inline(always)]
    pub fn begin(&mut self) {
        let i = self.col;
        self.plain = true;
        self.listed = false;
        self.wide = 0;
        match F::FORMAT {
            Format::Tsv | Format::Csv => {
                self.p.line.byte(Self::SEP);
                self.cell.0 = self.p.line.len();
            }
            Format::Jsonl => {
                let (key, numeric) = json_key(self.t, i);
                let w = &mut *self.p.line;
                w.put(key);
                if !numeric {
                    w.byte(b'"');
                }
                self.cell.0 = w.len();
            }
            Format::Pretty => self.cell = self.p.begin_cell(),
        }
    }

    /// The cell written in place since [`Cells::begin`] ends: quoted, escaped or padded as its
    /// format wants.
    #[inline(always)]
    pub fn end(&mut self) {
        let i = self.col;
        self.col += 1;
        let at = self.cell.0;
        let plain = self.plain;
        // A listed cell's opening quote is written (CSV): only plain pieces may follow it.
        debug_assert!(
            plain || !self.listed,
            "a listed cell with a piece that is not plain"
        );
        if cfg!(debug_assertions) && plain {
            let cell = self.p.line.bytes().get(at..).unwrap_or_default();
            let listed = self.listed;
            assert!(
                cell.iter()
                    .all(|&b| is_plain(b) || listed && b == b',' || self.wide > 0 && b >= 0x80),
                "a plain cell to quote or escape: {:?}",
                String::from_utf8_lossy(cell)
            );
            // A line that did not fit has dropped pieces (it is written again into more room).
            assert!(
                !listed || self.p.line.over() || cell.contains(&b','),
                "a listed cell without a comma: {:?}",
                String::from_utf8_lossy(cell)
            );
        }
        let rewritten = match F::FORMAT {
            Format::Tsv => {
                if !plain {
                    self.p.line.tsv_fix(at);
                }
                None
            }
            Format::Csv if plain => {
                if self.listed {
                    // Its opening quote is written (`begin_listed`), and nothing in it is doubled.
                    self.p.line.byte(b'"');
                }
                None
            }
            Format::Csv => self.p.line.csv_fix(at, &mut self.t.scratch),
            Format::Jsonl => {
                let numeric = json_key(self.t, i).1;
                if plain && !numeric && self.p.line.len() > at {
                    self.p.line.byte(b'"');
                    None
                } else {
                    self.p.line.json_fix(at, numeric, &mut self.t.scratch)
                }
            }
            Format::Pretty => {
                let i = if i > 8 { i - 1 } else { i };
                let last = self.last(i);
                let t = &mut *self.t;
                // A plain cell's width: its bytes, less those of characters beyond their first.
                let plain = plain.then_some(self.wide);
                self.p
                    .end_cell(&mut t.widths, i, last, self.cell, plain, &mut t.scratch);
                None
            }
        };
        if i == 7 {
            if rewritten.is_some() {
                // Kept apart from `scratch`, which a later cell written again reuses.
                std::mem::swap(&mut self.t.scratch, &mut self.t.data_copy);
            }
            self.rewritten = rewritten;
        }
    }

    /// Where a mark's text is: in the line, or in the copy of a Data cell written again.
    #[inline(always)]
    fn marked(&self, m: Mark) -> (bool, usize, usize) {
        match self.rewritten {
            Some((at, len)) if m.start >= at && m.end <= at + len => {
                (true, (m.start - at) as usize, (m.end - at) as usize)
            }
            _ => (false, m.start as usize, m.end as usize),
        }
    }

    /// Appends the marked text to the line.
    #[inline(always)]
    fn put_marked(&mut self, m: Mark) {
        match self.marked(m) {
            (false, a, b) => self.p.line.copy_within(a, b),
            (true, a, b) => {
                let s = self.t.data_copy.get(a..b).unwrap_or_default();
                self.p.line.put(s);
            }
        }
    }

    /// The Value column (not in pretty text): the number marked in the Data cell, or empty.
    #[inline(always)]
    pub fn value(&mut self, m: Option<Mark>) {
        debug_assert_eq!(self.col, 8, "Value follows Data");
        self.col = 9;
        match F::FORMAT {
            Format::Tsv | Format::Csv => {
                self.p.line.byte(Self::SEP);
                if let Some(m) = m {
                    // Digits, a sign and a point: nothing to escape or quote.
                    self.put_marked(m);
                }
            }
            Format::Jsonl => {
                self.p.line.put(JSON_KEYS[8]);
                match m {
                    Some(m) => self.put_marked(m),
                    None => self.p.line.put(b"null"),
                }
            }
            Format::Pretty => {}
        }
    }

    /// The Value column from a text (not in pretty text): a row's first number
    /// ([`super::Row::value`]), `None` when it has none.
    #[inline(always)]
    pub fn value_text(&mut self, s: Option<&str>) {
        debug_assert_eq!(self.col, 8, "Value follows Data");
        self.col = 9;
        match F::FORMAT {
            Format::Tsv => {
                self.p.line.byte(b'\t');
                self.p.line.tsv(s.unwrap_or("").as_bytes());
            }
            Format::Csv => {
                self.p.line.byte(b',');
                self.p.line.csv(s.unwrap_or("").as_bytes());
            }
            Format::Jsonl => {
                self.p.line.put(JSON_KEYS[8]);
                self.p.line.put(s.unwrap_or("null").as_bytes());
            }
            Format::Pretty => {}
        }
    }

    /// The raw bytes (with `--raw`) and the end of the line.
    #[inline(always)]
    fn finish(mut self, raw: &[u8]) {
        match F::FORMAT {
            Format::Tsv | Format::Csv => {
                let w = &mut *self.p.line;
                if self.t.raw {
                    w.byte(Self::SEP);
                    w.hex_bytes(raw);
                }
                w.put(if F::FORMAT == Format::Csv {
                    b"\r\n"
                } else {
                    b"\n"
                });
            }
            Format::Jsonl => {
                let w = &mut *self.p.line;
                if self.parts > 0 {
                    w.byte(b'}');
                }
                if self.t.raw {
                    w.put(b",\"raw\":\"");
                    w.hex_bytes(raw);
                    w.byte(b'"');
                }
                w.put(b"}\n");
            }
            Format::Pretty => {
                if self.t.raw {
                    // The last column: hex digits and blanks.
                    self.col = 9 + self.t.extra.len();
                    self.begin();
                    self.p.line.hex_bytes(raw);
                    self.end();
                }
                self.p.finish();
            }
        }
    }
}

/// A byte no format quotes or escapes: printable ASCII (or a blank) but `,` `"` `\`.
#[inline(always)]
fn is_plain(b: u8) -> bool {
    (0x20..0x7F).contains(&b) && !matches!(b, b',' | b'"' | b'\\')
}

/// The sum of the pretty widths of the columns ID to Sensor: spans are kept per widths.
#[inline(always)]
fn span_widths(widths: &[usize]) -> u32 {
    widths
        .get(2..7)
        .map_or(0, |w| w.iter().sum::<usize>() as u32)
}

/// Column `i`'s JSON key, and whether its cells are numbers.
#[inline(always)]
fn json_key(t: &Text, i: usize) -> (&[u8], bool) {
    if i < JSON_KEYS.len() {
        return (JSON_KEYS[i], false);
    }
    match t.json_keys.get(i - JSON_KEYS.len()) {
        Some((k, n)) => (k, *n),
        None => (&[], false),
    }
}
