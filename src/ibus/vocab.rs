//! What an iBUS table can show, for checking filters and names (`crate::filter`).

use super::map::{CHANNELS, DISCOVER, MEASURE, OTHER, SENSOR_TYPE, UNKNOWN};
use super::sensors::TYPES;
use crate::filter::Vocab;
use crate::row::kind;

/// Sensor addresses 0-15 (sensors use 1-15; RC frames have no ID); the Sensor column names the
/// sensor type as EdgeTX does, Sensor # is the type code in hex. The sensor bus is polled: a
/// poll nobody answered is a row of its own (`--hide-polls`).
pub const VOCAB: Vocab = Vocab {
    ids: 0..=15,
    id_name: "sensor address",
    id_hint,
    types: &[
        CHANNELS,
        DISCOVER,
        SENSOR_TYPE,
        MEASURE,
        OTHER,
        UNKNOWN,
        kind::BAD_CRC,
        kind::TRUNCATED,
        kind::GARBAGE,
        kind::LINK_DOWN,
        kind::LINK_UP,
    ],
    polls: true,
    keepalives: false,
    sensors,
    sensor_no_text: "shows the sensor type code in hex (0x03 for ExtV; 03 and 3 work too)",
    sensor_no,
    sensor_no_hex: true,
    devices: None,
};

/// A command byte (`0xA1`) given where an address is expected.
fn id_hint(id: u32) -> Option<String> {
    let b = u8::try_from(id).ok()?;
    (b >> 4 >= super::wire::CMD_DISCOVER).then(|| {
        format!(
            "0x{b:02X} is a command byte for address {}: use --id {}",
            b & 0x0F,
            b & 0x0F
        )
    })
}

/// Every sensor name of the type table, each once.
fn sensors() -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for t in TYPES {
        if !out.iter().any(|n| n == t.name) {
            out.push(t.name.to_owned());
        }
    }
    out
}

/// A type code in hex, with or without `0x`.
fn sensor_no(s: &str) -> bool {
    let h = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    !h.is_empty() && h.len() <= 2 && h.bytes().all(|b| b.is_ascii_hexdigit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_types_and_hints_at_command_bytes() {
        let s = sensors();
        for name in ["IntV", "Temp", "RPM", "ExtV", "Curr", "Fuel"] {
            assert!(s.iter().any(|n| n == name), "{name}");
        }
        assert!(id_hint(0xA1).unwrap().contains("address 1"));
        assert!(id_hint(40).is_none());
        assert!(sensor_no("0x03") && sensor_no("3") && !sensor_no("0x103"));
    }
}
