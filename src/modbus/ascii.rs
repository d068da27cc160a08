//! Modbus ASCII framing: `:`, the frame (address, function, data, LRC) as pairs of hexadecimal
//! digits, CR LF. Frames are marked, so this framer only reads them: the LRC (the two's
//! complement of the sum of the bytes) checks a frame; a frame cut by the next `:` or by the
//! end is `Truncated`, text that is no hex is `Truncated` too, and bytes outside frames are
//! `Garbage`. Request and response are told apart as for RTU ([`super::wire`]): by the lengths
//! the function gives and the exchange in progress. A frame whose LRC checks but whose length
//! no reading gives (a vendor's function) is `Unknown`.

use super::wire::{Broken, Event, Expecting, Frame, Junk, Kind};
use crate::row::GARBAGE_ROW_MAX;

/// Longest frame text: `:`, 2 × (address, function, 252 data bytes, LRC), CR LF.
pub const MAX_TEXT: usize = 1 + 2 * 255 + 2;

/// The ASCII reassembler.
#[derive(Debug)]
pub struct AsciiFramer {
    /// The frame's text since `:` (in a frame), or a garbage run.
    text: Vec<u8>,
    in_frame: bool,
    /// Stream offset and time of `text`'s first byte.
    start: (u64, Option<u64>),
    offset: u64,
    decoded: Vec<u8>,
    expect: Expecting,
    /// A silence this long (µs) ends the text held; the time of the latest bytes.
    settle: u64,
    last: Option<u64>,
}

/// The value of a hex digit.
fn hex(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'A'..=b'F' => Some(b - b'A' + 10),
        b'a'..=b'f' => Some(b - b'a' + 10),
        _ => None,
    }
}

/// The LRC of `bytes`: the two's complement of their sum.
pub fn lrc(bytes: &[u8]) -> u8 {
    bytes
        .iter()
        .fold(0u8, |s, &b| s.wrapping_add(b))
        .wrapping_neg()
}

/// The ASCII frame of `pdu` (address, function, data): `:`, hex, LRC, CR LF.
pub fn encode(pdu: &[u8]) -> Vec<u8> {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    let mut out = vec![b':'];
    for &b in pdu.iter().chain(std::iter::once(&lrc(pdu))) {
        out.push(HEX[(b >> 4) as usize]);
        out.push(HEX[(b & 15) as usize]);
    }
    out.extend_from_slice(b"\r\n");
    out
}

impl AsciiFramer {
    pub fn new(timeout: u64) -> Self {
        AsciiFramer {
            text: Vec::with_capacity(MAX_TEXT),
            in_frame: false,
            start: (0, None),
            offset: 0,
            decoded: Vec::with_capacity(256),
            expect: Expecting::new(timeout),
            settle: super::wire::SETTLE_MIN,
            last: None,
        }
    }

    /// A framer whose held text ends after a silence of `settle` µs (see
    /// [`super::wire::Framer::settling_after`]).
    pub fn settling_after(mut self, settle: u64) -> Self {
        self.settle = settle.max(super::wire::SETTLE_MIN);
        self
    }

    /// The text held after a settling silence: a cut frame or garbage.
    fn settle(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        let what = if self.in_frame {
            Broken::Truncated
        } else {
            Broken::Garbage
        };
        self.give(what, emit);
        self.in_frame = false;
    }

    /// Time passed on a live line without bytes.
    pub fn idle(&mut self, now: u64, emit: &mut impl FnMut(&Event<'_>)) {
        if self
            .last
            .is_some_and(|last| now > last.saturating_add(self.settle))
        {
            self.settle(emit);
        }
    }

    pub fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if data.is_empty() {
            return;
        }
        if let (Some(t), Some(last)) = (time, self.last)
            && t > last.saturating_add(self.settle)
        {
            self.settle(emit);
        }
        if time.is_some() {
            self.last = time;
        }
        for &b in data {
            self.byte(b, time, emit);
            self.offset += 1;
        }
    }

    /// The arrival time of the first byte held (a frame in progress, or garbage).
    pub fn held_since(&self) -> Option<u64> {
        (!self.text.is_empty()).then_some(self.start.1).flatten()
    }

    pub fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.settle(emit);
        self.expect.forget();
    }

    fn begin(&mut self, b: u8, time: Option<u64>) {
        if self.text.is_empty() {
            self.start = (self.offset, time);
        }
        self.text.push(b);
    }

    fn byte(&mut self, b: u8, time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
        if b == b':' {
            let what = if self.in_frame {
                Broken::Truncated
            } else {
                Broken::Garbage
            };
            self.give(what, emit);
            self.in_frame = true;
            self.begin(b, time);
            return;
        }
        self.begin(b, time);
        if !self.in_frame {
            if self.text.len() >= GARBAGE_ROW_MAX {
                self.give(Broken::Garbage, emit);
            }
            return;
        }
        if b == b'\n' {
            self.frame(emit);
        } else if self.text.len() >= MAX_TEXT {
            self.give(Broken::Truncated, emit);
            self.in_frame = false;
        }
    }

    /// Gives out `text` as broken bytes.
    fn give(&mut self, what: Broken, emit: &mut impl FnMut(&Event<'_>)) {
        if what == Broken::BadCrc {
            self.expect.broken(&self.decoded);
        }
        if !self.text.is_empty() {
            emit(&Event::Junk(Junk {
                bytes: &self.text,
                what,
                offset: self.start.0,
                time: self.start.1,
            }));
            self.text.clear();
        }
    }

    /// `text` is `:` … LF: a frame, checked.
    fn frame(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        self.in_frame = false;
        let body = &self.text[1..self.text.len() - 1];
        let body = body.strip_suffix(b"\r").unwrap_or(body);
        self.decoded.clear();
        let mut good = body.len().is_multiple_of(2) && body.len() >= 6;
        for p in body.chunks_exact(2) {
            match (hex(p[0]), hex(p[1])) {
                (Some(h), Some(l)) => self.decoded.push(h << 4 | l),
                _ => good = false,
            }
        }
        if !good {
            return self.give(Broken::Truncated, emit);
        }
        if lrc(&self.decoded) != 0 {
            return self.give(Broken::BadCrc, emit);
        }
        let time = self.start.1;
        let n = self.decoded.len();
        let (kind, ambiguous) = self
            .expect
            .kind_of(&self.decoded, n + 1, time)
            .unwrap_or((Kind::Unknown, false));
        emit(&Event::Frame(Frame {
            bytes: &self.text,
            pdu: &self.decoded[..n - 1],
            kind,
            offset: self.start.0,
            time,
            ambiguous,
        }));
        self.expect.after(kind, &self.decoded, time);
        self.text.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn events(data: &[u8]) -> Vec<(String, Vec<u8>)> {
        let run = |pieces: &mut dyn Iterator<Item = &[u8]>| {
            let mut f = AsciiFramer::new(1_000_000);
            let mut out = Vec::new();
            let mut take = |e: &Event<'_>| {
                out.push(match e {
                    Event::Frame(f) => (format!("{:?}", f.kind), f.pdu.to_vec()),
                    Event::Junk(j) => (format!("{:?}", j.what), j.bytes.to_vec()),
                })
            };
            for p in pieces {
                f.push(p, None, &mut take);
            }
            f.finish(&mut take);
            out
        };
        let whole = run(&mut std::iter::once(data));
        assert_eq!(whole, run(&mut data.chunks(1)));
        whole
    }

    #[test]
    fn pymodbus_ascii_frame() {
        // pymodbus test_multidrop.py: slave 0x11 reads 2 holding registers from 0x007C
        let ev = events(b":1103007C00026E\r\n");
        assert_eq!(
            ev,
            vec![("Request".into(), vec![0x11, 0x03, 0x00, 0x7C, 0x00, 0x02])]
        );
        assert_eq!(
            encode(&[0x11, 0x03, 0x00, 0x7C, 0x00, 0x02]),
            b":1103007C00026E\r\n"
        );
    }

    #[test]
    fn exchange_garbage_and_broken_frames() {
        let req = encode(&[0x01, 0x03, 0x00, 0x00, 0x00, 0x01]);
        let resp = encode(&[0x01, 0x03, 0x02, 0x12, 0x34]);
        let exc = encode(&[0x01, 0x83, 0x02]);
        let mut all = b"xx".to_vec();
        all.extend(&req);
        all.extend(&resp);
        all.extend(&req);
        all.extend(&exc);
        all.extend(b":0103");
        all.extend(&req);
        all.extend(b":0103000000010F\r\n"); // wrong LRC
        all.extend(b":01GG\r\n");
        all.extend(encode(&[0x01, 0x41, 0x05]));
        all.extend(b":0103");
        let kinds: Vec<String> = events(&all).into_iter().map(|e| e.0).collect();
        assert_eq!(
            kinds,
            [
                "Garbage",
                "Request",
                "Response",
                "Request",
                "Exception",
                "Truncated",
                "Request",
                "BadCrc",
                "Truncated",
                "Unknown",
                "Truncated"
            ]
        );
        // a write and its echo
        let w = encode(&[0x01, 0x06, 0x00, 0x01, 0x00, 0x03]);
        let kinds: Vec<String> = events(&[w.clone(), w].concat())
            .into_iter()
            .map(|e| e.0)
            .collect();
        assert_eq!(kinds, ["Request", "Response"]);
    }
}
