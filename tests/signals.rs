//! Signals end busnoop promptly whatever it is doing: replaying a fast endless source, a large
//! file, or waiting for a FIFO's writer. Every decoded row is kept, the output ends with a whole
//! row, and stderr says how much input was left.

mod common;

use std::io::Write;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use common::{mkfifo, wait_for_handlers};

/// Generous bound for "stops at once": the old driver took 70-180 s here.
const STOP_WITHIN: Duration = common::PATIENCE;

fn busnoop() -> Command {
    let mut c = Command::new(assert_cmd::cargo::cargo_bin("busnoop"));
    c.stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

/// Kills the child if the test fails before it exited.
struct Guard(Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Waits until `path` holds at least `lines` lines.
fn wait_for_rows(path: &Path, lines: usize) {
    let deadline = Instant::now() + common::PATIENCE;
    while std::fs::read(path)
        .unwrap_or_default()
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        < lines
    {
        assert!(Instant::now() < deadline, "rows did not arrive");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Sends `sig` and waits for the exit; fails when busnoop is still running after `within`.
fn signal_and_wait(guard: &mut Guard, sig: i32, within: Duration) -> (ExitStatus, String) {
    unsafe { libc::kill(guard.0.id() as i32, sig) };
    let sent = Instant::now();
    let status = loop {
        if let Some(s) = guard.0.try_wait().unwrap() {
            break s;
        }
        assert!(
            sent.elapsed() < within,
            "busnoop still running {within:?} after signal {sig}"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(guard.0.stderr.as_mut().unwrap(), &mut err).unwrap();
    (status, err)
}

#[test]
fn ctrl_c_stops_a_fast_endless_replay_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let (fifo, out) = (dir.path().join("feed"), dir.path().join("out.tsv"));
    let (mut guard, writer) = endless_replay(&fifo, &out, false);
    let (status, err) = signal_and_wait(&mut guard, libc::SIGINT, STOP_WITHIN);
    assert_eq!(status.code(), Some(130), "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.ends_with('\n'), "the output ends with a whole row");
    let rows = text.lines().count() - 1;
    let line = err
        .lines()
        .find(|l| l.contains("interrupted after"))
        .unwrap_or_else(|| panic!("no interrupted line: {err}"));
    assert!(line.contains(&format!("after {rows} rows")), "{line}");
    // A pipe has no size: what was decoded, what was read and dropped, the rest never read.
    assert!(line.contains("bytes of the input decoded"), "{line}");
    assert!(line.contains("rest left unread"), "{line}");
    writer.join().unwrap();
}

/// Starts `busnoop sport -f tsv -o OUT FIFO` on an endless stream of 0x7E (garbage rows as fast
/// as the pipe takes them, until busnoop closes its end), `ignore_hup`: with SIGHUP ignored, as `nohup` starts it. Returns
/// the child once its first 1000 rows are written, with the writer thread.
fn endless_replay(
    fifo: &Path,
    out: &Path,
    ignore_hup: bool,
) -> (Guard, std::thread::JoinHandle<()>) {
    use std::os::unix::process::CommandExt;
    mkfifo(fifo);
    let writer = {
        let fifo = fifo.to_owned();
        std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new().write(true).open(fifo).unwrap();
            let buf = [0x7Eu8; 64 * 1024];
            while f.write_all(&buf).is_ok() {}
        })
    };
    let mut cmd = busnoop();
    cmd.args(["sport", "-f", "tsv", "-o"]).arg(out).arg(fifo);
    // Ignored as `nohup` starts it, or as a terminal would start it whatever started the
    // tests (a suite run under `nohup` passes SIGHUP ignored on).
    let hup = if ignore_hup {
        libc::SIG_IGN
    } else {
        libc::SIG_DFL
    };
    // SAFETY: only signal() in the child before exec.
    unsafe {
        cmd.pre_exec(move || {
            libc::signal(libc::SIGHUP, hup);
            Ok(())
        });
    }
    let guard = Guard(cmd.spawn().unwrap());
    wait_for_rows(out, 1000);
    (guard, writer)
}

/// A hangup (the SSH session or the terminal gone) stops busnoop like SIGTERM: every decoded
/// row written, whole, exit code 129. It used to kill busnoop with the rows still buffered.
#[test]
fn a_hangup_stops_cleanly_with_every_row_written() {
    let dir = tempfile::tempdir().unwrap();
    let (fifo, out) = (dir.path().join("feed"), dir.path().join("out.tsv"));
    let (mut guard, writer) = endless_replay(&fifo, &out, false);
    let (status, err) = signal_and_wait(&mut guard, libc::SIGHUP, STOP_WITHIN);
    assert_eq!(status.code(), Some(129), "{status:?} {err}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.ends_with('\n'), "the output ends with a whole row");
    let rows = text.lines().count() - 1;
    assert!(err.contains(&format!("after {rows} rows")), "{err}");
    writer.join().unwrap();
}

/// Under `nohup` (SIGHUP ignored) a hangup does not stop busnoop: it keeps capturing.
#[test]
fn a_hangup_under_nohup_is_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let (fifo, out) = (dir.path().join("feed"), dir.path().join("out.tsv"));
    let (mut guard, writer) = endless_replay(&fifo, &out, true);
    unsafe { libc::kill(guard.0.id() as i32, libc::SIGHUP) };
    // Still decoding after the hangup: 10 000 rows more arrive.
    let rows = std::fs::read(&out)
        .unwrap()
        .iter()
        .filter(|&&b| b == b'\n')
        .count();
    wait_for_rows(&out, rows + 10_000);
    assert!(guard.0.try_wait().unwrap().is_none(), "a hangup stopped it");
    let (status, err) = signal_and_wait(&mut guard, libc::SIGTERM, STOP_WITHIN);
    assert_eq!(status.code(), Some(143), "{status:?} {err}");
    writer.join().unwrap();
}

#[test]
fn sigterm_stops_a_large_file_and_says_how_much_was_not_read() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.bin");
    let out = dir.path().join("out.csv");
    // 1 GiB of zeros (sparse, so it costs nothing): garbage rows for a long time.
    let size: u64 = 1 << 30;
    std::fs::File::create(&big).unwrap().set_len(size).unwrap();
    let child = busnoop()
        .args(["sport", "-o"])
        .arg(&out)
        .arg(&big)
        .spawn()
        .unwrap();
    let mut guard = Guard(child);
    wait_for_rows(&out, 1000);
    let (status, err) = signal_and_wait(&mut guard, libc::SIGTERM, STOP_WITHIN);
    assert_eq!(status.code(), Some(143), "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.ends_with("\r\n"), "the CSV ends with a whole row");
    let line = err
        .lines()
        .find(|l| l.contains("interrupted after"))
        .unwrap_or_else(|| panic!("no interrupted line: {err}"));
    assert!(line.contains(&format!("of {size} bytes")), "{line}");
    assert!(line.contains("not decoded"), "{line}");
}

#[test]
fn a_fifo_without_a_writer_ends_on_a_signal() {
    for (sig, code) in [(libc::SIGTERM, 143), (libc::SIGINT, 130)] {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("nobody-writes");
        mkfifo(&fifo);
        let child = busnoop().arg("sport").arg(&fifo).spawn().unwrap();
        let mut guard = Guard(child);
        wait_for_handlers(&guard.0);
        std::thread::sleep(Duration::from_millis(200));
        let (status, err) = signal_and_wait(&mut guard, sig, STOP_WITHIN);
        assert_eq!(status.code(), Some(code), "signal {sig}: {err}");
        assert!(!err.contains("panick"), "{err}");
    }
}

/// An output FIFO no one reads (`-o FIFO`, `--record FIFO`, `--export FIFO`): busnoop waits for
/// a reader, and SIGINT/SIGTERM end the wait at once. A plain open() waits inside the kernel,
/// where the handlers cannot end it: only a second signal (or SIGKILL) did.
#[test]
fn an_output_fifo_without_a_reader_ends_on_a_signal() {
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/sport-sample.bin");
    for (option, name) in [
        ("-o", "table"),
        ("--record", "rec.pcap"),
        ("--export", "frames.pcapng"),
    ] {
        for (sig, code) in [(libc::SIGTERM, 143), (libc::SIGINT, 130)] {
            let dir = tempfile::tempdir().unwrap();
            let fifo = dir.path().join(name);
            mkfifo(&fifo);
            let mut cmd = busnoop();
            cmd.arg("sport").arg(&sample).arg(option).arg(&fifo);
            if option != "-o" {
                cmd.args(["-o", "/dev/null"]);
            }
            let child = cmd.spawn().unwrap();
            let mut guard = Guard(child);
            wait_for_handlers(&guard.0);
            std::thread::sleep(Duration::from_millis(200));
            assert!(guard.0.try_wait().unwrap().is_none(), "{option}: no wait");
            let (status, err) = signal_and_wait(&mut guard, sig, STOP_WITHIN);
            assert_eq!(status.code(), Some(code), "{option}, signal {sig}: {err}");
            assert!(!err.contains("panick"), "{err}");
        }
    }
}

/// `busnoop detect -` on a slow pipe (`cat /dev/ttyUSB0 | busnoop detect -`) waits for 2 MiB;
/// Ctrl-C gives the evidence and the verdict on what arrived, says so, and exits 130. It used
/// to end with nothing at all on either output.
#[test]
fn ctrl_c_during_detect_on_a_slow_pipe_gives_the_verdict_so_far() {
    let sample =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/sport-sample.bin"))
            .unwrap();
    let child = busnoop()
        .args(["detect", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut guard = Guard(child);
    let mut pipe = guard.0.stdin.take().unwrap();
    pipe.write_all(&sample).unwrap();
    wait_for_handlers(&guard.0);
    // Once busnoop took in the 220 bytes and waits for more.
    let pid = guard.0.id();
    common::until("busnoop read the bytes", || {
        common::pipe_unread(&pipe) == 0 && common::waits_for_input(pid)
    });
    let (status, err) = signal_and_wait(&mut guard, libc::SIGINT, STOP_WITHIN);
    drop(pipe);
    let mut out = String::new();
    std::io::Read::read_to_string(guard.0.stdout.as_mut().unwrap(), &mut out).unwrap();
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(out.contains("220 bytes examined"), "{out}");
    assert!(out.contains("verdict: S.Port"), "{out}");
    assert!(err.contains("interrupted after 220 bytes"), "{err}");
}

#[test]
fn a_fifo_waits_for_its_writer_and_ends_when_the_writer_closes() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("late");
    mkfifo(&fifo);
    let child = Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .args(["sport", "-f", "tsv"])
        .arg(&fifo)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut guard = Guard(child);
    // No writer yet: busnoop waits instead of taking the FIFO for an empty input.
    std::thread::sleep(Duration::from_millis(300));
    assert!(
        guard.0.try_wait().unwrap().is_none(),
        "busnoop did not wait"
    );
    let mut bytes = Vec::new();
    for i in 0..5u32 {
        busnoop::sport::wire::encode_frame(
            &mut bytes,
            busnoop::sport::wire::header_for(0),
            0x10,
            0x0100,
            i,
        );
    }
    let mut w = std::fs::OpenOptions::new().write(true).open(&fifo).unwrap();
    w.write_all(&bytes).unwrap();
    drop(w);
    let deadline = Instant::now() + common::PATIENCE;
    let status = loop {
        if let Some(s) = guard.0.try_wait().unwrap() {
            break s;
        }
        assert!(
            Instant::now() < deadline,
            "busnoop did not end with its writer"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut text = String::new();
    std::io::Read::read_to_string(guard.0.stdout.as_mut().unwrap(), &mut text).unwrap();
    assert!(status.success(), "{status:?}");
    assert_eq!(text.lines().count(), 6, "{text}");
}

#[test]
fn the_wiring_hint_is_for_live_sources_only() {
    // A slow replay of bytes that never make a frame, lasting longer than the hint's 3 s.
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("slow");
    mkfifo(&fifo);
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new().write(true).open(fifo).unwrap();
            let start = Instant::now();
            while start.elapsed() < Duration::from_millis(3400) {
                f.write_all(&[0xA0, 0xA0, 0xE6, 0x57, 0x7F, 0x81].repeat(20))
                    .unwrap();
                std::thread::sleep(Duration::from_millis(50));
            }
        })
    };
    let out = busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(&fifo)
        .output()
        .unwrap();
    writer.join().unwrap();
    let err = String::from_utf8(out.stderr).unwrap();
    // Nothing decoded (exit 10, said at the end), but no live wiring hint.
    assert_eq!(out.status.code(), Some(10), "{err}");
    assert!(!err.contains("but no valid S.Port frame"), "{err}");
    assert!(err.contains("in 0 valid frames"), "{err}");
    assert!(err.contains("busnoop: no S.Port frame in "), "{err}");
}

/// Ctrl-C while a network capture streams in with `--record`: the recording ends with a whole
/// packet, and it holds exactly the packets the table shows (replayed, the same rows).
#[test]
fn ctrl_c_leaves_a_recording_of_the_packets_the_table_shows() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("feed");
    let out = dir.path().join("out.tsv");
    let rec = dir.path().join("rec.pcap");
    mkfifo(&fifo);
    let capture =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/sbus-digimat.pcap"))
            .unwrap();
    // The capture's packets over and over, until busnoop closes its end.
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new().write(true).open(fifo).unwrap();
            let mut ok = f.write_all(&capture).is_ok();
            while ok {
                ok = f.write_all(&capture[24..]).is_ok();
            }
        })
    };
    let child = busnoop()
        .args(["sbus", "-f", "tsv", "-o"])
        .arg(&out)
        .arg("--record")
        .arg(&rec)
        .arg(&fifo)
        .spawn()
        .unwrap();
    let mut guard = Guard(child);
    wait_for_rows(&out, 1000);
    let (status, err) = signal_and_wait(&mut guard, libc::SIGINT, STOP_WITHIN);
    assert_eq!(status.code(), Some(130), "{err}");
    writer.join().unwrap();
    let recorded = std::fs::read(&rec).unwrap();
    let mut stream = busnoop::pcap::PcapStream::new();
    stream.push(&recorded, &mut |_| {}).unwrap();
    stream
        .finish()
        .expect("the recording ends with a whole packet");
    let replay = busnoop()
        .args(["sbus", "-f", "tsv"])
        .arg(&rec)
        .stdout(Stdio::piped())
        .output()
        .unwrap();
    assert_eq!(replay.status.code(), Some(0));
    assert_eq!(replay.stdout, std::fs::read(&out).unwrap());
}
