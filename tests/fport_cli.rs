//! `busnoop fport` from the command line: the JSON Lines output contract (telemetry rows carry
//! `busnoop sport`'s cells for the same payload, channel rows `CH1`…`CHn` in µs, flags as
//! parts), detect (F.Port and not S.Port, and the other way round), filters, `--wide`, `plot`,
//! `--stats`, `--record` and `--variant`.

mod common;

use busnoop::fmt::parse_hex;
use busnoop::fport::wire;
use busnoop::sport::wire as sport_wire;
use common::{busnoop, fixture, ok, read_tsv, text};
use serde_json::Value;
use std::path::Path;

fn jsonl(args: &[&str], file: &Path) -> Vec<Value> {
    let out = busnoop()
        .args(args)
        .arg(file)
        .args(["-f", "jsonl"])
        .output()
        .unwrap();
    ok(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn s(v: &Value, key: &str) -> String {
    match &v[key] {
        Value::String(t) => t.clone(),
        Value::Null => String::new(),
        other => other.to_string(),
    }
}

/// The unstuffed header and body of every S.Port frame (not poll) of the vectors.
fn vectors() -> Vec<(Vec<u8>, u8, [u8; 8])> {
    read_tsv("sport-vectors.tsv")
        .into_iter()
        .filter(|v| v["expected_frame_type"] != "poll")
        .map(|v| {
            let wire_bytes = parse_hex(&v["hex_bytes_on_wire"]).unwrap();
            let mut body = Vec::new();
            let mut esc = false;
            for &b in &wire_bytes[1..] {
                match b {
                    sport_wire::ESCAPE => esc = true,
                    b if esc => {
                        body.push(b ^ 0x20);
                        esc = false;
                    }
                    b => body.push(b),
                }
            }
            (wire_bytes, body[0], body[1..9].try_into().unwrap())
        })
        .collect()
}

/// The output contract: for the same 8-byte S.Port payload, an F.Port telemetry row carries
/// the `sensor`, `sensor_no`, `value`, `unit` and `parts` of `busnoop sport`'s row.
#[test]
fn telemetry_rows_carry_the_s_port_cells() {
    let dir = tempfile::tempdir().unwrap();
    let vs = vectors();
    // S.Port: every frame as on the wire. F.Port 2: control, downlink, uplink with the same
    // physical ID byte. F.Port v1: the flight controller's answers, so S.Port is asked with
    // physical ID 27.
    let (mut sport, mut sport27, mut v2, mut v1) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (wire_bytes, header, body) in &vs {
        sport.extend_from_slice(wire_bytes);
        sport_wire::encode_raw(&mut sport27, sport_wire::header_for(27), body);
        let payload: [u8; 7] = body[..7].try_into().unwrap();
        wire::encode_v2_control(&mut v2, &[992; 16], 0, 100);
        wire::encode_v2_telemetry(&mut v2, *header, &payload);
        wire::encode_v2_telemetry(&mut v2, *header, &payload);
        wire::encode_v1_telemetry(&mut v1, wire::V1_UPLINK, &payload);
    }
    let files: Vec<_> = [
        ("s.bin", &sport),
        ("s27.bin", &sport27),
        ("v2.bin", &v2),
        ("v1.bin", &v1),
    ]
    .into_iter()
    .map(|(name, bytes)| {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    })
    .collect();
    let sport_rows = jsonl(&["sport"], &files[0]);
    let sport27_rows = jsonl(&["sport"], &files[1]);
    let uplinks = |rows: Vec<Value>| -> Vec<Value> {
        rows.into_iter()
            .filter(|r| r["frame"] == "Uplink")
            .collect()
    };
    let v2_rows = uplinks(jsonl(&["fport"], &files[2]));
    let v1_rows = uplinks(jsonl(&["fport", "--variant", "v1"], &files[3]));
    assert_eq!(sport_rows.len(), vs.len());
    for (want, got) in [(&sport_rows, &v2_rows), (&sport27_rows, &v1_rows)] {
        assert_eq!(want.len(), got.len());
        for (w, g) in want.iter().zip(got) {
            for key in [
                "sensor",
                "sensor_no",
                "value",
                "unit",
                "parts",
                "data",
                "type",
            ] {
                assert_eq!(w[key], g[key], "{key}: {w} against {g}");
            }
        }
    }
    // The contract is about real values: most rows carry some.
    assert!(v2_rows.iter().filter(|r| !r["value"].is_null()).count() > 40);
}

/// Channel rows: `CH1` … `CH16` in µs on Betaflight's scale `5/8 x + 880` (the raw values in the
/// Note), the flags as 0/1 parts and in the Note, RSSI; the error rows of the shared kinds.
#[test]
fn channel_rows_and_error_rows() {
    for file in ["fport-v1-session.bin", "fport2-session.bin"] {
        let rows = jsonl(&["fport"], &fixture(file));
        let control: Vec<&Value> = rows.iter().filter(|r| r["type"] == "Control").collect();
        assert!(control.len() >= 38, "{file}");
        let mut flagged = 0;
        for r in &control {
            let parts = r["parts"].as_object().unwrap();
            let n = parts.keys().filter(|k| k.starts_with("CH")).count();
            let channels = if n >= 24 { 24 } else { n - 2 };
            let note = s(r, "note");
            let raw: Vec<f64> = note
                .split("raw ")
                .nth(1)
                .unwrap()
                .split(' ')
                .map(|x| x.parse().unwrap())
                .collect();
            assert_eq!(raw.len(), channels, "{r}");
            for (i, x) in raw.iter().enumerate() {
                let us = parts[&format!("CH{}", i + 1)].as_f64().unwrap();
                assert_eq!(us, 5.0 / 8.0 * x + 880.0, "{r}");
            }
            assert_eq!(r["value"], parts["CH1"]);
            assert_eq!(s(r, "unit"), "µs");
            let lost = parts["FrameLost"].as_u64().unwrap();
            let failsafe = parts["Failsafe"].as_u64().unwrap();
            assert!(lost <= 1 && failsafe <= 1);
            assert_eq!(note.contains("frame lost"), lost == 1, "{r}");
            assert_eq!(note.contains("failsafe"), failsafe == 1, "{r}");
            if channels <= 16 {
                let ch17 = parts["CH17"].as_u64().unwrap();
                assert_eq!(note.contains("CH17"), ch17 == 1, "{r}");
            }
            flagged += lost + failsafe;
            assert!(parts["RSSI"].as_u64().unwrap() <= 100);
        }
        assert_eq!(flagged, 4, "{file}: three frames lost, one failsafe");
        for kind in ["BadCRC", "Truncated", "Garbage"] {
            let r = rows.iter().find(|r| r["type"] == kind).unwrap();
            assert!(r["value"].is_null() && r.get("parts").is_none(), "{r}");
        }
    }
}

fn verdict(out: &std::process::Output) -> (String, String) {
    let t = text(&out.stdout);
    let line = |p: &str| {
        t.lines()
            .find(|l| l.starts_with(p))
            .unwrap_or("")
            .to_owned()
    };
    (line("verdict: "), line("run:  "))
}

/// `detect` picks F.Port on F.Port traffic and S.Port on S.Port traffic: both start frames with
/// 0x7E, and neither passes for the other.
#[test]
fn detect_tells_f_port_from_s_port() {
    for (file, verdict_start, run) in [
        (
            "fport-v1-session.bin",
            "verdict: F.Port v1 (",
            "busnoop fport --variant v1",
        ),
        (
            "fport2-session.bin",
            "verdict: F.Port 2 (",
            "busnoop fport --variant v2",
        ),
        ("sport-sample.bin", "verdict: S.Port (", "busnoop sport"),
    ] {
        let out = busnoop().arg("detect").arg(fixture(file)).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let (v, r) = verdict(&out);
        assert!(v.starts_with(verdict_start), "{file}: {v}");
        assert!(r.contains(run), "{file}: {r}");
        let t = text(&out.stdout);
        let share = |label: &str| -> f64 {
            let line = t
                .lines()
                .find(|l| l.trim_start().starts_with(label) && !l.contains("inverted"))
                .unwrap();
            let cell = line[label.len() + 2..].split_whitespace().next().unwrap();
            cell.trim_end_matches('%').parse().unwrap()
        };
        if file.starts_with("fport") {
            assert!(share("S.Port") < 1.0, "{t}");
            assert!(share("F.Port v1").max(share("F.Port 2")) > 95.0, "{t}");
        } else {
            assert!(share("F.Port v1") < 1.0 && share("F.Port 2") < 1.0, "{t}");
        }
    }
    // The wrong command says which one to run.
    let out = busnoop()
        .arg("sport")
        .arg(fixture("fport-v1-session.bin"))
        .output()
        .unwrap();
    assert!(
        text(&out.stderr).contains("try: busnoop fport --variant v1"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn filters_select_rows() {
    let file = fixture("fport2-session.bin");
    let all = jsonl(&["fport"], &file);
    let polls = all
        .iter()
        .filter(|r| r["type"].is_null() && r["frame"] == "Downlink")
        .count();
    assert!(polls > 30);
    let no_polls = jsonl(&["fport", "--hide-polls"], &file);
    assert_eq!(no_polls.len(), all.len() - polls);
    let only_polls = jsonl(&["fport", "--type", "Poll"], &file);
    assert_eq!(only_polls.len(), polls);
    let control = jsonl(&["fport", "--type", "Control"], &file);
    assert!(control.iter().all(|r| r["type"] == "Control") && control.len() == 40);
    let vfas = jsonl(&["fport", "--sensor", "VFAS"], &file);
    assert!(!vfas.is_empty() && vfas.iter().all(|r| r["sensor"] == "Volts"));
    let ch = jsonl(&["fport", "--sensor", "CH1"], &file);
    assert_eq!(ch.len(), 40);
    let id24 = jsonl(&["fport", "--id", "24"], &file);
    assert!(id24.len() == 10 && id24.iter().all(|r| r["device"] == "Receiver"));
    let errors = jsonl(&["fport", "--errors"], &file);
    let kinds: Vec<String> = errors.iter().map(|r| s(r, "type")).collect();
    assert!(
        kinds.contains(&"BadCRC".into()) && kinds.contains(&"Garbage".into()),
        "{kinds:?}"
    );
    // The physical ID byte of an ID is pointed out.
    let out = busnoop()
        .args(["fport", "--id", "0x98"])
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("use --id 24"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn wide_table_and_plot() {
    let out = busnoop()
        .arg("fport")
        .arg(fixture("fport-v1-session.bin"))
        .args(["--wide", "-f", "csv"])
        .output()
        .unwrap();
    let t = ok(&out);
    let header: Vec<&str> = t.lines().next().unwrap().split(',').collect();
    for col in [
        "CH1(µs)",
        "CH16(µs)",
        "FrameLost",
        "RSSI",
        "VFAS(V)",
        "AccX(g)",
    ] {
        assert!(header.contains(&col), "{col} in {header:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("f.svg");
    let out = busnoop()
        .arg("plot")
        .arg(fixture("fport2-session.bin"))
        .args(["--sensor", "CH1,RSSI", "-o"])
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.contains("CH1") && text.contains("(µs)"),
        "no channel series"
    );
}

#[test]
fn stats_and_variants() {
    let out = busnoop()
        .arg("fport")
        .arg(fixture("fport2-session.bin"))
        .args(["--stats", "-o", "/dev/null"])
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(
        err.contains("variant: F.Port 2 (chosen by framing"),
        "{err}"
    );
    assert!(err.contains(" 27  FC "), "{err}");
    assert!(
        err.contains("F.Port 2: 1 CRC error, 1 truncated frame"),
        "{err}"
    );
    let out = busnoop()
        .arg("fport")
        .arg(fixture("fport2-session.bin"))
        .args(["--stats-format", "json", "-o", "/dev/null"])
        .output()
        .unwrap();
    let last = text(&out.stderr).lines().last().unwrap().to_owned();
    let v: Value = serde_json::from_str(&last).unwrap();
    assert!(v.to_string().contains("F.Port 2"), "{v}");

    // FBUS: the same framing at 460800, so a raw file's reconstructed times are a quarter.
    let millis = |variant: &str| -> u64 {
        let rows = jsonl(
            &["fport", "--variant", variant],
            &fixture("fport2-session.bin"),
        );
        rows.last().unwrap()["millis"].as_u64().unwrap()
    };
    let (v2, fbus) = (millis("v2"), millis("fbus"));
    assert!(
        v2 > 150 && fbus * 4 <= v2 && fbus * 4 + 4 >= v2,
        "{v2} {fbus}"
    );
    // The wrong framing finds nothing, and says what to check.
    let out = busnoop()
        .args(["fport", "--variant", "v1"])
        .arg(fixture("fport2-session.bin"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(10), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("fport --variant v2"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn a_recording_replays_the_same_rows() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec.pcap");
    let direct = busnoop()
        .arg("fport")
        .arg(fixture("fport-v1-session.bin"))
        .arg("--record")
        .arg(&rec)
        .args(["-f", "jsonl"])
        .output()
        .unwrap();
    let direct = ok(&direct);
    let replay = jsonl(&["fport"], &rec);
    let direct: Vec<Value> = direct
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(direct.len(), replay.len());
    for (a, b) in direct.iter().zip(&replay) {
        for key in ["type", "id", "sensor", "data", "value", "parts", "frame"] {
            assert_eq!(a[key], b[key]);
        }
    }
}

#[test]
fn help_names_the_variants_and_the_inversion() {
    let out = busnoop().args(["fport", "--help"]).output().unwrap();
    let t = ok(&out);
    for word in ["--variant", "fbus", "inverted", "460800", "5/8 x + 880"] {
        assert!(t.contains(word), "{word} in help");
    }
}

/// `detect` on a live line (a pseudo-terminal, which ignores the rate, so every rate hears the
/// same F.Port traffic): F.Port wins at its own rate, and its inverted bytes are recognised as
/// an inverted F.Port line.
#[test]
fn detect_listens_to_a_live_f_port_line() {
    use common::pty;
    use std::io::Write;
    for (file, invert, verdict_start, run) in [
        (
            "fport2-session.bin",
            false,
            "verdict: F.Port 2 at 115200 baud (",
            "run:  busnoop fport --variant v2",
        ),
        (
            "fport-v1-session.bin",
            true,
            "verdict: F.Port v1, inverted line at 115200 baud (",
            "then: busnoop fport --variant v1",
        ),
    ] {
        let _g = pty::lock();
        let mut bus = pty::bus();
        let (mut child, rx) = pty::spawn(
            &[
                "detect",
                "--listen-ms",
                "200",
                "--baud",
                "57600,115200,460800",
            ],
            &bus.path,
        );
        let mut bytes = std::fs::read(fixture(file)).unwrap();
        if invert {
            bytes.iter_mut().for_each(|b| *b = !*b);
        }
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            let _ = bus.master.write_all(&bytes);
            let _ = bus.master.flush();
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        let stderr = pty::stderr_of(&mut child);
        let mut lines = Vec::new();
        while let Ok((_, l)) = rx.recv_timeout(std::time::Duration::from_secs(2)) {
            lines.push(l);
        }
        assert_eq!(status.code(), Some(0), "{stderr}\n{lines:#?}");
        assert!(
            lines.iter().any(|l| l.starts_with(verdict_start)),
            "{file}: {lines:#?}"
        );
        assert!(
            lines.iter().any(|l| l.starts_with(run)),
            "{file}: {lines:#?}"
        );
    }
}
