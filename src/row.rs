//! The log table every protocol maps its frames onto.
//!
//! The first eight columns follow the S-Port_Snoop sample exactly: `Counter, Millis, ID, Device,
//! Type, Sensor #, Sensor, Data`. A protocol adds its own extra columns after them (see
//! [`crate::decoder::Decoder::columns`]); the sinks add `Raw` (with `--raw`) and `Time` (with
//! `--time abs`) last.

/// The eight fixed columns, in order.
pub const BASE_COLUMNS: [&str; 8] = [
    "Counter", "Millis", "ID", "Device", "Type", "Sensor #", "Sensor", "Data",
];

/// How a row is styled in pretty output and counted in summaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Class {
    /// A poll without an answer, or a normal frame.
    Plain,
    /// A keep-alive without data (S.Port `Null`): dimmed.
    Quiet,
    /// Unusual but not broken (wrong check bits, retries, timeouts): yellow.
    Warning,
    /// Broken: bad CRC, truncated frame, garbage: red.
    Error,
    /// A line inserted by busnoop itself (reconnect gap, notices): cyan.
    Info,
}

/// One row of the table. Strings are borrowed from the decoder's scratch buffers so that
/// producing a row allocates nothing.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// Microseconds since the capture started (`Millis` = this / 1000). `None` leaves Millis empty.
    pub micros: Option<u64>,
    /// `ID` column: physical ID, station or address.
    pub id: Option<u32>,
    pub device: &'a str,
    /// `Type` column.
    pub kind: &'a str,
    pub class: Class,
    /// `Sensor #` column.
    pub sensor_no: &'a str,
    pub sensor: &'a str,
    pub data: &'a str,
    /// Values of the decoder's extra columns, in the order of its column list.
    pub extra: &'a [&'a str],
    /// The row's bytes as they were on the wire (for `--raw` and recordings).
    pub raw: &'a [u8],
}

impl<'a> Row<'a> {
    /// A row with every text column empty.
    pub fn empty(micros: Option<u64>) -> Row<'static> {
        Row {
            micros,
            id: None,
            device: "",
            kind: "",
            class: Class::Plain,
            sensor_no: "",
            sensor: "",
            data: "",
            extra: &[],
            raw: &[],
        }
    }
}
