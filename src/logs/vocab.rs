//! What a telemetry log's table can show, for checking filters and names (`crate::filter`).
//! Its columns come from the file, so any sensor name and any ID pass; the types are a radio
//! log's `Log` and what S-Port_Snoop's table holds.

use super::map::LOG_TYPE;
use crate::protocol::vocab::{Sensor, Vocab};
use crate::row::kind;

pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=u32::MAX),
    id_name: "ID",
    id_hint: |_| None,
    types: &[
        LOG_TYPE,
        "Data",
        "Null",
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
    sensor_no_text: "shows what the log's Sensor # column holds",
    sensor_no: |_| true,
    sensor_no_hex: true,
    devices: None,
};

/// Not known before the file is read: every name is accepted.
fn sensors() -> Vec<Sensor> {
    Vec::new()
}
