//! The RC receiver bus fixtures (`fixtures/futaba-session.*`, `fixtures/ibus-*.*`): each `.bin`
//! was written by a generator of its own in `tools/` (Python, from the public descriptions,
//! independent of busnoop's encoders) together with a `.tsv` of the rows busnoop must print for
//! it. The decoder's rows must match the generator's, column by column, whatever the chunking.

use busnoop::protocol::Decoder;
use busnoop::row::{Collected, OwnedRow};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// The expected rows: a header line names the columns.
fn expected(name: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(fixture(name)).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split('\t')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| l.split('\t').map(String::from).collect())
        .collect();
    (head, rows)
}

fn decode(d: &mut dyn Decoder, bytes: &[u8], chunk: usize) -> Vec<OwnedRow> {
    let mut out = Collected::default();
    for c in bytes.chunks(chunk) {
        d.push(c, None, &mut out).unwrap();
    }
    d.finish(&mut out).unwrap();
    out.rows
}

/// The cell of `row` for a column of the TSV.
fn cell(r: &OwnedRow, col: &str) -> String {
    match col {
        "kind" => r.kind.clone(),
        "id" => r.id.map_or(String::new(), |i| i.to_string()),
        "sensor_no" => r.sensor_no.clone(),
        "sensor" => r.sensor.clone(),
        "data" => r.data.clone(),
        "value" => r.value().to_owned(),
        "unit" => r.extra[0].clone(),
        "raw" => busnoop::fmt::hex(&r.raw),
        c => panic!("unknown column {c}"),
    }
}

fn check(name: &str, new: &dyn Fn() -> Box<dyn Decoder>) -> Vec<OwnedRow> {
    let bytes = std::fs::read(fixture(&format!("{name}.bin"))).unwrap();
    let (head, want) = expected(&format!("{name}.tsv"));
    let rows = decode(new().as_mut(), &bytes, bytes.len().max(1));
    for chunk in [1, 7, 64] {
        assert_eq!(
            decode(new().as_mut(), &bytes, chunk),
            rows,
            "{name} in chunks of {chunk}"
        );
    }
    assert_eq!(rows.len(), want.len(), "{name}: row count");
    for (i, (r, w)) in rows.iter().zip(&want).enumerate() {
        for (col, expect) in head.iter().zip(w) {
            assert_eq!(
                &cell(r, col),
                expect,
                "{name} row {} column {col}: {r:?}",
                i + 1
            );
        }
    }
    rows
}

#[test]
fn futaba_session_matches_its_generator() {
    let rows = check("futaba-session", &|| {
        busnoop::futaba::decoder(busnoop::futaba::Options::default())
    });
    // Slots of all four groups, the receiver's slot 0, and flags.
    for n in [0, 1, 8, 15, 17, 21, 25, 29] {
        assert!(
            rows.iter().any(|r| r.kind == "Slot" && r.id == Some(n)),
            "slot {n}"
        );
    }
    assert!(
        rows.iter()
            .any(|r| r.parts.iter().any(|p| p.0 == "Failsafe" && p.2 == "1"))
    );
}

#[test]
fn ibus_sensor_session_matches_its_generator() {
    let rows = check("ibus-sensors", &|| {
        busnoop::ibus::decoder(busnoop::ibus::Options::default())
    });
    // Every measurement carries its value as a part named as the sensor (GPS: Lat).
    for r in rows.iter().filter(|r| r.kind == "Measure") {
        let name = if r.sensor == "GPS" { "Lat" } else { &r.sensor };
        assert_eq!(r.parts[0].0, name, "{r:?}");
        assert_eq!(r.parts[0].1, r.extra[0], "{r:?}");
    }
    // Betaflight's 'no value' on an external voltage is named in the Note.
    assert!(rows.iter().any(|r| r.extra[1].contains("no value")));
}

#[test]
fn ibus_rc_matches_its_generator() {
    let rows = check("ibus-rc", &|| {
        busnoop::ibus::decoder(busnoop::ibus::Options::default())
    });
    let counts: Vec<usize> = rows
        .iter()
        .filter(|r| r.kind == "Channels")
        .map(|r| r.parts.len())
        .collect();
    assert_eq!(counts.iter().filter(|&&n| n == 14).count(), 10);
    assert_eq!(counts.iter().filter(|&&n| n == 18).count(), 10);
}
