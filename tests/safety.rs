//! Data safety on the command line: the input is never overwritten, special outputs work,
//! option values are checked, any OS path is accepted (docs/robustness.md, "Paths and options").

mod common;

use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};

use busnoop::sport::wire;
use common::fixture;
use common::{busnoop, text};

fn no_panic(out: &Output) {
    let err = text(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
}

/// A copy of the S.Port sample, repeated so that it is more than one read chunk, in `dir` under
/// `name` (no capture extension: the extension guard of `-o` must not be what saves it).
fn capture(dir: &Path, name: &str) -> (PathBuf, Vec<u8>) {
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let bytes = sample.repeat(400);
    let p = dir.join(name);
    std::fs::write(&p, &bytes).unwrap();
    (p, bytes)
}

/// The run was refused with a usage error naming the clash, and `path` still holds `bytes`.
fn refused(out: &Output, path: &Path, bytes: &[u8]) {
    no_panic(out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("same file"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        std::fs::read(path).unwrap() == bytes,
        "{} was changed",
        path.display()
    );
}

#[test]
fn output_onto_the_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap");

    // -o onto the input, directly, through a symlink either way, through a hard link.
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&cap)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    let sym = dir.path().join("sym");
    std::os::unix::fs::symlink(&cap, &sym).unwrap();
    for (src, dst) in [(&cap, &sym), (&sym, &cap)] {
        let out = busnoop()
            .arg("sport")
            .arg(src)
            .arg("-o")
            .arg(dst)
            .output()
            .unwrap();
        refused(&out, &cap, &bytes);
    }
    let hard = dir.path().join("hard");
    std::fs::hard_link(&cap, &hard).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&hard)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);

    // A capture's own name (`-o a.bin` onto a.bin): the clash is named, not the hint to use
    // --record a.bin, which would point at the input again.
    let (bin, bin_bytes) = capture(dir.path(), "a.bin");
    let out = busnoop()
        .arg("sport")
        .arg(&bin)
        .arg("-o")
        .arg(&bin)
        .output()
        .unwrap();
    refused(&out, &bin, &bin_bytes);

    // Standard input is the file: `busnoop sport - -o cap < cap`.
    let out = busnoop()
        .args(["sport", "-", "-o"])
        .arg(&cap)
        .stdin(std::fs::File::open(&cap).unwrap())
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);

    // --record onto the input.
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&hard)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);

    // Standard output appends to the input: `busnoop sport - < cap >> cap`.
    let out = busnoop()
        .args(["sport", "-"])
        .stdin(std::fs::File::open(&cap).unwrap())
        .stdout(std::fs::OpenOptions::new().append(true).open(&cap).unwrap())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
}

#[test]
fn a_plot_onto_its_input_is_refused() {
    // `busnoop plot` writes .svg or .png: a capture under such a name (or a link of that name
    // to the capture) must not become the image.
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap.svg");
    let out = busnoop()
        .args(["plot", "--protocol", "sport"])
        .arg(&cap)
        .arg("-o")
        .arg(&cap)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    let png = dir.path().join("link.png");
    std::os::unix::fs::symlink(&cap, &png).unwrap();
    let out = busnoop()
        .args(["plot", "--protocol", "sport"])
        .arg(&cap)
        .arg("-o")
        .arg(&png)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
}

#[test]
fn a_recording_replayed_onto_itself_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let rec = dir.path().join("rec.pcap");
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&rec)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let bytes = std::fs::read(&rec).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&rec)
        .arg("--record")
        .arg(&rec)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    refused(&out, &rec, &bytes);
}

#[test]
fn record_and_output_onto_one_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap");
    // X does not exist yet: the names are compared.
    let x = dir.path().join("x.txt");
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("-o")
        .arg(dir.path().join(".").join("x.txt"))
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    assert!(!x.exists(), "nothing is created");
    // X exists: the files are compared.
    std::fs::write(&x, b"keep").unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("-o")
        .arg(&x)
        .output()
        .unwrap();
    refused(&out, &x, b"keep");
}

/// Runs `cmd` (standard input from `stdin`, written and closed by a thread; standard output to
/// `stdout`) and returns its output; kills it and fails when it has not exited within 10 s (a
/// run that writes into its own input pipe never ends).
fn output_within_10s(
    cmd: &mut std::process::Command,
    stdin: Option<Vec<u8>>,
    stdout: Stdio,
) -> Output {
    use std::io::Write;
    use std::time::{Duration, Instant};
    let mut child = cmd
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(stdout)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    if let Some(bytes) = stdin {
        let mut pipe = child.stdin.take().unwrap();
        // busnoop may refuse before reading anything: a broken pipe is fine.
        std::thread::spawn(move || pipe.write_all(&bytes));
    }
    let deadline = Instant::now() + Duration::from_secs(10);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("busnoop did not exit within 10 s: {cmd:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}

/// A refused run: exit code 2 and one line naming the clash and what writing would do.
fn refused_saying(out: &Output, consequence: &str) {
    no_panic(out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("same file"), "{err}");
    assert!(err.contains(consequence), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
}

#[test]
fn output_into_the_input_pipe_is_refused() {
    // `… | busnoop sport - -o /dev/stdin`: the output would be the pipe busnoop reads, which
    // then never ends (busnoop holds its write end) and carries busnoop's own rows back in.
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    for args in [
        ["sport", "-", "-o", "/dev/stdin"],
        ["sport", "-", "--record", "/dev/stdin"],
    ] {
        let out = output_within_10s(busnoop().args(args), Some(sample.clone()), Stdio::piped());
        refused_saying(&out, "its own output");
    }

    // A named pipe given as the input and as the output.
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    let c = std::ffi::CString::new(fifo.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let out = output_within_10s(
        busnoop().arg("sport").arg(&fifo).arg("-o").arg(&fifo),
        None,
        Stdio::piped(),
    );
    refused_saying(&out, "its own output");
}

#[test]
fn output_onto_the_serial_port_is_refused() {
    // `busnoop sport /dev/ttyUSB0 -o /dev/ttyUSB0` (or `> /dev/ttyUSB0`, or `--record` there)
    // would transmit the table on the bus: a passive sniffer never sends a byte.
    let _lock = common::pty::lock();
    let mut bus = common::pty::bus();
    let dev = bus.path.clone();
    for opt in ["-o", "--record"] {
        let out = output_within_10s(
            busnoop().arg("sport").arg(&dev).arg(opt).arg(&dev),
            None,
            Stdio::piped(),
        );
        refused_saying(&out, "transmit");
    }
    let tty = std::fs::OpenOptions::new().write(true).open(&dev).unwrap();
    let out = output_within_10s(busnoop().arg("sport").arg(&dev), None, tty.into());
    no_panic(&out);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("transmit"),
        "{}",
        text(&out.stderr)
    );
    // Nothing reached the bus side.
    serialport::SerialPort::set_timeout(&mut bus.master, std::time::Duration::from_millis(200))
        .unwrap();
    let mut buf = [0u8; 64];
    let got = std::io::Read::read(&mut bus.master, &mut buf);
    assert!(
        !matches!(got, Ok(n) if n > 0),
        "busnoop wrote to the bus: {got:?} {:?}",
        &buf[..*got.as_ref().unwrap_or(&0)]
    );
}

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
    let c = std::ffi::CString::new(fifo.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
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
    let big = dir.path().join("big.bin");
    let mut bytes = Vec::new();
    for i in 0..100_000u32 {
        wire::encode_frame(
            &mut bytes,
            wire::header_for((i % 28) as u8),
            0x10,
            0x0100,
            i,
        );
    }
    std::fs::write(&big, bytes).unwrap();
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
    let big = dir.path().join("big.bin");
    let mut bytes = Vec::new();
    for i in 0..100_000u32 {
        wire::encode_frame(
            &mut bytes,
            wire::header_for((i % 28) as u8),
            0x10,
            0x0100,
            i,
        );
    }
    std::fs::write(&big, bytes).unwrap();
    let fifo = dir.path().join("r.pcap");
    let c = std::ffi::CString::new(fifo.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
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
    let out = output_within_10s(
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
        out_of_range(&["sbus", "--timeout-ms", t], "1..=3600000");
        out_of_range(&["sbus", "--gap-ms", t], "1..=3600000");
        out_of_range(&["sab2", "--timeout-ms", t], "1..=3600000");
    }
    out_of_range(&["sbus", "--udp-port", "0"], "1..=65535");
    out_of_range(&["sbus", "--port", "0"], "1..=65535");
    out_of_range(&["sab2", "--max-payload", "0"], "1..=255");
    // --speed: 0, or 0.001 to 1000. A tiny speed (1e-300) panicked turning the first delay
    // into a Duration; 1e-10 would wait centuries per second of capture.
    for s in ["1e-300", "1e-10", "0.0009", "-1", "1001", "NaN"] {
        out_of_range(&["sport", &format!("--speed={s}")], "0.001 to 1000");
    }
    for cmd in ["sport", "sbus", "sab2"] {
        for b in ["0", "49", "12000001", "99999999999"] {
            out_of_range(&[cmd, "--baud", b], "50..=12000000");
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

/// `--export` is an output like `-o` and `--record`: compared with them as files, not as
/// names (`--record x.pcapng --export ./x.pcapng` used to write both into one file, the
/// recording's blocks and the export's interleaved), and the message names `--export`.
#[test]
fn export_onto_the_recording_or_the_table_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let x = dir.path().join("x.pcapng");
    // X does not exist yet: two spellings of one name (`Path`'s `==` would see through a
    // `.`, not through `sub/..`).
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("--export")
        .arg(dir.path().join("sub/../x.pcapng"))
        .args(["-o", "/dev/null"])
        .output()
        .unwrap();
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--export") && err.contains("same file"),
        "{err}"
    );
    assert!(!x.exists(), "nothing is created");
    // X exists, named through a symbolic link.
    std::fs::write(&x, b"keep").unwrap();
    let link = dir.path().join("link.pcapng");
    std::os::unix::fs::symlink(&x, &link).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("--export")
        .arg(&link)
        .args(["-o", "/dev/null"])
        .output()
        .unwrap();
    refused(&out, &x, b"keep");
    assert!(text(&out.stderr).contains("--export"));
    // Standard output appended to the export: the message names --export, not --record.
    let stdout = std::fs::OpenOptions::new().append(true).open(&x).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--export")
        .arg(&x)
        .stdout(stdout)
        .output()
        .unwrap();
    refused(&out, &x, b"keep");
    let err = text(&out.stderr);
    assert!(err.contains("standard output and --export"), "{err}");
}

/// An output named through a symbolic link whose target does not exist yet is created at the
/// target: `-o out.csv --record r.pcap` with `out.csv -> r.pcap` used to pass the check (a
/// dangling link had no name to compare) and wrote the table into the recording.
#[test]
fn outputs_meeting_through_a_dangling_link_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap");
    let rec = dir.path().join("r.pcap");
    let link = dir.path().join("out.csv");
    std::os::unix::fs::symlink("r.pcap", &link).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&link)
        .arg("--record")
        .arg(&rec)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    assert!(!rec.exists(), "nothing is created");
    // A chain of links, the last one dangling, to the export.
    let hop = dir.path().join("hop.pcapng");
    std::os::unix::fs::symlink("e.pcapng", &hop).unwrap();
    let first = dir.path().join("first.csv");
    std::os::unix::fs::symlink(&hop, &first).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&first)
        .arg("--export")
        .arg(dir.path().join("e.pcapng"))
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    assert!(!dir.path().join("e.pcapng").exists(), "nothing is created");
}

/// `busnoop plot`'s image name and folder are checked before the capture is read: they used
/// to be checked only when the image was drawn, after the whole input (a pipe, a FIFO, a long
/// capture) had been decoded, and a wrong extension was exit code 8. Here the input is a FIFO
/// no one writes to: reading it would wait for ever.
#[test]
fn a_plot_checks_its_image_name_before_reading_the_capture() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    let c = std::ffi::CString::new(fifo.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let plot = |image: PathBuf| {
        output_within_10s(
            busnoop()
                .arg("plot")
                .arg(&fifo)
                .args(["--protocol", "sport", "-o"])
                .arg(image),
            None,
            Stdio::piped(),
        )
    };
    let out = plot(dir.path().join("flight.txt"));
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(".svg or .png"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    let out = plot(dir.path().join("no-such-folder").join("flight.svg"));
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(8), "{err}");
    assert!(
        err.contains("no-such-folder") && err.contains("No such file or directory"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

/// An output into a folder that does not exist is refused before any output is created: a
/// typo in `-o` used to fail only after the recording and the export had been created (and an
/// existing recording of that name emptied), a typo in `--record` after the table had.
#[test]
fn an_output_into_a_missing_folder_creates_no_other_output() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let missing = dir.path().join("no-such-folder");
    let rec = dir.path().join("r.pcap");
    std::fs::write(&rec, b"keep").unwrap();
    let export = dir.path().join("e.pcapng");
    let table = dir.path().join("t.csv");
    let runs: [(&str, PathBuf, &str, PathBuf, &str, PathBuf); 3] = [
        (
            "-o",
            missing.join("t.csv"),
            "--record",
            rec.clone(),
            "--export",
            export.clone(),
        ),
        (
            "-o",
            table.clone(),
            "--record",
            missing.join("r.pcap"),
            "--export",
            export.clone(),
        ),
        (
            "-o",
            table.clone(),
            "--record",
            rec.clone(),
            "--export",
            missing.join("e.pcapng"),
        ),
    ];
    for (o, a, r, b, e, c) in runs {
        let out = busnoop()
            .arg("sport")
            .arg(&cap)
            .args([
                o.as_ref(),
                a.as_os_str(),
                r.as_ref(),
                b.as_os_str(),
                e.as_ref(),
                c.as_os_str(),
            ])
            .output()
            .unwrap();
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(8), "{err}");
        assert!(
            err.contains("no-such-folder") && err.contains("No such file"),
            "{err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(
            std::fs::read(&rec).unwrap(),
            b"keep",
            "the recording was emptied"
        );
        assert!(
            !export.exists() && !table.exists(),
            "an output was created: {err}"
        );
    }
}

/// The project file is an input too: `-o busnoop.toml` (the one in the current folder, read
/// without being named), `--config my.toml -o my.toml`, or a link to it, used to overwrite it
/// with the table (a note said only that .toml is no table format).
#[test]
fn output_onto_the_project_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let project = b"[sport]\nnames = { Rx = 24 }\n";
    let toml = dir.path().join("busnoop.toml");
    std::fs::write(&toml, project).unwrap();
    let link = dir.path().join("notes.txt");
    std::os::unix::fs::symlink("busnoop.toml", &link).unwrap();
    let mine = dir.path().join("my.toml");
    std::fs::write(&mine, project).unwrap();
    let runs: [(Vec<&OsStr>, &Path); 3] = [
        (vec!["-o".as_ref(), "busnoop.toml".as_ref()], &toml),
        (vec!["-o".as_ref(), link.as_os_str()], &toml),
        (
            vec![
                "--config".as_ref(),
                mine.as_os_str(),
                "-o".as_ref(),
                "./my.toml".as_ref(),
            ],
            &mine,
        ),
    ];
    for (args, file) in runs {
        let out = busnoop()
            .current_dir(dir.path())
            .arg("sport")
            .arg(&cap)
            .args(&args)
            .output()
            .unwrap();
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("project file"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(std::fs::read(file).unwrap(), project, "{args:?}");
    }
}
