//! F.Port v1 capture for `benches/c/fport_ref.c`: what a FrSky receiver and a Betaflight flight
//! controller put on their one inverted wire (115200 baud, read through an inverting adapter).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::fport::wire;

use crate::common::Rng;

/// The flight controller's S.Port sensors in the order Betaflight's `frsky_hub`-less S.Port
/// telemetry sends them, by app ID: voltages, current, fuel, altitude, vario,
/// heading, accelerations, GPS, temperatures (Betaflight's flight-mode and GPS-state numbers).
const SENSORS: [u16; 14] = [
    0x0210, 0x0200, 0x0600, 0x0910, 0x0100, 0x0110, 0x0840, 0x0700, 0x0710, 0x0720, 0x0800, 0x0830,
    0x0400, 0x0410,
];

/// F.Port v1 as Betaflight and a FrSky receiver speak it: a control frame (16 channels, flags,
/// RSSI) every 9 ms, each followed by the receiver's telemetry poll (`7E 08 01 00 …`) and the
/// flight controller's answer (`08 81 10 [app ID][value] [crc]`, without delimiters, right
/// after the poll's closing 0x7E, as Betaflight writes it) with the next sensor in turn
/// (one poll in 50 goes unanswered). The sticks move, the values drift, byte stuffing where the
/// bytes need it. One frame in 3000 has a bad checksum, one in 5000 is followed by 1-3 bytes of
/// line noise. `frames` control frames in all (about 43 bytes with their telemetry).
pub fn fport(path: &Path, frames: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x3C6E_F372_FE94_F82B);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut ch = [992u16; 16];
    ch[4] = 172;
    ch[5] = 1811;
    let (mut lat, mut lon) = (28_438_620i32, 5_160_000i32);
    let (mut volt, mut fuel, mut alt) = (1680u32, 0u32, 0i32);
    let mut next = 0usize;
    let mut gps = 0u64;
    let mut n = 0u64;
    while n < frames {
        for (i, c) in ch.iter_mut().enumerate() {
            if i < 4 {
                let step = rng.below(41) as i32 - 20;
                *c = (i32::from(*c) + step).clamp(172, 1811) as u16;
            } else if rng.below(500) == 0 {
                *c = [172, 992, 1811][rng.below(3) as usize];
            }
        }
        let flags = if rng.below(1000) == 0 {
            wire::FLAG_FRAME_LOST
        } else {
            0
        };
        let start = buf.len();
        wire::encode_v1_control(&mut buf, &ch, flags, 90 + rng.below(11) as u8);
        spoil(&mut buf, start, 2, &mut rng);
        let start = buf.len();
        wire::encode_v1_telemetry(&mut buf, wire::V1_DOWNLINK, &[0; 7]);
        spoil(&mut buf, start, 2, &mut rng);
        if rng.below(50) != 0 {
            let id = SENSORS[next];
            next = (next + 1) % SENSORS.len();
            let value: u32 = match id {
                0x0210 => {
                    if rng.below(8) == 0 {
                        volt -= 1;
                    }
                    if volt < 1320 {
                        volt = 1680;
                    }
                    volt
                }
                0x0200 => rng.below(600) as u32,
                0x0600 => {
                    fuel = (fuel + 1) % 100;
                    fuel
                }
                0x0910 => volt / 4,
                0x0100 => {
                    alt = (alt + rng.below(21) as i32 - 10).clamp(-500, 50_000);
                    alt as u32
                }
                0x0110 => (rng.below(801) as i32 - 400) as u32,
                0x0840 => rng.below(36000) as u32,
                0x0700..=0x0720 => (rng.below(2001) as i32 - 1000) as u32,
                0x0800 => {
                    // Latitude and longitude in turn, minutes / 10000 with their flags.
                    lat += rng.below(21) as i32 - 10;
                    lon += rng.below(21) as i32 - 10;
                    gps += 1;
                    if gps.is_multiple_of(2) {
                        (lat.unsigned_abs() * 6 / 10) & 0x3FFF_FFFF
                    } else {
                        (lon.unsigned_abs() * 6 / 10) & 0x3FFF_FFFF | 0x8000_0000
                    }
                }
                0x0830 => rng.below(50_000) as u32,
                0x0400 => [1u32, 10_001, 10_002, 10_004][rng.below(4) as usize],
                _ => 1000 + rng.below(20) as u32,
            };
            // Without delimiters, right after the poll's closing 0x7E (as Betaflight writes it).
            let start = buf.len();
            wire::encode_v1_telemetry(&mut buf, wire::V1_UPLINK, &wire::payload(0x10, id, value));
            buf.pop();
            buf.remove(start);
            spoil(&mut buf, start, 1, &mut rng);
        }
        if rng.below(5000) == 0 {
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

/// One frame in 3000 (the last one, from `start`, its checksum `back` bytes before the end)
/// gets a bad checksum: a flipped bit in a byte that is neither a delimiter nor stuffed.
fn spoil(buf: &mut [u8], start: usize, back: usize, rng: &mut Rng) {
    if rng.below(3000) != 0 {
        return;
    }
    let at = buf.len() - back;
    let b = buf[at];
    let flipped = b ^ 0x01;
    if at > start + 1
        && buf[at - 1] != wire::ESCAPE
        && ![wire::START, wire::ESCAPE].contains(&b)
        && ![wire::START, wire::ESCAPE].contains(&flipped)
    {
        buf[at] = flipped;
    }
}
