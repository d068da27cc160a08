//! Typed statistics: the `--stats` report and the one-line problem summary as values that a
//! protocol fills in and the driver formats (`cli::report`). Nothing here knows a protocol.
//!
//! A [`Report`] is lines before a table, the table (fixed-width columns, rows of cells and
//! detail lines under a row) and total lines after it; its [`Display`](fmt::Display) is the
//! text printed under `<protocol> statistics (N rows)`. A [`Problems`] collects what went wrong
//! as counted items and gives one line (`S-Bus: 2 CRC errors, 1 timeout in 10 valid
//! telegrams`), or nothing when every item is zero.

use std::fmt;

use crate::exit::count;

/// How a column's cells are padded to its width.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    Left,
    Right,
}

/// A column of a [`Report`] table: its heading, minimum width, alignment, and the spaces
/// before it (none before the first column).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    pub name: &'static str,
    pub width: usize,
    pub align: Align,
    pub gap: usize,
    /// The key of its cells in the JSON statistics; empty: the name in snake case
    /// ([`Column::json_key`]).
    pub key: &'static str,
    /// Right-aligned, but its cells are text (a hex value), not numbers.
    pub text: bool,
}

impl Column {
    /// A right-aligned column one space after the previous one.
    pub const fn right(name: &'static str, width: usize) -> Self {
        Column {
            name,
            width,
            align: Align::Right,
            gap: 1,
            key: "",
            text: false,
        }
    }

    /// A left-aligned column one space after the previous one.
    pub const fn left(name: &'static str, width: usize) -> Self {
        Column {
            name,
            width,
            align: Align::Left,
            gap: 1,
            key: "",
            text: false,
        }
    }

    /// The same column `gap` spaces after the previous one.
    pub const fn gap(self, gap: usize) -> Self {
        Column { gap, ..self }
    }

    /// The same column with its own JSON key (when the name in snake case would not say it:
    /// SAB's `median` is `resp_median_ms`).
    pub const fn key(self, key: &'static str) -> Self {
        Column { key, ..self }
    }

    /// The same column holding text, though right-aligned (`0x800F`).
    pub const fn text(self) -> Self {
        Column { text: true, ..self }
    }

    /// Whether its cells are numbers (right-aligned columns are counts and times, unless marked
    /// [`Column::text`]) rather than text (names, lists of codes).
    pub fn numeric(&self) -> bool {
        self.align == Align::Right && !self.text
    }

    /// The key of its cells in the JSON statistics: its own, or the name in snake case
    /// (`Mean ms` → `mean_ms`, `BadCRC` → `bad_crc`, `SeqGap` → `seq_gap`).
    pub fn json_key(&self) -> String {
        if self.key.is_empty() {
            snake_case(self.name)
        } else {
            self.key.to_owned()
        }
    }
}

/// `Mean ms` → `mean_ms`, `BadCRC` → `bad_crc`, `NACK codes` → `nack_codes`: words split at
/// blanks and where a capital follows a small letter, lower case, joined by `_`.
pub fn snake_case(name: &str) -> String {
    let mut out = String::new();
    let mut prev_lower = false;
    for c in name.chars() {
        if !c.is_ascii_alphanumeric() {
            if !out.is_empty() && !out.ends_with('_') {
                out.push('_');
            }
            prev_lower = false;
            continue;
        }
        if c.is_ascii_uppercase() && prev_lower && !out.ends_with('_') {
            out.push('_');
        }
        prev_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        out.push(c.to_ascii_lowercase());
    }
    while out.ends_with('_') {
        out.pop();
    }
    out
}

/// A row of a [`Report`] table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReportRow {
    /// Cells in column order; there may be fewer than columns (a totals row), and trailing
    /// empty cells are left out with their gaps.
    Cells(Vec<String>),
    /// Text about the row above it, indented to the second column.
    Detail(String),
    /// The sum of the rows above it (`all`): shown as a row, kept apart in the JSON (`all`).
    Total(Vec<String>),
}

/// The `--stats` report of a decoder.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Report {
    /// Lines before the table (the mode, the framing chosen).
    pub head: Vec<String>,
    pub columns: Vec<Column>,
    pub rows: Vec<ReportRow>,
    /// Lines after the table (counters of the whole input).
    pub totals: Vec<String>,
    /// The same counters by name (snake case), for the JSON statistics' `totals` object.
    pub counts: Vec<(&'static str, u64)>,
}

impl Report {
    /// An empty report with these columns.
    pub fn new(columns: &[Column]) -> Self {
        Report {
            columns: columns.to_vec(),
            ..Report::default()
        }
    }

    /// Adds a table row.
    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(ReportRow::Cells(cells));
    }

    /// Adds the row of sums (`all`) under the rows.
    pub fn total_row(&mut self, cells: Vec<String>) {
        self.rows.push(ReportRow::Total(cells));
    }

    /// Names the counters of the total lines for the JSON statistics (each key once; a
    /// later value of a key replaces the earlier).
    pub fn counts(&mut self, counts: &[(&'static str, u64)]) {
        for &(k, n) in counts {
            match self.counts.iter_mut().find(|(key, _)| *key == k) {
                Some(c) => c.1 = n,
                None => self.counts.push((k, n)),
            }
        }
    }

    /// Adds a detail line under the last row.
    pub fn detail(&mut self, text: String) {
        self.rows.push(ReportRow::Detail(text));
    }

    fn cells(&self, f: &mut fmt::Formatter<'_>, cells: &[impl AsRef<str>]) -> fmt::Result {
        let used = cells
            .iter()
            .rposition(|c| !c.as_ref().is_empty())
            .map_or(0, |i| i + 1);
        for (i, (c, col)) in cells.iter().zip(&self.columns).take(used).enumerate() {
            let c = c.as_ref();
            if i > 0 {
                write!(f, "{:1$}", "", col.gap)?;
            }
            match col.align {
                Align::Left => write!(f, "{c:<0$}", col.width)?,
                Align::Right => write!(f, "{c:>0$}", col.width)?,
            }
        }
        Ok(())
    }
}

impl fmt::Display for Report {
    /// The lines joined by newlines, without a newline at the end.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for h in &self.head {
            writeln!(f, "{h}")?;
        }
        let names: Vec<&str> = self.columns.iter().map(|c| c.name).collect();
        self.cells(f, &names)?;
        let indent = match self.columns.get(1) {
            Some(second) => self.columns[0].width + second.gap,
            None => 0,
        };
        for line in &self.rows {
            writeln!(f)?;
            match line {
                ReportRow::Cells(cells) | ReportRow::Total(cells) => self.cells(f, cells)?,
                ReportRow::Detail(text) => write!(f, "{:indent$}{text}", "")?,
            }
        }
        for t in &self.totals {
            write!(f, "\n{t}")?;
        }
        Ok(())
    }
}

/// What went wrong in a run, as one line: `<subject>: <items> in <valid frames><tail>`, and
/// the same as values for the JSON statistics: every counter asked about by its key (zero
/// included), and the items without a count as notes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problems {
    subject: &'static str,
    items: Vec<String>,
    valid: String,
    tail: String,
    counts: Vec<(&'static str, u64)>,
    notes: Vec<String>,
}

/// `12 bytes in 3 runs`, `1 byte in 1 run`: garbage in a statistics line.
pub fn garbage(bytes: u64, runs: u64) -> String {
    format!(
        "{} in {}",
        crate::exit::count(bytes, "byte", "bytes"),
        crate::exit::count(runs, "run", "runs")
    )
}

impl Problems {
    /// No problems yet, for `subject` (the protocol's name).
    pub fn new(subject: &'static str) -> Self {
        Problems {
            subject,
            items: Vec::new(),
            valid: String::new(),
            tail: String::new(),
            counts: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// `n one` or `n many` when `n` is not zero; `key` names the counter in the JSON
    /// statistics (snake case).
    pub fn count(&mut self, key: &'static str, n: u64, one: &str, many: &str) -> &mut Self {
        self.count_then(key, n, one, many, "")
    }

    /// Like [`Self::count`] with more words after it (`4 requests` + ` given up`).
    pub fn count_then(
        &mut self,
        key: &'static str,
        n: u64,
        one: &str,
        many: &str,
        then: &str,
    ) -> &mut Self {
        self.counts.push((key, n));
        if n > 0 {
            self.items.push(count(n, one, many) + then);
        }
        self
    }

    /// `N garbage bytes skipped (M runs)` when `bytes` is not zero (`garbage_bytes`,
    /// `garbage_runs`).
    pub fn garbage(&mut self, bytes: u64, runs: u64) -> &mut Self {
        self.counts.push(("garbage_runs", runs));
        let then = format!(" skipped ({})", count(runs, "run", "runs"));
        self.count_then(
            "garbage_bytes",
            bytes,
            "garbage byte",
            "garbage bytes",
            &then,
        )
    }

    /// An item of its own words (a note in the JSON statistics).
    pub fn item(&mut self, text: impl Into<String>) -> &mut Self {
        let text = text.into();
        self.notes.push(text.clone());
        self.items.push(text);
        self
    }

    /// Every counter asked about, by key, in order (zero included).
    pub fn counts(&self) -> &[(&'static str, u64)] {
        &self.counts
    }

    /// The items without a count.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The frames that did decode: ` in n one|many` at the end of the line.
    pub fn in_valid(&mut self, n: u64, one: &str, many: &str) -> &mut Self {
        self.valid = count(n, one, many);
        self
    }

    /// Words after the valid frames (` (SAB2)`).
    pub fn tail(&mut self, tail: &str) -> &mut Self {
        self.tail = tail.to_owned();
        self
    }

    /// Whether nothing went wrong.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The line, or `None` when nothing went wrong.
    pub fn line(&self) -> Option<String> {
        if self.items.is_empty() {
            return None;
        }
        let mut s = format!("{}: {}", self.subject, self.items.join(", "));
        if !self.valid.is_empty() {
            s.push_str(" in ");
            s.push_str(&self.valid);
        }
        s.push_str(&self.tail);
        Some(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Report {
        let mut r = Report::new(&[
            Column::right("ID", 3),
            Column::left("Device", 8).gap(2),
            Column::right("Count", 6),
            Column::left("Notes", 0).gap(2),
        ]);
        r.head.push("mode A".into());
        r.row(vec!["1".into(), "left".into(), "12".into(), "x 1".into()]);
        r.detail("more about 1".into());
        r.row(vec!["22".into(), "l".into(), "3".into(), String::new()]);
        r.row(vec!["all".into(), String::new(), "15".into()]);
        r.totals.push("bytes 9".into());
        r.totals.push("frames 2".into());
        r
    }

    #[test]
    fn report_pads_columns_and_leaves_out_trailing_empty_cells() {
        let text = table().to_string();
        let want = [
            "mode A",
            " ID  Device    Count  Notes",
            "  1  left         12  x 1",
            "     more about 1",
            " 22  l             3",
            "all               15",
            "bytes 9",
            "frames 2",
        ];
        assert_eq!(text, want.join("\n"));
    }

    #[test]
    fn report_without_totals_ends_with_its_last_row() {
        let mut r = table();
        r.totals.clear();
        r.head.clear();
        assert!(r.to_string().ends_with("all               15"));
        assert!(r.to_string().starts_with(" ID"));
    }

    #[test]
    fn wide_cells_push_the_line_out() {
        let mut r = Report::new(&[Column::right("N", 1), Column::left("Name", 3)]);
        r.row(vec!["100".into(), "longer".into()]);
        assert_eq!(r.to_string(), "N Name\n100 longer");
    }

    #[test]
    fn problems_line() {
        let mut p = Problems::new("X");
        p.count("crc_errors", 0, "CRC error", "CRC errors");
        p.in_valid(3, "valid frame", "valid frames");
        assert!(p.is_empty());
        assert_eq!(p.line(), None);
        p.count("crc_errors", 2, "CRC error", "CRC errors")
            .count("timeouts", 1, "timeout", "timeouts")
            .garbage(5, 1)
            .count_then("requests_given_up", 1, "request", "requests", " given up")
            .item("capture error: short file")
            .tail(" (v2)");
        assert_eq!(
            p.line().unwrap(),
            "X: 2 CRC errors, 1 timeout, 5 garbage bytes skipped (1 run), 1 request given up, \
             capture error: short file in 3 valid frames (v2)"
        );
        p.in_valid(1, "valid frame", "valid frames");
        assert!(p.line().unwrap().ends_with(" in 1 valid frame (v2)"));
        assert_eq!(
            p.counts(),
            [
                ("crc_errors", 0),
                ("crc_errors", 2),
                ("timeouts", 1),
                ("garbage_runs", 1),
                ("garbage_bytes", 5),
                ("requests_given_up", 1)
            ]
        );
        assert_eq!(p.notes(), ["capture error: short file"]);
    }

    #[test]
    fn json_keys_are_snake_case() {
        for (name, key) in [
            ("Mean ms", "mean_ms"),
            ("BadCRC", "bad_crc"),
            ("SeqGap", "seq_gap"),
            ("NACK codes", "nack_codes"),
            ("ID", "id"),
            ("Resp min", "resp_min"),
        ] {
            assert_eq!(Column::right(name, 1).json_key(), key);
        }
        assert_eq!(
            Column::right("median", 1).key("resp_median_ms").json_key(),
            "resp_median_ms"
        );
    }
}
