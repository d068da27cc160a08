//! The iBUS decoder as a whole: rows, values against Betaflight's unit tests, statistics,
//! chunking.

use super::wire::{self, encode, encode_poll, encode_rc};
use super::*;
use crate::fmt::parse_hex;
use crate::row::{Class, Collected, OwnedRow, kind};
use proptest::prelude::*;

fn h(s: &str) -> Vec<u8> {
    parse_hex(s).unwrap()
}

fn rows_with(opts: &Options, chunks: &[&[u8]]) -> (Vec<OwnedRow>, IbusDecoder) {
    let mut d = IbusDecoder::new(opts);
    let mut out = Collected::default();
    for c in chunks {
        d.push(c, None, &mut out).unwrap();
    }
    d.finish(&mut out).unwrap();
    (out.rows, d)
}

fn rows(bytes: &[u8]) -> Vec<OwnedRow> {
    rows_with(&Options::default(), &[bytes]).0
}

/// Kind, ID, Sensor, Data, Value, unit (the Unit column) of each row.
fn cells(r: &[OwnedRow]) -> Vec<(String, Option<u32>, String, String, String, String)> {
    r.iter()
        .map(|r| {
            (
                r.kind.clone(),
                r.id,
                r.sensor.clone(),
                r.data.clone(),
                r.value().to_owned(),
                r.extra[0].clone(),
            )
        })
        .collect()
}

fn c(
    k: &str,
    id: Option<u32>,
    sensor: &str,
    data: &str,
    value: &str,
    unit: &str,
) -> (String, Option<u32>, String, String, String, String) {
    (
        k.into(),
        id,
        sensor.into(),
        data.into(),
        value.into(),
        unit.into(),
    )
}

/// Betaflight's telemetry_ibus_unittest.cc exchanges, in the order of a session: the values
/// it asserts (1.00 V, 50/59/150 °C, 0 and 100 RPM) come out in units, named by the type the
/// sensor announced.
#[test]
fn betaflight_session_decodes_to_the_asserted_values() {
    let s = h("04 81 7A FF 04 81 7A FF \
               04 91 6A FF 06 91 03 02 63 FF \
               04 92 69 FF 06 92 01 02 64 FF \
               04 93 68 FF 06 93 02 02 62 FF \
               04 A1 5A FF 06 A1 00 00 58 FF \
               04 A1 5A FF 06 A1 64 00 F4 FE \
               04 A2 59 FF 06 A2 84 03 D0 FE \
               04 A2 59 FF 06 A2 DE 03 76 FE \
               04 A2 59 FF 06 A2 6C 07 E4 FE \
               04 A3 58 FF 06 A3 00 00 56 FF \
               04 A3 58 FF 06 A3 64 00 F2 FE \
               04 96 65 FF");
    let r = rows(&s);
    assert_eq!(
        cells(&r),
        [
            c("Discover", Some(1), "", "present", "", ""),
            c("SensorType", Some(1), "ExtV", "ExtV, 2 bytes", "", ""),
            c("SensorType", Some(2), "Temp", "Temp, 2 bytes", "", ""),
            c("SensorType", Some(3), "RPM", "RPM, 2 bytes", "", ""),
            c("Measure", Some(1), "ExtV", "0.00", "0.00", "V"),
            c("Measure", Some(1), "ExtV", "1.00", "1.00", "V"),
            c("Measure", Some(2), "Temp", "50.0", "50.0", "degC"),
            c("Measure", Some(2), "Temp", "59.0", "59.0", "degC"),
            c("Measure", Some(2), "Temp", "150.0", "150.0", "degC"),
            c("Measure", Some(3), "RPM", "0", "0", "rpm"),
            c("Measure", Some(3), "RPM", "100", "100", "rpm"),
            c("", Some(6), "", "", "", ""),
        ]
    );
    // The part carries the sensor's name; Sensor # the type code; raw is poll + answer.
    assert_eq!(r[5].parts, [("ExtV".into(), "V".into(), "1.00".into())]);
    assert_eq!(r[5].sensor_no, "0x03");
    assert_eq!(r[5].raw, h("04 A1 5A FF 06 A1 64 00 F4 FE"));
    assert!(
        r[11].extra[1].contains("type query poll, no answer"),
        "{:?}",
        r[11]
    );
    assert_eq!(r[11].raw, h("04 96 65 FF"));
    let total: usize = r.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, s.len());
}

/// The daisy-chained test of the same file: base address 3, sensors at 3, 4, 5.
#[test]
fn betaflight_daisy_chain() {
    let s = h("04 83 78 FF 04 83 78 FF 04 84 77 FF 04 84 77 FF \
               04 93 68 FF 06 93 03 02 61 FF 04 94 67 FF 06 94 01 02 62 FF \
               04 95 66 FF 06 95 02 02 60 FF \
               04 A3 58 FF 06 A3 64 00 F2 FE 04 A4 57 FF 06 A4 6C 07 E2 FE \
               04 A5 56 FF 06 A5 64 00 F0 FE");
    let r = rows(&s);
    let values: Vec<(Option<u32>, &str, &str)> = r
        .iter()
        .filter(|r| r.kind == "Measure")
        .map(|r| (r.id, r.sensor.as_str(), r.value()))
        .collect();
    assert_eq!(
        values,
        [
            (Some(3), "ExtV", "1.00"),
            (Some(4), "Temp", "150.0"),
            (Some(5), "RPM", "100")
        ]
    );
}

#[test]
fn unknown_types_are_raw_and_options_can_name_them() {
    let s = h("04 A1 5A FF 06 A1 64 00 F4 FE");
    let r = rows(&s);
    assert_eq!(cells(&r), [c("Measure", Some(1), "", "0x0064", "100", "")]);
    assert_eq!(r[0].parts[0].0, "Raw");
    assert!(r[0].extra[1].contains("unknown"), "{:?}", r[0]);
    let opts = Options {
        types: vec![parse_sensor_type("1=ExtV").unwrap()],
        ..Options::default()
    };
    let (r, d) = rows_with(&opts, &[&s]);
    assert_eq!(
        cells(&r),
        [c("Measure", Some(1), "ExtV", "1.00", "1.00", "V")]
    );
    assert_eq!(d.learned(1).map(|l| l.code), Some(3));
    assert_eq!(parse_sensor_type("2=0x01"), Ok((2, 1)));
    assert_eq!(parse_sensor_type("2=temp"), Ok((2, 1)));
    assert!(parse_sensor_type("16=ExtV").is_err());
    assert!(parse_sensor_type("1=Bogus").is_err());
}

#[test]
fn rc_frames_carry_14_or_18_channels_in_microseconds() {
    let ch: Vec<u16> = (0..18).map(|i| 1000 + 50 * i).collect();
    let mut b = Vec::new();
    encode_rc(&mut b, &ch[..14]);
    encode_rc(&mut b, &ch);
    let r = rows(&b);
    assert_eq!(r.len(), 2);
    assert_eq!(r[0].kind, "Channels");
    assert_eq!(r[0].id, None);
    assert_eq!(r[0].parts.len(), 14);
    assert_eq!(r[1].parts.len(), 18);
    assert_eq!(r[1].parts[17], ("CH18".into(), "us".into(), "1850".into()));
    assert_eq!(r[0].value(), "1000");
    assert!(r[0].data.starts_with("1000 1050 1100 "));
    assert!(r[1].extra[1].contains("18 channels"));
    let (_, d) = rows_with(&Options::default(), &[&b]);
    assert_eq!((d.counters().rc_frames, d.counters().rc_18), (2, 1));
}

/// Betaflight's rx_ibus_unittest.cc frames: `20 00`, channels 1-10 = 0 … 9, checksum `B2 FF`;
/// the same with `33` high bytes and a checksum of `00 00` is rejected.
#[test]
fn betaflight_rx_unit_test_frames() {
    let good = h(
        "20 00 00 00 01 00 02 00 03 00 04 00 05 00 06 00 07 00 08 00 09 00 \
                  00 00 00 00 00 00 00 00 B2 FF",
    );
    let bad = h(
        "20 00 00 33 01 33 02 33 03 33 04 33 05 33 06 33 07 33 08 33 09 33 \
                 00 00 00 00 00 00 00 00 00 00",
    );
    let r = rows(&good);
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].kind, "Channels");
    let ten: Vec<&str> = r[0].parts[..10].iter().map(|p| p.2.as_str()).collect();
    assert_eq!(ten, ["0", "1", "2", "3", "4", "5", "6", "7", "8", "9"]);
    assert!(r[0].extra[1].contains("not 0x40"), "{:?}", r[0]);
    let r = rows(&bad);
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].kind, kind::BAD_CRC);
    assert!(r[0].extra[1].contains("(RC frame)"), "{:?}", r[0]);
}

#[test]
fn broken_frames_are_rows_with_the_sensor_address() {
    let s = h("04 A1 5A FF 06 A1 64 00 F4 00 04 81 00 00 12 04 A2");
    let (r, d) = rows_with(&Options::default(), &[&s]);
    let kinds: Vec<(&str, Option<u32>)> = r.iter().map(|r| (r.kind.as_str(), r.id)).collect();
    assert_eq!(
        kinds,
        [
            ("", Some(1)),
            (kind::BAD_CRC, Some(1)),
            (kind::BAD_CRC, Some(1)),
            (kind::GARBAGE, None),
            (kind::TRUNCATED, Some(2)),
        ]
    );
    assert!(
        r[1].extra[1].contains("checksum 0x00F4, expected 0xFEF4 (measurement answer)"),
        "{:?}",
        r[1]
    );
    assert!(r[2].extra[1].contains("discover poll"), "{:?}", r[2]);
    assert!(
        r[1..]
            .iter()
            .all(|r| r.class == Class::Error && r.parts.is_empty())
    );
    let st = d.counters();
    assert_eq!((st.bad_crc, st.truncated, st.garbage_bytes), (2, 1, 1));
    assert_eq!(
        d.problems().line().unwrap(),
        "FlySky iBUS: 2 checksum errors, 1 truncated frame, 1 garbage byte skipped (1 run) in 1 \
         valid frame"
    );
}

#[test]
fn an_answer_without_its_poll_still_decodes() {
    let s = h("06 91 03 02 63 FF 06 A1 64 00 F4 FE");
    let r = rows(&s);
    assert_eq!(r[0].kind, "SensorType");
    assert_eq!(r[1].value(), "1.00");
    assert!(r[1].extra[1].contains("answer without its poll"));
}

#[test]
fn stats_per_address() {
    let mut b = Vec::new();
    encode_poll(&mut b, 9, 2);
    encode(&mut b, 0x92, &[0x02, 0x02]);
    for v in [10u16, 20, 30] {
        encode_poll(&mut b, 0xA, 2);
        encode(&mut b, 0xA2, &v.to_le_bytes());
        encode_poll(&mut b, 0xA, 1);
    }
    let (_, d) = rows_with(&Options::default(), &[&b]);
    let text = d.stats().to_string();
    assert!(text.contains("RPM"), "{text}");
    assert!(text.contains("30 rpm"), "{text}");
    assert_eq!(d.counters().unanswered(), 3);
    assert_eq!(d.counters().per[2].answered, 4);
    assert!(d.problems().is_empty());
}

/// Sensor bus and RC traffic with damage.
fn traffic() -> impl Strategy<Value = Vec<u8>> {
    let item = prop_oneof![
        (8u8..=0xF, 0u8..16).prop_map(|(cmd, addr)| {
            let mut v = Vec::new();
            encode_poll(&mut v, cmd, addr);
            v
        }),
        (0u8..16, any::<u8>(), 1u8..=4).prop_map(|(addr, ty, size)| {
            let mut v = Vec::new();
            encode_poll(&mut v, 9, addr);
            encode(&mut v, 0x90 | addr, &[ty, size]);
            v
        }),
        (0u8..16, prop::collection::vec(any::<u8>(), 1..=4)).prop_map(|(addr, value)| {
            let mut v = Vec::new();
            encode_poll(&mut v, 0xA, addr);
            encode(&mut v, 0xA0 | addr, &value);
            v
        }),
        prop::collection::vec(0u16..0x1000, 14..=18).prop_map(|ch| {
            let mut v = Vec::new();
            encode_rc(&mut v, &ch);
            v
        }),
        prop::collection::vec(any::<u8>(), 0..40),
        prop::collection::vec(
            prop::sample::select(vec![0x04u8, 0x06, 0x08, 0x20, 0x40, 0xA1, 0xFF]),
            0..20
        ),
    ];
    prop::collection::vec(item, 0..25).prop_map(|v| v.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Whole, byte by byte and in random pieces: the same rows, every byte in exactly one row.
    #[test]
    fn chunking_never_changes_the_rows(bytes in traffic(), cuts in prop::collection::vec(1usize..70, 1..40)) {
        let opts = Options::default();
        let whole = rows_with(&opts, &[&bytes]).0;
        let singles: Vec<&[u8]> = bytes.chunks(1).collect();
        prop_assert_eq!(&rows_with(&opts, &singles).0, &whole);
        let mut pieces = Vec::new();
        let mut rest = &bytes[..];
        let mut i = 0;
        while !rest.is_empty() {
            let n = cuts[i % cuts.len()].min(rest.len());
            pieces.push(&rest[..n]);
            rest = &rest[n..];
            i += 1;
        }
        prop_assert_eq!(&rows_with(&opts, &pieces).0, &whole);
        let total: usize = whole.iter().map(|r| r.raw.len()).sum();
        prop_assert_eq!(total, bytes.len());
        // No row that is not flagged carries a frame with a wrong checksum.
        for r in &whole {
            if r.class != Class::Error {
                let first = usize::from(r.raw[0]);
                prop_assert!(wire::check_ok(&r.raw[..first]), "{:?}", r);
            }
        }
    }

    /// A good exchange after any junk is still found.
    #[test]
    fn an_exchange_after_junk_is_found(junk in prop::collection::vec(any::<u8>(), 0..80), addr in 1u8..16, v in any::<u16>()) {
        let mut b = junk;
        let mut x = Vec::new();
        encode_poll(&mut x, 0xA, addr);
        encode(&mut x, 0xA0 | addr, &v.to_le_bytes());
        b.extend(&x);
        b.extend(&x);
        let r = rows(&b);
        let last = r.last().unwrap();
        prop_assert_eq!(&last.kind, "Measure");
        prop_assert_eq!(&last.raw, &x);
    }
}
