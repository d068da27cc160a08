//! `busnoop sab2` end to end: the demo sessions in `fixtures/`, generated captures, options,
//! output formats and failures.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use busnoop::sab::frame::Framing;
use busnoop::sab::header::Flags;
use busnoop::sab::sample;
use predicates::prelude::*;

fn busnoop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_busnoop"))
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// A TSV table: the header and the rows, each a map from column name to value.
struct Table {
    columns: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    fn parse(stdout: &[u8]) -> Table {
        let text = String::from_utf8(stdout.to_vec()).unwrap();
        let mut lines = text.lines();
        let columns = lines
            .next()
            .unwrap()
            .split('\t')
            .map(str::to_owned)
            .collect::<Vec<_>>();
        let rows = lines
            .map(|l| l.split('\t').map(str::to_owned).collect::<Vec<_>>())
            .collect::<Vec<_>>();
        for r in &rows {
            assert_eq!(r.len(), columns.len(), "{r:?}");
        }
        Table { columns, rows }
    }

    fn get(&self, row: usize, column: &str) -> &str {
        let i = self.columns.iter().position(|c| c == column).unwrap();
        &self.rows[row][i]
    }

    fn column(&self, column: &str) -> Vec<&str> {
        (0..self.rows.len()).map(|r| self.get(r, column)).collect()
    }
}

fn run_tsv(args: &[&str]) -> (Table, String) {
    let out = busnoop().args(args).args(["-f", "tsv"]).assert().success();
    let o = out.get_output();
    (
        Table::parse(&o.stdout),
        String::from_utf8(o.stderr.clone()).unwrap(),
    )
}

#[test]
fn demo_session_sab2() {
    let path = fixture("sab2-session.bin");
    let (t, stderr) = run_tsv(&[
        "sab2",
        path.to_str().unwrap(),
        "--device",
        "drive=1",
        "--device",
        "sonar=5",
        "--device",
        "imu=0x12",
        "--command",
        "speed=2",
        "--command",
        "distance=0x10",
        "--command",
        "heading=0x34",
    ]);
    assert_eq!(
        t.columns,
        [
            "Counter", "Millis", "ID", "Device", "Type", "Sensor #", "Sensor", "Data", "Value",
            "Unit", "Addr", "Resp ms", "Framing", "Note"
        ]
    );
    assert_eq!(t.rows.len(), 24);
    assert!(t.get(0, "Note").starts_with(
        "framing hdlc: SAB2 framing (0x7E flags, byte stuffing, CRC-16/MODBUS), detected"
    ));
    assert_eq!(
        t.rows[3],
        [
            "4",
            "1",
            "5",
            "sonar",
            "ACK",
            "0x10",
            "distance",
            "23 01 (291)",
            "291",
            "",
            "0x05",
            "1.215",
            "hdlc",
            ""
        ]
    );
    assert_eq!(t.get(7, "Type"), "NACK");
    assert_eq!(
        t.get(7, "Note"),
        "NACK NO_ACTION (no action registered for the command)"
    );
    assert_eq!(t.get(11, "Type"), "Timeout");
    assert_eq!(t.get(11, "ID"), "7");
    assert_eq!(t.get(16, "Type"), "BadCRC");
    assert_eq!(t.get(16, "Device"), "imu");
    assert!(t.column("Framing").iter().all(|f| *f == "hdlc"));
    assert!(
        t.column("Millis")
            .windows(2)
            .all(|w| { w[0].parse::<u64>().unwrap() <= w[1].parse::<u64>().unwrap() })
    );
    assert_eq!(
        stderr.trim_end(),
        "busnoop: SAB: 1 CRC error, 3 timeouts, 3 NACKs, 1 runt in 19 valid frames (SAB2)"
    );
}

#[test]
fn demo_session_sab1_with_alias_and_stats() {
    let path = fixture("sab1-session.bin");
    let (t, stderr) = run_tsv(&["sab", path.to_str().unwrap(), "--stats"]);
    assert_eq!(t.rows.len(), 24);
    assert!(t.get(0, "Note").starts_with("framing sync: SAB v1 framing"));
    assert_eq!(t.get(14, "Type"), "Garbage");
    assert_eq!(t.get(14, "Data"), "00 54 20");
    // The frames right after the false `54 20` were not swallowed.
    assert_eq!(t.get(15, "Type"), "Request");
    assert_eq!(t.get(16, "Type"), "BadCRC");
    assert!(stderr.contains("SAB statistics (24 rows)"), "{stderr}");
    assert!(stderr.contains("framing sync: SAB v1 framing (0x54 SYNC, LENGTH, CRC-8/MAXIM-DOW), detected (3 valid frames against 0 SAB2)"), "{stderr}");
    assert!(
        stderr.contains("NO_ACTION 1, WRONG_PAYLOAD_LENGTH 1"),
        "{stderr}"
    );
    assert!(stderr.contains("false 0x54 rescanned 1"), "{stderr}");
    assert!(stderr.contains("pairing: timeouts 3"), "{stderr}");
}

#[test]
fn generated_capture_every_framing_option() {
    let dir = tempfile::tempdir().unwrap();
    for framing in [Framing::Sync, Framing::Hdlc] {
        let mut w = Vec::new();
        for i in 0..5u8 {
            sample::frame(&mut w, framing, Flags::Request, 9, 0x20 + i, &[i]);
            sample::frame(&mut w, framing, Flags::Ack, 9, 0x20 + i, &[i, i]);
        }
        let path = dir.path().join(format!("{}.bin", framing.name()));
        std::fs::write(&path, &w).unwrap();
        let p = path.to_str().unwrap();
        for choice in ["auto", framing.name()] {
            let (t, stderr) = run_tsv(&["sab2", p, "--framing", choice]);
            assert_eq!(t.rows.len(), 10, "{choice}");
            assert!(t.column("Framing").iter().all(|f| *f == framing.name()));
            assert!(
                t.column("Type")
                    .iter()
                    .all(|k| *k == "Request" || *k == "ACK")
            );
            assert!(stderr.is_empty(), "{stderr}");
            let how = if choice == "auto" {
                "detected"
            } else {
                "forced by --framing"
            };
            assert!(t.get(0, "Note").contains(how), "{}", t.get(0, "Note"));
        }
        // The wrong framing finds nothing and says so.
        let wrong = framing.other().name();
        let out = busnoop()
            .args(["sab2", p, "--framing", wrong, "-f", "tsv"])
            .assert()
            .code(10);
        let o = out.get_output();
        let (t, stderr) = (
            Table::parse(&o.stdout),
            String::from_utf8(o.stderr.clone()).unwrap(),
        );
        assert!(
            stderr.ends_with(&format!(
                "with these options, but 100.0% of its bytes are in valid {} frames with the \
                 defaults; try: busnoop sab2 {p}\n",
                if framing == Framing::Sync {
                    "SAB v1 (sync framing)"
                } else {
                    "SAB2 (HDLC framing)"
                }
            )),
            "{stderr}"
        );
        assert!(
            t.column("Type")
                .iter()
                .all(|k| !matches!(*k, "Request" | "ACK"))
        );
        assert!(
            stderr.starts_with("busnoop: SAB: no valid frame"),
            "{stderr}"
        );
    }
    // Aliases of the framing values.
    let p = dir.path().join("sync.bin");
    let (t, _) = run_tsv(&["sab2", p.to_str().unwrap(), "--framing", "sab1"]);
    assert_eq!(t.get(0, "Framing"), "sync");
}

#[test]
fn baud_and_timeout_change_the_reconstructed_timing() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = Vec::new();
    sample::frame(&mut w, Framing::Hdlc, Flags::Request, 3, 1, &[]);
    sample::frame(&mut w, Framing::Hdlc, Flags::Ack, 3, 1, &[0; 8]);
    let path = dir.path().join("slow.bin");
    std::fs::write(&path, &w).unwrap();
    let p = path.to_str().unwrap();
    // 20 bytes: 1.736 ms at 115200 baud.
    let (t, _) = run_tsv(&["sab2", p]);
    assert_eq!(t.column("Type"), ["Request", "ACK"]);
    assert_eq!(t.get(1, "Resp ms"), "1.736");
    // 20.833 ms at 9600 baud: late for the 10 ms timeout …
    let (t, stderr) = run_tsv(&["sab2", p, "--baud", "9600"]);
    // The ACK starts at 6.25 ms, before the deadline, and ends after it: its Timeout row
    // (at 10 ms) follows it.
    assert_eq!(t.column("Type"), ["Request", "ACK", "Timeout"]);
    assert_eq!(t.column("Millis"), ["0", "6", "10"]);
    assert_eq!(t.get(1, "Resp ms"), "20.833");
    assert!(stderr.contains("1 timeout, 1 late response"), "{stderr}");
    // … but not for 25 ms.
    let (t, _) = run_tsv(&["sab2", p, "--baud", "9600", "--timeout-ms", "25"]);
    assert_eq!(t.column("Type"), ["Request", "ACK"]);
}

#[test]
fn standard_input_and_other_formats() {
    let bytes = std::fs::read(fixture("sab2-session.bin")).unwrap();
    let out = busnoop()
        .args(["sab2", "-", "-f", "jsonl"])
        .write_stdin(bytes.clone())
        .assert()
        .success();
    let text = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    let first = text.lines().next().unwrap();
    assert!(first.starts_with(r#"{"counter":1,"millis":0,"id":1,"device":null,"type":"Request","sensor_no":"0x02","sensor":null,"data":"55 (85)","value":85,"unit":null,"addr":"0x01","resp_ms":null,"framing":"hdlc","note":"framing hdlc: "#), "{first}");
    assert!(first.ends_with(r#","parts":{"0x02.req":85}}"#), "{first}");
    assert_eq!(text.lines().count(), 24);

    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("out.csv");
    busnoop()
        .args(["sab2", "-", "--raw", "-o"])
        .arg(&csv)
        .write_stdin(bytes)
        .assert()
        .success();
    let mut r = csv::Reader::from_path(&csv).unwrap();
    assert_eq!(&r.headers().unwrap()[14], "Raw");
    let rec = r.records().next().unwrap().unwrap();
    assert_eq!(&rec[14], "7E 01 02 55 E1 5F 7E");
}

#[test]
fn unusable_inputs_and_options_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let pcap = dir.path().join("x.pcap");
    let mut header = vec![0xD4, 0xC3, 0xB2, 0xA1, 2, 0, 4, 0];
    header.extend_from_slice(&[0; 16]);
    std::fs::write(&pcap, header).unwrap();
    busnoop()
        .args(["sab2"])
        .arg(&pcap)
        .assert()
        .code(9)
        .stderr(predicate::str::contains("pcap of network traffic"));
    busnoop()
        .args(["sab2"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .assert()
        .code(9)
        .stderr(predicate::str::contains("S.Port log"));
    busnoop().args(["sab2", "nonexistent.bin"]).assert().code(3);
    for bad in [
        &["--device", "motor=64"][..],
        &["--command", "speed"],
        &["--framing", "sab3"],
        &["--timeout-ms", "0"],
    ] {
        busnoop()
            .arg("sab2")
            .arg(fixture("sab2-session.bin"))
            .args(bad)
            .assert()
            .code(2);
    }
}

#[test]
fn timed_recordings_use_the_real_times() {
    use busnoop::{RecordContent, Recorder};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("timed.pcap");
    let frame = |flags, cmd, data: &[u8]| {
        let mut w = Vec::new();
        sample::frame(&mut w, Framing::Hdlc, flags, 5, cmd, data);
        w
    };
    let mut r = Recorder::create(&path, RecordContent::Line { timed: true }).unwrap();
    r.start(None).unwrap();
    r.data(&frame(Flags::Request, 0x10, &[]), Some(1_000))
        .unwrap();
    r.data(&frame(Flags::Ack, 0x10, &[7]), Some(3_500)).unwrap();
    r.data(&frame(Flags::Request, 0x11, &[]), Some(20_000))
        .unwrap();
    r.data(&frame(Flags::Ack, 0x11, &[8]), Some(40_000))
        .unwrap();
    r.data(&frame(Flags::Request, 0x12, &[]), Some(50_000))
        .unwrap();
    r.flush().unwrap();
    drop(r);
    let (t, stderr) = run_tsv(&["sab2", path.to_str().unwrap()]);
    assert_eq!(
        t.column("Type"),
        [
            "Request", "ACK", "Request", "Timeout", "ACK", "Request", "Timeout"
        ]
    );
    assert_eq!(t.column("Millis"), ["1", "3", "20", "30", "40", "50", "50"]);
    assert_eq!(t.column("Resp ms"), ["", "2.500", "", "", "20.000", "", ""]);
    assert_eq!(t.get(3, "Note"), "no response within 10 ms");
    assert_eq!(t.get(4, "Note"), "late: after the master's 10 ms timeout");
    assert!(
        t.get(6, "Note")
            .starts_with("no response before the end of the capture")
    );
    assert!(stderr.contains("2 timeouts, 1 late response"), "{stderr}");
}

/// The Value column of the demo sessions (default rule): the number of a request's payload (a
/// write, or a query's argument) and of an ACK's, unsigned little endian; none for NACKs, bad
/// frames and empty payloads. Both framings give the same values.
#[test]
fn demo_session_values() {
    for file in ["sab1-session.bin", "sab2-session.bin"] {
        let path = fixture(file);
        let (t, _) = run_tsv(&["sab2", path.to_str().unwrap()]);
        let typed: Vec<(&str, &str, &str)> = (0..t.rows.len())
            .map(|r| (t.get(r, "Type"), t.get(r, "Sensor #"), t.get(r, "Value")))
            .filter(|(_, _, v)| !v.is_empty())
            .collect();
        assert_eq!(
            typed,
            [
                ("Request", "0x02", "85"),
                ("ACK", "0x10", "291"),
                ("Request", "0x34", "3735928559"),
                ("ACK", "0x34", "305419896"),
                ("Request", "0x10", "1"),
                ("Request", "0x02", "126"),
                ("ACK", "0x02", "125"),
                ("Request", "0x34", "1"),
                ("Request", "0x34", "1"),
                ("ACK", "0x34", "2"),
                ("Request", "0x03", "10000"),
            ],
            "{file}"
        );
        assert!(t.column("Unit").iter().all(|u| u.is_empty()));
    }
}

/// `--value`: a declared type, scale and unit set Value, Unit and the Data reading; CMD is a
/// --command name or a code, with `.req`/`.ack` for one direction.
#[test]
fn declared_values_on_the_command_line() {
    let path = fixture("sab2-session.bin");
    let (t, stderr) = run_tsv(&[
        "sab2",
        path.to_str().unwrap(),
        "--command",
        "distance=0x10",
        "--value",
        "distance=u16*0.01:m",
        "--value",
        "0x34.ack=i32*0.5:deg",
        "--value",
        "2=i8",
    ]);
    assert_eq!(t.get(3, "Data"), "23 01 (2.91 m)");
    assert_eq!((t.get(3, "Value"), t.get(3, "Unit")), ("2.91", "m"));
    // The request direction of 0x34 keeps the default rule.
    assert_eq!((t.get(4, "Value"), t.get(4, "Unit")), ("3735928559", ""));
    assert_eq!(
        (t.get(5, "Value"), t.get(5, "Unit")),
        ("152709948.0", "deg")
    );
    // 0x7E as i8; the query argument of `distance` is one byte, not a u16.
    assert_eq!(t.get(12, "Value"), "126");
    assert_eq!(t.get(13, "Value"), "125");
    assert_eq!(t.get(8, "Value"), "");
    assert_eq!(
        t.get(8, "Note"),
        "1 payload byte, --value declares u16 (2): no value"
    );
    assert!(stderr.contains("3 timeouts"), "{stderr}");

    for (bad, says) in [
        ("distance", "CMD=TYPE"),
        ("speed=u8", "neither a command code"),
        ("0x10=u64", "unknown type `u64`"),
        ("0x10=u16*1e-2", "plain decimal"),
        ("0x10=u16:", "unit"),
    ] {
        busnoop()
            .arg("sab2")
            .arg(&path)
            .args(["--value", bad])
            .assert()
            .code(2)
            .stderr(predicate::str::contains(says));
    }
}

/// `[sab2.values]` in the project file, with the file's command names; mistakes there are the
/// file's (exit code 12), and other protocols have no such table.
#[test]
fn declared_values_in_the_project_file() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("busnoop.toml");
    std::fs::write(
        &config,
        "[sab2.commands]\ndistance = 0x10\n\n[sab2.values]\ndistance = \"u16*0.01:m\"\n\
         \"0x34\".ack = \"u32\"\n0x34.req = \"i32\"\n",
    )
    .unwrap();
    let path = fixture("sab1-session.bin");
    let (t, _) = run_tsv(&[
        "sab2",
        path.to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
    ]);
    assert_eq!(
        (t.get(3, "Sensor"), t.get(3, "Value"), t.get(3, "Unit")),
        ("distance", "2.91", "m")
    );
    assert_eq!(t.get(4, "Value"), "-559038737");
    assert_eq!(t.get(5, "Value"), "305419896");
    // The command line's declaration wins over the file's.
    let (t, _) = run_tsv(&[
        "sab2",
        path.to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
        "--value",
        "distance=u16:cm",
    ]);
    assert_eq!((t.get(3, "Value"), t.get(3, "Unit")), ("291", "cm"));

    for (text, says) in [
        (
            "[sab2.values]\n0x10 = \"u128\"\n",
            "[sab2.values] `0x10=u128`: unknown type",
        ),
        (
            "[sab2.values]\nspeed = \"u8\"\n",
            "[sab2.values] `speed` is neither",
        ),
        (
            "[sport.values]\n0x10 = \"u8\"\n",
            "[sport] has no key `values`: value declarations are for [sab2]",
        ),
        (
            "[sab2.values]\n0x10 = 5\n",
            "busnoop.toml:2: [sab2.values] 0x10 = 5: expected a text",
        ),
    ] {
        std::fs::write(&config, text).unwrap();
        busnoop()
            .arg("sab2")
            .arg(&path)
            .arg("--config")
            .arg(&config)
            .assert()
            .code(12)
            .stderr(predicate::str::contains(says));
    }
}

/// `--wide` on SAB: one column per command (and `.req` for request payloads), the last value
/// held; the one-byte argument of `distance` does not fit its declared u16, so no column.
#[test]
fn wide_table_of_the_demo_session() {
    for file in ["sab1-session.bin", "sab2-session.bin"] {
        let path = fixture(file);
        let out = busnoop()
            .args(["sab2", path.to_str().unwrap(), "--command", "distance=0x10"])
            .args(["--value", "distance=u16*0.01:m", "--wide", "-f", "csv"])
            .assert()
            .success();
        let mut r = csv::Reader::from_reader(out.get_output().stdout.as_slice());
        let headers: Vec<String> = r.headers().unwrap().iter().map(str::to_owned).collect();
        assert_eq!(
            headers,
            [
                "Millis",
                "0x02.req",
                "distance(m)",
                "0x34.req",
                "0x34",
                "0x02",
                "0x03.req"
            ],
            "{file}"
        );
        let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
        let last = rows.last().unwrap();
        assert_eq!(
            last.iter().skip(1).collect::<Vec<_>>(),
            ["126", "2.91", "1", "2", "125", "10000"],
            "{file}"
        );
        for rec in &rows {
            for cell in rec.iter().filter(|c| !c.is_empty()) {
                cell.parse::<f64>().unwrap();
            }
        }
    }
}

/// `busnoop plot` on SAB: a series per command, the project file's names and types apply.
#[test]
fn plot_of_the_demo_session() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("busnoop.toml"),
        "[sab2.commands]\nheading = 0x34\n\n[sab2.values]\nheading.ack = \"u32*0.001:deg\"\n",
    )
    .unwrap();
    let svg = dir.path().join("sab.svg");
    busnoop()
        .current_dir(dir.path())
        .args(["plot"])
        .arg(fixture("sab2-session.bin"))
        .args(["--sensor", "heading", "-o"])
        .arg(&svg)
        .assert()
        .success();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("heading"), "no label");
    assert!(text.contains("deg"), "no unit");
    // One series line (the legend's sample, right of x = 960, aside) with the two valid
    // answers, a step and a marker each (the corrupted one is a red mark).
    let points_of = |p: &str| -> Vec<String> {
        p.split("points=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .split_whitespace()
            .map(str::to_owned)
            .collect()
    };
    let x = |xy: &str| xy.split(',').next().unwrap().parse::<f64>().unwrap();
    let lines: Vec<Vec<String>> = text
        .split("<polyline")
        .skip(1)
        .filter(|p| p.split('>').next().unwrap().contains("stroke-width=\"2\""))
        .map(points_of)
        .filter(|pts| pts.iter().all(|xy| x(xy) < 960.0))
        .collect();
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0].len(), 3, "a step: {:?}", lines[0]);
    let markers = text
        .split("<circle")
        .skip(1)
        .filter(|c| {
            let cx = c.split("cx=\"").nth(1).unwrap().split('"').next().unwrap();
            cx.parse::<f64>().unwrap() < 960.0
        })
        .count();
    assert_eq!(markers, 2, "a marker at each answer");
    // Without names or types: the codes.
    busnoop()
        .args(["plot"])
        .arg(fixture("sab1-session.bin"))
        .args(["--protocol", "sab2", "--sensor", "0x10", "-o"])
        .arg(dir.path().join("b.svg"))
        .assert()
        .success();
}
