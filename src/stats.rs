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
}

impl Column {
    /// A right-aligned column one space after the previous one.
    pub const fn right(name: &'static str, width: usize) -> Self {
        Column {
            name,
            width,
            align: Align::Right,
            gap: 1,
        }
    }

    /// A left-aligned column one space after the previous one.
    pub const fn left(name: &'static str, width: usize) -> Self {
        Column {
            name,
            width,
            align: Align::Left,
            gap: 1,
        }
    }

    /// The same column `gap` spaces after the previous one.
    pub const fn gap(self, gap: usize) -> Self {
        Column { gap, ..self }
    }
}

/// A row of a [`Report`] table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReportRow {
    /// Cells in column order; there may be fewer than columns (a totals row), and trailing
    /// empty cells are left out with their gaps.
    Cells(Vec<String>),
    /// Text about the row above it, indented to the second column.
    Detail(String),
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
                ReportRow::Cells(cells) => self.cells(f, cells)?,
                ReportRow::Detail(text) => write!(f, "{:indent$}{text}", "")?,
            }
        }
        for t in &self.totals {
            write!(f, "\n{t}")?;
        }
        Ok(())
    }
}

/// What went wrong in a run, as one line: `<subject>: <items> in <valid frames><tail>`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problems {
    subject: &'static str,
    items: Vec<String>,
    valid: String,
    tail: String,
}

impl Problems {
    /// No problems yet, for `subject` (the protocol's name).
    pub fn new(subject: &'static str) -> Self {
        Problems {
            subject,
            items: Vec::new(),
            valid: String::new(),
            tail: String::new(),
        }
    }

    /// `n one` or `n many` when `n` is not zero.
    pub fn count(&mut self, n: u64, one: &str, many: &str) -> &mut Self {
        self.count_then(n, one, many, "")
    }

    /// Like [`Self::count`] with more words after it (`4 requests` + ` given up`).
    pub fn count_then(&mut self, n: u64, one: &str, many: &str, then: &str) -> &mut Self {
        if n > 0 {
            self.items.push(count(n, one, many) + then);
        }
        self
    }

    /// `N garbage bytes skipped (M runs)` when `bytes` is not zero.
    pub fn garbage(&mut self, bytes: u64, runs: u64) -> &mut Self {
        let then = format!(" skipped ({})", count(runs, "run", "runs"));
        self.count_then(bytes, "garbage byte", "garbage bytes", &then)
    }

    /// An item of its own words.
    pub fn item(&mut self, text: impl Into<String>) -> &mut Self {
        self.items.push(text.into());
        self
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
        p.count(0, "CRC error", "CRC errors");
        p.in_valid(3, "valid frame", "valid frames");
        assert!(p.is_empty());
        assert_eq!(p.line(), None);
        p.count(2, "CRC error", "CRC errors")
            .count(1, "timeout", "timeouts")
            .garbage(5, 1)
            .count_then(1, "request", "requests", " given up")
            .item("capture error: short file")
            .tail(" (v2)");
        assert_eq!(
            p.line().unwrap(),
            "X: 2 CRC errors, 1 timeout, 5 garbage bytes skipped (1 run), 1 request given up, \
             capture error: short file in 3 valid frames (v2)"
        );
        p.in_valid(1, "valid frame", "valid frames");
        assert!(p.line().unwrap().ends_with(" in 1 valid frame (v2)"));
    }
}
