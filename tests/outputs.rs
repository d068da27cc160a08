//! Outputs and options on the command line: special outputs (/dev/null, /dev/stdout, FIFOs,
//! closed pipes) work, `-` means standard output, option values are checked, any OS path is
//! accepted, EdgeTX logs keep their lines (docs/robustness.md, "Paths and options"). The input
//! is never overwritten: tests/safety.rs.

mod common;

use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::os::unix::ffi::OsStrExt;
use std::process::Stdio;

use common::fixture;
use common::{busnoop, capture, no_panic, output_within, text};

#[test]
fn unrelated_outputs_still_work() {
    // The check must not refuse what is fine: the same /dev/null twice, stdin and stdout on one
    // terminal-like device, a new output next to the input.
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap");
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(dir.path().join("cap.csv"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(std::fs::read(&cap).unwrap(), bytes);
    let out = busnoop()
        .args([
            "sport",
            "/dev/null",
            "-o",
            "/dev/null",
            "--record",
            "/dev/null",
        ])
        .output()
        .unwrap();
    // Accepted (no usage error); the input is empty, which is said with its own code.
    assert_eq!(out.status.code(), Some(10), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stderr),
        "busnoop: empty input: /dev/null holds no bytes\n"
    );
}

#[test]
fn special_outputs_are_not_synced() {
    // fdatasync fails on /dev/null, a FIFO or a pipe: only regular files are synced.
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .args(["-o", "/dev/null"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stderr), "");

    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .args(["-o", "/dev/stdout"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).starts_with("Counter\t"));

    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    common::mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap())
    };
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .arg("-o")
        .arg(&fifo)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&reader.join().unwrap()).starts_with("Counter\t"));
}

#[test]
fn output_to_dev_stdout_closed_by_the_reader_exits_quietly() {
    // `busnoop sport big.bin -o /dev/stdout | head -1`: like stdout itself, 141 and no message.
    let dir = tempfile::tempdir().unwrap();
    let big = common::big_sport(dir.path(), 100_000, 0x0100);
    let mut child = busnoop()
        .arg("sport")
        .arg(&big)
        .args(["-o", "/dev/stdout"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("Counter\t"));
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(141));
    assert_eq!(text(&out.stderr), "");
}

/// A recording into a pipe whose reader goes away (`--record FIFO`, `--record >(tshark -r -)`
/// and tshark quits) ends like the table's and the export's pipe: quietly, 141. It used to be
/// `cannot write recording …: Broken pipe`, exit 8.
#[test]
fn a_recording_pipe_closed_by_the_reader_exits_quietly() {
    use std::io::Read;
    let dir = tempfile::tempdir().unwrap();
    let big = common::big_sport(dir.path(), 100_000, 0x0100);
    let fifo = dir.path().join("r.pcap");
    common::mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut head = [0u8; 100];
            std::fs::File::open(&fifo)
                .unwrap()
                .read_exact(&mut head)
                .unwrap();
            head
        })
    };
    let out = output_within(
        busnoop()
            .arg("sport")
            .arg(&big)
            .arg("--record")
            .arg(&fifo)
            .args(["-o", "/dev/null"]),
        None,
        Stdio::null(),
    );
    let head = reader.join().unwrap();
    assert_eq!(&head[2..4], &[0xb2, 0xa1], "a pcap header");
    no_panic(&out);
    assert_eq!(out.status.code(), Some(141), "{}", text(&out.stderr));
    assert_eq!(text(&out.stderr), "");
}

#[test]
fn the_capture_extension_guard_ignores_case() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["x.PCAP", "x.PcapNG", "x.BIN"] {
        let target = dir.path().join(name);
        let out = busnoop()
            .arg("sport")
            .arg(fixture("sport-sample.bin"))
            .arg("-o")
            .arg(&target)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{name}");
        assert!(text(&out.stderr).contains("--record"), "{name}");
        assert!(!target.exists(), "{name}");
    }
}

#[test]
fn dash_means_standard_output() {
    let dir = tempfile::tempdir().unwrap();
    // -o -: the table on stdout, no file named `-`.
    let out = busnoop()
        .current_dir(dir.path())
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .args(["-o", "-"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).starts_with("Counter\t"));
    assert!(!dir.path().join("-").exists());

    // --record - with the table in a file: the raw bytes on stdout.
    let out = busnoop()
        .current_dir(dir.path())
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .args(["--record", "-", "-o", "t.csv"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        out.stdout,
        std::fs::read(fixture("sport-sample.bin")).unwrap()
    );
    assert!(dir.path().join("t.csv").exists());
    assert!(!dir.path().join("-").exists());

    // --record - with the table on stdout as well: refused.
    for extra in [&[][..], &["-o", "-"][..]] {
        let out = busnoop()
            .current_dir(dir.path())
            .arg("sport")
            .arg(fixture("sport-sample.bin"))
            .args(["--record", "-"])
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        assert!(
            text(&out.stderr).contains("--record - needs -o FILE"),
            "{}",
            text(&out.stderr)
        );
        assert!(out.stdout.is_empty());
        assert!(!dir.path().join("-").exists());
    }
}

#[test]
fn paths_that_are_not_utf8_are_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join(OsStr::from_bytes(b"cap\xff"));
    std::fs::copy(fixture("sport-sample.bin"), &src).unwrap();
    let csv = dir.path().join(OsStr::from_bytes(b"t\xfe.csv"));
    let rec = dir.path().join(OsStr::from_bytes(b"r\xfd.pcap"));
    let out = busnoop()
        .arg("sport")
        .arg(&src)
        .arg("-o")
        .arg(&csv)
        .arg("--record")
        .arg(&rec)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&std::fs::read(&csv).unwrap()).starts_with("Counter,"));
    // The recording replays.
    let out = busnoop().arg("sport").arg(&rec).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).lines().count() > 10);
}

/// The run was refused with clap's usage error naming the valid range.
fn out_of_range(args: &[&str], range: &str) {
    let out = busnoop()
        .args(args)
        .arg(fixture("sport-sample.bin"))
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(err.contains(range), "{args:?}: {err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn numeric_options_out_of_range_are_refused() {
    for t in ["0", "18446744073709552", "3600001"] {
        out_of_range(&["sbus", "--timeout-ms", t], "from 1 to 3600000");
        out_of_range(&["sbus", "--gap-ms", t], "from 1 to 3600000");
        out_of_range(&["sab2", "--timeout-ms", t], "from 1 to 3600000");
    }
    out_of_range(&["sbus", "--udp-port", "0"], "from 1 to 65535");
    out_of_range(&["sbus", "--port", "0"], "from 1 to 65535");
    out_of_range(&["sab2", "--max-payload", "0"], "from 1 to 255");
    // --speed: 0, or 0.001 to 1000. A tiny speed (1e-300) panicked turning the first delay
    // into a Duration; 1e-10 would wait centuries per second of capture.
    for s in ["1e-300", "1e-10", "0.0009", "-1", "1001", "NaN"] {
        out_of_range(&["sport", &format!("--speed={s}")], "0.001 to 1000");
    }
    for cmd in ["sport", "sbus", "sab2"] {
        for b in ["0", "49", "12000001", "99999999999"] {
            out_of_range(&[cmd, "--baud", b], "from 50 to 12000000");
        }
    }
    // The limits themselves are accepted.
    let out = busnoop()
        .args([
            "sbus",
            "--timeout-ms",
            "3600000",
            "--gap-ms",
            "1",
            "--baud",
            "50",
            // S.Port bytes through sbus: a poor run, accepted here.
            "--lenient",
        ])
        .arg(fixture("sport-sample.bin"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

#[test]
fn an_edgetx_log_with_a_byte_order_mark_keeps_its_first_line() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bom.log");
    let mut text_in = b"\xEF\xBB\xBF".to_vec();
    text_in.extend_from_slice(b"2014-07-11,22:41:01.340: 7E A1\n2014-07-11,22:41:01.350: 7E 22\n");
    std::fs::write(&log, text_in).unwrap();
    let out = busnoop().arg("sport").arg(&log).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stderr), "", "no line is skipped");
    let rows: Vec<String> = text(&out.stdout)
        .lines()
        .skip(1)
        .map(String::from)
        .collect();
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert!(rows[0].starts_with("1\t0\t1\t"), "{rows:?}");
}

#[test]
fn time_going_back_in_an_edgetx_log_is_a_row_and_keeps_the_logged_time() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("jump.log");
    std::fs::write(
        &log,
        "2014-07-11,22:41:05.000: 7E A1\n\
         2014-07-11,22:41:05.100: 7E 22\n\
         2014-07-11,22:41:01.000: 7E 83\n\
         2014-07-11,22:41:01.012: 7E E4\n",
    )
    .unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&log)
        .args(["--time", "abs", "--utc"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let rows: Vec<Vec<String>> = text(&out.stdout)
        .lines()
        .skip(1)
        .map(|l| l.split('\t').map(String::from).collect())
        .collect();
    let kinds: Vec<&str> = rows.iter().map(|r| r[4].as_str()).collect();
    assert_eq!(kinds, ["", "", "TimeJump", "", ""], "{rows:?}");
    let jump = &rows[2];
    assert!(jump[7].contains("4.100 s"), "{jump:?}");
    // Millis never goes back; the Time column shows what the log says.
    let millis: Vec<u64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    assert!(millis.windows(2).all(|w| w[0] <= w[1]), "{millis:?}");
    let times: Vec<&str> = rows.iter().map(|r| r[11].as_str()).collect();
    assert!(times[0].contains("22:41:05.000"), "{times:?}");
    assert!(times[3].contains("22:41:01.000"), "{times:?}");
    assert!(times[4].contains("22:41:01.012"), "{times:?}");
}
