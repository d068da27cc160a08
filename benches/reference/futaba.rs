//! Futaba SBUS / SBUS2 capture for `futaba_ref.c` (raw wire bytes, as an inverting adapter
//! hands them on at 100000 baud 8E2).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::futaba::wire::{self, CHANNELS};

use crate::common::Rng;

/// Futaba SBUS: `frames` channel frames, in runs of 500 from a plain SBUS receiver (end byte
/// 00) and from an SBUS2 receiver (end bytes 04, 14, 24, 34 in turn, each group followed by
/// the answers of its sensors: the receiver's voltage in slot 0 and sensors in slots 1-3 and
/// 8-10, 16 and 17, 24; one answer in 50 missing). Four sticks move, two switches flip now and
/// then, the other channels sit at 992; one frame in 100 has frame lost set, one in 1000
/// failsafe too, one in 300 CH17/CH18. Now and then the line is disturbed: one frame in 2000
/// is followed by 1-6 bytes of noise, one in 5000 loses a byte, one in 10000 has a wrong end
/// byte. Returns the number of frames.
pub fn futaba(path: &Path, frames: u64) -> std::io::Result<u64> {
    // The sensors answering in each group.
    let groups: [&[u8]; 4] = [&[0, 1, 2, 3], &[8, 9, 10], &[16, 17], &[24]];
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut rng = Rng(0x5B05_2F0A_17C3_9E61);
    let mut buf = Vec::with_capacity(1 << 16);
    let mut frame = Vec::with_capacity(32);
    let mut ch = [992u16; CHANNELS];
    let mut values = [0u16; 32];
    for (n, v) in values.iter_mut().enumerate() {
        *v = 0x8000 | (n as u16) << 8;
    }
    let mut group = 0usize;
    for n in 0..frames {
        for c in &mut ch[..4] {
            let step = rng.below(81) as i32 - 40;
            *c = (i32::from(*c) + step).clamp(172, 1811) as u16;
        }
        if rng.below(200) == 0 {
            ch[4] = [172, 992, 1811][rng.below(3) as usize];
        }
        if rng.below(500) == 0 {
            ch[5] = if ch[5] == 172 { 1811 } else { 172 };
        }
        let mut flags = 0;
        if rng.below(100) == 0 {
            flags |= wire::FLAG_FRAME_LOST;
            if rng.below(10) == 0 {
                flags |= wire::FLAG_FAILSAFE;
            }
        }
        if rng.below(300) == 0 {
            flags |= wire::FLAG_CH17 | wire::FLAG_CH18;
        }
        let sbus2 = (n / 500) % 2 == 1;
        let end = if sbus2 {
            [0x04, 0x14, 0x24, 0x34][group]
        } else {
            0
        };
        frame.clear();
        wire::encode_frame(&mut frame, &ch, flags, end);
        match rng.below(10_000) {
            0 => frame[24] = 0x77, // a wrong end byte
            1 | 2 => {
                frame.remove(1 + rng.below(23) as usize); // a byte lost
            }
            _ => {}
        }
        buf.extend_from_slice(&frame);
        if sbus2 {
            for &slot in groups[group] {
                if rng.below(50) == 0 {
                    continue;
                }
                let v = &mut values[usize::from(slot)];
                *v = v.wrapping_add(rng.below(7) as u16).wrapping_sub(3);
                wire::encode_slot(&mut buf, slot, *v);
            }
            group = (group + 1) % 4;
        }
        if rng.below(2000) == 0 {
            for _ in 0..1 + rng.below(6) {
                buf.push(0x40 | rng.below(0x40) as u8);
            }
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
