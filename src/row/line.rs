//! One output line, assembled before it is appended to the output buffer.
//!
//! The row writers put a row's cells into a line ([`W`]): a buffer that is kept at its full length
//! (zeroed once, grown when a row needs more) with a write position, so that appending a cell
//! costs no capacity check per byte and no call for a short copy. A row is then appended to
//! the output in one copy. The checks for bytes that need escaping (control characters in TSV,
//! quotes in CSV and JSON, non-printable bytes in pretty output) look at eight bytes at a time
//! ([`scan`]); only a cell that has such a byte takes the byte-by-byte path, which produces
//! exactly what the byte-by-byte rules always produced.

use super::{Part, PartSpan, Parts};

mod json;

const SPACES: [u8; 32] = [b' '; 32];

/// Writes one line with `write` into the room after `buf[..len]` and returns the line's length.
/// A line longer than the room is written again into more room (`buf` grows, and stays grown),
/// until it fits: nothing is cut, and nothing can overrun.
#[inline(always)]
pub(crate) fn write_line(
    buf: &mut Vec<u8>,
    len: usize,
    mut write: impl FnMut(&mut W<'_>),
) -> usize {
    loop {
        let mut w = W {
            buf: buf.get_mut(len..).unwrap_or_default(),
            pos: 0,
            over: false,
        };
        write(&mut w);
        if !w.over {
            return w.pos;
        }
        grow(buf, len);
    }
}

/// [`write_line`] for a row that almost always fits the room it has: `write` runs once
/// inline, and only a line longer than the room goes the slow way (`write` again, through a
/// call, into more room).
#[inline(always)]
pub(crate) fn write_once(
    buf: &mut Vec<u8>,
    len: usize,
    mut write: impl FnMut(&mut W<'_>),
) -> usize {
    let mut w = W {
        buf: buf.get_mut(len..).unwrap_or_default(),
        pos: 0,
        over: false,
    };
    write(&mut w);
    if !w.over {
        return w.pos;
    }
    again(buf, len, &mut write)
}

#[cold]
#[inline(never)]
fn again(buf: &mut Vec<u8>, len: usize, write: &mut dyn FnMut(&mut W<'_>)) -> usize {
    grow(buf, len);
    write_line(buf, len, write)
}

#[cold]
#[inline(never)]
fn grow(buf: &mut Vec<u8>, len: usize) {
    let more = buf.len().saturating_sub(len).max(ROOM);
    buf.resize(buf.len() + more, 0);
}

/// Room a line gets at least when it did not fit.
pub(crate) const ROOM: usize = 1024;

/// Where a number's text is in the Data cell: from [`super::Cells::here`] before it to
/// [`super::Cells::here`] after it (in the line, where the row's cells are written).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Mark {
    pub(crate) start: u32,
    pub(crate) end: u32,
}

impl Mark {
    pub fn new(start: u32, end: u32) -> Self {
        Mark { start, end }
    }
}

/// A line being written into the room [`write_line`] gives: `buf[..pos]` is the text so far.
/// A write that does not fit sets `over` (and is dropped); [`write_line`] then starts again.
pub(crate) struct W<'a> {
    buf: &'a mut [u8],
    pos: usize,
    over: bool,
}

impl W<'_> {
    /// The line so far.
    #[inline]
    pub fn bytes(&self) -> &[u8] {
        &self.buf[..self.pos]
    }

    /// Whether a write did not fit (the line is written again into more room).
    #[inline]
    pub fn over(&self) -> bool {
        self.over
    }

    /// Length of the line so far.
    #[inline]
    pub fn len(&self) -> usize {
        self.pos
    }

    /// Cuts the line back to `len` bytes.
    #[inline]
    pub fn truncate(&mut self, len: usize) {
        self.pos = self.pos.min(len);
    }

    /// Appends `s` as it is.
    #[inline(always)]
    pub fn put(&mut self, s: &[u8]) {
        let end = self.pos + s.len();
        match self.buf.get_mut(self.pos..end) {
            Some(room) => {
                copy(room, s);
                self.pos = end;
            }
            None => self.over = true,
        }
    }

    /// Appends the first `n` bytes of `src` with one fixed-size copy of all of it when there
    /// is room for it (the bytes after the `n` are written over later, or lie beyond the line).
    #[inline(always)]
    pub fn put_prefix<const N: usize>(&mut self, src: &[u8; N], n: usize) {
        if let Some(room) = self.buf.get_mut(self.pos..self.pos + N) {
            room.copy_from_slice(src);
            self.pos += n.min(N);
        } else {
            self.put(src.get(..n).unwrap_or(src));
        }
    }

    /// Appends the first `n` bytes of a span slot ([`super::spans::Spans::get_slot`]): one
    /// fixed-size copy of 32, 64 or all of the slot's bytes.
    #[inline(always)]
    pub fn put_span(&mut self, slot: &[u8; super::spans::SPAN_MAX], n: usize) {
        if n <= 32 {
            let mut head = [0u8; 32];
            head.copy_from_slice(&slot[..32]);
            self.put_prefix(&head, n);
        } else if n <= 64 {
            let mut head = [0u8; 64];
            head.copy_from_slice(&slot[..64]);
            self.put_prefix(&head, n);
        } else {
            self.put_prefix(slot, n);
        }
    }

    /// Appends a byte as two upper-case hex digits.
    #[inline(always)]
    pub fn hex2(&mut self, b: u8) {
        const HEX: &[u8; 16] = b"0123456789ABCDEF";
        self.put(&[HEX[usize::from(b >> 4)], HEX[usize::from(b & 15)]]);
    }

    /// Appends one byte.
    #[inline(always)]
    pub fn byte(&mut self, b: u8) {
        match self.buf.get_mut(self.pos) {
            Some(room) => {
                *room = b;
                self.pos += 1;
            }
            None => self.over = true,
        }
    }

    /// Appends `n` blanks.
    #[inline(always)]
    pub fn spaces(&mut self, mut n: usize) {
        // Usually: one fixed-size store of 32 blanks, of which the first `n` count (the rest
        // is written over by what follows, or lies beyond the line).
        if n <= SPACES.len()
            && let Some(room) = self.buf.get_mut(self.pos..self.pos + SPACES.len())
        {
            room.copy_from_slice(&SPACES);
            self.pos += n;
            return;
        }
        while n > 0 {
            let k = n.min(SPACES.len());
            self.put(&SPACES[..k]);
            n -= k;
        }
    }

    /// Appends `s` as it is and returns `test` ORed over words that cover it (as [`scan`]),
    /// from the same loads that copy it.
    #[inline(always)]
    pub fn put_scan(&mut self, s: &[u8], test: impl Fn(u64) -> u64) -> u64 {
        let n = s.len();
        let end = self.pos + n;
        let Some(room) = self.buf.get_mut(self.pos..end) else {
            self.over = true;
            return 0;
        };
        self.pos = end;
        if n <= 16 {
            return copy_test(room, s, test);
        }
        copy(room, s);
        scan(s, test)
    }

    /// A TSV field: copied whole, control characters (tabs, newlines) that would break the
    /// row replaced with spaces.
    #[inline(always)]
    pub fn tsv(&mut self, field: &[u8]) {
        let at = self.pos;
        if self.put_scan(field, below_0x20) != 0 {
            for b in self.buf.get_mut(at..self.pos).unwrap_or_default() {
                if *b < 0x20 {
                    *b = b' ';
                }
            }
        }
    }

    /// A CSV field (RFC 4180): as it is, or in double quotes with inner quotes doubled when it
    /// holds a comma, a quote, CR or LF (what the csv crate's `QuoteStyle::Necessary` does).
    #[inline(always)]
    pub fn csv(&mut self, field: &[u8]) {
        let at = self.pos;
        // Control characters are looked at exactly below; a comma or a quote always quotes.
        if self.put_scan(field, |x| {
            below_0x20(x) | zero_byte(x ^ rep(b',')) | zero_byte(x ^ rep(b'"'))
        }) == 0
            || !field
                .iter()
                .any(|&b| matches!(b, b',' | b'"' | b'\r' | b'\n'))
        {
            return;
        }
        // Written again, quoted: without inner quotes (a list of numbers, a note with commas)
        // the field between two quotes.
        self.pos = at;
        if has_quote(field) {
            self.aside(|w| w.csv_quoted(field));
        } else {
            self.byte(b'"');
            self.put(field);
            self.byte(b'"');
        }
    }

    /// `field` in double quotes, inner quotes doubled.
    fn csv_quoted(&mut self, field: &[u8]) {
        self.byte(b'"');
        let mut rest = field;
        while let Some(q) = rest.iter().position(|&b| b == b'"') {
            self.put(&rest[..=q]);
            self.byte(b'"');
            rest = &rest[q + 1..];
        }
        self.put(rest);
        self.byte(b'"');
    }

    /// Blanks the control characters of the TSV cell written since `at` (see [`W::tsv`]).
    #[inline(always)]
    pub fn tsv_fix(&mut self, at: usize) {
        let cell = self.buf.get_mut(at..self.pos).unwrap_or_default();
        if scan(cell, below_0x20) != 0 {
            for b in cell {
                if *b < 0x20 {
                    *b = b' ';
                }
            }
        }
    }

    /// Quotes the CSV cell written since `at` when it needs it (see [`W::csv`]): then it is
    /// written again from a copy in `scratch`, and its start and length come back.
    #[inline(always)]
    pub fn csv_fix(&mut self, at: usize, scratch: &mut Vec<u8>) -> Option<(u32, u32)> {
        let cell = self.buf.get(at..self.pos).unwrap_or_default();
        if scan(cell, |x| {
            below_0x20(x) | zero_byte(x ^ rep(b',')) | zero_byte(x ^ rep(b'"'))
        }) == 0
            || !cell
                .iter()
                .any(|&b| matches!(b, b',' | b'"' | b'\r' | b'\n'))
        {
            return None;
        }
        if has_quote(cell) {
            self.rewrite(at, scratch, |w, text| w.csv_quoted(text))
        } else {
            self.quote_within(at, scratch)
        }
    }

    /// The cell written since `at`, which holds no quote, between two quotes: moved one byte on
    /// in the line; its text is kept in `scratch` as [`W::rewrite`] keeps it (a number marked
    /// in it is read from there).
    #[inline(never)]
    fn quote_within(&mut self, at: usize, scratch: &mut Vec<u8>) -> Option<(u32, u32)> {
        let end = self.pos;
        let cell = self.buf.get(at..end).unwrap_or_default();
        scratch.clear();
        scratch.extend_from_slice(cell);
        if end + 2 > self.buf.len() || at > end {
            self.over = true;
        } else {
            self.buf.copy_within(at..end, at + 1);
            self.buf[at] = b'"';
            self.buf[end + 1] = b'"';
            self.pos = end + 2;
        }
        Some((at as u32, scratch.len() as u32))
    }

    /// Writes the text written since `at` again with `write`, from a copy in `scratch`;
    /// returns where it started and its length.
    #[cold]
    #[inline(never)]
    fn rewrite(
        &mut self,
        at: usize,
        scratch: &mut Vec<u8>,
        write: impl FnOnce(&mut W<'_>, &[u8]),
    ) -> Option<(u32, u32)> {
        scratch.clear();
        scratch.extend_from_slice(self.buf.get(at..self.pos).unwrap_or_default());
        self.pos = at.min(self.pos);
        write(self, scratch);
        Some((at as u32, scratch.len() as u32))
    }

    /// Appends the line's own bytes `a..b` (before the end) again.
    #[inline(always)]
    pub fn copy_within(&mut self, a: usize, b: usize) {
        if a > b || b > self.pos {
            return;
        }
        let n = b - a;
        if n <= 32 && self.pos + 32 <= self.buf.len() {
            // One fixed-size copy (the bytes after the text are written over later, or lie
            // beyond the line): `a + 32 <= pos + 32`, in the buffer.
            let mut tmp = [0u8; 32];
            tmp.copy_from_slice(&self.buf[a..a + 32]);
            self.buf[self.pos..self.pos + 32].copy_from_slice(&tmp);
            self.pos += n;
            return;
        }
        if self.pos + n > self.buf.len() {
            self.over = true;
            return;
        }
        self.buf.copy_within(a..b, self.pos);
        self.pos += n;
    }

    /// Bytes as upper-case hex pairs with a blank between them (`7E 1A 10`), as
    /// [`crate::fmt::push_hex_bytes`].
    #[inline]
    pub fn hex_bytes(&mut self, bytes: &[u8]) {
        const HEX: &[u8; 16] = b"0123456789ABCDEF";
        let n = bytes.len() * 3;
        let Some(room) = self.buf.get_mut(self.pos..self.pos + n) else {
            self.over = true;
            return;
        };
        for (i, b) in bytes.iter().enumerate() {
            room[3 * i] = HEX[usize::from(b >> 4)];
            room[3 * i + 1] = HEX[usize::from(b & 15)];
            room[3 * i + 2] = b' ';
        }
        self.pos += n.saturating_sub(1);
    }

    /// `raw / 10^prec` as [`crate::fmt::push_fixed`] writes it (`6543, 2` → `65.43`,
    /// `-150, 2` → `-1.50`, `5, 3` → `0.005`): its digits written straight into the line.
    #[inline(always)]
    pub fn fixed(&mut self, raw: i64, prec: u8) {
        if let Some(room) = self.buf.get_mut(self.pos..self.pos + 32)
            && let Some(n) = crate::digits::put_fixed(room, raw, prec)
        {
            self.pos += n;
            return;
        }
        self.fixed_slow(raw, prec);
    }

    /// [`W::fixed`] near the end of the room, or with more than 7 decimals.
    #[cold]
    #[inline(never)]
    fn fixed_slow(&mut self, raw: i64, prec: u8) {
        let mut s = String::new();
        crate::fmt::push_fixed(&mut s, raw, prec);
        self.put(s.as_bytes());
    }

    /// Writes with `write` in a function of its own (for what is seldom written: quoting,
    /// escaping, non-ASCII pretty cells), so that the writer of a row keeps its position in a
    /// register instead of handing its address to that function.
    #[inline(always)]
    pub fn aside(&mut self, write: impl FnOnce(&mut W<'_>)) {
        #[inline(never)]
        fn run(buf: &mut [u8], pos: usize, write: impl FnOnce(&mut W<'_>)) -> (usize, bool) {
            let mut w = W {
                buf,
                pos,
                over: false,
            };
            write(&mut w);
            (w.pos, w.over)
        }
        let (pos, over) = run(&mut *self.buf, self.pos, write);
        self.pos = pos;
        self.over |= over;
    }

    /// A number in decimal, its digits written straight into the line (eight at a time,
    /// [`crate::digits`]).
    #[inline(always)]
    pub fn dec(&mut self, n: u64) {
        match self.buf.get_mut(self.pos..self.pos + 24) {
            Some(room) => self.pos += crate::digits::put_u64(room, n),
            None => self.put(itoa::Buffer::new().format(n).as_bytes()),
        }
    }

    /// [`W::dec`] with the digits written through a call ([`crate::digits::put_u64_call`]),
    /// for the table's writer of [`super::Row`]s, whose loops lose more to the inlined digits
    /// than the call costs.
    #[inline(always)]
    pub fn dec_called(&mut self, n: u64) {
        match self.buf.get_mut(self.pos..self.pos + 24) {
            Some(room) => self.pos += crate::digits::put_u64_call(room, n),
            None => self.put(itoa::Buffer::new().format(n).as_bytes()),
        }
    }
}

/// Whether `s` holds a double quote (CSV then doubles it).
#[inline(always)]
fn has_quote(s: &[u8]) -> bool {
    s.contains(&b'"')
}

/// Copies `src` (at most 16 bytes) to the start of `dst` (at least as long) and returns
/// `test` ORed over words that cover it (as [`scan`]), from the same loads that copy it.
#[inline(always)]
fn copy_test(dst: &mut [u8], s: &[u8], test: impl Fn(u64) -> u64) -> u64 {
    let n = s.len();
    let load8 = |i: usize| u64::from_le_bytes(s[i..i + 8].try_into().unwrap_or([b'A'; 8]));
    let load4 = |i: usize| u32::from_le_bytes(s[i..i + 4].try_into().unwrap_or([b'A'; 4]));
    match n {
        0 => 0,
        1..=3 => {
            let (a, b, c) = (s[0], s[n / 2], s[n - 1]);
            dst[0] = a;
            dst[n / 2] = b;
            dst[n - 1] = c;
            test((rep(b'A') & !0xFF_FFFF) | a as u64 | (b as u64) << 8 | (c as u64) << 16)
        }
        4..=7 => {
            let (a, b) = (load4(0), load4(n - 4));
            dst[..4].copy_from_slice(&a.to_le_bytes());
            dst[n - 4..n].copy_from_slice(&b.to_le_bytes());
            test(a as u64 | (b as u64) << 32)
        }
        _ => {
            let (a, b) = (load8(0), load8(n - 8));
            dst[..8].copy_from_slice(&a.to_le_bytes());
            dst[n - 8..n].copy_from_slice(&b.to_le_bytes());
            test(a) | test(b)
        }
    }
}

/// Copies `src` to the start of `dst` (at least as long): short copies are done with one or
/// two overlapping fixed-size moves instead of a call.
#[inline(always)]
fn copy(dst: &mut [u8], src: &[u8]) {
    let n = src.len();
    let dst = &mut dst[..n];
    match n {
        0 => {}
        1..=3 => {
            dst[0] = src[0];
            dst[n / 2] = src[n / 2];
            dst[n - 1] = src[n - 1];
        }
        4..=7 => {
            dst[..4].copy_from_slice(&src[..4]);
            dst[n - 4..].copy_from_slice(&src[n - 4..]);
        }
        8..=16 => {
            dst[..8].copy_from_slice(&src[..8]);
            dst[n - 8..].copy_from_slice(&src[n - 8..]);
        }
        17..=32 => {
            dst[..16].copy_from_slice(&src[..16]);
            dst[n - 16..].copy_from_slice(&src[n - 16..]);
        }
        33..=128 => {
            // Pieces of 32 bytes, the last one overlapping: no call for a cell's text.
            let mut i = 0;
            while i + 32 < n {
                dst[i..i + 32].copy_from_slice(&src[i..i + 32]);
                i += 32;
            }
            dst[n - 32..].copy_from_slice(&src[n - 32..]);
        }
        _ => dst.copy_from_slice(src),
    }
}

/// `b` in every byte of a word.
pub(crate) const fn rep(b: u8) -> u64 {
    u64::from_le_bytes([b; 8])
}

const HIGH: u64 = rep(0x80);

/// Non-zero when some byte of `x` is zero. Exact as to whether one is (a borrow can mark a
/// byte above a zero byte, never a word without one).
#[inline(always)]
pub(crate) fn zero_byte(x: u64) -> u64 {
    x.wrapping_sub(rep(1)) & !x & HIGH
}

/// Whether `text` is ASCII without a byte that JSON strings escape (control characters, `"`,
/// `\\`): what [`W::json_spans`] needs.
#[inline]
pub(crate) fn json_plain(text: &str) -> bool {
    scan(text.as_bytes(), |x| {
        below_0x20(x) | zero_byte(x ^ rep(b'"')) | zero_byte(x ^ rep(b'\\')) | x & HIGH
    }) == 0
}

/// Non-zero when some byte of `x` is one a JSON string escapes (below 0x20, `"`, `\\`).
#[inline(always)]
pub(crate) fn json_escape(x: u64) -> u64 {
    below_0x20(x) | zero_byte(x ^ rep(b'"')) | zero_byte(x ^ rep(b'\\'))
}

/// Non-zero when some byte of `x` is below 0x20 (exact as to whether one is, as [`zero_byte`]).
#[inline(always)]
pub(crate) fn below_0x20(x: u64) -> u64 {
    x.wrapping_sub(rep(0x20)) & !x & HIGH
}

/// Non-zero when some byte of `x` is not printable ASCII (below 0x20, or 0x7F and above).
#[inline(always)]
pub(crate) fn not_printable(x: u64) -> u64 {
    // x + 1 sets a byte's high bit for 0x7F; bytes of 0x80 and above have it already (and the
    // carry out of an 0xFF byte only reaches bytes above one that is marked anyway).
    below_0x20(x) | x & HIGH | x.wrapping_add(rep(1)) & HIGH
}

/// ORs `test` over words that cover `s` (overlapping where `s` is not a multiple of eight
/// long; short slices padded with `A`, which no test marks): zero when no byte of `s` is
/// marked.
#[inline(always)]
pub(crate) fn scan(s: &[u8], test: impl Fn(u64) -> u64) -> u64 {
    let n = s.len();
    let word = |i: usize| u64::from_le_bytes(s[i..i + 8].try_into().unwrap_or([b'A'; 8]));
    let half = |i: usize| u32::from_le_bytes(s[i..i + 4].try_into().unwrap_or([b'A'; 4])) as u64;
    match n {
        0 => 0,
        1..=3 => {
            let x = (rep(b'A') & !0xFF_FFFF)
                | s[0] as u64
                | (s[n / 2] as u64) << 8
                | (s[n - 1] as u64) << 16;
            test(x)
        }
        4..=7 => test(half(0) | half(n - 4) << 32),
        8..=16 => test(word(0)) | test(word(n - 8)),
        _ => {
            // Sixteen bytes a step, as two words: the compiler tests them side by side.
            let mut acc = test(word(n - 16)) | test(word(n - 8));
            for c in s.chunks_exact(16) {
                let (a, b) = c.split_at(8);
                let a = u64::from_le_bytes(a.try_into().unwrap_or([b'A'; 8]));
                let b = u64::from_le_bytes(b.try_into().unwrap_or([b'A'; 8]));
                acc |= test(a) | test(b);
            }
            acc
        }
    }
}

/// A plain decimal JSON accepts as a number (`12`, `-1.50`, `0.5`; not `01`, `.5`, `1.`).
pub(crate) fn is_json_number(s: &[u8]) -> bool {
    let b = s.strip_prefix(b"-").unwrap_or(s);
    let (int, frac) = match b.iter().position(|&c| c == b'.') {
        Some(i) => (&b[..i], Some(&b[i + 1..])),
        None => (b, None),
    };
    let digits = |d: &[u8]| !d.is_empty() && d.iter().all(u8::is_ascii_digit);
    digits(int) && (int.len() == 1 || int[0] != b'0') && frac.is_none_or(digits)
}

#[cfg(test)]
mod tests;
