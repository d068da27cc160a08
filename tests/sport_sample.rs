//! The S-Port_Snoop sample log (lines 323-352 of the "S-Port Traffic" paper): encode the traffic
//! it describes as raw wire bytes with our own encoder, decode it, and get the sample's rows back.

mod common;

use assert_cmd::Command;
use busnoop::sport::wire;
use common::{fixture, read_tsv, sport_rows};

/// Implied decimals of the sample's sensors (wire reference §6.2).
fn precision(sensor_no: &str) -> u32 {
    match sensor_no {
        "100" | "110" | "210" => 2,
        "200" => 1,
        other => panic!("sensor {other} is not in the sample"),
    }
}

/// The sample's traffic on the wire: a poll per row, a Null or Data response where the sample has one.
fn encode_sample() -> Vec<u8> {
    let mut out = Vec::new();
    for row in read_tsv("sport-snoop-sample.tsv") {
        let id: u8 = row["ID"].parse().unwrap();
        let header = wire::header_for(id);
        match row["Type"].as_str() {
            "" => wire::encode_poll(&mut out, header),
            // A genuine FrSky sensor's keep-alive: type 0, app ID 0, value 0, CRC 0xFF.
            "Null" => wire::encode_raw(&mut out, header, &[0, 0, 0, 0, 0, 0, 0, 0xFF]),
            "Data" => {
                let app_id = u16::from_str_radix(&row["Sensor #"], 16).unwrap();
                let scale = 10f64.powi(precision(&row["Sensor #"]) as i32);
                let raw = (row["Data"].parse::<f64>().unwrap() * scale).round() as i32;
                wire::encode_frame(&mut out, header, 0x10, app_id, raw as u32);
            }
            t => panic!("unexpected type {t}"),
        }
    }
    out
}

/// "Varjo" in the sample is a scanning error for "Vario" (see fixtures/README.md).
fn unscan(s: &str) -> &str {
    if s == "Varjo" { "Vario" } else { s }
}

#[test]
fn committed_sample_bin_matches_the_encoder() {
    let bytes = encode_sample();
    let path = fixture("sport-sample.bin");
    if std::env::var_os("BUSNOOP_REGENERATE").is_some() {
        std::fs::write(&path, &bytes).unwrap();
    }
    assert_eq!(
        std::fs::read(&path).unwrap(),
        bytes,
        "run with BUSNOOP_REGENERATE=1 to rewrite"
    );
}

#[test]
fn decodes_to_the_sample_rows() {
    let sample = read_tsv("sport-snoop-sample.tsv");
    let rows = sport_rows(&encode_sample());
    assert_eq!(rows.len(), sample.len());
    let first_millis: u64 = sample[0]["Millis"].parse().unwrap();
    for (i, (want, got)) in sample.iter().zip(&rows).enumerate() {
        let ctx = format!("sample line {}", want["Counter"]);
        // Millis: 12 ms per poll slot from 0, so the sample's offsets.
        let millis: u64 = want["Millis"].parse().unwrap();
        assert_eq!(got.millis(), Some(millis - first_millis), "{ctx}");
        assert_eq!(got.millis(), Some(12 * i as u64), "{ctx}");
        assert_eq!(got.id, Some(want["ID"].parse().unwrap()), "{ctx}");
        // Devices: the sample names IDs 0-4; busnoop also names the other default devices
        // (docs/sport.md), which the sample leaves blank.
        let id: u8 = want["ID"].parse().unwrap();
        if want["Device"].is_empty() {
            assert_eq!(got.device, busnoop::sport::names::device(id), "{ctx}");
        } else {
            assert_eq!(got.device, unscan(&want["Device"]), "{ctx}");
        }
        assert_eq!(got.kind, want["Type"], "{ctx}");
        // The sample writes the app ID in hex without prefix or leading zeros (`210`); busnoop
        // writes every hex number as `0x` and the wire's digits (`0x0210`, docs/sport.md): the
        // same number, compared by value.
        if want["Sensor #"].is_empty() {
            assert_eq!(got.sensor_no, "", "{ctx}");
        } else {
            let w = u16::from_str_radix(&want["Sensor #"], 16).unwrap();
            let g = got.sensor_no.strip_prefix("0x").unwrap();
            assert_eq!(g.len(), 4, "{ctx}: {}", got.sensor_no);
            assert_eq!(u16::from_str_radix(g, 16).unwrap(), w, "{ctx}");
        }
        assert_eq!(got.sensor, unscan(&want["Sensor"]), "{ctx}");
        if want["Data"].is_empty() {
            assert_eq!(got.data, "", "{ctx}");
        } else {
            let w: f64 = want["Data"].parse().unwrap();
            let g: f64 = got.data.parse().unwrap();
            assert_eq!(w, g, "{ctx}: data {} vs {}", want["Data"], got.data);
        }
    }
    // Spot checks on the exact text.
    let alt = rows.iter().find(|r| r.sensor == "Alt").unwrap();
    assert_eq!(
        (alt.sensor_no.as_str(), alt.data.as_str()),
        ("0x0100", "65.43")
    );
}

#[test]
fn cli_prints_the_sample_rows_as_tsv() {
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .args(["sport", "-f", "tsv"])
        .arg(fixture("sport-sample.bin"))
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote"
    );
    assert_eq!(lines[1], "1\t0\t26\tTemp\t\t\t\t\t\t\t");
    assert_eq!(lines[2], "2\t12\t0\tVario\tNull\t\t\t\t\t\t");
    assert_eq!(
        lines[9],
        "9\t96\t2\tFAS-40S\tData\t0x0210\tVolts\t0.00\t0.00\tV\t"
    );
    assert_eq!(
        lines[23],
        "23\t264\t0\tVario\tData\t0x0100\tAlt\t65.43\t65.43\tm\t"
    );
    assert_eq!(lines.len(), 31);
}
