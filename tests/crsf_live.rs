//! `busnoop crsf` on a live serial line (a pseudo-terminal pair at the CRSF rate): rows come as
//! the frames arrive, a garbage run is shown while the line is quiet, the recording replays to
//! the same rows, and `detect` recognises the line.

mod common;

use std::io::Write;
use std::process::Command;
use std::time::{Duration, Instant};

use busnoop::crsf::wire;
use common::pty::{bin, bus, lock, next_line, spawn, stderr_of, wait_exit};

fn rc(i: u16) -> Vec<u8> {
    let ch: Vec<u16> = (0..16).map(|k| 172 + (i * 37 + k * 100) % 1640).collect();
    let mut f = Vec::new();
    wire::encode(&mut f, 0xC8, 0x16, &wire::pack_bits(&ch, 11));
    f
}

#[test]
fn rows_stream_live_and_the_recording_replays() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("live.pcapng");
    let mut b = bus();
    let (mut child, rx) = spawn(
        &["crsf", "-f", "tsv", "--record", rec.to_str().unwrap()],
        &b.path,
    );
    let (_, header) = next_line(&rx);
    assert!(header.starts_with("Counter\tMillis\tID"));
    let mut live = vec![header];
    // 20 RC frames at 250 Hz, each written in two pieces.
    for i in 0..20 {
        let f = rc(i);
        b.master.write_all(&f[..7]).unwrap();
        b.master.flush().unwrap();
        b.master.write_all(&f[7..]).unwrap();
        b.master.flush().unwrap();
        std::thread::sleep(Duration::from_millis(4));
    }
    for _ in 0..20 {
        let (_, line) = next_line(&rx);
        assert!(line.contains("\tRC\t0x16\tCH1\t"), "{line}");
        live.push(line);
    }
    // Noise, then quiet: the garbage row comes while nothing else arrives.
    b.master.write_all(&[0x11, 0x22, 0x33]).unwrap();
    b.master.flush().unwrap();
    let asked = Instant::now();
    let (at, line) = next_line(&rx);
    assert!(
        line.contains("\tGarbage\t") && line.contains("11 22 33"),
        "{line}"
    );
    assert!(at.duration_since(asked) < Duration::from_secs(5));
    live.push(line);
    drop(b.master);
    wait_exit(&mut child);
    let err = stderr_of(&mut child);
    assert!(err.contains("CRSF: 3 garbage bytes skipped"), "{err}");
    let millis: Vec<u64> = live[1..21]
        .iter()
        .map(|l| l.split('\t').nth(1).unwrap().parse().unwrap())
        .collect();
    assert!(millis.windows(2).all(|w| w[0] <= w[1]), "{millis:?}");

    let replay = Command::new(bin())
        .args(["crsf", "-f", "tsv"])
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
fn detect_recognises_a_live_crsf_line() {
    let _g = lock();
    let mut b = bus();
    let path = b.path.clone();
    let child = Command::new(bin())
        .args(["detect", "--listen-ms", "400", "--baud", "420000,115200"])
        .arg(&path)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(3);
    let mut i = 0;
    while Instant::now() < deadline {
        b.master.write_all(&rc(i)).unwrap();
        b.master.flush().unwrap();
        i += 1;
        std::thread::sleep(Duration::from_millis(4));
    }
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("verdict: CRSF"),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("busnoop crsf"), "{text}");
}
