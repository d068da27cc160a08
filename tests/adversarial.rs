//! Hostile inputs and conditions from the third reliability round (issue 32): each case of
//! docs/robustness.md's "Round three" table has its test here (the pty and signal cases are in
//! tests/top.rs and tests/signals.rs).

mod common;

use std::path::Path;
use std::process::Output;

use common::{busnoop, fixture, no_panic, pcap_packets, pcapng, text};

/// The rows of a TSV table, split into cells (the header first).
fn cells(table: &str) -> Vec<Vec<&str>> {
    table.lines().map(|l| l.split('\t').collect()).collect()
}

/// Runs busnoop with `args`, the table to `dir/out.tsv`; returns the run and the table.
fn run_to_file(dir: &Path, args: &[&str]) -> (Output, String) {
    let out_path = dir.join("out.tsv");
    let _ = std::fs::remove_file(&out_path);
    let out = busnoop()
        .args(args)
        .args(["-f", "tsv", "-o"])
        .arg(&out_path)
        .output()
        .unwrap();
    no_panic(&out);
    let table = std::fs::read_to_string(&out_path).unwrap_or_default();
    (out, table)
}

/// H1: a time stamp beyond chrono's range (a flipped top bit in a pcapng packet, `if_tsresol`
/// 10^0 with a far time) panicked in `--time abs`, `--wide`, `--record`, `--export` with an
/// empty output. Now it is a `TimeJump` row, its packet goes on at the time before, and every
/// row is written.
#[test]
fn h1_a_time_stamp_beyond_the_calendar_is_a_row_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    // Seconds (10^0): 2023, then 2^62 s, then a second later than the first.
    let seconds = pcapng(
        147,
        0,
        &[
            (1_700_000_000, &sample),
            (1 << 62, &sample),
            (1_700_000_001, &sample),
        ],
    );
    // Microseconds, the second packet's top bit flipped.
    let t0 = 1_700_000_000_000_000u64;
    let flipped = pcapng(
        147,
        6,
        &[
            (t0, &sample),
            ((t0 + 500_000) | (1 << 63), &sample),
            (t0 + 1_000_000, &sample),
        ],
    );
    for (name, bytes) in [("seconds.pcapng", &seconds), ("flipped.pcapng", &flipped)] {
        let input = dir.path().join(name);
        std::fs::write(&input, bytes).unwrap();
        let input = input.to_str().unwrap();
        let rec = dir.path().join("r.pcap");
        let rec_ng = dir.path().join("r.pcapng");
        let export = dir.path().join("e.pcapng");
        for extra in [
            vec!["--time", "abs"],
            vec!["--time", "abs", "--utc"],
            vec!["--record", rec.to_str().unwrap()],
            vec!["--record", rec_ng.to_str().unwrap()],
            vec!["--export", export.to_str().unwrap(), "--time", "abs"],
        ] {
            let mut args = vec!["sport", input];
            args.extend(&extra);
            let (out, table) = run_to_file(dir.path(), &args);
            assert_eq!(
                out.status.code(),
                Some(0),
                "{extra:?}: {}",
                text(&out.stderr)
            );
            let rows = cells(&table);
            // The header, 3 × 30 frames and the note.
            assert_eq!(rows.len(), 1 + 90 + 1, "{name} {extra:?}:\n{table}");
            let jump: Vec<_> = rows.iter().filter(|r| r[4] == "TimeJump").collect();
            assert_eq!(jump.len(), 1, "{table}");
            assert!(jump[0][7].contains("out of range"), "{:?}", jump[0]);
            // It comes after the first packet's rows, at the time before.
            let at = rows.iter().position(|r| r[4] == "TimeJump").unwrap();
            assert_eq!(at, 31, "{table}");
            assert_eq!(jump[0][1], rows[30][1]);
            if extra.contains(&"abs") {
                let time = rows[0].iter().position(|c| *c == "Time").unwrap();
                assert!(rows[1][time].starts_with("2023-11-"), "{:?}", rows[1]);
                assert!(rows[91][time].starts_with("2023-11-"), "{:?}", rows[91]);
            }
        }
        // The recordings hold the bytes at the times busnoop gave them: the same frames, with
        // no time out of range left.
        for r in [&rec, &rec_ng] {
            let (out, again) = run_to_file(dir.path(), &["sport", r.to_str().unwrap()]);
            assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
            assert_eq!(cells(&again).len(), 91, "{again}");
        }
        let out = busnoop()
            .args(["sport", input, "--wide", "-f", "csv"])
            .output()
            .unwrap();
        no_panic(&out);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    }
}

/// H1 for network captures: an Ether-S-Bus pcapng with one packet's top bit flipped.
#[test]
fn h1_an_ether_sbus_packet_beyond_the_calendar_is_a_row_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let (link, packets) = pcap_packets(&std::fs::read(fixture("sbus-digimat.pcap")).unwrap());
    let n = packets.len();
    let stamped: Vec<(u64, &[u8])> = packets
        .iter()
        .enumerate()
        .map(|(i, (ts, d))| (if i == n / 2 { ts | 1 << 63 } else { *ts }, &d[..]))
        .collect();
    let input = dir.path().join("bad.pcapng");
    std::fs::write(&input, pcapng(link as u16, 6, &stamped)).unwrap();
    let input = input.to_str().unwrap();
    let (good, good_table) = run_to_file(
        dir.path(),
        &["sbus", &fixture("sbus-digimat.pcap").to_string_lossy()],
    );
    assert_eq!(good.status.code(), Some(0));
    let good_rows = cells(&good_table).len();
    let rec = dir.path().join("r.pcapng");
    for extra in [
        vec!["--time", "abs"],
        vec!["--record", rec.to_str().unwrap()],
        vec!["--wide"],
    ] {
        let mut args = vec!["sbus", input];
        args.extend(&extra);
        let (out, table) = run_to_file(dir.path(), &args);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{extra:?}: {}",
            text(&out.stderr)
        );
        if extra == ["--wide"] {
            continue;
        }
        let rows = cells(&table);
        assert_eq!(rows.len(), good_rows + 1, "{extra:?}\n{table}");
        assert_eq!(rows.iter().filter(|r| r[4] == "TimeJump").count(), 1);
    }
}

/// S.Port data frames: first `columns` frames of app IDs never seen before (a new wide column
/// each), then `frames` more of the first 28 of them, physical IDs 0 to 27 in turn.
fn many_columns_sport(columns: u32, frames: u32) -> Vec<u8> {
    use busnoop::sport::wire;
    let mut bytes = Vec::new();
    for i in 0..columns + frames {
        let k = if i < columns { i } else { i % 28 };
        wire::encode_frame(
            &mut bytes,
            wire::header_for((k % 28) as u8),
            0x10,
            0x5100 + (k / 28) as u16 * 16,
            i,
        );
    }
    bytes
}

/// H2: `--wide` padded every line to every column seen so far and spooled all of them: the
/// spool grew with lines × columns (a crafted 10 MB S.Port capture: 5.75 GB in `$TMPDIR`). Now
/// the spool holds what changed, lines are padded at the end, and the columns are capped
/// (`--max-columns`, default 2000) with a note.
#[test]
fn h2_wide_spools_only_changes_and_caps_the_columns() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("columns.bin");
    std::fs::write(&input, many_columns_sport(6000, 60_000)).unwrap();
    // Any file busnoop writes (its temporary file) is limited to 4 MB; the table goes to a pipe.
    let mut cmd = busnoop();
    cmd.args(["sport", "--wide", "-f", "tsv"]).arg(&input);
    common::limit_file_size(&mut cmd, 4 << 20);
    let out = cmd.output().unwrap();
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("--wide: the table keeps the first 2000 columns")
            && err.contains("--max-columns"),
        "{err}"
    );
    let table = text(&out.stdout);
    let rows = cells(&table);
    assert_eq!(rows[0].len(), 1 + 2000, "Millis and 2000 columns");
    assert!(rows.iter().all(|r| r.len() == 2001), "every line padded");
    // One line per poll cycle of 28 IDs.
    assert_eq!(rows.len(), 1 + 66_000 / 28 + 1, "{}", rows.len());
    // A lower cap.
    let out = busnoop()
        .args(["sport", "--wide", "-f", "csv", "--max-columns", "10"])
        .arg(&input)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let table = text(&out.stdout);
    let header = table.lines().next().unwrap();
    assert_eq!(header.split(',').count(), 11, "{header}");
    assert!(text(&out.stderr).contains("the first 10 columns"));
    // Only with --wide.
    let out = busnoop()
        .args(["sport", "--max-columns", "10"])
        .arg(&input)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// M6: S.Port frames with non-standard check bits (the header byte, which the CRC does not
/// cover, is damaged: its physical ID cannot be trusted) still fed `--wide` and `plot`: bogus
/// columns (`ASpd@11(kts)`) and renamed real ones (`VSpd(m/s)` → `VSpd@0(m/s)`). Such a frame
/// now carries no number, so it enters neither (nor JSON `parts`); its row still shows the
/// decoded text and the note.
#[test]
fn m6_frames_with_damaged_check_bits_enter_neither_wide_nor_plot() {
    use busnoop::sport::wire;
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = Vec::new();
    for i in 0..300u32 {
        wire::encode_frame(&mut bytes, wire::header_for(0), 0x10, 0x0110, i);
        if i % 50 == 7 {
            // Physical ID 11 with the check bits of ID 0: a damaged header.
            let damaged = wire::header_for(0) ^ 0x0B;
            assert!(!wire::header_ok(damaged));
            wire::encode_frame(&mut bytes, damaged, 0x10, 0x0110, 9999);
        }
    }
    let input = dir.path().join("flipped.bin");
    std::fs::write(&input, bytes).unwrap();
    let run = |args: &[&str]| {
        let out = busnoop()
            .arg("sport")
            .arg(&input)
            .args(args)
            .output()
            .unwrap();
        no_panic(&out);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        text(&out.stdout)
    };
    let wide = run(&["--wide", "-f", "csv"]);
    assert_eq!(wide.lines().next().unwrap(), "Millis,VSpd(m/s)", "{wide}");
    assert!(!wide.contains("99.99"), "{wide}");
    let jsonl = run(&["-f", "jsonl"]);
    let flagged: Vec<&str> = jsonl
        .lines()
        .filter(|l| l.contains("non-standard check bits"))
        .collect();
    assert_eq!(flagged.len(), 6);
    for l in flagged {
        assert!(!l.contains("\"parts\""), "{l}");
        assert!(l.contains("\"id\":11") && l.contains("99.99"), "{l}");
    }
    let svg = dir.path().join("p.svg");
    let out = busnoop()
        .args(["plot", "--protocol", "sport"])
        .arg(&input)
        .arg("-o")
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let svg = std::fs::read_to_string(&svg).unwrap();
    assert!(
        svg.contains(">\nVSpd (m/s)\n<") && !svg.contains("VSpd@"),
        "one series"
    );
}

/// L6: `2>>capture.bin` was not refused: busnoop read its own messages back into the capture it
/// decoded. Standard error is compared with the input like standard output; the refusal goes
/// to the terminal when there is one, else nowhere, never into the input.
#[test]
fn l6_standard_error_onto_the_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (input, bytes) = common::capture(dir.path(), "capture");
    // Garbage in front, so that a run writes messages on stderr.
    let mut noisy = common::noise(5000, 3);
    noisy.extend_from_slice(&bytes);
    std::fs::write(&input, &noisy).unwrap();
    for extra in [&[][..], &["-o", "/dev/null"][..]] {
        let err = std::fs::OpenOptions::new()
            .append(true)
            .open(&input)
            .unwrap();
        let out = busnoop()
            .arg("sport")
            .arg(&input)
            .args(extra)
            .stdout(std::process::Stdio::null())
            .stderr(err)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
        assert!(
            std::fs::read(&input).unwrap() == noisy,
            "the capture is untouched"
        );
    }
}

/// L7: one flipped bit in a pcap record header could lose up to 27 % of the telegrams (an
/// impossible length ended the read; a wrong one misaligned every record after it). busnoop
/// now resynchronises at the next plausible record: at most the damaged record is lost, and a
/// row and a warning say how much was skipped.
#[test]
fn l7_a_flipped_bit_in_a_pcap_record_header_loses_one_telegram_at_most() {
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read(fixture("sbus-digimat.pcap")).unwrap();
    let rows = |bytes: &[u8]| {
        let p = dir.path().join("c.pcap");
        std::fs::write(&p, bytes).unwrap();
        let out = busnoop()
            .arg("sbus")
            .arg(&p)
            .args(["-f", "tsv"])
            .output()
            .unwrap();
        no_panic(&out);
        (out.status.code(), text(&out.stdout), text(&out.stderr))
    };
    let (_, all, _) = rows(&good);
    let telegrams = |t: &str| {
        t.lines()
            .filter(|l| {
                ["Request", "Response", "ACK", "NAK"]
                    .iter()
                    .any(|k| l.contains(&format!("\t{k}\t")))
            })
            .count()
    };
    let total = telegrams(&all);
    assert!(total > 40, "{total}");
    // The 20th record's header: its captured length, bit by bit.
    let mut at = 24;
    for _ in 0..20 {
        let incl = u32::from_le_bytes(good[at + 8..at + 12].try_into().unwrap()) as usize;
        at += 16 + incl;
    }
    for bit in 0..32 {
        let mut bad = good.clone();
        bad[at + 8 + bit / 8] ^= 1 << (bit % 8);
        let (code, table, err) = rows(&bad);
        assert_eq!(code, Some(0), "bit {bit}: {err}");
        let kept = telegrams(&table);
        assert!(
            kept + 2 >= total,
            "bit {bit}: {kept} of {total} telegrams\n{err}"
        );
        if kept < total {
            assert!(
                table.contains("of the capture skipped"),
                "bit {bit}:\n{table}"
            );
            assert!(err.contains("damaged capture"), "bit {bit}: {err}");
        }
    }
}

/// L8: "empty input: FILE holds no bytes" was printed for files that do hold bytes (an EdgeTX
/// log whose lines carry none, a recording without data records). The message names what
/// the file is and what it lacks.
#[test]
fn l8_an_input_without_wire_bytes_is_not_called_empty_of_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("e.log");
    std::fs::write(&log, "2014-07-11,22:41:01.340:\n2014-07-11,22:41:01.350:\n").unwrap();
    let rec = dir.path().join("r.pcap");
    let out = busnoop()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .args(["-o", "/dev/null", "--record"])
        .arg(&rec)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    // The header and the start record only.
    let bytes = std::fs::read(&rec).unwrap();
    let start_len = u32::from_le_bytes(bytes[32..36].try_into().unwrap()) as usize;
    std::fs::write(&rec, &bytes[..24 + 16 + start_len]).unwrap();
    for (file, want) in [
        (&log, "is an EdgeTX log whose lines carry no bytes"),
        (&rec, "is a busnoop recording without data records"),
    ] {
        for cmd in ["sport", "detect"] {
            let out = busnoop().arg(cmd).arg(file).output().unwrap();
            let err = text(&out.stderr);
            assert_eq!(out.status.code(), Some(10), "{cmd}: {err}");
            assert!(
                err.contains(want) && !err.contains("holds no bytes"),
                "{cmd}: {err}"
            );
        }
    }
    // A file of no bytes at all is still said so.
    let empty = dir.path().join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let out = busnoop().arg("sport").arg(&empty).output().unwrap();
    assert!(text(&out.stderr).contains("holds no bytes"));
}

/// L10: filters that contradict each other gave exit 0 and an empty table without a word, and
/// an empty filter value meant "everything". Contradictions the options alone show are refused;
/// an empty value is refused; a run whose filters hid every row says so.
#[test]
fn l10_contradicting_or_empty_filters_are_said_so() {
    let sample = fixture("sport-sample.bin");
    let run = |args: &[&str]| {
        let out = busnoop()
            .arg("sport")
            .arg(&sample)
            .args(args)
            .args(["-f", "tsv"])
            .output()
            .unwrap();
        no_panic(&out);
        (out.status.code(), text(&out.stdout), text(&out.stderr))
    };
    for (args, want) in [
        (
            &["--id", "5", "--not-id", "5"][..],
            "--not-id leaves no ID of --id",
        ),
        (
            &["--id", "3-5", "--not-id", "0-9"][..],
            "--not-id leaves no ID of --id",
        ),
        (
            &["--type", "Data", "--not-type", "Data"][..],
            "--not-type leaves no type of --type",
        ),
        (&["--id", ""][..], "--id \"\": an empty value"),
        (&["--type", " , "][..], "--type \" , \": an empty value"),
        (&["--sensor", ""][..], "--sensor \"\": an empty value"),
    ] {
        let (code, _, err) = run(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
    // Allowed on their own, but together nothing passes: said at the end.
    let (code, out, err) = run(&["--type", "Null", "--errors"]);
    assert_eq!(code, Some(0));
    assert_eq!(out.lines().count(), 1);
    assert!(err.contains("the filters hid all 30 rows"), "{err}");
    // A filter that keeps something is quiet.
    let (_, _, err) = run(&["--id", "5", "--not-id", "6"]);
    assert!(!err.contains("hid all"), "{err}");
}

/// L11: SAB command names could be a column name (`Millis`: two Millis columns in the wide
/// table), a code (`0x20` naming command 0x10, next to the column `0x20` of command 0x20), a
/// request column (`x.req`) or one name for two commands. They are refused.
#[test]
fn l11_sab_command_names_cannot_clash_with_columns_or_codes() {
    let session = fixture("sab2-session.bin");
    for args in [
        &["--command", "Millis=0x10"][..],
        &["--command", "time=0x10"][..],
        &["--command", "0x20=0x10"][..],
        &["--command", "32=0x10"][..],
        &["--command", "distance.req=0x10"][..],
        &["--command", "dist@5=0x10"][..],
        &["--command", "a,b=0x10"][..],
        &["--command", "speed=2", "--command", "speed=0x10"][..],
    ] {
        let out = busnoop()
            .arg("sab2")
            .arg(&session)
            .args(args)
            .args(["--wide", "-f", "csv"])
            .output()
            .unwrap();
        no_panic(&out);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    // The same name for one command twice is no clash; a fine name is fine.
    let out = busnoop()
        .arg("sab2")
        .arg(&session)
        .args([
            "--command",
            "distance=0x10",
            "--command",
            "distance=16",
            "--wide",
            "-f",
            "csv",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    // From the project file: exit 12, naming the file.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("busnoop.toml"),
        "[sab2.commands]\nMillis = 0x10\n",
    )
    .unwrap();
    let out = busnoop()
        .current_dir(dir.path())
        .arg("sab2")
        .arg(&session)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(12), "{}", text(&out.stderr));
}

/// Runs busnoop with its standard output closed (`>&-`).
fn with_stdout_closed(args: &[&str]) -> Output {
    use std::os::unix::process::CommandExt;
    let mut cmd = busnoop();
    cmd.args(args).stdout(std::process::Stdio::null());
    // SAFETY: only close() in the child before exec.
    unsafe {
        cmd.pre_exec(|| {
            libc::close(1);
            Ok(())
        });
    }
    cmd.output().unwrap()
}

/// L12: with standard output closed (`>&-`) the table and `--record -` were dropped with exit 0
/// (Rust puts /dev/null there). busnoop refuses before reading, exit 8; a `>/dev/null` is still
/// fine.
#[test]
fn l12_a_closed_standard_output_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sample = fixture("sport-sample.bin");
    let sample = sample.to_str().unwrap();
    let table = dir.path().join("t.tsv");
    for args in [
        vec!["sport", sample],
        vec![
            "sport",
            sample,
            "-o",
            table.to_str().unwrap(),
            "--record",
            "-",
        ],
    ] {
        let out = with_stdout_closed(&args);
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(8), "{args:?}: {err}");
        assert!(err.contains("standard output is closed"), "{err}");
    }
    // Not needed: fine.
    let out = with_stdout_closed(&["sport", sample, "-o", table.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let out = busnoop()
        .args(["sport", sample])
        .stdout(std::process::Stdio::null())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    // /dev/null opened for reading and writing, as Python's `subprocess.DEVNULL`, systemd's
    // `StandardOutput=null` and nohup-like wrappers give it: an open standard output, not a
    // closed one (busnoop took it for `>&-` by its open mode and refused with exit 8).
    let null = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open("/dev/null")
        .unwrap();
    let out = busnoop()
        .args(["sport", sample])
        .stdout(null)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}
