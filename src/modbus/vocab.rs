//! What a Modbus table can show, for checking filters and names (`crate::filter`).

use crate::protocol::vocab::{Sensor, Vocab, hex_digits};
use crate::row::kind;

/// Slave addresses 0-247 (0: broadcast); the Sensor column names the function, Sensor # is its
/// code in hex (`0x03`, the function an exception answers included). Registers and coils are
/// numbers named by their wire address (`R100`, `C7`), which `--sensor` takes too.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=247),
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
    sensor_no_text: "shows function codes in hex (0x03; 03 and 3 work too); registers and coils \
                     are named by their wire address (R100, C7)",
    sensor_no,
    sensor_no_hex: true,
    devices: None,
};

fn id_hint(id: u32) -> Option<String> {
    (248..=255)
        .contains(&id)
        .then(|| "addresses 248-255 are reserved; slaves are 1-247 (0 is broadcast)".to_owned())
}

/// Every function by name. The numbers of their rows are named by register or coil (`R100`, by
/// `sensor_no`) or by the map (the options' sensors), or shared by many functions (`start`,
/// `count`), which would make a sensor's second name select other functions' rows; only an
/// exception's `code` is its own.
fn sensors() -> Vec<Sensor> {
    super::function::PUBLIC
        .iter()
        .map(|&fc| Sensor::named(super::function::name(fc)))
        // Exception rows carry `code` (their Sensor column names the function answered).
        .chain(std::iter::once(Sensor {
            column: "Exception".into(),
            parts: vec!["code".into()],
        }))
        .collect()
}

/// A function code in hex (`03`, `0x2B`), or a register or coil by wire address (`R100`, `C7`,
/// `R+0` of an unpaired response).
fn sensor_no(s: &str) -> bool {
    if hex_digits(s, 2) {
        return true;
    }
    let Some(rest) = s.strip_prefix(['R', 'r', 'C', 'c']) else {
        return false;
    };
    let rest = rest.strip_prefix('+').unwrap_or(rest);
    !rest.is_empty() && rest.len() <= 5 && rest.bytes().all(|b| b.is_ascii_digit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_codes() {
        assert!(
            sensors()
                .iter()
                .any(|s| s.column == "Read Holding Registers")
        );
        assert!(sensor_no("0x03") && sensor_no("2B") && !sensor_no("0x100"));
        assert!(sensor_no("R100") && sensor_no("c7") && sensor_no("R+0"));
        assert!(!sensor_no("R") && !sensor_no("Rx1") && !sensor_no("Flow"));
        assert!(id_hint(250).is_some() && id_hint(3).is_none());
    }
}
