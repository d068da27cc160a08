//! The demo sessions `fixtures/sab1-session.bin` and `fixtures/sab2-session.bin`, built with
//! the encoders (a test regenerates them and compares). Try:
//!
//! ```sh
//! busnoop sab2 fixtures/sab2-session.bin --device drive=1 --device sonar=5 --device imu=0x12 \
//!     --command speed=2 --command distance=0x10 --command heading=0x34 --stats
//! ```

use super::frame::Framing;
use super::header::{Flags, header};
use super::{hdlc, sync};

/// Appends one frame in `framing`.
pub fn frame(out: &mut Vec<u8>, framing: Framing, flags: Flags, addr: u8, cmd: u8, data: &[u8]) {
    let h = header(flags, addr);
    match framing {
        Framing::Sync => sync::encode(out, h, cmd, data),
        Framing::Hdlc => hdlc::encode(out, h, cmd, data),
    }
}

/// The demo session: a master polling three slaves, with a NACK of each system code kind, an
/// escaped payload, a corrupted frame, line noise, a request without a response and one cut
/// off by the end of the capture.
pub fn session(framing: Framing) -> Vec<u8> {
    use Flags::{Ack, Nack, Request};
    let mut w = Vec::new();
    let f = framing;
    // drive (1): set speed 0x55 (the frame of modm's SAB2 example), ACK.
    frame(&mut w, f, Request, 0x01, 0x02, &[0x55]);
    frame(&mut w, f, Ack, 0x01, 0x02, &[]);
    // sonar (5): read distance, ACK with a u16.
    frame(&mut w, f, Request, 0x05, 0x10, &[]);
    frame(&mut w, f, Ack, 0x05, 0x10, &291u16.to_le_bytes());
    // imu (0x12): heading with a u32 argument, ACK with a u32.
    frame(
        &mut w,
        f,
        Request,
        0x12,
        0x34,
        &0xDEAD_BEEFu32.to_le_bytes(),
    );
    frame(&mut w, f, Ack, 0x12, 0x34, &0x1234_5678u32.to_le_bytes());
    // sonar: unknown command → NACK NO_ACTION.
    frame(&mut w, f, Request, 0x05, 0x11, &[]);
    frame(&mut w, f, Nack, 0x05, 0x11, &[0x01]);
    // sonar: distance with an unexpected argument → NACK WRONG_PAYLOAD_LENGTH.
    frame(&mut w, f, Request, 0x05, 0x10, &[0x01]);
    frame(&mut w, f, Nack, 0x05, 0x10, &[0x02]);
    // slave 7 does not answer: the next request closes the query (Timeout).
    frame(&mut w, f, Request, 0x07, 0x10, &[]);
    // drive: speed 0x7E (SAB2 escapes it), ACK echoes 0x7D.
    frame(&mut w, f, Request, 0x01, 0x02, &[0x7E]);
    frame(&mut w, f, Ack, 0x01, 0x02, &[0x7D]);
    // Line noise between two queries; in SAB v1 a stray 0x54 with a plausible LENGTH that
    // modm's receiver would follow for 35 bytes, hiding the next two frames.
    match framing {
        Framing::Sync => w.extend_from_slice(&[0x00, 0x54, 0x20]),
        Framing::Hdlc => w.extend_from_slice(&[0x00, 0x13, 0x37]),
    }
    frame(
        &mut w,
        f,
        Request,
        0x12,
        0x34,
        &0x0000_0001u32.to_le_bytes(),
    );
    // The imu's answer is corrupted (one payload bit flipped): BadCRC, then no valid answer.
    let start = w.len();
    frame(&mut w, f, Ack, 0x12, 0x34, &0x0000_0002u32.to_le_bytes());
    let flip = match framing {
        Framing::Sync => start + 4,
        Framing::Hdlc => start + 3,
    };
    w[flip] ^= 0x04;
    // The master retries (the first query times out at the retry).
    frame(
        &mut w,
        f,
        Request,
        0x12,
        0x34,
        &0x0000_0001u32.to_le_bytes(),
    );
    frame(&mut w, f, Ack, 0x12, 0x34, &0x0000_0002u32.to_le_bytes());
    // A user-defined error code.
    frame(&mut w, f, Request, 0x01, 0x03, &[0x10, 0x27]);
    frame(&mut w, f, Nack, 0x01, 0x03, &[0x21]);
    // The capture ends right after a request.
    frame(&mut w, f, Request, 0x05, 0x10, &[]);
    w
}
