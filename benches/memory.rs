//! Peak memory on adversarial inputs: busnoop's memory must stay flat whatever the input.
//!
//! ```sh
//! cargo bench --bench memory                          # 1x = 20 MB per input, then 2x and 4x
//! BUSNOOP_BENCH_MB=50 cargo bench --bench memory      # a larger 1x
//! BUSNOOP_BENCH_EXE=/path/to/busnoop cargo bench --bench memory   # another build
//! ```
//!
//! Writes each input at 1x, 2x and 4x size into a temporary directory, runs the release binary
//! on it (`-f tsv`, output thrown away) and reads the child's peak resident memory with
//! `wait4`. The inputs:
//!
//! * **conversations**: Ether-S-Bus requests, each from a new client address and port, to 1024
//!   PLCs, 1 µs apart, never answered (a port scan);
//! * **interfaces**: a pcapng file of interface description blocks, with a packet now and then;
//! * **constant timestamps**: answered polls on 64 conversations, every packet with the same
//!   timestamp (nothing ever expires by time);
//! * **unanswered requests**: the same, but nobody answers (more than 65 536 waiting);
//! * **retries**: four clients sending the same request again and again, at the same instant;
//! * **normal, --stats**: a normal Ether-S-Bus capture (4 clients polling 8 PLCs) with `--stats`;
//! * **SAB, 64 addresses, --stats**: SAB2 polls of all 64 addresses, each answered (more
//!   than 4096 response times per address at 1x).
//!
//! The whole run takes well under a minute.
//!
//! No timing is measured; the table goes to stdout (docs/robustness.md, "Memory").

mod common;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Command, Stdio};

use busnoop::pcap::write as pw;
use busnoop::sab::frame::Framing;
use busnoop::sab::header::Flags;
use busnoop::sab::sample;
use busnoop::sbus::telegram::encode_ether;
use common::Rng;

const T0: i64 = 1_750_000_000_000_000;

/// Writes records into a file, 1 MiB at a time.
struct Writer {
    out: BufWriter<File>,
    buf: Vec<u8>,
    frame: Vec<u8>,
    payload: Vec<u8>,
    written: u64,
}

impl Writer {
    fn new(path: &Path) -> Self {
        Writer {
            out: BufWriter::new(File::create(path).unwrap()),
            buf: Vec::with_capacity(1 << 20),
            frame: Vec::new(),
            payload: Vec::new(),
            written: 0,
        }
    }

    fn pcap(path: &Path) -> Self {
        let mut w = Writer::new(path);
        pw::header(&mut w.buf, 1);
        w
    }

    /// One Ether-S-Bus packet: a request (`at` 0, read R`addr`) or its answer.
    fn sbus(&mut self, ts: i64, client: ([u8; 4], u16), plc: ([u8; 4], u16), seq: u16, at: u8) {
        self.payload.clear();
        self.frame.clear();
        if at == 0 {
            encode_ether(&mut self.payload, seq, 0, &[1, 6, 0, 0, seq as u8]);
            pw::udp4_frame(&mut self.frame, client, plc, &self.payload);
        } else {
            encode_ether(&mut self.payload, seq, 1, &[0, 0, 1, seq as u8]);
            pw::udp4_frame(&mut self.frame, plc, client, &self.payload);
        }
        pw::record(&mut self.buf, ts, &self.frame);
        self.flush_some();
    }

    fn flush_some(&mut self) {
        if self.buf.len() >= 1 << 20 {
            self.out.write_all(&self.buf).unwrap();
            self.written += self.buf.len() as u64;
            self.buf.clear();
        }
    }

    fn len(&self) -> u64 {
        self.written + self.buf.len() as u64
    }

    fn close(mut self) -> u64 {
        self.out.write_all(&self.buf).unwrap();
        self.out.flush().unwrap();
        self.written + self.buf.len() as u64
    }
}

fn conversations(path: &Path, size: u64) -> u64 {
    let mut w = Writer::pcap(path);
    let mut i = 0u64;
    while w.len() < size {
        let client = (
            [10, (i >> 24) as u8 | 64, (i >> 16) as u8, (i >> 8) as u8],
            i as u16,
        );
        let p = i % 1024;
        let plc = ([172, 16, (p >> 8) as u8, p as u8], 5050);
        w.sbus(T0 + i as i64, client, plc, i as u16, 0);
        i += 1;
    }
    w.close()
}

fn interfaces(path: &Path, size: u64) -> u64 {
    fn block(out: &mut Vec<u8>, kind: u32, body: &[u8]) {
        let padded = body.len().div_ceil(4) * 4;
        let len = (12 + padded) as u32;
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(body);
        out.resize(out.len() + padded - body.len(), 0);
        out.extend_from_slice(&len.to_le_bytes());
    }
    let mut w = Writer::new(path);
    let mut shb = Vec::new();
    shb.extend_from_slice(&0x1A2B_3C4Du32.to_le_bytes());
    shb.extend_from_slice(&[1, 0, 0, 0]);
    shb.extend_from_slice(&(-1i64).to_le_bytes());
    block(&mut w.buf, 0x0A0D_0D0A, &shb);
    let mut i = 0u64;
    let mut body = Vec::new();
    while w.len() < size {
        // link type Ethernet, snap length 0; every 1000th block a packet on interface 0
        block(&mut w.buf, 1, &[1, 0, 0, 0, 0, 0, 0, 0]);
        if i.is_multiple_of(1000) {
            w.payload.clear();
            w.frame.clear();
            encode_ether(&mut w.payload, i as u16, 0, &[1, 6, 0, 0, 0]);
            pw::udp4_frame(
                &mut w.frame,
                ([10, 0, 0, 1], 40_000),
                ([10, 0, 0, 5], 5050),
                &w.payload,
            );
            body.clear();
            body.extend_from_slice(&0u32.to_le_bytes());
            let ts = (T0 + i as i64) as u64;
            body.extend_from_slice(&((ts >> 32) as u32).to_le_bytes());
            body.extend_from_slice(&(ts as u32).to_le_bytes());
            body.extend_from_slice(&(w.frame.len() as u32).to_le_bytes());
            body.extend_from_slice(&(w.frame.len() as u32).to_le_bytes());
            body.extend_from_slice(&w.frame);
            block(&mut w.buf, 6, &body);
        }
        w.flush_some();
        i += 1;
    }
    w.close()
}

fn constant_time(path: &Path, size: u64) -> u64 {
    let mut w = Writer::pcap(path);
    let plc = ([10, 0, 0, 5], 5050);
    let mut i = 0u64;
    while w.len() < size {
        let c = ([10, 0, 1, (i % 64) as u8], 40_000);
        w.sbus(T0, c, plc, (i / 64) as u16, 0);
        w.sbus(T0, c, plc, (i / 64) as u16, 1);
        i += 1;
    }
    w.close()
}

fn unanswered(path: &Path, size: u64) -> u64 {
    let mut w = Writer::pcap(path);
    let plc = ([10, 0, 0, 5], 5050);
    let mut i = 0u64;
    while w.len() < size {
        let c = ([10, 0, 2, (i % 16) as u8], 41_000);
        w.sbus(T0, c, plc, (i / 16) as u16, 0);
        i += 1;
    }
    w.close()
}

fn retries(path: &Path, size: u64) -> u64 {
    let mut w = Writer::pcap(path);
    let plc = ([10, 0, 0, 5], 5050);
    let mut i = 0u64;
    while w.len() < size {
        let c = ([10, 0, 0, 1 + (i % 4) as u8], 40_000);
        w.sbus(T0, c, plc, 77, 0);
        i += 1;
    }
    w.close()
}

fn normal(path: &Path, size: u64) -> u64 {
    let mut w = Writer::pcap(path);
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut seq = [[0u16; 8]; 4];
    let mut t = T0;
    while w.len() < size {
        let c = rng.below(4) as usize;
        let p = rng.below(8) as usize;
        let client = ([192, 168, 1, 10 + c as u8], 40_000 + c as u16);
        let plc = ([192, 168, 1, 100 + p as u8], 5050);
        seq[c][p] = seq[c][p].wrapping_add(1);
        w.sbus(t, client, plc, seq[c][p], 0);
        t += 300 + rng.below(2000) as i64;
        if rng.below(100) != 0 {
            w.sbus(t, client, plc, seq[c][p], 1);
        }
        t += 100 + rng.below(500) as i64;
    }
    w.close()
}

fn sab(path: &Path, size: u64) -> u64 {
    let mut w = Writer::new(path);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut payload = Vec::new();
    while w.len() < size {
        for addr in 0..64u8 {
            payload.clear();
            for _ in 0..rng.below(4) {
                payload.push(rng.next() as u8 & 0x3F);
            }
            sample::frame(
                &mut w.buf,
                Framing::Hdlc,
                Flags::Request,
                addr,
                0x21,
                &payload,
            );
            payload.clear();
            for _ in 0..rng.below(9) {
                payload.push(rng.next() as u8 & 0x3F);
            }
            sample::frame(&mut w.buf, Framing::Hdlc, Flags::Ack, addr, 0x21, &payload);
        }
        w.flush_some();
    }
    w.close()
}

/// Runs busnoop on `path`; returns its peak resident memory (kB) and its last stderr line.
// The child is reaped by `wait4`, which also gives its own peak memory.
#[allow(clippy::zombie_processes)]
fn peak_kb(args: &[&str], path: &Path, stderr: &Path) -> (u64, String) {
    let exe = std::env::var_os("BUSNOOP_BENCH_EXE")
        .unwrap_or_else(|| env!("CARGO_BIN_EXE_busnoop").into());
    let child = Command::new(exe)
        .args(args)
        .arg(path)
        .args(["-f", "tsv"])
        .stdout(Stdio::null())
        .stderr(File::create(stderr).unwrap())
        .spawn()
        .expect("busnoop runs");
    let mut status = 0;
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = child.id() as libc::pid_t;
    let r = unsafe { libc::wait4(pid, &mut status, 0, &mut ru) };
    assert_eq!(r, pid, "wait4");
    let status = std::process::ExitStatus::from_raw(status);
    assert!(
        status.success(),
        "busnoop {args:?} {}: {status}",
        path.display()
    );
    let err = std::fs::read_to_string(stderr).unwrap_or_default();
    let last = err
        .lines()
        .rev()
        .find(|l| l.starts_with("busnoop:"))
        .unwrap_or("")
        .to_string();
    (ru.ru_maxrss as u64, last)
}

type Generator = fn(&Path, u64) -> u64;

fn main() {
    let base = common::env_u64("BUSNOOP_BENCH_MB", 20) * 1_000_000;
    let inputs: [(&str, &[&str], &str, Generator); 7] = [
        (
            "conversations (port scan)",
            &["sbus"],
            "pcap",
            conversations,
        ),
        ("pcapng interfaces", &["sbus"], "pcapng", interfaces),
        ("constant timestamps", &["sbus"], "pcap", constant_time),
        ("unanswered requests", &["sbus"], "pcap", unanswered),
        ("retries", &["sbus"], "pcap", retries),
        (
            "normal Ether-S-Bus, --stats",
            &["sbus", "--stats"],
            "pcap",
            normal,
        ),
        (
            "SAB2, 64 addresses, --stats",
            &["sab2", "--stats"],
            "bin",
            sab,
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    let stderr = dir.path().join("stderr.txt");
    println!("| input | 1x | peak RSS | 2x | peak RSS | 4x | peak RSS |");
    println!("|---|---|---|---|---|---|---|");
    let mut notes = Vec::new();
    for (name, args, ext, generate) in inputs {
        let mut line = format!("| {name} |");
        for scale in [1, 2, 4] {
            let path = dir.path().join(format!("input.{ext}"));
            let size = generate(&path, base * scale);
            let (kb, last) = peak_kb(args, &path, &stderr);
            std::fs::remove_file(&path).unwrap();
            line.push_str(&format!(
                " {:.0} MB | {:.1} MB |",
                size as f64 / 1e6,
                kb as f64 / 1e3
            ));
            if scale == 4 && !last.is_empty() {
                notes.push(format!("{name} (4x): {last}"));
            }
        }
        println!("{line}");
    }
    println!();
    for n in notes {
        println!("* {n}");
    }
}
