//! The first ten minutes (issue 30): what a new user tries first, one test per finding of the
//! issue (`finding_N_…`) and the behaviour that answers it.

mod common;

use std::io::Write as _;
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

use common::{busnoop, fixture, noise, ok, text};

fn run(args: &[&str]) -> Output {
    busnoop().args(args).output().unwrap()
}

fn path(name: &str) -> String {
    fixture(name).display().to_string()
}

/// Every capture in `fixtures/` with the subcommand (and options) that decodes it.
const CAPTURES: &[(&str, &[&str])] = &[
    ("sport-sample.bin", &["sport"]),
    ("edgetx-MODELE24-2014-07-11-sport.log", &["sport"]),
    ("fport-v1-session.bin", &["fport", "--variant", "v1"]),
    ("fport2-session.bin", &["fport", "--variant", "v2"]),
    ("sbus-digimat.pcap", &["sbus"]),
    ("sbus_seeds_ether.pcap", &["sbus"]),
    ("sab1-session.bin", &["sab2"]),
    ("sab2-session.bin", &["sab2"]),
    ("crsf-mixed.bin", &["crsf"]),
    ("crsf-fc-to-rx.bin", &["crsf"]),
    ("crsf-rx-to-fc.bin", &["crsf"]),
    ("ghst-mixed.bin", &["ghst"]),
    ("futaba-session.bin", &["futaba"]),
    ("ibus-rc.bin", &["ibus"]),
    ("ibus-sensors.bin", &["ibus"]),
    ("edgetx-MODELE24-2014-07-11.csv", &["log"]),
    ("sport-snoop-sample.tsv", &["log"]),
    ("modbus-brainchild.bin", &["modbus"]),
    ("modbus-flowmeter-graph-tool.bin", &["modbus"]),
    ("modbus-gen.bin", &["modbus"]),
    ("modbus-gen.pcap", &["modbus"]),
    ("modbus-wizmodbus-bus.bin", &["modbus"]),
];

/// The files in `fixtures/` that are no capture: test vectors, generators' expectations, the
/// README, tshark's text. A bare `busnoop FILE` finds no protocol in them (exit 11).
const NOT_CAPTURES: &[&str] = &[
    "README.md",
    "crsf-fc-to-rx.expect.tsv",
    "crsf-mixed.expect.tsv",
    "crsf-rx-to-fc.expect.tsv",
    "fport-sessions.tsv",
    "futaba-session.tsv",
    "ghst-mixed.expect.tsv",
    "ibus-rc.tsv",
    "ibus-sensors.tsv",
    "ibus-vectors.tsv",
    "modbus-gen.expect",
    "sab.tsv",
    "sbus-digimat-tshark.tsv",
    "sbus.tsv",
    "sbus_seeds_ether_tshark.txt",
    "sport-vectors-crc-invalid.tsv",
    "sport-vectors.tsv",
];

/// Every file in `fixtures/` is either a capture (decoded as its protocol by a bare
/// `busnoop FILE`: [`finding_1_a_bare_file_is_detected_and_decoded`]) or listed as no capture,
/// which a bare `busnoop FILE` refuses with exit 11: a new fixture must be placed in one list.
#[test]
fn a_bare_file_decodes_every_fixture_as_its_protocol() {
    let dir = fixture("README.md").parent().unwrap().to_path_buf();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_dir() {
            // fixtures/logic: logic-analyzer traces, read with --channel by tests/logic.rs.
            continue;
        }
        let name = entry.file_name().to_string_lossy().into_owned();
        let capture = CAPTURES.iter().any(|(c, _)| *c == name);
        let other = NOT_CAPTURES.contains(&name.as_str());
        assert!(
            capture ^ other,
            "fixtures/{name}: list it in CAPTURES (with its subcommand) or in NOT_CAPTURES"
        );
        if other {
            let out = run(&[&path(&name)]);
            let err = text(&out.stderr);
            assert_eq!(out.status.code(), Some(11), "{name}: {err}");
            assert!(err.contains("verdict: no known protocol"), "{name}: {err}");
            assert!(out.stdout.is_empty(), "{name}");
        }
    }
}

/// Finding 1: `busnoop FILE` was "unrecognized subcommand". It detects the protocol, says on
/// stderr what it chose and why, and decodes exactly as the subcommand would.
#[test]
fn finding_1_a_bare_file_is_detected_and_decoded() {
    for (name, command) in CAPTURES {
        let file = path(name);
        let bare = run(&[&file, "-f", "tsv"]);
        let mut named: Vec<&str> = command.to_vec();
        named.extend([file.as_str(), "-f", "tsv"]);
        let named = run(&named);
        assert_eq!(ok(&bare), ok(&named), "{name}");
        let err = text(&bare.stderr);
        let first = err.lines().next().unwrap_or_default();
        assert!(
            first.starts_with("busnoop: decoding as ")
                && first.contains(" of the bytes in ")
                && first.ends_with(&format!(
                    "(detected; `busnoop {} {file}` skips the detection)",
                    command.join(" ")
                )),
            "{name}: {err}"
        );
        // The rest of stderr is the named run's.
        assert_eq!(
            err.lines().skip(1).collect::<Vec<_>>(),
            text(&named.stderr).lines().collect::<Vec<_>>(),
            "{name}"
        );
    }
    // The S.Port sample, as the issue asks it to read.
    let out = run(&[&path("sport-sample.bin"), "-f", "tsv"]);
    assert!(
        text(&out.stderr).starts_with(
            "busnoop: decoding as S.Port: 100.0% of the bytes in 30 valid frames (detected;"
        ),
        "{}",
        text(&out.stderr)
    );
}

/// Finding 1: options before the subcommand were refused (`-f csv`, without a tip).
#[test]
fn finding_1_options_before_the_subcommand_count() {
    let file = path("sport-sample.bin");
    let before = run(&["-f", "csv", "--raw", "sport", &file]);
    let after = run(&["sport", &file, "-f", "csv", "--raw"]);
    assert_eq!(ok(&before), ok(&after));
    assert!(ok(&before).starts_with("Counter,Millis,"));
    // And before a bare SOURCE.
    let bare = run(&["-f", "csv", "--raw", &file]);
    assert_eq!(ok(&bare), ok(&after));
}

/// Finding 1: what a bare SOURCE cannot be: a pipe (read once: no detection before the
/// decoding), an unknown content (the detect report and exit 11), a mistyped subcommand.
#[test]
fn finding_1_a_bare_source_that_cannot_be_decoded_says_why() {
    let mut child = busnoop()
        .arg("-")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let _ = child
        .stdin
        .take()
        .unwrap()
        .write_all(&std::fs::read(fixture("sport-sample.bin")).unwrap());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("standard input: a pipe can be read only once")
            && err.contains("name the protocol: busnoop sport|"),
        "{err}"
    );

    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("noise.bin");
    std::fs::write(&p, noise(30_000, 7)).unwrap();
    let out = busnoop().arg(&p).output().unwrap();
    assert_eq!(out.status.code(), Some(11));
    assert!(out.stdout.is_empty());
    let err = text(&out.stderr);
    assert!(err.contains("  candidate "), "the evidence: {err}");
    assert!(err.contains("verdict: no known protocol"), "{err}");
    assert!(
        err.contains("to decode it anyway, name the protocol: busnoop sport|"),
        "{err}"
    );

    let out = run(&["sprot", "x.bin"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("did you mean `busnoop sport`?"),
        "{}",
        text(&out.stderr)
    );
    let out = busnoop().arg(dir.path().join("gone.bin")).output().unwrap();
    assert_eq!(out.status.code(), Some(3));
    assert!(text(&out.stderr).contains("gone.bin: no such file or device"));
}

/// Finding 2: `busnoop sport -` with a terminal on standard input waited without a word.
#[test]
fn finding_2_standard_input_on_a_terminal_is_said() {
    let _g = common::pty::lock();
    let bus = common::pty::bus();
    let tty = std::fs::File::open(&bus.path).unwrap();
    let mut child = busnoop()
        .args(["sport", "-", "-f", "tsv"])
        .stdin(tty)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = std::io::BufRead::read_line(&mut err, &mut line);
        let _ = tx.send(line);
    });
    let line = rx.recv_timeout(Duration::from_secs(20)).unwrap_or_default();
    let _ = child.kill();
    let _ = child.wait();
    assert_eq!(line, "busnoop: reading standard input (Ctrl-D to end)\n");
    // A pipe is not a terminal: nothing to say.
    let mut child = busnoop()
        .args(["sport", "-", "-f", "tsv"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdin.take());
    let out = child.wait_with_output().unwrap();
    assert!(!text(&out.stderr).contains("Ctrl-D"));
}

/// Finding 3: `--baud`, `--reconnect` and `--dtr-rts keep` did nothing on a file, silently.
#[test]
fn finding_3_serial_options_on_a_file_are_noted() {
    let log = path("edgetx-MODELE24-2014-07-11-sport.log");
    let out = run(&[
        "sport",
        &log,
        "-f",
        "tsv",
        "--baud",
        "115200",
        "--reconnect",
        "--dtr-rts",
        "keep",
        "--line",
        "8N1",
    ]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    for option in ["--baud", "--line", "--reconnect", "--dtr-rts"] {
        assert!(
            err.contains(&format!(
                "busnoop: note: {option} has no effect on an EdgeTX log"
            )),
            "{option}: {err}"
        );
    }
    // The same rows as without them.
    assert_eq!(ok(&out), ok(&run(&["sport", &log, "-f", "tsv"])));
    // Raw bytes take their times from --baud: no note.
    let out = run(&["sport", &path("sport-sample.bin"), "--baud", "9600"]);
    assert!(
        !text(&out.stderr).contains("--baud"),
        "{}",
        text(&out.stderr)
    );
}

/// Finding 3: `--reconnect` gave exit 3 at once when the adapter was not plugged in yet; it
/// waits for it and says so.
#[test]
fn finding_3_reconnect_waits_for_an_adapter_not_there_yet() {
    use std::io::{BufRead, BufReader};
    let _g = common::pty::lock();
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("adapter");
    let mut child = busnoop()
        .args(["sport", "--reconnect", "-f", "tsv"])
        .arg(&link)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    assert_eq!(
        line,
        format!(
            "busnoop: waiting for {} to appear (--reconnect; Ctrl-C to stop)\n",
            link.display()
        )
    );
    std::thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "still waiting");
    // Plugged in: the device appears under the name, and frames decode.
    let mut bus = common::pty::bus();
    std::os::unix::fs::symlink(&bus.path, &link).unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut l = String::new();
        while out.read_line(&mut l).is_ok_and(|n| n > 0) {
            let _ = tx.send(std::mem::take(&mut l));
        }
    });
    let mut rows = Vec::new();
    while Instant::now() < deadline && rows.len() < 5 {
        let _ = bus.master.write_all(&sample);
        while let Ok(l) = rx.recv_timeout(Duration::from_millis(100)) {
            rows.push(l);
        }
    }
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    let _ = child.wait();
    assert!(rows.len() >= 5, "{rows:?}");
    assert!(rows[0].starts_with("Counter\tMillis"), "{rows:?}");
    let mut rest = String::new();
    let _ = std::io::Read::read_to_string(&mut err, &mut rest);
    assert!(
        rest.starts_with(&format!("busnoop: {} is there\n", link.display())),
        "{rest}"
    );
}

/// Finding 4: a busnoop.toml in the current directory filtered rows without a word.
#[test]
fn finding_4_the_project_file_in_use_is_said() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("busnoop.toml"),
        "[sport.filter]\nid = [1]\n",
    )
    .unwrap();
    let log = path("edgetx-MODELE24-2014-07-11-sport.log");
    let out = busnoop()
        .current_dir(dir.path())
        .args(["sport", &log, "-f", "pretty"])
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert_eq!(
        err.lines().next(),
        Some("busnoop: using busnoop.toml: [sport] filter.id = [1] (--no-config ignores it)"),
        "{err}"
    );
    let stdout = ok(&out);
    assert_eq!(
        stdout.lines().next(),
        Some("project file busnoop.toml: [sport] filter.id = [1]")
    );
    assert!(stdout.lines().nth(1).unwrap().starts_with("Counter"));
    // TSV stays a table for programs; stderr still says it.
    let out = busnoop()
        .current_dir(dir.path())
        .args(["sport", &log, "-f", "tsv"])
        .output()
        .unwrap();
    assert!(ok(&out).starts_with("Counter\t"));
    assert!(text(&out.stderr).starts_with("busnoop: using busnoop.toml"));
    // --no-config: nothing said, every row.
    let out = busnoop()
        .current_dir(dir.path())
        .args(["sport", &log, "-f", "tsv", "--no-config"])
        .output()
        .unwrap();
    assert!(text(&out.stderr).is_empty(), "{}", text(&out.stderr));
    assert_eq!(ok(&out).lines().count(), 1 + 592);
    // Another protocol's section changes nothing for sport: nothing to say.
    std::fs::write(dir.path().join("busnoop.toml"), "[sbus]\ntimeout-ms = 5\n").unwrap();
    let out = busnoop()
        .current_dir(dir.path())
        .args(["sport", &log, "-f", "tsv"])
        .output()
        .unwrap();
    assert!(text(&out.stderr).is_empty(), "{}", text(&out.stderr));
}

/// Finding 5: the wrong protocol and noise exited 0. They exit 13 (the rows written), and
/// `--lenient` accepts them.
#[test]
fn finding_5_the_wrong_protocol_or_noise_has_its_exit_code() {
    let sample = path("sport-sample.bin");
    let out = run(&["sbus", &sample, "-f", "tsv"]);
    assert_eq!(out.status.code(), Some(13));
    assert_eq!(
        text(&out.stdout).lines().count(),
        1 + 36,
        "the rows are kept"
    );
    let err = text(&out.stderr);
    assert!(
        err.ends_with(
            "busnoop: most of the input is not valid S-Bus frames (exit code 13; --lenient \
             accepts such a run)\n"
        ),
        "{err}"
    );
    assert!(err.contains("it looks like S.Port"), "{err}");
    let lenient = run(&["sbus", &sample, "-f", "tsv", "--lenient"]);
    assert_eq!(lenient.status.code(), Some(0));
    assert_eq!(lenient.stdout, out.stdout);
    assert!(text(&lenient.stderr).contains("busnoop: note: only 49.1% of the bytes"));

    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("noise.bin");
    std::fs::write(&p, noise(300_000, 11)).unwrap();
    let out = busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(&p)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(13), "{}", text(&out.stderr));
    // Good captures stay 0.
    for (name, command) in CAPTURES {
        let mut args: Vec<&str> = command.to_vec();
        let file = path(name);
        args.extend([file.as_str(), "-f", "tsv"]);
        assert_eq!(run(&args).status.code(), Some(0), "{name}");
    }
}

/// Writes `bytes` to the bus side every `every` until the returned flag is set.
fn keep_writing(
    mut bus: common::pty::Bus,
    bytes: Vec<u8>,
    every: Duration,
) -> (
    std::sync::Arc<std::sync::atomic::AtomicBool>,
    std::thread::JoinHandle<common::pty::Bus>,
) {
    use std::sync::atomic::{AtomicBool, Ordering};
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let writer = std::thread::spawn(move || {
        while !flag.load(Ordering::Relaxed) {
            let _ = bus.master.write_all(&bytes);
            std::thread::sleep(every);
        }
        bus
    });
    (stop, writer)
}

/// Finding 7: `detect` on a serial port printed the winning rate's row blank. A pty hears the
/// same bytes at every rate: every row of S.Port's format names the best candidate, the
/// winner's too.
#[test]
fn finding_7_detect_on_a_port_shows_the_winners_row() {
    let _g = common::pty::lock();
    let bus = common::pty::bus();
    let device = bus.path.clone();
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let (stop, writer) = keep_writing(bus, sample, Duration::from_millis(20));
    let out = busnoop()
        .args(["detect", "--listen-ms", "300", "--baud", "57600,9600"])
        .arg(&device)
        .output()
        .unwrap();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = writer.join();
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("verdict: S.Port at 57600 baud"),
        "{stdout}{}",
        text(&out.stderr)
    );
    let winner = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("57600 baud 8N1"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(winner.contains(", best S.Port ("), "{winner}");
}

/// Finding 10: the messages: `--baud 57.6k` ("invalid digit"), `--baud 0` (Rust's range
/// syntax), `--name 1=Pack`, `sport` on an Ether-S-Bus pcap, "1 bytes".
#[test]
fn finding_10_messages_say_what_to_write() {
    let sample = path("sport-sample.bin");
    let plain = ok(&run(&["sport", &sample, "-f", "tsv", "--baud", "57600"]));
    for form in ["57.6k", "57.6K", "57600"] {
        assert_eq!(
            ok(&run(&["sport", &sample, "-f", "tsv", "--baud", form])),
            plain,
            "{form}"
        );
    }
    let out = run(&["sport", &sample, "--baud", "57.6x"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("expected a speed in baud: 57600, 57.6k or 1M"),
        "{}",
        text(&out.stderr)
    );
    for (args, want) in [
        (
            &["sport", "x", "--baud", "0"][..],
            "0 is out of range: from 50 to 12000000 baud",
        ),
        (
            &["sport", "x", "--wide", "--every", "0"][..],
            "0 is out of range: from 1 to 3600000",
        ),
        (
            &["sbus", "x", "--timeout-ms", "0"][..],
            "0 is out of range: from 1 to 3600000",
        ),
        (
            &["detect", "x", "--listen-ms", "5"][..],
            "5 is out of range: from 10 to 60000",
        ),
    ] {
        let out = run(args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("..="), "{args:?}: {err}");
    }
    let out = run(&["sport", &sample, "--name", "1=Pack"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr),
        "busnoop: --name \"1=Pack\": the name comes first, then the ID: --name Pack=1\n"
    );
    let out = run(&["sport", &path("sbus-digimat.pcap")]);
    assert_eq!(out.status.code(), Some(9));
    assert!(
        text(&out.stderr).ends_with("; busnoop sbus reads it\n"),
        "{}",
        text(&out.stderr)
    );
    // One garbage byte is "1 byte", in the row and in the statistics.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("one.bin");
    let mut bytes = vec![0x01];
    bytes.extend(std::fs::read(fixture("sport-sample.bin")).unwrap());
    std::fs::write(&p, bytes).unwrap();
    let out = busnoop()
        .args(["sport", "-f", "tsv", "--stats"])
        .arg(&p)
        .output()
        .unwrap();
    let all = text(&out.stdout) + &text(&out.stderr);
    assert!(all.contains("1 byte before the first 0x7E"), "{all}");
    assert!(all.contains("garbage 1 byte in 1 run,"), "{all}");
    assert!(!all.contains("1 bytes") && !all.contains("1 runs"), "{all}");
}

/// Stop conditions, as candump and tshark have them.
#[test]
fn stop_after_a_count_a_duration_or_a_silence() {
    let log = path("edgetx-MODELE24-2014-07-11-sport.log");
    let all = ok(&run(&["sport", &log, "-f", "tsv"]));
    let rows: Vec<&str> = all.lines().collect();
    let out = ok(&run(&["sport", &log, "-f", "tsv", "-c", "5"]));
    assert_eq!(out.lines().collect::<Vec<_>>(), rows[..6]);
    let out = ok(&run(&[
        "sport", &log, "-f", "tsv", "--count", "5", "--id", "1",
    ]));
    assert_eq!(out.lines().count(), 6);
    assert!(
        out.lines()
            .skip(1)
            .all(|l| l.split('\t').nth(2) == Some("1"))
    );
    // --duration: the capture's own time.
    let out = ok(&run(&["sport", &log, "-f", "tsv", "--duration", "0.5"]));
    let millis: Vec<u64> = out
        .lines()
        .skip(1)
        .map(|l| l.split('\t').nth(1).unwrap().parse().unwrap())
        .collect();
    assert!(millis.iter().all(|&m| m < 500), "{millis:?}");
    assert!(millis.len() > 10 && millis.len() < rows.len() - 1);
    assert_eq!(
        ok(&run(&["sport", &log, "-f", "tsv", "--duration", "500ms"])),
        out
    );
    let out = run(&["sport", &log, "--duration", "soon"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("expected a time: seconds (1.5, 90) or with a unit"));
}

/// `--until-idle` on a live line: the bus goes quiet, busnoop ends with the rows so far.
#[test]
fn until_idle_ends_a_live_capture_when_the_bus_goes_quiet() {
    use std::io::BufRead;
    let _g = common::pty::lock();
    let bus = common::pty::bus();
    let device = bus.path.clone();
    let mut child = busnoop()
        .args(["sport", "-f", "tsv", "--until-idle", "1"])
        .arg(&device)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = std::io::BufReader::new(child.stdout.take().unwrap());
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for l in out.lines().map_while(Result::ok) {
            let _ = tx.send(l);
        }
    });
    // The bus talks until rows come out (however slowly busnoop starts), then goes quiet.
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let (stop, writer) = keep_writing(bus, sample, Duration::from_millis(100));
    let mut rows = 0;
    let deadline = Instant::now() + Duration::from_secs(30);
    while rows < 40 && Instant::now() < deadline {
        if rx.recv_timeout(Duration::from_millis(100)).is_ok() {
            rows += 1;
        }
    }
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _bus = writer.join().unwrap();
    let quiet = Instant::now();
    let status = child.wait().unwrap();
    assert!(
        quiet.elapsed() < Duration::from_secs(8),
        "{:?}",
        quiet.elapsed()
    );
    assert_eq!(status.code(), Some(0));
    assert!(rows >= 40);
}

/// `-q` with `--record`: the recording and nothing on standard output (tshark -w -q).
#[test]
fn quiet_writes_the_recording_and_no_table() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("r.pcap");
    let sample = path("sport-sample.bin");
    let out = busnoop()
        .args(["sport", &sample, "-q", "--record"])
        .arg(&rec)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(out.stdout.is_empty());
    let replay = ok(&busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(&rec)
        .output()
        .unwrap());
    assert_eq!(replay, ok(&run(&["sport", &sample, "-f", "tsv"])));
    // -q with -o: the table still goes to the file.
    let csv = dir.path().join("t.csv");
    let out = busnoop()
        .args(["sport", &sample, "-q", "-o"])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(out.stdout.is_empty());
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 31);
    // -q alone: the exit code and stderr for a script.
    let out = run(&["sbus", &sample, "-q"]);
    assert_eq!(out.status.code(), Some(13));
    assert!(out.stdout.is_empty());
}

/// The protocols' subcommands, every one registered (a hand-kept list here had left out
/// `modbus` and `log`).
fn protocols() -> impl Iterator<Item = &'static str> {
    busnoop::protocols::PROTOCOLS.iter().map(|p| p.command)
}

/// Finding 8: `-h` was 79 to 111 lines, listed filters the protocol refuses, the `--baud`
/// default of every protocol, `--wide` in S.Port's words for everyone, and three ways to name a
/// device. `-h` is a summary, `--help` the whole; each shows only what applies.
#[test]
fn finding_8_help_per_protocol() {
    for p in protocols() {
        let short = ok(&run(&[p, "-h"]));
        let long = ok(&run(&[p, "--help"]));
        assert!(short.lines().count() <= 42, "{p} -h: {short}");
        assert!(long.lines().count() > short.lines().count() + 60, "{p}");
        assert!(short.contains("Examples:"), "{p}");
        assert!(short.contains(&format!("busnoop {p} --help")), "{p}");
        // One line per option in -h (no next-line layout).
        assert!(
            !short
                .lines()
                .any(|l| l.trim_start().starts_with("--") && l.trim_end().ends_with('>')),
            "{p}: {short}"
        );
        // Only its own default speed.
        let flat = long.split_whitespace().collect::<Vec<_>>().join(" ");
        let baud = flat
            .split("--baud <BAUD>")
            .nth(1)
            .and_then(|t| t.split("[default: ").nth(1))
            .and_then(|t| t.split(']').next())
            .unwrap_or_else(|| panic!("{p}: {long}"))
            .to_owned();
        assert!(baud.parse::<u32>().is_ok(), "{p}: {baud}");
        // One way to name a device.
        assert!(!long.contains("--station"), "{p}");
        assert!(
            !long.contains("motor=5") && !long.contains("A value with `=`"),
            "{p}"
        );
    }
    // Filters a protocol always refuses are not offered.
    for p in ["sbus", "sab2", "crsf", "futaba"] {
        let long = ok(&run(&[p, "--help"]));
        assert!(!long.contains("--hide-polls"), "{p}");
        assert!(!long.contains("--hide-null"), "{p}");
    }
    let sport = ok(&run(&["sport", "--help"]));
    assert!(sport.contains("--hide-polls") && sport.contains("--hide-null"));
    let flat = sport.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(flat.contains("[default: 57600]") && !flat.contains("115200"));
    // --wide in the protocol's words.
    let sab = ok(&run(&["sab2", "--help"]));
    let wide = sab.split("--wide").nth(1).unwrap();
    let wide = &wide[..wide.find("--every").unwrap()];
    assert!(wide.contains("each address's next frame"), "{wide}");
    assert!(!wide.contains("poll") && !wide.contains("Cell1"), "{wide}");
    // The hidden aliases still work.
    let file = path("sbus-digimat.pcap");
    let named = ok(&run(&["sbus", &file, "-f", "tsv", "--name", "Boiler=10"]));
    assert!(named.contains("\tBoiler\t"));
    assert_eq!(
        ok(&run(&[
            "sbus",
            &file,
            "-f",
            "tsv",
            "--station",
            "Boiler=10"
        ])),
        named
    );
    assert_eq!(
        ok(&run(&["sbus", &file, "-f", "tsv", "--device", "Boiler=10"])),
        named
    );
    // busnoop -h: the bare SOURCE and every exit code.
    let top = ok(&run(&["-h"]));
    assert!(top.contains("busnoop <SOURCE> [OPTIONS]"), "{top}");
    assert!(
        top.contains("13 mostly not frames of the protocol"),
        "{top}"
    );
}

/// The subcommands are built in one pass over their options (clap's `mut_arg` moves an option to
/// the end of the list, and editing each of them that way was two thirds of the start-up). The
/// help's order must not change with it: options with the same display order are sorted by
/// name, so a renumbering moves `-v` among the shared ones; the protocol's own options come
/// first in the completion scripts.
#[test]
fn help_and_completions_keep_the_options_order() {
    let short = ok(&run(&["modbus", "-h"]));
    let flags = |section: &str| -> Vec<String> {
        let body = short.split(&format!("\n{section}:\n")).nth(1).unwrap();
        let body = &body[..body.find("\n\n").unwrap()];
        body.lines()
            .map(|l| {
                let l = l.trim_start();
                let l = l.strip_prefix("-").map_or(l, |_| l);
                l.split([' ', ','])
                    .find(|w| w.starts_with("--"))
                    .unwrap_or(l)
                    .trim_end_matches("...")
                    .to_owned()
            })
            .collect()
    };
    assert_eq!(
        flags("Options"),
        [
            "--format",
            "--output",
            "--stats",
            "--verbose",
            "--top",
            "--wide",
            "--baud",
            "--record",
            "--help"
        ],
        "{short}"
    );
    assert_eq!(
        flags("Protocol options"),
        ["--timeout-ms", "--ascii"],
        "{short}"
    );
    assert_eq!(
        flags("Filters and names (AND across options, OR within one)"),
        ["--id", "--type", "--sensor", "--name"],
        "{short}"
    );
    let long = ok(&run(&["sport", "--help"]));
    let at = |flag: &str| {
        long.find(&format!(" {flag}"))
            .unwrap_or_else(|| panic!("{flag}"))
    };
    assert!(at("--stats\n") < at("--stats-format") && at("--stats-format") < at("--verbose"));
    assert!(at("--verbose") < at("--stats-json") && at("--stats-json") < at("--time"));
    let bash = ok(&run(&["completions", "bash"]));
    let modbus = bash
        .lines()
        .find(|l| l.contains("opts=\"") && l.contains("--timeout-ms --ascii"))
        .unwrap_or_else(|| panic!("{bash}"));
    assert!(
        modbus.contains("-v -h --timeout-ms --ascii --format --output"),
        "{modbus}"
    );
}

/// Finding 6: the radio's SD-card CSV and S-Port_Snoop's table gave Garbage rows and "no known
/// protocol". They are recognised by content and read: plot, --wide and --stats on their
/// numbers.
#[test]
fn finding_6_the_logs_users_have_are_read() {
    let csv = path("edgetx-MODELE24-2014-07-11.csv");
    let tsv = path("sport-snoop-sample.tsv");
    for (file, rows) in [(&csv, 76), (&tsv, 30)] {
        let out = run(&[file, "-f", "tsv"]);
        let stdout = ok(&out);
        assert_eq!(stdout.lines().count(), 1 + rows, "{file}");
        assert!(
            text(&out.stderr)
                .starts_with("busnoop: decoding as telemetry log: 100.0% of the bytes"),
            "{}",
            text(&out.stderr)
        );
        assert_eq!(stdout, ok(&run(&["log", file, "-f", "tsv"])));
        let out = run(&["detect", file]);
        assert_eq!(out.status.code(), Some(0));
        assert!(text(&out.stdout).contains(&format!("run:  busnoop log {file}")));
    }
    // The radio's own numbers: --wide gives its columns back, one line per log line.
    let wide = ok(&run(&["log", &csv, "--wide", "-f", "csv"]));
    let lines: Vec<&str> = wide.lines().collect();
    assert_eq!(lines.len(), 1 + 76);
    assert!(lines[0].starts_with("Millis,SWR,RSSI,A1,"), "{}", lines[0]);
    assert!(lines[0].contains(",Cell 1,Cell 2,"), "{}", lines[0]);
    // --stats on its columns.
    let out = run(&["log", &csv, "--stats", "-q"]);
    let err = text(&out.stderr);
    assert!(err.contains("telemetry log statistics (76 rows)"), "{err}");
    let a1 = err.lines().find(|l| l.starts_with("A1 ")).unwrap();
    assert!(a1.ends_with("5.07"), "{a1}");
    // plot, detected.
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("radio.svg");
    let out = busnoop()
        .args(["plot", &csv, "--sensor", "RSSI,A1", "-o"])
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let image = std::fs::read_to_string(&svg).unwrap();
    assert!(image.contains("RSSI") && image.contains("A1"));
    // The wrong subcommand names the right one.
    let out = run(&["sport", &csv]);
    assert_eq!(out.status.code(), Some(10));
    assert!(
        text(&out.stderr).contains(&format!("try: busnoop log {csv}")),
        "{}",
        text(&out.stderr)
    );
    // The Snoop table's numbers.
    let out = ok(&run(&["log", &tsv, "-f", "jsonl", "--sensor", "Alt"]));
    assert!(out.contains("\"parts\":{\"Alt\":65.43}"), "{out}");
}

/// `--wide` on RC channel frames (no ID): one line per frame, not one for the whole capture.
#[test]
fn wide_has_a_line_per_channel_frame() {
    let out = ok(&run(&["ibus", &path("ibus-rc.bin"), "--wide", "-f", "csv"]));
    assert_eq!(out.lines().count(), 1 + 20);
}

/// Finding 9 (the man page): exit codes were under `EXTRA`, `busnoop-help(1)` was named though
/// `man --dir` does not write it, and the options every protocol shares were nowhere. The page
/// has SHARED OPTIONS and EXIT STATUS sections, and every page it (or any other page) names is
/// one `man --dir` writes.
#[test]
fn finding_9_the_man_page_has_shared_options_and_exit_codes() {
    let page = ok(&run(&["man"]));
    assert!(
        !page.contains(".SH EXTRA"),
        "exit codes in a section of their own"
    );
    let section = |name: &str| {
        let at = page
            .find(&format!(".SH \"{name}\"\n"))
            .unwrap_or_else(|| panic!("no section {name}"));
        let rest = &page[at + 5..];
        rest[..rest.find("\n.SH ").unwrap_or(rest.len())].to_string()
    };
    let exit = section("EXIT STATUS");
    for code in [0, 1, 2, 3, 9, 10, 11, 12, 13, 129, 130, 141, 143] {
        assert!(
            exit.contains(&format!(".TP\n{code}\n")),
            "exit code {code}: {exit}"
        );
    }
    let shared = section("SHARED OPTIONS");
    for opt in [
        "\\-\\-format",
        "\\-\\-output",
        "\\-\\-stats",
        "\\-\\-baud",
        "\\-\\-record",
        "\\-\\-id",
        "\\-\\-count",
        "\\-\\-lenient",
        "\\-\\-quiet",
        "\\-\\-reconnect",
        "\\-\\-wide",
    ] {
        assert!(shared.contains(opt), "{opt} in SHARED OPTIONS");
    }
    let dir = tempfile::tempdir().unwrap();
    let out = busnoop()
        .args(["man", "--dir"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let written: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        std::fs::read_to_string(dir.path().join("busnoop.1")).unwrap(),
        page,
        "busnoop.1 is the page of `busnoop man`"
    );
    for name in &written {
        let text = std::fs::read_to_string(dir.path().join(name)).unwrap();
        let mut rest = text.as_str();
        while let Some(at) = rest.find("busnoop\\-") {
            let after = &rest[at + "busnoop\\-".len()..];
            if let Some(end) = after.find("(1)")
                && after[..end].chars().all(|c| c.is_ascii_alphanumeric())
            {
                let named = format!("busnoop-{}.1", &after[..end]);
                assert!(
                    written.contains(&named),
                    "{name} names {named}: not written"
                );
            }
            rest = after;
        }
    }
    for p in protocols().chain(["detect", "plot", "ports", "man"]) {
        assert!(written.contains(&format!("busnoop-{p}.1")), "{p}");
    }
}

/// Finding 5 with several sources: a port that is mostly not frames of the protocol ends the
/// run with exit code 13 after the rows, as one source does; --lenient accepts it.
#[test]
fn finding_5_several_sources_have_the_poor_run_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("b.bin");
    std::fs::copy(fixture("sport-sample.bin"), &copy).unwrap();
    let copy = copy.display().to_string();
    let sample = path("sport-sample.bin");
    let out = run(&["sbus", &sample, &copy, "-f", "tsv"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(13), "{err}");
    assert!(err.contains("try: busnoop sport "), "{err}");
    assert!(ok_or_rows(&out) > 10, "the rows are written");
    let out = run(&["sbus", &sample, &copy, "-f", "tsv", "--lenient"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let out = run(&["sport", &sample, &copy, "-f", "tsv"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

/// The rows of a run whatever its exit code.
fn ok_or_rows(out: &Output) -> usize {
    text(&out.stdout).lines().count()
}
