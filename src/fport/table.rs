//! What the table shows of an F.Port line that the mapper and the direct rows share: the extra
//! columns, the receiver's name, the physical IDs F.Port v1 telemetry is shown with, and a
//! row's time.

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Frame", "Note"];

/// The Device column of the receiver's control frames.
pub const RECEIVER: &str = "Receiver";
/// The physical ID F.Port v1 telemetry is shown with: the flight controller's (Betaflight's
/// FSSP_SENSOR_ID1 0x1B), the only device an F.Port v1 line has.
pub const V1_PHYS: u8 = 27;
/// The physical ID of MSP requests in S.Port (the radio's uplink ID 0x0D); F.Port v1 carries
/// none, so read and write requests are shown with it.
pub const V1_REQUEST_PHYS: u8 = 13;

/// Time of a row: the source's, or 10 bits per byte at the line's speed.
pub(super) fn micros(time: Option<u64>, offset: u64, baud: u32) -> u64 {
    time.unwrap_or_else(|| crate::protocol::untimed_micros(offset, 10, baud))
}
