//! GHST capture for `benches/c/ghst_ref.c`: what an ImmersionRC Ghost receiver and a Betaflight
//! flight controller put on their one half-duplex wire (420000 baud): the receiver's RC frames
//! to the flight controller (0x82) and, in the slot after every other one, the flight
//! controller's telemetry to the receiver (0x89).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::crsf::wire;

use crate::common::Rng;

/// The receiver's address (telemetry goes to it) and the flight controller's.
const RX: u8 = 0x89;
const FC: u8 = 0x82;

/// A Ghost receiver into Betaflight: RC frames of the 12-bit scale in turn 0x30 (CH5-8), 0x31
/// (CH9-12), 0x32 (CH13-16) and 0x33 (link quality, RSSI, RF protocol, power), ten payload bytes
/// each (Betaflight's `GHST_UL_RC_CHANS_SIZE`); after every other one a telemetry frame of the
/// flight controller, in turn battery 0x23, GPS 0x25, GPS 2 0x26 and magnetometer/baro 0x27
/// (ten payload bytes, zero-padded, as Betaflight's `ghstInitializeFrame` sends them). The
/// sticks move, the values drift. One frame in 2000 has a bad CRC (when no frame may start
/// inside it), one in 5000 is followed by 1-4 bytes of line noise. `frames` frames in all (14
/// bytes each).
pub fn ghst(path: &Path, frames: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0xBB67_AE85_84CA_A73B);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut payload = Vec::with_capacity(16);
    let mut ch = [2048u16; 4];
    let mut aux = [128u8; 12];
    aux[0] = 0;
    aux[1] = 255;
    let (mut lat, mut lon, mut alt) = (473_977_000i32, 86_000_000i32, 420i16);
    let (mut volt, mut cap) = (1680u16, 0u16);
    let (mut head, mut balt) = (0i16, 0i16);
    let mut n = 0u64;
    let mut tick = 0u64;
    while n < frames {
        let rc_ty = 0x30 + (tick % 4) as u8;
        let mut now: [(u8, u8); 2] = [(FC, rc_ty), (0, 0)];
        if tick % 2 == 1 {
            now[1] = (RX, [0x23, 0x25, 0x26, 0x27][(tick / 2 % 4) as usize]);
        }
        tick += 1;
        for (addr, ty) in now {
            if ty == 0 {
                continue;
            }
            payload.clear();
            match ty {
                0x30..=0x33 => {
                    for c in &mut ch {
                        let step = rng.below(81) as i32 - 40;
                        *c = (i32::from(*c) + step).clamp(0, 4095) as u16;
                    }
                    payload.extend_from_slice(&wire::pack_bits(&ch, 12));
                    if ty == 0x33 {
                        payload.extend_from_slice(&[
                            if rng.below(20) == 0 {
                                60 + rng.below(40) as u8
                            } else {
                                100
                            },
                            40 + rng.below(60) as u8,
                            [0x05u8, 0x06, 0x07, 0x08, 0x0A][rng.below(5) as usize],
                            [10u8, 14, 20, 24][rng.below(4) as usize],
                        ]);
                    } else {
                        let first = usize::from(ty - 0x30) * 4;
                        for a in &mut aux[first..first + 4] {
                            if rng.below(300) == 0 {
                                *a = [0, 128, 255][rng.below(3) as usize];
                            }
                        }
                        payload.extend_from_slice(&aux[first..first + 4]);
                    }
                }
                0x23 => {
                    if rng.below(8) == 0 {
                        volt -= 1;
                    }
                    if volt < 1320 {
                        volt = 1680;
                    }
                    cap = cap.wrapping_add(rng.below(3) as u16);
                    payload.extend_from_slice(&volt.to_le_bytes());
                    payload.extend_from_slice(&(rng.below(6000) as u16).to_le_bytes());
                    payload.extend_from_slice(&cap.to_le_bytes());
                    payload.push(48 + rng.below(5) as u8);
                }
                0x25 => {
                    lat += rng.below(201) as i32 - 100;
                    lon += rng.below(201) as i32 - 100;
                    alt = (alt + rng.below(5) as i16 - 2).clamp(-20, 900);
                    let lon_s = if rng.below(50) == 0 { -lon } else { lon };
                    payload.extend_from_slice(&lat.to_le_bytes());
                    payload.extend_from_slice(&lon_s.to_le_bytes());
                    payload.extend_from_slice(&alt.to_le_bytes());
                }
                0x26 => {
                    payload.extend_from_slice(&(rng.below(3000) as u16).to_le_bytes());
                    payload.extend_from_slice(&(rng.below(3600) as u16).to_le_bytes());
                    payload.push(5 + rng.below(15) as u8);
                    payload.extend_from_slice(&(rng.below(2000) as u16).to_le_bytes());
                    payload.extend_from_slice(&(rng.below(3600) as u16).to_le_bytes());
                    payload.push(if rng.below(100) == 0 { 0 } else { 3 });
                }
                _ => {
                    head = (head + rng.below(21) as i16 - 10).rem_euclid(3600);
                    balt = (balt + rng.below(5) as i16 - 2).clamp(-50, 500);
                    payload.extend_from_slice(&head.to_le_bytes());
                    payload.extend_from_slice(&balt.to_le_bytes());
                    payload.push((rng.below(201) as i16 - 100) as i8 as u8);
                    payload.extend_from_slice(&[0, 0, 0, 0]);
                    payload.push(if rng.below(50) == 0 { 6 } else { 7 });
                }
            }
            payload.resize(10, 0);
            let start = buf.len();
            wire::encode(&mut buf, addr, ty, &payload);
            if rng.below(2000) == 0 {
                let last = buf.len() - 1;
                buf[last] ^= 1 << rng.below(8);
                // Kept only when no frame may start inside it (else a chance CRC match there
                // would make a frame of noise, which the C reference leaves out).
                let f = &buf[start..];
                let may_start = (1..f.len()).any(|q| {
                    busnoop::ghst::ADDRESSES[usize::from(f[q])]
                        && f.get(q + 1).is_none_or(|&l| (2..=62).contains(&l))
                });
                if may_start {
                    buf[last] = wire::crc8(&buf[start + 2..last]);
                }
            }
            if rng.below(5000) == 0 {
                for _ in 0..=rng.below(3) {
                    buf.push([0xFF, 0x7F, 0xFE, 0x55][rng.below(4) as usize]);
                }
            }
            n += 1;
        }
        if buf.len() > 1 << 20 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    out.write_all(&buf)?;
    out.flush()?;
    Ok(n)
}
