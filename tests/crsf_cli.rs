//! `busnoop crsf` and `busnoop ghst` on the command line: the JSON Lines contract, the table,
//! filters, `--wide`, `plot`, `--stats`, `--record` and replay, `--export` decoded by tshark with
//! `busnoop-crsf.lua`, and `detect`.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use busnoop::crsf::wire;
use common::{busnoop, fixture, ok, text};
use serde_json::Value;

fn run(args: &[&str], input: &Path) -> std::process::Output {
    busnoop().args(args).arg(input).output().unwrap()
}

fn jsonl(protocol: &str, input: &Path) -> Vec<Value> {
    let out = ok(&run(&[protocol, "-f", "jsonl"], input));
    out.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// A capture of `frames` (address, type, payload) written to `dir`.
fn capture(dir: &tempfile::TempDir, name: &str, frames: &[(u8, u8, Vec<u8>)]) -> PathBuf {
    let mut bytes = Vec::new();
    for (a, t, p) in frames {
        wire::encode(&mut bytes, *a, *t, p);
    }
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn parts(row: &Value) -> HashMap<String, Value> {
    row["parts"]
        .as_object()
        .map(|o| o.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
        .unwrap_or_default()
}

/// The acceptance contract: `id` the address byte as a number, `sensor_no` the type, the
/// error rows, channels in µs on Betaflight's scale, telemetry named as EdgeTX names it.
#[test]
fn jsonl_contract() {
    let dir = tempfile::tempdir().unwrap();
    let mut ch = [992u16; 16];
    ch[0] = 172;
    ch[1] = 1811;
    let mut gps = Vec::new();
    gps.extend(560_000_000i32.to_be_bytes());
    gps.extend(1_630_000_000i32.to_be_bytes());
    gps.extend([0x02, 0x4B, 0x39, 0xC6, 0x0D, 0x11, 9]);
    let mut att = Vec::new();
    for v in [11_833i16, 26_092, -31_398] {
        att.extend(v.to_be_bytes());
    }
    let path = capture(
        &dir,
        "c.bin",
        &[
            (0xC8, 0x16, wire::pack_bits(&ch, 11)),
            (0xC8, 0x08, vec![0, 33, 1, 40, 0, 4, 210, 67]),
            (0xC8, 0x14, vec![62, 70, 100, 9, 1, 7, 3, 80, 98, 0xFC]),
            (0xC8, 0x02, gps),
            (0xC8, 0x1E, att),
            (0xC8, 0x07, vec![0xFF, 0x38]),
        ],
    );
    let rows = jsonl("crsf", &path);
    assert_eq!(rows.len(), 6);
    assert!(rows.iter().all(|r| r["id"] == 200 && r["device"] == "FC"));
    let rc = &rows[0];
    assert_eq!(
        (&rc["type"], &rc["sensor_no"]),
        (&"RC".into(), &"0x16".into())
    );
    let p = parts(rc);
    assert_eq!(p.len(), 16);
    assert_eq!(
        (&p["CH1"], &p["CH2"], &p["CH3"]),
        (&988.into(), &2012.into(), &1501.into())
    );
    assert!((1..=16).all(|i| p[&format!("CH{i}")].is_number()));
    assert_eq!(rc["unit"], "us");
    let b = parts(&rows[1]);
    assert_eq!(
        (b["RxBt"].as_f64(), b["Curr"].as_f64()),
        (Some(3.3), Some(29.6))
    );
    assert_eq!((&b["Capa"], &b["Bat%"]), (&1234.into(), &67.into()));
    assert_eq!(rows[1]["unit"], "V");
    let l = parts(&rows[2]);
    let want = [
        ("1RSS", -62),
        ("2RSS", -70),
        ("RQly", 100),
        ("RSNR", 9),
        ("ANT", 1),
        ("RFMD", 7),
        ("TPWR", 100),
        ("TRSS", -80),
        ("TQly", 98),
        ("TSNR", -4),
    ];
    for (name, v) in want {
        assert_eq!(l[name], v, "{name}");
    }
    let g = parts(&rows[3]);
    assert_eq!(g["GSpd"].as_f64(), Some(58.7));
    assert_eq!(g["Hdg"].as_f64(), Some(147.9));
    assert_eq!((&g["Alt"], &g["Sats"]), (&2345.into(), &9.into()));
    assert_eq!(g["Lat"].as_f64(), Some(56.0));
    let a = parts(&rows[4]);
    assert_eq!(
        (a["Ptch"].as_f64(), a["Roll"].as_f64(), a["Yaw"].as_f64()),
        (Some(1.1833), Some(2.6092), Some(-3.1398))
    );
    assert_eq!(rows[4]["unit"], "rad");
    assert_eq!(parts(&rows[5])["VSpd"].as_f64(), Some(-2.0));
    assert_eq!(rows[5]["unit"], "m/s");
}

#[test]
fn jsonl_error_rows() {
    let rows = jsonl("crsf", &fixture("crsf-mixed.bin"));
    let kinds: Vec<&str> = rows.iter().map(|r| r["type"].as_str().unwrap()).collect();
    for k in ["BadCRC", "Truncated", "Garbage"] {
        assert!(kinds.contains(&k), "{k}");
    }
    for r in &rows {
        match r["type"].as_str().unwrap() {
            "Garbage" => assert!(r["id"].is_null()),
            "BadCRC" | "Truncated" => {
                assert!(r["id"].is_number() && r.get("parts").is_none(), "{r}");
            }
            _ => assert!(r["id"].is_number() && r["sensor_no"].as_str().unwrap().starts_with("0x")),
        }
    }
    let rc = rows.iter().filter(|r| r["type"] == "RC").count();
    assert_eq!(rc, 1502);
}

#[test]
fn ghst_jsonl() {
    let rows = jsonl("ghst", &fixture("ghst-mixed.bin"));
    assert_eq!(rows.iter().filter(|r| r["type"] == "RC").count(), 900);
    let rc = rows.iter().find(|r| r["type"] == "RC").unwrap();
    assert_eq!(
        (&rc["id"], &rc["sensor_no"]),
        (&0x82.into(), &"0x10".into())
    );
    let p = parts(rc);
    assert!(
        ["CH1", "CH2", "CH3", "CH4", "CH5", "CH8"]
            .iter()
            .all(|c| p.contains_key(*c))
    );
    let bat = rows.iter().find(|r| r["type"] == "Battery").unwrap();
    let b = parts(bat);
    assert!(
        ["RxBt", "Curr", "Capa"].iter().all(|c| b.contains_key(*c)),
        "{bat}"
    );
    let link = rows.iter().find(|r| r["type"] == "LinkStats").unwrap();
    assert_eq!(parts(link)["RQly"], 100);
}

#[test]
fn pretty_table_and_red_errors() {
    let out = ok(&run(
        &["crsf", "-f", "pretty", "--color", "always"],
        &fixture("crsf-mixed.bin"),
    ));
    let header = out.lines().next().unwrap();
    for c in [
        "Counter", "Millis", "ID", "Device", "Type", "Sensor #", "Sensor", "Data",
    ] {
        assert!(header.contains(c), "{header}");
    }
    let bad = out.lines().find(|l| l.contains("BadCRC")).unwrap();
    assert!(
        bad.contains("\x1b[31m") || bad.contains("\x1b[1;31m"),
        "{bad:?}"
    );
    let rc = out.lines().find(|l| l.contains(" RC ")).unwrap();
    assert!(
        rc.contains("Broadcast") && rc.contains("0x16") && rc.contains("CH1"),
        "{rc}"
    );
}

#[test]
fn filters_by_type_sensor_part_name_id_and_errors() {
    let f = fixture("crsf-mixed.bin");
    let types = |args: &[&str]| -> Vec<String> {
        let mut a = vec!["crsf", "-f", "tsv"];
        a.extend(args);
        ok(&run(&a, &f))
            .lines()
            .skip(1)
            .map(|l| l.split('\t').nth(4).unwrap().to_owned())
            .collect()
    };
    let link = types(&["--type", "LinkStats"]);
    assert_eq!(link.len(), 376);
    assert!(link.iter().all(|t| t == "LinkStats"));
    // A number's name selects the rows of the sensors that carry it (link statistics 0x14 and
    // 0x1C) and, as the filter takes either name of a sensor for both, the rows named by the
    // others of their names (TRSS: 0x1D).
    let rqly = types(&["--sensor", "RQly"]);
    assert!(
        rqly.iter()
            .all(|t| ["LinkStats", "LinkRX", "LinkTX"].contains(&t.as_str())),
        "{rqly:?}"
    );
    assert_eq!(rqly.iter().filter(|t| *t != "LinkTX").count(), 376 + 9);
    assert_eq!(types(&["--sensor", "0x1e"]).len(), 10);
    // Errors and warnings: unknown frame types, the accepted baud-rate change.
    let errors = types(&["--errors"]);
    let shown = ["BadCRC", "Truncated", "Garbage", "Unknown", "Command"];
    assert!(
        errors.iter().all(|t| shown.contains(&t.as_str())),
        "{errors:?}"
    );
    assert!(
        shown.iter().all(|k| errors.iter().any(|t| t == k)),
        "{errors:?}"
    );
    assert_eq!(types(&["--id", "0", "--type", "RC"]).len(), 2);
    // A misspelt name gets a suggestion; an address outside a byte is refused.
    let out = run(&["crsf", "--sensor", "RQlx"], &f);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("did you mean RQly"));
    let out = run(&["crsf", "--id", "256"], &f);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn wide_has_a_column_per_number() {
    let out = ok(&run(&["crsf", "--wide"], &fixture("crsf-rx-to-fc.bin")));
    let header: Vec<&str> = out.lines().next().unwrap().split('\t').collect();
    for c in ["CH1(us)", "CH16(us)", "RQly(%)", "1RSS(dBm)", "TPWR(mW)"] {
        assert!(header.contains(&c), "{c} in {header:?}");
    }
    let out = ok(&run(&["crsf", "--wide"], &fixture("crsf-fc-to-rx.bin")));
    let header = out.lines().next().unwrap();
    for c in ["RxBt(V)", "GSpd(km/h)", "Ptch(rad)", "VSpd(m/s)", "Cel1(V)"] {
        assert!(header.contains(c), "{c} in {header}");
    }
}

#[test]
fn plot_draws_link_quality_and_a_channel() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("link.svg");
    ok(&busnoop()
        .arg("plot")
        .arg(fixture("crsf-rx-to-fc.bin"))
        .args(["--sensor", "RQly,CH1", "-o"])
        .arg(&svg)
        .output()
        .unwrap());
    let svg = std::fs::read_to_string(svg).unwrap();
    assert!(svg.contains("RQly") && svg.contains("CH1"));
    assert!(svg.contains("(%)") && svg.contains("(us)"));
}

#[test]
fn stats_and_the_problems_line() {
    let out = run(
        &["crsf", "--stats", "-o", "/dev/null"],
        &fixture("crsf-mixed.bin"),
    );
    assert_eq!(out.status.code(), Some(0));
    let err = text(&out.stderr);
    assert!(err.contains("CRSF statistics"), "{err}");
    assert!(err.contains("0xC8  FC"), "{err}");
    assert!(err.contains("LinkStats") && err.contains("Per s"), "{err}");
    assert!(err.contains("link quality: last"), "{err}");
    assert!(err.contains("resyncs 6"), "{err}");
    assert!(
        err.contains(
            "CRSF: 2 CRC errors, 1 truncated frame, 163 garbage bytes skipped (6 runs), 6 \
             resyncs in 2184 valid frames"
        ),
        "{err}"
    );
    let out = run(&["crsf", "-o", "/dev/null"], &fixture("crsf-rx-to-fc.bin"));
    assert!(text(&out.stderr).contains("CRSF: 5 garbage bytes skipped (1 run), 1 resync"));
}

#[test]
fn baud_sets_the_time_of_raw_captures() {
    let at = |baud: &str| -> Vec<String> {
        ok(&run(
            &["crsf", "-f", "tsv", "--baud", baud],
            &fixture("crsf-fc-to-rx.bin"),
        ))
        .lines()
        .skip(1)
        .map(|l| l.split('\t').nth(1).unwrap().to_owned())
        .collect()
    };
    let fast = at("420000");
    let slow = at("115200");
    let last = |v: &[String]| v.last().unwrap().parse::<u64>().unwrap();
    // 2039 bytes minus the last frame's: 10 bits each.
    assert!((last(&fast) as f64 / last(&slow) as f64 - 115_200.0 / 420_000.0).abs() < 0.01);
}

#[test]
fn recording_replays_to_the_same_rows() {
    let dir = tempfile::tempdir().unwrap();
    for (protocol, input) in [("crsf", "crsf-mixed.bin"), ("ghst", "ghst-mixed.bin")] {
        let rec = dir.path().join(format!("{protocol}.pcapng"));
        let live = ok(&busnoop()
            .args([protocol, "-f", "tsv", "--record"])
            .arg(&rec)
            .arg(fixture(input))
            .output()
            .unwrap());
        let replay = ok(&run(&[protocol, "-f", "tsv"], &rec));
        assert_eq!(live, replay, "{protocol}");
        assert!(live.lines().count() > 1000);
    }
}

#[test]
fn detect_recognises_both_files() {
    for (input, name, cmd) in [
        ("crsf-mixed.bin", "CRSF", "busnoop crsf"),
        ("ghst-mixed.bin", "GHST", "busnoop ghst"),
        ("crsf-fc-to-rx.bin", "CRSF", "busnoop crsf"),
    ] {
        let out = ok(&busnoop()
            .arg("detect")
            .arg(fixture(input))
            .output()
            .unwrap());
        assert!(out.contains(&format!("verdict: {name}")), "{out}");
        assert!(out.contains(cmd), "{out}");
    }
}

/// tshark, when it is installed; `None` with a message otherwise.
fn tshark() -> Option<Command> {
    let ok = Command::new("tshark")
        .arg("-v")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!("tshark is not installed: skipping the Wireshark comparison");
        return None;
    }
    let mut c = Command::new("tshark");
    c.env(
        "WIRESHARK_CONFIG_DIR",
        std::env::temp_dir().join("busnoop-no-wireshark-profile"),
    );
    Some(c)
}

/// The export decoded by tshark with busnoop-crsf.lua, against the table: frame for frame the
/// same address, type, CRC status and numbers.
#[test]
fn tshark_decodes_the_export_like_the_table() {
    for (protocol, input) in [("crsf", "crsf-mixed.bin"), ("ghst", "ghst-mixed.bin")] {
        let Some(mut tshark) = tshark() else { return };
        let dir = tempfile::tempdir().unwrap();
        let export = dir.path().join("export.pcapng");
        let table = ok(&busnoop()
            .args([protocol, "-f", "jsonl", "--raw", "--export"])
            .arg(&export)
            .arg(fixture(input))
            .output()
            .unwrap());
        let rows: Vec<Value> = table
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let lua = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/contrib/wireshark/busnoop-crsf.lua"
        );
        let fields = ok(&tshark
            .arg("-X")
            .arg(format!("lua_script:{lua}"))
            .arg("-r")
            .arg(&export)
            .args(["-T", "fields", "-E", "occurrence=a", "-E", "separator=|"])
            .args(["-e", &format!("{protocol}.address")])
            .args(["-e", &format!("{protocol}.type")])
            .args(["-e", &format!("{protocol}.parts")])
            .args(["-e", &format!("{protocol}.crc_status")])
            .args(["-e", "_ws.expert.message"])
            .output()
            .unwrap());
        let packets: Vec<Vec<&str>> = fields.lines().map(|l| l.split('|').collect()).collect();
        assert_eq!(packets.len(), rows.len(), "{protocol}");
        let (mut numbers, mut bad) = (0, 0);
        for (row, pkt) in rows.iter().zip(&packets) {
            let what = format!("{protocol}: {row} against {pkt:?}");
            match row["type"].as_str().unwrap() {
                "BadCRC" => {
                    bad += 1;
                    assert_eq!(pkt[3], "bad", "{what}");
                    assert!(pkt[4].contains("Bad CRC"), "{what}");
                }
                "Garbage" | "Truncated" => {
                    assert_eq!(pkt[3], "", "{what}");
                    assert!(pkt[4].contains("Not a whole frame"), "{what}");
                }
                kind => {
                    assert_eq!(pkt[3], "good", "{what}");
                    assert_eq!(
                        u32::from_str_radix(pkt[0].trim_start_matches("0x"), 16).ok(),
                        row["id"].as_u64().map(|i| i as u32),
                        "{what}"
                    );
                    assert_eq!(pkt[1], kind, "{what}");
                    if let Some(p) = row["parts"].as_object() {
                        let names: Vec<String> = pkt[2]
                            .split(' ')
                            .map(|n| n.split('=').next().unwrap().to_owned())
                            .collect();
                        let want: Vec<&String> = p.keys().collect();
                        assert_eq!(names.len(), want.len(), "{what}");
                        for (k, v) in p {
                            let text = pkt[2]
                                .split(' ')
                                .find_map(|n| n.strip_prefix(&format!("{k}=")))
                                .unwrap_or_else(|| panic!("{k} missing: {what}"));
                            let num: String = text
                                .chars()
                                .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-')
                                .collect();
                            assert_eq!(num.parse::<f64>().ok(), v.as_f64(), "{k}: {what}");
                        }
                        numbers += 1;
                    }
                }
            }
        }
        assert!(
            bad > 0 && numbers > 1000,
            "{protocol}: {bad} bad, {numbers} with numbers"
        );
    }
}
