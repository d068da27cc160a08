use super::*;
use crate::row::{Collected, OwnedRow};

fn fixture(name: &str) -> Vec<u8> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name);
    std::fs::read(p).unwrap()
}

fn rows_of(pieces: &[&[u8]]) -> Vec<OwnedRow> {
    let mut d = LogDecoder::default();
    let mut out = Collected::default();
    for p in pieces {
        d.push(p, None, &mut out).unwrap();
    }
    d.finish(&mut out).unwrap();
    out.rows
}

fn rows(bytes: &[u8]) -> Vec<OwnedRow> {
    rows_of(&[bytes])
}

fn part<'a>(r: &'a OwnedRow, name: &str) -> Option<(&'a str, &'a str)> {
    r.parts
        .iter()
        .find(|p| p.0 == name)
        .map(|p| (p.1.as_str(), p.2.as_str()))
}

#[test]
fn the_radios_csv_of_the_flight() {
    let bytes = fixture("edgetx-MODELE24-2014-07-11.csv");
    let rows = rows(&bytes);
    // 76 lines after the header, each one row; every byte in exactly one row.
    assert_eq!(rows.len(), 76);
    assert_eq!(rows.iter().map(|r| r.raw.len()).sum::<usize>(), bytes.len());
    assert!(rows.iter().all(|r| r.kind == LOG_TYPE));
    assert_eq!(rows[0].millis(), Some(0));
    assert_eq!(rows[1].millis(), Some(200));
    // The values the fixture's README names: cells 4.12/4.14/4.20 V, RSSI 89-91, A1 5.07 V.
    let with_cells = rows
        .iter()
        .find(|r| part(r, "Cell 1").is_some_and(|(_, t)| t != "0.00"))
        .unwrap();
    assert_eq!(part(with_cells, "Cell 1").unwrap().1, "4.12");
    let rssi: Vec<f64> = rows
        .iter()
        .filter_map(|r| part(r, "RSSI"))
        .map(|(_, t)| t.parse().unwrap())
        .filter(|&v| v > 0.0)
        .collect();
    assert!(rssi.iter().all(|v| (89.0..=91.0).contains(v)), "{rssi:?}");
    assert!(rows.iter().any(|r| part(r, "A1") == Some(("", "5.07"))));
    // Text fields are in Data, not numbers.
    assert!(
        rows[0].data.starts_with("SWR=0 RSSI=0 A1=0.00"),
        "{}",
        rows[0].data
    );
    assert!(rows[0].data.contains("GPS Date=2000-00-00"));
    assert!(part(&rows[0], "GPS Date").is_none());
}

#[test]
fn units_from_the_header() {
    let text = b"Date,Time,1RSS(dB),RxBt(V),Cels(V),Mode\n\
                 2024-05-01,14:03:22.150,-71,7.9,3.95,Acro\n\
                 2024-05-01,14:03:22.350,-70,7.8,3.94,Acro\n";
    let rows = rows(text);
    assert_eq!(rows.len(), 2);
    assert_eq!(part(&rows[0], "1RSS"), Some(("dB", "-71")));
    assert_eq!(part(&rows[1], "RxBt"), Some(("V", "7.8")));
    assert_eq!(rows[1].millis(), Some(200));
    assert_eq!(rows[0].data, "1RSS=-71 RxBt=7.9 Cels=3.95 Mode=Acro");
}

#[test]
fn the_snoop_table() {
    let bytes = fixture("sport-snoop-sample.tsv");
    let rows = rows(&bytes);
    assert_eq!(rows.len(), 30);
    assert_eq!(rows.iter().map(|r| r.raw.len()).sum::<usize>(), bytes.len());
    assert_eq!(rows[0].millis(), Some(4280));
    assert_eq!(rows[0].id, Some(26));
    assert_eq!(rows[0].kind, "");
    assert_eq!(rows[1].kind, "Null");
    assert_eq!(rows[1].class, crate::row::Class::Quiet);
    let alt = rows.iter().find(|r| r.sensor == "Alt").unwrap();
    assert_eq!(alt.data, "65.43");
    assert_eq!(alt.value(), "65.43");
    assert_eq!(alt.device, "Varjo");
}

#[test]
fn busnoops_own_tsv_comes_back() {
    // The Value and Unit columns of busnoop's TSV give the number and its unit.
    let text = "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote\n\
                78\t920\t1\tFLVSS\tData\t0x0300\tCels\tcount=3 cell1=4.122\t4.122\tV\t\n";
    let rows = rows(text.as_bytes());
    assert_eq!(rows.len(), 1);
    assert_eq!(part(&rows[0], "Cels"), Some(("V", "4.122")));
    assert_eq!(rows[0].extra, ["V", ""]);
}

#[test]
fn lines_that_do_not_fit_and_what_comes_before_the_header() {
    let text = b"\xff\xfe binary\nDate,Time,RSSI\n2014-07-11,22:41:00.570,90\n1,2,3,4\n\
                 2014-07-11,bad,91\n";
    let rows = rows(text);
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(kinds, ["Garbage", "Log", "Garbage", "Garbage"]);
    assert_eq!(rows[2].data, "4 fields, the header has 3");
    assert!(rows[3].data.starts_with("no date and time"));
    assert_eq!(rows.iter().map(|r| r.raw.len()).sum::<usize>(), text.len());
    let mut d = LogDecoder::default();
    let mut sink = crate::row::Discard::default();
    d.push(text, None, &mut sink).unwrap();
    d.finish(&mut sink).unwrap();
    assert_eq!(
        d.problems().line().unwrap(),
        "telemetry log: 2 lines that do not fit the header, 10 garbage bytes skipped (1 run) in \
         1 line"
    );
}

#[test]
fn binary_input_is_garbage_in_bounded_rows() {
    let bytes = fixture("sport-sample.bin");
    let rows = rows(&bytes);
    assert!(
        rows.iter()
            .all(|r| r.kind == "Garbage" && r.raw.len() <= 64)
    );
    assert_eq!(rows.iter().map(|r| r.raw.len()).sum::<usize>(), bytes.len());
}

proptest::proptest! {
    /// The same rows however the input is split (the fixtures and noise around them).
    #[test]
    fn any_split_gives_the_same_rows(
        cuts in proptest::collection::vec(1usize..400, 1..40),
        which in 0usize..3,
        noise in proptest::collection::vec(proptest::num::u8::ANY, 0..300),
    ) {
        let mut bytes = noise.clone();
        bytes.extend(fixture(["edgetx-MODELE24-2014-07-11.csv", "sport-snoop-sample.tsv",
            "sport-sample.bin"][which]));
        bytes.extend(&noise);
        let whole = rows(&bytes);
        let singles: Vec<&[u8]> = bytes.chunks(1).collect();
        proptest::prop_assert_eq!(&rows_of(&singles), &whole);
        let mut pieces = Vec::new();
        let mut rest = &bytes[..];
        for c in cuts.iter().cycle() {
            if rest.is_empty() {
                break;
            }
            let n = (*c).min(rest.len());
            pieces.push(&rest[..n]);
            rest = &rest[n..];
        }
        proptest::prop_assert_eq!(&rows_of(&pieces), &whole);
    }
}
