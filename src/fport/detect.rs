//! Telling the framings apart (`--variant auto`), and F.Port from its neighbours.
//!
//! Both reassemblers read the stream until one of them has found enough frames of a known
//! shape: a framing is chosen when it has at least [`LOCK_FRAMES`] and [`LOCK_MARGIN`] more
//! for every one the other framing found. Until then the bytes are held (at most
//! [`HOLD_BYTES`]) and replayed through the chosen reassembler, so no row is lost. When the
//! limit is reached, the input ends, or a live source stays undecided for [`HOLD_MICROS`], the
//! framing with more frames wins (F.Port 2 on a tie). The rule is applied after every byte, so
//! the choice does not depend on how the input was split.
//!
//! ## F.Port v1 and S.Port
//!
//! Both start frames with 0x7E and stuff the same way. What tells them apart ([`evidence`]
//! counts only frames that have all of it):
//!
//! * the byte after 0x7E: F.Port v1 has a length, 0x08 (telemetry) or 0x19 (control); as an
//!   S.Port header neither has valid check bits (the headers of physical IDs 8 and 25 are 0x48
//!   and 0x39);
//! * the byte after that: the F.Port type 0x00 (control), 0x01 (downlink) or 0x81 (uplink);
//! * the length: a control frame is 29 bytes between its delimiters, where an S.Port slot is 2
//!   (a poll) or 10;
//! * the checksum covers the length and the type byte (S.Port's covers the 7 bytes after the
//!   header), so an S.Port frame read as F.Port v1 (or the other way round) fails it.
//!
//! F.Port 2 has no 0x7E at all: `18 FF` control frames and `08` telemetry frames right after
//! them, checksummed from the type byte.

use super::Framing;
use super::frame::{Check, Event, Frame, Role};
use super::v1::V1;
use super::v2::V2;
use super::wire::{V1_CONTROL_LEN, V1_TELEMETRY_LEN};

/// Frames of one framing needed to choose it.
pub const LOCK_FRAMES: u64 = 3;
/// Extra frames needed per frame of the other framing.
pub const LOCK_MARGIN: u64 = 3;
/// Bytes held at most while undecided (about 1.4 s at 115200 baud).
pub const HOLD_BYTES: usize = 16 * 1024;
/// A live source that stays undecided this long (µs) is decided by majority.
pub const HOLD_MICROS: u64 = 1_000_000;

/// The lock rule: `Some(framing)` once one framing has clearly won.
pub fn lock(v1: u64, v2: u64) -> Option<Framing> {
    if v1 >= LOCK_FRAMES + LOCK_MARGIN * v2 {
        Some(Framing::V1)
    } else if v2 >= LOCK_FRAMES + LOCK_MARGIN * v1 {
        Some(Framing::V2)
    } else {
        None
    }
}

/// The fallback rule: more frames wins, F.Port 2 on a tie.
pub fn majority(v1: u64, v2: u64) -> Framing {
    if v1 > v2 { Framing::V1 } else { Framing::V2 }
}

/// Whether `f` is a frame of a known F.Port shape with a valid checksum (what detection
/// counts: frames of an unknown type or length pass by chance too often).
pub fn known(framing: Framing, f: &Frame<'_>) -> bool {
    if f.check != Check::Ok {
        return false;
    }
    match (framing, f.role) {
        (_, Role::Unknown) => false,
        (Framing::V1, Role::Control) => f.body[0] == V1_CONTROL_LEN,
        (Framing::V1, _) => f.body[0] == V1_TELEMETRY_LEN,
        // F.Port 2 recognises only known shapes; a direction it had to guess is weaker.
        (Framing::V2, _) => !f.guessed,
    }
}

/// How much of a stretch of bytes is F.Port, in each framing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Evidence {
    /// Bytes examined.
    pub total: u64,
    /// Frames of a known shape with a valid checksum, and the bytes in them.
    pub v1_frames: u64,
    pub v1_bytes: u64,
    pub v2_frames: u64,
    pub v2_bytes: u64,
}

impl Evidence {
    /// The framing that covers more bytes, if any frame was found.
    pub fn framing(&self) -> Option<Framing> {
        match (self.v1_bytes, self.v2_bytes) {
            (0, 0) => None,
            (a, b) if a > b => Some(Framing::V1),
            _ => Some(Framing::V2),
        }
    }

    /// Share of the bytes (0 to 1) inside valid frames of the better framing.
    pub fn share(&self) -> f64 {
        if self.total == 0 {
            return 0.0;
        }
        self.v1_bytes.max(self.v2_bytes) as f64 / self.total as f64
    }
}

/// Reads `bytes` in both framings and counts what is F.Port. Scores near 1 on F.Port traffic
/// and near 0 on S.Port (see the module documentation), SBUS or noise.
pub fn evidence(bytes: &[u8]) -> Evidence {
    let mut e = Evidence {
        total: bytes.len() as u64,
        ..Evidence::default()
    };
    let count = |framing: Framing, ev: Event<'_>, frames: &mut u64, n: &mut u64| {
        if let Event::Frame(f) = ev
            && known(framing, &f)
        {
            *frames += 1;
            *n += f.raw.len() as u64;
        }
    };
    let (mut f1, mut b1, mut f2, mut b2) = (0, 0, 0, 0);
    let mut v1 = V1::new();
    v1.push(bytes, None, &mut |ev| {
        count(Framing::V1, ev, &mut f1, &mut b1)
    });
    v1.finish(&mut |ev| count(Framing::V1, ev, &mut f1, &mut b1));
    let mut v2 = V2::new();
    v2.push(bytes, None, &mut |ev| {
        count(Framing::V2, ev, &mut f2, &mut b2)
    });
    v2.finish(&mut |ev| count(Framing::V2, ev, &mut f2, &mut b2));
    (e.v1_frames, e.v1_bytes, e.v2_frames, e.v2_bytes) = (f1, b1, f2, b2);
    e
}
