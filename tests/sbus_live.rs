//! Live serial S-Bus on a pseudo-terminal pair: rows appear as telegrams complete, a missing
//! answer becomes a Timeout row while the line is silent, and the recording replays to the same
//! rows.

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use busnoop::sbus::telegram::{CrcBasis, encode_data};
use serialport::{SerialPort, TTYPort};

fn bin() -> PathBuf {
    assert_cmd::cargo::cargo_bin("busnoop")
}

fn spawn(args: &[&str], device: &std::path::Path) -> (Child, Receiver<(Instant, String)>) {
    let mut child = Command::new(bin())
        .args(args)
        .arg(device)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send((Instant::now(), line)).is_err() {
                break;
            }
        }
    });
    (child, rx)
}

fn next_line(rx: &Receiver<(Instant, String)>) -> (Instant, String) {
    rx.recv_timeout(Duration::from_secs(10))
        .expect("busnoop printed nothing for 10 s")
}

fn wait_exit(child: &mut Child) -> std::process::ExitStatus {
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        assert!(Instant::now() < deadline, "busnoop did not exit");
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn telegram(at: u8, payload: &[u8]) -> Vec<u8> {
    let mut v = Vec::new();
    encode_data(&mut v, at, payload, CrcBasis::Both);
    v
}

#[test]
fn live_timeouts_and_the_recording_replays() {
    use std::os::fd::AsRawFd;
    let (mut master, slave) = TTYPort::pair().expect("pty pair");
    for fd in [master.as_raw_fd(), slave.as_raw_fd()] {
        unsafe { libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC) };
    }
    let path = PathBuf::from(slave.name().unwrap());
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
    while let Ok((_, l)) = rx.recv_timeout(Duration::from_secs(2)) {
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
