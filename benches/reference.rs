//! busnoop against hand-written C decoders that do the same job (`benches/c/`, README there):
//! busnoop's share of the C program's speed, per protocol and output format, in one run.
//!
//! ```sh
//! cargo bench --bench reference                         # every protocol, 7 alternated runs
//! BUSNOOP_BENCH_RUNS=15 cargo bench --bench reference   # more runs
//! BUSNOOP_BENCH_ONLY=sport,ether cargo bench --bench reference
//! BUSNOOP_BENCH_COUNT=1 cargo bench --bench reference   # instructions (valgrind), not time
//! BUSNOOP_BENCH_BIN=/path/to/busnoop cargo bench --bench reference   # another build
//! BUSNOOP_BENCH_TSHARK=3 cargo bench --bench reference  # also `tshark -r`, best of 3
//! ```
//!
//! It generates captures of what the C decoders cover (`target/bench-data/ref-*`: S.Port
//! `BUSNOOP_BENCH_POLLS` polls, 3 M; Ether-S-Bus `BUSNOOP_BENCH_PACKETS` packets, 1 M; serial S-Bus
//! in data mode of `BUSNOOP_BENCH_MB` MiB, 16; SAB2 of `BUSNOOP_BENCH_MB` MiB; Futaba SBUS
//! `BUSNOOP_BENCH_FUTABA_FRAMES` frames, 800 k; CRSF `BUSNOOP_BENCH_CRSF_FRAMES` frames, 800 k;
//! Modbus RTU `BUSNOOP_BENCH_EXCHANGES` exchanges, 600 k; FlySky iBUS `BUSNOOP_BENCH_IBUS_FRAMES`
//! RC frames with as many sensor polls, 600 k; GHST `BUSNOOP_BENCH_GHST_FRAMES` frames, 1.2 M;
//! F.Port v1 `BUSNOOP_BENCH_FPORT_FRAMES` control frames with their telemetry, 500 k),
//! compiles the C decoders with `cc -O2` (skipped with
//! a message when there is no C compiler), checks that each one's output is byte-identical to
//! `busnoop … -f tsv`, and then runs the C decoder and busnoop to TSV, CSV, JSON Lines and pretty
//! text (no colour) alternately, each pinned to CPU 0 with its output going to /dev/null,
//! `BUSNOOP_BENCH_RUNS` times. Times are CPU times (user + system of the child): the minimum of the
//! runs. The share is the C decoder's time over busnoop's (100 % = as fast as the C decoder, which
//! writes TSV in every comparison). `--stats` is not given; peak memory (`--stats` on) is `cargo
//! bench --bench memory`'s.
//!
//! With `BUSNOOP_BENCH_COUNT=1`, every run is counted instead of timed: instructions under
//! `valgrind --tool=cachegrind --cache-sim=no` (the same whatever else the machine runs).

#![allow(clippy::duplicate_mod)]

#[path = "reference/captures.rs"]
mod captures;
mod common;
#[path = "reference/crsf.rs"]
mod crsf;
#[path = "reference/fport.rs"]
mod fport;
#[path = "reference/fport2.rs"]
mod fport2;
#[path = "reference/futaba.rs"]
mod futaba;
#[path = "reference/ghst.rs"]
mod ghst;
#[path = "reference/ibus.rs"]
mod ibus;
#[path = "reference/modbus.rs"]
mod modbus;
#[path = "reference/sab.rs"]
mod sab;

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// A protocol's comparison: the C source, the capture and busnoop's arguments before `-f`.
struct Case {
    name: &'static str,
    c: &'static str,
    file: PathBuf,
    args: &'static [&'static str],
    /// Rows of the capture (for instructions a row).
    rows: u64,
}

/// busnoop's formats: a label and the arguments.
const FORMATS: [(&str, &[&str]); 4] = [
    ("tsv", &["-f", "tsv"]),
    ("csv", &["-f", "csv"]),
    ("jsonl", &["-f", "jsonl"]),
    ("pretty", &["-f", "pretty", "--color", "never"]),
];

fn busnoop_exe() -> PathBuf {
    std::env::var_os("BUSNOOP_BENCH_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_busnoop")))
}

/// Compiles `benches/c/NAME.c` into the data folder; `None` (with a message) without a
/// compiler.
fn compile(name: &str) -> Option<PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("benches/c")
        .join(format!("{name}.c"));
    let exe = common::data_dir().join(name);
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .args(["-O2", "-march=x86-64-v2", "-o"])
        .arg(&exe)
        .arg(&src)
        .status();
    match status {
        Ok(s) if s.success() => Some(exe),
        Ok(s) => {
            eprintln!("{cc} failed on {} ({s}): skipped", src.display());
            None
        }
        Err(e) => {
            eprintln!("no C compiler ({cc}: {e}): the comparison with {name} is skipped");
            None
        }
    }
}

/// A command's output, pinned to CPU 0.
fn output_of(cmd: &mut Command) -> Vec<u8> {
    pin(cmd);
    let out = cmd.stderr(Stdio::null()).output().expect("cannot run");
    assert!(out.status.success(), "{cmd:?} failed: {}", out.status);
    out.stdout
}

fn pin(cmd: &mut Command) {
    unsafe {
        cmd.pre_exec(|| {
            common::pin_to_core0();
            Ok(())
        });
    }
}

/// Runs `cmd` with its output to /dev/null; its CPU time, or its instructions (as nanoseconds)
/// under cachegrind when `count`.
fn measure(cmd: &Command, count: bool) -> Duration {
    let mut c = if count {
        let mut v = Command::new("valgrind");
        v.args([
            "--tool=cachegrind",
            "--cache-sim=no",
            "--cachegrind-out-file=/dev/null",
        ])
        .arg(cmd.get_program())
        .args(cmd.get_args());
        v
    } else {
        let mut c = Command::new(cmd.get_program());
        c.args(cmd.get_args());
        c
    };
    pin(&mut c);
    if count {
        let out = c
            .stdout(Stdio::null())
            .output()
            .expect("cannot run valgrind");
        let err = String::from_utf8_lossy(&out.stderr);
        let refs = err
            .lines()
            .find_map(|l| {
                l.split_once("I refs:")
                    .or_else(|| l.split_once("I   refs:"))
            })
            .map(|(_, n)| n.trim().replace(',', ""))
            .and_then(|n| n.parse::<u64>().ok())
            .unwrap_or_else(|| panic!("no instruction count from valgrind: {err}"));
        return Duration::from_nanos(refs);
    }
    let before = common::cpu_time(libc::RUSAGE_CHILDREN);
    let status = c
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .expect("cannot run");
    assert!(status.success(), "{c:?} failed");
    common::cpu_time(libc::RUSAGE_CHILDREN) - before
}

/// The first line where two outputs differ, for the message.
fn first_difference(a: &[u8], b: &[u8]) -> String {
    let (mut la, mut lb) = (a.split(|&c| c == b'\n'), b.split(|&c| c == b'\n'));
    for n in 1.. {
        match (la.next(), lb.next()) {
            (Some(x), Some(y)) if x == y => continue,
            (x, y) => {
                let show = |l: Option<&[u8]>| {
                    l.map_or("(end)".into(), |l| String::from_utf8_lossy(l).into_owned())
                };
                return format!("line {n}:\n  busnoop: {}\n  C:       {}", show(x), show(y));
            }
        }
    }
    unreachable!()
}

/// A protocol's case before its capture exists: its name (as `BUSNOOP_BENCH_ONLY` takes it),
/// the C program, busnoop's arguments, the capture's file name, its generator and the size it
/// takes (polls, packets, bytes or frames).
struct Spec {
    name: &'static str,
    c: &'static str,
    args: &'static [&'static str],
    file: String,
    make: fn(&Path, u64) -> std::io::Result<u64>,
    size: u64,
}

/// The protocols' cases, each capture generated when it is not there yet.
fn cases(only: &[String]) -> Vec<Case> {
    let env = common::env_u64;
    let polls = env("BUSNOOP_BENCH_POLLS", 3_000_000);
    let packets = env("BUSNOOP_BENCH_PACKETS", 1_000_000);
    let mb = env("BUSNOOP_BENCH_MB", 16);
    let futaba_frames = env("BUSNOOP_BENCH_FUTABA_FRAMES", 800_000);
    let ibus_frames = env("BUSNOOP_BENCH_IBUS_FRAMES", 600_000);
    let crsf_frames = env("BUSNOOP_BENCH_CRSF_FRAMES", 800_000);
    let exchanges = env("BUSNOOP_BENCH_EXCHANGES", 600_000);
    let ghst_frames = env("BUSNOOP_BENCH_GHST_FRAMES", 1_200_000);
    let fport_frames = env("BUSNOOP_BENCH_FPORT_FRAMES", 500_000);
    let fport2_frames = env("BUSNOOP_BENCH_FPORT2_FRAMES", 500_000);
    let table = [
        Spec {
            name: "sport",
            c: "sport_ref",
            args: &["sport", "--no-config"],
            file: format!("ref-sport-{polls}.bin"),
            make: captures::sport,
            size: polls,
        },
        Spec {
            name: "ether",
            c: "ether_ref",
            args: &["sbus", "--no-config"],
            file: format!("ref-ether-{packets}.pcap"),
            make: captures::ether,
            size: packets,
        },
        Spec {
            name: "sbus",
            c: "sbus_ref",
            args: &["sbus", "--no-config", "--mode", "data"],
            file: format!("ref-sbus-data-{mb}mib.bin"),
            make: captures::sbus_data,
            size: mb << 20,
        },
        Spec {
            name: "futaba",
            c: "futaba_ref",
            args: &["futaba", "--no-config"],
            file: format!("ref-futaba-{futaba_frames}.bin"),
            make: futaba::futaba,
            size: futaba_frames,
        },
        Spec {
            name: "ibus",
            c: "ibus_ref",
            args: &["ibus", "--no-config"],
            file: format!("ref-ibus-{ibus_frames}.bin"),
            make: ibus::ibus,
            size: ibus_frames,
        },
        Spec {
            name: "crsf",
            c: "crsf_ref",
            args: &["crsf", "--no-config"],
            file: format!("ref-crsf-{crsf_frames}.bin"),
            make: crsf::crsf,
            size: crsf_frames,
        },
        Spec {
            name: "sab",
            c: "sab_ref",
            // Forced: detection would read every byte twice (the other framing in the
            // background, to switch), which the C decoder does not.
            args: &["sab", "--no-config", "--framing", "hdlc"],
            file: format!("ref-sab2-{mb}mib.bin"),
            make: sab::sab,
            size: mb << 20,
        },
        Spec {
            name: "sab1",
            c: "sab1_ref",
            // Forced, as for SAB2: detection would also run the SAB2 reassembler.
            args: &["sab", "--no-config", "--framing", "sync"],
            file: format!("ref-sab1-{mb}mib.bin"),
            make: sab::sab1,
            size: mb << 20,
        },
        Spec {
            name: "modbus",
            c: "modbus_ref",
            args: &["modbus", "--no-config"],
            file: format!("ref-modbus-{exchanges}.bin"),
            make: modbus::modbus,
            size: exchanges,
        },
        Spec {
            name: "ghst",
            c: "ghst_ref",
            args: &["ghst", "--no-config"],
            file: format!("ref-ghst-{ghst_frames}.bin"),
            make: ghst::ghst,
            size: ghst_frames,
        },
        Spec {
            name: "fport",
            c: "fport_ref",
            args: &["fport", "--no-config"],
            file: format!("ref-fport-{fport_frames}.bin"),
            make: fport::fport,
            size: fport_frames,
        },
        Spec {
            name: "fport2",
            c: "fport2_ref",
            args: &["fport", "--no-config"],
            file: format!("ref-fport2-{fport2_frames}.bin"),
            make: fport2::fport2,
            size: fport2_frames,
        },
    ];
    let dir = common::data_dir();
    table
        .into_iter()
        .filter(|s| only.is_empty() || only.iter().any(|o| o == s.name))
        .map(|s| {
            let file = dir.join(s.file);
            if !file.exists() {
                eprintln!("generating {} ...", file.display());
                (s.make)(&file, s.size).expect("cannot write the capture");
            }
            Case {
                name: s.name,
                c: s.c,
                file,
                args: s.args,
                rows: 0,
            }
        })
        .collect()
}

fn main() {
    let runs = common::env_u64("BUSNOOP_BENCH_RUNS", 7).max(1);
    let count = common::env_u64("BUSNOOP_BENCH_COUNT", 0) == 1;
    let only: Vec<String> = std::env::var("BUSNOOP_BENCH_ONLY")
        .unwrap_or_default()
        .split(',')
        .filter(|s| !s.is_empty())
        .map(str::to_owned)
        .collect();
    let exe = busnoop_exe();
    common::pin_to_core0();
    let what = if count {
        "instructions (cachegrind)".to_owned()
    } else {
        format!("CPU time, minimum of {runs} alternated runs, pinned to CPU 0")
    };
    println!(
        "busnoop {} against the C reference decoders; {what}",
        exe.display()
    );
    let mut results = Vec::new();
    for mut case in cases(&only) {
        let Some(c) = compile(case.c) else { continue };
        let mut reference = Command::new(&c);
        reference.arg(&case.file);
        let busnoop = |fmt: &[&str]| {
            let mut b = Command::new(&exe);
            b.args(case.args).args(fmt).arg(&case.file);
            b
        };
        let theirs = output_of(Command::new(&c).arg(&case.file));
        let ours = output_of(&mut busnoop(&["-f", "tsv"]));
        if ours != theirs {
            panic!(
                "{}: busnoop's TSV and {}'s output differ at {}",
                case.name,
                case.c,
                first_difference(&ours, &theirs)
            );
        }
        case.rows = ours.iter().filter(|&&b| b == b'\n').count() as u64 - 1;
        let size = std::fs::metadata(&case.file).map_or(0, |m| m.len());
        println!(
            "{}: {} ({:.1} MiB, {} rows), outputs identical ({} bytes)",
            case.name,
            case.file.display(),
            size as f64 / (1 << 20) as f64,
            case.rows,
            ours.len()
        );
        let mut commands = vec![("C (tsv)".to_owned(), reference)];
        for (label, args) in FORMATS {
            commands.push((format!("busnoop {label}"), busnoop(args)));
        }
        let runs = if count { 1 } else { runs };
        let mut best = vec![Duration::MAX; commands.len()];
        for _ in 0..runs {
            for (i, (_, cmd)) in commands.iter().enumerate() {
                best[i] = best[i].min(measure(cmd, count));
            }
        }
        for (i, (label, _)) in commands.iter().enumerate() {
            let share = best[0].as_secs_f64() / best[i].as_secs_f64();
            if count {
                let n = best[i].as_nanos() as f64;
                println!(
                    "  {label:<16} {:>14.0} instructions, {:>7.1} a row, share {:>5.1} %",
                    n,
                    n / case.rows as f64,
                    share * 100.0
                );
            } else {
                println!(
                    "  {label:<16} {:>8.3} s, share {:>5.1} %",
                    best[i].as_secs_f64(),
                    share * 100.0
                );
            }
            results.push((case.name, label.clone(), share));
        }
        if case.name == "ether" && !count {
            tshark(&case, best[1]);
        }
    }
    println!(
        "\nshares (C decoder's {} over busnoop's):",
        if count { "instructions" } else { "CPU time" }
    );
    for (name, label, share) in results {
        if label.starts_with("busnoop") {
            println!("  {name:<6} {:<8} {:>5.1} %", &label[8..], share * 100.0);
        }
    }
}

/// `tshark -r FILE` on the Ether-S-Bus capture (`BUSNOOP_BENCH_TSHARK` runs, best taken),
/// against busnoop's best to TSV.
fn tshark(case: &Case, busnoop_tsv: Duration) {
    let runs = common::env_u64("BUSNOOP_BENCH_TSHARK", 0);
    if runs == 0 {
        return;
    }
    let mut best = Duration::MAX;
    for _ in 0..runs {
        let mut c = Command::new("tshark");
        c.arg("-r").arg(&case.file);
        pin(&mut c);
        let before = common::cpu_time(libc::RUSAGE_CHILDREN);
        match c.stdout(Stdio::null()).stderr(Stdio::null()).status() {
            Ok(s) if s.success() => {}
            _ => {
                println!("  tshark is not installed (or failed): skipped");
                return;
            }
        }
        let t = common::cpu_time(libc::RUSAGE_CHILDREN) - before;
        println!("  tshark -r: {:.2} s", t.as_secs_f64());
        best = best.min(t);
    }
    println!(
        "  busnoop to TSV against tshark -r (best of {runs}): {:.1}x",
        best.as_secs_f64() / busnoop_tsv.as_secs_f64()
    );
}
