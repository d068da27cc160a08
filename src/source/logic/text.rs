//! Text traces, read line by line: Saleae's CSV exports (edges, and the Async Serial
//! analyzer's characters): their lines, fields and times.

use std::io::{self, Read};

use super::Opened;

/// Seconds as a decimal (`-1.5`, `0.000123`, `1.2e-05`) in picoseconds, rounded toward zero;
/// `None` if it is not a number or out of range.
pub fn parse_seconds(text: &[u8]) -> Option<i128> {
    let text = text.trim_ascii();
    let (neg, text) = match text.first()? {
        b'-' => (true, &text[1..]),
        b'+' => (false, &text[1..]),
        _ => (false, text),
    };
    let (mant, exp) = match text.iter().position(|&b| b == b'e' || b == b'E') {
        Some(i) => {
            let e = std::str::from_utf8(&text[i + 1..]).ok()?;
            let e: i32 = e.parse().ok()?;
            (&text[..i], e)
        }
        None => (text, 0),
    };
    let (int, frac) = match mant.iter().position(|&b| b == b'.') {
        Some(i) => (&mant[..i], &mant[i + 1..]),
        None => (mant, &mant[..0]),
    };
    if int.is_empty() && frac.is_empty() {
        return None;
    }
    let mut value: i128 = 0;
    for &b in int.iter().chain(frac) {
        if !b.is_ascii_digit() || value > 10_i128.pow(30) {
            return None;
        }
        value = value * 10 + i128::from(b - b'0');
    }
    // Powers of ten to multiply by to get picoseconds.
    let scale = 12 + i64::from(exp) - i64::try_from(frac.len()).ok()?;
    if scale >= 0 {
        if scale > 24 {
            return (value == 0).then_some(0);
        }
        value = value.checked_mul(10_i128.pow(scale as u32))?;
    } else {
        value /= 10_i128.pow((-scale).min(38) as u32);
    }
    Some(if neg { -value } else { value })
}

/// Reads lines (without their line end) of at most `max` bytes; a longer line is cut there and
/// flagged.
pub struct Lines {
    reader: Box<dyn Read + Send>,
    buf: Vec<u8>,
    pos: usize,
    filled: usize,
    eof: bool,
    line: Vec<u8>,
    max: usize,
    /// Lines read so far.
    pub number: u64,
}

impl Lines {
    pub fn new(opened: Opened, max: usize) -> Self {
        let filled = opened.prefix.len();
        Lines {
            reader: opened.reader,
            buf: opened.prefix,
            pos: 0,
            filled,
            eof: false,
            line: Vec::new(),
            max,
            number: 0,
        }
    }

    /// The next line, whether it was too long (cut) and its number; `None` at the end.
    pub fn next_line(&mut self) -> io::Result<Option<(&[u8], bool, u64)>> {
        self.line.clear();
        let mut long = false;
        loop {
            if self.pos >= self.filled {
                if self.eof {
                    if self.line.is_empty() && !long {
                        return Ok(None);
                    }
                    break;
                }
                self.buf.resize(64 * 1024, 0);
                self.pos = 0;
                self.filled = loop {
                    match self.reader.read(&mut self.buf) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        Err(e) => return Err(e),
                    }
                };
                self.eof = self.filled == 0;
                continue;
            }
            let rest = &self.buf[self.pos..self.filled];
            let (part, found) = match memchr::memchr(b'\n', rest) {
                Some(i) => (&rest[..i], true),
                None => (rest, false),
            };
            let room = self.max.saturating_sub(self.line.len());
            if part.len() > room {
                long = true;
            }
            self.line.extend_from_slice(&part[..part.len().min(room)]);
            self.pos += part.len() + usize::from(found);
            if found {
                break;
            }
        }
        self.number += 1;
        if self.line.last() == Some(&b'\r') {
            self.line.pop();
        }
        let line = if self.number == 1 {
            self.line
                .strip_prefix(b"\xEF\xBB\xBF")
                .unwrap_or(&self.line)
        } else {
            &self.line[..]
        };
        Ok(Some((line, long, self.number)))
    }
}

/// Splits a CSV line into fields (`out`: their ranges in `line`, without blanks and the
/// double quotes around them; commas inside quotes are kept).
pub fn split_fields(line: &[u8], out: &mut Vec<(usize, usize)>) {
    out.clear();
    let mut start = 0;
    let mut quoted = false;
    for (i, &b) in line.iter().enumerate() {
        match b {
            b'"' => quoted = !quoted,
            b',' if !quoted => {
                out.push(field_range(line, start, i));
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(field_range(line, start, line.len()));
}

fn field_range(line: &[u8], mut a: usize, mut b: usize) -> (usize, usize) {
    while a < b && line[a].is_ascii_whitespace() {
        a += 1;
    }
    while b > a && line[b - 1].is_ascii_whitespace() {
        b -= 1;
    }
    if b >= a + 2 && line[a] == b'"' && line[b - 1] == b'"' {
        (a + 1, b - 1)
    } else {
        (a, b)
    }
}
