//! modm SAB replay benchmark: generates a large raw capture in each framing with a realistic mix
//! of traffic and measures decode-only throughput (framing detected and forced) and the to-TSV
//! throughput and peak memory of the binary, pinned to one core.
//!
//! ```sh
//! cargo bench --bench sab_replay                    # 128 MiB per framing
//! BUSNOOP_BENCH_MB=512 cargo bench --bench sab_replay
//! ```
//!
//! The captures are written to `target/bench-data/` and reused while their size matches.

mod common;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Duration;

use busnoop::sab::frame::Framing;
use busnoop::sab::header::Flags;
use busnoop::sab::{FramingChoice, Options, SabDecoder, sample};
use common::{Rng, best_of, busnoop, children_peak_kb, decode_file, pin_to_core0};

/// Writes about `target` bytes of SAB traffic: a master polls five slaves with their commands;
/// a slave answers with an ACK carrying 0 to 8 bytes (90 %), a NACK (6 %) or not at all (3 %),
/// and 1 % of the time a corrupted ACK; a quarter of the payloads contain 0x7E/0x7D/0x54.
pub fn generate(path: &Path, framing: Framing, target: u64) -> u64 {
    let mut out = BufWriter::new(File::create(path).unwrap());
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    // (address, commands)
    let slaves: [(u8, &[u8]); 5] = [
        (0x01, &[0x02, 0x03]),
        (0x05, &[0x10, 0x11, 0x12]),
        (0x12, &[0x34]),
        (0x20, &[0x01, 0x02, 0x40, 0x41]),
        (0x3F, &[0x7E, 0x54]),
    ];
    let mut written = 0u64;
    let mut buf = Vec::with_capacity(1 << 16);
    let mut payload = Vec::new();
    while written < target {
        buf.clear();
        for _ in 0..256 {
            for &(addr, cmds) in &slaves {
                let cmd = cmds[rng.below(cmds.len() as u64) as usize];
                payload.clear();
                for _ in 0..rng.below(5) {
                    payload.push(rng.next() as u8);
                }
                sample::frame(&mut buf, framing, Flags::Request, addr, cmd, &payload);
                payload.clear();
                for _ in 0..rng.below(9) {
                    payload.push(rng.next() as u8);
                }
                if rng.below(4) == 0 {
                    payload.extend_from_slice(&[0x7E, 0x7D, 0x54]);
                }
                match rng.below(100) {
                    0..=2 => {}
                    3..=8 => sample::frame(&mut buf, framing, Flags::Nack, addr, cmd, &[0x01]),
                    9 => {
                        let start = buf.len();
                        sample::frame(&mut buf, framing, Flags::Ack, addr, cmd, &payload);
                        buf[start + 2] ^= 0x01;
                    }
                    _ => sample::frame(&mut buf, framing, Flags::Ack, addr, cmd, &payload),
                }
            }
        }
        out.write_all(&buf).unwrap();
        written += buf.len() as u64;
    }
    out.flush().unwrap();
    written
}

fn decode_only(path: &Path, framing: FramingChoice) -> (Duration, u64) {
    decode_file(
        path,
        &mut SabDecoder::new(Options {
            framing,
            ..Options::default()
        }),
    )
}

fn to_tsv(path: &Path) -> (Duration, u64) {
    let t = common::time_command(busnoop().args(["sab2", "-f", "tsv"]).arg(path))
        .expect("busnoop failed");
    (t, children_peak_kb())
}

fn main() {
    // `cargo bench` passes `--bench`; ignore arguments.
    let mb = common::env_u64("BUSNOOP_BENCH_MB", 128);
    let runs = common::env_u64("BUSNOOP_BENCH_RUNS", 3).max(1);
    let dir = common::data_dir();
    pin_to_core0();
    println!("modm SAB replay benchmark, pinned to CPU 0, best of {runs} runs");
    for (framing, forced) in [
        (Framing::Sync, FramingChoice::Sync),
        (Framing::Hdlc, FramingChoice::Hdlc),
    ] {
        let path = dir.join(format!("sab-{}-{mb}mib.bin", framing.name()));
        let target = mb << 20;
        let size = match std::fs::metadata(&path) {
            Ok(m) if m.len() >= target && m.len() < target + (1 << 20) => m.len(),
            _ => {
                eprintln!("generating {} ...", path.display());
                generate(&path, framing, target)
            }
        };
        let mib = size as f64 / (1 << 20) as f64;
        println!(
            "{} capture {} ({mib:.0} MiB)",
            framing.protocol(),
            path.display()
        );
        let _ = decode_only(&path, forced); // warm the page cache
        for (label, choice) in [("forced", forced), ("detected", FramingChoice::Auto)] {
            let (t, rows) = best_of(runs, || decode_only(&path, choice));
            let secs = t.as_secs_f64();
            println!(
                "  decode only, framing {label}: {:.1} MiB/s, {:.2} M rows/s ({rows} rows in {secs:.2} s)",
                mib / secs,
                rows as f64 / secs / 1e6
            );
        }
        let (t, peak) = best_of(runs, || to_tsv(&path));
        let secs = t.as_secs_f64();
        println!(
            "  busnoop sab2 -f tsv > /dev/null (detected): {:.1} MiB/s ({secs:.2} s), peak RSS {peak} kB",
            mib / secs
        );
    }
}
