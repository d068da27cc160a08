//! Live serial S-Bus on a pseudo-terminal pair: rows appear as telegrams complete, a missing
//! answer becomes a Timeout row while the line is silent, and the recording replays to the same
//! rows.

mod common;

use std::io::Write;
use std::process::Command;
use std::time::{Duration, Instant};

use common::pty::{bin, bus, lock, next_line, spawn, wait_exit};

use busnoop::sbus::telegram::{CrcBasis, encode_data};

fn telegram(at: u8, payload: &[u8]) -> Vec<u8> {
    let mut v = Vec::new();
    encode_data(&mut v, at, payload, CrcBasis::Both);
    v
}

#[test]
fn live_timeouts_and_the_recording_replays() {
    let _g = lock();
    let common::pty::Bus {
        mut master,
        slave,
        path,
    } = bus();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("sbus.pcap");
    let (mut child, rx) = spawn(
        &[
            "sbus",
            "--mode",
            "data",
            "-f",
            "tsv",
            "--stats",
            "--record",
            rec.to_str().unwrap(),
        ],
        &path,
    );
    let (_, header) = next_line(&rx);
    assert!(header.starts_with("Counter\tMillis\tID"), "{header}");
    let mut live = vec![header];

    // A read of R5 at station 3 that nobody answers.
    master.write_all(&telegram(0, &[3, 6, 0, 0, 5])).unwrap();
    master.flush().unwrap();
    let sent = Instant::now();
    let (_, req) = next_line(&rx);
    assert!(req.contains("\tRequest\tR5\tRead register(s)\t"), "{req}");
    live.push(req);
    // The Timeout row comes while the line is silent, after the 375 ms master timeout.
    let (t, timeout) = next_line(&rx);
    assert!(timeout.contains("\tTimeout\tR5\t"), "{timeout}");
    assert!(timeout.ends_with("no answer within 375 ms"), "{timeout}");
    assert!(
        t.duration_since(sent) >= Duration::from_millis(300),
        "{:?}",
        t - sent
    );
    live.push(timeout);

    // The late answer still pairs, flagged.
    std::thread::sleep(Duration::from_millis(100));
    master.write_all(&telegram(1, &[0, 0, 0, 42])).unwrap();
    master.flush().unwrap();
    let (_, resp) = next_line(&rx);
    assert!(
        resp.contains("\tResponse\tR5\tRead register(s)\tR5=42\t"),
        "{resp}"
    );
    assert!(resp.contains("late: after the 375 ms timeout"), "{resp}");
    live.push(resp);

    // A write answered at once.
    std::thread::sleep(Duration::from_millis(50));
    master
        .write_all(&telegram(0, &[3, 0x0E, 5, 0, 7, 0, 0, 0, 9]))
        .unwrap();
    master.write_all(&telegram(2, &[0, 0])).unwrap();
    master.flush().unwrap();
    for want in ["\tRequest\tR7\tWrite register(s)\tR7=9\t", "\tACK\tR7\t"] {
        let (_, l) = next_line(&rx);
        assert!(l.contains(want), "{l}");
        live.push(l);
    }

    // Unplug.
    std::thread::sleep(Duration::from_millis(100));
    drop(master);
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(7), "adapter disconnected");
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert!(err.contains("S-Bus statistics"), "{err}");
    assert!(err.contains("data mode, master timeout 375 ms"), "{err}");
    while let Ok((_, l)) = rx.recv_timeout(common::PATIENCE) {
        live.push(l);
    }
    assert_eq!(live.len(), 6, "{live:?}");

    // The recording (real arrival times) replays to the same rows.
    let replay = Command::new(bin())
        .args(["sbus", "--mode", "data", "-f", "tsv"])
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
