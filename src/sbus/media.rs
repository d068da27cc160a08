//! Media lists in the Data cell (`R57=-859895076 R58=12`, `F135=0 F136=1`): written a block
//! at a time with the place of every number recorded ([`MediaSpans`]), so that the row's numbers
//! (`Row::parts`) need not be read back from the text; and read back from the text
//! ([`media_parts`]) where nothing was recorded.

use super::commands::{Elem, be, push_elem, push_value};
use crate::digits::put_u32;
use crate::row::{Cells, Fmt, Mark, Part};

/// Where the numbers of a Data cell that lists media values stand (`R0=1 R1=2`), recorded while
/// the cell is written so that the row's numbers (`Row::parts`) need not be read back from
/// the text. Only a list that is the whole cell is recorded.
#[derive(Clone, Debug, Default)]
pub(crate) struct MediaSpans {
    /// The cell's length when its list was written: the spans describe that text only.
    /// `None`: nothing recorded.
    pub len: Option<usize>,
    /// Each number of the list; empty when the list names no medium (`DB4000[2]=5`): the
    /// rule of the parts (`[RFIOTC][0-9]+=[+-]?[0-9]+` per token) then gives none.
    pub spans: Vec<MediaSpan>,
    /// The block the recorded lists are gathered in, kept from list to list (a list on the
    /// stack would clear its 512 bytes first).
    block: Box<Block>,
    /// Keep a list of words that is the whole cell as [`LazyWords`] instead of writing it
    /// (the row's scratch does: its row then writes the list straight into the table, or as
    /// text with [`MediaSpans::settle`] for any other reader).
    pub defer: bool,
    /// The list kept (see `defer`).
    pub lazy: Option<LazyWords>,
    /// The words of `lazy`, as received (4 bytes each).
    pub lazy_bytes: Vec<u8>,
    /// The block `lazy` is gathered in when written straight into the table (by a row that
    /// only reads the scratch).
    lazy_block: std::cell::RefCell<Box<Block>>,
}

/// A media list of words not written yet (`R57=-8 R58=12`): the medium's letter, the first
/// address, the sign bit of its values (see [`Words`]) and the number of words (in
/// [`MediaSpans::lazy_bytes`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct LazyWords {
    letter: u8,
    addr: u32,
    sign_bit: u32,
    pub count: u32,
    /// The Sensor # cell is the list's first name (`R57`), kept here too.
    pub name: bool,
    /// Not a list but the range of a read (`R57..R63`, `count` elements; it names no number).
    pub range: bool,
}

impl LazyWords {
    /// The range of a read of `count` elements of the medium `letter` from `addr`, and its
    /// first name as the Sensor # cell (what `push_name_and_range` writes).
    pub(super) fn range(letter: u8, addr: u32, count: u32) -> Self {
        LazyWords {
            letter,
            addr,
            sign_bit: 0,
            count,
            name: true,
            range: true,
        }
    }
}

/// One `name=number` of a media list: byte offsets in the Data cell.
pub(crate) use crate::row::PartSpan as MediaSpan;

impl MediaSpans {
    pub fn clear(&mut self) {
        self.len = None;
        self.spans.clear();
        self.lazy = None;
    }

    /// The list kept in `lazy` written into `out` (which is empty), recorded, as
    /// [`push_words`] writes it when nothing is deferred.
    pub(super) fn settle(&mut self, sensor_no: &mut String, out: &mut String) {
        let Some(l) = self.lazy.take() else {
            return;
        };
        debug_assert!(out.is_empty(), "a deferred list is the whole cell");
        if l.range {
            let mut buf = RangeText([0; 32]);
            let (text, first) = media_range(&mut buf, l.letter, l.addr, l.count);
            out.push_str(text);
            sensor_no.push_str(text.get(..first).unwrap_or_default());
            self.clear();
            self.len = Some(out.len());
            return;
        }
        if l.name {
            let mut buf = RangeText([0; 32]);
            sensor_no.push_str(media_range(&mut buf, l.letter, l.addr, 1).0);
        }
        let bytes = std::mem::take(&mut self.lazy_bytes);
        let words = bytes
            .chunks_exact(4)
            .map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]));
        let text = Words {
            sign_bit: l.sign_bit,
        };
        let media = MediaSpans::begin(Some(self), out);
        write_recorded(out, media, l.letter, l.addr, words, text);
        self.lazy_bytes = bytes;
    }

    /// Recording for a list written into `out`: only when the list is the whole cell.
    pub(super) fn begin<'m>(
        media: Option<&'m mut MediaSpans>,
        out: &str,
    ) -> Option<&'m mut MediaSpans> {
        let m = media.filter(|_| out.is_empty())?;
        m.clear();
        Some(m)
    }
}

/// The media [`medium_letter`] names (for tests that go through all of them).
#[cfg(test)]
pub(super) const LETTERED: [Elem; 6] = [
    Elem::Register,
    Elem::Flag,
    Elem::Input,
    Elem::Output,
    Elem::Timer,
    Elem::Counter,
];

/// The letter of the media whose element names are that letter and a decimal address (`R`,
/// `F`, `I`, `O`, `T`, `C`): the ones a row's numbers are named after.
pub(super) fn medium_letter(elem: Elem) -> Option<u8> {
    match elem {
        Elem::Register => Some(b'R'),
        Elem::Flag => Some(b'F'),
        Elem::Input => Some(b'I'),
        Elem::Output => Some(b'O'),
        Elem::Timer => Some(b'T'),
        Elem::Counter => Some(b'C'),
        _ => None,
    }
}

pub(super) fn push_words(
    out: &mut String,
    elem: Elem,
    block: u16,
    addr: u32,
    data: &[u8],
    media: Option<&mut MediaSpans>,
) -> usize {
    let media = MediaSpans::begin(media, out);
    let Some(letter) = medium_letter(elem) else {
        // Data-block, byte and other elements: named by the general path, never recorded.
        for (i, w) in data.chunks_exact(4).enumerate() {
            if i > 0 {
                out.push(' ');
            }
            push_elem(out, elem, block, addr.wrapping_add(i as u32));
            out.push('=');
            push_value(out, elem, be(w));
        }
        if let Some(m) = media {
            m.len = Some(out.len());
        }
        return 0;
    };
    // the bit that makes a value negative: the sign bit of an `i32`, none for unsigned media
    let sign_bit = if elem.is_unsigned() { 0 } else { 1 << 31 };
    let media = match media {
        Some(m) if m.defer && data.len() >= 4 => {
            let whole = data.len() / 4 * 4;
            m.lazy_bytes.clear();
            m.lazy_bytes.extend_from_slice(&data[..whole]);
            m.lazy = Some(LazyWords {
                letter,
                addr,
                sign_bit,
                count: (whole / 4) as u32,
                name: false,
                range: false,
            });
            return 0;
        }
        media => media,
    };
    let words = data
        .chunks_exact(4)
        .map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]));
    write_recorded(out, media, letter, addr, words, Words { sign_bit })
}

/// How a list writes each value's text: it returns the text's length and the number.
trait ValueText {
    fn text(&self, v: u32, w: &mut [u8; VALUE_ROOM]) -> (usize, f64);
}

/// A word's value, negative when `sign_bit` is set in it (0 for unsigned media).
struct Words {
    sign_bit: u32,
}

impl ValueText for Words {
    #[inline(always)]
    fn text(&self, v: u32, w: &mut [u8; VALUE_ROOM]) -> (usize, f64) {
        let neg = v & self.sign_bit != 0;
        // |v as i32| (2^31 for i32::MIN)
        let magnitude = if neg { v.wrapping_neg() } else { v };
        // `-` is written before every number and kept only when the number is negative.
        w[0] = b'-';
        let k = usize::from(neg);
        let n = k + put_u32(&mut w[k..], magnitude);
        let value = f64::from(magnitude);
        (n, if neg { -value } else { value })
    }
}

/// A bit's value, 0 or 1.
struct Bits;

impl ValueText for Bits {
    #[inline(always)]
    fn text(&self, bit: u32, w: &mut [u8; VALUE_ROOM]) -> (usize, f64) {
        w[0] = b'0' + bit as u8;
        (1, bit as f64)
    }
}

/// `F0=1 F1=0 …`: element 0 is bit 0 of the first byte.
pub(super) fn push_bits(
    out: &mut String,
    elem: Elem,
    addr: u32,
    bits: u32,
    data: &[u8],
    media: Option<&mut MediaSpans>,
) -> usize {
    let media = MediaSpans::begin(media, out);
    let n = bits.min(data.len() as u32 * 8);
    let Some(letter) = medium_letter(elem) else {
        for i in 0..n {
            if i > 0 {
                out.push(' ');
            }
            push_elem(out, elem, 0, addr.wrapping_add(i));
            let bit = data[(i / 8) as usize] >> (i % 8) & 1;
            out.push('=');
            out.push(if bit == 1 { '1' } else { '0' });
        }
        if let Some(m) = media {
            m.len = Some(out.len());
        }
        return 0;
    };
    let bits = (0..n).map(|i| u32::from(data[(i / 8) as usize] >> (i % 8) & 1));
    write_recorded(out, media, letter, addr, bits, Bits)
}

/// [`write_list`] recording into `media` (in its block), or into nothing (in a block of its
/// own) when there is nothing to record.
#[inline(always)]
fn write_recorded(
    out: &mut String,
    media: Option<&mut MediaSpans>,
    letter: u8,
    addr: u32,
    values: impl Iterator<Item = u32>,
    text: impl ValueText,
) -> usize {
    match media {
        Some(m) => {
            let names = Names::new(letter, addr);
            let first = write_list(out, &mut m.block, names, values, &mut m.spans, text);
            m.len = Some(out.len());
            first
        }
        None => write_list(
            out,
            &mut Block::default(),
            Names::new(letter, addr),
            values,
            Unrecorded,
            text,
        ),
    }
}

/// Where the numbers of a list go as they are written: into [`MediaSpans::spans`] or nowhere
/// (a type per choice, so that the list's loop asks nothing per element).
trait Record {
    /// One number written at `base + span` (its `=` at `base + eq`).
    fn record(&mut self, base: usize, span: std::ops::Range<usize>, eq: usize, value: f64);
}

impl Record for &mut Vec<MediaSpan> {
    #[inline(always)]
    fn record(&mut self, base: usize, span: std::ops::Range<usize>, eq: usize, value: f64) {
        let at = base as u32;
        self.push(MediaSpan {
            start: at + span.start as u32,
            eq: at + eq as u32,
            end: at + span.end as u32,
            value,
        });
    }
}

/// Nothing recorded (a list after other text, or a caller that wants no parts).
struct Unrecorded;

impl Record for Unrecorded {
    #[inline(always)]
    fn record(&mut self, _: usize, _: std::ops::Range<usize>, _: usize, _: f64) {}
}

/// Writes the list `R57=v0 R58=v1 …` (the medium's `letter`, addresses counted up from
/// `addr`, wrapping like `u32::wrapping_add`) with each value's `text` (it returns the text's
/// length and the number), recording every number in `rec`. Returns the length of the first
/// name (`R57`: 3), or 0 for an empty list.
///
/// Every element is written with the blank before it (`" R58=…"`, a copy of [`Names`]'s text);
/// the first element's blank is then left out of the cell ([`ListText`] starts past it).
#[inline(always)]
fn write_list<R: Record, O: ListOut>(
    out: &mut O,
    block: &mut Block,
    mut names: Names,
    values: impl Iterator<Item = u32>,
    mut rec: R,
    text: impl ValueText,
) -> usize {
    let mut list = ListText::new(out, block);
    let was = list.out.len();
    let first = names.len - 2;
    for v in values {
        let (at, p, w) = list.room();
        w[..NAME_ROOM].copy_from_slice(&names.text);
        // in `w`: the blank, the name, `=` at `eq`, the value
        let eq = names.len - 1;
        let value_at: &mut [u8; VALUE_ROOM] = (&mut w[eq + 1..eq + 1 + VALUE_ROOM])
            .try_into()
            .expect("VALUE_ROOM bytes");
        let (n, value) = text.text(v, value_at);
        let end = eq + 1 + n;
        list.n = p + end;
        rec.record(at, 0..end - 1, eq - 1, value);
        names.step();
    }
    list.flush();
    if list.out.len() > was { first } else { 0 }
}

/// Room of an element's name text: a blank, the letter, 10 address digits and `=` (13), copied
/// as 16 bytes.
const NAME_ROOM: usize = 16;
/// Room a value's text may use ([`put_u32`] may write up to 10 bytes, a sign before them).
const VALUE_ROOM: usize = 12;
/// Room a list element needs at most: the name's copy, or the name (13) and the value.
const ELEM_ROOM: usize = 32;
const _: () = assert!(NAME_ROOM <= ELEM_ROOM && 13 + VALUE_ROOM <= ELEM_ROOM);
/// The stack block a list is gathered in before it is appended to the cell.
const LIST_BLOCK: usize = 512;

/// A media list's text (`R0=1 R1=-2`), gathered in a block and appended to the cell one
/// block at a time: one copy and one ASCII check per block instead of a push per name, number
/// and separator. Everything written into it is ASCII.
struct ListText<'o, O: ListOut> {
    out: &'o mut O,
    buf: &'o mut Block,
    /// Where the block's text starts: [`FIRST`] in the first block (past the first element's
    /// blank, which is not part of the cell), then 0.
    from: usize,
    /// Bytes of `buf` in use.
    n: usize,
}

/// The list's block, aligned so that the text appended from it starts at a word boundary:
/// `str::from_utf8` checks ASCII a word at a time from there, and byte by byte before it.
/// A list reads only what it wrote: the bytes a block starts with do not matter.
#[derive(Clone, Debug)]
#[repr(align(16))]
struct Block([u8; LIST_BLOCK]);

impl Default for Block {
    fn default() -> Self {
        Block([0; LIST_BLOCK])
    }
}

/// Where the first block's text starts: the first element's blank stands just before it.
const FIRST: usize = 8;

impl<'o, O: ListOut> ListText<'o, O> {
    fn new(out: &'o mut O, buf: &'o mut Block) -> Self {
        ListText {
            out,
            buf,
            from: FIRST,
            n: FIRST - 1,
        }
    }

    /// Room for one element (its blank, name and value): where the name (`buf[p + 1]`) will
    /// stand in the cell, `p`, and the bytes from there (the caller sets `n` past what it
    /// wrote). Appends the block first when the room is not there.
    #[inline(always)]
    fn room(&mut self) -> (usize, usize, &mut [u8; ELEM_ROOM]) {
        if self.n > LIST_BLOCK - ELEM_ROOM {
            self.flush();
        }
        let p = self.n;
        let at = self.out.len() + p + 1 - self.from;
        let w: &mut [u8; ELEM_ROOM] = (&mut self.buf.0[p..p + ELEM_ROOM])
            .try_into()
            .expect("ELEM_ROOM bytes");
        (at, p, w)
    }

    fn flush(&mut self) {
        let from = self.buf.0.get(self.from..).unwrap_or_default();
        self.out.put_block(from, self.n.saturating_sub(self.from));
        self.from = 0;
        self.n = 0;
    }
}

/// Where a list's text goes: a cell's text, or a cell written in place in the table.
trait ListOut {
    /// The length written so far (where the next byte goes).
    fn len(&self) -> usize;
    /// Appends the first `len` bytes of `block` (ASCII).
    fn put_block(&mut self, block: &[u8], len: usize);
}

impl ListOut for String {
    #[inline(always)]
    fn len(&self) -> usize {
        String::len(self)
    }

    #[inline(always)]
    fn put_block(&mut self, block: &[u8], len: usize) {
        self.push_str(ascii_text(block, len));
    }
}

impl<F: Fmt> ListOut for Cells<'_, '_, F> {
    #[inline(always)]
    fn len(&self) -> usize {
        self.here() as usize
    }

    #[inline(always)]
    fn put_block(&mut self, block: &[u8], len: usize) {
        self.put_ascii(block.get(..len).unwrap_or(block));
    }
}

/// Only the first number of a list, as a mark of its text in the line.
struct FirstMark(Option<Mark>);

impl Record for &mut FirstMark {
    #[inline(always)]
    fn record(&mut self, base: usize, span: std::ops::Range<usize>, eq: usize, _: f64) {
        if self.0.is_none() {
            self.0 = Some(Mark::new((base + eq + 1) as u32, (base + span.end) as u32));
        }
    }
}

impl MediaSpans {
    /// Writes the list kept as `l` (see `lazy`) into the cell `c` is writing in place
    /// (between [`Cells::begin`] and [`Cells::end`]): the same text as
    /// [`MediaSpans::settle`]; `name` is `l`'s [`LazyWords::first_name`]. Returns the marks of
    /// its first number and of the whole list.
    #[inline]
    pub(super) fn write_lazy<F: Fmt>(
        &self,
        l: &LazyWords,
        name: &FirstName,
        c: &mut Cells<'_, '_, F>,
    ) -> (Option<Mark>, Mark) {
        let start = c.here();
        if l.range {
            c.put_ascii(name.text());
            return (None, Mark::new(start, c.here()));
        }
        let words = self
            .lazy_bytes
            .chunks_exact(4)
            .map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]));
        let mut first = FirstMark(None);
        let text = Words {
            sign_bit: l.sign_bit,
        };
        let names = Names::of_first(name, l.letter, l.addr);
        match self.lazy_block.try_borrow_mut() {
            Ok(mut block) => {
                write_list(c, &mut block, names, words, &mut first, text);
            }
            Err(_) => {
                let mut block = Block::default();
                write_list(c, &mut block, names, words, &mut first, text);
            }
        }
        (first.0, Mark::new(start, c.here()))
    }
}

/// The first name of a deferred list (`R57`), or the whole range of a read (`R57..R63`),
/// formatted once for both cells that show it (Sensor # and Data).
pub(super) struct FirstName {
    buf: RangeText,
    /// The length of the range (of the name, for a list).
    n: usize,
    /// The length of the first name.
    first: usize,
}

impl FirstName {
    /// The range (the first name, for a list).
    fn text(&self) -> &[u8] {
        self.buf.0.get(..self.n).unwrap_or_default()
    }

    /// The first name.
    fn first(&self) -> &[u8] {
        self.buf.0.get(..self.first).unwrap_or_default()
    }
}

impl LazyWords {
    /// The list's first name, or the range: see [`FirstName`].
    #[inline(always)]
    pub(super) fn first_name(&self) -> FirstName {
        let mut buf = RangeText([0; 32]);
        let count = if self.range { self.count } else { 1 };
        let (n, first) = range_bytes(&mut buf, self.letter, self.addr, count);
        FirstName { buf, n, first }
    }

    /// The Sensor # cell when it is the list's first name ([`LazyWords::name`]; `name` is
    /// [`LazyWords::first_name`]), written straight into the table; else `sensor_no`.
    #[inline(always)]
    pub(super) fn sensor_cell<F: Fmt>(
        &self,
        name: &FirstName,
        sensor_no: &str,
        c: &mut Cells<'_, '_, F>,
    ) {
        if self.name {
            c.begin();
            c.put_ascii(name.first());
            c.end();
        } else {
            c.text(sensor_no);
        }
    }
}

/// The room [`media_range`] writes in, aligned so that `str::from_utf8` reads it from a word
/// boundary (byte by byte up to one, otherwise).
#[repr(align(8))]
pub(super) struct RangeText(pub [u8; 32]);

/// A medium's range `R57..R63` (`R57` alone for one element), as [`push_elem`] and
/// `push_range_end` write it: the letter and digits gathered in `buf` and checked as UTF-8
/// once (a push and a formatted number per name cost more). Returns the text and the length
/// of its first name.
pub(super) fn media_range(buf: &mut RangeText, letter: u8, addr: u32, count: u32) -> (&str, usize) {
    let (n, first) = range_bytes(buf, letter, addr, count);
    (ascii_text(&buf.0, n), first)
}

/// [`media_range`]'s bytes in `buf`: their length and the length of the first name.
#[inline(always)]
fn range_bytes(buf: &mut RangeText, letter: u8, addr: u32, count: u32) -> (usize, usize) {
    let w = &mut buf.0;
    w[0] = letter;
    let first = 1 + put_u32(&mut w[1..], addr);
    let mut n = first;
    if count > 1 {
        w[n..n + 3].copy_from_slice(&[b'.', b'.', letter]);
        n += 3;
        n += put_u32(&mut w[n..], addr.wrapping_add(count - 1));
    }
    (n, first)
}

/// The first `len` bytes of `block` (at most all of it) as text, for a block that holds ASCII
/// only (what a list or a range writes, and the zeros it started with): `str::from_utf8`
/// checks 16 bytes a step from a word boundary and the rest byte by byte, so the block is
/// checked up to the next multiple of 16 bytes, which costs less than the text's tail alone.
/// Should the bytes after the text not be ASCII, the text alone is checked.
pub(super) fn ascii_text(block: &[u8], len: usize) -> &str {
    let text = block.get(..len).unwrap_or(block);
    let padded = block.get(..len.next_multiple_of(16)).unwrap_or(block);
    std::str::from_utf8(padded)
        .ok()
        .and_then(|all| all.get(..text.len()))
        .unwrap_or_else(|| std::str::from_utf8(text).expect("the text is ASCII"))
}

/// The name part of a list's elements, `" R57="` (a blank, the letter, the address's digits,
/// `=`), counted up in place: a list's addresses are consecutive.
struct Names {
    text: [u8; NAME_ROOM],
    /// Bytes of `text` in use.
    len: usize,
    addr: u32,
}

impl Names {
    fn new(letter: u8, addr: u32) -> Self {
        let mut text = [b' '; NAME_ROOM];
        text[1] = letter;
        let n = put_u32(&mut text[2..], addr);
        text[2 + n] = b'=';
        Names {
            text,
            len: 3 + n,
            addr,
        }
    }

    /// [`Names::new`] from the first name already written (`R57`: `letter` and the decimal
    /// digits of `addr`, see [`LazyWords::first_name`]), copied instead of formatted again
    /// (the bytes after the `=` are not the blanks of [`Names::new`]: a list writes over them).
    #[inline(always)]
    fn of_first(name: &FirstName, letter: u8, addr: u32) -> Self {
        let mut text = [b' '; NAME_ROOM];
        text[1..].copy_from_slice(&name.buf.0[..NAME_ROOM - 1]);
        match text.get_mut(1 + name.first) {
            Some(eq) if name.first >= 2 && name.buf.0[0] == letter => {
                *eq = b'=';
                Names {
                    text,
                    len: 2 + name.first,
                    addr,
                }
            }
            _ => Names::new(letter, addr),
        }
    }

    /// The next address (wrapping like `u32::wrapping_add`): the last digit counted up, a
    /// carry over the nines before it; written again when the number gets one digit longer
    /// or wraps to 0.
    #[inline(always)]
    fn step(&mut self) {
        self.addr = self.addr.wrapping_add(1);
        let mut i = self.len - 2;
        while self.addr != 0 {
            match self.text.get_mut(i) {
                Some(d) if (b'0'..=b'8').contains(d) => {
                    *d += 1;
                    return;
                }
                Some(d) if *d == b'9' && i > 2 => {
                    *d = b'0';
                    i -= 1;
                }
                _ => break,
            }
        }
        *self = Names::new(self.text[1], self.addr);
    }
}

/// A parts buffer for the usual row (up to 16 registers), cheaper to set up than the largest.
pub(super) const FEW_PARTS: usize = 16;

/// The most numbers an S-Bus telegram carries (a read or write of 128 flags).
pub(super) const MAX_PARTS: usize = 128;

/// The numbers of a Data cell that lists media values, `R0=305419896 R1=100` or `F3=0`: each
/// `R`/`F`/`I`/`O`/`T`/`C` with its address and an integer is a number named like the medium
/// (`R0`, `F3`). Any other Data (a range `R0..R3`, a status, a NAK, a clock) carries none: every
/// token must be such a pair.
/// `buf` holds at most [`MAX_PARTS`] parts; more tokens than `buf` holds give none.
///
/// One pass over the bytes: every token must read `[RFIOTC][0-9]+=[+-]?[0-9]+` with the number
/// in the range of an `i64` (what `str::parse::<i64>` accepts), tokens separated by single
/// spaces.
pub(super) fn media_parts<'a>(data: &'a str, buf: &mut [Part<'a>]) -> usize {
    let bytes = data.as_bytes();
    let digits = |mut i: usize| {
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut n = 0;
    let mut i = 0;
    loop {
        // the name: a medium letter and its address (the slices below are at ASCII bytes)
        let start = i;
        if !matches!(bytes.get(i), Some(b'R' | b'F' | b'I' | b'O' | b'T' | b'C')) {
            return 0;
        }
        let eq = digits(i + 1);
        if eq == i + 1 || bytes.get(eq) != Some(&b'=') {
            return 0;
        }
        // the number
        i = eq + 1;
        let neg = bytes.get(i) == Some(&b'-');
        if neg || bytes.get(i) == Some(&b'+') {
            i += 1;
        }
        let first = i;
        let mut value: i64 = 0;
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            let d = (bytes[i] - b'0') as i64;
            let v = value.checked_mul(10).and_then(|v| {
                if neg {
                    v.checked_sub(d)
                } else {
                    v.checked_add(d)
                }
            });
            let Some(v) = v else {
                return 0;
            };
            value = v;
            i += 1;
        }
        if i == first || n == buf.len() {
            return 0;
        }
        buf[n] = Part {
            name: &data[start..eq],
            unit: "",
            text: &data[eq + 1..i],
            value: value as f64,
        };
        n += 1;
        match bytes.get(i) {
            None => return n,
            Some(b' ') => i += 1,
            Some(_) => return 0,
        }
    }
}

#[cfg(test)]
mod tests;
