//! F.Port 2 capture for `benches/c/fport2_ref.c`: what a FrSky receiver and an INAV flight
//! controller put on their one wire (115200 baud, length-prefixed frames, no stuffing).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::fport::wire;

use crate::common::Rng;

/// The physical ID byte of the flight controller (S.Port ID 27 with its check bits).
const FC: u8 = 0x1B;
/// Other physical IDs the receiver polls in turn (IDs 0, 1, 2 and 7: no one answers on this
/// line).
const OTHERS: [u8; 4] = [0x00, 0xA1, 0x22, 0x67];

/// The flight controller's sensors in turn, by app ID: battery voltage and current, fuel,
/// cell voltage, altitude, vario, heading, accelerations, GPS (latitude and longitude in
/// turn), ground speed, two temperatures (INAV's flight modes and GPS state).
const SENSORS: [u16; 14] = [
    0x0210, 0x0200, 0x0600, 0x0910, 0x0100, 0x0110, 0x0840, 0x0700, 0x0710, 0x0720, 0x0800, 0x0830,
    0x0400, 0x0410,
];

/// F.Port 2 as INAV and a FrSky receiver speak it: a control frame of 16 channels
/// (`18 FF [22 bytes] [flags] [RSSI] [crc]`) every 9 ms, each followed by the receiver's
/// downlink poll (`08 [physical ID] 00 …`): three polls in four go to the flight controller,
/// which answers (`08 1B 10 [app ID] [value] [crc]`) with its next sensor, one in 40 with a
/// null frame; the fourth goes to another ID in turn that nobody answers. The sticks move, the
/// values drift; a frame in 2500 has a flipped bit (bad checksum), one in 4000 control frames
/// is followed by 1-3 bytes of line noise. `frames` control frames in all (about 33 bytes with
/// their telemetry).
pub fn fport2(path: &Path, frames: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut ch = [992u16; 16];
    ch[4] = 172;
    ch[6] = 1811;
    let (mut lat, mut lon) = (47_376_900i32, 8_541_700i32);
    let (mut volt, mut fuel, mut alt, mut gps) = (2520u32, 100u32, 0i32, 0u32);
    let (mut next, mut other) = (0usize, 0usize);
    let mut n = 0u64;
    while n < frames {
        for (i, c) in ch.iter_mut().enumerate() {
            if i < 4 {
                let step = rng.below(33) as i32 - 16;
                *c = (i32::from(*c) + step).clamp(172, 1811) as u16;
            } else if rng.below(400) == 0 {
                *c = [172, 992, 1811][rng.below(3) as usize];
            }
        }
        let flags = match rng.below(2000) {
            0 => wire::FLAG_FRAME_LOST,
            1 => wire::FLAG_FRAME_LOST | wire::FLAG_FAILSAFE,
            _ => 0,
        };
        wire::encode_v2_control(&mut buf, &ch, flags, 80 + rng.below(21) as u8);
        spoil(&mut buf, 27, &mut rng);
        let phys = if n % 4 == 3 {
            other = (other + 1) % OTHERS.len();
            OTHERS[other]
        } else {
            FC
        };
        wire::encode_v2_telemetry(&mut buf, phys, &[0; 7]);
        spoil(&mut buf, 10, &mut rng);
        if phys == FC {
            let payload = if rng.below(40) == 0 {
                [0; 7]
            } else {
                let id = SENSORS[next];
                next = (next + 1) % SENSORS.len();
                let value: u32 = match id {
                    0x0210 => {
                        if rng.below(6) == 0 {
                            volt -= 1;
                        }
                        if volt < 1980 {
                            volt = 2520;
                        }
                        volt
                    }
                    0x0200 => rng.below(1500) as u32,
                    0x0600 => {
                        if rng.below(20) == 0 {
                            fuel = if fuel == 0 { 100 } else { fuel - 1 };
                        }
                        fuel
                    }
                    0x0910 => volt / 6,
                    0x0100 => {
                        alt = (alt + rng.below(31) as i32 - 15).clamp(-1000, 120_000);
                        alt as u32
                    }
                    0x0110 => (rng.below(1201) as i32 - 600) as u32,
                    0x0840 => rng.below(36_000) as u32,
                    0x0700..=0x0720 => (rng.below(301) as i32 - 150) as u32,
                    0x0800 => {
                        lat += rng.below(31) as i32 - 15;
                        lon += rng.below(31) as i32 - 15;
                        gps += 1;
                        if gps % 2 == 0 {
                            (lat.unsigned_abs() * 6 / 10) & 0x3FFF_FFFF
                        } else {
                            (lon.unsigned_abs() * 6 / 10) & 0x3FFF_FFFF | 0x8000_0000
                        }
                    }
                    0x0830 => rng.below(40_000) as u32,
                    0x0400 => [1u32, 2, 3, 10_001][rng.below(4) as usize],
                    _ => 1000 + rng.below(12) as u32,
                };
                wire::payload(0x10, id, value)
            };
            wire::encode_v2_telemetry(&mut buf, FC, &payload);
            spoil(&mut buf, 10, &mut rng);
        }
        if rng.below(4000) == 0 {
            for _ in 0..=rng.below(2) {
                buf.push([0xFF, 0x55, 0x00][rng.below(3) as usize]);
            }
        }
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

/// One frame in 2500 (the last `len` bytes of `buf`) gets a flipped bit in a data byte.
fn spoil(buf: &mut [u8], len: usize, rng: &mut Rng) {
    if rng.below(2500) != 0 {
        return;
    }
    let at = buf.len() - len + 2 + rng.below(len as u64 - 3) as usize;
    buf[at] ^= 1 << rng.below(8);
}
