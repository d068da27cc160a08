//! Captures of what the C reference decoders cover (`benches/c/`), so that their output and
//! busnoop's are byte-identical: every row is real work for both, none falls back to a generic
//! row.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::pcap::write as pw;
use busnoop::sbus::telegram::{CrcBasis, encode_data, encode_ether};
use busnoop::sport::wire;

use crate::common::Rng;

/// S.Port: the receiver polls the present sensors in turn and one absent ID after each
/// round; 10 % of the polls go unanswered, a third are answered by a keep-alive, the rest by
/// data frames of the common sensors (scalars, FLVSS cells, GPS coordinates), a quarter of the
/// values with a byte that needs stuffing, one frame in a thousand with a bad CRC. `polls`
/// slots in all.
pub fn sport(path: &Path, polls: u64) -> std::io::Result<u64> {
    let sensors: &[(u8, &[u16])] = &[
        (0, &[0x0100, 0x0110]),
        (1, &[0x0300]),
        (2, &[0x0200, 0x0210]),
        (3, &[0x0800, 0x0820, 0x0830, 0x0840]),
        (4, &[0x0500, 0x0400, 0x0410]),
        (9, &[0x0A00]),
        (22, &[0x0D00, 0x0D20, 0x0D40]),
        (26, &[0x0600, 0x0900]),
    ];
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut n = 0;
    let mut absent = 5u8;
    while n < polls {
        for &(phys, ids) in sensors {
            let header = wire::header_for(phys);
            match rng.below(20) {
                0 | 1 => wire::encode_poll(&mut buf, header),
                2..=7 => wire::encode_raw(&mut buf, header, &[0, 0, 0, 0, 0, 0, 0, 0xFF]),
                _ => {
                    let app_id = ids[rng.below(ids.len() as u64) as usize];
                    let mut value = rng.next() as u32;
                    if app_id == 0x0300 {
                        // FLVSS: cell index and count in the low byte
                        let count = 1 + rng.below(6) as u32;
                        let index = rng.below(count as u64) as u32 & !1;
                        value = (value & 0xFFFF_FF00) | count << 4 | index;
                    }
                    if rng.below(4) == 0 {
                        value = (value & 0xFFFF_0000) | 0x7E7D; // stuffing
                    }
                    if rng.below(1000) == 0 {
                        let mut body = [0x10, app_id as u8, (app_id >> 8) as u8, 0, 0, 0, 0, 0];
                        body[3..7].copy_from_slice(&value.to_le_bytes());
                        body[7] = wire::crc(&body[..7]) ^ 0x55;
                        wire::encode_raw(&mut buf, header, &body);
                    } else {
                        wire::encode_frame(&mut buf, header, 0x10, app_id, value);
                    }
                }
            }
            n += 1;
        }
        wire::encode_poll(&mut buf, wire::header_for(absent));
        absent = if absent == 8 { 5 } else { absent + 1 };
        n += 1;
        if buf.len() > 1 << 20 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    out.write_all(&buf)?;
    out.flush()?;
    Ok(n)
}

/// Ether-S-Bus: 4 clients polling 8 PLCs over UDP port 5050: register reads of 1-16
/// registers (60 %), register writes of 1-4 values (38 %), both answered (reads with their
/// values, writes with an ACK), 2 % of the reads answered by a NAK. `packets` packets.
pub fn ether(path: &Path, packets: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut buf = Vec::with_capacity(1 << 16);
    pw::header(&mut buf, 1);
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut t: i64 = 1_750_000_000_000_000;
    let mut seq = [[0u16; 8]; 4];
    let mut payload = Vec::with_capacity(256);
    let mut frame = Vec::with_capacity(512);
    let mut n = 0;
    while n < packets {
        let c = rng.below(4) as usize;
        let p = rng.below(8) as usize;
        let client = ([192, 168, 1, 10 + c as u8], 40_000 + c as u16);
        let plc = ([192, 168, 1, 100 + p as u8], 5050);
        let station = 1 + p as u8;
        seq[c][p] = seq[c][p].wrapping_add(1);
        let s = seq[c][p];
        let addr = rng.below(2000) as u16;
        let [ah, al] = addr.to_be_bytes();
        let kind = rng.below(100);
        let mut req = vec![station];
        let (at, resp): (u8, Vec<u8>) = if kind < 2 {
            req.extend_from_slice(&[0x06, 0, ah, al]);
            (2, vec![0, 1])
        } else if kind < 62 {
            let cnt = 1 + rng.below(16) as u8;
            req.extend_from_slice(&[0x06, cnt - 1, ah, al]);
            (1, (0..4 * cnt as usize).map(|_| rng.next() as u8).collect())
        } else {
            let cnt = 1 + rng.below(4) as u8;
            req.extend_from_slice(&[0x0E, 4 * cnt + 1, ah, al]);
            req.extend((0..4 * cnt).map(|_| rng.next() as u8));
            (2, vec![0, 0])
        };
        for (at, from, to, bytes) in [(0, client, plc, &req), (at, plc, client, &resp)] {
            payload.clear();
            encode_ether(&mut payload, s, at, bytes);
            frame.clear();
            pw::udp4_frame(&mut frame, from, to, &payload);
            pw::record(&mut buf, t, &frame);
            t += if at == 0 {
                300 + rng.below(2000) as i64
            } else {
                100 + rng.below(500) as i64
            };
        }
        n += 2;
        if buf.len() > 1 << 20 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    out.write_all(&buf)?;
    out.flush()?;
    Ok(n)
}

/// Serial S-Bus in data mode: a master polling eight stations: reads of 1-8 registers, timers
/// or counters answered with their values (a quarter of the register values need DLE
/// escaping), writes of one or two of them answered by an ACK, 2 % NAKs. About `bytes` bytes.
pub fn sbus_data(path: &Path, bytes: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut written = 0;
    while written < bytes {
        buf.clear();
        for _ in 0..1024 {
            let station = 1 + rng.below(8) as u8;
            let addr = rng.below(1000) as u16;
            let [ah, al] = addr.to_be_bytes();
            // registers, timers, counters: read and write commands
            let (read, write) =
                [(0x06, 0x0E), (0x06, 0x0E), (0x07, 0x0F), (0x00, 0x0A)][rng.below(4) as usize];
            if rng.below(10) < 7 {
                let cnt = 1 + rng.below(8) as u8;
                encode_data(
                    &mut buf,
                    0,
                    &[station, read, cnt - 1, ah, al],
                    CrcBasis::Escaped,
                );
                if rng.below(50) == 0 {
                    encode_data(&mut buf, 2, &[0, 1], CrcBasis::Escaped);
                    continue;
                }
                let mut data = Vec::with_capacity(4 * cnt as usize);
                for _ in 0..cnt {
                    let mut v = rng.next() as u32;
                    if rng.below(4) == 0 {
                        v = (v & 0xFFFF_0000) | 0xB5C5;
                    }
                    data.extend_from_slice(&v.to_be_bytes());
                }
                encode_data(&mut buf, 1, &data, CrcBasis::Escaped);
            } else {
                let cnt = 1 + rng.below(2) as u8;
                let mut req = vec![station, write, 4 * cnt + 1, ah, al];
                req.extend((0..4 * cnt).map(|_| rng.next() as u8));
                encode_data(&mut buf, 0, &req, CrcBasis::Escaped);
                encode_data(&mut buf, 2, &[0, 0], CrcBasis::Escaped);
            }
        }
        out.write_all(&buf)?;
        written += buf.len() as u64;
    }
    out.flush()?;
    Ok(written)
}
