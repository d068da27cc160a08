//! `busnoop ibus` on the command line: Betaflight's unit-test vectors, the JSON Lines contract
//! of sensor rows, polls and --hide-polls, --sensor-type and the project file, detect (file and
//! live), filters, --wide, plot, --stats, --record.

mod common;

use std::io::Write;
use std::time::Duration;

use busnoop::fmt::parse_hex;
use busnoop::ibus::wire;
use common::{busnoop, fixture, ok, pty, read_tsv, text};
use serde_json::Value;

fn sensors() -> std::path::PathBuf {
    fixture("ibus-sensors.bin")
}

fn jsonl_of(path: &std::path::Path, args: &[&str]) -> Vec<Value> {
    let out = busnoop()
        .arg("ibus")
        .arg(path)
        .args(args)
        .args(["-f", "jsonl"])
        .output()
        .unwrap();
    ok(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// A cell as text; a number as the shortest text of its value (`12.6` for the line's `12.60`:
/// exact texts are compared in `data`).
fn opt(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A number's text as `opt` gives it (`"12.60"` → `"12.6"`).
fn num(s: &str) -> String {
    if s.is_empty() {
        return String::new();
    }
    serde_json::from_str::<Value>(s).unwrap().to_string()
}

/// Every vector of `fixtures/ibus-vectors.tsv` (Betaflight's unit tests) as a capture of its
/// own: the last row has the ID, Type, Sensor, value and unit the test asserts.
#[test]
fn betaflight_vectors_decode_to_their_asserted_values() {
    let dir = tempfile::tempdir().unwrap();
    for (i, v) in read_tsv("ibus-vectors.tsv").iter().enumerate() {
        let path = dir.path().join(format!("v{i}.bin"));
        std::fs::write(&path, parse_hex(&v["hex_on_wire"]).unwrap()).unwrap();
        let out = busnoop()
            .arg("ibus")
            .arg(&path)
            .args(["-f", "jsonl"])
            .output()
            .unwrap();
        assert!(matches!(out.status.code(), Some(0) | Some(10)), "{v:?}");
        let rows: Vec<Value> = text(&out.stdout)
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let r = rows.last().unwrap_or_else(|| panic!("no row for {v:?}"));
        let got = (
            opt(&r["id"]),
            opt(&r["type"]),
            opt(&r["sensor"]),
            opt(&r["value"]),
            opt(&r["unit"]),
        );
        let want = (
            v["id"].clone(),
            v["type"].clone(),
            v["sensor"].clone(),
            num(&v["value"]),
            v["unit"].clone(),
        );
        assert_eq!(got, want, "{}: {}", v["source"], v["meaning"]);
        if v["type"] == "Measure" {
            assert_eq!(opt(&r["data"]), v["value"], "the exact text: {r}");
            assert_eq!(
                opt(&r["parts"][v["sensor"].as_str()]),
                num(&v["value"]),
                "the value again as a part under the sensor's name: {r}"
            );
        }
    }
}

#[test]
fn sensor_rows_follow_the_contract() {
    let rows = jsonl_of(&sensors(), &[]);
    let measure = |id: u64| {
        rows.iter()
            .find(|r| r["type"] == "Measure" && r["id"] == id)
            .unwrap()
            .clone()
    };
    for (id, sensor, value, unit) in [
        (1, "IntV", "5.12", "V"),
        (2, "Temp", "25.3", "degC"),
        (3, "RPM", "0", "rpm"),
        (4, "ExtV", "12.60", "V"),
        (5, "Curr", "0.00", "A"),
        (6, "Fuel", "100", "%"),
    ] {
        let r = measure(id);
        assert_eq!(
            (opt(&r["sensor"]), opt(&r["data"]), opt(&r["unit"])),
            (sensor.to_owned(), value.to_owned(), unit.to_owned()),
            "{r}"
        );
        assert_eq!(opt(&r["value"]), num(value), "{r}");
        assert_eq!(opt(&r["parts"][sensor]), num(value), "{r}");
    }
    let gps = measure(7);
    assert_eq!(gps["sensor"], "GPS");
    assert_eq!(opt(&gps["data"]), "52.5200000");
    assert_eq!(opt(&gps["parts"]["Lat"]), "52.52");
    // Unanswered polls: an ID and no Type; a type answer names the type.
    let polls: Vec<&Value> = rows.iter().filter(|r| r["type"].is_null()).collect();
    assert_eq!(polls.len(), 10);
    assert!(polls.iter().all(|r| r["id"].is_u64()));
    let t = rows
        .iter()
        .find(|r| r["type"] == "SensorType" && r["id"] == 5)
        .unwrap();
    assert_eq!(
        (opt(&t["sensor_no"]), opt(&t["sensor"])),
        ("0x05".into(), "Curr".into())
    );
    let kinds: Vec<String> = rows.iter().map(|r| opt(&r["type"])).collect();
    for k in ["BadCRC", "Garbage", "Truncated", "Discover"] {
        assert!(kinds.iter().any(|x| x == k), "{k}");
    }
}

#[test]
fn hide_polls_and_type_poll() {
    let all = jsonl_of(&sensors(), &[]);
    let shown = jsonl_of(&sensors(), &["--hide-polls"]);
    assert_eq!(shown.len(), all.len() - 10);
    assert!(shown.iter().all(|r| !r["type"].is_null()));
    let polls = jsonl_of(&sensors(), &["--type", "Poll"]);
    assert_eq!(polls.len(), 10);
    let ext = jsonl_of(&sensors(), &["--sensor", "ExtV", "--hide-polls"]);
    assert!(ext.iter().all(|r| r["id"] == 4), "{ext:#?}");
    assert_eq!(ext.len(), 4, "type answer and three measurements");
    let by_code = jsonl_of(&sensors(), &["--sensor", "0x03", "--type", "Measure"]);
    assert_eq!(by_code.len(), 3);
    let out = busnoop()
        .args(["ibus", "--id", "0xA1"])
        .arg(sensors())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("command byte for address 1"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn sensor_types_from_the_options_or_the_project_file() {
    // The between-sensors capture of the field starts after the type queries: without a type,
    // a value is raw.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mid.bin");
    let mut b = Vec::new();
    wire::encode_poll(&mut b, wire::CMD_MEASURE, 2);
    wire::encode(&mut b, 0xA2, &1500u16.to_le_bytes());
    std::fs::write(&path, &b).unwrap();
    let raw = jsonl_of(&path, &[]);
    assert_eq!(
        (opt(&raw[0]["data"]), raw[0]["parts"]["Raw"].clone()),
        ("0x05DC".into(), Value::from(1500))
    );
    let typed = jsonl_of(&path, &["--sensor-type", "2=RPM"]);
    assert_eq!(
        (opt(&typed[0]["sensor"]), opt(&typed[0]["value"])),
        ("RPM".into(), "1500".into())
    );
    let cfg = dir.path().join("busnoop.toml");
    std::fs::write(&cfg, "[ibus.sensor-types]\n2 = \"Temp\"\n").unwrap();
    let file = jsonl_of(&path, &["--config", cfg.to_str().unwrap()]);
    assert_eq!(
        (opt(&file[0]["sensor"]), opt(&file[0]["data"])),
        ("Temp".into(), "110.0".into())
    );
    let out = busnoop()
        .args(["ibus", "--sensor-type", "2=Bogus"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("unknown sensor type"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn rc_frames_and_the_rc_fixture() {
    let rows = jsonl_of(&fixture("ibus-rc.bin"), &[]);
    let ch: Vec<&Value> = rows.iter().filter(|r| r["type"] == "Channels").collect();
    assert_eq!(ch.len(), 20);
    assert!(ch.iter().all(|r| r["id"].is_null() && r["unit"] == "us"));
    assert_eq!(ch[0]["parts"].as_object().unwrap().len(), 14);
    assert_eq!(ch[19]["parts"].as_object().unwrap().len(), 18);
    assert!(ch[19]["parts"]["CH18"].is_u64());
    assert_eq!(rows.iter().filter(|r| r["type"] == "BadCRC").count(), 1);
}

#[test]
fn detect_names_ibus_in_files_and_on_a_live_line() {
    for f in ["ibus-sensors.bin", "ibus-rc.bin"] {
        let t = ok(&busnoop().arg("detect").arg(fixture(f)).output().unwrap());
        assert!(t.contains("verdict: FlySky iBUS ("), "{t}");
        assert!(t.contains("run:  busnoop ibus "), "{t}");
    }
    let _g = pty::lock();
    let mut bus = pty::bus();
    let (mut child, rx) = pty::spawn(
        &["detect", "--listen-ms", "150", "--baud", "100000,115200"],
        &bus.path,
    );
    let traffic = std::fs::read(sensors()).unwrap();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        let _ = bus.master.write_all(&traffic);
        let _ = bus.master.flush();
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr = pty::stderr_of(&mut child);
    let mut lines = Vec::new();
    while let Ok((_, l)) = rx.recv_timeout(Duration::from_secs(2)) {
        lines.push(l);
    }
    assert_eq!(status.code(), Some(0), "{stderr}\n{lines:#?}");
    let verdict = lines.iter().find(|l| l.starts_with("verdict:")).unwrap();
    assert!(
        verdict.starts_with("verdict: FlySky iBUS at 115200 baud"),
        "{lines:#?}"
    );
    assert!(
        lines.contains(&format!("run:  busnoop ibus {}", bus.path.display())),
        "{lines:#?}"
    );
}

#[test]
fn wide_plot_and_stats() {
    let out = busnoop()
        .args(["ibus", "--wide", "-f", "csv"])
        .arg(sensors())
        .output()
        .unwrap();
    let t = ok(&out);
    assert_eq!(
        t.lines().next().unwrap(),
        "Millis,IntV(V),Temp(degC),RPM(rpm),ExtV(V),Curr(A),Fuel(%),Lat(deg)"
    );
    assert!(t.lines().count() >= 4, "a line per poll cycle: {t}");

    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("s.svg");
    let out = busnoop()
        .args(["plot", "--sensor", "ExtV,Temp", "-o"])
        .arg(&svg)
        .arg(sensors())
        .output()
        .unwrap();
    ok(&out);
    let img = std::fs::read_to_string(&svg).unwrap();
    assert!(img.contains("ExtV") && img.contains("Temp"));

    let out = busnoop()
        .args(["ibus", "--stats", "-f", "tsv"])
        .arg(sensors())
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(err.contains("FlySky iBUS statistics"), "{err}");
    assert!(err.contains("  4  ExtV"), "{err}");
    assert!(
        err.contains("FlySky iBUS: 1 checksum error, 2 truncated frames"),
        "{err}"
    );
}

#[test]
fn a_live_sensor_bus_is_paired_and_recorded() {
    let _g = pty::lock();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("bus.pcap");
    let mut bus = pty::bus();
    let rec_s = rec.to_str().unwrap().to_owned();
    let (mut child, rx) = pty::spawn(&["ibus", "-f", "tsv", "--record", &rec_s], &bus.path);
    let header = pty::next_line(&rx).1;
    let mut live = vec![header];
    let mut send = |b: &[u8]| {
        bus.master.write_all(b).unwrap();
        bus.master.flush().unwrap();
        std::thread::sleep(Duration::from_millis(8));
    };
    let mut b = Vec::new();
    wire::encode_poll(&mut b, wire::CMD_TYPE, 1);
    wire::encode(&mut b, 0x91, &[0x03, 0x02]);
    send(&b);
    live.push(pty::next_line(&rx).1);
    for v in [1160u16, 1170] {
        let mut b = Vec::new();
        wire::encode_poll(&mut b, wire::CMD_MEASURE, 1);
        wire::encode(&mut b, 0xA1, &v.to_le_bytes());
        send(&b);
        live.push(pty::next_line(&rx).1);
    }
    // A poll nobody answers comes out with the next frame.
    let mut b = Vec::new();
    wire::encode_poll(&mut b, wire::CMD_MEASURE, 5);
    wire::encode_poll(&mut b, wire::CMD_MEASURE, 1);
    wire::encode(&mut b, 0xA1, &1180u16.to_le_bytes());
    send(&b);
    live.push(pty::next_line(&rx).1);
    live.push(pty::next_line(&rx).1);
    drop(bus.master);
    let status = pty::wait_exit(&mut child);
    assert_eq!(status.code(), Some(7), "adapter disconnected");
    while let Ok((_, l)) = rx.recv_timeout(Duration::from_secs(1)) {
        live.push(l);
    }
    assert!(
        live[2].contains("\tMeasure\t0x03\tExtV\t11.60\t11.60\tV\t"),
        "{live:#?}"
    );
    assert!(
        live[4].contains("\t5\t\t\t\t\t\t\t\tmeasurement poll, no answer"),
        "{live:#?}"
    );
    let replay = busnoop()
        .args(["ibus", "-f", "tsv"])
        .arg(&rec)
        .output()
        .unwrap();
    let replayed: Vec<String> = ok(&replay).lines().map(String::from).collect();
    assert_eq!(replayed, live);
}
