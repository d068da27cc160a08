//! A cursor over a payload: numbers in either byte order and NUL-terminated text, each `None`
//! once the payload ends (the TBS text: "don't try to read optional fields beyond frame
//! payload").

/// Reads fields from the front of a payload.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reader<'a> {
    rest: &'a [u8],
    /// Bytes read so far.
    pub pos: usize,
}

impl<'a> Reader<'a> {
    pub fn new(payload: &'a [u8]) -> Self {
        Reader {
            rest: payload,
            pos: 0,
        }
    }

    /// The bytes not read yet.
    pub fn rest(&self) -> &'a [u8] {
        self.rest
    }

    pub fn bytes(&mut self, n: usize) -> Option<&'a [u8]> {
        if self.rest.len() < n {
            return None;
        }
        let (a, b) = self.rest.split_at(n);
        self.rest = b;
        self.pos += n;
        Some(a)
    }

    fn array<const N: usize>(&mut self) -> Option<[u8; N]> {
        self.bytes(N).and_then(|b| b.try_into().ok())
    }

    pub fn u8(&mut self) -> Option<u8> {
        self.array::<1>().map(|[b]| b)
    }

    pub fn i8(&mut self) -> Option<i8> {
        self.u8().map(|b| b as i8)
    }

    pub fn be_u16(&mut self) -> Option<u16> {
        self.array().map(u16::from_be_bytes)
    }

    pub fn be_i16(&mut self) -> Option<i16> {
        self.array().map(i16::from_be_bytes)
    }

    pub fn be_u24(&mut self) -> Option<u32> {
        self.array::<3>()
            .map(|[a, b, c]| u32::from_be_bytes([0, a, b, c]))
    }

    /// A signed 24-bit number, sign-extended.
    pub fn be_i24(&mut self) -> Option<i32> {
        self.be_u24().map(|v| ((v << 8) as i32) >> 8)
    }

    pub fn be_u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_be_bytes)
    }

    pub fn be_i32(&mut self) -> Option<i32> {
        self.array().map(i32::from_be_bytes)
    }

    pub fn le_u16(&mut self) -> Option<u16> {
        self.array().map(u16::from_le_bytes)
    }

    pub fn le_i16(&mut self) -> Option<i16> {
        self.array().map(i16::from_le_bytes)
    }

    pub fn le_u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_le_bytes)
    }

    pub fn le_i32(&mut self) -> Option<i32> {
        self.array().map(i32::from_le_bytes)
    }

    /// Text up to a NUL (consumed) or the end of the payload; `terminated` tells which.
    pub fn cstr(&mut self) -> (&'a [u8], bool) {
        match self.rest.iter().position(|&b| b == 0) {
            Some(n) => {
                let t = &self.rest[..n];
                self.rest = &self.rest[n + 1..];
                self.pos += n + 1;
                (t, true)
            }
            None => {
                let t = self.rest;
                self.pos += t.len();
                self.rest = &[];
                (t, false)
            }
        }
    }
}

/// Appends `text` as printable ASCII: other bytes as `\xNN`.
pub(crate) fn push_text(out: &mut String, text: &[u8]) {
    for &b in text {
        if (0x20..0x7F).contains(&b) {
            out.push(b as char);
        } else {
            out.push_str("\\x");
            crate::fmt::push_hex_u8(out, b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_fields_and_stops_at_the_end() {
        let mut r = Reader::new(&[0xFF, 0x80, 0x00, 0x01, b'A', b'B', 0, 0x12, 0x34]);
        assert_eq!(r.be_i24(), Some(-32768));
        assert_eq!(r.u8(), Some(1));
        assert_eq!(r.cstr(), (&b"AB"[..], true));
        assert_eq!(r.pos, 7);
        assert_eq!(r.be_u32(), None);
        assert_eq!(r.le_u16(), Some(0x3412));
        assert_eq!(r.u8(), None);
        let mut s = String::new();
        push_text(&mut s, b"ok\x01");
        assert_eq!(s, "ok\\x01");
    }
}
