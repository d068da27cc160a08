//! `busnoop modbus` on the command line: the JSON Lines contract, the real captures, the
//! generated recording, the register map of the project file, filters, `--wide`, `plot`,
//! `--stats`, `detect`, `--record` and the export read back by tshark.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use busnoop::modbus::wire::push_crc;
use common::{busnoop, fixture, ok, text};
use serde_json::Value;

/// A frame from its bytes without the CRC.
fn f(bytes: &[u8]) -> Vec<u8> {
    let mut v = bytes.to_vec();
    push_crc(&mut v);
    v
}

fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// JSON Lines rows of `busnoop modbus SOURCE ARGS -f jsonl`.
fn jsonl(source: &Path, args: &[&str]) -> Vec<Value> {
    let out = busnoop()
        .arg("modbus")
        .arg(source)
        .args(args)
        .args(["-f", "jsonl", "--no-config"])
        .output()
        .unwrap();
    lines(&ok(&out))
}

/// Rows of JSON Lines text; `parts` becomes an array of `[name, number text]` in the line's
/// order (serde_json's maps sort their keys).
fn lines(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            if v.get("parts").is_some() {
                v["parts"] = Value::Array(
                    parts_in_order(l)
                        .into_iter()
                        .map(|(k, n)| Value::Array(vec![k.into(), n.into()]))
                        .collect(),
                );
            }
            v
        })
        .collect()
}

/// The members of a line's `"parts":{…}` in order: names (no escapes in them here) and
/// numbers as written.
fn parts_in_order(line: &str) -> Vec<(String, String)> {
    let Some(at) = line.find("\"parts\":{") else {
        return Vec::new();
    };
    let body = &line[at + 9..];
    let body = &body[..body.find('}').unwrap()];
    let mut out = Vec::new();
    let mut rest = body;
    while let Some(r) = rest.strip_prefix('"') {
        let end = r.find('"').unwrap();
        let name = r[..end].to_string();
        let r = &r[end + 2..];
        let stop = r.find(',').unwrap_or(r.len());
        out.push((name, r[..stop].to_string()));
        rest = r[stop..].strip_prefix(',').unwrap_or("");
    }
    out
}

fn parts(row: &Value) -> Vec<(String, String)> {
    row["parts"].as_array().map_or(Vec::new(), |a| {
        a.iter()
            .map(|p| {
                (
                    p[0].as_str().unwrap().to_string(),
                    p[1].as_str().unwrap().to_string(),
                )
            })
            .collect()
    })
}

/// The number named `name` of a row.
fn part(row: &Value, name: &str) -> Option<String> {
    parts(row).into_iter().find(|p| p.0 == name).map(|p| p.1)
}

fn types(rows: &[Value]) -> Vec<&str> {
    rows.iter().map(|r| r["type"].as_str().unwrap()).collect()
}

/// The exchanges of the output contract: a read of holding registers, a read of coils, an
/// exception, a broadcast, a stray turnaround byte, a bad CRC, a request without an answer
/// (ended by the next request) and a frame cut by the end.
fn contract_capture() -> Vec<u8> {
    let mut bad = f(&[0x11, 0x03, 0x02, 0x00, 0x01]);
    bad[4] ^= 0x40;
    [
        f(&[0x11, 0x03, 0x00, 0x6B, 0x00, 0x03]),
        vec![0x00],
        f(&[0x11, 0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64]),
        f(&[0x0A, 0x01, 0x00, 0x13, 0x00, 0x0A]),
        f(&[0x0A, 0x01, 0x02, 0xCD, 0x01]),
        f(&[0x0A, 0x03, 0x27, 0x10, 0x00, 0x02]),
        f(&[0x0A, 0x83, 0x02]),
        f(&[0x00, 0x06, 0x00, 0x01, 0x00, 0x03]),
        f(&[0x11, 0x03, 0x00, 0x01, 0x00, 0x01]),
        bad,
        f(&[0x05, 0x04, 0x00, 0x00, 0x00, 0x01]),
        f(&[0x06, 0x04, 0x00, 0x00, 0x00, 0x01]),
        f(&[0x07, 0x04, 0x00, 0x00, 0x00, 0x01])[..5].to_vec(),
    ]
    .concat()
}

#[test]
fn jsonl_output_contract() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "contract.bin", &contract_capture());
    let rows = jsonl(&path, &[]);
    assert_eq!(
        types(&rows),
        [
            "Request",
            "Garbage",
            "Response",
            "Request",
            "Response",
            "Request",
            "Exception",
            "Request",
            "Request",
            "BadCRC",
            "Request",
            "Timeout",
            "Request",
            "Truncated"
        ]
    );
    let r = &rows[0];
    assert_eq!(
        (r["id"].as_u64(), r["sensor_no"].as_str()),
        (Some(17), Some("0x03"))
    );
    assert_eq!(r["sensor"], "Read Holding Registers");
    assert_eq!(
        parts(r),
        [("start".into(), "107".into()), ("count".into(), "3".into())]
    );
    let r = &rows[2];
    assert_eq!(
        parts(r),
        [
            ("R107".to_string(), "555".to_string()),
            ("R108".into(), "0".into()),
            ("R109".into(), "100".into())
        ]
    );
    assert_eq!(r["value"], 555);
    let r = &rows[4];
    assert_eq!(r["sensor_no"], "0x01");
    let coils = parts(r);
    assert_eq!(coils.len(), 10);
    assert_eq!(coils[0], ("C19".into(), "1".into()));
    assert_eq!(coils[9], ("C28".into(), "0".into()));
    let r = &rows[6];
    assert_eq!(
        (r["id"].as_u64(), r["sensor_no"].as_str()),
        (Some(10), Some("0x03"))
    );
    assert_eq!(parts(r), [("code".into(), "2".into())]);
    assert_eq!(r["data"], "Illegal Data Address (2)");
    let r = &rows[7];
    assert_eq!(r["id"], 0);
    assert_eq!(r["note"], "broadcast");
    for (i, kind) in [(1, "Garbage"), (9, "BadCRC"), (13, "Truncated")] {
        assert_eq!(rows[i]["type"], kind);
        assert!(rows[i].get("parts").is_none(), "{}", rows[i]);
    }
    assert_eq!(rows[9]["id"], 17, "a bad frame still names its slave");
    let t = &rows[11];
    assert_eq!(
        (t["id"].as_u64(), t["sensor_no"].as_str()),
        (Some(5), Some("0x04"))
    );
    assert_eq!(t["note"], "no answer before the next request");
    // every row has the shared keys
    for r in &rows {
        for k in [
            "counter",
            "millis",
            "id",
            "device",
            "type",
            "sensor_no",
            "sensor",
            "data",
        ] {
            assert!(r.get(k).is_some(), "{k} in {r}");
        }
    }
    // Millis: 11 bits a byte at 19200 (8E1); --line changes it
    assert_eq!(rows[2]["millis"], 5, "9 bytes at 572.9 µs");
    let at_9600 = jsonl(&path, &["--line", "9600-8N1"]);
    assert_eq!(at_9600[2]["millis"], 9);
}

#[test]
fn the_sigrok_captures() {
    // brainchild: 19200 8E1, the default line
    let rows = jsonl(&fixture("modbus-brainchild.bin"), &[]);
    assert_eq!(rows.len(), 30);
    let fcs: Vec<&str> = rows
        .iter()
        .map(|r| r["sensor_no"].as_str().unwrap())
        .collect();
    assert_eq!(
        fcs[..16],
        [
            "0x01", "0x01", "0x02", "0x02", "0x03", "0x03", "0x04", "0x04", "0x05", "0x05", "0x06",
            "0x06", "0x0F", "0x0F", "0x10", "0x10"
        ]
    );
    assert_eq!(parts(&rows[5]), [("R99".into(), "513".into())]);
    assert_eq!(parts(&rows[7]), [("R120".into(), "19200".into())]);
    assert_eq!(
        types(&rows).iter().filter(|t| **t == "Response").count(),
        15
    );
    // wizmodbus: the bus channel at 9600 8N1, a turnaround byte after every frame
    let rows = jsonl(
        &fixture("modbus-wizmodbus-bus.bin"),
        &["--line", "9600-8N1"],
    );
    let frames: Vec<&Value> = rows.iter().filter(|r| r["type"] != "Garbage").collect();
    assert_eq!(frames.len(), 88);
    assert!(frames.iter().all(|r| r["id"] == 1));
    assert_eq!(
        rows.len() - frames.len(),
        88,
        "one garbage row per turnaround byte"
    );
    assert!(
        rows.iter()
            .filter(|r| r["type"] == "Garbage")
            .all(|r| r["data"] == "00" || r["data"] == "FE")
    );
    // the request that also checks as a response with the 00 after it
    let trap = rows
        .iter()
        .position(|r| r["data"] == "start=1024 count=2")
        .unwrap();
    assert_eq!(rows[trap]["type"], "Request");
    assert_eq!(
        parts(&rows[trap + 2]),
        [
            ("R1024".into(), "24148".into()),
            ("R1025".into(), "18221".into())
        ]
    );
    // flowmeter: slave 247
    let rows = jsonl(
        &fixture("modbus-flowmeter-graph-tool.bin"),
        &["--baud", "9600"],
    );
    assert_eq!(rows.len(), 18);
    assert!(rows.iter().all(|r| r["id"] == 247));
}

/// The generator's recording (tools/modbus-gen.py): the rows it says the session shows.
#[test]
fn the_generated_recording_and_its_statistics() {
    let expect: Vec<(String, String, String)> =
        std::fs::read_to_string(fixture("modbus-gen.expect"))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| {
                let w: Vec<&str> = l.split(' ').collect();
                (w[0].into(), w[1].into(), w[2].into())
            })
            .collect();
    let rows = jsonl(&fixture("modbus-gen.pcap"), &[]);
    let got: Vec<(String, String, String)> = rows
        .iter()
        .map(|r| {
            let s = |v: &Value| match v {
                Value::Null => "-".to_string(),
                Value::String(s) if s.is_empty() => "-".to_string(),
                Value::String(s) => s.clone(),
                v => v.to_string(),
            };
            (s(&r["type"]), s(&r["id"]), s(&r["sensor_no"]))
        })
        .collect();
    assert_eq!(got, expect);
    let long = rows.iter().find(|r| parts(r).len() == 125).unwrap();
    assert_eq!(part(long, "R124").as_deref(), Some("868"));
    assert!(
        rows.iter()
            .any(|r| r["resp_ms"].as_f64().is_some_and(|ms| ms > 1000.0))
    );
    let out = busnoop()
        .args(["modbus", "--no-config", "--stats", "-o", "/dev/null"])
        .arg(fixture("modbus-gen.pcap"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let err = text(&out.stderr);
    assert!(
        err.contains("Modbus RTU, 19200 8E1, master timeout 1000 ms"),
        "{err}"
    );
    assert!(err.contains("0x17 Read/Write Multiple Registers"), "{err}");
    assert!(
        err.contains("exceptions: 2 Illegal Data Address ×1"),
        "{err}"
    );
    assert!(
        err.contains("Modbus: 1 CRC error, 37 garbage bytes skipped (37 runs), 3 timeouts"),
        "{err}"
    );
    // the same as JSON
    let out = busnoop()
        .args([
            "modbus",
            "--no-config",
            "--stats",
            "--stats-format",
            "json",
            "-o",
            "/dev/null",
        ])
        .arg(fixture("modbus-gen.pcap"))
        .output()
        .unwrap();
    let last = text(&out.stderr).lines().last().unwrap().to_string();
    let v: Value = serde_json::from_str(&last).unwrap();
    assert!(v.to_string().contains("Read Device Identification"), "{v}");
}

const MAP: &str = r#"
[modbus]
timeout-ms = 500

[modbus.slaves]
Boiler = 0x11

[modbus.registers]
"Boiler/107" = { name = "Flow temperature", type = "i16", scale = 0.1, unit = "°C" }
"17/108" = { name = "Power", type = "u32", order = "ABCD", unit = "W" }
"#;

#[test]
fn the_register_map_of_the_project_file() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write(&dir, "busnoop.toml", MAP.as_bytes());
    let data = write(&dir, "c.bin", &contract_capture());
    let out = busnoop()
        .arg("modbus")
        .arg(&data)
        .args(["-f", "jsonl", "--config"])
        .arg(&cfg)
        .output()
        .unwrap();
    let rows = lines(&ok(&out));
    let r = &rows[2];
    assert_eq!(r["device"], "Boiler");
    assert_eq!(r["unit"], "°C");
    assert_eq!(
        parts(r),
        [
            ("Flow temperature".into(), "55.5".into()),
            ("Power".into(), "100".into())
        ]
    );
    assert_eq!(r["data"], "Flow temperature=55.5 °C Power=100 W");
    // --sensor by a name of the map, --wide columns by the map's names
    let out = busnoop()
        .arg("modbus")
        .arg(&data)
        .args([
            "-f",
            "csv",
            "--wide",
            "--sensor",
            "Flow temperature",
            "--config",
        ])
        .arg(&cfg)
        .output()
        .unwrap();
    let csv = ok(&out);
    let header = csv.lines().next().unwrap();
    assert!(header.contains("Flow temperature"), "{header}");
    // mistakes name the file and the line
    let bad = write(
        &dir,
        "bad.toml",
        b"[modbus.registers]\n\"1/100\" = { name = \"x\", type = \"u8\" }\n",
    );
    let out = busnoop()
        .arg("modbus")
        .arg(&data)
        .arg("--config")
        .arg(&bad)
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(0));
    let err = text(&out.stderr);
    assert!(err.contains("bad.toml:2: [modbus.registers]"), "{err}");
    assert!(err.contains("type \"u8\""), "{err}");
    // a key of another section is refused with the section it belongs to
    let bad = write(&dir, "bad2.toml", b"[modbus]\ncommands = 1\n");
    let out = busnoop()
        .arg("modbus")
        .arg(&data)
        .arg("--config")
        .arg(&bad)
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(0));
    assert!(
        text(&out.stderr).contains("bad2.toml:2"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn filters_by_slave_type_and_function() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "c.bin", &contract_capture());
    let rows = jsonl(&path, &["--id", "10"]);
    assert_eq!(
        types(&rows),
        ["Request", "Response", "Request", "Exception"]
    );
    let rows = jsonl(&path, &["--type", "Exception,Timeout"]);
    assert_eq!(types(&rows), ["Exception", "Timeout"]);
    let rows = jsonl(&path, &["--sensor", "0x01"]);
    assert_eq!(rows.len(), 2);
    let rows = jsonl(&path, &["--sensor", "R108"]);
    assert_eq!(types(&rows), ["Response"]);
    let rows = jsonl(&path, &["--sensor", "code"]);
    assert_eq!(types(&rows), ["Exception"]);
    let rows = jsonl(&path, &["--sensor", "read coils"]);
    assert_eq!(types(&rows), ["Request", "Response"]);
    let rows = jsonl(&path, &["--errors"]);
    assert!(
        rows.iter()
            .all(|r| r["type"] != "Request" && r["type"] != "Response")
    );
    let out = busnoop()
        .args(["modbus", "--no-config", "--id", "250"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("reserved"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn wide_and_plot_take_the_registers() {
    let rows = busnoop()
        .arg("modbus")
        .arg(fixture("modbus-wizmodbus-bus.bin"))
        .args(["--line", "9600-8N1", "--wide", "-f", "csv", "--no-config"])
        .output()
        .unwrap();
    let csv = ok(&rows);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert!(
        header.contains(&"R1000") && header.contains(&"R1024"),
        "{header:?}"
    );
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("r.svg");
    let out = busnoop()
        .args(["plot", "--protocol", "modbus", "--sensor", "R1000,R1002"])
        .arg(fixture("modbus-wizmodbus-bus.bin"))
        .arg("-o")
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let image = std::fs::read_to_string(&svg).unwrap();
    assert!(image.contains("R1000") && image.contains("R1002"));
}

#[test]
fn detect_recognises_modbus_files() {
    for (name, fmt) in [
        ("modbus-brainchild.bin", "modbus"),
        ("modbus-wizmodbus-bus.bin", "modbus"),
        ("modbus-gen.bin", "modbus"),
    ] {
        let out = busnoop().arg("detect").arg(fixture(name)).output().unwrap();
        let report = ok(&out);
        assert!(report.contains("verdict: Modbus RTU"), "{name}: {report}");
        assert!(
            report.contains(&format!("run:  busnoop {fmt} ")),
            "{name}: {report}"
        );
    }
    // Modbus ASCII text
    let dir = tempfile::tempdir().unwrap();
    let mut ascii = Vec::new();
    for _ in 0..8 {
        ascii.extend_from_slice(b":1103007C00026E\r\n:110304000A000BD3\r\n");
    }
    let p = write(&dir, "ascii.txt", &ascii);
    let report = ok(&busnoop().arg("detect").arg(&p).output().unwrap());
    assert!(report.contains("verdict: Modbus ASCII"), "{report}");
    assert!(report.contains("--ascii"), "{report}");
}

#[test]
fn ascii_framing() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        &dir,
        "ascii.txt",
        b":1103007C00026E\r\n:110304000A000BD3\r\n:1183026A\r\n",
    );
    let rows = jsonl(&p, &["--ascii", "--line", "9600-7E1"]);
    assert_eq!(types(&rows), ["Request", "Response", "Exception"]);
    assert_eq!(
        parts(&rows[1]),
        [("R124".into(), "10".into()), ("R125".into(), "11".into())]
    );
}

#[test]
fn a_recording_replays_the_same_rows() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("r.pcap");
    let first = ok(&busnoop()
        .arg("modbus")
        .arg(fixture("modbus-gen.pcap"))
        .args(["-f", "tsv", "--no-config", "--record"])
        .arg(&rec)
        .output()
        .unwrap());
    let again = ok(&busnoop()
        .arg("modbus")
        .arg(&rec)
        .args(["-f", "tsv", "--no-config"])
        .output()
        .unwrap());
    assert_eq!(first, again);
}

fn tshark() -> Option<Command> {
    let ok = Command::new("tshark")
        .arg("-v")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!("tshark is not installed: skipping the comparison with Wireshark's mbudp");
        return None;
    }
    let mut c = Command::new("tshark");
    c.env(
        "WIRESHARK_CONFIG_DIR",
        std::env::temp_dir().join("busnoop-no-wireshark-profile"),
    );
    Some(c)
}

/// `--export`: every frame a Modbus/UDP datagram that Wireshark's own dissector reads as the
/// table does (unit, function, request or response, start address, count, register values);
/// the rest raw with busnoop's verdict as comment. (The raw bytes: in the timed recording an
/// echo that came in the same read as its request has the request's time and bytes, and the
/// export takes it for a second row of the same frame.)
#[test]
fn export_decodes_in_wiresharks_modbus_dissector_like_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let export = dir.path().join("e.pcapng");
    let rows = jsonl(&fixture("modbus-gen.bin"), &[]);
    let out = busnoop()
        .arg("modbus")
        .arg(fixture("modbus-gen.bin"))
        .args(["--no-config", "-o", "/dev/null", "--export"])
        .arg(&export)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let packets: Vec<&Value> = rows.iter().filter(|r| r["type"] != "Timeout").collect();
    let Some(mut tshark) = tshark() else {
        return;
    };
    let fields = [
        "ip.src",
        "ip.dst",
        "mbtcp.unit_id",
        "modbus.func_code",
        "modbus.reference_num",
        "modbus.word_cnt",
        "modbus.bit_cnt",
        "modbus.regval_uint16",
        "modbus.exception_code",
        "frame.comment",
    ];
    let mut cmd = tshark
        .args(["-r"])
        .arg(&export)
        .args(["-T", "fields", "-E", "separator=/t"]);
    for f in fields {
        cmd = cmd.args(["-e", f]);
    }
    let out = cmd.output().unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let lines: Vec<HashMap<&str, String>> = text(&out.stdout)
        .lines()
        .map(|l| {
            fields
                .iter()
                .copied()
                .zip(
                    l.split('\t')
                        .map(String::from)
                        .chain(std::iter::repeat(String::new())),
                )
                .collect()
        })
        .collect();
    assert_eq!(lines.len(), packets.len());
    let mut checked = [0usize; 4];
    for (row, p) in packets.iter().zip(&lines) {
        let kind = row["type"].as_str().unwrap();
        let fc = u8::from_str_radix(
            row["sensor_no"]
                .as_str()
                .unwrap_or("")
                .trim_start_matches("0x"),
            16,
        )
        .ok();
        match kind {
            "Request" | "Response" | "Exception" => {
                let id = row["id"].as_u64().unwrap();
                assert_eq!(p["mbtcp.unit_id"], id.to_string(), "{row} {p:?}");
                let slave = format!("10.0.0.{}", if id == 0 { 255 } else { id });
                let (src, dst) = if kind == "Request" {
                    ("10.0.1.254".to_string(), slave)
                } else {
                    (slave, "10.0.1.254".to_string())
                };
                assert_eq!((&p["ip.src"], &p["ip.dst"]), (&src, &dst), "{row}");
                // (Wireshark shows an exception's function without the high bit)
                assert_eq!(
                    p["modbus.func_code"],
                    fc.unwrap().to_string(),
                    "{row} {p:?}"
                );
                let part = |n: &str| part(row, n).unwrap_or_default();
                match (kind, fc) {
                    ("Request", Some(1..=4)) => {
                        assert_eq!(p["modbus.reference_num"], part("start"), "{row} {p:?}");
                        let cnt = if fc <= Some(2) {
                            &p["modbus.bit_cnt"]
                        } else {
                            &p["modbus.word_cnt"]
                        };
                        assert_eq!(*cnt, part("count"), "{row} {p:?}");
                        checked[0] += 1;
                    }
                    ("Response", Some(3 | 4)) => {
                        let values: Vec<String> = parts(row).into_iter().map(|p| p.1).collect();
                        assert_eq!(p["modbus.regval_uint16"], values.join(","), "{row} {p:?}");
                        checked[1] += 1;
                    }
                    ("Exception", _) => {
                        assert_eq!(p["modbus.exception_code"], part("code"));
                        checked[2] += 1;
                    }
                    _ => {}
                }
            }
            _ => {
                assert_eq!(p["ip.src"], "0.0.0.0", "{row}");
                assert!(p["frame.comment"].contains(kind), "{row} {p:?}");
                checked[3] += 1;
            }
        }
    }
    assert!(checked.iter().all(|&n| n > 0), "{checked:?}");
}
