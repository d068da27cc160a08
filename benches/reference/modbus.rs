//! A Modbus RTU capture of what `benches/c/modbus_ref.c` covers: raw bytes without times, as
//! `busnoop modbus FILE` reads them (its rows are byte-identical to the C decoder's).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::modbus::function::{Dir, Len, frame_len};
use busnoop::modbus::wire::{crc_ok, push_crc};

use crate::common::Rng;

/// The polled slaves. None of them is the function code of a broadcastable write (5, 6, 15,
/// 16, 21, 22), so that a turnaround `00` before a request (address 0, then the slave's
/// address as a function code) never reads as the start of a broadcast.
const SLAVES: [u8; 8] = [1, 2, 3, 4, 7, 9, 10, 17];

/// `pdu` with its CRC, its byte `at` (inside every shorter reading) first changed until no reading of the frame shorter than
/// itself checks by chance (one frame in 65,536 would, and busnoop would rightly take that
/// shorter frame): the capture holds the frames it means to.
fn framed(mut pdu: Vec<u8>, at: usize, rng: &mut Rng) -> Vec<u8> {
    loop {
        push_crc(&mut pdu);
        let n = pdu.len();
        let chance = [Dir::Request, Dir::Response]
            .into_iter()
            .any(|d| match frame_len(&pdu, d) {
                Len::Known(m) if (4..n).contains(&m) => crc_ok(&pdu[..m]),
                _ => false,
            });
        if !chance {
            return pdu;
        }
        pdu.truncate(n - 2);
        pdu[at] = rng.next() as u8;
    }
}

/// A master polling eight slaves over RS-485: reads of holding registers (1-32, now and then
/// 125), input registers (1-16) and coils (1-64), writes of a single register and of 1-10
/// registers, each answered (echo or start and count); 3 % of the reads answered by an
/// exception; 1 % of the requests unanswered the first time, sent again once (answered half of
/// the time); one write in 20 broadcast; a turnaround byte (`00` or `FF`) after a fifth of the
/// frames; one read response in 2000 with a bit flipped (`BadCRC`). `exchanges` exchanges;
/// returns the bytes written.
pub fn modbus(path: &Path, exchanges: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x5DEE_CE66_D1CE_4E5B);
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 20);
    let mut written = 0u64;
    // A turnaround byte after the last frame: written before the next one.
    let mut turn = false;
    let mut frame = |buf: &mut Vec<u8>, rng: &mut Rng, bytes: &[u8]| {
        if turn {
            buf.push(if rng.below(2) == 0 { 0x00 } else { 0xFF });
        }
        buf.extend_from_slice(bytes);
        turn = rng.below(5) == 0;
    };
    for _ in 0..exchanges {
        let slave = SLAVES[rng.below(SLAVES.len() as u64) as usize];
        let kind = rng.below(100);
        let start = if rng.below(4) == 0 {
            rng.below(4000) as u16
        } else {
            rng.below(200) as u16
        };
        let [sh, sl] = start.to_be_bytes();
        // The request, and the response to it (`None`: a broadcast).
        let (req, resp): (Vec<u8>, Option<Vec<u8>>) = match kind {
            0..=57 => {
                // read holding (3) or input (4) registers
                let fc = if kind < 38 { 3 } else { 4 };
                let count = match (fc, rng.below(50)) {
                    (3, 0) => 125,
                    (3, _) => 1 + rng.below(32) as u16,
                    _ => 1 + rng.below(16) as u16,
                };
                let mut resp = vec![slave, fc, (2 * count) as u8];
                for _ in 0..count {
                    let v = if rng.below(3) == 0 {
                        rng.below(1000) as u16
                    } else {
                        rng.next() as u16
                    };
                    resp.extend_from_slice(&v.to_be_bytes());
                }
                let [ch, cl] = count.to_be_bytes();
                (vec![slave, fc, sh, sl, ch, cl], Some(resp))
            }
            58..=72 => {
                // read coils
                let count = 1 + rng.below(64) as u16;
                let mut resp = vec![slave, 1, count.div_ceil(8) as u8];
                for i in 0..count.div_ceil(8) {
                    let mut b = rng.next() as u8;
                    if 8 * (i + 1) > count {
                        b &= (1u16 << (count % 8)).wrapping_sub(1) as u8;
                    }
                    resp.push(b);
                }
                (vec![slave, 1, sh, sl, 0, count as u8], Some(resp))
            }
            73..=87 => {
                // write single register: the echo
                let v = (rng.next() as u16).to_be_bytes();
                let req = vec![slave, 6, sh, sl, v[0], v[1]];
                (req.clone(), Some(req))
            }
            _ => {
                // write multiple registers: start and count back
                let count = 1 + rng.below(10) as u8;
                let mut req = vec![slave, 16, sh, sl, 0, count, 2 * count];
                for _ in 0..2 * count {
                    req.push(rng.next() as u8);
                }
                (req, Some(vec![slave, 16, sh, sl, 0, count]))
            }
        };
        let broadcast = matches!(req[1], 6 | 16) && rng.below(20) == 0;
        let mut req = req;
        if broadcast {
            req[0] = 0;
        }
        // A chance frame is avoided by another start address (reads) or value (writes).
        let at = if req[1] <= 4 { 3 } else { 7 };
        let req = framed(req, at, &mut rng);
        frame(&mut buf, &mut rng, &req);
        let Some(mut resp) = resp.filter(|_| !broadcast) else {
            continue;
        };
        if rng.below(100) == 0 {
            // no answer: the master sends the request again
            frame(&mut buf, &mut rng, &req);
            if rng.below(2) == 0 {
                continue;
            }
        }
        if resp[1] <= 4 && rng.below(33) == 0 {
            let code = [2, 2, 2, 1, 3, 4, 6][rng.below(7) as usize];
            resp = vec![slave, resp[1] | 0x80, code];
        }
        let mut resp = framed(resp, 3, &mut rng);
        if matches!(resp[1], 3 | 4) && rng.below(2000) == 0 {
            // a bit flipped after the byte count
            let at = 3 + rng.below(resp.len() as u64 - 3) as usize;
            resp[at] ^= 1 << rng.below(8);
        }
        frame(&mut buf, &mut rng, &resp);
        if buf.len() >= 1 << 20 {
            out.write_all(&buf)?;
            written += buf.len() as u64;
            buf.clear();
        }
    }
    out.write_all(&buf)?;
    written += buf.len() as u64;
    out.flush()?;
    Ok(written)
}
