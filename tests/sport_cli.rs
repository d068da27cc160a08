//! The `busnoop sport` command line: formats, output files, options, and bad input.

mod common;

use std::io::{BufRead, BufReader, Write};
use std::process::Stdio;

use assert_cmd::Command;
use busnoop::fmt::parse_hex;
use busnoop::sport::wire;
use common::{fixture, read_tsv};
use predicates::prelude::*;

fn busnoop() -> Command {
    let mut c = Command::cargo_bin("busnoop").unwrap();
    c.env_remove("NO_COLOR").env_remove("RUST_LOG");
    c
}

fn sample() -> std::path::PathBuf {
    fixture("sport-sample.bin")
}

/// All S.Port vectors with an invalid CRC, as one capture.
fn bad_crc_capture(dir: &tempfile::TempDir) -> std::path::PathBuf {
    let mut bytes = Vec::new();
    for v in read_tsv("sport-vectors-crc-invalid.tsv") {
        bytes.extend(parse_hex(&v["hex_bytes_on_wire"]).unwrap());
    }
    bytes.extend([0x7E, 0x22, 0x10, 0x00]); // a truncated frame at the end
    let path = dir.path().join("bad.bin");
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn tsv_is_the_default_when_not_a_terminal() {
    let out = busnoop().arg("sport").arg(sample()).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\t"));
    assert_eq!(text.lines().count(), 31);
    assert!(!text.contains('\x1b'));
}

#[test]
fn csv_output_parses_with_the_same_columns() {
    let out = busnoop()
        .args(["sport", "-f", "csv"])
        .arg(sample())
        .output()
        .unwrap();
    assert!(out.status.success());
    let mut r = csv::Reader::from_reader(out.stdout.as_slice());
    let headers: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        &headers[..8],
        [
            "Counter", "Millis", "ID", "Device", "Type", "Sensor #", "Sensor", "Data"
        ]
    );
    let recs: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(recs.len(), 30);
    let alt = recs.iter().find(|r| &r[6] == "Alt").unwrap();
    assert_eq!(
        (&alt[0], &alt[1], &alt[5], &alt[7], &alt[8], &alt[9]),
        ("23", "264", "0x0100", "65.43", "65.43", "m")
    );
}

#[test]
fn jsonl_output_is_one_object_per_row() {
    let out = busnoop()
        .args(["sport", "-f", "jsonl", "--raw"])
        .arg(sample())
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let objs: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(objs.len(), 30);
    assert_eq!(objs[0]["counter"], 1);
    assert_eq!(objs[0]["id"], 26);
    assert_eq!(objs[0]["raw"], "7E BA");
    let alt = objs.iter().find(|o| o["sensor"] == "Alt").unwrap();
    assert_eq!(alt["millis"], 264);
    assert_eq!(alt["sensor_no"], "0x0100");
    assert_eq!(alt["data"], "65.43");
    assert_eq!(alt["unit"], "m");
}

#[test]
fn pretty_output_aligns_and_colours_on_request() {
    let plain = busnoop()
        .args(["sport", "-f", "pretty"])
        .arg(sample())
        .output()
        .unwrap();
    let text = String::from_utf8(plain.stdout).unwrap();
    assert!(
        !text.contains('\x1b'),
        "auto colour is off when not on a terminal"
    );
    let header = text.lines().next().unwrap();
    let data_col = header.find("Data").unwrap();
    let alt = text.lines().find(|l| l.contains(" Alt ")).unwrap();
    assert_eq!(
        alt.find("65.43"),
        Some(data_col),
        "Data column aligned:\n{header}\n{alt}"
    );

    let colored = busnoop()
        .args(["sport", "-f", "pretty", "--color", "always"])
        .arg(sample())
        .env("NO_COLOR", "1")
        .output()
        .unwrap();
    let text = String::from_utf8(colored.stdout).unwrap();
    assert!(text.contains("\x1b[2m"), "Null rows are dimmed");
    let never = busnoop()
        .args(["sport", "-f", "pretty", "--color", "never"])
        .arg(sample())
        .output()
        .unwrap();
    assert!(!never.stdout.contains(&0x1b));
}

#[test]
fn errors_are_red_in_pretty_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = busnoop()
        .args(["sport", "-f", "pretty", "--color", "always"])
        .arg(bad_crc_capture(&dir))
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let bad = text.lines().find(|l| l.contains("BadCRC")).unwrap();
    assert!(bad.starts_with("\x1b[31m"), "{bad:?}");
}

#[test]
fn output_file_format_comes_from_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    let csv_path = dir.path().join("out.csv");
    busnoop()
        .arg("sport")
        .arg(sample())
        .arg("-o")
        .arg(&csv_path)
        .assert()
        .success()
        .stdout("");
    let text = std::fs::read_to_string(&csv_path).unwrap();
    assert!(
        text.starts_with("Counter,Millis,ID,Device,Type,Sensor #,Sensor,Data,Value,Unit,Note\r\n")
    );
    assert!(text.ends_with("\r\n"));

    let jsonl = dir.path().join("out.jsonl");
    busnoop()
        .arg("sport")
        .arg(sample())
        .arg("-o")
        .arg(&jsonl)
        .assert()
        .success();
    assert!(
        std::fs::read_to_string(&jsonl)
            .unwrap()
            .starts_with("{\"counter\":1,")
    );

    // --format wins over the extension.
    let forced = dir.path().join("out.txt");
    busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(sample())
        .arg("-o")
        .arg(&forced)
        .assert()
        .success();
    assert!(
        std::fs::read_to_string(&forced)
            .unwrap()
            .starts_with("Counter\tMillis")
    );
}

#[test]
fn raw_adds_the_wire_bytes() {
    let out = busnoop()
        .args(["sport", "--raw"])
        .arg(sample())
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().ends_with("\tUnit\tNote\tRaw"));
    let alt = text.lines().find(|l| l.contains("\tAlt\t")).unwrap();
    let mut w = Vec::new();
    wire::encode_frame(&mut w, 0x00, 0x10, 0x0100, 6543);
    assert!(
        alt.ends_with(&format!("\t{}", busnoop::fmt::hex(&w))),
        "{alt}"
    );
}

#[test]
fn stats_go_to_stderr() {
    busnoop()
        .args(["sport", "--stats"])
        .arg(sample())
        .assert()
        .success()
        .stderr(predicate::str::contains("S.Port statistics (30 rows)"))
        .stderr(
            predicate::str::is_match(
                r"(?m)^\s+0\s+Vario\s+10\s+10\s+8\s+2\s+0\s+0\s+0\s+36\.0\s+36\.0$",
            )
            .unwrap(),
        )
        .stderr(predicate::str::is_match(r"(?m)^\s+26\s+Temp\s+1\s+0\s").unwrap())
        .stderr(predicate::str::is_match(r"(?m)^all\s+30\s+20\s").unwrap());
}

#[test]
fn problems_give_one_line_without_stats() {
    let dir = tempfile::tempdir().unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(bad_crc_capture(&dir))
        .output()
        .unwrap();
    // Not one valid frame: the summary line, then what that means, exit 10.
    assert_eq!(out.status.code(), Some(10));
    let err = String::from_utf8(out.stderr).unwrap();
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(
        lines[0],
        "busnoop: S.Port: 14 CRC errors, 1 truncated frame in 0 valid frames"
    );
    assert!(
        lines[1].starts_with("busnoop: no valid S.Port frame in ")
            && lines[1].contains(
                "though 14 frames with a bad check and 1 truncated frame look like S.Port"
            ),
        "{err}"
    );
    assert_eq!(lines.len(), 2, "{err}");
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.contains("\tBadCRC\t")).count(),
        14
    );
    assert_eq!(
        text.lines().filter(|l| l.contains("\tTruncated\t")).count(),
        1
    );
}

#[test]
fn clean_capture_prints_nothing_on_stderr() {
    busnoop()
        .arg("sport")
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .assert()
        .success()
        .stderr("");
}

#[test]
fn standard_input_works() {
    let bytes = std::fs::read(sample()).unwrap();
    let out = busnoop()
        .args(["sport", "-"])
        .write_stdin(bytes)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8(out.stdout).unwrap().lines().count(), 31);
    // The EdgeTX log is recognised by content on standard input too.
    let log = std::fs::read(fixture("edgetx-MODELE24-2014-07-11-sport.log")).unwrap();
    let out = busnoop()
        .args(["sport", "-"])
        .write_stdin(log)
        .output()
        .unwrap();
    assert_eq!(String::from_utf8(out.stdout).unwrap().lines().count(), 593);
}

#[test]
fn time_abs_prints_the_log_clock() {
    let out = busnoop()
        .args(["sport", "--time", "abs"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().ends_with("\tTime"));
    assert!(lines.next().unwrap().ends_with("\t2014-07-11T22:41:01.340"));
    assert!(
        text.lines()
            .last()
            .unwrap()
            .ends_with("\t2014-07-11T22:41:08.430")
    );
}

#[test]
fn missing_file_is_a_clear_error() {
    busnoop()
        .args(["sport", "/nonexistent/capture.bin"])
        .assert()
        .code(3)
        .stdout("")
        .stderr("busnoop: /nonexistent/capture.bin: no such file or device\n");
}

#[test]
fn a_directory_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    busnoop()
        .arg("sport")
        .arg(dir.path())
        .assert()
        .code(3)
        .stderr(predicate::str::contains("is a directory"));
}

#[test]
fn missing_output_directory_is_a_clear_error_and_creates_nothing() {
    busnoop()
        .arg("sport")
        .arg(sample())
        .args(["-o", "/nonexistent/dir/out.csv"])
        .assert()
        .code(8)
        .stderr(predicate::str::starts_with(
            "busnoop: cannot create /nonexistent/dir/out.csv: ",
        ));
}

#[test]
fn empty_file_gives_just_the_header() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    busnoop()
        .arg("sport")
        .arg(&empty)
        .assert()
        .code(10)
        .stdout("Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote\n")
        .stderr(format!(
            "busnoop: empty input: {} holds no bytes\n",
            empty.display()
        ));
}

#[test]
fn usage_errors_exit_2() {
    busnoop().args(["sport"]).assert().code(2);
    busnoop()
        .args(["sport", "x", "--format", "xml"])
        .assert()
        .code(2);
    busnoop().args(["frobnicate"]).assert().code(2);
}

#[test]
fn closed_stdout_exits_quietly() {
    // `busnoop sport big.bin | head -1`: enough rows to fill the pipe, the reader goes away.
    let dir = tempfile::tempdir().unwrap();
    let big = common::big_sport(dir.path(), 200_000, 0x0100);
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .arg("sport")
        .arg(&big)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("Counter\t"));
    // stdout is dropped here: the pipe's read end is closed.
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(141));
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
}

#[test]
fn a_pipe_is_decoded_as_it_arrives() {
    // Rows appear before the writer has finished: the first frame's row is read back while the
    // writer still holds the pipe open.
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .args(["sport", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut reader = BufReader::new(child.stdout.take().unwrap());
    let mut frame = Vec::new();
    wire::encode_frame(&mut frame, 0x00, 0x10, 0x0100, 6543);
    stdin.write_all(&frame).unwrap();
    stdin.flush().unwrap();
    let mut line = String::new();
    reader.read_line(&mut line).unwrap();
    assert!(line.starts_with("Counter"));
    line.clear();
    reader.read_line(&mut line).unwrap();
    assert!(line.contains("\tAlt\t65.43\t"), "{line}");
    drop(stdin);
    assert!(child.wait().unwrap().success());
}

#[test]
fn ctrl_c_flushes_every_row_and_prints_stats() {
    // busnoop reads a pipe that stays open; SIGINT stops it cleanly with exit code 130.
    let dir = tempfile::tempdir().unwrap();
    let csv_path = dir.path().join("live.csv");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .args(["sport", "-", "--stats", "-o"])
        .arg(&csv_path)
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut bytes = Vec::new();
    for i in 0..50u32 {
        wire::encode_frame(&mut bytes, wire::header_for((i % 3) as u8), 0x10, 0x0100, i);
    }
    stdin.write_all(&bytes).unwrap();
    stdin.flush().unwrap();
    // Wait until the rows are in the file (they are flushed per chunk), then interrupt.
    let deadline = std::time::Instant::now() + common::PATIENCE;
    while std::fs::read_to_string(&csv_path)
        .unwrap_or_default()
        .lines()
        .count()
        < 51
    {
        assert!(std::time::Instant::now() < deadline, "rows did not arrive");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let out = child.wait_with_output().unwrap();
    drop(stdin);
    assert_eq!(out.status.code(), Some(130));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("S.Port statistics (50 rows)"), "{err}");
    assert!(err.contains("interrupted after 50 rows"), "{err}");
    let text = std::fs::read_to_string(&csv_path).unwrap();
    assert_eq!(text.lines().count(), 51);
    assert!(text.ends_with("\r\n"), "the file ends with a whole row");
}
