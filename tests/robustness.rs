//! The bad-input matrix of docs/robustness.md: every case gives a clear message, no panic, its
//! own exit code, and keeps the rows decoded so far.

mod common;

use std::os::unix::process::CommandExt;
use std::process::{Output, Stdio};

use common::fixture;
use common::{busnoop, noise, text};

/// No panic message, whatever happened.
fn no_panic(out: &Output) {
    let err = text(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(!err.contains("RUST_BACKTRACE"), "{err}");
}

const HEADER: &str = "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote";

#[test]
fn empty_file() {
    // An empty input is said so, with the exit code of "nothing decoded" (10).
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("empty.bin");
    std::fs::write(&p, b"").unwrap();
    let out = busnoop().arg("sport").arg(&p).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(10));
    assert_eq!(text(&out.stdout), format!("{HEADER}\n"));
    assert_eq!(
        text(&out.stderr),
        format!("busnoop: empty input: {} holds no bytes\n", p.display())
    );
    // Empty standard input too.
    let out = busnoop()
        .args(["sport", "-"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(10));
    assert_eq!(text(&out.stdout), format!("{HEADER}\n"));
    assert_eq!(
        text(&out.stderr),
        "busnoop: empty input: standard input holds no bytes\n"
    );
}

#[test]
fn truncated_file() {
    let dir = tempfile::tempdir().unwrap();
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    // Cut inside the last data frame (Alt 65.43 is frame 23 of 30 rows; cut 4 bytes into it).
    let alt = sample
        .windows(4)
        .position(|w| w == [0x7E, 0x00, 0x10, 0x00])
        .unwrap();
    let cut = &sample[..alt + 5];
    let p = dir.path().join("cut.bin");
    std::fs::write(&p, cut).unwrap();
    let out = busnoop().arg("sport").arg(&p).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(0));
    let stdout = text(&out.stdout);
    let last = stdout.lines().last().unwrap();
    assert!(last.contains("\tTruncated\t"), "{last}");
    assert!(last.contains("3 of 8 bytes"), "{last}");
    assert_eq!(
        stdout.lines().count(),
        1 + 23,
        "every row before the cut is kept"
    );
    assert_eq!(
        text(&out.stderr),
        "busnoop: S.Port: 1 truncated frame in 14 valid frames\n"
    );
}

#[test]
fn random_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = noise(200_000, 0x2545_F491_4F6C_DD1D);
    let p = dir.path().join("noise.bin");
    std::fs::write(&p, &bytes).unwrap();
    let out = busnoop().args(["sport", "--raw"]).arg(&p).output().unwrap();
    no_panic(&out);
    // A valid frame or two turn up in noise by chance: the rows, the summary line, that
    // almost nothing decodes and no protocol fits, and exit 13 (README, "Exit codes").
    assert_eq!(out.status.code(), Some(13));
    let err = text(&out.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "{err}");
    assert!(lines[0].starts_with("busnoop: S.Port: "), "{err}");
    assert!(lines[0].contains("garbage bytes skipped"), "{err}");
    assert!(
        lines[1].starts_with("busnoop: only <0.1% of the bytes are in valid S.Port frames")
            && lines[1].ends_with("finds no known protocol in it"),
        "{err}"
    );
    assert!(lines[2].contains("exit code 13"), "{err}");
    // Every input byte is in the Raw column of exactly one row.
    let stdout = text(&out.stdout);
    let raw_bytes: usize = stdout
        .lines()
        .skip(1)
        .map(|l| {
            l.rsplit('\t')
                .next()
                .unwrap()
                .split(' ')
                .filter(|s| !s.is_empty())
                .count()
        })
        .sum();
    assert_eq!(raw_bytes, bytes.len());
}

#[test]
fn wrong_protocol_for_the_file() {
    // Bytes that are no S.Port: no valid frame, shown as garbage, the summary line, then the
    // "nothing decoded" failure (exit 10) pointing at `busnoop detect`.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("sbus.bin");
    let telegram = [0xB5, 0x00, 0x01, 0x06, 0x00, 0x00, 0x0A, 0x12, 0x34];
    std::fs::write(&p, telegram.repeat(50)).unwrap();
    let out = busnoop().arg("sport").arg(&p).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(10));
    let err = text(&out.stderr);
    assert!(err.contains("in 0 valid frames"), "{err}");
    assert!(
        err.ends_with(&format!(
            "busnoop: no S.Port frame in {0}; `busnoop detect {0}` finds no known protocol in it\n",
            p.display()
        )),
        "{err}"
    );
    // A pcap of network traffic given to the S.Port decoder is refused with a reason.
    let mut pcap = vec![0xD4, 0xC3, 0xB2, 0xA1, 2, 0, 4, 0];
    pcap.extend_from_slice(&[0; 8]);
    pcap.extend_from_slice(&65535u32.to_le_bytes());
    pcap.extend_from_slice(&1u32.to_le_bytes()); // Ethernet
    let p = dir.path().join("net.pcap");
    std::fs::write(&p, &pcap).unwrap();
    let out = busnoop().arg("sport").arg(&p).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(9));
    assert!(
        text(&out.stderr).contains("pcap of network traffic"),
        "{}",
        text(&out.stderr)
    );
    assert_eq!(
        text(&out.stdout),
        "",
        "nothing written before the input is known to be usable"
    );
}

#[test]
fn recording_cut_short() {
    // A recording whose records are cut short is replayed up to the cut, with a warning.
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("r.pcap");
    let out = busnoop()
        .arg("sport")
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .arg("--record")
        .arg(&rec)
        .output()
        .unwrap();
    assert!(out.status.success());
    let full = std::fs::read(&rec).unwrap();
    std::fs::write(&rec, &full[..full.len() - 5]).unwrap();
    let out = busnoop().arg("sport").arg(&rec).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(0));
    assert!(
        text(&out.stderr).contains("the last record is cut short"),
        "{}",
        text(&out.stderr)
    );
    assert_eq!(
        text(&out.stdout).lines().count(),
        592,
        "all but the cut record"
    );
}

#[test]
fn directory_as_source() {
    let dir = tempfile::tempdir().unwrap();
    let out = busnoop().arg("sport").arg(dir.path()).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(3));
    assert_eq!(
        text(&out.stderr),
        format!(
            "busnoop: {} is a directory; give a capture file, a serial device or - for standard input\n",
            dir.path().display()
        )
    );
}

#[test]
fn missing_file() {
    let out = busnoop()
        .args(["sport", "no/such/capture.bin"])
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(3));
    assert_eq!(
        text(&out.stderr),
        "busnoop: no/such/capture.bin: no such file or device\n"
    );
}

#[test]
fn unreadable_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let p = dir.path().join("secret.bin");
    std::fs::copy(fixture("sport-sample.bin"), &p).unwrap();
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o000)).unwrap();
    // Root reads anything: then busnoop runs as an unprivileged user.
    let (_keep, mut cmd) = common::unprivileged_busnoop();
    let out = cmd
        .arg("sport")
        .arg(&p)
        .env_remove("RUST_LOG")
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(4));
    assert_eq!(
        text(&out.stderr),
        format!(
            "busnoop: {}: permission denied (check the file's permissions)\n",
            p.display()
        )
    );
}

#[test]
fn output_to_a_full_disk() {
    // /dev/full: every write fails with ENOSPC.
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .args(["-o", "/dev/full"])
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(8));
    assert_eq!(
        text(&out.stderr),
        "busnoop: cannot write to /dev/full: No space left on device (os error 28)\n"
    );
    // Standard output on a full disk.
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .stdout(full)
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(8));
    assert_eq!(
        text(&out.stderr),
        "busnoop: cannot write to standard output: No space left on device (os error 28)\n"
    );
}

#[test]
fn output_file_that_fills_up_ends_with_a_whole_row() {
    // A file size limit makes the disk "full" after 100 kB: the file is cut back to the last
    // whole row, and the exit code says so.
    let dir = tempfile::tempdir().unwrap();
    let big = common::big_sport(dir.path(), 20_000, 0x0300);
    let csv = dir.path().join("out.csv");
    let mut cmd = busnoop();
    cmd.arg("sport").arg(&big).arg("-o").arg(&csv);
    common::limit_file_size(&mut cmd, 100_000);
    let out = cmd.output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(8));
    assert!(
        text(&out.stderr).starts_with(&format!("busnoop: cannot write to {}: ", csv.display())),
        "{}",
        text(&out.stderr)
    );
    let written = std::fs::read_to_string(&csv).unwrap();
    assert!(
        written.len() <= 100_000 && written.len() > 50_000,
        "{}",
        written.len()
    );
    assert!(written.ends_with("\r\n"), "the file ends with a whole row");
    let mut r = csv::Reader::from_reader(written.as_bytes());
    let n = r.records().inspect(|rec| assert!(rec.is_ok())).count();
    assert!(n > 500, "rows decoded so far are kept: {n}");
}

/// The lengths of the records of a classic pcap (`pcapng`: of the blocks), or the byte where
/// the file ends inside one.
fn whole_records(bytes: &[u8], pcapng: bool) -> Result<usize, usize> {
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    let (mut at, mut n) = (if pcapng { 0 } else { 24 }, 0);
    while at < bytes.len() {
        let len = match (pcapng, bytes.len() - at) {
            (true, left) if left >= 12 => u32_at(at + 4),
            (false, left) if left >= 16 => 16 + u32_at(at + 8),
            _ => return Err(at),
        };
        if len < 12 || at + len > bytes.len() {
            return Err(at);
        }
        at += len;
        n += 1;
    }
    Ok(n)
}

/// A recording or an export on a disk that fills up during the run ends with its last whole
/// record, like the table ends with its last whole row; it replays without a warning. Both
/// used to end inside a record (Wireshark: "cut short in the middle of a packet").
#[test]
fn recording_and_export_that_fill_up_end_with_a_whole_record() {
    let dir = tempfile::tempdir().unwrap();
    let big = common::big_sport(dir.path(), 20_000, 0x0300);
    for (option, name) in [
        ("--record", "r.pcap"),
        ("--record", "r.pcapng"),
        ("--export", "e.pcapng"),
    ] {
        let file = dir.path().join(name);
        let mut cmd = busnoop();
        cmd.arg("sport")
            .arg(&big)
            .arg(option)
            .arg(&file)
            .args(["-o", "/dev/null"]);
        common::limit_file_size(&mut cmd, 100_000);
        let out = cmd.output().unwrap();
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(8), "{name}: {err}");
        assert!(err.contains(&file.display().to_string()), "{err}");
        let written = std::fs::read(&file).unwrap();
        assert!(written.len() <= 100_000, "{name}: {}", written.len());
        let records = whole_records(&written, name.ends_with("pcapng"));
        assert!(
            records.is_ok_and(|n| n > 10),
            "{name}: {records:?} of {} bytes",
            written.len()
        );
        if option == "--record" {
            let out = busnoop()
                .arg("sport")
                .arg(&file)
                .args(["-o", "/dev/null"])
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(0), "{name}");
            assert!(
                !text(&out.stderr).contains("cut short"),
                "{}",
                text(&out.stderr)
            );
        }
    }
}

#[test]
fn recording_to_a_full_disk() {
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .args(["--record", "/dev/full", "-o", "/dev/null"])
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(8));
    assert!(
        text(&out.stderr).starts_with("busnoop: cannot write recording /dev/full: No space left"),
        "{}",
        text(&out.stderr)
    );
}

/// The cases every protocol shares, for each protocol of the table.
fn protocols() -> impl Iterator<Item = &'static str> {
    busnoop::protocols::PROTOCOLS.iter().map(|p| p.command)
}

#[test]
fn every_protocol_empty_random_missing_directory_full_disk() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let noisy = dir.path().join("noise.bin");
    std::fs::write(&noisy, noise(50_000, 0x9E37_79B9_7F4A_7C15)).unwrap();
    for p in protocols() {
        // Empty: the header only, "empty input", exit 10.
        let out = busnoop().arg(p).arg(&empty).output().unwrap();
        no_panic(&out);
        assert_eq!(out.status.code(), Some(10), "{p}");
        assert_eq!(text(&out.stdout).lines().count(), 1, "{p}");
        assert!(
            text(&out.stdout)
                .starts_with("Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData")
        );
        assert_eq!(
            text(&out.stderr),
            format!("busnoop: empty input: {} holds no bytes\n", empty.display()),
            "{p}"
        );
        // Random bytes: rows, the summary line naming what went wrong, and the word that no
        // protocol fits: exit 13 when a frame turned up by chance, else exit 10.
        let out = busnoop().arg(p).arg(&noisy).output().unwrap();
        no_panic(&out);
        let err = text(&out.stderr);
        let lines: Vec<&str> = err.lines().collect();
        assert!((2..=3).contains(&lines.len()), "{p}: {err}");
        assert!(
            lines[0].starts_with("busnoop: ") && lines[0].contains("garbage"),
            "{p}: {err}"
        );
        assert!(
            lines[1].ends_with("finds no known protocol in it"),
            "{p}: {err}"
        );
        // No row of a whole frame at all: "no … frame"; some by chance: a poor run.
        let expected = if lines[1].starts_with("busnoop: no ") {
            assert_eq!(lines.len(), 2, "{p}: {err}");
            10
        } else {
            assert!(lines[1].starts_with("busnoop: only "), "{p}: {err}");
            assert!(lines[2].contains("(exit code 13;"), "{p}: {err}");
            13
        };
        assert_eq!(out.status.code(), Some(expected), "{p}: {err}");
        assert!(text(&out.stdout).lines().count() > 10, "{p}");
        // Missing file and directory.
        let out = busnoop()
            .arg(p)
            .arg(dir.path().join("missing.bin"))
            .output()
            .unwrap();
        no_panic(&out);
        assert_eq!(out.status.code(), Some(3), "{p}");
        assert!(
            text(&out.stderr).ends_with("missing.bin: no such file or device\n"),
            "{p}"
        );
        let out = busnoop().arg(p).arg(dir.path()).output().unwrap();
        assert_eq!(out.status.code(), Some(3), "{p}");
        assert!(text(&out.stderr).contains("is a directory"), "{p}");
        // Full disk.
        let out = busnoop()
            .arg(p)
            .arg(&noisy)
            .args(["-o", "/dev/full"])
            .output()
            .unwrap();
        no_panic(&out);
        assert_eq!(out.status.code(), Some(8), "{p}");
        assert!(
            text(&out.stderr).starts_with("busnoop: cannot write to /dev/full: No space left"),
            "{p}"
        );
    }
}

#[test]
fn every_protocol_closed_stdout_is_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let noisy = dir.path().join("noise.bin");
    std::fs::write(&noisy, noise(400_000, 0x2545_F491_4F6C_DD1D)).unwrap();
    for p in protocols() {
        let mut child = busnoop()
            .arg(p)
            .arg(&noisy)
            .arg("--raw")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        std::io::BufRead::read_line(
            &mut std::io::BufReader::new(child.stdout.take().unwrap()),
            &mut first,
        )
        .unwrap();
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(141), "{p}");
        assert_eq!(text(&out.stderr), "", "{p}");
    }
}

#[test]
fn pcap_with_a_link_type_that_is_not_network_traffic() {
    // Link type 105 (802.11): S-Bus reports a Skipped row and counts the packets; the serial
    // protocols refuse a pcap of network traffic.
    let dir = tempfile::tempdir().unwrap();
    let mut pcap = vec![0xD4, 0xC3, 0xB2, 0xA1, 2, 0, 4, 0];
    pcap.extend_from_slice(&[0; 8]);
    pcap.extend_from_slice(&65535u32.to_le_bytes());
    pcap.extend_from_slice(&105u32.to_le_bytes());
    for i in 0..3u32 {
        pcap.extend_from_slice(&(1_700_000_000 + i).to_le_bytes());
        pcap.extend_from_slice(&0u32.to_le_bytes());
        pcap.extend_from_slice(&40u32.to_le_bytes());
        pcap.extend_from_slice(&40u32.to_le_bytes());
        pcap.extend_from_slice(&[0xAB; 40]);
    }
    let p = dir.path().join("wifi.pcap");
    std::fs::write(&p, &pcap).unwrap();
    let out = busnoop().arg("sbus").arg(&p).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(10), "nothing decoded");
    let stdout = text(&out.stdout);
    assert_eq!(stdout.lines().count(), 2, "{stdout}");
    assert!(
        stdout.lines().nth(1).unwrap().contains("\tSkipped\t"),
        "{stdout}"
    );
    assert!(
        stdout.contains("link type 105 are not network traffic"),
        "{stdout}"
    );
    assert_eq!(
        text(&out.stderr),
        format!(
            "busnoop: S-Bus: 3 packets of a link type that is not network traffic skipped in 0 valid telegrams\n\
             busnoop: no S-Bus frame in {0}; `busnoop detect {0}` finds no known protocol in it\n",
            p.display()
        )
    );
    for proto in ["sport", "sab2"] {
        let out = busnoop().arg(proto).arg(&p).output().unwrap();
        no_panic(&out);
        assert_eq!(out.status.code(), Some(9), "{proto}");
        assert!(
            text(&out.stderr).contains("pcap of network traffic"),
            "{proto}"
        );
    }
}

#[test]
fn wrong_protocol_for_every_decoder() {
    // Each protocol's own sample given to the other decoders: no panic, the summary line, then
    // the protocol that fits with the command to run: exit 10 when nothing decoded, else
    // exit 13 (S-Bus break mode reads S.Port's zero keep-alives as telegrams).
    let samples = [
        ("sport", fixture("sport-sample.bin"), "busnoop sport"),
        ("sab2", fixture("sab2-session.bin"), "busnoop sab2"),
        ("sab2", fixture("sab1-session.bin"), "busnoop sab2"),
        ("sbus", fixture("sbus-digimat.pcap"), "busnoop sbus"),
    ];
    for (own, file, command) in &samples {
        for p in protocols().filter(|p| p != own) {
            let out = busnoop().arg(p).arg(file).output().unwrap();
            no_panic(&out);
            let code = out.status.code();
            let err = text(&out.stderr);
            if file.extension().is_some_and(|e| e == "pcap") {
                // A pcap of network traffic is refused by the serial-only decoders.
                assert_eq!(code, Some(9), "{p} on {own}: {err}");
                continue;
            }
            let lines: Vec<&str> = err.lines().collect();
            let suggestion = format!("; try: {command} {}", file.display());
            assert!(lines[1].ends_with(&suggestion), "{p} on {own}: {err}");
            if lines[1].starts_with("busnoop: no ") {
                assert_eq!(lines.len(), 2, "{p} on {own}: {err}");
                assert_eq!(code, Some(10), "{p} on {own}: {err}");
            } else {
                assert_eq!(lines.len(), 3, "{p} on {own}: {err}");
                assert_eq!(code, Some(13), "{p} on {own}: {err}");
                assert!(
                    lines[1].starts_with("busnoop: only "),
                    "{p} on {own}: {err}"
                );
            }
        }
    }
}

#[test]
fn sbus_on_an_sport_capture_names_sport() {
    // The case of the issue: break mode reads S.Port's zero keep-alives as 16 valid telegrams.
    let file = fixture("sport-sample.bin");
    let out = busnoop().arg("sbus").arg(&file).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(13));
    assert_eq!(
        text(&out.stderr),
        format!(
            "busnoop: S-Bus: 2 CRC errors, 97 garbage bytes skipped (17 runs), 1 timeout in 16 valid telegrams\n\
             busnoop: only 49.1% of the bytes are in valid S-Bus frames; it looks like S.Port \
             (100.0% of the bytes in 30 valid frames); try: busnoop sport {}\n\
             busnoop: most of the input is not valid S-Bus frames (exit code 13; --lenient \
             accepts such a run)\n",
            file.display()
        )
    );
}

#[test]
fn sport_on_a_text_file_is_nothing_decoded() {
    let file = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
    let out = busnoop().arg("sport").arg(&file).output().unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(10));
    let err = text(&out.stderr);
    assert!(
        err.ends_with(&format!(
            "busnoop: no S.Port frame in {0}; `busnoop detect {0}` finds no known protocol in it\n",
            file.display()
        )),
        "{err}"
    );
}

#[test]
fn wrong_options_for_the_right_protocol() {
    // Ether-S-Bus on another UDP port: nothing decodes with these options, the defaults do.
    let file = fixture("sbus-digimat.pcap");
    let out = busnoop()
        .args(["sbus", "--udp-port", "5051"])
        .arg(&file)
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(10));
    let err = text(&out.stderr);
    assert!(
        err.ends_with(&format!(
            "busnoop: no S-Bus frame in {0} with these options, but 100.0% of its bytes are in \
             valid Ether-S-Bus frames with the defaults; try: busnoop sbus {0}\n",
            file.display()
        )),
        "{err}"
    );
    // The old name of the option still works (hidden).
    let out = busnoop()
        .args(["sbus", "--port", "5050"])
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

#[test]
fn output_to_a_capture_name_points_to_record() {
    // `-o capture.pcap` would write a table into a file named like a capture: refused, with the
    // option that does what was meant.
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("capture.pcap");
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .arg("-o")
        .arg(&target)
        .output()
        .unwrap();
    no_panic(&out);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr),
        format!(
            "busnoop: -o writes the decoded table (pretty, tsv, csv or jsonl); to keep the bytes from the wire use --record {}\n",
            target.display()
        )
    );
    assert!(!target.exists(), "nothing is created");
}

/// Standard error on a full disk (`2>/dev/full`) or closed (`2>&-`): the messages are lost, but
/// the run ends with its own exit code. Every message used to panic there (exit 101), a
/// warning in the middle of a run ending it.
#[test]
fn a_full_or_closed_stderr_keeps_the_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let random = dir.path().join("random.bin");
    std::fs::write(&random, noise(5000, 7)).unwrap();
    let sample = fixture("sport-sample.bin");
    let table = dir.path().join("table.tsv");
    let runs: [(Vec<&std::ffi::OsStr>, i32); 5] = [
        // Warnings and the problems line, then "no S.Port frame".
        (vec!["sport".as_ref(), random.as_os_str()], 10),
        (vec!["sport".as_ref(), "/no/such/capture".as_ref()], 3),
        (
            vec![
                "sport".as_ref(),
                sample.as_os_str(),
                "--stats".as_ref(),
                "-o".as_ref(),
                table.as_os_str(),
            ],
            0,
        ),
        (vec!["detect".as_ref(), random.as_os_str()], 11),
        (
            vec![
                "sport".as_ref(),
                "-".as_ref(),
                "--wide".as_ref(),
                "-f".as_ref(),
                "jsonl".as_ref(),
            ],
            2,
        ),
    ];
    for (args, code) in runs {
        for closed in [false, true] {
            let mut cmd = busnoop();
            cmd.args(&args).stdout(Stdio::null()).stdin(Stdio::null());
            if closed {
                // SAFETY: only closes a descriptor in the child before exec.
                unsafe {
                    cmd.pre_exec(|| {
                        libc::close(2);
                        Ok(())
                    });
                }
            } else {
                cmd.stderr(std::fs::File::create("/dev/full").unwrap());
            }
            let out = cmd.output().unwrap();
            assert_eq!(
                out.status.code(),
                Some(code),
                "{args:?}, stderr closed: {closed}"
            );
        }
    }
    // The table is whole: the --stats run wrote every row.
    assert_eq!(text(&std::fs::read(&table).unwrap()).lines().count(), 31);
}

/// A character device that is not a terminal is read as a file, /dev/urandom as well as
/// /dev/zero: its terminal ioctl fails with EINVAL rather than ENOTTY, and busnoop took it for a
/// serial port it could not open (`cannot open the serial port: tcgetattr: Invalid argument`,
/// exit 6).
#[test]
fn dev_urandom_is_read_as_a_file() {
    if !std::path::Path::new("/dev/urandom").exists() {
        return;
    }
    let out = busnoop().args(["detect", "/dev/urandom"]).output().unwrap();
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(11), "{err}");
    assert!(
        text(&out.stdout).contains("2097"),
        "2 MiB examined: {}",
        text(&out.stdout)
    );
    // The decoders read it until Ctrl-C: sent once its handlers are in place and 100 rows are
    // written (into a file, to count them while it runs).
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("t.tsv");
    let mut child = busnoop()
        .args(["sport", "/dev/urandom", "-f", "tsv", "-o"])
        .arg(&table)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_for_handlers(&child);
    common::until("100 rows", || {
        std::fs::read(&table).is_ok_and(|t| t.iter().filter(|&&b| b == b'\n').count() > 100)
    });
    // SAFETY: kill() sends a signal to our own child; no memory is involved.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let status = child.wait().unwrap();
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(std::fs::read_to_string(&table).unwrap().lines().count() > 100);
}

/// `busnoop detect /dev/zero` reads it as a file: stderr does not claim that busnoop listens to
/// it at nine baud rates (it used to, before finding out it is no terminal).
#[test]
fn detect_on_a_device_that_is_no_terminal_does_not_claim_to_listen() {
    let out = busnoop().args(["detect", "/dev/zero"]).output().unwrap();
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(11), "{err}");
    assert!(!err.contains("listening"), "{err}");
    assert!(
        text(&out.stdout).contains("/dev/zero: raw bytes"),
        "{}",
        text(&out.stdout)
    );
}

/// Every command that prints on standard output ends quietly with 141 when the reader went
/// away: `busnoop extcap --extcap-interfaces` into a closed pipe used to say `cannot write to
/// standard output: Broken pipe` with exit 8, unlike `detect`, `ports`, `man` and the tables.
#[test]
fn every_command_on_a_closed_pipe_is_quiet() {
    for args in [
        &["extcap", "--extcap-interfaces"][..],
        &[
            "extcap",
            "--extcap-interface",
            "busnoop-sport",
            "--extcap-dlts",
        ][..],
        &["man"][..],
        &["completions", "bash"][..],
    ] {
        let mut fds = [0; 2];
        // SAFETY: pipe() fills the two descriptors; the read end is closed at once, the write
        // end handed to the child as its standard output (and closed here by the File).
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        unsafe { libc::close(fds[0]) };
        let write_end = unsafe { <std::fs::File as std::os::fd::FromRawFd>::from_raw_fd(fds[1]) };
        let out = busnoop().args(args).stdout(write_end).output().unwrap();
        no_panic(&out);
        assert_eq!(
            out.status.code(),
            Some(141),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert_eq!(text(&out.stderr), "", "{args:?}");
    }
}
