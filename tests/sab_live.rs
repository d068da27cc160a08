//! `busnoop sab2` on a live serial line (a pseudo-terminal pair): a request without a response
//! gets its `Timeout` row while the bus is quiet, detection decides on a quiet line, and the
//! recording replays to the same rows.

mod common;

use std::io::Write;
use std::process::Command;
use std::sync::mpsc::Receiver;
use std::time::{Duration, Instant};

use common::pty::{Bus, bus, lock, spawn, wait_exit};

use busnoop::sab::frame::Framing;
use busnoop::sab::header::Flags;
use busnoop::sab::sample;

fn next_line(rx: &Receiver<(Instant, String)>) -> String {
    common::pty::next_line(rx).1
}

fn field(line: &str, i: usize) -> &str {
    line.split('\t').nth(i).unwrap_or("")
}

fn write(b: &mut Bus, flags: Flags, cmd: u8, data: &[u8]) {
    let mut w = Vec::new();
    sample::frame(&mut w, Framing::Hdlc, flags, 5, cmd, data);
    b.master.write_all(&w).unwrap();
    b.master.flush().unwrap();
}

#[test]
fn timeout_rows_appear_while_the_bus_is_quiet_and_the_recording_replays() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("sab.pcap");
    let mut b = bus();
    // A long timeout keeps the in-time answer below in time on a loaded machine.
    let (mut child, rx) = spawn(
        &[
            "sab2",
            "-f",
            "tsv",
            "--framing",
            "hdlc",
            "--timeout-ms",
            "200",
            "--record",
            rec.to_str().unwrap(),
        ],
        &b.path,
    );
    let header = next_line(&rx);
    assert!(header.starts_with("Counter\tMillis\tID"));
    let mut live = vec![header];

    // A request nobody answers: the Timeout row comes while nothing else arrives.
    write(&mut b, Flags::Request, 0x10, &[]);
    let req = next_line(&rx);
    assert_eq!(field(&req, 4), "Request", "{req}");
    let timeout = next_line(&rx);
    assert_eq!(field(&timeout, 4), "Timeout", "{timeout}");
    assert_eq!(field(&timeout, 13), "no response within 200 ms");
    let at = |l: &str| field(l, 1).parse::<u64>().unwrap();
    assert_eq!(at(&timeout), at(&req) + 200, "placed at the deadline");
    live.extend([req, timeout]);

    // A request answered in time.
    // The ACK goes out once the request's row is there: busnoop has read it, so the ACK
    // arrives later and the response time is above 0 however loaded the machine.
    write(&mut b, Flags::Request, 0x11, &[]);
    let req = next_line(&rx);
    std::thread::sleep(Duration::from_millis(2));
    write(&mut b, Flags::Ack, 0x11, &[1, 2]);
    let ack = next_line(&rx);
    assert_eq!(field(&req, 4), "Request", "{req}");
    assert_eq!(field(&ack, 4), "ACK", "{ack}");
    let resp: f64 = field(&ack, 11).parse().unwrap();
    assert!(resp > 0.0 && resp < 200.0, "{ack}");
    live.extend([req, ack]);

    drop(b.master);
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(7), "adapter disconnected");
    while let Ok((_, l)) = rx.recv_timeout(Duration::from_secs(1)) {
        live.push(l);
    }
    assert_eq!(live.len(), 5, "{live:#?}");

    // The replay has no idle ticks: the Timeout row comes from the next request's time, at
    // the same place and with the same content.
    let replay = Command::new(env!("CARGO_BIN_EXE_busnoop"))
        .args([
            "sab2",
            "-f",
            "tsv",
            "--framing",
            "hdlc",
            "--timeout-ms",
            "200",
        ])
        .arg(&rec)
        .output()
        .unwrap();
    assert!(replay.status.success());
    let replayed: Vec<String> = String::from_utf8(replay.stdout)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(replayed, live);
}

#[test]
fn detection_decides_on_a_quiet_line() {
    let _g = lock();
    let mut b = bus();
    let (mut child, rx) = spawn(&["sab2", "-f", "tsv"], &b.path);
    next_line(&rx);
    // One frame is not enough to lock; after a quiet second busnoop decides anyway.
    let sent = Instant::now();
    write(&mut b, Flags::Request, 0x10, &[]);
    let req = next_line(&rx);
    assert!(
        sent.elapsed() >= Duration::from_millis(900),
        "decided too early"
    );
    assert_eq!(field(&req, 4), "Request", "{req}");
    assert!(
        field(&req, 13).contains("framing hdlc") && field(&req, 13).contains("quiet second"),
        "{req}"
    );
    // The request had long timed out by then.
    let timeout = next_line(&rx);
    assert_eq!(field(&timeout, 4), "Timeout", "{timeout}");
    drop(b.master);
    wait_exit(&mut child);
}
