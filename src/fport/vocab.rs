//! What an F.Port table can show, for checking filters and names (`crate::filter`).

use crate::protocol::vocab::{Sensor, Vocab};
use crate::row::kind;

/// Physical IDs 0-31 as in S.Port (telemetry rows; control frames have none); the Sensor
/// column names app IDs as S.Port does, control frames `Channels`, OTA frames `OTA`.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=31),
    id_name: "physical ID",
    id_hint,
    types: &[
        "Control",
        "OtaStart",
        "OtaData",
        "OtaStop",
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
    ],
    polls: true,
    keepalives: true,
    sensors,
    sensor_no_text: "shows app IDs in hex as S.Port does (0x0210, 0xF101; 0210 and 210 work too)",
    sensor_no,
    sensor_no_hex: true,
    devices: Some(device),
};

/// An F.Port 2 physical ID byte (`0x1B`, `0x98`) given where a physical ID is expected.
fn id_hint(id: u32) -> Option<String> {
    let b = u8::try_from(id).ok()?;
    crate::sport::wire::header_ok(b).then(|| {
        format!(
            "0x{b:02X} is the physical ID byte of ID {}: use --id {}",
            b & 0x1F,
            b & 0x1F
        )
    })
}

/// S.Port's sensors, the control frames' `Channels` with the names of their numbers, and `OTA`.
fn sensors() -> Vec<Sensor> {
    let mut out = (crate::sport::PROTOCOL.vocab.sensors)();
    let mut parts: Vec<String> = (1..=24).map(|i| format!("CH{i}")).collect();
    parts.extend(["FrameLost", "Failsafe", "RSSI"].map(String::from));
    out.push(Sensor {
        column: "Channels".to_owned(),
        parts,
    });
    out.push(Sensor::named("OTA"));
    out
}

fn sensor_no(s: &str) -> bool {
    (crate::sport::PROTOCOL.vocab.sensor_no)(s)
}

/// Telemetry rows name devices as S.Port does; control rows come from the receiver.
fn device(id: u32) -> &'static str {
    crate::sport::names::device(id as u8)
}
