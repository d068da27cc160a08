//! Snapshots of the pretty output of every protocol's fixtures: the columns of each protocol
//! line up (widths from the protocol descriptor, growing for long values). The expected files
//! are in tests/snapshots/; after a deliberate change of the output, rewrite them with
//! `BUSNOOP_BLESS=1 cargo test --test pretty_snapshots` and review the diff.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::fixture;

fn pretty(args: &[&str], source: &Path) -> String {
    let out = Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .args(args)
        .arg(source)
        .args(["-f", "pretty", "--color", "never"])
        .env_remove("NO_COLOR")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn snapshot(name: &str, actual: &str) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/snapshots")
        .join(name);
    if std::env::var_os("BUSNOOP_BLESS").is_some() {
        std::fs::write(&path, actual).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; write it with BUSNOOP_BLESS=1 cargo test --test pretty_snapshots",
            path.display()
        )
    });
    if expected != actual {
        let line = expected
            .lines()
            .zip(actual.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(expected.lines().count().min(actual.lines().count()));
        panic!(
            "{name} differs from line {}:\nexpected: {:?}\nactual:   {:?}\n(BUSNOOP_BLESS=1 rewrites the snapshots)",
            line + 1,
            expected.lines().nth(line),
            actual.lines().nth(line)
        );
    }
}

/// The pretty output against the TSV of the same input: every cell of the left-aligned columns
/// (Device onwards) starts no earlier than the header's column, and never earlier than the same
/// column did in an earlier row (widths only grow): rows are not ragged.
fn assert_aligned(name: &str, args: &[&str], source: &Path, pretty_text: &str) {
    let out = Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .args(args)
        .arg(source)
        .args(["-f", "tsv"])
        .output()
        .unwrap();
    let tsv = String::from_utf8(out.stdout).unwrap();
    let mut lines = pretty_text.lines();
    let header = lines.next().unwrap();
    // Pretty output has no Value column (its Data says the same): leave it out of the TSV.
    let value_at = tsv
        .lines()
        .next()
        .unwrap()
        .split('\t')
        .position(|n| n == "Value");
    let without_value = |row: &str| -> Vec<String> {
        row.split('\t')
            .enumerate()
            .filter(|(i, _)| Some(*i) != value_at)
            .map(|(_, c)| c.to_string())
            .collect()
    };
    let names: Vec<String> = without_value(tsv.lines().next().unwrap());
    // Positions are counted in characters, as the table aligns them (`µs` is two columns and
    // three bytes); `cursor` is a byte offset.
    let column = |line: &str, byte: usize| line[..byte].chars().count();
    let mut start: Vec<usize> = Vec::new();
    let mut cursor = 0;
    for n in &names {
        let at = cursor + header[cursor..].find(n).unwrap();
        start.push(column(header, at));
        cursor = at + n.len();
    }
    let mut rows = 0;
    for (line, row) in lines.zip(tsv.lines().skip(1)) {
        let cells = without_value(row);
        let mut cursor = line
            .char_indices()
            .nth(start[3])
            .map_or(line.len(), |(b, _)| b);
        let mut overflowed = false;
        for (i, cell) in cells.iter().enumerate().skip(3) {
            if cell.is_empty() {
                continue;
            }
            let at = cursor
                + line[cursor..]
                    .find(cell)
                    .unwrap_or_else(|| panic!("{name}: {cell:?} not found in {line:?}"));
            cursor = at + cell.len();
            if overflowed {
                continue;
            }
            let col = column(line, at);
            assert!(
                col >= start[i],
                "{name}: {} starts at {col}, before {} (an earlier row): {line}",
                names[i],
                start[i]
            );
            start[i] = col;
            // A cell longer than the table grows a column for (60 characters) overflows its
            // row only: the cells after it are out of line in that row alone.
            overflowed = cell.chars().count() > 60;
        }
        rows += 1;
    }
    assert!(rows > 0, "{name}");
}

#[test]
fn sport_pretty() {
    let sample = fixture("sport-sample.bin");
    let text = pretty(&["sport"], &sample);
    assert_aligned("sport-sample", &["sport"], &sample, &text);
    snapshot("sport-sample.pretty", &text);
    let log = fixture("edgetx-MODELE24-2014-07-11-sport.log");
    let text = pretty(&["sport"], &log);
    assert_aligned("edgetx", &["sport"], &log, &text);
    snapshot("edgetx-MODELE24-2014-07-11-sport.pretty", &text);
}

#[test]
fn sab_pretty() {
    for name in ["sab1-session", "sab2-session"] {
        let f = fixture(&format!("{name}.bin"));
        let text = pretty(&["sab2"], &f);
        assert_aligned(name, &["sab2"], &f, &text);
        snapshot(&format!("{name}.pretty"), &text);
    }
}

#[test]
fn sbus_pretty() {
    for name in ["sbus-digimat", "sbus_seeds_ether"] {
        let f = fixture(&format!("{name}.pcap"));
        let text = pretty(&["sbus"], &f);
        assert_aligned(name, &["sbus"], &f, &text);
        snapshot(&format!("{name}.pretty"), &text);
    }
    // A serial data-mode session (encoded here: there is no serial S-Bus fixture).
    use busnoop::sbus::telegram::{CrcBasis, encode_data};
    let mut w = Vec::new();
    for i in 0..6u8 {
        encode_data(&mut w, 0, &[10, 6, 1, 0, i * 40], CrcBasis::Escaped);
        encode_data(&mut w, 1, &[0, 0, 1, i, 0, 0, 0, i], CrcBasis::Escaped);
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("sbus-serial.bin");
    std::fs::write(&p, &w).unwrap();
    let text = pretty(&["sbus"], &p);
    assert_aligned("sbus-serial", &["sbus"], &p, &text);
    snapshot("sbus-serial.pretty", &text);
}

#[test]
fn rc_buses_pretty() {
    for (protocol, name) in [("futaba", "futaba-session"), ("ibus", "ibus-sensors")] {
        let f = fixture(&format!("{name}.bin"));
        let text = pretty(&[protocol], &f);
        assert_aligned(name, &[protocol], &f, &text);
        snapshot(&format!("{name}.pretty"), &text);
    }
    // iBUS's Data column is sized for the sensor bus: the channels of an RC frame (69 or 89
    // characters) and a broken RC frame's hex (95) are longer than a column grows, so these
    // rows overflow, each by its own length (not checked for alignment).
    let f = fixture("ibus-rc.bin");
    snapshot("ibus-rc.pretty", &pretty(&["ibus"], &f));
}

#[test]
fn fport_pretty() {
    for name in ["fport-v1-session", "fport2-session"] {
        let f = fixture(&format!("{name}.bin"));
        let text = pretty(&["fport"], &f);
        assert_aligned(name, &["fport"], &f, &text);
        snapshot(&format!("{name}.pretty"), &text);
    }
}

#[test]
fn modbus_pretty() {
    for (name, args) in [
        ("modbus-brainchild", &["modbus", "--no-config"][..]),
        (
            "modbus-wizmodbus-bus",
            &["modbus", "--no-config", "--line", "9600-8N1"][..],
        ),
    ] {
        let f = fixture(&format!("{name}.bin"));
        let text = pretty(args, &f);
        assert_aligned(name, args, &f, &text);
        snapshot(&format!("{name}.pretty"), &text);
    }
}
