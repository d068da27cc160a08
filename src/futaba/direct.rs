//! The common Futaba rows written straight into the table ([`crate::row::direct`]): channel
//! frames and slot answers. Broken bytes (and every row when the table lends no
//! [`crate::row::Direct`]) go through the mapper as a [`crate::row::Row`]; both give the same
//! bytes (`testing::assert_direct_rows_match`).

use super::map::{CH_NAMES, CHANNELS_TYPE, RX_VOLTAGE, SLOT_NAMES, SLOT_TYPE, device, group_text};
use super::wire::{self, CHANNELS, FRAME_LEN, SLOT_LEN};
use crate::fmt::hex_0x;
use crate::row::{Cells, Class, Direct, Fmt, Mark, WriteRow};

/// Stamps of the cells ID to Sensor: a frame's follow from its end byte, a slot's from its id
/// byte.
const FRAME_STAMP: u32 = 1 << 30;
const SLOT_STAMP: u32 = 1 << 29;

/// Bytes of one number's text in the tables: a blank and up to four digits.
const W: usize = 5;
/// Numbers an 11-bit channel can be.
const RAWS: usize = 1 << 11;
/// A table's bytes: every number's `W`, and room for reading 8 bytes at the last.
const TABLE: usize = RAWS * W + 8;

/// The texts of every 11-bit channel value (`micros`: of its microseconds), each a blank and
/// its digits in `W` bytes (padded with blanks), and each text's length (blank included).
const fn number_table(micros: bool) -> ([u8; TABLE], [u8; RAWS]) {
    let mut text = [b' '; TABLE];
    let mut len = [0u8; RAWS];
    let mut x = 0;
    while x < RAWS {
        let mut v = if micros {
            wire::micros(x as u16) as usize
        } else {
            x
        };
        let mut digits = 1;
        let mut p = 10;
        while v >= p {
            digits += 1;
            p *= 10;
        }
        let mut i = digits;
        while i > 0 {
            text[x * W + i] = b'0' + (v % 10) as u8;
            v /= 10;
            i -= 1;
        }
        len[x] = 1 + digits as u8;
        x += 1;
    }
    (text, len)
}

static US: ([u8; TABLE], [u8; RAWS]) = number_table(true);
static RAW: ([u8; TABLE], [u8; RAWS]) = number_table(false);

/// A line of ASCII text built in place: fixed-size copies of 8 bytes (the bytes past the text
/// are written over later), then checked as text once.
struct Text<const N: usize> {
    b: [u8; N],
    n: usize,
}

impl<const N: usize> Text<N> {
    fn new() -> Self {
        Text { b: [b' '; N], n: 0 }
    }

    /// The number `r`'s text from a table (a blank and digits), from its `skip`th byte.
    #[inline(always)]
    fn number(&mut self, table: &([u8; TABLE], [u8; RAWS]), r: u16, skip: usize) {
        let r = usize::from(r) & (RAWS - 1);
        let (Some(dst), Some(src)) = (
            self.b.get_mut(self.n..self.n + 8),
            table.0.get(r * W + skip..r * W + skip + 8),
        ) else {
            return;
        };
        dst.copy_from_slice(src);
        self.n += usize::from(table.1[r]) - skip;
    }

    #[inline(always)]
    fn put(&mut self, s: &[u8]) {
        if let Some(dst) = self.b.get_mut(self.n..self.n + s.len()) {
            dst.copy_from_slice(s);
            self.n += s.len();
        }
    }

    #[inline(always)]
    fn as_str(&self) -> &str {
        std::str::from_utf8(&self.b[..self.n.min(N)]).unwrap_or("")
    }
}

/// The texts of a group's slots following, by slot group.
const FOLLOW: [&str; 4] = [
    "; slots 0-7 follow",
    "; slots 8-15 follow",
    "; slots 16-23 follow",
    "; slots 24-31 follow",
];

/// A channel frame's row: the Data and Note cells made beforehand (`ends`: where each
/// channel's text ends in Data).
struct ChannelRow {
    flags: u8,
    end: u8,
    data: Text<96>,
    ends: [u8; CHANNELS],
    note: Text<200>,
}

impl ChannelRow {
    #[inline(always)]
    fn new(f: &[u8; FRAME_LEN]) -> Self {
        let raw = wire::channels(f);
        let (flags, end) = (f[23], f[24]);
        let mut data = Text::new();
        let mut ends = [0u8; CHANNELS];
        for (i, (&r, e)) in raw.iter().zip(&mut ends).enumerate() {
            // The first without its blank.
            data.number(&US, r, usize::from(i == 0));
            *e = data.n as u8;
        }
        let mut note = Text::new();
        note.put(b"CH17=0 CH18=0 FrameLost=0 Failsafe=0");
        note.b[5] += flags & wire::FLAG_CH17;
        note.b[12] += (flags & wire::FLAG_CH18) >> 1;
        note.b[24] += (flags & wire::FLAG_FRAME_LOST) >> 2;
        note.b[35] += (flags & wire::FLAG_FAILSAFE) >> 3;
        if flags & 0xF0 != 0 {
            note.put(b"; unused flag bits set (flags ");
            note.put(hex_0x(flags).as_bytes());
            note.put(b")");
        }
        match wire::slot_group(end) {
            Some(g) => note.put(FOLLOW[usize::from(g & 3)].as_bytes()),
            None if end == wire::END_FAST => note.put(b"; SBUS2 fast pace, no slots"),
            None => {}
        }
        note.put(b"; raw");
        for &r in &raw {
            note.number(&RAW, r, 0);
        }
        ChannelRow {
            flags,
            end,
            data,
            ends,
            note,
        }
    }
}

impl WriteRow for ChannelRow {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let (flags, end) = (self.flags, self.end);
        if c.stamp(FRAME_STAMP | u32::from(end)) {
            c.id(None);
            c.empty();
            c.text(CHANNELS_TYPE);
            c.text(hex_0x(end));
            c.text(if end == wire::END_SBUS {
                "SBUS"
            } else {
                "SBUS2"
            });
            c.stamp_end();
        }
        c.begin();
        let at = c.here();
        c.str(self.data.as_str());
        c.end();
        let mark = |i: usize| {
            // After the blank before it (the first has none).
            let start = if i == 0 {
                0
            } else {
                u32::from(self.ends[i - 1]) + 1
            };
            Mark::new(at + start, at + u32::from(self.ends[i]))
        };
        c.value(Some(mark(0)));
        c.text("us");
        c.begin();
        c.str(self.note.as_str());
        c.end();
        for (i, name) in CH_NAMES.iter().enumerate() {
            c.part(name, mark(i));
        }
        let bit = |b: u8| if flags & b != 0 { "1" } else { "0" };
        c.part_text("CH17", bit(wire::FLAG_CH17));
        c.part_text("CH18", bit(wire::FLAG_CH18));
        c.part_text("FrameLost", bit(wire::FLAG_FRAME_LOST));
        c.part_text("Failsafe", bit(wire::FLAG_FAILSAFE));
    }
}

/// Writes a channel frame's row (the statistics are the mapper's, kept before).
#[inline]
pub(super) fn frame(d: Direct<'_>, micros: u64, f: &[u8; FRAME_LEN]) {
    let class = if f[23] & (wire::FLAG_FRAME_LOST | wire::FLAG_FAILSAFE) != 0 {
        Class::Warning
    } else {
        Class::Plain
    };
    d.row(Some(micros), class, f, &ChannelRow::new(f));
}

/// A slot answer's row.
struct SlotRow {
    id: u8,
    n: u8,
    value: u16,
    /// The group the frame before announced, when another than the slot's.
    other: Option<u8>,
}

impl WriteRow for SlotRow {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let n = self.n;
        if c.stamp(SLOT_STAMP | u32::from(self.id)) {
            c.id(Some(u32::from(n)));
            c.text(device(u32::from(n)));
            c.text(SLOT_TYPE);
            c.text(hex_0x(self.id));
            c.text(if n == 0 { RX_VOLTAGE } else { "" });
            c.stamp_end();
        }
        c.begin();
        c.str("0x");
        c.hex2((self.value >> 8) as u8);
        c.hex2(self.value as u8);
        c.end();
        let mut ib = itoa::Buffer::new();
        let v = ib.format(self.value);
        c.value_text(Some(v));
        c.empty();
        c.begin();
        c.str(if n == 0 {
            "receiver voltage slot, raw value"
        } else {
            "raw value (the sensor is assigned on the transmitter)"
        });
        if let Some(g) = self.other {
            c.str("; answered after a frame announcing ");
            c.str(group_text(g));
        }
        c.end();
        c.part_text(SLOT_NAMES[usize::from(n & 31)], v);
    }
}

/// Writes a slot answer's row (the statistics are the mapper's, kept before): slot `n`,
/// answered after a frame that announced `other` when that was another group.
#[inline]
pub(super) fn slot(d: Direct<'_>, micros: u64, b: &[u8; SLOT_LEN], n: u8, other: Option<u8>) {
    let row = SlotRow {
        id: b[0],
        n,
        value: u16::from_be_bytes([b[1], b[2]]),
        other,
    };
    let class = if other.is_some() {
        Class::Warning
    } else {
        Class::Plain
    };
    d.row(Some(micros), class, b, &row);
}
