//! Decimal digits of integers without a division per digit: eight digits at a time with
//! multiplications (S-Bus media lists and ranges).
//!
//! The writer puts the digits at the start of a byte slice that has room for the longest
//! number (10 bytes for a `u32`), may write over the bytes of that room after the number, and
//! returns the number's length.

const ZEROS: u64 = 0x3030_3030_3030_3030;

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
#[inline]
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
    fn u32_digits_are_the_decimal_text() {
        for v in samples().map(|v| v as u32) {
            let mut b = [b'#'; 10];
            let n = put_u32(&mut b, v);
            assert_eq!(std::str::from_utf8(&b[..n]).unwrap(), v.to_string());
        }
    }
}
