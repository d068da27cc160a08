//! Unit tests of the F.Port decoder: the table mapping, both framings, resynchronisation and
//! the choice of framing.

use super::wire::*;
use super::*;
use crate::row::{Class, Collected, OwnedRow};

fn rows_of(variant: Variant, bytes: &[u8]) -> Vec<OwnedRow> {
    let mut d = decoder(Options {
        variant,
        baud: None,
    });
    let mut out = Collected::default();
    d.push(bytes, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    out.rows
}

fn frame_col(r: &OwnedRow) -> &str {
    &r.extra[1]
}

fn note(r: &OwnedRow) -> &str {
    &r.extra[2]
}

fn part<'a>(r: &'a OwnedRow, name: &str) -> &'a str {
    &r.parts.iter().find(|p| p.0 == name).unwrap().2
}

const NULL_POLL: [u8; 12] = [
    0x7E, 0x08, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF6, 0x7E,
];

#[test]
fn the_v1_null_poll_is_a_poll_of_the_flight_controller() {
    for variant in [Variant::V1, Variant::Auto] {
        let rows = rows_of(variant, &NULL_POLL);
        assert_eq!(rows.len(), 1, "{rows:?}");
        let r = &rows[0];
        assert_eq!(r.kind, "", "a poll has no Type, as in S.Port");
        assert_eq!((r.id, r.device.as_str()), (Some(27), "FC"));
        assert_eq!(frame_col(r), "Downlink");
        assert_eq!(r.class, Class::Plain);
        assert_eq!(r.raw, NULL_POLL);
        assert!(r.parts.is_empty() && r.sensor.is_empty() && r.data.is_empty());
    }
}

fn channels() -> [u16; 16] {
    let mut ch = [992u16; 16];
    ch[0] = 172;
    ch[1] = 1811;
    ch[2] = 200;
    ch[3] = 1000;
    ch[4] = 1800;
    ch[5] = 993;
    ch
}

#[test]
fn a_control_frame_shows_channels_in_microseconds_and_flags_as_parts() {
    let mut bytes = Vec::new();
    encode_v1_control(&mut bytes, &channels(), FLAG_FRAME_LOST | FLAG_CH18, 87);
    let rows = rows_of(Variant::V1, &bytes);
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    assert_eq!(
        (r.kind.as_str(), r.device.as_str(), r.sensor.as_str()),
        ("Control", "Receiver", "Channels")
    );
    assert_eq!(r.id, None);
    assert_eq!(r.class, Class::Warning, "frame lost");
    // Betaflight's scale 5/8 x + 880: 200 -> 1005, 1000 -> 1505, 1800 -> 2005, exactly.
    assert_eq!(part(r, "CH1"), "987.5");
    assert_eq!(part(r, "CH2"), "2011.875");
    assert_eq!(part(r, "CH3"), "1005");
    assert_eq!(part(r, "CH4"), "1505");
    assert_eq!(part(r, "CH5"), "2005");
    assert_eq!(part(r, "CH6"), "1500.625");
    assert_eq!(part(r, "CH16"), "1500");
    assert_eq!(r.value(), "987.5");
    assert_eq!(r.parts[0].1, "µs");
    assert_eq!(
        [
            part(r, "CH17"),
            part(r, "CH18"),
            part(r, "FrameLost"),
            part(r, "Failsafe"),
            part(r, "RSSI")
        ],
        ["0", "1", "1", "0", "87"]
    );
    assert_eq!(r.parts.len(), 21);
    // Data: the first 8 channels in whole µs, as Betaflight shows them.
    assert_eq!(r.data, "987 2011 1005 1505 2005 1500 1500 1500 …");
    assert!(
        note(r).starts_with("flags 0x06: CH18, frame lost; raw 172 1811 200 1000 1800 993 992"),
        "{}",
        note(r)
    );
    assert_eq!(r.extra[0], "µs");
}

#[test]
fn f_port_2_control_frames_of_8_16_and_24_channels_and_ota() {
    let ch: Vec<u16> = (0..24).map(|i| 172 + 60 * i).collect();
    let mut bytes = Vec::new();
    for n in [8, 16, 24] {
        encode_v2_control(&mut bytes, &ch[..n], FLAG_FAILSAFE, 50);
    }
    encode_v2(&mut bytes, V2_CONTROL_16, OTA_START, &[2, 3].repeat(12));
    encode_v2(&mut bytes, V2_OTA_LEN, OTA_DATA, &[0xAB; 32]);
    encode_v2(&mut bytes, V2_CONTROL_16, OTA_STOP, &[0; 24]);
    let rows = rows_of(Variant::V2, &bytes);
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(
        kinds,
        [
            "Control", "Control", "Control", "OtaStart", "OtaData", "OtaStop"
        ]
    );
    for (r, n) in rows.iter().zip([8, 16, 24]) {
        let chans = r.parts.iter().filter(|p| p.1 == "µs").count();
        assert_eq!(chans, n);
        assert_eq!(part(r, &format!("CH{n}")), {
            let raw = 172 + 60 * (n as i64 - 1);
            let milli = raw * 625 + 880_000;
            let mut s = format!("{}.{:03}", milli / 1000, milli % 1000);
            while s.ends_with('0') {
                s.pop();
            }
            s.trim_end_matches('.').to_owned()
        });
        assert_eq!(part(r, "Failsafe"), "1");
        assert_eq!(r.class, Class::Warning);
    }
    // 24 channels: CH17 and CH18 are channels, the flag bits are not parts.
    assert_eq!(rows[2].parts.len(), 27);
    assert!(rows.iter().all(|r| !r.kind.is_empty()));
    assert!(note(&rows[3]).contains("answer delay 200 µs, answer time 300 µs"));
    assert_eq!(rows[4].data, ["AB"; 32].join(" "));
    assert!(
        rows[3..]
            .iter()
            .all(|r| r.sensor == "OTA" && r.class == Class::Plain)
    );
}

/// An S.Port data frame inside F.Port 2: the physical ID byte names the device, and the
/// Sensor, Data, Value and Unit are S.Port's.
#[test]
fn f_port_2_telemetry_after_a_control_frame() {
    let mut bytes = Vec::new();
    encode_v2_control(&mut bytes, &[992; 16], 0, 100);
    encode_v2_telemetry(&mut bytes, 0x1B, &[0; 7]);
    encode_v2_telemetry(&mut bytes, 0x1B, &payload(0x10, 0x0210, 1680));
    let rows = rows_of(Variant::V2, &bytes);
    assert_eq!(rows.len(), 3);
    let (poll, answer) = (&rows[1], &rows[2]);
    assert_eq!((poll.kind.as_str(), frame_col(poll)), ("", "Downlink"));
    assert_eq!((poll.id, poll.device.as_str()), (Some(27), "FC"));
    assert_eq!(
        (
            answer.kind.as_str(),
            frame_col(answer),
            answer.sensor_no.as_str(),
            answer.sensor.as_str(),
            answer.value(),
            answer.extra[0].as_str()
        ),
        ("Data", "Uplink", "0x0210", "Volts", "16.80", "V")
    );
}

#[test]
fn a_bad_frame_is_flagged_and_the_next_one_is_kept() {
    // F.Port v1: a corrupted control frame, then a good poll.
    let mut bytes = Vec::new();
    encode_v1_control(&mut bytes, &channels(), 0, 100);
    bytes[5] ^= 0x01;
    bytes.extend_from_slice(&NULL_POLL);
    let rows = rows_of(Variant::V1, &bytes);
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(kinds, ["BadCRC", ""]);
    assert_eq!(rows[1].raw, NULL_POLL);
    assert!(note(&rows[0]).contains("(control frame)"), "{rows:?}");

    // F.Port 2: a bad control frame, then a good downlink.
    let mut bytes = Vec::new();
    encode_v2_control(&mut bytes, &[992; 16], 0, 100);
    bytes[7] ^= 0x10;
    let good = bytes.len();
    encode_v2_telemetry(&mut bytes, 0x1B, &[0; 7]);
    let rows = rows_of(Variant::V2, &bytes);
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(kinds, ["BadCRC", ""]);
    assert_eq!(rows[1].raw, &bytes[good..]);
    assert_eq!(frame_col(&rows[1]), "Downlink");
}

#[test]
fn a_cut_frame_is_truncated_and_the_next_one_is_kept() {
    // F.Port v1: a control frame cut after 10 bytes by the next frame's 0x7E.
    let mut full = Vec::new();
    encode_v1_control(&mut full, &channels(), 0, 100);
    let mut bytes = full[..10].to_vec();
    bytes.extend_from_slice(&NULL_POLL);
    let rows = rows_of(Variant::V1, &bytes);
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(kinds, ["Truncated", ""], "{rows:?}");
    assert_eq!(rows[0].raw, &full[..10]);
    assert_eq!(rows[1].raw, NULL_POLL);

    // F.Port 2: a control frame cut after 12 bytes, then a whole control frame and a
    // downlink: the whole frame starts inside the cut one's length and is found there.
    let mut full = Vec::new();
    encode_v2_control(&mut full, &[992; 16], 0, 100);
    let mut bytes = full[..12].to_vec();
    bytes.extend_from_slice(&full);
    encode_v2_telemetry(&mut bytes, 0x1B, &[0; 7]);
    let rows = rows_of(Variant::V2, &bytes);
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(kinds, ["Truncated", "Control", ""], "{rows:?}");
    assert_eq!(rows[0].raw, &full[..12]);
    assert_eq!(rows[1].raw, full);

    // Cut by the end of the input.
    let rows = rows_of(Variant::V2, &full[..20]);
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0].kind, "Truncated");
    assert!(note(&rows[0]).contains("20 of 27 bytes"), "{rows:?}");
}

#[test]
fn garbage_is_shown_and_every_byte_is_in_one_row() {
    let mut bytes = vec![0x55, 0xAA, 0x00];
    bytes.extend_from_slice(&NULL_POLL);
    bytes.extend_from_slice(&[0x13, 0x37]);
    let rows = rows_of(Variant::V1, &bytes);
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    // 0x13 0x37 follow a frame but are no frame start: garbage up to the end.
    assert_eq!(kinds, ["Garbage", "", "Garbage"], "{rows:?}");
    let total: usize = rows.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, bytes.len());
    let rows = rows_of(Variant::V2, &bytes);
    let total: usize = rows.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, bytes.len());
    assert!(rows.iter().all(|r| r.kind == "Garbage"));
}

/// Betaflight and ArduPilot answer without delimiters, ArduPilot optionally after a 0xFF pad;
/// the PDF has the sender put 0x7E on both ends. Each reading gives the same rows.
#[test]
fn v1_answers_with_and_without_delimiters() {
    let answer = payload(0x10, 0x0700, 20);
    let mut delimited = Vec::new();
    encode_v1_telemetry(&mut delimited, V1_UPLINK, &answer);
    let bare = &delimited[1..delimited.len() - 1];
    for (tail, pad) in [
        (delimited.clone(), false),
        (bare.to_vec(), false),
        ([&[0xFF], bare].concat(), true),
    ] {
        let mut bytes = NULL_POLL.to_vec();
        bytes.extend_from_slice(&tail);
        bytes.extend_from_slice(&NULL_POLL);
        let rows = rows_of(Variant::V1, &bytes);
        let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
        assert_eq!(kinds, ["", "Data", ""], "{rows:?}");
        let a = &rows[1];
        assert_eq!(frame_col(a), "Uplink");
        assert_eq!((a.sensor.as_str(), a.value()), ("AccX", "0.20"));
        assert_eq!(a.raw, tail);
        assert_eq!(note(a).contains("pad"), pad);
        let total: usize = rows.iter().map(|r| r.raw.len()).sum();
        assert_eq!(total, bytes.len());
    }
}

/// v1 stuffing: bytes 0x7E and 0x7D inside a frame travel as 7D 5E / 7D 5D.
#[test]
fn v1_unstuffs() {
    let p = payload(0x10, 0x7E7D, 0x7D7E_7E7D);
    let mut bytes = Vec::new();
    encode_v1_telemetry(&mut bytes, V1_UPLINK, &p);
    assert!(bytes.len() > 12);
    let rows = rows_of(Variant::V1, &bytes);
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0].sensor_no, "0x7E7D");
    assert_eq!(rows[0].class, Class::Plain, "{rows:?}");
}

#[test]
fn auto_chooses_the_framing() {
    let mut v1 = Vec::new();
    let mut v2 = Vec::new();
    for i in 0..6u16 {
        let mut ch = [992u16; 16];
        ch[0] = 172 + i;
        encode_v1_control(&mut v1, &ch, 0, 100);
        v1.extend_from_slice(&NULL_POLL);
        encode_v2_control(&mut v2, &ch, 0, 100);
        encode_v2_telemetry(&mut v2, 0x1B, &[0; 7]);
    }
    for (bytes, framing, fixed) in [
        (&v1, Framing::V1, Variant::V1),
        (&v2, Framing::V2, Variant::V2),
    ] {
        let mut d = FportDecoder::new(Options::default());
        let mut out = Collected::default();
        for c in bytes.chunks(5) {
            d.push(c, None, &mut out).unwrap();
        }
        d.finish(&mut out).unwrap();
        assert!(matches!(d.chosen(), Some((f, Reason::Locked { .. })) if f == framing));
        assert_eq!(out.rows, rows_of(fixed, bytes));
        assert_eq!(out.rows.len(), 12);
    }
}

/// The S.Port sample (polls and frames with 7E framing) is no F.Port; F.Port v1 and F.Port 2
/// traffic is.
#[test]
fn evidence_tells_f_port_from_s_port() {
    let sport = include_bytes!("../../fixtures/sport-sample.bin");
    let e = detect::evidence(sport);
    assert_eq!((e.v1_frames, e.v2_frames), (0, 0), "{e:?}");
    assert!(e.share() < 0.01);
    let mut v1 = Vec::new();
    let mut v2 = Vec::new();
    for _ in 0..4 {
        encode_v1_control(&mut v1, &channels(), 0, 100);
        v1.extend_from_slice(&NULL_POLL);
        encode_v2_control(&mut v2, &channels(), 0, 100);
        encode_v2_telemetry(&mut v2, 0x1B, &[0; 7]);
    }
    let e = detect::evidence(&v1);
    assert_eq!(e.framing(), Some(Framing::V1));
    assert_eq!(e.share(), 1.0);
    let e = detect::evidence(&v2);
    assert_eq!(e.framing(), Some(Framing::V2));
    assert_eq!(e.share(), 1.0);
}

#[test]
fn stats_count_frames_per_kind_and_phys() {
    let mut bytes = Vec::new();
    encode_v2_control(&mut bytes, &[992; 16], FLAG_FAILSAFE, 40);
    encode_v2_telemetry(&mut bytes, 0x1B, &[0; 7]);
    encode_v2_telemetry(&mut bytes, 0x1B, &payload(0x10, 0x0210, 1680));
    bytes.extend_from_slice(&[0x00, 0x01]);
    encode_v2_control(&mut bytes, &[992; 8], 0, 60);
    let mut d = FportDecoder::new(Options {
        variant: Variant::V2,
        baud: None,
    });
    let mut out = Collected::default();
    d.push(&bytes, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    let text = d.stats().to_string();
    assert!(text.contains("variant: F.Port 2 (--variant)"), "{text}");
    assert!(
        text.contains("control frames 2 (8 channels 1, 16 channels 1"),
        "{text}"
    );
    assert!(text.contains("failsafe 1, RSSI 40-60"), "{text}");
    assert!(text.contains("resyncs 1"), "{text}");
    let fc = text.lines().find(|l| l.contains("FC")).unwrap();
    let cells: Vec<&str> = fc.split_whitespace().collect();
    assert_eq!(cells, ["27", "FC", "1", "0", "1", "1", "0", "0"], "{text}");
    let p = d.problems().line().unwrap();
    assert!(p.starts_with("F.Port 2: 2 garbage bytes"), "{p}");
    assert!(p.ends_with("in 4 valid frames"), "{p}");
}
