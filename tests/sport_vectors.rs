//! Every row of the S.Port test vectors (fixtures/sport-vectors*.tsv) decodes as listed.

mod common;

use busnoop::fmt::parse_hex;
use busnoop::row::Class;
use busnoop::row::OwnedRow;
use common::{read_tsv, sport_rows};

/// EdgeTX's labels in the canonical decode → busnoop's Sensor column (the sample's names).
fn label(canonical: &str) -> &str {
    match canonical {
        "VFAS" => "Volts",
        "Curr" => "Amps",
        "VSpd" => "Vario",
        "SWR(RAS)" => "SWR",
        other => other,
    }
}

/// The canonical one-line decode of `vectors/README.md`, rebuilt from a busnoop row, for the
/// categories where the two describe the same thing.
/// The vectors give cells as EdgeTX keeps them (`raw / 5` hundredths); busnoop shows the wire's
/// 2 mV steps (`4.122`). Turns busnoop's `name=4.122` back into the radio's `name=4.12`.
/// The vectors name a cell by its 0-based wire index (`cell0`, `idx0`); busnoop's Data numbers
/// cells from 1 as the radio does (`cell1`).
fn radio_cell(part: &str) -> String {
    let (name, v) = part.split_once('=').unwrap();
    let digits = name.trim_start_matches(|c: char| c.is_ascii_alphabetic());
    let name = match digits.parse::<u32>() {
        Ok(n) => format!("{}{}", &name[..name.len() - digits.len()], n - 1),
        Err(_) => name.to_owned(),
    };
    let mv: u32 = v.replace('.', "").parse().unwrap();
    let hundredths = mv / 2 / 5;
    format!("{name}={}.{:02}", hundredths / 100, hundredths % 100)
}

fn canonical(row: &OwnedRow, app_id: u16, value: u32) -> String {
    let unit = row.extra[0].as_str();
    match row.kind.as_str() {
        "Null" => format!("empty appid=0x{app_id:04X} value=0x{value:08X}"),
        "MaintOff" => format!("cfg-0x20 appid=0x{app_id:04X} value=0x{value:08X}"),
        "MaintOn" => format!("cfg-0x21 appid=0x{app_id:04X} value=0x{value:08X}"),
        "Read" => format!("req-0x30 appid=0x{app_id:04X} value=0x{value:08X}"),
        "Write" => format!("write-0x31 appid=0x{app_id:04X} value=0x{value:08X}"),
        "Reply" => format!("resp-0x32 appid=0x{app_id:04X} value=0x{value:08X}"),
        _ => match row.sensor.as_str() {
            "Cels" => {
                // "count=3 cell1=4.12 cell2=4.14" + unit V → "Cels count=3 cell0=4.12V cell1=4.14V"
                let parts: Vec<String> = row
                    .data
                    .split(' ')
                    .map(|p| {
                        if p.starts_with("cell") {
                            format!("{}{unit}", radio_cell(p))
                        } else {
                            p.to_string()
                        }
                    })
                    .collect();
                format!("Cels {}", parts.join(" "))
            }
            // busnoop rounds to 1e-7 degree, the vectors truncate to 1e-6: dropping the last
            // digit gives the same (a wire step is 1/600000 degree, never close to the boundary).
            "GPS" => format!("GPS {} {unit}", &row.data[..row.data.len() - 1]),
            "Hub Cell" => format!("hub Cell {}{unit}", radio_cell(&row.data)),
            s if s.starts_with("Hub ") => format!("hub id=0x{app_id:02X} v16={}", row.data),
            "A1" | "A2" | "RxBt" => {
                // The vectors give the raw byte and EdgeTX's one-decimal display; busnoop shows two
                // decimals as the radio's CSV log does. Both come from the same raw byte.
                let raw = value & 0xFF;
                let tenths = (132 * raw + 122) / 255;
                format!(
                    "{} raw={raw} ({}.{}V @13.2 ratio)",
                    row.sensor,
                    tenths / 10,
                    tenths % 10
                )
            }
            _ if unit.is_empty() => format!("{}={}", row.sensor, row.data),
            _ => format!("{}={} {unit}", row.sensor, row.data),
        },
    }
}

fn check_file(name: &str, crc_valid: bool) -> usize {
    let mut checked = 0;
    for v in read_tsv(name) {
        let wire = parse_hex(&v["hex_bytes_on_wire"]).unwrap();
        let ctx = format!("{name}: {}", v["hex_bytes_on_wire"]);
        let rows = sport_rows(&wire);
        assert_eq!(rows.len(), 1, "{ctx}: {rows:?}");
        let row = &rows[0];
        assert_eq!(row.raw, wire, "{ctx}: Raw is the slot as on the wire");
        let phys: u32 = v["expected_physical_id"].parse().unwrap();
        assert_eq!(row.id, Some(phys), "{ctx}");
        let note = &row.extra[1];
        let check_bits_ok = busnoop::sport::wire::header_ok(wire[1]);
        assert_eq!(
            note.contains("non-standard check bits"),
            !check_bits_ok,
            "{ctx}: {note}"
        );
        if v["expected_frame_type"] == "poll" {
            assert_eq!(row.kind, "", "{ctx}");
            assert_eq!(row.class, Class::Plain, "{ctx}");
            assert_eq!(
                v["expected_decoded"].split(" | ").next().unwrap(),
                format!("poll phys={phys}")
            );
            checked += 1;
            continue;
        }
        let app_id =
            u16::from_str_radix(v["expected_app_id_hex"].trim_start_matches("0x"), 16).unwrap();
        let value =
            u32::from_str_radix(v["expected_raw_value"].trim_start_matches("0x"), 16).unwrap();
        let frame_type =
            u8::from_str_radix(v["expected_frame_type"].trim_start_matches("0x"), 16).unwrap();
        if crc_valid {
            assert_ne!(row.kind, "BadCRC", "{ctx}");
            let want_type = busnoop::sport::names::frame_type(frame_type).unwrap();
            assert_eq!(row.kind, want_type, "{ctx}");
        } else {
            assert_eq!(row.kind, "BadCRC", "{ctx}");
            assert_eq!(row.class, Class::Error, "{ctx}");
            assert!(note.contains("CRC 0xFF, expected"), "{ctx}: {note}");
        }
        if frame_type == 0x10 || app_id != 0 {
            assert_eq!(row.sensor_no, format!("0x{app_id:04X}"), "{ctx}");
        }
        let expected = v["expected_decoded"].split(" | ").next().unwrap().trim();
        if expected.is_empty() {
            // The unit-test frame without a published decode: app ID 0x0010 is a legacy hub ID.
            assert_eq!(row.data, (value & 0xFFFF).to_string(), "{ctx}");
        } else if crc_valid {
            let got = canonical(row, app_id, value);
            let want = match expected.split_once('=') {
                Some((l, rest)) if !l.contains(' ') => format!("{}={rest}", label(l)),
                _ => expected.to_string(),
            };
            assert_eq!(got, want, "{ctx}");
        } else {
            // Bad-CRC frames are still decoded (type Data in these vectors).
            let mut fake = row.clone();
            fake.kind = "Data".into();
            let got = canonical(&fake, app_id, value);
            let want = match expected.split_once('=') {
                Some((l, rest)) if !l.contains(' ') => format!("{}={rest}", label(l)),
                _ => expected.to_string(),
            };
            assert_eq!(got, want, "{ctx}");
        }
        checked += 1;
    }
    checked
}

#[test]
fn valid_vectors_decode_as_listed() {
    assert_eq!(check_file("sport-vectors.tsv", true), 94);
}

#[test]
fn invalid_crc_vectors_are_flagged() {
    assert_eq!(check_file("sport-vectors-crc-invalid.tsv", false), 14);
}

#[test]
fn all_vectors_in_one_stream_give_one_row_each() {
    let mut stream = Vec::new();
    let mut n = 0;
    for name in ["sport-vectors.tsv", "sport-vectors-crc-invalid.tsv"] {
        for v in read_tsv(name) {
            stream.extend(parse_hex(&v["hex_bytes_on_wire"]).unwrap());
            n += 1;
        }
    }
    let rows = sport_rows(&stream);
    assert_eq!(rows.len(), n);
    assert_eq!(rows.iter().filter(|r| r.kind == "BadCRC").count(), 14);
    assert!(
        rows.iter()
            .all(|r| r.kind != "Garbage" && r.kind != "Truncated")
    );
}
