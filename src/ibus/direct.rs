//! The common iBUS rows written straight into the table ([`crate::row::direct`]): RC frames
//! (command byte `40`) and measurement exchanges decoded in their sensor's type. The other
//! rows (and every row when the table lends no [`crate::row::Direct`]) go through the mapper as
//! a [`crate::row::Row`]; both give the same bytes (`testing::assert_direct_rows_match`).

use super::names::{CH_NAMES, CHANNELS, MEASURE};
use super::sensors::{Enc, SensorType};
use super::wire::{self, RC_CHANNELS_MAX, RC_SLOTS};
use crate::fmt::hex_0x;
use crate::row::{Cells, Class, Direct, Fmt, Mark, PartNames, WriteRow};

/// Stamps of the cells ID to Sensor: an RC frame's are always the same, a measurement's follow
/// from its address and type code.
const RC_STAMP: u32 = 1 << 30;
const MEASURE_STAMP: u32 = 1 << 29;

/// Numbers a channel can be (12 bits).
const VALUES: usize = 1 << 12;

/// The texts of every 12-bit channel value, each a blank and its digits in the low bytes of a
/// word, and the text's length (blank included) in its top byte: one load gives both.
const fn number_table() -> [u64; VALUES] {
    let mut table = [0u64; VALUES];
    let mut x = 0;
    while x < VALUES {
        table[x] = crate::digits::blank_digits_word(x as u64);
        x += 1;
    }
    table
}

static NUMBERS: [u64; VALUES] = number_table();

/// An RC frame's row.
struct RcRow {
    ch: [u16; RC_CHANNELS_MAX],
    high: bool,
}

impl WriteRow for RcRow {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        if c.stamp(RC_STAMP) {
            c.id(None);
            c.empty();
            c.text(CHANNELS);
            c.empty();
            c.empty();
            c.stamp_end();
        }
        let n = if self.high { RC_CHANNELS_MAX } else { RC_SLOTS };
        // The channels' texts from the table, fixed-size copies of 8 bytes (the bytes past a
        // text are written over by the next), written as ASCII.
        let mut text = [b' '; RC_CHANNELS_MAX * 5 + 8];
        let mut ends = [0u8; RC_CHANNELS_MAX];
        let mut at = 0usize;
        for (i, (&v, e)) in self.ch[..n].iter().zip(&mut ends).enumerate() {
            let word = NUMBERS[usize::from(v) & (VALUES - 1)];
            let (word, len) = if i == 0 {
                (word >> 8, (word >> 56) as usize - 1)
            } else {
                (word, (word >> 56) as usize)
            };
            let to = at.min(text.len() - 8);
            text[to..to + 8].copy_from_slice(&word.to_le_bytes());
            at = to + len;
            *e = at as u8;
        }
        let data = &text[..at.min(text.len())];
        c.begin();
        let start = c.here();
        c.put_ascii(data);
        c.end();
        // Channel i's text: after the blank before it (the first has none).
        let mark = |i: usize| {
            let a = if i == 0 {
                0
            } else {
                u32::from(ends[i - 1]) + 1
            };
            Mark::new(start + a, start + u32::from(ends[i]))
        };
        c.value(Some(mark(0)));
        c.text("us");
        c.text(if self.high {
            "18 channels (15-18 from the high nibbles)"
        } else {
            "14 channels"
        });
        static CH: PartNames<RC_CHANNELS_MAX> = PartNames::new(CH_NAMES);
        let marks: [Mark; RC_CHANNELS_MAX] = std::array::from_fn(mark);
        c.parts_marked(&CH, &marks[..n]);
    }
}

/// Writes an RC frame's row (command byte `40`; the statistics are the mapper's, kept before).
#[inline]
pub(super) fn rc(d: Direct<'_>, micros: u64, b: &[u8]) -> bool {
    let (ch, high) = wire::rc_channels(b);
    d.row(Some(micros), Class::Plain, b, &RcRow { ch, high });
    high
}

/// A measurement exchange's row: the value `r` in the address's type `t`.
struct MeasureRow<'a> {
    addr: u8,
    t: &'a SensorType,
    r: u32,
}

impl WriteRow for MeasureRow<'_> {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let (t, r) = (self.t, self.r);
        if c.stamp(MEASURE_STAMP | u32::from(self.addr) << 8 | u32::from(t.code)) {
            c.id(Some(u32::from(self.addr)));
            c.empty();
            c.text(MEASURE);
            c.text(hex_0x(t.code));
            c.text(t.name);
            c.stamp_end();
        }
        c.begin();
        let a = c.here();
        match t.enc {
            Enc::U16 => c.fixed(i64::from(r as u16), t.prec),
            Enc::S16 => c.fixed(i64::from(r as u16 as i16), t.prec),
            Enc::Temp => c.fixed(i64::from(r as u16) - 400, 1),
            Enc::S32 => c.fixed(i64::from(r as i32), t.prec),
            Enc::GpsStatus => c.dec(u64::from(r >> 8 & 0xFF)),
            // Raw values go through the mapper.
            Enc::Pressure | Enc::Raw => c.dec(u64::from(r & 0x7FFFF)),
        }
        let first = Mark::new(a, c.here());
        let mut second = first;
        let unit = match t.enc {
            Enc::GpsStatus => {
                c.str(" satellites, fix ");
                let b = c.here();
                c.dec(u64::from(r & 0xFF));
                second = Mark::new(b, c.here());
                ""
            }
            Enc::Pressure => {
                c.str(", ");
                let b = c.here();
                c.fixed(i64::from(r >> 19) - 400, 1);
                second = Mark::new(b, c.here());
                c.str(" degC");
                ""
            }
            _ => t.unit,
        };
        c.end();
        c.value(Some(first));
        c.text(unit);
        c.text(if t.code == 0x03 && r == 0x8000 {
            "0x8000: no value (Betaflight)"
        } else {
            ""
        });
        c.part(t.part, first);
        match t.enc {
            Enc::GpsStatus => c.part("Fix", second),
            Enc::Pressure => c.part("Tmp2", second),
            _ => {}
        }
    }
}

/// Writes a measurement exchange's row, whose value is decoded in units (a known type of
/// another encoding than `Raw`, with the width it expects; the statistics are the mapper's,
/// kept before). `raw`: the poll's and the answer's bytes.
#[inline]
pub(super) fn measure(d: Direct<'_>, micros: u64, addr: u8, t: &SensorType, r: u32, raw: &[u8]) {
    d.row(Some(micros), Class::Plain, raw, &MeasureRow { addr, t, r });
}
