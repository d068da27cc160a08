//! Helpers shared by the benchmarks: a deterministic generator, CPU pinning, timing of the
//! release binary and of in-process decoding, peak memory.
#![allow(dead_code)]

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use busnoop::protocol::Decoder;
use busnoop::row::Discard;

/// A tiny deterministic PRNG (xorshift), so generated captures are the same on every run.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// Where generated captures go (`target/bench-data/`).
pub fn data_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"));
    let dir = target.join("bench-data");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An integer from the environment, or `default`.
pub fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Pins the current thread (and threads and processes it starts later) to CPU 0.
pub fn pin_to_core0() {
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(0, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
    }
}

/// Peak resident memory of this process so far (kB).
pub fn self_peak_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// Peak resident memory of the largest waited-for child (kB).
pub fn children_peak_kb() -> u64 {
    unsafe {
        let mut ru: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru);
        ru.ru_maxrss as u64
    }
}

/// Reads `path` in 64 KiB chunks through `decoder`, rows rendered and discarded; returns the
/// time and the number of rows.
pub fn decode_file(path: &Path, decoder: &mut dyn Decoder) -> (Duration, u64) {
    let mut f = File::open(path).unwrap();
    let mut buf = vec![0u8; 64 * 1024];
    let mut out = Discard::default();
    let start = Instant::now();
    loop {
        let n = f.read(&mut buf).unwrap();
        if n == 0 {
            break;
        }
        decoder.push(&buf[..n], None, &mut out).unwrap();
    }
    decoder.finish(&mut out).unwrap();
    (start.elapsed(), out.rows)
}

/// Runs `cmd` pinned to CPU 0 with its output thrown away; `None` when it cannot run or fails.
pub fn time_command(cmd: &mut Command) -> Option<Duration> {
    use std::os::unix::process::CommandExt;
    unsafe {
        cmd.pre_exec(|| {
            pin_to_core0();
            Ok(())
        });
    }
    let start = Instant::now();
    let status = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .ok()?;
    let d = start.elapsed();
    status.success().then_some(d)
}

/// User + system CPU time of this process (`libc::RUSAGE_SELF`) or of its waited-for children
/// (`libc::RUSAGE_CHILDREN`): on a machine shared with other work, wall times say more about
/// the neighbours than about the program measured.
pub fn cpu_time(who: i32) -> Duration {
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(who, &mut ru) };
    let tv = |t: libc::timeval| Duration::new(t.tv_sec as u64, t.tv_usec as u32 * 1000);
    tv(ru.ru_utime) + tv(ru.ru_stime)
}

/// Runs `cmd` pinned to CPU 0 (output thrown away) and returns its CPU time (user + system);
/// `None` when it cannot run or fails.
pub fn cpu_time_command(cmd: &mut Command) -> Option<Duration> {
    let before = cpu_time(libc::RUSAGE_CHILDREN);
    time_command(cmd)?;
    Some(cpu_time(libc::RUSAGE_CHILDREN) - before)
}

/// The release binary under benchmark.
pub fn busnoop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_busnoop"))
}

/// The fastest of `runs` runs of `f` (by its first value).
pub fn best_of<T>(runs: u64, mut f: impl FnMut() -> (Duration, T)) -> (Duration, T) {
    let mut best = f();
    for _ in 1..runs {
        let r = f();
        if r.0 < best.0 {
            best = r;
        }
    }
    best
}
