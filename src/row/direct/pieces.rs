//! The pieces of a cell written in place, between [`Cells::begin`] (or
//! [`Cells::begin_listed`]) and [`Cells::end`]: texts, plain ASCII, numbers, hex.

use super::*;

impl<F: Fmt> Cells<'_, '_, F> {
    /// [`Cells::begin`] for a cell known to hold a comma and otherwise nothing to quote or
    /// escape (a reading with its signed twin, `B5 (181, -75)`; a list of numbers): written with
    /// the pieces that keep a cell plain ([`Cells::put_ascii`], [`Cells::dec`], hex …) and
    /// [`Cells::put_listed`] for the ones with commas. CSV quotes such a cell: its opening quote
    /// is written now, so that the cell is not moved one byte on (from a copy) at its end, and a
    /// number marked in it is read from the line; the other formats write it as a plain cell.
    /// Debug builds check that it does hold a comma (else CSV would quote it needlessly).
    #[inline(always)]
    pub fn begin_listed(&mut self) {
        self.begin();
        self.listed = true;
        if F::FORMAT == Format::Csv {
            self.p.line.byte(b'"');
            self.cell.0 = self.p.line.len();
        }
    }

    /// In place, in a cell begun with [`Cells::begin_listed`]: bytes plain as
    /// [`Cells::put_ascii`] takes them, or commas.
    #[inline(always)]
    pub fn put_listed(&mut self, b: &[u8]) {
        debug_assert!(self.listed, "put_listed outside begin_listed");
        debug_assert!(
            b.iter().all(|&c| is_plain(c) || c == b','),
            "put_listed: {b:?}"
        );
        self.p.line.put(b);
    }

    /// Where the line is now (to mark a number: [`Mark::new`]).
    #[inline(always)]
    pub fn here(&self) -> u32 {
        self.p.line.len() as u32
    }

    /// In place: a text.
    #[inline(always)]
    pub fn str(&mut self, s: &str) {
        self.plain = false;
        self.p.line.put(s.as_bytes());
    }

    /// In place: bytes known to be plain ASCII, printable (blanks included) and none of
    /// `,` `"` `\` (a text built from tables of digits, letters, blanks, signs), as
    /// [`Cells::str`] writes them, without the check for UTF-8 a `&str` made of them costs;
    /// and a cell of such pieces and numbers is not looked at again for what TSV, CSV or JSON
    /// quote or escape. Debug builds check that the bytes are plain.
    #[inline(always)]
    pub fn put_ascii(&mut self, b: &[u8]) {
        debug_assert!(b.iter().all(|&c| is_plain(c)), "put_ascii: {b:?}");
        self.p.line.put(b);
    }

    /// In place: a text of characters that are not controls, with none of the ASCII bytes
    /// [`Cells::put_ascii`] refuses (`" …"`, `"µs"`): the cell stays plain, not looked at
    /// again in any format (TSV, CSV and JSON write such characters as they are; pretty text
    /// counts a cell's width in characters). For texts fixed in the program, not
    /// for text from the wire or from the user. Debug builds check the text.
    #[inline(always)]
    pub fn put_glyphs(&mut self, s: &str) {
        debug_assert!(
            s.chars().all(|c| if c.is_ascii() {
                is_plain(c as u8)
            } else {
                !c.is_control()
            }),
            "put_glyphs: {s:?}"
        );
        // Bytes beyond the first of each character: 0b10xx_xxxx continuation bytes.
        self.wide += s.bytes().filter(|&b| b & 0xC0 == 0x80).count();
        self.p.line.put(s.as_bytes());
    }

    /// In place: an ASCII byte (a byte of 0x80 or more is written as `?`).
    #[inline(always)]
    pub fn ascii(&mut self, b: u8) {
        self.plain = false;
        self.p.line.byte(if b < 0x80 { b } else { b'?' });
    }

    /// In place: an integer in decimal.
    #[inline(always)]
    pub fn dec(&mut self, n: u64) {
        self.p.line.dec(n);
    }

    /// In place: a signed integer in decimal.
    #[inline(always)]
    pub fn dec_i(&mut self, n: i64) {
        if n < 0 {
            self.p.line.byte(b'-');
        }
        self.p.line.dec(n.unsigned_abs());
    }

    /// In place: `raw / 10^prec` as [`crate::fmt::push_fixed`] writes it (`6543, 2` →
    /// `65.43`).
    #[inline(always)]
    pub fn fixed(&mut self, raw: i64, prec: u8) {
        self.p.line.fixed(raw, prec);
    }

    /// In place: a byte as two upper-case hex digits.
    #[inline(always)]
    pub fn hex2(&mut self, b: u8) {
        self.p.line.hex2(b);
    }

    /// In place: bytes as upper-case hex pairs with a blank between them (`7E 1A 10`).
    #[inline(always)]
    pub fn hex_bytes(&mut self, b: &[u8]) {
        self.p.line.hex_bytes(b);
    }
}
