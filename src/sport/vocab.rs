//! What an S.Port table can show, for checking filters and names (`crate::filter`).

use crate::protocol::vocab::{Sensor, Vocab};
use crate::row::kind;

/// Physical IDs 0-31; the Sensor column names app IDs as EdgeTX does; Sensor # is the app ID
/// in hex.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=31),
    id_name: "physical ID",
    id_hint,
    types: &[
        "Data",
        "Null",
        "MaintOff",
        "MaintOn",
        "Read",
        "Write",
        "Reply",
        "FwUpdate",
        "Unknown",
        kind::BAD_CRC,
        kind::TRUNCATED,
        kind::GARBAGE,
        kind::LINK_DOWN,
        kind::LINK_UP,
        kind::TIME_JUMP,
    ],
    polls: true,
    keepalives: true,
    sensors,
    sensor_no_text: "shows app IDs in hex (0x0210, 0xF101; 0210 and 210 work too)",
    sensor_no,
    sensor_no_hex: true,
    devices: Some(device),
};

/// A poll byte (`0xA1`) given where a physical ID is expected.
fn id_hint(id: u32) -> Option<String> {
    let b = u8::try_from(id).ok()?;
    super::wire::header_ok(b).then(|| {
        format!(
            "0x{b:02X} is the poll byte of physical ID {}: use --id {}",
            b & 0x1F,
            b & 0x1F
        )
    })
}

/// Every sensor busnoop knows by app ID, each once: the Sensor column's label (S-Port_Snoop's
/// `Volts`, `Cels`) with the names of its numbers (EdgeTX's `VFAS`, `Cell1` … `Cell16`).
fn sensors() -> Vec<Sensor> {
    let mut out: Vec<Sensor> = Vec::new();
    let (mut label, mut hex, mut data) = (String::new(), String::new(), String::new());
    let mut nums = super::values::SportNumbers::default();
    for app_id in 0..=u16::MAX {
        label.clear();
        hex.clear();
        data.clear();
        nums.clear();
        super::values::decode_numbers(0, app_id, 0, &mut label, &mut data, &mut nums);
        super::values::push_hex_id(&mut hex, app_id);
        // Hub frames of unknown IDs are named by number (`Hub 0x41`): not worth listing.
        if label.is_empty() || label == hex || label.starts_with("Hub 0x") {
            continue;
        }
        let mut parts: Vec<String> =
            nums.with_parts(|p| p.iter().map(|p| p.name.to_owned()).collect());
        // A cell frame names the cells it carries; the sensor has all of them.
        if parts.iter().any(|p| p.starts_with("Cell")) {
            parts = (1..=16).map(|i| format!("Cell{i}")).collect();
        }
        parts.retain(|p| *p != label && *p != hex);
        match out.iter_mut().find(|s| s.column == label) {
            Some(s) => {
                for p in parts {
                    if !s.parts.contains(&p) {
                        s.parts.push(p);
                    }
                }
            }
            None => out.push(Sensor {
                column: label.clone(),
                parts,
            }),
        }
    }
    out
}

/// An app ID in hex, with or without `0x` (`0210`, `210`, `0xF101`).
fn sensor_no(s: &str) -> bool {
    let h = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    !h.is_empty() && h.len() <= 4 && h.bytes().all(|b| b.is_ascii_hexdigit())
}

fn device(id: u32) -> &'static str {
    super::names::device(id as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knows_the_common_sensors_and_hints_at_poll_bytes() {
        let s = sensors();
        for name in ["Cels", "RxBt", "RSSI", "Alt", "Volts"] {
            assert!(s.iter().any(|n| n.column == name), "{name} in {s:?}");
        }
        // Both names of a sensor: the table's and the radio's.
        let of = |name: &str| -> Vec<&str> {
            s.iter()
                .filter(|n| n.is(name))
                .map(|n| n.column.as_str())
                .collect()
        };
        assert_eq!(of("VFAS"), ["Hub VFAS", "Volts"]);
        assert_eq!(of("Curr"), ["Amps"]);
        assert_eq!(of("VSpd"), ["Vario"]);
        assert_eq!(of("cell3"), ["Hub Cell", "Cels"]);
        assert_eq!(of("RxBt"), ["RxBt"]);
        assert!(
            !s.iter()
                .any(|n| n.column.len() == 4 && n.column.bytes().all(|b| b.is_ascii_hexdigit()))
        );
        assert!(id_hint(0xA1).unwrap().contains("physical ID 1"));
        assert!(id_hint(40).is_none());
        assert!(sensor_no("0210") && sensor_no("0xF101") && !sensor_no("12345"));
    }
}
