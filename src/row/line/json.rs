//! The JSON Lines writers of [`W`]: strings and their escapes, numbers kept as numbers, a
//! row's `parts` member by member or a whole list at once.

use super::*;

impl W<'_> {
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
    pub(super) fn json_bytes(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            self.put(b"null");
            return;
        }
        self.byte(b'"');
        self.json_escaped(bytes);
        self.byte(b'"');
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

    /// A member of `parts` from its kept key ([`PartKeys::get`](crate::row::part_keys::PartKeys::get), `k` bytes long: `,"name":`)
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
        let pos = self.pos;
        let n = marks.len();
        if n == 0 {
            return true;
        }
        if n > N {
            return false;
        }
        let Some(mut at) = self.keys_begin(first, n) else {
            return false;
        };
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
        self.keys_end(first, at);
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
        let n = texts.len();
        if n == 0 {
            return true;
        }
        if n > N || texts.iter().any(|t| t.len() > 32) {
            return false;
        }
        let Some(mut at) = self.keys_begin(first, n) else {
            return false;
        };
        for ((key, &k), t) in keys.iter().zip(lens).zip(texts) {
            self.buf[at..at + 16].copy_from_slice(key);
            let k = usize::from(k).min(16);
            copy(&mut self.buf[at + k..at + k + 32], t.as_bytes());
            at += k + t.len();
        }
        self.keys_end(first, at);
        true
    }

    /// Room for `n` members of kept keys (16 bytes) and numbers (32) at most, written by
    /// fixed-size copies: where the first key goes (after `,"parts":{` when `first`, the key's
    /// comma over its `{`), or `None` when the room is short.
    #[inline(always)]
    fn keys_begin(&mut self, first: bool, n: usize) -> Option<usize> {
        const PARTS: &[u8; 16] = b",\"parts\":{\0\0\0\0\0\0";
        let pos = self.pos;
        if pos + 9 + 48 * n > self.buf.len() {
            return None;
        }
        if first {
            self.buf[pos..pos + 16].copy_from_slice(PARTS);
            return Some(pos + 9);
        }
        Some(pos)
    }

    /// The members from [`W::keys_begin`] end at `at`: `parts`' `{` written again over the
    /// first key's comma when `first`.
    #[inline(always)]
    fn keys_end(&mut self, first: bool, at: usize) {
        if first {
            self.buf[self.pos + 9] = b'{';
        }
        self.pos = at;
    }

    #[cold]
    pub(super) fn json_key_slow(
        &mut self,
        first: bool,
        key: &[u8; 16],
        k: usize,
        a: usize,
        b: usize,
    ) {
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
    pub(super) fn json_member_slow(&mut self, pre: &[u8], name: &str, a: usize, b: usize) {
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
    pub(super) fn json_member(&mut self, i: usize, p: &Part<'_>) {
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
    pub(super) fn json_member_pieces(&mut self, i: usize, p: &Part<'_>) {
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
    pub(super) fn json_spans(&mut self, text: &str, spans: &[PartSpan]) {
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

    pub(super) fn json_escaped(&mut self, bytes: &[u8]) {
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
}
