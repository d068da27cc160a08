//! One output line, assembled before it is appended to the output buffer.
//!
//! The row writers put a row's cells into a [`Line`]: a buffer that is kept at its full length
//! (zeroed once, grown when a row needs more) with a write position, so that appending a cell
//! costs no capacity check per byte and no call for a short copy. A row is then appended to
//! the output in one copy. The checks for bytes that need escaping (control characters in TSV,
//! quotes in CSV and JSON, non-printable bytes in pretty output) look at eight bytes at a time
//! ([`scan`]); only a cell that has such a byte takes the byte-by-byte path, which produces
//! exactly what the byte-by-byte rules always produced.

use super::direct::Mark;
use super::{Part, PartSpan, Parts};

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

    /// Ends a JSON cell written in place since `at`: a string (`null` when empty; its
    /// opening quote before `at`) with what needs escaping escaped, or with `numeric` a number
    /// as it is when it is one (else a string); as [`W::json_str`] and the table's numeric
    /// extra columns write it. A cell written again from a copy in `scratch` gives its first
    /// text's start and length.
    #[inline(always)]
    pub fn json_fix(
        &mut self,
        at: usize,
        numeric: bool,
        scratch: &mut Vec<u8>,
    ) -> Option<(u32, u32)> {
        let cell = self.buf.get(at..self.pos).unwrap_or_default();
        if numeric {
            if is_json_number(cell) {
                return None;
            }
            return self.rewrite(at, scratch, |w, text| w.json_bytes(text));
        }
        if cell.is_empty() {
            self.pos = at.saturating_sub(1);
            self.put(b"null");
            return None;
        }
        let rewritten = if scan(cell, |x| {
            below_0x20(x) | zero_byte(x ^ rep(b'"')) | zero_byte(x ^ rep(b'\\'))
        }) != 0
        {
            self.rewrite(at, scratch, |w, text| w.json_escaped(text))
        } else {
            None
        };
        self.byte(b'"');
        rewritten
    }

    /// `bytes` (UTF-8) as a JSON string, or `null` when empty (as [`W::json_str`]).
    fn json_bytes(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            self.put(b"null");
            return;
        }
        self.byte(b'"');
        self.json_escaped(bytes);
        self.byte(b'"');
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

    /// A JSON string, or `null` for an empty cell.
    #[inline(always)]
    pub fn json_str(&mut self, s: &str) {
        if s.is_empty() {
            self.put(b"null");
            return;
        }
        let bytes = s.as_bytes();
        self.byte(b'"');
        let at = self.pos;
        if self.put_scan(bytes, |x| {
            below_0x20(x) | zero_byte(x ^ rep(b'"')) | zero_byte(x ^ rep(b'\\'))
        }) != 0
        {
            // Written again, escaped.
            self.pos = at;
            self.aside(|w| w.json_escaped(bytes));
        }
        self.byte(b'"');
    }

    /// A member of a JSON object after `pre` (`,` or `,"parts":{`): `name` as a JSON string
    /// (as [`W::json_str`]), `:`, and the line's own bytes `a..b` (a number written before in
    /// the line) again. Usually one bounds check and fixed-size copies: when the name is
    /// short and needs no escaping, the number is short and the room is wide enough.
    #[inline(always)]
    pub fn json_member_within(&mut self, pre: &[u8], name: &str, a: usize, b: usize) {
        let nb = name.as_bytes();
        let k = pre.len() + nb.len() + 3;
        if !nb.is_empty()
            && nb.len() <= 16
            && pre.len() <= 12
            && a <= b
            && b - a <= 32
            && b <= self.pos
            && self.pos + 64 <= self.buf.len()
        {
            // The number and what follows it, copied whole (`a + 32 <= pos + 32`, in the
            // buffer; the bytes after it are written over later, or lie beyond the line).
            let mut num = [0u8; 32];
            num.copy_from_slice(&self.buf[a..a + 32]);
            let room = &mut self.buf[self.pos..self.pos + 64];
            copy(room, pre);
            room[pre.len()] = b'"';
            if copy_test(&mut room[pre.len() + 1..], nb, json_escape) != 0 {
                // A name to escape: the piece-by-piece way (over what was written here).
                return self.json_member_slow(pre, name, a, b);
            }
            room[k - 2] = b'"';
            room[k - 1] = b':';
            room[k..k + 32].copy_from_slice(&num);
            self.pos += k + (b - a);
            return;
        }
        self.json_member_slow(pre, name, a, b);
    }

    /// A member of `parts` from its kept key ([`super::part_keys::PartKeys::get`], `k` bytes long: `,"name":`)
    /// and the line's own bytes `a..b` (a number written before in the line): after
    /// `,"parts":{` instead of the key's comma when `first`. As [`W::json_member_within`]
    /// writes it; usually one bounds check and fixed-size copies.
    #[inline(always)]
    pub fn json_key_within(&mut self, first: bool, key: &[u8; 16], k: usize, a: usize, b: usize) {
        const PARTS: &[u8; 16] = b",\"parts\":{\0\0\0\0\0\0";
        if a <= b && b - a <= 32 && b <= self.pos && self.pos + 9 + 16 + 32 <= self.buf.len() {
            // The number and what follows it, copied whole (`a + 32 <= pos + 32`, in the
            // buffer; the bytes after it are written over later, or lie beyond the line).
            let mut num = [0u8; 32];
            num.copy_from_slice(&self.buf[a..a + 32]);
            let mut at = self.pos;
            if first {
                self.buf[at..at + 16].copy_from_slice(PARTS);
                at += 9;
            }
            self.buf[at..at + 16].copy_from_slice(key);
            if first {
                self.buf[at] = b'{';
            }
            let k = k.min(16);
            self.buf[at + k..at + k + 32].copy_from_slice(&num);
            self.pos = at + k + (b - a);
            return;
        }
        self.json_key_slow(first, key, k, a, b);
    }

    /// Members of `parts` from kept keys (`keys[i]`, `lens[i]` bytes of it: `,"name":`) and
    /// the line's own bytes `marks[i]` (numbers written before in the line), after
    /// `,"parts":{` instead of the first key's comma when `first`: what [`W::json_key_within`]
    /// writes for each, with one room check for them all. `false`, and nothing written, when
    /// the room or a mark does not allow its fixed-size copies.
    #[inline(always)]
    pub fn json_keys_within<const N: usize>(
        &mut self,
        first: bool,
        keys: &[[u8; 16]; N],
        lens: &[u8; N],
        marks: &[Mark],
    ) -> bool {
        const PARTS: &[u8; 16] = b",\"parts\":{\0\0\0\0\0\0";
        let pos = self.pos;
        let n = marks.len();
        if n == 0 {
            return true;
        }
        if n > N || pos + 9 + 48 * n > self.buf.len() {
            return false;
        }
        let mut at = pos;
        if first {
            self.buf[at..at + 16].copy_from_slice(PARTS);
            at += 9;
        }
        for (i, m) in marks.iter().enumerate().take(N) {
            let (a, b) = (m.start as usize, m.end as usize);
            // (`a > b` wraps to more than 32.)
            if (b.wrapping_sub(a) > 32) | (b > pos) {
                return false;
            }
            let (key, k) = (&keys[i], lens[i]);
            // The number and what follows it, copied whole (`a + 32 <= pos + 32`, in the
            // buffer; the bytes after it are written over by the next key, or lie beyond
            // the line). Read before the key is written: it may cover the number's tail.
            let mut num = [0u8; 32];
            num.copy_from_slice(&self.buf[a..a + 32]);
            self.buf[at..at + 16].copy_from_slice(key);
            let k = usize::from(k).min(16);
            self.buf[at + k..at + k + 32].copy_from_slice(&num);
            at += k + (b - a);
        }
        if first {
            self.buf[pos + 9] = b'{';
        }
        self.pos = at;
        true
    }

    /// Members of `parts` from kept keys (as [`W::json_keys_within`]) and their numbers'
    /// texts: with one room check for them all. `false`, and nothing written, when the room
    /// or a text's length (more than 32 bytes) does not allow it.
    #[inline(always)]
    pub fn json_keys_text<const N: usize>(
        &mut self,
        first: bool,
        keys: &[[u8; 16]; N],
        lens: &[u8; N],
        texts: &[&str],
    ) -> bool {
        const PARTS: &[u8; 16] = b",\"parts\":{\0\0\0\0\0\0";
        let pos = self.pos;
        let n = texts.len();
        if n == 0 {
            return true;
        }
        if n > N || pos + 9 + 48 * n > self.buf.len() || texts.iter().any(|t| t.len() > 32) {
            return false;
        }
        let mut at = pos;
        if first {
            self.buf[at..at + 16].copy_from_slice(PARTS);
            at += 9;
        }
        for ((key, &k), t) in keys.iter().zip(lens).zip(texts) {
            self.buf[at..at + 16].copy_from_slice(key);
            let k = usize::from(k).min(16);
            copy(&mut self.buf[at + k..at + k + 32], t.as_bytes());
            at += k + t.len();
        }
        if first {
            self.buf[pos + 9] = b'{';
        }
        self.pos = at;
        true
    }

    #[cold]
    fn json_key_slow(&mut self, first: bool, key: &[u8; 16], k: usize, a: usize, b: usize) {
        let key = key.get(..k).unwrap_or(key);
        if first {
            self.put(b",\"parts\":{");
            self.put(key.get(1..).unwrap_or_default());
        } else {
            self.put(key);
        }
        self.copy_within(a, b);
    }

    /// A member of `parts` from its kept key (as [`W::json_key_within`]) and its number's
    /// text.
    #[inline(always)]
    pub fn json_key_text(&mut self, first: bool, key: &[u8; 16], k: usize, text: &[u8]) {
        if first {
            self.put(b",\"parts\":{");
            self.put(key.get(1..k).unwrap_or_default());
        } else {
            self.put_prefix(key, k);
        }
        self.put(text);
    }

    /// [`W::json_member_within`] piece by piece.
    #[cold]
    fn json_member_slow(&mut self, pre: &[u8], name: &str, a: usize, b: usize) {
        self.put(pre);
        self.json_str(name);
        self.byte(b':');
        self.copy_within(a, b);
    }

    /// `key` as it is, then `s` as [`W::json_str`] writes it: for a short key and text with
    /// nothing to escape, one room check and fixed-size copies.
    #[inline(always)]
    pub fn json_key_str(&mut self, key: &[u8], s: &str) {
        let sb = s.as_bytes();
        let (k, n) = (key.len(), sb.len());
        if k <= 16 && n <= 16 && self.pos + 48 <= self.buf.len() {
            let room = &mut self.buf[self.pos..self.pos + 48];
            copy(room, key);
            if n == 0 {
                room[k..k + 4].copy_from_slice(b"null");
                self.pos += k + 4;
                return;
            }
            room[k] = b'"';
            if copy_test(&mut room[k + 1..], sb, json_escape) == 0 {
                room[k + 1 + n] = b'"';
                self.pos += k + n + 2;
                return;
            }
        }
        self.put(key);
        self.json_str(s);
    }

    /// A row's numbers as JSON (`,"parts":{"Cell1":3.918,…}`). Not inlined: the table
    /// writer's code for the rest of the row stays as it was.
    #[inline(never)]
    pub fn json_parts(&mut self, parts: Parts<'_>) {
        self.put(b",\"parts\":{");
        match parts {
            Parts::List(list) => {
                for (i, p) in list.iter().enumerate() {
                    self.json_member(i, p);
                }
            }
            // Names and numbers cut from one text with nothing to escape: copied.
            Parts::Spans { text, spans } if json_plain(text) => self.json_spans(text, spans),
            parts => {
                for (i, p) in parts.iter().enumerate() {
                    self.json_member(i, &p);
                }
            }
        }
        self.byte(b'}');
    }

    /// One member of `parts` (the `i`-th): its name as a JSON string, its number as it is.
    #[inline(always)]
    fn json_member(&mut self, i: usize, p: &Part<'_>) {
        let (nb, tb) = (p.name.as_bytes(), p.text.as_bytes());
        let (n, t) = (nb.len(), tb.len());
        if n > 0 && n <= 16 && t <= 32 && self.pos + 64 <= self.buf.len() {
            // Usually: one room check and short copies; a name to escape goes the way of
            // its pieces (over what was written here).
            let c = usize::from(i > 0);
            let room = &mut self.buf[self.pos..self.pos + 64];
            room[0] = b',';
            room[c] = b'"';
            if copy_test(&mut room[c + 1..], nb, json_escape) == 0 {
                room[c + 1 + n] = b'"';
                room[c + 2 + n] = b':';
                copy(&mut room[c + 3 + n..], tb);
                self.pos += c + 3 + n + t;
                return;
            }
        }
        self.json_member_pieces(i, p);
    }

    /// [`W::json_member`] piece by piece.
    #[inline(never)]
    fn json_member_pieces(&mut self, i: usize, p: &Part<'_>) {
        if i > 0 {
            self.byte(b',');
        }
        self.json_str(p.name);
        self.byte(b':');
        self.put(p.text.as_bytes());
    }

    /// The members for the `name=number` spans of `text` (see [`Parts::Spans`]): what
    /// [`W::json_member`] writes for each, when [`json_plain`] holds for `text` (then every
    /// byte offset is a character boundary, and no name needs escaping). A span outside the
    /// text gives empty strings, as [`Parts::get`] does.
    #[inline(always)]
    fn json_spans(&mut self, text: &str, spans: &[PartSpan]) {
        let t = text.as_bytes();
        let cut = |a: u32, b: u32| t.get(a as usize..b as usize).unwrap_or_default();
        for (i, s) in spans.iter().enumerate() {
            let name = cut(s.start, s.eq);
            let num = cut(s.eq.saturating_add(1), s.end);
            let (n, m) = (name.len(), num.len());
            if n > 0 && n <= 16 && m <= 32 && self.pos + 64 <= self.buf.len() {
                // Usually: one room check and short copies.
                let c = usize::from(i > 0);
                let room = &mut self.buf[self.pos..self.pos + 64];
                room[0] = b',';
                room[c] = b'"';
                copy(&mut room[c + 1..], name);
                room[c + 1 + n] = b'"';
                room[c + 2 + n] = b':';
                copy(&mut room[c + 3 + n..], num);
                self.pos += c + 3 + n + m;
                continue;
            }
            if i > 0 {
                self.byte(b',');
            }
            if name.is_empty() {
                self.put(b"null");
            } else {
                self.byte(b'"');
                self.put(name);
                self.byte(b'"');
            }
            self.byte(b':');
            self.put(cut(s.eq.saturating_add(1), s.end));
        }
    }

    fn json_escaped(&mut self, bytes: &[u8]) {
        const HEX: &[u8; 16] = b"0123456789abcdef";
        for &b in bytes {
            match b {
                b'"' => self.put(b"\\\""),
                b'\\' => self.put(b"\\\\"),
                b'\n' => self.put(b"\\n"),
                b'\r' => self.put(b"\\r"),
                b'\t' => self.put(b"\\t"),
                0..=0x1F => self.put(&[
                    b'\\',
                    b'u',
                    b'0',
                    b'0',
                    HEX[(b >> 4) as usize],
                    HEX[(b & 0xF) as usize],
                ]),
                _ => self.byte(b),
            }
        }
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
mod tests {
    use super::super::part_keys::PartKeys;
    use super::*;

    /// Every length up to 40 and every position of a marked byte: the word tests agree with
    /// the byte tests.
    #[test]
    fn scans_agree_with_byte_tests() {
        type WordTest<'a> = &'a dyn Fn(u64) -> u64;
        type ByteTest<'a> = &'a dyn Fn(u8) -> bool;
        let tests: [(WordTest<'_>, ByteTest<'_>); 4] = [
            (&below_0x20, &|b| b < 0x20),
            (&not_printable, &|b| !(0x20..0x7F).contains(&b)),
            (&|x| zero_byte(x ^ rep(b'"')), &|b| b == b'"'),
            (&|x| zero_byte(x ^ rep(b',')), &|b| b == b','),
        ];
        let specials = [
            0x00, 0x01, 0x09, 0x0A, 0x0D, 0x1F, 0x20, 0x21, 0x22, 0x2C, 0x5C, 0x7E, 0x7F, 0x80,
            0xC3, 0xFE, 0xFF,
        ];
        for (word_test, byte_test) in tests {
            for n in 0..40 {
                for &fill in &[b'a', b' ', b'~', 0x21, 0xFF, 0x80] {
                    let base = vec![fill; n];
                    assert_eq!(
                        scan(&base, word_test) != 0,
                        base.iter().any(|&b| byte_test(b)),
                        "n {n} fill {fill:#x}"
                    );
                    for at in 0..n {
                        for &sp in &specials {
                            let mut s = base.clone();
                            s[at] = sp;
                            assert_eq!(
                                scan(&s, word_test) != 0,
                                s.iter().any(|&b| byte_test(b)),
                                "n {n} at {at} byte {sp:#x} fill {fill:#x}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The spans' copy path writes what the member-by-member path writes, for texts with and
    /// without bytes to escape (quotes, backslashes, control characters, non-ASCII), empty
    /// names and numbers, and spans off the text or off its character boundaries.
    #[test]
    fn json_spans_write_what_each_member_writes() {
        let texts = [
            "R57=-859895076 R58=12 F3=0",
            "a=1",
            "=5 x= y=7",
            "q\"=1 b\\=2",
            "t\tab=3 n\nl=4",
            "caf\u{e9}=1 z=2",
            "",
        ];
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let mut next = |n: u32| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % u64::from(n)) as u32
        };
        for text in texts {
            let n = text.len() as u32;
            // the spans a writer records, then random ones, some off the text
            let mut lists: Vec<Vec<PartSpan>> = vec![
                text.split(' ')
                    .scan(0u32, |at, tok| {
                        let start = *at;
                        *at += tok.len() as u32 + 1;
                        let eq = start + tok.find('=').unwrap_or(tok.len()) as u32;
                        Some(PartSpan {
                            start,
                            eq,
                            end: start + tok.len() as u32,
                            value: 1.0,
                        })
                    })
                    .collect(),
            ];
            for _ in 0..200 {
                let k = next(5) as usize;
                lists.push(
                    (0..k)
                        .map(|_| {
                            let (a, b, c) = (next(n + 3), next(n + 3), next(n + 3));
                            let eq = if next(9) == 0 { u32::MAX } else { b };
                            PartSpan {
                                start: a,
                                eq,
                                end: c,
                                value: 0.0,
                            }
                        })
                        .collect(),
                );
            }
            for spans in &lists {
                let parts = Parts::Spans { text, spans };
                // The same members as a list: written as `Parts::List`.
                let list: Vec<Part<'_>> = parts.iter().collect();
                for room in [8, 30, 70] {
                    let line = |parts: Parts<'_>| {
                        let mut buf = vec![0; room];
                        let len = write_line(&mut buf, 0, |w| {
                            w.put(b"{\"data\":null");
                            w.json_parts(parts)
                        });
                        buf.truncate(len);
                        buf
                    };
                    let mut slow = vec![0; room];
                    let slow_len = write_line(&mut slow, 0, |w| {
                        w.put(b"{\"data\":null");
                        w.put(b",\"parts\":{");
                        for (i, p) in parts.iter().enumerate() {
                            w.json_member_pieces(i, &p);
                        }
                        w.byte(b'}');
                    });
                    let slow = &slow[..slow_len];
                    assert_eq!(line(parts), slow, "{text:?} {spans:?} {room}");
                    assert_eq!(line(Parts::List(&list)), slow, "{text:?} {spans:?} {room}");
                }
            }
        }
    }

    /// A member copied in one piece is what the piece-by-piece writes give: names short,
    /// long, empty or to escape, numbers short and long, near the end of the room or not.
    #[test]
    fn json_member_within_writes_what_each_piece_writes() {
        let names = [
            "CH1",
            "",
            "a\"b",
            "x\ty",
            "A_rather_long_name_of_a_part",
            "caf\u{e9}",
        ];
        let numbers = ["1", "-0.5", "1234567890123456789012345678901234567890"];
        for pre in [&b","[..], b",\"parts\":{"] {
            for name in names {
                for number in numbers {
                    for room in [8, 40, 70, 200] {
                        let write = |w: &mut W<'_>, fast: bool| {
                            w.put(b"{\"data\":");
                            let a = w.len();
                            w.put(number.as_bytes());
                            let b = w.len();
                            if fast {
                                w.json_member_within(pre, name, a, b);
                            } else {
                                w.put(pre);
                                w.json_str(name);
                                w.byte(b':');
                                w.put(number.as_bytes());
                            }
                        };
                        let mut fast = vec![0; room];
                        let n = write_line(&mut fast, 0, |w| write(w, true));
                        let mut slow = vec![0; room];
                        let m = write_line(&mut slow, 0, |w| write(w, false));
                        assert_eq!(&fast[..n], &slow[..m], "{name:?} {number:?} {room}");
                    }
                }
            }
        }
    }

    /// A row's members from a list's keys made by the compiler, with one room check: what
    /// [`W::json_key_within`] and [`W::json_key_text`] write member by member, first or not,
    /// for every count of members, numbers short and long (then nothing is written and the
    /// caller writes member by member), near the end of the room or not.
    #[test]
    fn listed_part_keys_write_what_each_member_writes() {
        use super::super::part_keys::PartNames;
        static NAMES: PartNames<4> = PartNames::new(["CH1", "FrameLost", "Bat%", "ABCDEFGHIJKL"]);
        let numbers = [
            ["1", "-0.5", "22", "3"],
            ["1500", "1", "-1234567.1234567", "0"],
            ["1", "1234567890123456789012345678901234567890", "2", "3"],
        ];
        for first in [true, false] {
            for number in numbers {
                for n in 0..=4 {
                    for room in [8, 40, 70, 150, 200, 260, 400] {
                        let write = |w: &mut W<'_>, fast: u8| {
                            w.put(b"{\"data\":\"");
                            let mut marks = [Mark::default(); 4];
                            for (i, num) in number.iter().enumerate() {
                                if i > 0 {
                                    w.byte(b' ');
                                }
                                let a = w.len() as u32;
                                w.put(num.as_bytes());
                                marks[i] = Mark::new(a, w.len() as u32);
                            }
                            w.byte(b'"');
                            let pieces = |w: &mut W<'_>| {
                                for (i, m) in marks[..n].iter().enumerate() {
                                    let (key, k) = (&NAMES.keys[i], usize::from(NAMES.lens[i]));
                                    if fast == 2 {
                                        let t = number[i].as_bytes();
                                        w.json_key_text(first && i == 0, key, k, t);
                                    } else {
                                        let (a, b) = (m.start as usize, m.end as usize);
                                        w.json_key_within(first && i == 0, key, k, a, b);
                                    }
                                }
                            };
                            match fast {
                                0 | 2 => pieces(w),
                                1 => {
                                    if !w.json_keys_within(
                                        first,
                                        &NAMES.keys,
                                        &NAMES.lens,
                                        &marks[..n],
                                    ) {
                                        pieces(w)
                                    }
                                }
                                _ => {
                                    if !w.json_keys_text(
                                        first,
                                        &NAMES.keys,
                                        &NAMES.lens,
                                        &number[..n],
                                    ) {
                                        pieces(w)
                                    }
                                }
                            }
                            w.put(b"}\n");
                        };
                        let line = |fast: u8| {
                            let mut buf = vec![0; room];
                            let len = write_line(&mut buf, 0, |w| write(w, fast));
                            buf.truncate(len);
                            String::from_utf8(buf).unwrap()
                        };
                        let want = line(0);
                        assert_eq!(line(1), want, "{first} {number:?} {n} {room}");
                        assert_eq!(line(2), want, "{first} {number:?} {n} {room}");
                        assert_eq!(line(3), want, "{first} {number:?} {n} {room}");
                    }
                }
            }
        }
    }

    /// A member from its kept key, first or not, and a member with its number's text: what
    /// [`W::json_member_within`] and the pieces write, for names kept or not (empty, long, to
    /// escape, the same text at another address), numbers short and long, near the end of the
    /// room or not.
    #[test]
    fn kept_part_keys_write_what_each_piece_writes() {
        let owned = String::from("CH1");
        let names = [
            "CH1",
            owned.as_str(),
            "",
            "a\"b",
            "x\ty",
            "A_rather_long_name_of_a_part",
            "ABCDEFGHIJKL",
            "ABCDEFGHIJKLM",
            "caf\u{e9}",
            "FrameLost",
            "Bat%",
        ];
        let numbers = ["1", "-0.5", "1234567890123456789012345678901234567890"];
        let mut keys = PartKeys::new();
        for round in 0..2 {
            for first in [true, false] {
                for name in names {
                    for number in numbers {
                        for room in [8, 40, 70, 200] {
                            let pre: &[u8] = if first { b",\"parts\":{" } else { b"," };
                            let key = keys.get(name).copied();
                            assert_eq!(
                                key.is_some(),
                                (1..=PartKeys::NAME).contains(&name.len())
                                    && !name.contains(['"', '\t']),
                                "{name:?}"
                            );
                            let write = |w: &mut W<'_>, fast: u8| {
                                w.put(b"{\"data\":");
                                let a = w.len();
                                w.put(number.as_bytes());
                                let b = w.len();
                                match (fast, key) {
                                    (1, Some(key)) => {
                                        w.json_key_within(first, &key, name.len() + 4, a, b)
                                    }
                                    (2, Some(key)) => w.json_key_text(
                                        first,
                                        &key,
                                        name.len() + 4,
                                        number.as_bytes(),
                                    ),
                                    (0, _) => w.json_member_within(pre, name, a, b),
                                    _ => {
                                        w.put(pre);
                                        w.json_str(name);
                                        w.byte(b':');
                                        w.put(number.as_bytes());
                                    }
                                }
                            };
                            let mut want = vec![0; room];
                            let m = write_line(&mut want, 0, |w| write(w, 3));
                            for fast in 0..3 {
                                let mut got = vec![0; room];
                                let n = write_line(&mut got, 0, |w| write(w, fast));
                                assert_eq!(
                                    &got[..n],
                                    &want[..m],
                                    "{round} {first} {name:?} {number:?} {room} {fast}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    /// A key and a string in one piece: what the key and [`W::json_str`] write.
    #[test]
    fn json_key_str_writes_what_each_piece_writes() {
        let keys: [&[u8]; 3] = [b",\"unit\":", b",\"a_rather_long_column_key\":", b""];
        let texts = [
            "",
            "us",
            "q\"",
            "t\tab",
            "sixteen_bytes_xx",
            "seventeen_bytes_x",
            "caf\u{e9}",
        ];
        for key in keys {
            for s in texts {
                for room in [4, 20, 60, 200] {
                    let mut fast = vec![0; room];
                    let n = write_line(&mut fast, 0, |w| w.json_key_str(key, s));
                    let mut slow = vec![0; room];
                    let m = write_line(&mut slow, 0, |w| {
                        w.put(key);
                        w.json_str(s);
                    });
                    assert_eq!(&fast[..n], &slow[..m], "{s:?} {room}");
                }
            }
        }
    }

    #[test]
    fn copies_every_length_up_to_the_call() {
        let src: Vec<u8> = (0..=255u8).collect();
        for n in 0..=140 {
            let mut dst = vec![0u8; 160];
            copy(&mut dst, &src[7..7 + n]);
            assert_eq!(&dst[..n], &src[7..7 + n], "{n} bytes");
            assert!(dst[n..].iter().all(|&b| b == 0), "{n} bytes: nothing after");
        }
    }

    #[test]
    fn copies_every_length_and_grows() {
        let mut buf = vec![0; ROOM];
        let src: Vec<u8> = (0..=255u8).cycle().take(3000).collect();
        let mut expected = Vec::new();
        for n in 0..70 {
            expected.extend_from_slice(&src[n..n * 2]);
        }
        expected.extend_from_slice(&src);
        expected.extend_from_slice(&[b' '; 150]);
        let mut tries = 0;
        let len = write_line(&mut buf, 0, |w| {
            tries += 1;
            for n in 0..70 {
                w.put(&src[n..n * 2]);
            }
            w.put(&src);
            w.spaces(150);
        });
        assert_eq!(&buf[..len], &expected[..]);
        // 5565 bytes: 1024 bytes of room at first, then 2048, 4096, 8192 (kept for the next
        // line).
        assert_eq!(tries, 4);
        assert_eq!(buf.len(), 8192);
        // After 5565 bytes kept, a line in the rest of the room.
        let n = write_line(&mut buf, len, |w| w.put(b"x"));
        assert_eq!(&buf[len..len + n], b"x");
    }

    /// A CSV field as the csv crate writes it (`QuoteStyle::Necessary`), whether written by
    /// [`W::csv`] or in place and quoted afterwards by [`W::csv_fix`] (in the line, or moved one
    /// byte on when it holds no quote), in every room the line starts with; `csv_fix` keeps the
    /// field's text for the marks.
    #[test]
    fn csv_fields_as_the_csv_crate_writes_them() {
        let fields: [&[u8]; 9] = [
            b"plain",
            b"",
            b"84 (132, -124)",
            b"a,\"b\"",
            b"\"",
            b"line\nbreak",
            b"cr\r",
            b"framing hdlc: SAB2 framing (0x7E flags, byte stuffing, CRC-16/MODBUS), forced",
            b",",
        ];
        for field in fields {
            let mut want = Vec::new();
            {
                let mut wr = csv::WriterBuilder::new().from_writer(&mut want);
                wr.write_record([field, b"x"]).unwrap();
            }
            let want = &want[..want.len() - 3];
            for room in 0..100 {
                let mut buf = vec![0; room];
                let len = write_line(&mut buf, 0, |w| {
                    w.byte(b'|');
                    w.csv(field);
                    w.byte(b'|');
                });
                assert_eq!(&buf[1..len - 1], want, "{field:?} in {room}");
                let mut buf = vec![0; room];
                let mut scratch = Vec::new();
                let mut kept = None;
                let len = write_line(&mut buf, 0, |w| {
                    w.byte(b'|');
                    let at = w.len();
                    w.put(field);
                    kept = w.csv_fix(at, &mut scratch);
                    w.byte(b'|');
                });
                assert_eq!(&buf[1..len - 1], want, "{field:?} in {room}");
                match kept {
                    Some((at, n)) => {
                        assert_eq!((at, &scratch[..n as usize]), (1, field), "{room}")
                    }
                    None => assert_eq!(want, field),
                }
            }
        }
    }

    #[test]
    fn fields_as_the_byte_rules_write_them() {
        let mut buf = vec![0; 4];
        let len = write_line(&mut buf, 0, |w| {
            w.tsv(b"a\tb\nc");
            w.byte(b'|');
            w.csv(b"plain");
            w.byte(b'|');
            w.csv(b"a,\"b\"");
            w.byte(b'|');
            w.csv(b"tab\tonly");
            w.byte(b'|');
            w.json_str("q\"\\\n\x01 \u{e9}");
            w.byte(b'|');
            w.json_str("");
            w.byte(b'|');
            w.dec(0);
            w.byte(b' ');
            w.dec(u64::MAX);
        });
        assert_eq!(
            std::str::from_utf8(&buf[..len]).unwrap(),
            "a b c|plain|\"a,\"\"b\"\"\"|tab\tonly|\"q\\\"\\\\\\n\\u0001 \u{e9}\"|null|0 18446744073709551615"
        );
    }
}
