//! The names a Futaba table shows: row types, the numbers' names, the Device column, the slot
//! groups. Below `map` (the rows as `Row`s) and `direct` (the rows written straight), which
//! both write them.

use super::wire::CHANNELS;

/// Part names of the 16 proportional channels.
pub(super) const CH_NAMES: [&str; CHANNELS] = [
    "CH1", "CH2", "CH3", "CH4", "CH5", "CH6", "CH7", "CH8", "CH9", "CH10", "CH11", "CH12", "CH13",
    "CH14", "CH15", "CH16",
];

/// Part names of the slots' raw values.
pub(super) const SLOT_NAMES: [&str; 32] = [
    "Slot0", "Slot1", "Slot2", "Slot3", "Slot4", "Slot5", "Slot6", "Slot7", "Slot8", "Slot9",
    "Slot10", "Slot11", "Slot12", "Slot13", "Slot14", "Slot15", "Slot16", "Slot17", "Slot18",
    "Slot19", "Slot20", "Slot21", "Slot22", "Slot23", "Slot24", "Slot25", "Slot26", "Slot27",
    "Slot28", "Slot29", "Slot30", "Slot31",
];

/// Type of a channel frame's row.
pub const CHANNELS_TYPE: &str = "Channels";
/// Type of a slot answer's row.
pub const SLOT_TYPE: &str = "Slot";
/// Sensor of slot 0: the receiver's own voltage (every Futaba SBUS2 receiver answers there).
pub const RX_VOLTAGE: &str = "RxV";

/// The Device column of a slot row: slot 0 is the receiver's, the others a sensor's.
pub fn device(slot: u32) -> &'static str {
    if slot == 0 { "Receiver" } else { "Sensor" }
}

/// The slots of a group, as the Note names them.
pub(super) fn group_text(group: u8) -> &'static str {
    ["slots 0-7", "slots 8-15", "slots 16-23", "slots 24-31"][usize::from(group & 3)]
}
