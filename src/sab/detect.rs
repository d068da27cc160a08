//! Telling the two framings apart (`--framing auto`).
//!
//! Both reassemblers read the stream until one of them has produced enough CRC-valid frames:
//! a framing is chosen when it has at least [`LOCK_FRAMES`] valid frames and
//! [`LOCK_MARGIN`] more for every valid frame of the other framing (so three against none,
//! six against one, …). A CRC-valid frame can appear by chance in the other framing's traffic
//! (a 0x54 with a plausible LENGTH inside SAB2 data passes the CRC-8 one time in 256; a run
//! between two 0x7E inside SAB v1 data passes the CRC-16 one time in 65536), which is why one
//! stray frame of the other kind raises the bar instead of blocking the decision.
//!
//! Until then the bytes are held (at most [`HOLD_BYTES`]) and replayed through the chosen
//! reassembler, so no row is lost. When the limit is reached, the input ends, or a live source
//! stays undecided for [`HOLD_MICROS`], the framing with more valid frames wins (SAB2 on a
//! tie: it is what modm's current code sends).
//!
//! After the choice the other reassembler keeps reading in the background; when it finds
//! [`SWITCH_FRAMES`] valid frames while the chosen one finds none, busnoop switches framing
//! (a different bus, or a wrong early choice on a noisy start).

use super::frame::Framing;

/// Valid frames of one framing needed to choose it.
pub const LOCK_FRAMES: u64 = 3;
/// Extra valid frames needed per valid frame of the other framing.
pub const LOCK_MARGIN: u64 = 3;
/// Valid frames of the other framing, with none of the chosen one in between, that make
/// busnoop switch.
pub const SWITCH_FRAMES: u64 = 6;
/// Bytes held at most while undecided (about 1.4 s at 115200 baud).
pub const HOLD_BYTES: usize = 16 * 1024;
/// A live source that stays undecided this long (µs) is decided by majority.
pub const HOLD_MICROS: u64 = 1_000_000;

/// The lock rule: `Some(framing)` once one framing has clearly won.
pub fn lock(sync_valid: u64, hdlc_valid: u64) -> Option<Framing> {
    if sync_valid >= LOCK_FRAMES + LOCK_MARGIN * hdlc_valid {
        Some(Framing::Sync)
    } else if hdlc_valid >= LOCK_FRAMES + LOCK_MARGIN * sync_valid {
        Some(Framing::Hdlc)
    } else {
        None
    }
}

/// The fallback rule: more valid frames wins, SAB2 on a tie.
pub fn majority(sync_valid: u64, hdlc_valid: u64) -> Framing {
    if sync_valid > hdlc_valid {
        Framing::Sync
    } else {
        Framing::Hdlc
    }
}

/// How the framing was chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// `--framing sync|hdlc`.
    Forced,
    /// The lock rule decided.
    Locked { sync: u64, hdlc: u64 },
    /// [`HOLD_BYTES`] bytes arrived without a decision: majority.
    HoldFull { sync: u64, hdlc: u64 },
    /// The input ended before a decision: majority.
    EndOfInput { sync: u64, hdlc: u64 },
    /// A live source stayed undecided for [`HOLD_MICROS`]: majority.
    Quiet { sync: u64, hdlc: u64 },
    /// Switched from the other framing after [`SWITCH_FRAMES`] valid frames of this one and
    /// none of the other, at this stream offset.
    Switched { at: u64 },
}

impl Reason {
    /// Appends a sentence saying how `framing` was chosen.
    pub fn describe(self, framing: Framing, out: &mut String) {
        use crate::fmt::push_u64;
        let counts = |out: &mut String, sync: u64, hdlc: u64| {
            let (mine, other) = match framing {
                Framing::Sync => (sync, hdlc),
                Framing::Hdlc => (hdlc, sync),
            };
            push_u64(out, mine);
            out.push_str(if mine == 1 {
                " valid frame against "
            } else {
                " valid frames against "
            });
            push_u64(out, other);
            out.push(' ');
            out.push_str(framing.other().protocol());
        };
        out.push_str("framing ");
        out.push_str(framing.name());
        out.push_str(": ");
        out.push_str(framing.long_name());
        match self {
            Reason::Forced => out.push_str(", forced by --framing"),
            Reason::Locked { sync, hdlc } => {
                out.push_str(", detected (");
                counts(out, sync, hdlc);
                out.push(')');
            }
            Reason::HoldFull { sync, hdlc } => {
                out.push_str(", chosen by majority after ");
                push_u64(out, HOLD_BYTES as u64);
                out.push_str(" bytes (");
                counts(out, sync, hdlc);
                out.push(')');
            }
            Reason::EndOfInput { sync, hdlc } => {
                out.push_str(", chosen by majority when the input ended or was cut (");
                counts(out, sync, hdlc);
                out.push(')');
            }
            Reason::Quiet { sync, hdlc } => {
                out.push_str(", chosen by majority after a quiet second (");
                counts(out, sync, hdlc);
                out.push(')');
            }
            Reason::Switched { at } => {
                out.push_str(", switched at byte ");
                push_u64(out, at);
                out.push_str(" after ");
                push_u64(out, SWITCH_FRAMES);
                out.push_str(" valid frames and none of ");
                out.push_str(framing.other().protocol());
            }
        }
        if let Reason::HoldFull { sync: 0, hdlc: 0 }
        | Reason::EndOfInput { sync: 0, hdlc: 0 }
        | Reason::Quiet { sync: 0, hdlc: 0 } = self
        {
            out.push_str("; no valid frame of either framing yet");
        }
    }
}

/// Bytes held while undecided, with their times.
#[derive(Clone, Debug, Default)]
pub struct Held {
    bytes: Vec<u8>,
    /// `(offset, time)`: bytes from `offset` up to the next mark arrived at `time`.
    marks: Vec<(usize, Option<u64>)>,
}

/// One run of held bytes with their time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment<'a> {
    pub bytes: &'a [u8],
    pub time: Option<u64>,
}

impl Held {
    pub fn push(&mut self, b: u8, time: Option<u64>) {
        if self.marks.last().is_none_or(|&(_, t)| t != time) {
            self.marks.push((self.bytes.len(), time));
        }
        self.bytes.push(b);
    }

    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Time of the first held byte.
    pub fn first_time(&self) -> Option<u64> {
        self.marks.first().and_then(|m| m.1)
    }

    pub fn segments(&self) -> impl Iterator<Item = Segment<'_>> {
        self.marks
            .iter()
            .enumerate()
            .map(move |(i, &(start, time))| {
                let end = self.marks.get(i + 1).map_or(self.bytes.len(), |m| m.0);
                Segment {
                    bytes: &self.bytes[start..end],
                    time,
                }
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lock_rule() {
        assert_eq!(lock(0, 0), None);
        assert_eq!(lock(2, 0), None);
        assert_eq!(lock(3, 0), Some(Framing::Sync));
        assert_eq!(lock(0, 3), Some(Framing::Hdlc));
        assert_eq!(lock(5, 1), None);
        assert_eq!(lock(1, 5), None);
        assert_eq!(lock(1, 6), Some(Framing::Hdlc));
        assert_eq!(lock(6, 1), Some(Framing::Sync));
        for s in 0..50 {
            for h in 0..50 {
                if let Some(f) = lock(s, h) {
                    assert_eq!(f, majority(s, h), "{s} {h}");
                }
            }
        }
        assert_eq!(majority(0, 0), Framing::Hdlc);
        assert_eq!(majority(2, 1), Framing::Sync);
    }

    #[test]
    fn held_segments_keep_times() {
        let mut h = Held::default();
        h.push(1, Some(5));
        h.push(2, Some(5));
        h.push(3, Some(9));
        h.push(4, None);
        let segs: Vec<_> = h.segments().collect();
        assert_eq!(
            segs,
            [
                Segment {
                    bytes: &[1, 2],
                    time: Some(5)
                },
                Segment {
                    bytes: &[3],
                    time: Some(9)
                },
                Segment {
                    bytes: &[4],
                    time: None
                },
            ]
        );
        assert_eq!(h.first_time(), Some(5));
        assert_eq!(h.len(), 4);
    }

    #[test]
    fn descriptions() {
        let mut s = String::new();
        Reason::Locked { sync: 0, hdlc: 3 }.describe(Framing::Hdlc, &mut s);
        assert_eq!(
            s,
            "framing hdlc: SAB2 framing (0x7E flags, byte stuffing, CRC-16/MODBUS), detected \
             (3 valid frames against 0 SAB v1)"
        );
        s.clear();
        Reason::EndOfInput { sync: 0, hdlc: 0 }.describe(Framing::Hdlc, &mut s);
        assert!(s.ends_with("no valid frame of either framing yet"), "{s}");
    }
}
