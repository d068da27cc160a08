//! CRSF capture for `benches/c/crsf_ref.c`: what an ExpressLRS receiver and a Betaflight flight
//! controller put on their wires, merged into one raw file (as `busnoop crsf RX TX` reads both).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::crsf::wire;

use crate::common::Rng;

/// The flight modes Betaflight reports (`*`: disarmed).
const MODES: [&[u8]; 8] = [
    b"ACRO", b"ACRO*", b"ANGL", b"HOR", b"AIR", b"!FS!", b"WAIT*", b"MANU",
];

/// ELRS at 500 Hz into a flight controller: RC channels (0x16) back to back, link statistics
/// (0x14) after every tenth of them, and the FC's telemetry in between (attitude after every
/// fourth RC frame, and in turn battery 0x08, GPS 0x02 and flight mode 0x21 after every
/// twelfth); the sticks move, the values drift. One frame in 2000 has a bad CRC (when no frame may start inside it), one in 5000
/// is followed by 1-4 bytes of line noise. `frames` frames in all (about 22 bytes each).
pub fn crsf(path: &Path, frames: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x6A09_E667_F3BC_C908);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut payload = Vec::with_capacity(64);
    let mut ch = [992u16; 16];
    ch[4] = 172;
    ch[5] = 1811;
    let (mut lat, mut lon, mut alt) = (473_977_000i32, 86_000_000i32, 1_120u16);
    let (mut volt, mut cap) = (168i16, 0u32);
    let (mut pitch, mut roll, mut yaw) = (0i16, 0i16, 0i16);
    let mut n = 0u64;
    let mut tick = 0u64;
    while n < frames {
        tick += 1;
        // (type, present)
        let mut frames_now: [(u8, bool); 3] = [(0x16, true), (0, false), (0, false)];
        if tick.is_multiple_of(10) {
            frames_now[1] = (0x14, true);
        }
        if tick.is_multiple_of(4) {
            frames_now[2] = (0x1E, true);
        } else if tick % 12 == 2 {
            frames_now[2] = ([0x08, 0x02, 0x21][(tick / 12 % 3) as usize], true);
        }
        for (ty, on) in frames_now {
            if !on {
                continue;
            }
            payload.clear();
            match ty {
                0x16 => {
                    for (i, c) in ch.iter_mut().enumerate() {
                        if i < 4 {
                            let step = rng.below(41) as i32 - 20;
                            *c = (i32::from(*c) + step).clamp(172, 1811) as u16;
                        } else if rng.below(500) == 0 {
                            *c = [172, 992, 1811][rng.below(3) as usize];
                        }
                    }
                    payload.extend_from_slice(&wire::pack_bits(&ch, 11));
                }
                0x14 => {
                    let rssi = 30 + rng.below(70) as u8;
                    payload.extend_from_slice(&[
                        rssi,
                        rssi + rng.below(6) as u8,
                        if rng.below(20) == 0 {
                            70 + rng.below(30) as u8
                        } else {
                            100
                        },
                        (rng.below(30) as i8 - 10) as u8,
                        rng.below(2) as u8,
                        [4u8, 5, 6, 7][rng.below(4) as usize],
                        [1u8, 2, 3, 7][rng.below(4) as usize],
                        40 + rng.below(60) as u8,
                        90 + rng.below(11) as u8,
                        (rng.below(20) as i8 - 5) as u8,
                    ]);
                }
                0x08 => {
                    if rng.below(8) == 0 {
                        volt -= 1;
                    }
                    if volt < 132 {
                        volt = 168;
                    }
                    cap += rng.below(5) as u32;
                    let curr = rng.below(600) as i16;
                    payload.extend_from_slice(&volt.to_be_bytes());
                    payload.extend_from_slice(&curr.to_be_bytes());
                    payload.extend_from_slice(&cap.to_be_bytes()[1..]);
                    payload.push(((volt - 132) * 100 / 36) as u8);
                }
                0x02 => {
                    lat += rng.below(201) as i32 - 100;
                    lon += rng.below(201) as i32 - 100;
                    alt = (i32::from(alt) + rng.below(5) as i32 - 2).clamp(900, 1500) as u16;
                    let lon_s = if rng.below(50) == 0 { -lon } else { lon };
                    payload.extend_from_slice(&lat.to_be_bytes());
                    payload.extend_from_slice(&lon_s.to_be_bytes());
                    payload.extend_from_slice(&(rng.below(1200) as u16).to_be_bytes());
                    payload.extend_from_slice(&(rng.below(36000) as u16).to_be_bytes());
                    payload.extend_from_slice(&alt.to_be_bytes());
                    payload.push(5 + rng.below(15) as u8);
                }
                0x1E => {
                    let walk = |v: &mut i16, rng: &mut Rng, lim: i16| {
                        *v = (*v + rng.below(201) as i16 - 100).clamp(-lim, lim);
                    };
                    walk(&mut pitch, &mut rng, 15_707);
                    walk(&mut roll, &mut rng, 31_415);
                    walk(&mut yaw, &mut rng, 31_415);
                    for v in [pitch, roll, yaw] {
                        payload.extend_from_slice(&v.to_be_bytes());
                    }
                }
                _ => {
                    payload.extend_from_slice(MODES[rng.below(MODES.len() as u64) as usize]);
                    payload.push(0);
                }
            }
            let start = buf.len();
            wire::encode(&mut buf, 0xC8, ty, &payload);
            if rng.below(2000) == 0 {
                let last = buf.len() - 1;
                buf[last] ^= 1 << rng.below(8);
                // Kept only when no frame may start inside it (else a chance CRC match there
                // would make a frame of noise, which the C reference leaves out).
                let f = &buf[start..];
                let may_start = (1..f.len()).any(|q| {
                    wire::CRSF_ADDRESSES[usize::from(f[q])]
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
            debug_assert!(buf.len() > start);
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
