//! What a Futaba SBUS table can show, for checking filters and names (`crate::filter`).

use super::names::{CHANNELS_TYPE, RX_VOLTAGE, SLOT_TYPE, device};
use crate::protocol::vocab::{Sensor, Vocab, hex_digits};
use crate::row::kind;

/// Slots 0-31 (channel frames have no ID); the Sensor column says SBUS or SBUS2 for a frame
/// and `RxV` for slot 0; Sensor # is the end byte of a frame or the id byte of a slot.
pub const VOCAB: Vocab = Vocab {
    ids: Some(0..=31),
    id_name: "slot",
    id_hint,
    types: &[
        CHANNELS_TYPE,
        SLOT_TYPE,
        kind::TRUNCATED,
        kind::GARBAGE,
        kind::LINK_DOWN,
        kind::LINK_UP,
    ],
    polls: false,
    keepalives: false,
    sensors,
    sensor_no_text: "shows a frame's end byte (0x00, 0x04, 0x14, 0x24, 0x34, 0x08) or a slot's \
                     id byte (0x03, 0x83 …) in hex",
    sensor_no,
    sensor_no_hex: true,
    devices: Some(device),
};

/// A slot's id byte (`0x83`) given where a slot number is expected.
fn id_hint(id: u32) -> Option<String> {
    let b = u8::try_from(id).ok()?;
    super::wire::slot_number(b)
        .map(|n| format!("0x{b:02X} is the id byte of slot {n}: use --id {n}"))
}

/// The Sensor column's names (a frame's SBUS or SBUS2, slot 0's receiver voltage `RxV` with
/// its number `Slot0`), and the names of the numbers no Sensor column shows: `CH1` … `CH18`,
/// `FrameLost`, `Failsafe` of every frame, `Slot1` … `Slot31`. Each its own, so that
/// `--sensor SBUS` keeps to SBUS frames.
fn sensors() -> Vec<Sensor> {
    let mut out = vec![
        Sensor::named("SBUS"),
        Sensor::named("SBUS2"),
        Sensor {
            column: RX_VOLTAGE.into(),
            parts: vec!["Slot0".into()],
        },
    ];
    out.extend((1..=18).map(|n| Sensor::named(&format!("CH{n}"))));
    out.extend(["FrameLost", "Failsafe"].map(Sensor::named));
    out.extend((1..32).map(|n| Sensor::named(&format!("Slot{n}"))));
    out
}

/// A byte in hex, with or without `0x`.
fn sensor_no(s: &str) -> bool {
    hex_digits(s, 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hints_at_slot_id_bytes() {
        assert!(id_hint(0x83).unwrap().contains("slot 1"));
        assert!(id_hint(40).is_none());
        assert!(sensor_no("0x83") && sensor_no("04") && !sensor_no("0x123"));
        assert!(sensors().iter().any(|s| s.is("RxV") && s.is("Slot0")));
        assert!(sensors().iter().any(|s| s.is("Failsafe")));
        assert!(!sensors().iter().any(|s| s.is("SBUS") && s.is("CH1")));
    }
}
