//! What a CRSF table can show, for checking filters and names (`crate::filter`).

use crate::protocol::vocab::{Sensor, Vocab, hex_digits, no_hint};
use crate::row::kind;

/// Addresses 0-255 (the address byte); Sensor # is the frame type in hex (`0x16`); Sensor
/// names the first number of a frame, as EdgeTX names it.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=255),
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

/// Every Type the table shows: every name [`super::names::frame_type`] gives (a test checks)
/// and the shared kinds.
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

/// A frame type in hex, `0x16` or `16`.
pub(crate) fn frame_type(s: &str) -> bool {
    hex_digits(s, 2)
}

/// A Sensor column value and the names of the numbers its rows carry.
pub(crate) fn sensor(column: &str, parts: &[&str]) -> Sensor {
    Sensor {
        column: column.to_owned(),
        parts: parts.iter().map(|p| (*p).to_owned()).collect(),
    }
}

/// `<base>1` … `<base><n>`.
pub(crate) fn numbered(base: &str, n: usize) -> Vec<String> {
    (1..=n).map(|i| format!("{base}{i}")).collect()
}

/// The Sensor column's values (the first number of each frame type, the words of the frames
/// without numbers), each with the names of the numbers of its rows (EdgeTX's).
fn sensors() -> Vec<Sensor> {
    let mut out = vec![
        sensor("GPS", &["Lat", "Lon", "GSpd", "Hdg", "Alt", "Sats"]),
        sensor("Date", &[]),
        sensor(
            "Fix",
            &[
                "Fix", "NSpd", "ESpd", "GVSp", "SAcc", "TAcc", "EAlt", "HAcc", "VAcc", "HDOP",
                "VDOP",
            ],
        ),
        sensor("VSpd", &["VSpd"]),
        sensor("RxBt", &["RxBt", "Curr", "Capa", "Bat%"]),
        sensor("BAlt", &["BAlt", "VSpd"]),
        sensor("ASpd", &["ASpd"]),
        sensor("VPwr", &["VPwr", "VFrq"]),
        sensor(
            "1RSS",
            &[
                "1RSS", "2RSS", "RQly", "RSNR", "ANT", "RFMD", "TPWR", "TRSS", "TQly", "TSNR",
            ],
        ),
        sensor("RRSS", &["RRSS", "RRSP", "RQly", "RSNR", "TPWR"]),
        sensor("TRSS", &["TRSS", "TRSP", "TQly", "TSNR", "RPWR", "TFPS"]),
        sensor("Ptch", &["Ptch", "Roll", "Yaw"]),
        sensor("FM", &[]),
        sensor("Intv", &["Intv", "Offs"]),
        Sensor {
            column: "CH1".into(),
            parts: numbered("CH", 16),
        },
        Sensor {
            column: "RPM1".into(),
            parts: numbered("RPM", 19),
        },
        Sensor {
            column: "Tmp1".into(),
            parts: numbered("Tmp", 29),
        },
        Sensor {
            column: "Cel1".into(),
            parts: (1..=29)
                .map(|i| {
                    if i < 10 {
                        format!("Cel{i}")
                    } else {
                        format!("Cl{i}")
                    }
                })
                .collect(),
        },
        Sensor {
            column: "Volt1".into(),
            parts: numbered("Volt", 29),
        },
    ];
    // A subset frame's first channel.
    out.extend((2..=32).map(|n| Sensor::named(&format!("CH{n}"))));
    for cmd in [0x01, 0x03, 0x05, 0x08, 0x09, 0x0A, 0x10, 0x20, 0x22, 0xFF] {
        for sub in 0..=0xFF {
            let (group, name) = super::names::command(cmd, sub);
            for s in [Some(group), name].into_iter().flatten() {
                if !s.is_empty() && !out.iter().any(|o| o.column == s) {
                    out.push(Sensor::named(s));
                }
            }
        }
    }
    out.extend(msp_sensors());
    out
}

/// The MSP commands busnoop names.
pub(crate) fn msp_sensors() -> Vec<Sensor> {
    (0..=255)
        .filter_map(super::names::msp)
        .map(Sensor::named)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radios_sensor_names_are_in_the_vocabulary() {
        let s = sensors();
        for name in [
            "RxBt",
            "1RSS",
            "RQly",
            "CH1",
            "CH16",
            "speed proposal",
            "MSP_STATUS",
        ] {
            assert!(s.iter().any(|n| n.is(name)), "{name}");
        }
        assert!(frame_type("0x16") && frame_type("16") && !frame_type("0x123"));
    }
}
