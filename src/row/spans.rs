//! The cells `ID` to `Sensor` of rows already written, kept per [`Row::stamp`] as the table's
//! format wrote them, so that the next row with the same stamp copies them in one piece
//! instead of writing (and checking) five cells again.
//!
//! A stamp promises that its rows have the same `id`, `device`, `kind`, `sensor_no` and
//! `sensor` (see [`Row::stamp`]); in pretty output the text also depends on the column
//! widths, so a span is kept with the widths it was written with ([`Spans::get`]'s `widths`).
//! Debug builds (every test) write the cells again after each copy and compare.
//!
//! The cache is direct-mapped: a fixed number of slots of a fixed size, a newer stamp takes
//! the slot of an older one, and a span longer than a slot is simply not kept. Its memory is
//! the same whatever the capture.
//!
//! [`Row::stamp`]: crate::row::Row::stamp

/// Number of slots (a power of two).
const SLOTS: usize = 256;
/// Longest span kept, in bytes.
pub(crate) const SPAN_MAX: usize = 118;

#[derive(Clone, Copy)]
struct Slot {
    /// 0: empty.
    stamp: u32,
    /// What the pretty column widths were (0 for the other formats).
    widths: u32,
    len: u8,
    /// Pretty output: the blanks owed after the span (the last cell's padding).
    blanks: u8,
    bytes: [u8; SPAN_MAX],
}

const EMPTY: Slot = Slot {
    stamp: 0,
    widths: 0,
    len: 0,
    blanks: 0,
    bytes: [0; SPAN_MAX],
};

/// The spans written so far: 256 slots of 128 bytes.
pub(crate) struct Spans {
    slots: Box<[Slot; SLOTS]>,
}

impl Spans {
    pub fn new() -> Self {
        Spans {
            slots: Box::new([EMPTY; SLOTS]),
        }
    }

    #[inline(always)]
    fn index(stamp: u32) -> usize {
        (stamp.wrapping_mul(0x9E37_79B1) >> 24) as usize % SLOTS
    }

    /// The span kept for `stamp` when it was written with these `widths`, and the blanks owed
    /// after it. Stamp 0 has none.
    #[inline(always)]
    pub fn get(&self, stamp: u32, widths: u32) -> Option<(&[u8], usize)> {
        let s = &self.slots[Self::index(stamp)];
        if s.stamp == stamp && stamp != 0 && s.widths == widths {
            Some((&s.bytes[..usize::from(s.len)], usize::from(s.blanks)))
        } else {
            None
        }
    }

    /// [`Spans::get`] with the whole slot: its bytes (the span's, then what the slot held
    /// before), the span's length and the blanks owed after it.
    #[inline(always)]
    pub fn get_slot(&self, stamp: u32, widths: u32) -> Option<(&[u8; SPAN_MAX], usize, usize)> {
        let s = &self.slots[Self::index(stamp)];
        if s.stamp == stamp && stamp != 0 && s.widths == widths {
            Some((&s.bytes, usize::from(s.len), usize::from(s.blanks)))
        } else {
            None
        }
    }

    /// Keeps `bytes` (and the blanks owed after them) for `stamp`; a span too long for a slot,
    /// and stamp 0, are not kept.
    #[inline]
    pub fn put(&mut self, stamp: u32, widths: u32, bytes: &[u8], blanks: usize) {
        let (Ok(len), Ok(blanks)) = (u8::try_from(bytes.len()), u8::try_from(blanks)) else {
            return;
        };
        if stamp == 0 || bytes.len() > SPAN_MAX {
            return;
        }
        let s = &mut self.slots[Self::index(stamp)];
        s.stamp = stamp;
        s.widths = widths;
        s.len = len;
        s.blanks = blanks;
        s.bytes[..bytes.len()].copy_from_slice(bytes);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_span_is_kept_per_stamp_and_widths() {
        let mut s = Spans::new();
        assert!(s.get(7, 0).is_none());
        s.put(7, 0, b"\t1\tVario", 0);
        assert_eq!(s.get(7, 0), Some((&b"\t1\tVario"[..], 0)));
        assert!(s.get(7, 1).is_none(), "other widths");
        assert!(s.get(8, 0).is_none(), "other stamp");
        s.put(7, 3, b"  1  Vario", 4);
        assert_eq!(s.get(7, 3), Some((&b"  1  Vario"[..], 4)));
        assert!(s.get(7, 0).is_none(), "replaced");
    }

    #[test]
    fn stamp_zero_and_long_spans_are_not_kept() {
        let mut s = Spans::new();
        s.put(0, 0, b"x", 0);
        assert!(s.get(0, 0).is_none());
        s.put(9, 0, &[b'x'; SPAN_MAX + 1], 0);
        assert!(s.get(9, 0).is_none());
        s.put(9, 0, &[b'x'; SPAN_MAX], 0);
        assert_eq!(s.get(9, 0).map(|(b, _)| b.len()), Some(SPAN_MAX));
        s.put(10, 0, b"x", 300);
        assert!(s.get(10, 0).is_none(), "blanks beyond a byte");
    }

    #[test]
    fn colliding_stamps_take_each_others_slot() {
        let mut s = Spans::new();
        let a = 1;
        let b = (2..).find(|&b| Spans::index(b) == Spans::index(a)).unwrap();
        s.put(a, 0, b"a", 0);
        s.put(b, 0, b"b", 0);
        assert!(s.get(a, 0).is_none());
        assert_eq!(s.get(b, 0), Some((&b"b"[..], 0)));
    }
}
