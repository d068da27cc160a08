//! The text of SAB's cells that the mapper builds: payload bytes as hex with their integer
//! reading, one-byte payloads from a table, response times in milliseconds with three decimals.

use crate::fmt::push_hex;
use std::ops::Range;

/// The little-endian integer reading of a payload of 1, 2 or 4 bytes: (unsigned, signed).
#[inline]
pub(super) fn int_reading(payload: &[u8]) -> Option<(u32, i32)> {
    Some(match *payload {
        [a] => (a as u32, a as i8 as i32),
        [a, b] => {
            let v = u16::from_le_bytes([a, b]);
            (v as u32, v as i16 as i32)
        }
        [a, b, c, d] => {
            let v = u32::from_le_bytes([a, b, c, d]);
            (v, v as i32)
        }
        _ => return None,
    })
}

/// Appends the payload in hex plus its little-endian integer reading for 1, 2 or 4 bytes
/// (`AA BA (47786)`; with the signed reading when the top bit is set: `FF FF (65535, -1)`).
pub fn push_payload(out: &mut String, payload: &[u8]) {
    push_data(out, payload);
}

/// [`push_payload`]; returns where the reading's unsigned number stands in `out` and its
/// value, `None` for a payload without a reading. A 1-byte payload's text is one copy from
/// [`DATA1`]. Inlined: the call would cost more than the length test.
#[inline(always)]
pub(super) fn push_data(out: &mut String, payload: &[u8]) -> Option<(Range<usize>, u64)> {
    if let [b] = *payload {
        // After `XX (`.
        let start = out.len() + 4;
        out.push_str(DATA1[b as usize]);
        let digits = 1 + usize::from(b >= 10) + usize::from(b >= 100);
        return Some((start..start + digits, b as u64));
    }
    push_hex(out, payload);
    let (unsigned, signed) = int_reading(payload)?;
    Some((push_reading(out, unsigned, signed), unsigned as u64))
}

/// [`push_payload`]'s text of every 1-byte payload, 16 bytes a slot (`80 (128, -128)` is the
/// longest), and its length.
const DATA1_TEXT: ([u8; 256 * 16], [usize; 256]) = {
    /// Writes `v` (below 1000) in decimal at `t[at..]`; returns the position after it.
    const fn put(t: &mut [u8; 256 * 16], mut at: usize, v: usize) -> usize {
        if v >= 100 {
            t[at] = b'0' + (v / 100) as u8;
            at += 1;
        }
        if v >= 10 {
            t[at] = b'0' + (v / 10 % 10) as u8;
            at += 1;
        }
        t[at] = b'0' + (v % 10) as u8;
        at + 1
    }
    /// An upper-case hex digit.
    const fn hex(nibble: usize) -> u8 {
        if nibble < 10 {
            b'0' + nibble as u8
        } else {
            b'A' + (nibble - 10) as u8
        }
    }
    let mut t = [b' '; 256 * 16];
    let mut lens = [0; 256];
    let mut b = 0;
    while b < 256 {
        let mut at = 16 * b;
        t[at] = hex(b >> 4);
        t[at + 1] = hex(b & 0x0F);
        t[at + 2] = b' ';
        t[at + 3] = b'(';
        at = put(&mut t, at + 4, b);
        if b >= 128 {
            t[at] = b',';
            t[at + 1] = b' ';
            t[at + 2] = b'-';
            at = put(&mut t, at + 3, 256 - b);
        }
        t[at] = b')';
        lens[b] = at + 1 - 16 * b;
        b += 1;
    }
    (t, lens)
};

/// `C6 (198, -58)`, `2A (42)`, … for every byte value: the Data cell of a 1-byte payload as
/// static strings, one copy instead of the hex, a number formatted and three pushes.
pub(super) static DATA1: [&str; 256] = {
    let (text, lens) = &DATA1_TEXT;
    let mut t = [""; 256];
    let mut b = 0;
    while b < 256 {
        let (_, rest) = text.split_at(16 * b);
        let (slot, _) = rest.split_at(lens[b]);
        t[b] = match std::str::from_utf8(slot) {
            Ok(s) => s,
            Err(_) => panic!("ASCII"),
        };
        b += 1;
    }
    t
};

/// Appends ` (unsigned)` or ` (unsigned, signed)`; returns where the unsigned number's text
/// stands in `out`. The numbers are formatted as 32-bit ones (one buffer, itoa's 32-bit
/// path).
#[inline]
pub(super) fn push_reading(out: &mut String, unsigned: u32, signed: i32) -> Range<usize> {
    let mut digits = itoa::Buffer::new();
    out.push_str(" (");
    let start = out.len();
    out.push_str(digits.format(unsigned));
    let text = start..out.len();
    if signed < 0 {
        out.push_str(", ");
        out.push_str(digits.format(signed));
    }
    out.push(')');
    text
}

/// `000` … `999`, the three decimals of a response time.
static DECIMALS3: &str = {
    const TEXT: [u8; 3000] = {
        let mut t = [0u8; 3000];
        let mut i = 0;
        while i < 1000 {
            t[3 * i] = b'0' + (i / 100) as u8;
            t[3 * i + 1] = b'0' + (i / 10 % 10) as u8;
            t[3 * i + 2] = b'0' + (i % 10) as u8;
            i += 1;
        }
        t
    };
    match std::str::from_utf8(&TEXT) {
        Ok(s) => s,
        Err(_) => panic!("ASCII"),
    }
};

/// `.000` … `.999`, the point and three decimals of a response time.
pub(super) static DOT_DECIMALS3: &str = {
    const TEXT: [u8; 4000] = {
        let mut t = [0u8; 4000];
        let mut i = 0;
        while i < 1000 {
            t[4 * i] = b'.';
            t[4 * i + 1] = b'0' + (i / 100) as u8;
            t[4 * i + 2] = b'0' + (i / 10 % 10) as u8;
            t[4 * i + 3] = b'0' + (i % 10) as u8;
            i += 1;
        }
        t
    };
    match std::str::from_utf8(&TEXT) {
        Ok(s) => s,
        Err(_) => panic!("ASCII"),
    }
};

/// [`push_ms`](crate::fmt::push_ms) for a response time: µs as milliseconds with three decimals.
pub(super) fn push_ms3(out: &mut String, micros: u64) {
    let micros = micros.min(i64::MAX as u64);
    let ms = micros / 1000;
    if ms < 10 {
        out.push(char::from(b'0' + ms as u8));
    } else {
        out.push_str(itoa::Buffer::new().format(ms));
    }
    out.push('.');
    let f = (micros % 1000) as usize;
    out.push_str(&DECIMALS3[3 * f..3 * f + 3]);
}
