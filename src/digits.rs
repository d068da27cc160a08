//! Decimal digits of integers without a division per digit: eight digits at a time with
//! multiplications (S-Bus media lists and ranges).
//!
//! The writer puts the digits at the start of a byte slice that has room for the longest
//! number (10 bytes for a `u32`), may write over the bytes of that room after the number, and
//! returns the number's length.

const ZEROS: u64 = 0x3030_3030_3030_3030;

/// The text ` DIGITS` of `v < 10^6` packed in a word for a table of small numbers (RC channel
/// values): a blank in the lowest byte, the decimal digits in the next ones, and the text's
/// length (blank included) in the top byte, so one load gives both.
pub const fn blank_digits_word(v: u64) -> u64 {
    let mut digits = 1;
    let mut p = 10;
    while v >= p {
        digits += 1;
        p *= 10;
    }
    let mut word = b' ' as u64 | (1 + digits) << 56;
    let mut rest = v;
    let mut i = digits;
    while i > 0 {
        word |= (b'0' as u64 + rest % 10) << (8 * i);
        rest /= 10;
        i -= 1;
    }
    word
}

/// `"00" "01" … "99"`: two decimal digits per step.
static DEC2: [u8; 200] = {
    let mut t = [0u8; 200];
    let mut i = 0;
    while i < 100 {
        t[2 * i] = b'0' + (i / 10) as u8;
        t[2 * i + 1] = b'0' + (i % 10) as u8;
        i += 1;
    }
    t
};

/// Writes `v` in decimal at the start of `w` (at least 10 bytes long; bytes after
/// the number may be overwritten too); returns its length.
#[inline(always)]
pub fn put_u32(w: &mut [u8], v: u32) -> usize {
    if v < 100_000_000 {
        // the eight digits without their leading zeros (in the low bytes, which come first)
        let d = eight_digits(v);
        let lead = if v == 0 {
            7
        } else {
            (d.trailing_zeros() / 8) as usize
        };
        w[..8].copy_from_slice(&((d >> (lead * 8)) | ZEROS).to_le_bytes());
        8 - lead
    } else {
        let hi = (v / 100_000_000) as usize;
        let k = if hi >= 10 {
            w[..2].copy_from_slice(&DEC2[2 * hi..2 * hi + 2]);
            2
        } else {
            w[0] = b'0' + hi as u8;
            1
        };
        let d = eight_digits(v % 100_000_000) | ZEROS;
        w[k..k + 8].copy_from_slice(&d.to_le_bytes());
        k + 8
    }
}

/// Writes `v` in decimal at the start of `w` (at least 24 bytes long; bytes after the number
/// may be overwritten too); returns its length. The numbers of a row mostly fit 32 bits: that
/// case is inline where it is called (the call cost about a fifth of a number's instructions),
/// the longer ones are out of line. [`put_u64_call`] is the same through a call.
#[inline(always)]
pub fn put_u64(w: &mut [u8], v: u64) -> usize {
    if v <= u64::from(u32::MAX) {
        put_u32(w, v as u32)
    } else {
        put_u64_wide(w, v)
    }
}

/// [`put_u64`] through a call, where the code around it is better off without the inlined
/// digits (the table's writer of [`crate::row::Row`]s: inlined there, they cost 2 % more
/// instructions in all).
#[inline(never)]
pub fn put_u64_call(w: &mut [u8], v: u64) -> usize {
    put_u64(w, v)
}

/// [`put_u64`] of a number above `u32::MAX`.
#[inline(never)]
fn put_u64_wide(w: &mut [u8], v: u64) -> usize {
    let hi = v / 100_000_000;
    let k = if hi <= u64::from(u32::MAX) {
        put_u32(w, hi as u32)
    } else {
        let k = put_u32(w, (hi / 100_000_000) as u32);
        let d = eight_digits((hi % 100_000_000) as u32) | ZEROS;
        w[k..k + 8].copy_from_slice(&d.to_le_bytes());
        k + 8
    };
    let d = eight_digits((v % 100_000_000) as u32) | ZEROS;
    w[k..k + 8].copy_from_slice(&d.to_le_bytes());
    k + 8
}

/// Writes `raw / 10^prec` in decimal at the start of `w` as
/// [`crate::numbers::push_decimal`] writes it (`6543, 2` → `65.43`, `-150, 2` → `-1.50`,
/// `5, 3` → `0.005`), for `prec` up to 7; `w` at least 32 bytes long (bytes after the number
/// may be overwritten too). Returns its length, or `None` for a larger `prec`.
#[inline(always)]
pub fn put_fixed(w: &mut [u8], raw: i64, prec: u8) -> Option<usize> {
    let m = raw.unsigned_abs();
    let sign = usize::from(raw < 0);
    w[0] = b'-';
    // The whole part and the fraction, by constants (no division instruction).
    let (whole, frac) = match prec {
        0 => return Some(sign + put_u64(&mut w[sign..], m)),
        1 => (m / 10, m % 10),
        2 => (m / 100, m % 100),
        3 => (m / 1_000, m % 1_000),
        4 => (m / 10_000, m % 10_000),
        5 => (m / 100_000, m % 100_000),
        6 => (m / 1_000_000, m % 1_000_000),
        7 => (m / 10_000_000, m % 10_000_000),
        _ => return None,
    };
    let k = sign + put_u64(&mut w[sign..], whole);
    w[k] = b'.';
    // The fraction's `prec` digits with their leading zeros: the last of its eight.
    let d = eight_digits(frac as u32) >> (8 * (8 - u32::from(prec))) | ZEROS;
    w[k + 1..k + 9].copy_from_slice(&d.to_le_bytes());
    Some(k + 1 + usize::from(prec))
}

/// The eight decimal digits of `v` (below 10^8, leading zeros included) as the values 0-9 in
/// the eight bytes of a `u64`, the first digit in the lowest byte: all digits at once with
/// multiplications (after D. Lemire, "Converting integers to decimal strings faster").
#[inline]
fn eight_digits(v: u32) -> u64 {
    // abcd | efgh << 32
    let merged = (v / 10_000) as u64 | ((v % 10_000) as u64) << 32;
    // ab, ef: / 100 in each 32-bit lane
    let top = ((merged * 10_486) >> 20) & (0x7F << 32 | 0x7F);
    let bottom = merged - 100 * top;
    // ab | cd << 16 | ef << 32 | gh << 48
    let hundreds = (bottom << 16) + top;
    // the tens in the low byte of each 16-bit lane, the units in the high byte
    let mut tens = ((hundreds * 103) >> 10) & (0xF << 48 | 0xF << 32 | 0xF << 16 | 0xF);
    tens += (hundreds - 10 * tens) << 8;
    tens
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blank_digits_words() {
        for (v, text) in [
            (0u64, " 0"),
            (7, " 7"),
            (10, " 10"),
            (2047, " 2047"),
            (999_999, " 999999"),
        ] {
            let w = blank_digits_word(v);
            let len = (w >> 56) as usize;
            assert_eq!(&w.to_le_bytes()[..len], text.as_bytes(), "{v}");
        }
    }

    /// Powers of ten and their neighbours, and xorshift values of every size.
    fn samples() -> impl Iterator<Item = u64> {
        let edges = (0..20).flat_map(|p| {
            let t = 10u64.pow(p);
            [t - 1, t, t + 1]
        });
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let random = (0..300_000).map(move |i| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x >> (i % 64)
        });
        edges
            .chain(random)
            .chain((0..2000).map(|i| i * 7919))
            .chain([0, u32::MAX as u64, u32::MAX as u64 + 1, u64::MAX])
    }

    #[test]
    fn fixed_is_push_decimal() {
        for v in samples() {
            for raw in [v as i64, -(v as i64), (v >> 1) as i64, -((v >> 33) as i64)] {
                for prec in 0..=7u8 {
                    let mut b = [b'#'; 32];
                    let n = put_fixed(&mut b, raw, prec).unwrap();
                    let mut s = String::new();
                    crate::numbers::push_decimal(&mut s, raw, prec);
                    assert_eq!(std::str::from_utf8(&b[..n]).unwrap(), s, "{raw} {prec}");
                }
            }
        }
        assert_eq!(put_fixed(&mut [0; 32], 1, 8), None);
    }

    #[test]
    fn u64_digits_are_the_decimal_text() {
        for v in samples() {
            let mut b = [b'#'; 24];
            let n = put_u64(&mut b, v);
            assert_eq!(std::str::from_utf8(&b[..n]).unwrap(), v.to_string());
        }
    }

    #[test]
    fn u32_digits_are_the_decimal_text() {
        for v in samples().map(|v| v as u32) {
            let mut b = [b'#'; 10];
            let n = put_u32(&mut b, v);
            assert_eq!(std::str::from_utf8(&b[..n]).unwrap(), v.to_string());
        }
    }
}
