//! modm SAB: a capture of what `benches/c/sab_ref.c` covers (SAB2 framing), built with
//! busnoop's own frame encoder (`busnoop::sab::sample::frame`).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::sab::frame::Framing;
use busnoop::sab::header::Flags;
use busnoop::sab::sample::frame;

use crate::common::Rng;

/// SAB2 (0x7E flags, byte stuffing, CRC-16/MODBUS): a master querying twelve slaves one at a
/// time, back to back. Requests: 60 % sensor reads without payload, the rest with an argument
/// of 1, 2 or 4 bytes. Answers: ACKs with a reading of 2, 4 or 1 bytes, empty ACKs (writes)
/// and a few of 3 bytes (no number); 4 % NACKs (NO_ACTION, WRONG_PAYLOAD_LENGTH, a user code);
/// 5 % no answer (the next request closes the query: a Timeout row); 1 % an answer with a
/// flipped payload bit (BadCRC, then the Timeout). One payload in eight holds a 0x7E or 0x7D
/// (stuffing); the CRC bytes need it now and then. About `bytes` bytes; ends with an answer.
pub fn sab(path: &Path, bytes: u64) -> std::io::Result<u64> {
    master(path, bytes, Framing::Hdlc, 0x5AB2_0000_C0FF_EE11)
}

/// SAB v1 (`54 LEN HDR CMD DATA CRC8`): the same master as [`sab`] (twelve slaves, one
/// query at a time, the same mix of requests, ACKs, NACKs, missing answers and bad-CRC
/// answers), no stuffing: payload bytes of 0x54 come by chance (one payload byte in 256),
/// which busnoop's resynchronisation checks as possible frame starts. One exchange in 500 is
/// followed by line noise holding a 0x54 with a LENGTH above 32 (a Garbage row). About
/// `bytes` bytes; starts with a request, ends with an answer.
pub fn sab1(path: &Path, bytes: u64) -> std::io::Result<u64> {
    master(path, bytes, Framing::Sync, 0x5AB1_0000_C0FF_EE22)
}

/// The master of [`sab`] and [`sab1`] in framing `f`: SAB2 payloads hold a byte to stuff now and
/// then, a SAB v1 line has noise with a too-long LENGTH after one exchange in 500.
fn master(path: &Path, bytes: u64, f: Framing, seed: u64) -> std::io::Result<u64> {
    use Flags::{Ack, Nack, Request};
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(seed);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut written = 0;
    let hdlc = f == Framing::Hdlc;
    let payload = |rng: &mut Rng, len: usize| -> Vec<u8> {
        let mut p: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
        if hdlc && len > 0 && rng.below(8) == 0 {
            let i = rng.below(len as u64) as usize;
            p[i] = 0x7D + rng.below(2) as u8;
        }
        p
    };
    while written < bytes {
        buf.clear();
        for _ in 0..1024 {
            let addr = 1 + rng.below(12) as u8;
            let cmd = [0x01, 0x02, 0x10, 0x11, 0x20, 0x34, 0x40, 0x41][rng.below(8) as usize];
            let req_len = match rng.below(20) {
                0..=11 => 0,
                12..=15 => 1,
                16..=18 => 2,
                _ => 4,
            };
            let p = payload(&mut rng, req_len);
            frame(&mut buf, f, Request, addr, cmd, &p);
            match rng.below(100) {
                0..=3 => {
                    let code = [0x01, 0x02, 0x21][rng.below(3) as usize];
                    frame(&mut buf, f, Nack, addr, cmd, &[code]);
                }
                4..=8 => {} // no answer
                9 => {
                    // a bit flipped in the first payload byte (SAB2: when it needs no stuffing
                    // either way, else the answer stays intact)
                    let start = buf.len();
                    let p = payload(&mut rng, 2);
                    frame(&mut buf, f, Ack, addr, cmd, &p);
                    let at = start + if hdlc { 3 } else { 4 };
                    if !hdlc || !matches!(buf[at], 0x7D | 0x7E | 0x79 | 0x7A) {
                        buf[at] ^= 0x04;
                    }
                }
                r => {
                    let len = match r % 20 {
                        0..=7 => 2,
                        8..=13 => 4,
                        14..=15 => 1,
                        16..=18 => 0,
                        _ => 3,
                    };
                    let p = payload(&mut rng, len);
                    frame(&mut buf, f, Ack, addr, cmd, &p);
                }
            }
            if !hdlc && rng.below(500) == 0 {
                buf.extend_from_slice(&[0x00, 0x54, 0x80 | rng.next() as u8, 0xFF]);
            }
        }
        frame(&mut buf, f, Request, 1, 0x10, &[]);
        frame(&mut buf, f, Ack, 1, 0x10, &[0x23, 0x01]);
        out.write_all(&buf)?;
        written += buf.len() as u64;
    }
    out.flush()?;
    Ok(written)
}
