//! The names an iBUS table shows: row types and the channels' names. Below `map` (the rows as
//! `Row`s) and `direct` (the common rows written straight), which both write them.

use super::wire::RC_CHANNELS_MAX;

/// Part names of the 18 channels of an RC frame.
pub(super) const CH_NAMES: [&str; RC_CHANNELS_MAX] = [
    "CH1", "CH2", "CH3", "CH4", "CH5", "CH6", "CH7", "CH8", "CH9", "CH10", "CH11", "CH12", "CH13",
    "CH14", "CH15", "CH16", "CH17", "CH18",
];

/// Types of rows.
pub const CHANNELS: &str = "Channels";
pub const DISCOVER: &str = "Discover";
pub const SENSOR_TYPE: &str = "SensorType";
pub const MEASURE: &str = "Measure";
/// A command other than 8, 9 and A, answered.
pub const OTHER: &str = "Other";
/// A valid frame of no known kind.
pub const UNKNOWN: &str = "Unknown";
