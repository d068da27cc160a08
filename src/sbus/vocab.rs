//! What an S-Bus table can show, for checking filters and names (`crate::filter`).

use crate::protocol::vocab::{Sensor, Vocab};
use crate::row::kind;

/// Stations 0-255; the Sensor column names the command (as Wireshark does); Sensor # is the
/// first element in S-Bus notation. The Device column is open: Ether-S-Bus shows PLC
/// addresses, which only the capture knows.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=255),
    id_name: "station",
    id_hint: no_hint,
    types: &[
        "Request",
        "Response",
        "ACK",
        "NAK",
        "Retry",
        kind::TIMEOUT,
        kind::BAD_CRC,
        kind::TRUNCATED,
        kind::GARBAGE,
        "Unknown",
        "Fragment",
        "Skipped",
        kind::LINK_DOWN,
        kind::LINK_UP,
    ],
    polls: false,
    keepalives: false,
    sensors,
    sensor_no_text: "shows elements (R100, F5, I8, O16, T0, C3, DB4000[2], X12, EE0, UM256, \
                     PL256, 0x01F000)",
    sensor_no: element,
    sensor_no_hex: false,
    devices: None,
};

fn no_hint(_: u32) -> Option<String> {
    None
}

/// Every command name of the Sensor column, each once.
fn sensors() -> Vec<Sensor> {
    let mut out: Vec<Sensor> = Vec::new();
    for cmd in 0..=u8::MAX {
        let name = super::telegram::command_name(cmd);
        if !out.iter().any(|n| n.column == name) {
            out.push(Sensor::named(name));
        }
    }
    out
}

/// An element in S-Bus notation: `R100`, `DB4000[2]`, `X12`, `0x01F000`.
fn element(s: &str) -> bool {
    let digits = |d: &str| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit());
    if let Some(h) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        return !h.is_empty() && h.len() <= 6 && h.bytes().all(|b| b.is_ascii_hexdigit());
    }
    let upper = s.to_ascii_uppercase();
    if let Some(rest) = upper.strip_prefix("DB") {
        return match rest.split_once('[') {
            Some((block, index)) => digits(block) && index.strip_suffix(']').is_some_and(digits),
            None => digits(rest),
        };
    }
    ["EE", "UM", "PL", "R", "F", "I", "O", "T", "C", "X"]
        .iter()
        .any(|p| upper.strip_prefix(p).is_some_and(digits))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elements_and_commands() {
        for e in [
            "R100",
            "f5",
            "DB4000[2]",
            "DB4000",
            "X12",
            "EE0",
            "0x01F000",
            "UM256",
        ] {
            assert!(element(e), "{e}");
        }
        for e in ["R", "Q5", "DB4000[", "Boiler", "0x"] {
            assert!(!element(e), "{e}");
        }
        let s = sensors();
        assert!(s.iter().any(|n| n.column == "Read register(s)"), "{s:?}");
    }
}
