//! The Data cell and the numbers of the common frames written in one pass: requests and
//! responses of functions 1-6, 15 and 16 of a slave without names in the register map. The
//! text is exactly what [`super::pdu::describe`] writes (`start=100 count=2`, `R100=615
//! R101=3`, `C7=1`), and its numbers are recorded as spans of it ([`Parts::Spans`]): no names
//! and texts are built a second time, and a table that shows the first number alone reads
//! no more. Every other frame goes through `describe`; tests compare both.

use super::pairing::Req;
use super::pdu::{Content, byte_count_note, coil_note, count_note, word};
use super::wire::Kind;
use crate::row::{PartSpan, Parts};

/// Room for the longest Data cell of these frames: at most 2016 numbers (the coils of a
/// 253-byte PDU) and 2 more, each at most 24 bytes with what a number may write past it.
/// Every number is below 10^8: values are 16 bits, addresses at most 65535 + 2015.
const ROOM: usize = 64 * 1024;

/// Writes `v` (below 10^8) in decimal at `w[at..]`, which has room for 8 bytes (bytes after
/// the number may be overwritten); returns its length. The method of `crate::digits`, inlined
/// here for the many small numbers of a register list.
#[inline(always)]
fn digits(w: &mut [u8], at: usize, v: u32) -> usize {
    debug_assert!(v < 100_000_000);
    // abcd | efgh << 32
    let merged = (v / 10_000) as u64 | ((v % 10_000) as u64) << 32;
    // ab, ef: / 100 in each 32-bit lane
    let top = ((merged * 10_486) >> 20) & (0x7F << 32 | 0x7F);
    let bottom = merged - 100 * top;
    // ab | cd << 16 | ef << 32 | gh << 48
    let hundreds = (bottom << 16) + top;
    // the tens in the low byte of each 16-bit lane, the units in the high byte
    let mut d = ((hundreds * 103) >> 10) & (0xF << 48 | 0xF << 32 | 0xF << 16 | 0xF);
    d += (hundreds - 10 * d) << 8;
    // without the leading zeros (in the low bytes, which come first)
    let lead = if v == 0 {
        7
    } else {
        (d.trailing_zeros() / 8) as usize
    };
    w[at..at + 8].copy_from_slice(&((d >> (lead * 8)) | 0x3030_3030_3030_3030).to_le_bytes());
    8 - lead
}

/// The Data cell being written and its numbers.
pub(super) struct Fast {
    buf: Vec<u8>,
    len: usize,
    spans: Vec<PartSpan>,
}

impl Default for Fast {
    fn default() -> Self {
        Fast {
            buf: vec![0; ROOM],
            len: 0,
            spans: Vec::new(),
        }
    }
}

impl Fast {
    /// The Data cell.
    #[inline]
    pub fn text(&self) -> &str {
        // Only ASCII is written.
        std::str::from_utf8(&self.buf[..self.len]).unwrap_or_default()
    }

    /// The numbers, as spans of [`Fast::text`].
    #[inline]
    pub fn parts<'a>(&'a self, text: &'a str) -> Parts<'a> {
        Parts::Spans {
            text,
            spans: &self.spans,
        }
    }

    #[inline(always)]
    fn begin(&mut self) -> usize {
        if self.len > 0 {
            self.buf[self.len] = b' ';
            self.len += 1;
        }
        self.len
    }

    #[inline(always)]
    fn value(&mut self, start: usize, v: u32) {
        let eq = self.len;
        self.buf[eq] = b'=';
        self.len += 1 + digits(&mut self.buf, eq + 1, v);
        self.spans.push(PartSpan {
            start: start as u32,
            eq: eq as u32,
            end: self.len as u32,
            value: f64::from(v),
        });
    }

    /// `name=v`.
    #[inline(always)]
    fn named(&mut self, name: &[u8], v: u32) {
        let start = self.begin();
        self.buf[start..start + name.len()].copy_from_slice(name);
        self.len += name.len();
        self.value(start, v);
    }

    /// `R<addr>=v` (`letter` R or C), or `R+<i>=v` without an address.
    #[inline(always)]
    fn reg(&mut self, letter: u8, addr: Option<u32>, i: usize, v: u32) {
        let start = self.begin();
        self.buf[start] = letter;
        self.len += 1;
        match addr {
            Some(a) => self.len += digits(&mut self.buf, self.len, a),
            None => {
                self.buf[self.len] = b'+';
                self.len += 1;
                self.len += digits(&mut self.buf, self.len, i as u32);
            }
        }
        self.value(start, v);
    }

    fn start_count(&mut self, d: &[u8]) -> (u16, u16) {
        let (start, count) = (word(d, 0), word(d, 2));
        self.named(b"start", start.into());
        self.named(b"count", count.into());
        (start, count)
    }

    fn registers(&mut self, bytes: &[u8], start: Option<u16>) {
        for (i, p) in bytes.chunks_exact(2).enumerate() {
            let addr = start.map(|s| u32::from(s) + i as u32);
            self.reg(b'R', addr, i, u32::from(u16::from_be_bytes([p[0], p[1]])));
        }
    }

    fn coils(&mut self, bytes: &[u8], start: Option<u16>, count: usize) {
        for i in 0..count.min(bytes.len() * 8) {
            let v = (bytes[i / 8] >> (i % 8)) & 1;
            self.reg(b'C', start.map(|s| u32::from(s) + i as u32), i, v.into());
        }
    }

    fn coil(&mut self, c: &mut Content, addr: u16, v: u16) {
        match v {
            0xFF00 | 0x0000 => self.reg(b'C', Some(addr.into()), 0, u32::from(v != 0)),
            _ => coil_note(c, v),
        }
    }

    /// Writes the Data cell and numbers of a checked frame's content `pdu` (address, function,
    /// data; no CRC) of `kind` (`req`: the request a response was paired with), with its notes
    /// into `c`, as `describe` does without a register map; `false` (nothing written) for a
    /// frame this does not cover.
    pub fn describe(&mut self, pdu: &[u8], kind: Kind, req: Option<&Req>, c: &mut Content) -> bool {
        self.len = 0;
        self.spans.clear();
        let fc = pdu[1];
        let d = &pdu[2..];
        match (kind, fc) {
            (Kind::Request, 1..=4) => {
                let (_, count) = self.start_count(d);
                count_note(c, count, if fc <= 2 { 2000 } else { 125 });
            }
            (Kind::Request, 5) => {
                let addr = word(d, 0);
                self.named(b"start", addr.into());
                self.named(b"count", 1);
                self.coil(c, addr, word(d, 2));
            }
            (Kind::Request, 6) => {
                let addr = word(d, 0);
                self.named(b"start", addr.into());
                self.named(b"count", 1);
                self.registers(d.get(2..4).unwrap_or_default(), Some(addr));
            }
            (Kind::Request, 15) => {
                let (start, count) = self.start_count(d);
                count_note(c, count, 1968);
                byte_count_note(c, d.get(4), (count as usize).div_ceil(8));
                self.coils(d.get(5..).unwrap_or_default(), Some(start), count as usize);
            }
            (Kind::Request, 16) => {
                let (start, count) = self.start_count(d);
                count_note(c, count, 123);
                byte_count_note(c, d.get(4), 2 * count as usize);
                self.registers(d.get(5..).unwrap_or_default(), Some(start));
            }
            (Kind::Response, 1 | 2) => {
                let req = req.filter(|r| r.function == fc);
                let bytes = d.get(1..).unwrap_or_default();
                let count = match req {
                    Some(r) => {
                        byte_count_note(c, d.first(), (r.count as usize).div_ceil(8));
                        r.count as usize
                    }
                    None => bytes.len() * 8,
                };
                self.coils(bytes, req.map(|r| r.start), count);
            }
            (Kind::Response, 3 | 4) => {
                let req = req.filter(|r| r.function == fc);
                let bytes = d.get(1..).unwrap_or_default();
                if let Some(r) = req
                    && bytes.len() != 2 * r.count as usize
                {
                    byte_count_note(c, d.first(), 2 * r.count as usize);
                }
                self.registers(bytes, req.map(|r| r.start));
            }
            (Kind::Response, 5) => self.coil(c, word(d, 0), word(d, 2)),
            (Kind::Response, 6) => {
                self.registers(d.get(2..4).unwrap_or_default(), Some(word(d, 0)));
            }
            (Kind::Response, 15 | 16) => {
                self.start_count(d);
            }
            _ => return false,
        }
        debug_assert!(self.len + 32 <= ROOM);
        true
    }
}
