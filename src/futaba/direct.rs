//! The common Futaba rows written straight into the table ([`crate::row::direct`]): channel
//! frames and slot answers. Broken bytes (and every row when the table lends no
//! [`crate::row::Direct`]) go through the mapper as a [`crate::row::Row`]; both give the same
//! bytes (`testing::assert_direct_rows_match`).

use super::names::{
    CH_NAMES, CHANNELS_TYPE, RX_VOLTAGE, SLOT_NAMES, SLOT_TYPE, device, group_text,
};
use super::wire::{self, CHANNELS, FRAME_LEN, SLOT_LEN};
use crate::fmt::hex_0x;
use crate::row::{Cells, Class, Direct, Fmt, Mark, PartNames, WriteRow};

/// Stamps of the cells ID to Sensor: a frame's follow from its end byte, a slot's from its id
/// byte.
const FRAME_STAMP: u32 = 1 << 30;
const SLOT_STAMP: u32 = 1 << 29;

/// Numbers an 11-bit channel can be.
const RAWS: usize = 1 << 11;

/// The texts of every 11-bit channel value (`micros`: of its microseconds), each a blank and
/// its digits in the low bytes of a word, and the text's length (blank included) in its top
/// byte: one load gives both.
const fn number_table(micros: bool) -> [u64; RAWS] {
    let mut table = [0u64; RAWS];
    let mut x = 0;
    while x < RAWS {
        let v = if micros {
            wire::micros(x as u16) as u64
        } else {
            x as u64
        };
        table[x] = crate::digits::blank_digits_word(v);
        x += 1;
    }
    table
}

static US: [u64; RAWS] = number_table(true);
static RAW: [u64; RAWS] = number_table(false);

/// A line of ASCII text built in place: fixed-size copies of 8 bytes (the bytes past the text
/// are written over later), written as ASCII ([`Cells::put_ascii`]).
struct Text<const N: usize> {
    b: [u8; N],
    n: usize,
}

impl<const N: usize> Text<N> {
    fn new() -> Self {
        Text { b: [b' '; N], n: 0 }
    }

    /// The number `r`'s text from a table: a blank and digits, or (`first`) the digits.
    #[inline(always)]
    fn number(&mut self, table: &[u64; RAWS], r: u16, first: bool) {
        let word = table[usize::from(r) & (RAWS - 1)];
        let (word, len) = if first {
            (word >> 8, (word >> 56) as usize - 1)
        } else {
            (word, (word >> 56) as usize)
        };
        // Nothing but the addition in the chain of positions from one number to the next
        // (the check for room is a branch, not a clamp in the chain).
        let at = self.n;
        if let Some(room) = self.b.get_mut(at..at + 8) {
            room.copy_from_slice(&word.to_le_bytes());
        }
        self.n = at + len;
    }

    /// The text (ASCII: digits and blanks from the tables).
    #[inline(always)]
    fn as_bytes(&self) -> &[u8] {
        &self.b[..self.n.min(N)]
    }
}

/// The flags' part of the Note, by the four low bits of the flags byte.
const FLAGS: [&str; 16] = [
    "CH17=0 CH18=0 FrameLost=0 Failsafe=0",
    "CH17=1 CH18=0 FrameLost=0 Failsafe=0",
    "CH17=0 CH18=1 FrameLost=0 Failsafe=0",
    "CH17=1 CH18=1 FrameLost=0 Failsafe=0",
    "CH17=0 CH18=0 FrameLost=1 Failsafe=0",
    "CH17=1 CH18=0 FrameLost=1 Failsafe=0",
    "CH17=0 CH18=1 FrameLost=1 Failsafe=0",
    "CH17=1 CH18=1 FrameLost=1 Failsafe=0",
    "CH17=0 CH18=0 FrameLost=0 Failsafe=1",
    "CH17=1 CH18=0 FrameLost=0 Failsafe=1",
    "CH17=0 CH18=1 FrameLost=0 Failsafe=1",
    "CH17=1 CH18=1 FrameLost=0 Failsafe=1",
    "CH17=0 CH18=0 FrameLost=1 Failsafe=1",
    "CH17=1 CH18=0 FrameLost=1 Failsafe=1",
    "CH17=0 CH18=1 FrameLost=1 Failsafe=1",
    "CH17=1 CH18=1 FrameLost=1 Failsafe=1",
];

/// What the Note says after the flags, by end byte: the slots that follow, the fast pace.
fn after_flags(end: u8) -> &'static str {
    match end {
        0x04 => "; slots 0-7 follow; raw",
        0x14 => "; slots 8-15 follow; raw",
        0x24 => "; slots 16-23 follow; raw",
        0x34 => "; slots 24-31 follow; raw",
        wire::END_FAST => "; SBUS2 fast pace, no slots; raw",
        _ => "; raw",
    }
}

/// A channel frame's row: the Data cell and the Note's list of raw values made beforehand,
/// one after the other in `text` (Data's ends at `ends[15]`; `ends`: where each channel's
/// text ends).
struct ChannelRow {
    flags: u8,
    end: u8,
    ends: [u8; CHANNELS],
    text: Text<176>,
}

impl ChannelRow {
    #[inline(always)]
    fn new(f: &[u8; FRAME_LEN]) -> Self {
        let mut row = ChannelRow {
            flags: f[23],
            end: f[24],
            ends: [0; CHANNELS],
            text: Text::new(),
        };
        let raw = wire::channels(f);
        let t = &mut row.text;
        for (i, (&r, e)) in raw.iter().zip(&mut row.ends).enumerate() {
            t.number(&US, r, i == 0);
            *e = t.n as u8;
        }
        for &r in &raw {
            t.number(&RAW, r, false);
        }
        row
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
        let (data, raw) = self
            .text
            .as_bytes()
            .split_at_checked(usize::from(self.ends[CHANNELS - 1]))
            .unwrap_or_default();
        c.begin();
        let at = c.here();
        c.put_ascii(data);
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
        // Plain pieces (names, digits, blanks, `;`, parentheses): the cell is not looked at
        // again in any format. The fast pace's text holds a comma: that cell is begun as
        // listed (CSV opens its quote first).
        let fast = end == wire::END_FAST;
        if fast {
            c.begin_listed();
        } else {
            c.begin();
        }
        c.put_ascii(FLAGS[usize::from(flags & 0x0F)].as_bytes());
        if flags & 0xF0 != 0 {
            c.put_ascii(b"; unused flag bits set (flags ");
            c.put_ascii(hex_0x(flags).as_bytes());
            c.put_ascii(b")");
        }
        if fast {
            c.put_listed(after_flags(end).as_bytes());
        } else {
            c.put_ascii(after_flags(end).as_bytes());
        }
        c.put_ascii(raw);
        c.end();
        static CH: PartNames<CHANNELS> = PartNames::new(CH_NAMES);
        c.parts_marked(&CH, &std::array::from_fn::<_, CHANNELS, _>(mark));
        static FLAG_NAMES: PartNames<4> = PartNames::new(["CH17", "CH18", "FrameLost", "Failsafe"]);
        let bit = |b: u8| if flags & b != 0 { "1" } else { "0" };
        c.parts_text(
            &FLAG_NAMES,
            &[
                bit(wire::FLAG_CH17),
                bit(wire::FLAG_CH18),
                bit(wire::FLAG_FRAME_LOST),
                bit(wire::FLAG_FAILSAFE),
            ],
        );
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
        c.put_ascii(hex_0x((self.value >> 8) as u8).as_bytes());
        c.hex2(self.value as u8);
        c.end();
        let mut ib = itoa::Buffer::new();
        let v = ib.format(self.value);
        c.value_text(Some(v));
        c.empty();
        let note = if n == 0 {
            "receiver voltage slot, raw value"
        } else {
            "raw value (the sensor is assigned on the transmitter)"
        };
        match self.other {
            None => c.text(note),
            Some(g) => {
                c.begin();
                c.str(note);
                c.str("; answered after a frame announcing ");
                c.str(group_text(g));
                c.end();
            }
        }
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
