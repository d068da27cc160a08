//! Live capture benchmark on a pseudo-terminal pair:
//!
//! 1. latency: the time from writing a frame's last byte on the bus side to reading its row back
//!    from busnoop's standard output (median, 99th percentile, maximum);
//! 2. paced load at 10× the S.Port byte rate for 5 s: every frame must come back as a row;
//! 3. flood: bytes written as fast as the pty takes them; the byte rate busnoop keeps up with
//!    and the check that every frame still comes back.
//!
//! ```sh
//! cargo bench --bench live_latency
//! ```

use std::io::{BufRead, BufReader, Write};
use std::os::fd::AsRawFd;
use std::process::{Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use busnoop::sport::wire;
use serialport::{SerialPort, TTYPort};

/// S.Port: 57600 baud, 10 bits per byte.
const SPORT_BYTES_PER_S: f64 = 5760.0;

fn frame(i: u32) -> Vec<u8> {
    let mut b = Vec::new();
    wire::encode_frame(&mut b, wire::header_for((i % 28) as u8), 0x10, 0x0100, i);
    b
}

struct Run {
    master: TTYPort,
    _slave: TTYPort,
    child: std::process::Child,
    lines: Receiver<Instant>,
}

fn start() -> Run {
    let (master, slave) = TTYPort::pair().expect("pty pair");
    for fd in [master.as_raw_fd(), slave.as_raw_fd()] {
        unsafe { libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC) };
    }
    let path = slave.name().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_busnoop"))
        .args(["sport", "-f", "tsv", &path])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        let mut r = BufReader::new(stdout);
        let mut line = String::new();
        loop {
            line.clear();
            match r.read_line(&mut line) {
                Ok(0) | Err(_) => break,
                Ok(_) => {
                    if tx.send(Instant::now()).is_err() {
                        break;
                    }
                }
            }
        }
    });
    // The header row says busnoop has the port open.
    rx.recv_timeout(Duration::from_secs(10)).expect("no header");
    Run {
        master,
        _slave: slave,
        child,
        lines: rx,
    }
}

fn stop(run: Run) {
    let Run {
        master, mut child, ..
    } = run;
    drop(master);
    let _ = child.wait();
}

fn percentiles(mut v: Vec<Duration>) -> (Duration, Duration, Duration) {
    v.sort();
    let p = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    (p(0.5), p(0.99), *v.last().unwrap())
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn main() {
    // 1. Latency, one frame at a time.
    let mut run = start();
    let mut lat = Vec::new();
    for i in 0..500 {
        let f = frame(i);
        let (head, last) = f.split_at(f.len() - 1);
        run.master.write_all(head).unwrap();
        run.master.flush().unwrap();
        std::thread::sleep(Duration::from_millis(1));
        run.master.write_all(last).unwrap();
        run.master.flush().unwrap();
        let t0 = Instant::now();
        let t1 = run
            .lines
            .recv_timeout(Duration::from_secs(5))
            .expect("row lost");
        lat.push(t1.saturating_duration_since(t0));
        std::thread::sleep(Duration::from_millis(2));
    }
    let (p50, p99, max) = percentiles(lat);
    println!(
        "latency, last byte written -> row read (500 frames): median {:.0} µs, p99 {:.0} µs, max {:.0} µs",
        us(p50),
        us(p99),
        us(max)
    );
    stop(run);

    // 2. Paced load at 10x the S.Port byte rate for 5 s.
    let mut run = start();
    let rate = 10.0 * SPORT_BYTES_PER_S;
    let started = Instant::now();
    let mut sent_bytes = 0usize;
    let mut frames = 0u32;
    let mut rows = 0u32;
    while started.elapsed() < Duration::from_secs(5) {
        let due = started + Duration::from_secs_f64(sent_bytes as f64 / rate);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let f = frame(frames);
        run.master.write_all(&f).unwrap();
        run.master.flush().unwrap();
        sent_bytes += f.len();
        frames += 1;
        while run.lines.try_recv().is_ok() {
            rows += 1;
        }
    }
    while rows < frames {
        match run.lines.recv_timeout(Duration::from_secs(5)) {
            Ok(_) => rows += 1,
            Err(_) => break,
        }
    }
    let secs = started.elapsed().as_secs_f64();
    println!(
        "paced at 10x S.Port ({:.0} B/s for {secs:.1} s): {frames} frames written, {rows} rows read{}",
        rate,
        if rows == frames {
            ", no loss"
        } else {
            ", ROWS LOST"
        }
    );
    stop(run);

    // 3. Flood: as fast as the pty takes it.
    let run = start();
    let n = 200_000u32;
    let mut all = Vec::new();
    for i in 0..n {
        all.extend_from_slice(&frame(i));
    }
    let started = Instant::now();
    let writer = {
        let mut m = run.master.try_clone_native().unwrap();
        let data = all.clone();
        std::thread::spawn(move || {
            for chunk in data.chunks(4096) {
                m.write_all(chunk).unwrap();
            }
            m.flush().unwrap();
        })
    };
    let mut rows = 0u32;
    while rows < n {
        match run.lines.recv_timeout(Duration::from_secs(10)) {
            Ok(_) => rows += 1,
            Err(_) => break,
        }
    }
    let secs = started.elapsed().as_secs_f64();
    writer.join().unwrap();
    println!(
        "flood: {} bytes, {n} frames in {secs:.2} s = {:.0} kB/s ({:.0}x the S.Port byte rate), {rows} rows read{}",
        all.len(),
        all.len() as f64 / secs / 1000.0,
        all.len() as f64 / secs / SPORT_BYTES_PER_S,
        if rows == n {
            ", no loss"
        } else {
            ", ROWS LOST"
        }
    );
    stop(run);
}
