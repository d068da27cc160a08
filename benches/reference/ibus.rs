//! FlySky iBUS capture for `ibus_ref.c` (raw wire bytes at 115200 baud 8N1): one line carrying
//! both the RC frames and the sensor bus, as Betaflight's shared iBUS wire does.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::ibus::wire::{self, CMD_DISCOVER, CMD_MEASURE, CMD_TYPE};

use crate::common::Rng;

/// The sensors at addresses 1-13: type code and value width.
const SENSORS: [(u8, u8); 13] = [
    (0x00, 2), // IntV
    (0x01, 2), // Temp
    (0x02, 2), // RPM
    (0x03, 2), // ExtV
    (0x04, 2), // Cels
    (0x05, 2), // Curr
    (0x06, 2), // Fuel
    (0x08, 2), // Hdg
    (0x09, 2), // VSpd
    (0x0B, 2), // Sats
    (0x80, 4), // GPS latitude
    (0x81, 4), // GPS longitude
    (0x82, 4), // GPS altitude
];

/// FlySky iBUS: the power-up command `F` ten times, the discovery of addresses 1-14 (13
/// sensors echo, 14 is empty), the type queries of the 13, then `frames` RC frames (14
/// channels; every fourth run of 1000 frames from an 18-channel receiver), each followed by
/// the measurement poll of the next sensor in turn and its answer (values drifting; the
/// external voltage reads 0x8000 now and then). One poll in 40 goes unanswered, one answer in
/// 3000 has a wrong checksum, one RC frame in 5000 is followed by 1-3 bytes of noise. Returns
/// the number of RC frames.
pub fn ibus(path: &Path, frames: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x1B05_6A3C_D2E1_0F47);
    let mut buf = Vec::with_capacity(1 << 16);
    for _ in 0..10 {
        wire::encode_poll(&mut buf, 0xF, 0);
    }
    for addr in 1..=14u8 {
        wire::encode_poll(&mut buf, CMD_DISCOVER, addr);
        if addr <= 13 {
            wire::encode_poll(&mut buf, CMD_DISCOVER, addr);
        }
    }
    for (i, &(code, size)) in SENSORS.iter().enumerate() {
        let addr = i as u8 + 1;
        wire::encode_poll(&mut buf, CMD_TYPE, addr);
        wire::encode(&mut buf, CMD_TYPE << 4 | addr, &[code, size]);
    }
    let mut ch = [1500u16; 18];
    let mut values: [i64; 13] = [
        512,
        650,
        0,
        1260,
        410,
        120,
        100,
        90,
        0,
        0x0903,
        525_200_000,
        134_050_000,
        3400,
    ];
    let mut next = 0usize;
    for n in 0..frames {
        for c in &mut ch[..4] {
            let step = rng.below(41) as i32 - 20;
            *c = (i32::from(*c) + step).clamp(1000, 2000) as u16;
        }
        if rng.below(300) == 0 {
            ch[4] = [1000, 1500, 2000][rng.below(3) as usize];
        }
        let wide = (n / 1000) % 4 == 3;
        wire::encode_rc(&mut buf, if wide { &ch[..] } else { &ch[..14] });
        if rng.below(5000) == 0 {
            for _ in 0..1 + rng.below(3) {
                buf.push(0x40 | rng.below(0x40) as u8);
            }
        }
        let i = next;
        next = (next + 1) % SENSORS.len();
        let addr = i as u8 + 1;
        wire::encode_poll(&mut buf, CMD_MEASURE, addr);
        if rng.below(40) == 0 {
            continue;
        }
        let v = &mut values[i];
        let r = rng.below(21) as i64 - 10;
        *v = match i {
            2 => (*v + 50 * r).clamp(0, 30_000),              // RPM
            6 => (*v - i64::from(rng.below(50) == 0)).max(0), // Fuel
            7 => (*v + r).rem_euclid(360),                    // heading
            8 => (*v + 5 * r).clamp(-800, 800),               // climb rate
            9 => (rng.below(4) as i64 + 7) << 8 | 3,          // satellites, fix 3
            10 | 11 => *v + 37 * r,
            _ => (*v + r).clamp(0, 20_000),
        };
        let mut raw = *v;
        if i == 3 && rng.below(1000) == 0 {
            raw = 0x8000;
        }
        let cmd = CMD_MEASURE << 4 | addr;
        if SENSORS[i].1 == 4 {
            wire::encode(&mut buf, cmd, &(raw as i32).to_le_bytes());
        } else {
            wire::encode(&mut buf, cmd, &(raw as u16).to_le_bytes());
        }
        if rng.below(3000) == 0 {
            let last = buf.len() - 1;
            buf[last] ^= 1 << rng.below(8);
        }
        if buf.len() > 1 << 20 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    out.write_all(&buf)?;
    out.flush()?;
    Ok(frames)
}
