//! First contact: `busnoop detect`, the notes on options that cannot do what they ask, the
//! help texts, shell completions and the manual page.

mod common;

use std::io::Write as _;
use std::process::{Output, Stdio};

use common::fixture;
use common::{busnoop, noise, text};

fn run(args: &[&str], source: &std::path::Path) -> Output {
    busnoop().args(args).arg(source).output().unwrap()
}

/// The `verdict:` and `run:` lines of a detect report.
fn verdict_and_run(out: &Output) -> (String, String) {
    let stdout = text(&out.stdout);
    let verdict = stdout
        .lines()
        .find(|l| l.starts_with("verdict: "))
        .unwrap_or_else(|| panic!("{stdout}"))
        .to_owned();
    let run = stdout
        .lines()
        .find(|l| l.starts_with("run:  ") || l.starts_with("then: "))
        .map(str::to_owned)
        .unwrap_or_default();
    (verdict, run)
}

#[test]
fn detect_names_the_protocol_of_every_fixture() {
    let cases = [
        (
            "sport-sample.bin",
            "verdict: S.Port (100.0%",
            "busnoop sport",
        ),
        (
            "edgetx-MODELE24-2014-07-11-sport.log",
            "verdict: S.Port (100.0%",
            "busnoop sport",
        ),
        (
            "sab1-session.bin",
            "verdict: SAB v1 (sync framing) (91.3%",
            "busnoop sab2",
        ),
        (
            "sab2-session.bin",
            "verdict: SAB2 (HDLC framing) (91.9%",
            "busnoop sab2",
        ),
        (
            "sbus-digimat.pcap",
            "verdict: Ether-S-Bus (100.0%",
            "busnoop sbus",
        ),
        (
            "sbus_seeds_ether.pcap",
            "verdict: Ether-S-Bus (100.0%",
            "busnoop sbus",
        ),
    ];
    for (name, verdict, command) in cases {
        let path = fixture(name);
        let out = run(&["detect"], &path);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", text(&out.stderr));
        let (v, r) = verdict_and_run(&out);
        assert!(v.starts_with(verdict), "{name}: {v}");
        assert_eq!(r, format!("run:  {command} {}", path.display()), "{name}");
        // The evidence: a header and one line per candidate, with the frame starts.
        let stdout = text(&out.stdout);
        assert!(stdout.lines().nth(1).unwrap().contains("frames start with"));
    }
    // The S.Port evidence in full.
    let out = run(&["detect"], &fixture("sport-sample.bin"));
    let stdout = text(&out.stdout);
    assert!(
        stdout.starts_with(&format!(
            "{}: raw bytes, 220 bytes examined\n",
            fixture("sport-sample.bin").display()
        )),
        "{stdout}"
    );
    let sport_line = stdout.lines().nth(2).unwrap();
    assert_eq!(
        sport_line.split_whitespace().collect::<Vec<_>>(),
        ["S.Port", "100.0%", "30", "0", "0", "0", "7E", "×30"]
    );
}

#[test]
fn detect_on_a_recording_and_standard_input() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec.pcap");
    let out = busnoop()
        .args(["sab2"])
        .arg(fixture("sab2-session.bin"))
        .arg("--record")
        .arg(&rec)
        .args(["-o", "/dev/null"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let out = run(&["detect"], &rec);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stdout).contains(": a busnoop recording, 161 bytes examined"));
    assert!(
        verdict_and_run(&out)
            .0
            .starts_with("verdict: SAB2 (HDLC framing)")
    );

    let out = busnoop()
        .args(["detect", "-"])
        .stdin(std::fs::File::open(fixture("sport-sample.bin")).unwrap())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(verdict_and_run(&out).1, "run:  busnoop sport -");
}

#[test]
fn detect_random_bytes_is_no_known_protocol() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("noise.bin");
    std::fs::write(&p, noise(300_000, 0x2545_F491_4F6C_DD1D)).unwrap();
    let out = run(&["detect"], &p);
    assert_eq!(out.status.code(), Some(11), "{}", text(&out.stderr));
    let (v, r) = verdict_and_run(&out);
    assert!(v.starts_with("verdict: no known protocol"), "{v}");
    assert_eq!(r, "");
    assert_eq!(
        text(&out.stderr),
        format!(
            "busnoop: no known protocol in {}: another protocol, a capture made at the wrong \
             baud rate, or not a capture at all\n",
            p.display()
        )
    );
    // A text file, too.
    let out = run(&["detect"], &fixture("README.md"));
    assert_eq!(out.status.code(), Some(11));
}

#[test]
fn detect_empty_input() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("empty.bin");
    std::fs::write(&p, b"").unwrap();
    let out = run(&["detect"], &p);
    assert_eq!(out.status.code(), Some(10));
    assert_eq!(
        text(&out.stderr),
        format!("busnoop: empty input: {} holds no bytes\n", p.display())
    );
    // Missing files and directories keep their codes.
    assert_eq!(
        run(&["detect"], &dir.path().join("nope.bin")).status.code(),
        Some(3)
    );
    assert_eq!(run(&["detect"], dir.path()).status.code(), Some(3));
    // One byte is "1 byte examined".
    let one = dir.path().join("one.bin");
    std::fs::write(&one, b"\x7e").unwrap();
    let out = run(&["detect"], &one);
    assert!(
        text(&out.stdout).starts_with(&format!("{}: raw bytes, 1 byte examined\n", one.display())),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn detect_truncated_and_mixed_files() {
    let dir = tempfile::tempdir().unwrap();
    let sport = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let sab1 = std::fs::read(fixture("sab1-session.bin")).unwrap();
    // Truncated in the middle of a frame.
    let p = dir.path().join("cut.bin");
    std::fs::write(&p, &sport[..sport.len() - 5]).unwrap();
    let out = run(&["detect"], &p);
    assert_eq!(out.status.code(), Some(0));
    assert!(verdict_and_run(&out).0.starts_with("verdict: S.Port ("));
    // Noise around frames.
    let mut bytes = noise(200, 3);
    bytes.extend(&sport);
    bytes.extend(noise(200, 4));
    let p = dir.path().join("noisy.bin");
    std::fs::write(&p, &bytes).unwrap();
    let out = run(&["detect"], &p);
    assert_eq!(out.status.code(), Some(0));
    assert!(verdict_and_run(&out).0.starts_with("verdict: S.Port ("));
    // Two protocols one after the other: both named, each with its command.
    let mut bytes = sport.clone();
    bytes.extend(&sab1);
    let p = dir.path().join("mixed.bin");
    std::fs::write(&p, &bytes).unwrap();
    let out = run(&["detect"], &p);
    assert_eq!(out.status.code(), Some(0));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("verdict: S.Port ("), "{stdout}");
    assert!(
        stdout.contains("also: SAB v1 (sync framing) in ") && stdout.contains("the input is mixed"),
        "{stdout}"
    );
    assert!(
        stdout.ends_with(&format!("run:  busnoop sab2 {}\n", p.display())),
        "{stdout}"
    );
}

#[test]
fn detect_an_inverted_sport_capture() {
    let dir = tempfile::tempdir().unwrap();
    let inverted: Vec<u8> = std::fs::read(fixture("sport-sample.bin"))
        .unwrap()
        .iter()
        .map(|b| !b)
        .collect();
    let p = dir.path().join("inv.bin");
    std::fs::write(&p, &inverted).unwrap();
    let out = run(&["detect"], &p);
    assert_eq!(out.status.code(), Some(0));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("verdict: S.Port, inverted line (100.0%"),
        "{stdout}"
    );
    assert!(
        stdout.contains("fix:  the line is inverted: 0x81 arrives where S.Port's 0x7E belongs"),
        "{stdout}"
    );
    // sport on it: nothing decodes, and the message says why.
    let out = run(&["sport"], &p);
    assert_eq!(out.status.code(), Some(10));
    assert!(
        text(&out.stderr).contains("it looks like S.Port with inverted bytes"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn detect_listens_to_a_serial_port() {
    // A pty ignores the baud rate, so every rate hears the same S.Port traffic; the verdict
    // goes to S.Port's own rate, and the command needs no --baud.
    use common::pty;
    let _g = pty::lock();
    let mut bus = pty::bus();
    let (mut child, rx) = pty::spawn(
        &[
            "detect",
            "--listen-ms",
            "150",
            "--baud",
            "9600,57600,115200",
        ],
        &bus.path,
    );
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        let _ = bus.master.write_all(&sample);
        let _ = bus.master.flush();
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    let stderr = pty::stderr_of(&mut child);
    let mut lines = Vec::new();
    while let Ok((_, l)) = rx.recv_timeout(common::PATIENCE) {
        lines.push(l);
    }
    assert_eq!(status.code(), Some(0), "{stderr}\n{lines:#?}");
    // Each of the 3 rates in every protocol's character format (8N1, Futaba's 8E2, Modbus's 8E1 …).
    let formats: std::collections::BTreeSet<String> = busnoop::protocols::PROTOCOLS
        .iter()
        .map(|p| p.line.format())
        .collect();
    let settings = 3 * formats.len();
    assert!(
        stderr.contains("listening to")
            && stderr.contains(&format!("at each of {settings} line settings")),
        "{stderr}"
    );
    assert_eq!(lines[0], format!("{}: a serial line", bus.path.display()));
    assert_eq!(lines.len(), 1 + settings + 2, "{lines:#?}");
    assert!(
        lines[1..=settings]
            .iter()
            .any(|l| l.trim_start().starts_with("9600 baud 8N1: ")),
        "{lines:#?}"
    );
    assert!(
        lines[1 + settings].starts_with("verdict: S.Port at 57600 baud ("),
        "{lines:#?}"
    );
    assert_eq!(
        lines[2 + settings],
        format!("run:  busnoop sport {}", bus.path.display())
    );
}

#[test]
fn help_names_only_the_sources_each_protocol_reads() {
    let help = |cmd: &str| text(&busnoop().args([cmd, "--help"]).output().unwrap().stdout);
    let sport = help("sport");
    assert!(sport.contains("EdgeTX/OpenTX S.Port debug log"), "{sport}");
    // Recordings may be pcapng (--record FILE.pcapng); network captures are not for S.Port.
    assert!(
        sport.contains("a busnoop .pcap or .pcapng recording")
            && !sport.contains("pcap/pcapng capture")
            && !sport.contains("network"),
        "{sport}"
    );
    let sbus = help("sbus");
    assert!(sbus.contains("Ether-S-Bus traffic"), "{sbus}");
    assert!(!sbus.contains("EdgeTX"), "{sbus}");
    assert!(sbus.contains("--udp-port <PORT>"), "{sbus}");
    assert!(!sbus.contains("--port"), "the old name is hidden: {sbus}");
    let sab = help("sab2");
    assert!(!sab.contains("EdgeTX") && !sab.contains("network"), "{sab}");
    assert!(
        sab.contains("raw wire bytes, a busnoop .pcap or .pcapng recording"),
        "{sab}"
    );
    let top = text(&busnoop().arg("--help").output().unwrap().stdout);
    assert!(top.contains("10 nothing decoded"), "{top}");
    assert!(top.contains("11 no known protocol (detect)"), "{top}");
}

#[test]
fn notes_on_options_that_cannot_apply() {
    let dir = tempfile::tempdir().unwrap();
    // --time abs on raw bytes.
    let out = busnoop()
        .args(["sport", "--time", "abs"])
        .arg(fixture("sport-sample.bin"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        text(&out.stderr),
        "busnoop: note: --time abs: raw wire bytes carry no wall-clock time, so the Time column \
         stays empty (a recording made with --record FILE.pcap keeps the times)\n"
    );
    // --utc on an EdgeTX log's naive times.
    let out = busnoop()
        .args(["sport", "--time", "abs", "--utc"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        text(&out.stderr),
        "busnoop: note: --utc: an EdgeTX log's times have no time zone; they are shown as logged\n"
    );
    // --utc without --time abs.
    let out = busnoop()
        .args(["sport", "--utc"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .output()
        .unwrap();
    assert_eq!(
        text(&out.stderr),
        "busnoop: note: --utc has an effect only with --time abs\n"
    );
    // A recording has real times: no note.
    let out = busnoop()
        .args(["sbus", "--time", "abs", "--utc"])
        .arg(fixture("sbus-digimat.pcap"))
        .output()
        .unwrap();
    assert_eq!(
        text(&out.stderr),
        "busnoop: S-Bus: 1 NAK in 50 valid telegrams\n"
    );
    // -o with an extension that names no format: TSV, said so.
    let xlsx = dir.path().join("table.xlsx");
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .arg("-o")
        .arg(&xlsx)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        text(&out.stderr),
        format!(
            "busnoop: note: -o {}: .xlsx is not a format busnoop writes; the table is TSV \
             (tab-separated). Use .csv, .tsv, .jsonl or .txt, or --format\n",
            xlsx.display()
        )
    );
    assert!(
        std::fs::read_to_string(&xlsx)
            .unwrap()
            .starts_with("Counter\tMillis\t")
    );
    // ... but not with --format, nor for a known extension.
    for extra in [&["-f", "csv"][..], &[]] {
        let target = if extra.is_empty() {
            dir.path().join("t.csv")
        } else {
            xlsx.clone()
        };
        let out = busnoop()
            .arg("sport")
            .arg(fixture("sport-sample.bin"))
            .arg("-o")
            .arg(&target)
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(text(&out.stderr), "", "{extra:?}");
    }
}

#[test]
fn verbose_diagnostics_are_plain_text_off_a_terminal() {
    let out = busnoop()
        .args(["-vv", "sport"])
        .arg(fixture("sport-sample.bin"))
        .stdout(Stdio::null())
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(err.contains("INFO"), "{err}");
    assert!(!err.contains('\x1b'), "colour codes in a pipe: {err:?}");
}

#[test]
fn completions_for_every_shell() {
    for (shell, marker) in [
        ("bash", "_busnoop()"),
        ("zsh", "#compdef busnoop"),
        ("fish", "complete -c busnoop"),
        ("elvish", "busnoop"),
        ("powershell", "busnoop"),
    ] {
        let out = busnoop().args(["completions", shell]).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{shell}");
        let script = text(&out.stdout);
        assert!(script.contains(marker), "{shell}");
        for sub in ["sport", "sbus", "sab2", "detect"] {
            assert!(script.contains(sub), "{shell}: {sub}");
        }
    }
    // The new S-Bus option name is completed, the hidden old one is not.
    let bash = text(
        &busnoop()
            .args(["completions", "bash"])
            .output()
            .unwrap()
            .stdout,
    );
    assert!(bash.contains("--udp-port"));
    let out = busnoop().args(["completions", "tcsh"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn man_pages() {
    let out = busnoop().arg("man").output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let page = text(&out.stdout);
    assert!(page.contains(".TH busnoop 1"), "{}", &page[..200]);
    assert!(page.contains("EXIT STATUS"));
    let dir = tempfile::tempdir().unwrap();
    let out = busnoop()
        .args(["man", "--dir"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    for name in [
        "busnoop.1",
        "busnoop-sport.1",
        "busnoop-sbus.1",
        "busnoop-detect.1",
    ] {
        let p = dir.path().join(name);
        assert!(
            std::fs::read_to_string(&p).unwrap().contains(".TH"),
            "{name}"
        );
    }
    let out = busnoop()
        .args(["man", "--dir"])
        .arg(dir.path().join("busnoop.1"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}
