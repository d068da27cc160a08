//! The generated CRSF and GHST fixtures (`tools/crsf_gen.py`, written from the protocol texts)
//! against the decoder: every row's kind, length, time, type and numbers as the generator's own
//! reading of the resync rule and its own scaling say.

mod common;

use busnoop::protocol::Decoder;
use common::decode;

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(format!("{}/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn check(name: &str, mut decoder: Box<dyn Decoder>, baud: u64) {
    let data = fixture(&format!("{name}.bin"));
    let expect = String::from_utf8(fixture(&format!("{name}.expect.tsv"))).unwrap();
    let rows = decode(&mut *decoder, [(&data[..], None)]);
    let lines: Vec<&str> = expect.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(rows.len(), lines.len(), "{name}: rows");
    let mut numbers = 0;
    for (row, line) in rows.iter().zip(&lines) {
        let f: Vec<&str> = line.split('\t').collect();
        let (offset, len, kind, ty, tname, parts) = (f[0], f[1], f[2], f[3], f[4], f[5]);
        let offset: u64 = offset.parse().unwrap();
        let at = format!("{name} at {offset}: {row:?}");
        assert_eq!(row.raw.len(), len.parse::<usize>().unwrap(), "{at}");
        assert_eq!(row.micros, Some(offset * 10_000_000 / baud), "{at}");
        match kind {
            "Frame" => {
                if !tname.is_empty() {
                    assert_eq!(row.kind, tname, "{at}");
                }
                assert_eq!(row.sensor_no, ty, "{at}");
            }
            "BadCRC" => assert_eq!((row.kind.as_str(), row.sensor_no.as_str()), ("BadCRC", ty)),
            _ => assert_eq!(row.kind, kind, "{at}"),
        }
        if !parts.is_empty() {
            let got: Vec<String> = row
                .parts
                .iter()
                .map(|(n, _, t)| format!("{n}={t}"))
                .collect();
            assert_eq!(got.join(" "), parts, "{at}");
            numbers += 1;
        }
    }
    assert!(
        numbers > 50,
        "{name}: only {numbers} rows with numbers checked"
    );
}

#[test]
fn crsf_mixed_traffic() {
    check(
        "crsf-mixed",
        busnoop::crsf::decoder(Default::default()),
        420_000,
    );
}

#[test]
fn crsf_each_direction() {
    check(
        "crsf-rx-to-fc",
        busnoop::crsf::decoder(Default::default()),
        420_000,
    );
    check(
        "crsf-fc-to-rx",
        busnoop::crsf::decoder(Default::default()),
        420_000,
    );
}

#[test]
fn ghst_mixed_traffic() {
    check(
        "ghst-mixed",
        busnoop::ghst::decoder(Default::default()),
        420_000,
    );
}

/// Time of raw captures follows `--baud`: at 115200 (the radio's mirror) a byte takes 86.8 µs.
#[test]
fn time_follows_the_baud_rate() {
    let data = fixture("crsf-fc-to-rx.bin");
    let mut d = busnoop::crsf::decoder(busnoop::crsf::Options {
        line: busnoop::protocol::Line::n81(115_200),
    });
    let rows = decode(&mut *d, [(&data[..], None)]);
    let last = rows.last().unwrap();
    let offset = (data.len() - last.raw.len()) as u64;
    assert_eq!(last.micros, Some(offset * 10_000_000 / 115_200));
}
