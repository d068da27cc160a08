//! Decoder tests: every frame type against the public vectors' asserted values (Betaflight
//! `rx_crsf_unittest.cc` and `telemetry_crsf_unittest.cc`, EdgeTX `tests/crossfire.cpp`), and
//! the frames of the TBS text built with the encoder.

use super::wire::{encode, encode_command, encode_ext};
use super::*;
use crate::fmt::parse_hex;
use crate::row::{Collected, OwnedRow};

fn h(s: &str) -> Vec<u8> {
    parse_hex(s).unwrap()
}

fn rows(data: &[u8]) -> Vec<OwnedRow> {
    let mut d = decoder(Options::default());
    let mut out = Collected::default();
    d.push(data, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    out.rows
}

fn one(data: &[u8]) -> OwnedRow {
    let r = rows(data);
    assert_eq!(r.len(), 1, "{r:#?}");
    r.into_iter().next().unwrap()
}

/// The row's parts as `name=text` (units left out).
fn parts(r: &OwnedRow) -> Vec<String> {
    r.parts.iter().map(|(n, _, t)| format!("{n}={t}")).collect()
}

fn frame(addr: u8, ty: u8, payload: &[u8]) -> Vec<u8> {
    let mut f = Vec::new();
    encode(&mut f, addr, ty, payload);
    f
}

fn ext(ty: u8, dest: u8, origin: u8, payload: &[u8]) -> Vec<u8> {
    let mut f = Vec::new();
    encode_ext(&mut f, 0xC8, ty, dest, origin, payload);
    f
}

#[test]
fn betaflight_captured_rc_frames() {
    let data = h(
        "00 18 16 BD 08 9F F4 AE F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 6C \
         00 18 16 BD 08 9F F4 AA F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 94",
    );
    let r = rows(&data);
    assert_eq!(r.len(), 2);
    let a = &r[0];
    assert_eq!(
        (
            a.id,
            a.device.as_str(),
            a.kind.as_str(),
            a.sensor_no.as_str()
        ),
        (Some(0), "Broadcast", "RC", "0x16")
    );
    assert_eq!(a.sensor, "CH1");
    assert_eq!(
        &parts(a)[..4],
        ["CH1=999", "CH2=1501", "CH3=1492", "CH4=1495"]
    );
    assert_eq!(a.parts.len(), 16);
    assert!(a.parts.iter().all(|p| p.1 == "us"));
    assert_eq!((a.value(), a.extra[0].as_str()), ("999", "us"));
    assert!(
        a.extra[1].starts_with("raw 189 993 978 983 "),
        "{}",
        a.extra[1]
    );
    assert!(a.data.starts_with("999 1501 1492 1495 "));
    // The second frame's CH4 is 981: 1493.9 µs.
    assert_eq!(parts(&r[1])[3], "CH4=1494");
    // Untimed input: the second frame starts 26 bytes in, 26 × 10 bits at 420000 baud.
    assert_eq!(r[1].micros, Some(619));
}

#[test]
fn channel_scale_of_the_contract() {
    let mut ch = [992u16; 16];
    ch[0] = 172;
    ch[1] = 1811;
    let f = frame(0xC8, 0x16, &wire::pack_bits(&ch, 11));
    let r = one(&f);
    assert_eq!(&parts(&r)[..3], ["CH1=988", "CH2=2012", "CH3=1501"]);
    assert_eq!(r.device, "FC");
}

#[test]
fn betaflight_subset_frame() {
    let r = one(&h("C8 09 17 24 00 A0 D9 E9 FF 0F D1"));
    assert_eq!(r.kind, "RCSubset");
    // Betaflight asserts 988, 1398, 1967, 2011 (its float truncated): 988 + raw / 2.
    assert_eq!(
        parts(&r),
        ["CH5=988.0", "CH6=1398.0", "CH7=1967.5", "CH8=2011.5"]
    );
    assert!(r.extra[1].contains("raw 0 820 1959 2047"), "{}", r.extra[1]);
    assert!(r.extra[1].contains("first channel CH5, 11 bits"));
}

#[test]
fn betaflight_baud_rate_negotiation() {
    let mut data = h("C8 0C 32 C8 EC 0A 70 01 00 1E 84 80 22 72");
    encode_command(&mut data, 0xC8, 0xEC, 0xC8, 0x0A, 0x71, &[1, 1]);
    let r = rows(&data);
    assert_eq!(r.len(), 2);
    assert_eq!(
        (r[0].kind.as_str(), r[0].sensor.as_str()),
        ("Command", "speed proposal")
    );
    assert_eq!((r[0].class, r[1].class), (Class::Plain, Class::Warning));
    assert!(
        r[0].extra[1].contains("from Receiver (0xEC) to FC (0xC8)"),
        "{}",
        r[0].extra[1]
    );
    assert!(r[0].extra[1].contains("baud rate change proposed: port 1 to 2000000 baud"));
    assert!(
        r[1].extra[1].contains("accepted: port 1, the line now runs at 2000000 baud"),
        "{}",
        r[1].extra[1]
    );
    // A wrong inner CRC (the frame CRC made right again) is a warning and counted.
    let mut bad = h("C8 0C 32 C8 EC 0A 70 01 00 1E 84 80 23");
    bad.push(wire::crc8(&bad[2..]));
    let mut d = decoder(Options::default());
    let mut out = Collected::default();
    d.push(&bad, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    assert_eq!(out.rows[0].class, Class::Warning);
    assert!(out.rows[0].extra[1].contains("command CRC 0x23, expected 0x22"));
    assert_eq!(
        d.problems().line().unwrap(),
        "CRSF: 1 command CRC error in 1 valid frame"
    );
}

#[test]
fn edgetx_link_statistics() {
    let r = one(&h("00 0C 14 00 00 00 00 FF 01 03 00 00 00 F4"));
    assert_eq!(r.kind, "LinkStats");
    assert_eq!(
        parts(&r),
        [
            "1RSS=0", "2RSS=0", "RQly=0", "RSNR=0", "ANT=255", "RFMD=1", "TPWR=100", "TRSS=0",
            "TQly=0", "TSNR=0"
        ]
    );
    let units: Vec<&str> = r.parts.iter().map(|p| p.1.as_str()).collect();
    assert_eq!(
        units,
        ["dBm", "dBm", "%", "dB", "", "", "mW", "dBm", "%", "dB"]
    );
    // An ExpressLRS-like frame: RSSI as dBm × -1, negative SNR.
    let r = one(&frame(
        0xEA,
        0x14,
        &[62, 0xC1, 100, 0xF6, 1, 7, 2, 70, 98, 5],
    ));
    assert_eq!(
        parts(&r),
        [
            "1RSS=-62", "2RSS=-63", "RQly=100", "RSNR=-10", "ANT=1", "RFMD=7", "TPWR=25",
            "TRSS=-70", "TQly=98", "TSNR=5"
        ]
    );
}

#[test]
fn betaflight_telemetry_frames() {
    // telemetry_crsf_unittest.cc: the values its encoder writes, rebuilt with the spec's CRC.
    let mut gps = Vec::new();
    gps.extend(560_000_000i32.to_be_bytes());
    gps.extend(1_630_000_000i32.to_be_bytes());
    gps.extend(587u16.to_be_bytes());
    gps.extend(14_790u16.to_be_bytes());
    gps.extend(3_345u16.to_be_bytes());
    gps.push(9);
    let r = one(&frame(0xC8, 0x02, &gps));
    assert_eq!((r.kind.as_str(), r.sensor.as_str()), ("GPS", "GPS"));
    assert_eq!(
        parts(&r),
        [
            "Lat=56.0000000",
            "Lon=163.0000000",
            "GSpd=58.7",
            "Hdg=147.90",
            "Alt=2345",
            "Sats=9"
        ]
    );
    let units: Vec<&str> = r.parts.iter().map(|p| p.1.as_str()).collect();
    assert_eq!(units, ["deg", "deg", "km/h", "deg", "m", ""]);

    let r = one(&frame(0xC8, 0x08, &[0, 33, 1, 40, 0, 4, 210, 67]));
    assert_eq!(r.kind, "Battery");
    assert_eq!(parts(&r), ["RxBt=3.3", "Curr=29.6", "Capa=1234", "Bat%=67"]);
    assert_eq!(r.data, "RxBt=3.3V Curr=29.6A Capa=1234mAh Bat%=67%");
    assert_eq!((r.sensor.as_str(), r.extra[0].as_str()), ("RxBt", "V"));

    let mut att = Vec::new();
    for v in [11_833i16, 26_092, -31_398] {
        att.extend(v.to_be_bytes());
    }
    let r = one(&frame(0xC8, 0x1E, &att));
    assert_eq!(parts(&r), ["Ptch=1.1833", "Roll=2.6092", "Yaw=-3.1398"]);
    assert_eq!(r.extra[0], "rad");

    for (text, want) in [
        (&b"ACRO*\0"[..], "ACRO*"),
        (b"ACRO\0", "ACRO"),
        (b"STAB\0", "STAB"),
        (b"HOR\0", "HOR"),
        (b"AIR\0", "AIR"),
    ] {
        let f = frame(0xC8, 0x21, text);
        assert_eq!(f[1] as usize, text.len() + 2);
        let r = one(&f);
        assert_eq!((r.kind.as_str(), r.sensor.as_str()), ("FlightMode", "FM"));
        assert_eq!(r.data, want);
        assert!(r.parts.is_empty());
    }
}

#[test]
fn sensor_frames_of_the_tbs_text() {
    let cases: Vec<(u8, Vec<u8>, &[&str])> = vec![
        (0x07, vec![0xFF, 0x38], &["VSpd=-2.00"]),
        // Baro: 10000 + 352.2 m in dm; the TBS 3-byte and EdgeTX 4-byte vertical speeds.
        (0x09, vec![0x34, 0xD2, 0x00], &["BAlt=352.2", "VSpd=0.00"]),
        (
            0x09,
            vec![0x80, 0x64, 0x01, 0x2C],
            &["BAlt=100.0", "VSpd=3.00"],
        ),
        (0x09, vec![0x27, 0x06], &["BAlt=-1.0"]),
        (0x0A, vec![0x03, 0xE8], &["ASpd=100.0"]),
        (
            0x0C,
            vec![0, 0x00, 0x2E, 0xE0, 0xFF, 0xD1, 0x20],
            &["RPM1=12000", "RPM2=-12000"],
        ),
        (
            0x0D,
            vec![1, 0x00, 0xFA, 0xFF, 0xCE],
            &["Tmp1_1=25.0", "Tmp2_1=-5.0"],
        ),
        (
            0x0E,
            vec![0, 0x0F, 0x0A, 0x0F, 0x00],
            &["Cel1=3.850", "Cel2=3.840"],
        ),
        (0x0E, vec![128, 0x2E, 0xE0], &["Volt1_128=12.000"]),
        (
            0x10,
            vec![0xCE, 25, 0x16, 0xA8, 0b0000_1011],
            &["VPwr=25", "VFrq=5800"],
        ),
        (
            0x1C,
            vec![80, 60, 99, 7, 20],
            &["RRSS=-80", "RRSP=60", "RQly=99", "RSNR=7", "TPWR=20"],
        ),
        (
            0x1D,
            vec![75, 65, 97, 0xFE, 17, 50],
            &[
                "TRSS=-75", "TRSP=65", "TQly=97", "TSNR=-2", "RPWR=17", "TFPS=500",
            ],
        ),
    ];
    for (ty, payload, want) in cases {
        let r = one(&frame(0xC8, ty, &payload));
        assert_eq!(parts(&r), want, "type {ty:#04X}: {r:?}");
        assert_eq!(r.sensor_no, format!("0x{ty:02X}"));
        assert_eq!(r.class, Class::Plain);
    }
    let r = one(&frame(0xC8, 0x10, &[0xCE, 25, 0x16, 0xA8, 0b0000_1011]));
    assert!(
        r.extra[1].contains("from VTX (0xCE), pit mode on, control on, switch 1"),
        "{}",
        r.extra[1]
    );
    let r = one(&frame(0xC8, 0x09, &[0x34, 0xD2, 0x00]));
    assert!(r.extra[1].contains("TBS logarithmic"));
}

#[test]
fn gps_time_and_extended() {
    let mut t = Vec::new();
    t.extend(2024i16.to_be_bytes());
    t.extend([5, 1, 12, 3, 4]);
    t.extend(56u16.to_be_bytes());
    let r = one(&frame(0xC8, 0x03, &t));
    assert_eq!(
        (r.sensor.as_str(), r.data.as_str()),
        ("Date", "2024-05-01 12:03:04.056")
    );

    let mut e = vec![3];
    for v in [150i16, -20, 35, 40, 15, 412, 250, 400] {
        e.extend(v.to_be_bytes());
    }
    e.extend([0, 9, 14]);
    let r = one(&frame(0xC8, 0x06, &e));
    assert_eq!(
        parts(&r),
        [
            "Fix=3",
            "NSpd=1.50",
            "ESpd=-0.20",
            "GVSp=0.35",
            "SAcc=0.40",
            "TAcc=1.5",
            "EAlt=412",
            "HAcc=2.50",
            "VAcc=4.00",
            "HDOP=0.9",
            "VDOP=1.4"
        ]
    );
}

#[test]
fn heartbeat_mavlink_fc_and_esp_now() {
    let r = one(&frame(0xC8, 0x0B, &[0x00, 0xC8]));
    assert_eq!(r.data, "from FC (0xC8)");
    let mut m = vec![0x01, 0x2C, 0x81];
    m.extend(5u32.to_be_bytes());
    m.extend([3, 1]);
    let r = one(&frame(0xC8, 0x1F, &m));
    assert_eq!(
        r.data,
        "airspeed=300 base_mode=0x81 custom_mode=5 autopilot=3 type=1"
    );
    let mut e = vec![2, 7];
    e.extend(b"1:02.345\0\0\0\0\0\0\0");
    e.extend(b"0:58.100\0\0\0\0\0\0\0");
    e.extend(b"GO\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0");
    let r = one(&frame(0xC8, 0x22, &e));
    assert_eq!(r.data, "seat 2 lap 7 \"1:02.345\" \"0:58.100\" \"GO\"");
}

#[test]
fn device_frames_and_parameters() {
    let r = one(&ext(0x28, 0x00, 0xEA, &[]));
    assert_eq!((r.kind.as_str(), r.data.as_str()), ("Ping", "ping"));
    assert!(r.extra[1].contains("from Radio (0xEA) to Broadcast (0x00)"));

    let mut info = b"ELRS RX\0ELRS".to_vec();
    info.extend([0, 0, 0, 0x12, 0, 3, 4, 1, 20, 0]);
    let r = one(&ext(0x29, 0xEA, 0xEC, &info));
    assert_eq!(
        r.data,
        "\"ELRS RX\" serial ELRS hw 0x00000012 fw 3.4.1, 20 parameters, version 0"
    );

    let mut sel = vec![4, 0, 1, 9];
    sel.extend(b"Packet Rate\0");
    sel.extend(b"50Hz;150Hz;250Hz\0");
    sel.extend([2, 0, 2, 1]);
    sel.extend(b"\0");
    let r = one(&ext(0x2B, 0xEA, 0xEE, &sel));
    assert_eq!(
        r.data,
        "parameter 4 \"Packet Rate\" TEXT_SELECTION in folder 1 = \"250Hz\" of \"50Hz;150Hz;250Hz\""
    );

    // A parameter in two chunks: the second is a continuation.
    let mut data = ext(0x2B, 0xEA, 0xEE, &[7, 1, 0, 0x0C, b'V', b'e', b'r', 0]);
    data.extend(ext(0x2B, 0xEA, 0xEE, &[7, 0, b'3', b'.', b'4', 0]));
    let r = rows(&data);
    assert!(
        r[0].extra[1].contains("1 chunks to come"),
        "{}",
        r[0].extra[1]
    );
    assert_eq!(r[1].data, "parameter 7 continued: 33 2E 34 00");

    let mut fl = vec![9, 0, 0, 8];
    fl.extend(b"Gain\0");
    for v in [1234i32, 0, 5000, 1000] {
        fl.extend(v.to_be_bytes());
    }
    fl.push(2);
    fl.extend(1i32.to_be_bytes());
    fl.extend(b"dB\0");
    let r = one(&ext(0x2B, 0xEA, 0xEE, &fl));
    assert_eq!(
        r.data,
        "parameter 9 \"Gain\" FLOAT in folder 0 = 12.34 (0.00..50.00) dB"
    );

    let r = one(&ext(0x2C, 0xEE, 0xEA, &[4, 0]));
    assert_eq!(r.data, "read parameter 4 chunk 0");
    let r = one(&ext(0x2D, 0xEE, 0xEA, &[4, 2]));
    assert_eq!(r.data, "write parameter 4 value 2");
}

#[test]
fn radio_timing_game_and_logging() {
    let mut t = vec![0x10];
    t.extend(40_000u32.to_be_bytes());
    t.extend((-25i32).to_be_bytes());
    let r = one(&ext(0x3A, 0xEA, 0xEE, &t));
    assert_eq!(parts(&r), ["Intv=4000.0", "Offs=-2.5"]);
    assert_eq!((r.kind.as_str(), r.extra[0].as_str()), ("Radio", "us"));

    let r = one(&ext(0x3C, 0xC8, 0xEA, &[1, 0xFF, 0xF6]));
    assert_eq!(r.data, "add points -10");

    let mut l = Vec::new();
    l.extend(3u16.to_be_bytes());
    l.extend(1000u32.to_be_bytes());
    l.extend(7u32.to_be_bytes());
    let r = one(&frame(0xC8, 0x34, &l));
    assert_eq!(r.data, "log type 3 at 1000 7");
}

#[test]
fn msp_requests_and_responses_name_the_command() {
    // MSPv1 request MSP_STATUS: status 0x30 (start, version 1, seq 0), size 0, command 101.
    let r = one(&ext(0x7A, 0xC8, 0xEA, &[0x30, 0x00, 101]));
    assert_eq!(
        (r.kind.as_str(), r.sensor.as_str()),
        ("MSPReq", "MSP_STATUS")
    );
    assert_eq!(r.data, "MSPv1 seq 0 start cmd 101: 00 65");
    // MSPv2 response (status 0x51: start, version 2, seq 1), command 0x1001.
    let r = one(&ext(
        0x7B,
        0xEA,
        0xC8,
        &[0x51, 0x00, 0x01, 0x10, 0x02, 0x00, 0xAB, 0xCD],
    ));
    assert_eq!(
        (r.kind.as_str(), r.sensor.as_str()),
        ("MSPResp", "MSP 4097")
    );
    // A continuation chunk names no command.
    let r = one(&ext(0x7B, 0xEA, 0xC8, &[0x22, 0xAB, 0xCD]));
    assert_eq!(
        (r.sensor.as_str(), r.data.as_str()),
        ("", "MSPv1 seq 2: AB CD")
    );
}

#[test]
fn ardupilot_mlrs_and_mavlink_envelopes() {
    let mut p = vec![0xF0];
    p.extend(0x5003u16.to_le_bytes());
    p.extend(0x1234_5678u32.to_le_bytes());
    let r = one(&frame(0xC8, 0x80, &p));
    assert_eq!(r.kind, "APPassthru");
    assert_eq!(r.data, "single app 0x5003 value 305419896");
    let mut m = vec![0xF2, 2];
    for (a, v) in [(0x5000u16, 1u32), (0x5006, 2)] {
        m.extend(a.to_le_bytes());
        m.extend(v.to_le_bytes());
    }
    let r = one(&frame(0xC8, 0x80, &m));
    assert_eq!(r.data, "multi 2, app 0x5000 value 1, app 0x5006 value 2");
    let r = one(&frame(0xC8, 0x80, b"\xF1\x04PreArm: Gyros\0"));
    assert_eq!(r.data, "status text severity 4 \"PreArm: Gyros\"");
    let r = one(&frame(0xEE, 0x80, &[0x4F, 0x57, 0x01, 0x02]));
    assert_eq!(r.kind, "mLRS");

    let mut env = vec![0x21, 12];
    env.extend(h("FD 05 00 00 07 01 01 21 00 00 AA BB"));
    let r = one(&frame(0xC8, 0xAA, &env));
    assert_eq!(r.kind, "MAVLink");
    assert_eq!(
        r.data,
        "chunk 1 of 2, 12 bytes: FD 05 00 00 07 01 01 21 00 00 AA BB"
    );
    assert!(r.extra[1].contains("MAVLink 2 message 33 from system 1 component 1"));

    let mut s = Vec::new();
    for v in [0x0000_00FFu32, 0x0F, 0x0E] {
        s.extend(v.to_be_bytes());
    }
    let r = one(&frame(0xC8, 0xAC, &s));
    assert_eq!(
        r.data,
        "present=0x000000FF enabled=0x0000000F health=0x0000000E"
    );
}

#[test]
fn unknown_types_are_warnings() {
    let r = one(&frame(0xC8, 0x05, &[1, 2, 3]));
    assert_eq!((r.kind.as_str(), r.class), ("Unknown", Class::Warning));
    assert_eq!(r.data, "01 02 03");
    assert!(r.extra[1].contains("unknown frame type 0x05"));
    let r = one(&ext(0x99, 0xEA, 0xC8, &[9]));
    assert_eq!((r.kind.as_str(), r.class), ("Unknown", Class::Warning));
}

#[test]
fn error_rows() {
    let good = frame(0xC8, 0x08, &[0, 33, 1, 40, 0, 4, 210, 67]);
    let mut bad = good.clone();
    bad[4] ^= 1;
    let mut data = vec![0x11, 0x22];
    data.extend(&good);
    data.extend(&bad);
    data.extend(&good);
    data.extend(&good[..6]);
    let r = rows(&data);
    let kinds: Vec<&str> = r.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(
        kinds,
        ["Garbage", "Battery", "BadCRC", "Battery", "Truncated"]
    );
    assert_eq!((r[0].id, r[0].data.as_str()), (None, "11 22"));
    assert_eq!(r[0].extra[1], "2 bytes before the first frame");
    assert_eq!((r[2].id, r[2].sensor_no.as_str()), (Some(0xC8), "0x08"));
    assert!(r[2].parts.is_empty());
    assert!(
        r[2].extra[1].contains("(Battery frame)"),
        "{}",
        r[2].extra[1]
    );
    assert_eq!(r[4].extra[1], "6 of 12 bytes, cut by the end of the input");
    assert!(
        r.iter()
            .all(|r| r.class == Class::Error || r.kind == "Battery")
    );
    let total: usize = r.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, data.len());

    let mut d = decoder(Options::default());
    let mut out = Collected::default();
    d.push(&data, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    assert_eq!(
        d.problems().line().unwrap(),
        "CRSF: 1 CRC error, 1 truncated frame, 2 garbage bytes skipped (1 run), 1 resync \
         in 2 valid frames"
    );
    let report = d.stats().to_string();
    assert!(report.contains("0xC8  FC"), "{report}");
    assert!(report.contains("Battery"), "{report}");
    assert!(report.contains("resyncs 1"), "{report}");
}

#[test]
fn link_quality_in_the_statistics() {
    let mut data = Vec::new();
    for lq in [100u8, 90, 95] {
        data.extend(frame(0xC8, 0x14, &[60, 60, lq, 10, 0, 5, 3, 60, 100, 8]));
    }
    let mut d = decoder(Options::default());
    let mut out = Collected::default();
    d.push(&data, Some(0), &mut out).unwrap();
    d.finish(&mut out).unwrap();
    let report = d.stats().to_string();
    assert!(
        report.contains("link quality: last 95 %, min 90 %, mean 95.0 % in 3 frames"),
        "{report}"
    );
}

#[test]
fn json_lines_carry_the_contract() {
    use crate::sink::Format;
    let mut data = frame(0xC8, 0x16, &wire::pack_bits(&[172; 16], 11));
    data.extend(frame(0xC8, 0x08, &[0, 33, 1, 40, 0, 4, 210, 67]));
    data.extend([0xC8, 0x18, 0x16]);
    let mut t = crate::testing::memory_table(Format::Jsonl, false, COLUMNS);
    let mut d = decoder(Options::default());
    struct W<'a>(&'a mut crate::sink::Table);
    impl crate::row::RowOut for W<'_> {
        fn row(&mut self, row: &crate::row::Row<'_>) -> crate::row::RowResult {
            self.0.write(row)
        }
    }
    d.push(&data, None, &mut W(&mut t)).unwrap();
    d.finish(&mut W(&mut t)).unwrap();
    t.flush().unwrap();
    let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
    let lines: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines[0]["id"], 200);
    assert_eq!(lines[0]["sensor_no"], "0x16");
    assert_eq!(lines[0]["parts"]["CH1"], 988);
    assert_eq!(lines[0]["parts"]["CH16"], 988);
    assert_eq!(lines[1]["parts"]["RxBt"], 3.3);
    assert_eq!(lines[1]["parts"]["Bat%"], 67);
    assert_eq!(lines[2]["type"], "Truncated");
}

#[test]
fn stamps_never_change_the_table() {
    let mut data = frame(0xC8, 0x16, &wire::pack_bits(&[992; 16], 11));
    data.extend(crate::testing::noise(300, 4));
    data.extend(frame(0xC8, 0x14, &[60, 60, 100, 10, 0, 5, 3, 60, 100, 8]));
    let chunks: Vec<&[u8]> = data.chunks(17).collect();
    let mut d = LinkDecoder::<Crsf>::new(Line::n81(DEFAULT_BAUD));
    crate::testing::assert_stamps_hold(&mut d, &chunks);
}
