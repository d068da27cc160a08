//! Live Modbus RTU on a pseudo-terminal pair: rows appear as frames complete (a long response
//! written in pieces is one row, a request and its answer in one write are two), a missing
//! answer becomes a Timeout row while the line is silent, a late answer is flagged, and the
//! recording replays to the same rows; `detect` recognises the line.

mod common;

use std::io::Write;
use std::process::Command;
use std::time::{Duration, Instant};

use busnoop::modbus::wire::push_crc;
use common::pty::{bin, bus, lock, next_line, spawn, stderr_of, wait_exit};

fn f(bytes: &[u8]) -> Vec<u8> {
    let mut v = bytes.to_vec();
    push_crc(&mut v);
    v
}

#[test]
fn live_rows_timeouts_and_the_recording_replays() {
    let _g = lock();
    let common::pty::Bus {
        mut master,
        slave,
        path,
    } = bus();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("modbus.pcap");
    let (mut child, rx) = spawn(
        &[
            "modbus",
            "--no-config",
            "-f",
            "tsv",
            "--timeout-ms",
            "300",
            "--stats",
            "--record",
            rec.to_str().unwrap(),
        ],
        &path,
    );
    let (_, header) = next_line(&rx);
    assert!(header.starts_with("Counter\tMillis\tID"), "{header}");
    let mut live = vec![header];
    let mut send = |bytes: &[u8]| {
        master.write_all(bytes).unwrap();
        master.flush().unwrap();
    };

    // A read of register 5 at slave 3 that nobody answers: the Timeout row comes while the
    // line is silent, after the 300 ms timeout.
    send(&f(&[3, 3, 0, 5, 0, 1]));
    let sent = Instant::now();
    let (_, req) = next_line(&rx);
    assert!(
        req.contains("\t3\t\tRequest\t0x03\tRead Holding Registers\tstart=5 count=1\t"),
        "{req}"
    );
    live.push(req);
    let (t, timeout) = next_line(&rx);
    assert!(timeout.contains("\tTimeout\t0x03\t"), "{timeout}");
    assert!(timeout.ends_with("no answer within 300 ms"), "{timeout}");
    assert!(
        t.duration_since(sent) >= Duration::from_millis(250),
        "{:?}",
        t - sent
    );
    live.push(timeout);

    // The late answer still pairs, flagged.
    std::thread::sleep(Duration::from_millis(100));
    send(&f(&[3, 3, 2, 0, 42]));
    let (_, resp) = next_line(&rx);
    assert!(
        resp.contains("\tResponse\t0x03\tRead Holding Registers\tR5=42\t"),
        "{resp}"
    );
    assert!(resp.contains("late: after the 300 ms timeout"), "{resp}");
    live.push(resp);

    // 100 registers in pieces of 20 bytes, 30 ms apart, as a USB adapter hands them over:
    // one row.
    std::thread::sleep(Duration::from_millis(50));
    send(&f(&[7, 4, 0, 0, 0, 100]));
    let mut long = vec![7, 4, 200];
    for i in 0..100u16 {
        long.extend_from_slice(&i.to_be_bytes());
    }
    let long = f(&long);
    for piece in long.chunks(20) {
        std::thread::sleep(Duration::from_millis(30));
        send(piece);
    }
    for want in [
        "\tRequest\t0x04\t",
        "\tResponse\t0x04\tRead Input Registers\tR0=0 R1=1 ",
    ] {
        let (_, l) = next_line(&rx);
        assert!(l.contains(want), "{l}");
        live.push(l);
    }
    assert!(live.last().unwrap().contains("R99=99"));

    // A write and its echo in one piece, a turnaround byte after it: three rows.
    std::thread::sleep(Duration::from_millis(50));
    let w = f(&[9, 6, 0, 1, 0, 7]);
    send(&[&w[..], &w[..], &[0xFF]].concat());
    for want in ["\tRequest\t0x06\t", "\tResponse\t0x06\t", "\tGarbage\t"] {
        let (_, l) = next_line(&rx);
        assert!(l.contains(want), "{l}");
        live.push(l);
    }

    // A broadcast: no answer awaited, no Timeout row.
    std::thread::sleep(Duration::from_millis(50));
    send(&f(&[0, 6, 0, 1, 0, 7]));
    let (_, l) = next_line(&rx);
    assert!(
        l.contains("\t0\t\tRequest\t0x06\t") && l.ends_with("broadcast"),
        "{l}"
    );
    live.push(l);
    std::thread::sleep(Duration::from_millis(400));

    // Unplug.
    drop(master);
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(7), "adapter disconnected");
    let err = stderr_of(&mut child);
    assert!(err.contains("Modbus statistics"), "{err}");
    assert!(err.contains("master timeout 300 ms"), "{err}");
    while let Ok((_, l)) = rx.recv_timeout(Duration::from_secs(2)) {
        live.push(l);
    }
    assert_eq!(live.len(), 10, "{live:#?}");

    // The recording (real arrival times) replays to the same rows.
    let replay = Command::new(bin())
        .args(["modbus", "--no-config", "-f", "tsv", "--timeout-ms", "300"])
        .arg(&rec)
        .output()
        .unwrap();
    assert!(replay.status.success(), "{replay:?}");
    let replayed: Vec<String> = String::from_utf8(replay.stdout)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(replayed, live);
    drop(slave);
}

#[test]
fn detect_hears_modbus_on_a_serial_port() {
    let _g = lock();
    let mut bus = bus();
    let (mut child, rx) = spawn(
        &["detect", "--listen-ms", "200", "--baud", "9600"],
        &bus.path,
    );
    let traffic = std::fs::read(common::fixture("modbus-wizmodbus-bus.bin")).unwrap();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        let _ = bus.master.write_all(&traffic);
        let _ = bus.master.flush();
        std::thread::sleep(Duration::from_millis(20));
    };
    let stderr = stderr_of(&mut child);
    let mut lines = Vec::new();
    while let Ok((_, l)) = rx.recv_timeout(Duration::from_secs(2)) {
        lines.push(l);
    }
    assert_eq!(status.code(), Some(0), "{stderr}\n{lines:#?}");
    let verdict = lines.iter().find(|l| l.starts_with("verdict:")).unwrap();
    assert!(
        verdict.starts_with("verdict: Modbus RTU at 9600 baud"),
        "{lines:#?}"
    );
    let run = lines.iter().find(|l| l.starts_with("run:")).unwrap();
    assert!(run.starts_with("run:  busnoop modbus "), "{lines:#?}");
}
