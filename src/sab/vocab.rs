//! What a SAB table can show, for checking filters and names (`crate::filter`).

use crate::protocol::vocab::Vocab;
use crate::row::kind;

/// Addresses 0-63; Sensor # is the command code in hex (`0x34`); the Sensor and Device
/// columns hold only the names given with `--command` and `--name`/`--device`.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=63),
    id_name: "address",
    id_hint: no_hint,
    types: &[
        "Request",
        "ACK",
        "NACK",
        "Reserved",
        kind::TIMEOUT,
        kind::BAD_CRC,
        kind::TRUNCATED,
        kind::GARBAGE,
        "Runt",
        "Abort",
        "Overlong",
        kind::LINK_DOWN,
        kind::LINK_UP,
    ],
    polls: false,
    keepalives: false,
    sensors: Vec::new,
    sensor_no_text: "shows command codes in hex (0x34); name commands with --command NAME=CODE",
    sensor_no: code,
    sensor_no_hex: true,
    devices: Some(unnamed),
};

fn no_hint(_: u32) -> Option<String> {
    None
}

/// A command code in hex, `0x34` or `34`.
fn code(s: &str) -> bool {
    let h = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    !h.is_empty() && h.len() <= 2 && h.bytes().all(|b| b.is_ascii_hexdigit())
}

/// Without names the Device column is empty.
fn unnamed(_: u32) -> &'static str {
    ""
}
