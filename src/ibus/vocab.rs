//! What an iBUS table can show, for checking filters and names (`crate::filter`).

use super::names::{CHANNELS, DISCOVER, MEASURE, OTHER, SENSOR_TYPE, UNKNOWN};
use super::sensors::TYPES;
use crate::protocol::vocab::{Sensor, Vocab, hex_digits};
use crate::row::kind;

/// Sensor addresses 0-15 (sensors use 1-15; RC frames have no ID); the Sensor column names the
/// sensor type as EdgeTX does, Sensor # is the type code in hex. The sensor bus is polled: a
/// poll nobody answered is a row of its own (`--hide-polls`).
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=15),
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

/// Every sensor name of the type table, each once, with the names of its numbers where they
/// differ (GPS: Lat, Lon; Sats: Fix; Pres: Tmp2), and the numbers no Sensor column shows: the
/// channels CH1 … CH18 of RC frames and the raw values of unknown types (`Raw`).
fn sensors() -> Vec<Sensor> {
    let mut out: Vec<Sensor> = Vec::new();
    for t in TYPES {
        let extra: &[&str] = match t.enc {
            super::sensors::Enc::GpsStatus => &["Fix"],
            super::sensors::Enc::Pressure => &["Tmp2"],
            _ => &[],
        };
        let i = match out.iter().position(|s| s.column == t.name) {
            Some(i) => i,
            None => {
                out.push(Sensor::named(t.name));
                out.len() - 1
            }
        };
        for p in std::iter::once(t.part).chain(extra.iter().copied()) {
            if p != t.name && !out[i].parts.iter().any(|q| q == p) {
                out[i].parts.push(p.to_owned());
            }
        }
    }
    out.extend((1..=18).map(|n| Sensor::named(&format!("CH{n}"))));
    out.push(Sensor::named("Raw"));
    out
}

/// A type code in hex, with or without `0x`.
fn sensor_no(s: &str) -> bool {
    hex_digits(s, 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_types_and_hints_at_command_bytes() {
        let s = sensors();
        for name in ["IntV", "Temp", "RPM", "ExtV", "Curr", "Fuel", "Lat", "CH18"] {
            assert!(s.iter().any(|n| n.is(name)), "{name}");
        }
        assert!(s.iter().any(|n| n.is("GPS") && n.is("Lon")));
        assert!(id_hint(0xA1).unwrap().contains("address 1"));
        assert!(id_hint(40).is_none());
        assert!(sensor_no("0x03") && sensor_no("3") && !sensor_no("0x103"));
    }
}
