//! The table's text state that both ways of writing a row share: the row through
//! [`crate::row::Row`] (the sink's table writer) and a decoder's row written straight from its
//! frame ([`super::direct`]). Rows of both kinds interleave in one table, so the Counter, the
//! pretty column widths and the cells kept per stamp live here, once.

use super::spans::Spans;

/// Output format.
/// (The command line's names for it are in `cli/choices.rs`.)
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
    pub fn from_path(path: &std::path::Path) -> Option<Format> {
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

/// The column after `Data` in TSV, CSV and JSON Lines (not in pretty output, where Data says
/// the same): the row's first number ([`super::Row::value`]).
pub const VALUE_COLUMN: &str = "Value";

/// Extra columns whose cells are numbers (JSON writes them as numbers).
pub const NUMERIC_EXTRA: [&str; 2] = ["Resp ms", "Seq"];

/// A row counter as decimal digits, incremented in place (no division per row).
#[derive(Clone, Debug)]
pub(crate) struct Digits {
    /// The digits are `buf[start..END]`; the bytes after them are room for a fixed-size copy.
    buf: [u8; 2 * Digits::END],
    start: usize,
}

impl Digits {
    const END: usize = 20;

    pub(crate) fn zero() -> Self {
        let mut buf = [0u8; 2 * Self::END];
        buf[..Self::END].fill(b'0');
        Digits {
            buf,
            start: Self::END - 1,
        }
    }

    /// Adds one: nine rows in ten change only the last digit, inline; a carry goes through a
    /// call.
    #[inline(always)]
    pub(crate) fn increment(&mut self) {
        let last = &mut self.buf[Self::END - 1];
        if *last != b'9' {
            *last += 1;
            return;
        }
        self.carry();
    }

    /// [`Digits::increment`] of a number that ends in 9.
    #[inline(never)]
    fn carry(&mut self) {
        let mut i = Self::END;
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

    #[inline]
    pub(crate) fn as_bytes(&self) -> &[u8] {
        &self.buf[self.start..Self::END]
    }

    /// Appends the digits to `w` with one fixed-size copy.
    #[inline(always)]
    pub(crate) fn put(&self, w: &mut super::line::W<'_>) {
        let mut chunk = [0u8; Self::END];
        chunk.copy_from_slice(&self.buf[self.start..self.start + Self::END]);
        w.put_prefix(&chunk, Self::END - self.start);
    }
}

/// What the rows of one table share, whichever way they are written.
pub struct Text {
    pub(crate) format: Format,
    /// Pretty output in colour.
    pub(crate) color: bool,
    /// A `Raw` column (`--raw`).
    pub(crate) raw: bool,
    /// The decoder's extra columns the table was made with (a decoder writes rows straight
    /// into the table only for these columns).
    pub(crate) extra: Vec<&'static str>,
    /// Rows so far, written and skipped (the last Counter), and its decimal digits.
    pub(crate) counter: u64,
    pub(crate) digits: Digits,
    /// Rows of whole frames (with wire bytes, not an error or a note).
    pub(crate) frames: u64,
    /// Pretty output: the width of each column now (they only grow).
    pub(crate) widths: Vec<usize>,
    /// JSON Lines: the key of each extra column (`,"resp_ms":`), built once, and whether its
    /// cells are numbers.
    pub(crate) json_keys: Vec<(Vec<u8>, bool)>,
    /// JSON Lines: the cells Data, Value and every extra column empty
    /// (`,"data":null,"value":null,"unit":null…`), and where each column's piece starts in it
    /// (from Data on).
    pub(crate) json_nulls: (Vec<u8>, Vec<usize>),
    /// JSON Lines: the keys of `parts`' members, written once per name.
    pub(crate) part_keys: super::part_keys::PartKeys,
    /// The cells ID to Sensor as written, per [`super::Row::stamp`].
    pub(crate) spans: Spans,
    /// A cell written again (quoted, escaped) keeps its first text here.
    pub(crate) scratch: Vec<u8>,
    /// A direct row's Data cell as first written, when it was written again (quoted,
    /// escaped): the numbers marked in it are read from here. Its own buffer, as a later cell
    /// written again reuses `scratch`.
    pub(crate) data_copy: Vec<u8>,
    /// Debug builds: the copied cells of a stamp, to compare with the cells written again.
    pub(crate) check: Vec<u8>,
}

impl Text {
    pub(crate) fn new(
        format: Format,
        color: bool,
        raw: bool,
        extra: &[&'static str],
        widths: Vec<usize>,
    ) -> Self {
        Text {
            format,
            color,
            raw,
            extra: extra.to_vec(),
            counter: 0,
            digits: Digits::zero(),
            frames: 0,
            widths,
            json_keys: extra
                .iter()
                .map(|name| (json_key(name), NUMERIC_EXTRA.contains(name)))
                .collect(),
            json_nulls: json_nulls(extra),
            part_keys: super::part_keys::PartKeys::new(),
            spans: Spans::new(),
            scratch: Vec::new(),
            data_copy: Vec::new(),
            check: Vec::new(),
        }
    }

    /// The next row's number (a row written or skipped).
    #[inline]
    pub(crate) fn count(&mut self) {
        self.counter += 1;
        self.digits.increment();
    }
}

/// [`Text::json_nulls`] for the extra columns `extra`.
fn json_nulls(extra: &[&'static str]) -> (Vec<u8>, Vec<usize>) {
    let (mut text, mut at) = (Vec::new(), Vec::new());
    let keys = [json_key("Data"), json_key("Value")];
    for key in keys
        .into_iter()
        .chain(extra.iter().map(|name| json_key(name)))
    {
        at.push(text.len());
        text.extend_from_slice(&key);
        text.extend_from_slice(b"null");
    }
    at.push(text.len());
    (text, at)
}

/// The JSON key of a column, with its comma and colon: `,"sensor_no":` for `Sensor #`.
pub(crate) fn json_key(name: &str) -> Vec<u8> {
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

pub(crate) use super::line::is_json_number;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counter_digits_count_like_itoa() {
        let mut d = Digits::zero();
        let mut ib = itoa::Buffer::new();
        for n in 1..=100_100u64 {
            d.increment();
            assert_eq!(d.as_bytes(), ib.format(n).as_bytes(), "{n}");
            // and as one fixed-size copy, with room and (8 bytes) without
            let mut v = vec![0u8; 8];
            let len = super::super::line::write_line(&mut v, 0, |w| {
                d.put(w);
                w.byte(b'|');
            });
            assert_eq!(&v[..len - 1], ib.format(n).as_bytes(), "{n}");
        }
        let mut d = Digits::zero();
        d.buf[..20].copy_from_slice(b"00018446744073709549");
        d.start = 3;
        for _ in 0..10 {
            d.increment();
        }
        assert_eq!(d.as_bytes(), b"18446744073709559");
    }
}
