//! Pretty lines: cells padded to the column widths, trailing blanks trimmed, a row class's
//! colour around the line (the table's default on a terminal and for `.txt`).

use super::line::{self, W};

/// A pretty column grows to fit a longer value (and stays that wide, so later rows stay
/// aligned with each other) up to this many characters; a longer value overflows its row only.
pub const PRETTY_GROW_MAX: usize = 60;

/// SGR codes of the row classes and the header, as owo-colors writes them.
pub(crate) const BOLD: &[u8] = b"\x1b[1m";
pub(crate) const DIMMED: &[u8] = b"\x1b[2m";
pub(crate) const YELLOW: &[u8] = b"\x1b[33m";
pub(crate) const RED: &[u8] = b"\x1b[31m";
pub(crate) const CYAN: &[u8] = b"\x1b[36m";
pub(crate) const RESET: &[u8] = b"\x1b[0m";

/// One pretty line: cells padded to the column widths (the first three right-aligned),
/// trailing blanks trimmed, optionally wrapped in a colour. Blanks are held back until a cell
/// with text follows them, so that the blanks at the end of a line are never written.
pub(crate) struct PrettyLine<'b, 'l> {
    pub(crate) line: &'b mut W<'l>,
    style: Option<&'static [u8]>,
    /// Where the line's text starts (after the colour code).
    start: usize,
    /// Blanks owed before the next text.
    pub(crate) blanks: usize,
}

impl<'b, 'l> PrettyLine<'b, 'l> {
    // Inlined: every format's row starts one (a call cost each row some twenty instructions).
    #[inline(always)]
    pub(crate) fn start(line: &'b mut W<'l>, style: Option<&'static [u8]>) -> Self {
        if let Some(s) = style {
            line.put(s);
        }
        let start = line.len();
        PrettyLine {
            line,
            style,
            start,
            blanks: 0,
        }
    }

    /// Cell `i`; with `grow`, a column whose value is longer than its width (up to
    /// [`PRETTY_GROW_MAX`]) widens for this row and every later one. Printable ASCII is one
    /// column per byte; any other text is written char by char, control characters as blanks.
    #[inline(always)]
    pub(crate) fn cell(
        &mut self,
        widths: &mut [usize],
        i: usize,
        cell: &str,
        grow: bool,
        last: bool,
    ) {
        let bytes = cell.as_bytes();
        if i < 3 {
            // Right-aligned: the padding goes first, so the length must be known first.
            if line::scan(bytes, line::not_printable) == 0 {
                self.right(widths, i, bytes, None, grow, last);
            } else {
                self.right(widths, i, bytes, Some(cell), grow, last);
            }
            return;
        }
        // Left-aligned: written after the blanks owed and checked in one go (a cell that is not
        // printable ASCII is written again).
        self.blanks += 2;
        let len = if bytes.is_empty() {
            0
        } else {
            self.pay_blanks();
            let at = self.line.len();
            if self.line.put_scan(bytes, line::not_printable) == 0 {
                bytes.len()
            } else if let Some(width) = clean_width(bytes) {
                width
            } else {
                self.line.truncate(at);
                self.chars(cell)
            }
        };
        let pad = fit(widths, i, len, grow, last);
        if !last {
            self.blanks += pad;
        }
    }

    /// A left-aligned cell (Sensor # or later) is written in place after this: the blanks
    /// owed are paid. Returns where its text starts, where the line was before the blanks,
    /// and the blanks owed then, for [`PrettyLine::end_cell`].
    #[inline(always)]
    pub(crate) fn begin_cell(&mut self) -> (usize, usize, usize) {
        self.blanks += 2;
        let (before, owed) = (self.line.len(), self.blanks);
        self.pay_blanks();
        (self.line.len(), before, owed)
    }

    /// The cell `i` written in place since [`PrettyLine::begin_cell`] (UTF-8 only) ends, as
    /// [`PrettyLine::cell`] writes a text, with `grow`: an empty cell leaves the blanks owed,
    /// and a cell that is not printable ASCII is written again from a copy in `scratch`. A
    /// `plain` cell (only pieces known to be printable, one column a character) is not looked
    /// at: `Some(wide)`, its width is its length less `wide` (the bytes of its characters
    /// beyond their first).
    #[inline(always)]
    pub(crate) fn end_cell(
        &mut self,
        widths: &mut [usize],
        i: usize,
        last: bool,
        (at, before, owed): (usize, usize, usize),
        plain: Option<usize>,
        scratch: &mut Vec<u8>,
    ) {
        let cell = self.line.bytes().get(at..).unwrap_or_default();
        let len = if cell.is_empty() {
            self.line.truncate(before);
            self.blanks = owed;
            0
        } else if let Some(wide) = plain {
            // (A line over its room may have dropped pieces: it is written again.)
            cell.len().saturating_sub(wide)
        } else if line::scan(cell, line::not_printable) == 0 {
            cell.len()
        } else if let Some(width) = clean_width(cell) {
            width
        } else {
            self.rewrite(at, scratch)
        };
        let pad = fit(widths, i, len, true, last);
        if !last {
            self.blanks += pad;
        }
    }

    /// Writes the cell from `at` again char by char ([`PrettyLine::chars`]) from a copy in
    /// `scratch`; returns its width.
    #[cold]
    #[inline(never)]
    fn rewrite(&mut self, at: usize, scratch: &mut Vec<u8>) -> usize {
        scratch.clear();
        scratch.extend_from_slice(self.line.bytes().get(at..).unwrap_or_default());
        self.line.truncate(at);
        match std::str::from_utf8(scratch) {
            Ok(text) => self.chars(text),
            Err(_) => self.chars(&String::from_utf8_lossy(scratch)),
        }
    }

    /// A cell of ASCII digits (Counter, Millis, ID).
    #[inline(always)]
    pub(crate) fn digits(&mut self, widths: &mut [usize], i: usize, digits: &[u8]) {
        self.right(widths, i, digits, None, true, false);
    }

    /// A right-aligned cell: `bytes`, printable ASCII, or the `chars` of a cell that is not.
    #[inline(always)]
    pub(crate) fn right(
        &mut self,
        widths: &mut [usize],
        i: usize,
        bytes: &[u8],
        chars: Option<&str>,
        grow: bool,
        last: bool,
    ) {
        if i > 0 {
            self.blanks += 2;
        }
        let len = chars.map_or(bytes.len(), |c| c.chars().count());
        self.blanks += fit(widths, i, len, grow, last);
        if !bytes.is_empty() {
            self.pay_blanks();
            match chars {
                None => self.line.put(bytes),
                Some(cell) => {
                    self.chars(cell);
                }
            }
        }
    }

    /// Writes cells kept from an earlier row ([`Spans`](super::spans::Spans)): their text, after the blanks owed
    /// before it, and the blanks owed after it.
    #[inline(always)]
    pub(crate) fn copy(&mut self, bytes: &[u8], blanks: usize) {
        if bytes.is_empty() {
            self.blanks += blanks;
        } else {
            self.pay_blanks();
            self.line.put(bytes);
            self.blanks = blanks;
        }
    }

    /// Writes the blanks owed.
    #[inline(always)]
    fn pay_blanks(&mut self) {
        self.line.spaces(self.blanks);
        self.blanks = 0;
    }

    /// Writes a cell that is not printable ASCII char by char, control characters as blanks;
    /// returns its width (one column per char).
    fn chars(&mut self, cell: &str) -> usize {
        self.line.aside(|w| {
            for c in cell.chars() {
                let c = if c.is_control() { ' ' } else { c };
                let mut tmp = [0u8; 4];
                w.put(c.encode_utf8(&mut tmp).as_bytes());
            }
        });
        cell.chars().count()
    }

    /// Trims the line's trailing whitespace (as `str::trim_end`), closes the colour, ends
    /// the line.
    #[inline(always)]
    pub(crate) fn finish(self) {
        let text = &self.line.bytes()[self.start..];
        // Blanks held back were never written; a line that ends in printable ASCII other than
        // a blank has nothing to trim.
        let keep = match text.last() {
            None | Some(0x21..=0x7E) => text.len(),
            Some(_) => match std::str::from_utf8(text) {
                Ok(t) => t.trim_end().len(),
                Err(_) => text.len(),
            },
        };
        self.line.truncate(self.start + keep);
        if self.style.is_some() {
            self.line.put(RESET);
        }
        self.line.byte(b'\n');
    }
}

/// The width of a text that is not printable ASCII (one column per char) when it is UTF-8 and
/// holds no control character, so that it stays as written (`…`, `µs`); `None` when one must
/// become a blank, or a byte a replacement character ([`PrettyLine::chars`]). Counted on the
/// bytes, eight at a time: a char is a byte that does not continue one; the controls are C0,
/// DEL and C1 (`C2 80` to `C2 9F`), what `char::is_control` finds. Only the text from its first
/// byte that is not ASCII on is checked for UTF-8 (an ASCII start cannot make it invalid).
#[inline]
fn clean_width(b: &[u8]) -> Option<usize> {
    let (mut continuing, mut first_high) = (0, None);
    let mut words = b.chunks_exact(8);
    for (k, word) in words.by_ref().enumerate() {
        let x = u64::from_le_bytes(word.try_into().unwrap_or_default());
        if line::below_0x20(x) | line::zero_byte(x ^ line::rep(0x7F)) != 0 {
            return None;
        }
        let high = x & line::rep(0x80);
        if high == 0 {
            continue;
        }
        first_high.get_or_insert(k * 8 + high.trailing_zeros() as usize / 8);
        if line::zero_byte(x ^ line::rep(0xC2)) != 0 && c1_control(b, k * 8, k * 8 + 8) {
            return None;
        }
        // A continuing byte: 10xxxxxx (bit 7 set, bit 6 clear).
        continuing += (x & !(x << 1) & line::rep(0x80)).count_ones() as usize;
    }
    let tail = b.len() - words.remainder().len();
    for (i, &x) in b.iter().enumerate().skip(tail) {
        if x < 0x20 || x == 0x7F || c1_control(b, i, i + 1) {
            return None;
        }
        if x >= 0x80 {
            first_high.get_or_insert(i);
        }
        continuing += usize::from(x & 0xC0 == 0x80);
    }
    if let Some(from) = first_high {
        std::str::from_utf8(b.get(from..).unwrap_or_default()).ok()?;
    }
    Some(b.len() - continuing)
}

/// Whether a C1 control (`C2 80` to `C2 9F`) starts in `b[from..to]`.
#[inline]
fn c1_control(b: &[u8], from: usize, to: usize) -> bool {
    (from..to).any(|i| b.get(i) == Some(&0xC2) && matches!(b.get(i + 1), Some(0x80..=0x9F)))
}

/// Column `i`'s width for a cell `len` columns wide: with `grow` (and not the last column), a
/// longer cell up to [`PRETTY_GROW_MAX`] widens the column for this row and every later one.
/// Returns the padding the cell needs.
#[inline(always)]
pub(crate) fn fit(widths: &mut [usize], i: usize, len: usize, grow: bool, last: bool) -> usize {
    let mut spare = 4;
    let width = widths.get_mut(i).unwrap_or(&mut spare);
    // The rare case first: a cell longer than its column (one test for every other cell).
    if len > *width && grow && !last && len <= PRETTY_GROW_MAX {
        *width = len;
    }
    width.saturating_sub(len)
}

#[cfg(test)]
mod tests {
    use super::clean_width;
    use proptest::prelude::*;

    fn by_chars(text: &str) -> Option<usize> {
        (!text.chars().any(char::is_control)).then(|| text.chars().count())
    }

    #[test]
    fn clean_widths_of_the_tables_texts() {
        assert_eq!(clean_width("992 992 \u{2026}".as_bytes()), Some(9));
        assert_eq!(clean_width("\u{b5}s".as_bytes()), Some(2));
        assert_eq!(clean_width("a\u{85}b".as_bytes()), None);
        assert_eq!(clean_width("a\u{9f}".as_bytes()), None);
        assert_eq!(clean_width("\u{a0}\u{7f}".as_bytes()), None);
        assert_eq!(clean_width("\t".as_bytes()), None);
        assert_eq!(clean_width("\u{1F680}\u{c0}".as_bytes()), Some(2));
    }

    proptest! {
        #[test]
        fn clean_width_is_the_char_count_of_a_text_without_controls(text in ".*", c in any::<char>()) {
            prop_assert_eq!(clean_width(text.as_bytes()), by_chars(&text));
            let t = format!("{text}{c}{text}");
            prop_assert_eq!(clean_width(t.as_bytes()), by_chars(&t));
        }

        /// Any bytes: `None` for what is not UTF-8, as the cell is then written again with
        /// replacement characters.
        #[test]
        fn clean_width_of_any_bytes(
            b in proptest::collection::vec(
                prop_oneof![any::<u8>(), Just(0xC2u8), Just(0x85u8), Just(b'a'), Just(0xE2u8)],
                0..40,
            ),
        ) {
            let want = std::str::from_utf8(&b).ok().and_then(by_chars);
            prop_assert_eq!(clean_width(&b), want);
        }
    }
}
