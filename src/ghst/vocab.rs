//! What a GHST table can show, for checking filters and names (`crate::filter`).

use crate::crsf::vocab::{numbered, sensor};
use crate::protocol::vocab::{Sensor, Vocab, no_hint};
use crate::row::kind;

/// Addresses 0-255 (the address byte; GHST uses 0x80-0x89); Sensor # is the frame type in hex.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=255),
    id_name: "address",
    id_hint: no_hint,
    types: TYPES,
    polls: false,
    keepalives: false,
    sensors,
    sensor_no_text: "shows frame types in hex (0x10, 0x23; 10 works too)",
    sensor_no: crate::crsf::vocab::frame_type,
    sensor_no_hex: true,
    devices: Some(device),
};

/// Every Type the table shows: every name [`super::names::frame_type`] gives (a test checks)
/// and the shared kinds.
pub const TYPES: &[&str] = &[
    "RC",
    "RCLink",
    "MenuCtrl",
    "Sync",
    "MSPReq",
    "MSPWrite",
    "LinkStats",
    "VTXStats",
    "Battery",
    "Menu",
    "GPS",
    "GPS2",
    "MagBaro",
    "MSPResp",
    "Unknown",
    kind::BAD_CRC,
    kind::TRUNCATED,
    kind::GARBAGE,
    kind::LINK_DOWN,
    kind::LINK_UP,
];

fn device(id: u32) -> &'static str {
    super::names::device(id as u8)
}

/// The Sensor column's values (the first number of each frame type), each with the names of the
/// numbers of its rows.
fn sensors() -> Vec<Sensor> {
    let mut ch = numbered("CH", 16);
    ch.extend(["RQly", "RSSI", "RFMD", "TPWR"].map(String::from));
    let mut out = vec![
        Sensor {
            column: "CH1".into(),
            parts: ch,
        },
        sensor("Intv", &["Intv", "Offs"]),
        sensor(
            "RSSI",
            &["RSSI", "RQly", "RSNR", "TPWR", "FRat", "TLat", "RFMD"],
        ),
        sensor("VFrq", &["VFrq", "VPwr", "VChn"]),
        sensor("RxBt", &["RxBt", "Curr", "Capa", "RxV"]),
        sensor("GPS", &["Lat", "Lon", "Alt"]),
        sensor("GSpd", &["GSpd", "Hdg", "Sats", "Dist", "HDir"]),
        sensor("MHdg", &["MHdg", "BAlt", "VSpd"]),
        sensor("BAlt", &["BAlt", "VSpd"]),
        sensor("VSpd", &["VSpd"]),
    ];
    out.extend(crate::crsf::vocab::msp_sensors());
    out
}
