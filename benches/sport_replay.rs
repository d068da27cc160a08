//! S.Port replay benchmark: generates a large raw capture with a realistic mix of traffic and
//! measures decode-only and to-TSV throughput and peak memory, pinned to one core.
//!
//! ```sh
//! cargo bench --bench sport_replay                  # 128 MiB capture
//! BUSNOOP_BENCH_MB=512 cargo bench --bench sport_replay
//! BUSNOOP_BENCH_MB=26000 BUSNOOP_BENCH_RUNS=1 cargo bench --bench sport_replay  # larger than RAM
//! ```
//!
//! The capture is written to `target/bench-data/` and reused while its size matches.

mod common;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::sport::{SportDecoder, wire};
use common::{Rng, best_of, busnoop, children_peak_kb, decode_file, pin_to_core0, self_peak_kb};

/// Writes about `target` bytes of S.Port traffic: the receiver polls the present devices in turn
/// and one absent ID after each round (as the S-Port_Snoop sample describes); present devices
/// answer with Null keep-alives or data frames of their sensors, with values that need stuffing.
pub fn generate(path: &Path, target: u64) -> u64 {
    let mut out = BufWriter::new(File::create(path).unwrap());
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    // (physical ID, app IDs it sends)
    let present: [(u8, &[u16]); 6] = [
        (0, &[0x0100, 0x0110]),
        (1, &[0x0300]),
        (2, &[0x0200, 0x0210]),
        (3, &[0x0800, 0x0820, 0x0830, 0x0840, 0x0850]),
        (24, &[0xF101, 0xF104, 0xF105]),
        (27, &[0x5001, 0x5002, 0x5003, 0x5004, 0x5005, 0x5006]),
    ];
    let mut absent = 0u8;
    let mut written = 0u64;
    let mut buf = Vec::with_capacity(1 << 16);
    while written < target {
        buf.clear();
        for _ in 0..256 {
            for &(phys, ids) in &present {
                let header = wire::header_for(phys);
                match rng.below(10) {
                    0 => wire::encode_poll(&mut buf, header), // no answer this time
                    1..=4 => wire::encode_raw(&mut buf, header, &[0, 0, 0, 0, 0, 0, 0, 0xFF]),
                    _ => {
                        let app_id = ids[rng.below(ids.len() as u64) as usize];
                        let mut value = rng.next() as u32;
                        if rng.below(4) == 0 {
                            value = (value & 0xFFFF_0000) | 0x7E7D; // stuffing
                        }
                        wire::encode_frame(&mut buf, header, 0x10, app_id, value);
                    }
                }
            }
            // One absent ID per round, skipping the present ones.
            loop {
                absent = (absent + 1) % 28;
                if !present.iter().any(|p| p.0 == absent) {
                    break;
                }
            }
            wire::encode_poll(&mut buf, wire::header_for(absent));
        }
        out.write_all(&buf).unwrap();
        written += buf.len() as u64;
    }
    out.flush().unwrap();
    written
}

fn main() {
    // `cargo bench` passes `--bench`; ignore arguments.
    let mb = common::env_u64("BUSNOOP_BENCH_MB", 128);
    let runs = common::env_u64("BUSNOOP_BENCH_RUNS", 3);
    let path = common::data_dir().join(format!("sport-{mb}mib.bin"));
    let target = mb << 20;
    let size = match std::fs::metadata(&path) {
        Ok(m) if m.len() >= target && m.len() < target + (1 << 20) => m.len(),
        _ => {
            eprintln!("generating {} ...", path.display());
            generate(&path, target)
        }
    };
    pin_to_core0();
    let mib = size as f64 / (1 << 20) as f64;
    println!(
        "S.Port replay benchmark, capture {} ({mib:.0} MiB), pinned to CPU 0",
        path.display()
    );

    // Warm the page cache, then take the best of the runs.
    let decode = || decode_file(&path, &mut SportDecoder::new());
    if runs > 1 {
        decode();
    }
    let (t, rows) = best_of(runs, decode);
    let secs = t.as_secs_f64();
    println!(
        "decode only: {:.1} MiB/s, {:.2} M rows/s ({rows} rows in {secs:.2} s), peak RSS {} kB",
        mib / secs,
        rows as f64 / secs / 1e6,
        self_peak_kb()
    );

    let (t, ()) = best_of(runs, || {
        let t = common::time_command(busnoop().args(["sport", "-f", "tsv"]).arg(&path))
            .expect("busnoop failed");
        (t, ())
    });
    let secs = t.as_secs_f64();
    println!(
        "busnoop sport -f tsv > /dev/null: {:.1} MiB/s, {:.2} M rows/s ({secs:.2} s), peak RSS {} kB",
        mib / secs,
        rows as f64 / secs / 1e6,
        children_peak_kb()
    );
}
