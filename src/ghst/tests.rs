//! GHST decoder tests: the channel scales of Betaflight's `ghst.c` and the telemetry layouts of
//! Betaflight's `telemetry/ghst.c` and EdgeTX's `ghost.cpp`, built with CRSF's encoder.

use super::*;
use crate::crsf::wire::{encode, pack_bits};
use crate::row::{Class, Collected, OwnedRow};

fn rows(data: &[u8]) -> Vec<OwnedRow> {
    let mut d = decoder(Options::default());
    let mut out = Collected::default();
    d.push(data, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    out.rows
}

fn one(addr: u8, ty: u8, payload: &[u8]) -> OwnedRow {
    let mut f = Vec::new();
    encode(&mut f, addr, ty, payload);
    let r = rows(&f);
    assert_eq!(r.len(), 1, "{r:#?}");
    r.into_iter().next().unwrap()
}

fn parts(r: &OwnedRow) -> Vec<String> {
    r.parts.iter().map(|(n, _, t)| format!("{n}={t}")).collect()
}

#[test]
fn legacy_rc_frame_to_the_fc() {
    let mut p = pack_bits(&[1984, 1984, 344, 3622], 12);
    p.extend([124, 124, 22, 226]);
    let r = one(0x82, 0x10, &p);
    assert_eq!(
        (
            r.id,
            r.device.as_str(),
            r.kind.as_str(),
            r.sensor_no.as_str()
        ),
        (Some(0x82), "FC", "RC", "0x10")
    );
    assert_eq!(
        parts(&r),
        [
            "CH1=1500.50",
            "CH2=1500.50",
            "CH3=988.00",
            "CH4=2012.25",
            "CH5=1500",
            "CH6=1500",
            "CH7=990",
            "CH8=2010"
        ]
    );
    assert!(r.extra[1].contains("raw 1984 1984 344 3622; aux raw 124 124 22 226; legacy scale"));
}

#[test]
fn twelve_bit_rc_frame() {
    let mut p = pack_bits(&[0, 2048, 4095, 1024], 12);
    p.extend([0, 128, 255, 64]);
    let r = one(0x82, 0x31, &p);
    assert_eq!(
        parts(&r),
        [
            "CH1=988.00",
            "CH2=1500.00",
            "CH3=2011.75",
            "CH4=1244.00",
            "CH9=988",
            "CH10=1500",
            "CH11=2008",
            "CH12=1244"
        ]
    );
    assert!(r.extra[1].ends_with("12-bit scale"));
}

#[test]
fn channels_and_link_frame_and_menu_control() {
    let mut p = pack_bits(&[2048; 4], 12);
    p.extend([98, 75, 5, 20]);
    let r = one(0x82, 0x33, &p);
    assert_eq!(r.kind, "RCLink");
    assert_eq!(
        &parts(&r)[4..],
        ["RQly=98", "RSSI=-75", "RFMD=5", "TPWR=20"]
    );
    assert!(r.extra[1].contains("RF protocol Normal"));
    let r = one(0x81, 0x13, &[1, 2, 0, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(
        (r.kind.as_str(), r.device.as_str()),
        ("MenuCtrl", "TX module")
    );
}

#[test]
fn downlink_statistics_to_the_radio() {
    let r = one(
        0x80,
        0x21,
        &[70, 100, 12, 0x00, 0x64, 0x00, 0xFA, 0x01, 0x2C, 2],
    );
    assert_eq!((r.kind.as_str(), r.device.as_str()), ("LinkStats", "Radio"));
    assert_eq!(
        parts(&r),
        [
            "RSSI=-70", "RQly=100", "RSNR=12", "TPWR=100", "FRat=250", "TLat=300", "RFMD=2"
        ]
    );
    assert!(r.extra[1].contains("RF mode Race"));
    let r = one(0x80, 0x22, &[0, 0x16, 0xA8, 0x00, 0x19, 2, 4, 0, 0, 0]);
    assert_eq!(r.kind, "VTXStats");
    assert_eq!(parts(&r), ["VFrq=5800", "VPwr=25", "VChn=4"]);
    assert!(r.extra[1].contains("band Race"));
}

#[test]
fn telemetry_from_the_fc() {
    let mut p = Vec::new();
    for v in [1680u16, 250, 123] {
        p.extend(v.to_le_bytes());
    }
    p.extend([50, 0, 0, 0]);
    let r = one(0x89, 0x23, &p);
    assert_eq!(
        (r.kind.as_str(), r.device.as_str()),
        ("Battery", "Receiver")
    );
    assert_eq!(
        parts(&r),
        ["RxBt=16.80", "Curr=2.50", "Capa=1230", "RxV=5.0"]
    );

    let mut p = Vec::new();
    p.extend(560_000_000i32.to_le_bytes());
    p.extend((-1_630_000_000i32).to_le_bytes());
    p.extend(2345i16.to_le_bytes());
    let r = one(0x89, 0x25, &p);
    assert_eq!(
        parts(&r),
        ["Lat=56.0000000", "Lon=-163.0000000", "Alt=2345"]
    );
    assert_eq!(r.sensor, "GPS");

    let mut p = Vec::new();
    p.extend(1630u16.to_le_bytes());
    p.extend(1479u16.to_le_bytes());
    p.push(9);
    p.extend(120u16.to_le_bytes());
    p.extend(900u16.to_le_bytes());
    p.push(3);
    let r = one(0x89, 0x26, &p);
    assert_eq!(
        parts(&r),
        ["GSpd=58.7", "Hdg=147.9", "Sats=9", "Dist=1200", "HDir=90.0"]
    );
    assert!(r.extra[1].contains("fix, home set"));

    let mut p = Vec::new();
    p.extend(1234i16.to_le_bytes());
    p.extend(100i16.to_le_bytes());
    p.push(50);
    p.extend([0, 0, 0, 0, 7]);
    let r = one(0x89, 0x27, &p);
    assert_eq!(parts(&r), ["MHdg=123.4", "BAlt=100", "VSpd=0.50"]);
    p[9] = 2;
    let r = one(0x89, 0x27, &p);
    assert_eq!(parts(&r), ["BAlt=100"]);
}

#[test]
fn msp_sync_menu_and_unknown() {
    let r = one(0x82, 0x21, &[0x30, 0, 101, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(
        (r.kind.as_str(), r.sensor.as_str()),
        ("MSPReq", "MSP_STATUS")
    );
    let r = one(0x89, 0x28, &[0x30, 2, 101, 0x11, 0x22, 0, 0, 0, 0, 0]);
    assert_eq!(r.kind, "MSPResp");
    let mut p = Vec::new();
    p.extend(40_000u32.to_be_bytes());
    p.extend((-25i32).to_be_bytes());
    let r = one(0x80, 0x20, &p);
    assert_eq!(parts(&r), ["Intv=4000.0", "Offs=-2.5"]);
    let mut p = vec![1, 0, 2];
    p.extend(b"Band|Race\0\0\0\0\0\0\0\0\0\0\0");
    let r = one(0x80, 0x24, &p);
    assert_eq!(
        (r.kind.as_str(), r.data.as_str()),
        ("Menu", "line 2 \"Band|Race\"")
    );
    let r = one(0x80, 0x2A, &[1, 2]);
    assert_eq!((r.kind.as_str(), r.class), ("Unknown", Class::Warning));
}

#[test]
fn crsf_bytes_are_not_ghst_frames() {
    // A CRSF RC frame starts with 0xC8 or 0x00: no GHST address, every byte is garbage.
    let mut f = Vec::new();
    encode(&mut f, 0xC8, 0x16, &[0; 22]);
    let r = rows(&f);
    assert!(r.iter().all(|r| r.kind == "Garbage"), "{r:#?}");
    let mut d = decoder(Options::default());
    let mut out = Collected::default();
    d.push(&f, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    assert_eq!(
        d.problems().line().unwrap(),
        "GHST: 26 garbage bytes skipped (1 run) in 0 valid frames"
    );
}
