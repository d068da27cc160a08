//! What a Modbus table can show, for checking filters and names (`crate::filter`).

use crate::filter::Vocab;
use crate::row::kind;

/// Slave addresses 0-247 (0: broadcast); the Sensor column names the function, Sensor # is its
/// code in hex (`0x03`, the function an exception answers included).
pub const VOCAB: Vocab = Vocab {
    ids: 0..=247,
    id_name: "slave address",
    id_hint,
    types: &[
        "Request",
        "Response",
        "Exception",
        "Unknown",
        kind::TIMEOUT,
        kind::BAD_CRC,
        kind::TRUNCATED,
        kind::GARBAGE,
        kind::LINK_DOWN,
        kind::LINK_UP,
    ],
    polls: false,
    keepalives: false,
    sensors,
    sensor_no_text: "shows function codes in hex (0x03; 03 and 3 work too)",
    sensor_no,
    sensor_no_hex: true,
    devices: None,
};

fn id_hint(id: u32) -> Option<String> {
    (248..=255)
        .contains(&id)
        .then(|| "addresses 248-255 are reserved; slaves are 1-247 (0 is broadcast)".to_owned())
}

/// Every function name of the Sensor column.
fn sensors() -> Vec<String> {
    super::function::PUBLIC
        .iter()
        .map(|&fc| super::function::name(fc).to_owned())
        .collect()
}

/// A function code in hex, with or without `0x` (`03`, `0x2B`).
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
    fn names_and_codes() {
        assert!(sensors().iter().any(|s| s == "Read Holding Registers"));
        assert!(sensor_no("0x03") && sensor_no("2B") && !sensor_no("0x100"));
        assert!(id_hint(250).is_some() && id_hint(3).is_none());
    }
}
