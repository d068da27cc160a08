//! What a GHST table can show, for checking filters and names (`crate::filter`).

use crate::filter::Vocab;
use crate::row::kind;

/// Addresses 0-255 (the address byte; GHST uses 0x80-0x89); Sensor # is the frame type in hex.
pub const VOCAB: Vocab = Vocab {
    ids: 0..=255,
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

/// Every Type the table shows: [`super::names::FRAME_TYPES`] and the shared kinds.
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

fn no_hint(_: u32) -> Option<String> {
    None
}

fn device(id: u32) -> &'static str {
    super::names::device(id as u8)
}

/// The names the Sensor column shows: the first number of each frame type.
fn sensors() -> Vec<String> {
    let mut out: Vec<String> = ["CH1", "Intv", "RSSI", "VFrq", "RxBt", "GPS", "GSpd", "MHdg"]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    for c in 0..=255 {
        if let Some(n) = crate::crsf::names::msp(c) {
            out.push(n.to_owned());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_frame_type_is_a_type() {
        for t in super::super::names::FRAME_TYPES {
            assert!(TYPES.contains(t), "{t}");
        }
    }
}
