//! What a CRSF table can show, for checking filters and names (`crate::filter`).

use crate::filter::Vocab;
use crate::row::kind;

/// Addresses 0-255 (the address byte); Sensor # is the frame type in hex (`0x16`); Sensor
/// names the first number of a frame, as EdgeTX names it.
pub const VOCAB: Vocab = Vocab {
    ids: 0..=255,
    id_name: "address",
    id_hint: no_hint,
    types: TYPES,
    polls: false,
    keepalives: false,
    sensors,
    sensor_no_text: "shows frame types in hex (0x16, 0x14; 16 works too)",
    sensor_no: frame_type,
    sensor_no_hex: true,
    devices: Some(device),
};

/// Every Type the table shows: [`super::names::FRAME_TYPES`] and the shared kinds.
pub const TYPES: &[&str] = &[
    "GPS",
    "GPSTime",
    "GPSExt",
    "Vario",
    "Battery",
    "Baro",
    "Airspeed",
    "Heartbeat",
    "RPM",
    "Temp",
    "Voltages",
    "VTX",
    "LinkStats",
    "RC",
    "RCSubset",
    "RC11",
    "LinkRX",
    "LinkTX",
    "Attitude",
    "MAVLinkFC",
    "FlightMode",
    "ESPNow",
    "Ping",
    "DeviceInfo",
    "ParamEntry",
    "ParamRead",
    "ParamWrite",
    "ELRSStatus",
    "Command",
    "Logging",
    "Radio",
    "Game",
    "KISS",
    "MSPReq",
    "MSPResp",
    "MSPWrite",
    "APLegacy",
    "APPassthru",
    "mLRS",
    "MAVLink",
    "MAVSysStatus",
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

fn no_hint(_: u32) -> Option<String> {
    None
}

/// A frame type in hex, `0x16` or `16`.
pub(crate) fn frame_type(s: &str) -> bool {
    let h = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    !h.is_empty() && h.len() <= 2 && h.bytes().all(|b| b.is_ascii_hexdigit())
}

/// The names the Sensor column shows: the first number of each frame type, and the words of
/// the frames without numbers.
fn sensors() -> Vec<String> {
    let mut out: Vec<String> = [
        "GPS", "Date", "Fix", "VSpd", "RxBt", "BAlt", "ASpd", "RPM1", "Tmp1", "Cel1", "Volt1",
        "VPwr", "1RSS", "RRSS", "TRSS", "Ptch", "FM", "Intv",
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .collect();
    out.extend((1..=16).map(|n| format!("CH{n}")));
    for cmd in [0x01, 0x03, 0x05, 0x08, 0x09, 0x0A, 0x10, 0x20, 0x22, 0xFF] {
        for sub in 0..=0xFF {
            let (group, name) = super::names::command(cmd, sub);
            for s in [Some(group), name].into_iter().flatten() {
                if !s.is_empty() && !out.iter().any(|o| o == s) {
                    out.push(s.to_owned());
                }
            }
        }
    }
    for c in 0..=255 {
        if let Some(n) = super::names::msp(c) {
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
        let s = sensors();
        for name in [
            "RxBt",
            "1RSS",
            "CH1",
            "CH16",
            "speed proposal",
            "MSP_STATUS",
        ] {
            assert!(s.iter().any(|n| n == name), "{name}");
        }
        assert!(frame_type("0x16") && frame_type("16") && !frame_type("0x123"));
    }
}
