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

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use busnoop::decoder::{Decoder, Discard};
use busnoop::sport::{SportDecoder, wire};

/// A tiny deterministic PRNG (xorshift), so the capture is the same on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// Writes about `target` bytes of S.Port traffic: the receiver polls the present devices in turn
/// and one absent ID after each round (as the S-Port_Snoop sample describes); present devices
/// answer with Null keep-alives or data frames of their sensors, with values that need stuffing.
fn generate(path: &Path, target: u64) -> u64 {
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

/// Pins the current thread (and threads it spawns later) to CPU 0.
fn pin_to_core0() {
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(0, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
    }
}

/// Peak resident memory of this process so far (kB).
fn self_peak_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// Peak resident memory of the largest waited-for child (kB).
fn children_peak_kb() -> u64 {
    unsafe {
        let mut ru: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru);
        ru.ru_maxrss as u64
    }
}

fn decode_only(path: &Path) -> (f64, u64) {
    let mut f = File::open(path).unwrap();
    let mut buf = vec![0u8; 64 * 1024];
    let mut d = SportDecoder::new();
    let mut out = Discard::default();
    let start = Instant::now();
    loop {
        let n = f.read(&mut buf).unwrap();
        if n == 0 {
            break;
        }
        d.push(&buf[..n], None, &mut out).unwrap();
    }
    d.finish(&mut out).unwrap();
    (start.elapsed().as_secs_f64(), out.rows)
}

fn to_tsv(path: &Path) -> (f64, u64) {
    use std::os::unix::process::CommandExt;
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_busnoop"));
    cmd.args(["sport", "-f", "tsv"])
        .arg(path)
        .stdout(Stdio::null())
        .stderr(Stdio::inherit());
    unsafe {
        cmd.pre_exec(|| {
            pin_to_core0();
            Ok(())
        });
    }
    let start = Instant::now();
    let status = cmd.status().unwrap();
    let secs = start.elapsed().as_secs_f64();
    assert!(status.success());
    (secs, children_peak_kb())
}

fn main() {
    // `cargo bench` passes `--bench`; ignore arguments.
    let mb: u64 = std::env::var("BUSNOOP_BENCH_MB")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(128);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("sport-{mb}mib.bin"));
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

    // Warm the page cache, then take the best of three runs.
    let runs: usize = std::env::var("BUSNOOP_BENCH_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    if runs > 1 {
        let _ = decode_only(&path);
    }
    let mut best = (f64::MAX, 0);
    for _ in 0..runs {
        let r = decode_only(&path);
        if r.0 < best.0 {
            best = r;
        }
    }
    let (secs, rows) = best;
    println!(
        "decode only: {:.1} MiB/s, {:.2} M rows/s ({rows} rows in {secs:.2} s), peak RSS {} kB",
        mib / secs,
        rows as f64 / secs / 1e6,
        self_peak_kb()
    );

    let mut best = (f64::MAX, 0);
    for _ in 0..runs {
        let r = to_tsv(&path);
        if r.0 < best.0 {
            best = r;
        }
    }
    let (secs, peak) = best;
    println!(
        "busnoop sport -f tsv > /dev/null: {:.1} MiB/s, {:.2} M rows/s ({secs:.2} s), peak RSS {peak} kB",
        mib / secs,
        rows as f64 / secs / 1e6
    );
}
