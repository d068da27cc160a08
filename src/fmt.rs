//! Small allocation-free formatting helpers used on the hot path.

const HEX: &[u8; 16] = b"0123456789ABCDEF";

/// Appends a byte as two upper-case hex digits (`7E`).
#[inline]
pub fn push_hex_u8(out: &mut String, b: u8) {
    out.push(HEX[(b >> 4) as usize] as char);
    out.push(HEX[(b & 0x0F) as usize] as char);
}

/// `0x00` … `0xFF`, four bytes each (see [`hex_0x`]).
const HEX_0X_TEXT: [u8; 1024] = {
    let mut t = [0u8; 1024];
    let mut i = 0;
    while i < 256 {
        t[4 * i] = b'0';
        t[4 * i + 1] = b'x';
        t[4 * i + 2] = HEX[i >> 4];
        t[4 * i + 3] = HEX[i & 0x0F];
        i += 1;
    }
    t
};

/// `0xNN` for every byte, as static strings (see [`hex_0x`]).
static HEX_0X: [&str; 256] = {
    let mut t = [""; 256];
    let mut i = 0;
    while i < 256 {
        let (_, rest) = HEX_0X_TEXT.split_at(4 * i);
        let (digits, _) = rest.split_at(4);
        t[i] = match std::str::from_utf8(digits) {
            Ok(s) => s,
            Err(_) => panic!("ASCII"),
        };
        i += 1;
    }
    t
};

/// `0xNN` as a static string (what [`push_0x`] appends), for columns that need no copy.
#[inline]
pub fn hex_0x(b: u8) -> &'static str {
    HEX_0X[b as usize]
}

/// Appends `0xNN`.
pub fn push_0x(out: &mut String, b: u8) {
    out.push_str("0x");
    push_hex_u8(out, b);
}

/// Appends `0xNNNN`.
pub fn push_0x16(out: &mut String, v: u16) {
    out.push_str("0x");
    let [hi, lo] = v.to_be_bytes();
    push_hex_u8(out, hi);
    push_hex_u8(out, lo);
}

/// `"00 "` … `"FF "`, three bytes each (see [`HEX_SP`]).
const HEX_SP_TEXT: [u8; 768] = {
    let mut t = [b' '; 768];
    let mut i = 0;
    while i < 256 {
        t[3 * i] = HEX[i >> 4];
        t[3 * i + 1] = HEX[i & 0x0F];
        i += 1;
    }
    t
};

/// `"00 "` … `"FF "` for every byte, as static strings: a byte's hex is one copy of three
/// bytes instead of three pushes.
static HEX_SP: [&str; 256] = {
    let mut t = [""; 256];
    let mut i = 0;
    while i < 256 {
        let (_, rest) = HEX_SP_TEXT.split_at(3 * i);
        let (digits, _) = rest.split_at(3);
        t[i] = match std::str::from_utf8(digits) {
            Ok(s) => s,
            Err(_) => panic!("ASCII"),
        };
        i += 1;
    }
    t
};

/// Appends `bytes` as upper-case hex separated by single spaces (`7E A1 10`): one copy of three
/// bytes per byte.
pub fn push_hex(out: &mut String, bytes: &[u8]) {
    let Some((&last, init)) = bytes.split_last() else {
        return;
    };
    out.reserve(bytes.len() * 3);
    for &b in init {
        out.push_str(&HEX_SP[b as usize][..3]);
    }
    out.push_str(&HEX_SP[last as usize][..2]);
}

/// Same as [`push_hex`] into a byte buffer.
pub fn push_hex_bytes(out: &mut Vec<u8>, bytes: &[u8]) {
    out.reserve(bytes.len() * 3);
    for (i, b) in bytes.iter().enumerate() {
        if i > 0 {
            out.push(b' ');
        }
        out.push(HEX[(b >> 4) as usize]);
        out.push(HEX[(b & 0x0F) as usize]);
    }
}

/// `bytes` as spaced hex in a new string (for notes and tests, not the hot path).
pub fn hex(bytes: &[u8]) -> String {
    let mut s = String::new();
    push_hex(&mut s, bytes);
    s
}

/// Parses spaced or unspaced hex (`"7E A1 10"`, `"7ea110"`). Returns `None` on any other character
/// or an odd number of digits.
pub fn parse_hex(text: &str) -> Option<Vec<u8>> {
    let digits: Vec<u8> = text
        .bytes()
        .filter(|b| !b.is_ascii_whitespace())
        .map(|b| (b as char).to_digit(16).map(|d| d as u8))
        .collect::<Option<_>>()?;
    if !digits.len().is_multiple_of(2) {
        return None;
    }
    Some(digits.chunks(2).map(|p| p[0] << 4 | p[1]).collect())
}

/// Appends an unsigned integer in decimal.
pub fn push_u64(out: &mut String, v: u64) {
    out.push_str(itoa::Buffer::new().format(v));
}

/// Appends a signed integer in decimal.
pub fn push_i64(out: &mut String, v: i64) {
    out.push_str(itoa::Buffer::new().format(v));
}

/// Appends `raw / 10^prec` as a plain decimal with exactly `prec` decimals (`6543, 2` → `65.43`,
/// `-150, 2` → `-1.50`, `5, 3` → `0.005`).
pub fn push_fixed(out: &mut String, raw: i64, prec: u8) {
    if prec == 0 {
        push_i64(out, raw);
        return;
    }
    let scale = 10u64.pow(prec as u32);
    let mag = raw.unsigned_abs();
    if raw < 0 {
        out.push('-');
    }
    push_u64(out, mag / scale);
    out.push('.');
    let frac = mag % scale;
    let mut buf = itoa::Buffer::new();
    let digits = buf.format(frac);
    for _ in digits.len()..prec as usize {
        out.push('0');
    }
    out.push_str(digits);
}

/// Appends µs as milliseconds with three decimals (`2500` → `2.500`).
pub fn push_ms(out: &mut String, micros: u64) {
    push_fixed(out, micros.min(i64::MAX as u64) as i64, 3);
}

/// Appends µs as milliseconds without useless decimals (`10000` → `10`, `2500` → `2.5`).
pub fn push_ms_short(out: &mut String, micros: u64) {
    if micros.is_multiple_of(1000) {
        push_u64(out, micros / 1000);
    } else {
        push_ms(out, micros);
        while out.ends_with('0') {
            out.pop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_from_the_table_is_the_byte_buffer_hex() {
        let all: Vec<u8> = (0..=255).collect();
        for len in [0, 1, 2, 3, 4, 7, 33, 256] {
            let bytes = &all[all.len() - len..];
            let (mut text, mut buf) = (String::new(), Vec::new());
            push_hex(&mut text, bytes);
            push_hex_bytes(&mut buf, bytes);
            assert_eq!(text.as_bytes(), buf, "{len} bytes");
        }
        let mut s = String::new();
        push_hex(&mut s, &[0x7E, 0xA1, 0x10]);
        assert_eq!(s, "7E A1 10");
    }

    #[test]
    fn static_0x_texts() {
        for b in 0..=255u8 {
            let mut s = String::new();
            push_0x(&mut s, b);
            assert_eq!(hex_0x(b), s);
        }
    }

    #[test]
    fn fixed_point() {
        let cases = [
            (6543, 2, "65.43"),
            (-150, 2, "-1.50"),
            (0, 2, "0.00"),
            (5, 3, "0.005"),
            (-5, 1, "-0.5"),
            (42, 0, "42"),
            (i64::MIN, 2, "-92233720368547758.08"),
        ];
        for (raw, prec, want) in cases {
            let mut s = String::new();
            push_fixed(&mut s, raw, prec);
            assert_eq!(s, want, "{raw} prec {prec}");
        }
    }

    #[test]
    fn hex_round_trip() {
        let bytes = [0x7E, 0xA1, 0x00, 0xFF];
        assert_eq!(hex(&bytes), "7E A1 00 FF");
        assert_eq!(parse_hex("7E A1 00 FF").unwrap(), bytes);
        assert_eq!(parse_hex("7ea100ff").unwrap(), bytes);
        assert!(parse_hex("7E A").is_none());
        assert!(parse_hex("7G").is_none());
    }

    #[test]
    fn hex_prefixed() {
        let mut s = String::new();
        push_hex_u8(&mut s, 0x0A);
        s.push(' ');
        push_0x(&mut s, 0xF0);
        s.push(' ');
        push_0x16(&mut s, 0x8F1D);
        s.push(' ');
        push_0x16(&mut s, 0x0001);
        assert_eq!(s, "0A 0xF0 0x8F1D 0x0001");
    }

    #[test]
    fn milliseconds() {
        let cases = [
            (0, "0.000", "0"),
            (1, "0.001", "0.001"),
            (2_500, "2.500", "2.5"),
            (10_000, "10.000", "10"),
            (10_010, "10.010", "10.01"),
            (86_805, "86.805", "86.805"),
            (u64::MAX, "9223372036854775.807", "9223372036854775.807"),
        ];
        for (micros, full, short) in cases {
            let mut s = String::new();
            push_ms(&mut s, micros);
            assert_eq!(s, full, "{micros}");
            s.clear();
            push_ms_short(&mut s, micros);
            assert_eq!(s, short, "{micros}");
        }
    }
}
