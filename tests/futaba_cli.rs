//! `busnoop futaba` on the command line: the JSON Lines contract, help, detect (file and live
//! at 100000 8E2), filters, --wide, plot, --stats, --record.

mod common;

use std::io::Write;
use std::time::Duration;

use busnoop::futaba::wire;
use common::{busnoop, fixture, ok, pty, text};
use serde_json::Value;

fn session() -> std::path::PathBuf {
    fixture("futaba-session.bin")
}

fn jsonl_text(args: &[&str]) -> String {
    let out = busnoop()
        .arg("futaba")
        .args(args)
        .args(["-f", "jsonl"])
        .output()
        .unwrap();
    ok(&out)
}

fn jsonl(args: &[&str]) -> Vec<Value> {
    jsonl_text(args)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn frame(ch: &[u16; 16], flags: u8, end: u8) -> Vec<u8> {
    let mut v = Vec::new();
    wire::encode_frame(&mut v, ch, flags, end);
    v
}

#[test]
fn channel_rows_carry_ch1_to_ch16_in_microseconds_and_the_flags() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sbus.bin");
    let mut ch = [992u16; 16];
    ch[0] = 200;
    ch[1] = 1000;
    ch[2] = 1800;
    let mut b = frame(&ch, wire::FLAG_CH17 | wire::FLAG_FAILSAFE, 0x00);
    b.extend(frame(&[992; 16], 0, 0x04));
    wire::encode_slot(&mut b, 0, 0x8032);
    b.extend(&frame(&[992; 16], 0, 0)[..10]);
    std::fs::write(&path, &b).unwrap();
    let rows = jsonl(&[path.to_str().unwrap()]);
    assert_eq!(rows.len(), 4, "{rows:#?}");

    let r = &rows[0];
    assert_eq!(r["type"], "Channels");
    assert_eq!(r["id"], Value::Null, "channel frames have no ID");
    assert_eq!(
        (r["sensor_no"].as_str(), r["sensor"].as_str()),
        (Some("0x00"), Some("SBUS"))
    );
    assert_eq!(r["unit"], "us");
    let parts = r["parts"].as_object().unwrap();
    let mut want: Vec<String> = (1..=16).map(|n| format!("CH{n}")).collect();
    want.extend(["CH17", "CH18", "FrameLost", "Failsafe"].map(String::from));
    assert_eq!(parts.len(), want.len());
    // In wire order in the line itself.
    let line = jsonl_text(&[path.to_str().unwrap()])
        .lines()
        .next()
        .unwrap()
        .to_owned();
    let at: Vec<usize> = want
        .iter()
        .map(|n| line.find(&format!("\"{n}\":")).unwrap())
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "{line}");
    assert_eq!(parts["CH1"], 1005);
    assert_eq!(parts["CH2"], 1505);
    assert_eq!(parts["CH3"], 2005);
    assert_eq!(parts["CH4"], 1500);
    assert_eq!(
        (
            &parts["CH17"],
            &parts["CH18"],
            &parts["FrameLost"],
            &parts["Failsafe"]
        ),
        (
            &Value::from(1),
            &Value::from(0),
            &Value::from(0),
            &Value::from(1)
        )
    );
    assert_eq!(r["value"], 1005);
    let note = r["note"].as_str().unwrap();
    assert!(
        note.starts_with("CH17=1 CH18=0 FrameLost=0 Failsafe=1; raw 200 1000 1800 992"),
        "{note}"
    );
    assert!(
        r["data"]
            .as_str()
            .unwrap()
            .starts_with("1005 1505 2005 1500")
    );

    assert_eq!(rows[1]["sensor"], "SBUS2");
    assert!(
        rows[1]["note"]
            .as_str()
            .unwrap()
            .contains("slots 0-7 follow")
    );
    let slot = &rows[2];
    assert_eq!(
        (
            &slot["type"],
            &slot["id"],
            &slot["device"],
            &slot["sensor_no"],
            &slot["sensor"]
        ),
        (
            &Value::from("Slot"),
            &Value::from(0),
            &Value::from("Receiver"),
            &Value::from("0x03"),
            &Value::from("RxV")
        )
    );
    assert_eq!(slot["parts"]["Slot0"], 0x8032);
    assert_eq!(rows[3]["type"], "Truncated");
    assert_eq!(rows[3]["parts"], Value::Null);
}

#[test]
fn the_session_fixture_through_every_format() {
    let rows = jsonl(&[session().to_str().unwrap()]);
    assert_eq!(rows.len(), 89);
    let types = |t: &str| rows.iter().filter(|r| r["type"] == t).count();
    assert_eq!((types("Channels"), types("Slot")), (27, 57));
    assert_eq!((types("Truncated"), types("Garbage")), (3, 2));
    for format in ["tsv", "csv", "pretty"] {
        let out = busnoop()
            .args(["futaba", "-f", format])
            .arg(session())
            .output()
            .unwrap();
        let t = ok(&out);
        assert!(t.contains("RxV") && t.contains("Slot"), "{format}");
        assert!(
            text(&out.stderr)
                .contains("Futaba SBUS: 3 truncated frames, 1 frame with a wrong end byte"),
            "{}",
            text(&out.stderr)
        );
    }
}

#[test]
fn help_of_futaba_and_sbus_name_each_other() {
    // Words as they are, whatever the line breaks of the help.
    let help = |args: &[&str]| {
        let t = text(&busnoop().args(args).output().unwrap().stdout);
        t.split_whitespace().collect::<Vec<_>>().join(" ")
    };
    let futaba = help(&["futaba", "--help"]);
    assert!(
        futaba.contains("Saia S-Bus") && futaba.contains("busnoop sbus"),
        "{futaba}"
    );
    assert!(
        futaba.contains("8E2") && futaba.contains("inverted"),
        "{futaba}"
    );
    let sbus = help(&["sbus", "--help"]);
    assert!(
        sbus.contains("Futaba SBUS") && sbus.contains("busnoop futaba"),
        "{sbus}"
    );
    let top = help(&["--help"]);
    assert!(
        top.contains("futaba") && top.contains("not Saia S-Bus"),
        "{top}"
    );
}

#[test]
fn detect_names_futaba_and_tells_it_from_saia_s_bus() {
    let out = busnoop().arg("detect").arg(session()).output().unwrap();
    let t = ok(&out);
    assert!(t.contains("verdict: Futaba SBUS ("), "{t}");
    assert!(
        t.contains(&format!("run:  busnoop futaba {}", session().display())),
        "{t}"
    );
    // Saia S-Bus telegrams (data mode) are not read as Futaba frames.
    let dir = tempfile::tempdir().unwrap();
    let saia = dir.path().join("saia.bin");
    let mut bytes = Vec::new();
    for v in common::read_tsv("sbus.tsv") {
        if v["mode"] == "data" && v["crc_ok"] == "yes" {
            bytes.extend(busnoop::fmt::parse_hex(&v["hex_on_wire"]).unwrap());
        }
    }
    std::fs::write(&saia, bytes.repeat(4)).unwrap();
    let t = ok(&busnoop().arg("detect").arg(&saia).output().unwrap());
    assert!(t.contains("verdict: S-Bus data mode"), "{t}");
    let futaba_line = t
        .lines()
        .find(|l| l.trim_start().starts_with("Futaba SBUS "))
        .unwrap();
    assert!(futaba_line.contains(" 0.0%"), "{t}");
}

#[test]
fn detect_listens_at_100000_baud_8e2() {
    // A pty ignores the line settings: every setting hears the same frames; the verdict goes
    // to Futaba's own line, and the command needs no --baud.
    let _g = pty::lock();
    let mut bus = pty::bus();
    let (mut child, rx) = pty::spawn(
        &["detect", "--listen-ms", "150", "--baud", "100000,115200"],
        &bus.path,
    );
    let mut traffic = Vec::new();
    for i in 0..8u16 {
        traffic.extend(frame(&[172 + 100 * i; 16], 0, 0x04));
        wire::encode_slot(&mut traffic, 0, 0x8000 | 50);
    }
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
    assert!(
        lines.iter().any(|l| l.contains("100000 baud 8E2")),
        "{lines:#?}"
    );
    let verdict = lines.iter().find(|l| l.starts_with("verdict:")).unwrap();
    assert!(
        verdict.starts_with("verdict: Futaba SBUS at 100000 baud"),
        "{lines:#?}"
    );
    assert!(
        lines.contains(&format!("run:  busnoop futaba {}", bus.path.display())),
        "{lines:#?}"
    );
}

#[test]
fn filters_by_slot_type_sensor_and_errors() {
    let s = session();
    let p = s.to_str().unwrap();
    let rows = jsonl(&[p, "--id", "0"]);
    assert!(!rows.is_empty());
    assert!(rows.iter().all(|r| r["id"] == 0 && r["sensor"] == "RxV"));
    let rows = jsonl(&[p, "--sensor", "RxV"]);
    assert!(rows.iter().all(|r| r["id"] == 0), "{rows:#?}");
    let rows = jsonl(&[p, "--sensor", "SBUS2"]);
    assert_eq!(rows.len(), 15);
    assert!(rows.iter().all(|r| r["sensor"] == "SBUS2"));
    let rows = jsonl(&[p, "--type", "Slot", "--id", "8-15"]);
    assert!(
        rows.iter()
            .all(|r| r["type"] == "Slot" && (8..=15).contains(&r["id"].as_u64().unwrap()))
    );
    let rows = jsonl(&[p, "--errors"]);
    let kinds: Vec<&str> = rows.iter().map(|r| r["type"].as_str().unwrap()).collect();
    assert!(
        kinds.contains(&"Garbage") && kinds.contains(&"Truncated"),
        "{kinds:?}"
    );
    assert!(
        rows.iter()
            .filter(|r| r["type"] == "Channels")
            .all(|r| r["parts"]["Failsafe"] == 1 || r["parts"]["FrameLost"] == 1),
        "frames shown by --errors have a flag set"
    );
    // A slot id byte where a slot number belongs gets a hint; polls do not exist here.
    let out = busnoop()
        .args(["futaba", p, "--id", "131"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("0x83 is the id byte of slot 1"),
        "{}",
        text(&out.stderr)
    );
    let out = busnoop()
        .args(["futaba", p, "--hide-polls"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn wide_plot_and_stats() {
    let s = session();
    let out = busnoop()
        .args(["futaba", "--wide", "--every", "5", "-f", "csv"])
        .arg(&s)
        .output()
        .unwrap();
    let t = ok(&out);
    let header = t.lines().next().unwrap();
    assert!(
        header.starts_with("Millis,CH1(us),CH2(us),CH3(us)") && header.contains("Failsafe,Slot0"),
        "{header}"
    );
    assert!(t.lines().count() > 10);

    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("ch.svg");
    busnoop()
        .args(["plot", "--protocol", "futaba", "--sensor", "CH1,CH2", "-o"])
        .arg(&svg)
        .arg(&s)
        .output()
        .map(|o| ok(&o))
        .unwrap();
    let img = std::fs::read_to_string(&svg).unwrap();
    assert!(
        img.contains("CH1") && img.contains("CH2"),
        "the legend names the channels"
    );

    let out = busnoop()
        .args(["futaba", "--stats", "-f", "tsv"])
        .arg(&s)
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(err.contains("Futaba SBUS statistics (89 rows)"), "{err}");
    assert!(err.contains("frames: SBUS 12, SBUS2 14"), "{err}");
    assert!(
        err.contains("frame lost set in 2 frames, failsafe in 1"),
        "{err}"
    );
    let out = busnoop()
        .args(["futaba", "--stats-format", "json", "-f", "tsv"])
        .arg(&s)
        .output()
        .unwrap();
    let last = text(&out.stderr).lines().last().unwrap().to_owned();
    let v: Value = serde_json::from_str(&last).unwrap();
    assert!(v.is_object(), "{last}");
}

#[test]
fn a_live_line_is_decoded_and_recorded() {
    let _g = pty::lock();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rc.pcapng");
    let mut bus = pty::bus();
    let rec_s = rec.to_str().unwrap().to_owned();
    let (mut child, rx) = pty::spawn(&["futaba", "-f", "tsv", "--record", &rec_s], &bus.path);
    let header = pty::next_line(&rx).1;
    assert!(header.starts_with("Counter\tMillis\tID"));
    let mut live = vec![header];
    for i in 0..5u16 {
        let mut b = frame(&[300 + i; 16], 0, 0x14);
        wire::encode_slot(&mut b, 8 + i as u8, 1000 + i);
        bus.master.write_all(&b).unwrap();
        bus.master.flush().unwrap();
        live.push(pty::next_line(&rx).1);
        live.push(pty::next_line(&rx).1);
        std::thread::sleep(Duration::from_millis(14));
    }
    drop(bus.master);
    let status = pty::wait_exit(&mut child);
    assert_eq!(status.code(), Some(7), "adapter disconnected");
    while let Ok((_, l)) = rx.recv_timeout(Duration::from_secs(1)) {
        live.push(l);
    }
    assert!(
        live[1].contains("\tChannels\t0x14\tSBUS2\t1067 "),
        "{live:#?}"
    );
    assert!(live[2].contains("\t8\tSensor\tSlot\t0x13\t"), "{live:#?}");
    let replay = busnoop()
        .args(["futaba", "-f", "tsv"])
        .arg(&rec)
        .output()
        .unwrap();
    let replayed: Vec<String> = ok(&replay).lines().map(String::from).collect();
    assert_eq!(replayed, live);
}
