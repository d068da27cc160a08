//! The real EdgeTX capture decodes with every CRC valid, and its values match the radio's own CSV
//! log of the same flight.

mod common;

use std::collections::BTreeSet;

use busnoop::edgetx::parse_line;
use busnoop::row::OwnedRow;
use common::{decode, fixture};

fn capture_rows() -> Vec<OwnedRow> {
    let text = std::fs::read(fixture("edgetx-MODELE24-2014-07-11-sport.log")).unwrap();
    let lines: Vec<_> = text.split(|&b| b == b'\n').filter_map(parse_line).collect();
    assert_eq!(lines.len(), 592);
    let first = lines[0].time;
    let segments: Vec<(Vec<u8>, Option<u64>)> = lines
        .iter()
        .map(|l| {
            let us = (l.time - first).num_microseconds().unwrap() as u64;
            (l.bytes.clone(), Some(us))
        })
        .collect();
    let mut d = busnoop::sport::SportDecoder::new();
    decode(&mut d, segments.iter().map(|(b, t)| (b.as_slice(), *t)))
}

/// Distinct non-zero values of a column of the radio's CSV log.
fn csv_values(column: &str) -> BTreeSet<String> {
    let mut r = csv::Reader::from_path(fixture("edgetx-MODELE24-2014-07-11.csv")).unwrap();
    let idx = r
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == column)
        .unwrap();
    r.records()
        .map(|rec| rec.unwrap()[idx].trim().to_string())
        .filter(|v| v.parse::<f64>().unwrap() != 0.0)
        .collect()
}

fn values(rows: &[OwnedRow], sensor: &str) -> BTreeSet<String> {
    rows.iter()
        .filter(|r| r.sensor == sensor)
        .map(|r| r.data.clone())
        .filter(|v| v.parse::<f64>().unwrap() != 0.0)
        .collect()
}

#[test]
fn every_crc_is_valid_and_nothing_is_lost() {
    let rows = capture_rows();
    assert_eq!(
        rows.len(),
        592,
        "one row per poll slot (one slot per log line)"
    );
    for r in &rows {
        assert!(
            !matches!(
                r.kind.as_str(),
                "BadCRC" | "Truncated" | "Garbage" | "Unknown"
            ),
            "{r:?}"
        );
        assert!(r.extra[1].is_empty(), "no notes expected: {r:?}");
    }
    assert_eq!(rows.iter().filter(|r| r.kind == "Data").count(), 131);
    // Millis counts from the first line; the log's lines are 10 ms apart (sometimes 20).
    assert_eq!(rows[0].millis(), Some(0));
    assert_eq!(rows.last().unwrap().millis(), Some(7090));
}

#[test]
fn values_match_the_radio_csv() {
    let rows = capture_rows();
    // FLVSS at physical ID 1: cells 4.12 / 4.14 / 4.20 V.
    let mut cells = BTreeSet::new();
    for r in rows
        .iter()
        .filter(|r| r.sensor == "Cels" && r.id == Some(1))
    {
        // busnoop shows the wire's 2 mV steps; the radio keeps raw / 5 hundredths (4.122 → 4.12).
        for part in r.data.split(' ').filter(|p| p.starts_with("cell")) {
            let (name, v) = part.split_once('=').unwrap();
            let mv: u32 = v.replace('.', "").parse().unwrap();
            let h = mv / 2 / 5;
            cells.insert(format!("{name}={}.{:02}", h / 100, h % 100));
        }
    }
    let want: BTreeSet<String> = [
        format!("cell1={}", csv_values("Cell 1").pop_first().unwrap()),
        format!("cell2={}", csv_values("Cell 2").pop_first().unwrap()),
        format!("cell3={}", csv_values("Cell 3").pop_first().unwrap()),
    ]
    .into();
    assert_eq!(cells, want);
    assert_eq!(
        want,
        ["cell1=4.12", "cell2=4.14", "cell3=4.20"]
            .map(String::from)
            .into()
    );
    // Receiver data (header 0x98): RSSI 89-91, SWR 16/17, and the receiver battery value the
    // 2014 radio logged in its A1 column: 5.07 V.
    assert_eq!(values(&rows, "RSSI"), csv_values("RSSI"));
    assert_eq!(
        values(&rows, "RSSI"),
        ["89", "90", "91"].map(String::from).into()
    );
    assert_eq!(values(&rows, "SWR"), csv_values("SWR"));
    assert_eq!(values(&rows, "SWR"), ["16", "17"].map(String::from).into());
    assert_eq!(values(&rows, "RxBt"), csv_values("A1"));
    assert_eq!(values(&rows, "RxBt"), ["5.07"].map(String::from).into());
    // The second FLVSS (moved to physical ID 8) reads 4.13 V or the faulty 0.04 V.
    let mut second = BTreeSet::new();
    for r in rows
        .iter()
        .filter(|r| r.sensor == "Cels" && r.id == Some(8))
    {
        for part in r.data.split(' ').filter(|p| p.starts_with("cell")) {
            second.insert(part.split('=').nth(1).unwrap().to_string());
        }
    }
    // At full wire precision: 4.130 and 4.138 V (the radio keeps 4.13 for both) and 0.042 V.
    assert_eq!(second, ["0.042", "4.130", "4.138"].map(String::from).into());
}
