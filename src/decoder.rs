//! The interface between the protocol-independent driver ([`crate::run`]) and a protocol.
//!
//! A protocol module keeps its reassembler pure (bytes and times in, frames out); its
//! [`Decoder`] wraps that reassembler, maps frames onto [`Row`]s and keeps the statistics.

use std::io;

use crate::row::Row;

/// Receives the rows a decoder produces.
pub trait RowOut {
    fn row(&mut self, row: &Row<'_>) -> io::Result<()>;

    /// The wall-clock time at which the capture started (µs 0), when a decoder learns it from
    /// the data itself (pcap packet headers). Call it before the first row; used by `--time abs`.
    fn anchor(&mut self, _anchor: crate::sink::Anchor) {}
}

/// Collects rows as owned strings (tests, tools).
#[derive(Default, Debug, Clone)]
pub struct Collected {
    pub rows: Vec<OwnedRow>,
}

/// An owned copy of a [`Row`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OwnedRow {
    pub micros: Option<u64>,
    pub id: Option<u32>,
    pub device: String,
    pub kind: String,
    pub class: crate::row::Class,
    pub sensor_no: String,
    pub sensor: String,
    pub data: String,
    pub extra: Vec<String>,
    pub raw: Vec<u8>,
}

impl OwnedRow {
    pub fn millis(&self) -> Option<u64> {
        self.micros.map(|m| m / 1000)
    }
}

impl RowOut for Collected {
    fn row(&mut self, row: &Row<'_>) -> io::Result<()> {
        self.rows.push(OwnedRow {
            micros: row.micros,
            id: row.id,
            device: row.device.to_owned(),
            kind: row.kind.to_owned(),
            class: row.class,
            sensor_no: row.sensor_no.to_owned(),
            sensor: row.sensor.to_owned(),
            data: row.data.to_owned(),
            extra: row.extra.iter().map(|s| (*s).to_owned()).collect(),
            raw: row.raw.to_vec(),
        });
        Ok(())
    }
}

/// Counts rows and throws them away (decode-only benchmarks).
#[derive(Default, Debug)]
pub struct Discard {
    pub rows: u64,
}

impl RowOut for Discard {
    fn row(&mut self, row: &Row<'_>) -> io::Result<()> {
        std::hint::black_box(row);
        self.rows += 1;
        Ok(())
    }
}

/// A protocol decoder as the driver sees it.
pub trait Decoder {
    /// Extra column names that follow the eight base columns.
    fn columns(&self) -> &'static [&'static str];

    /// Feeds bytes that arrived at `time` (microseconds since the capture started; `None` for
    /// sources without time). Rows for every frame completed by these bytes are emitted at once.
    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> io::Result<()>;

    /// Time passed without data on a live serial source; `now` is the current capture time
    /// (µs since the capture started). Lets a decoder report timeouts promptly.
    fn idle(&mut self, _now: u64, _out: &mut dyn RowOut) -> io::Result<()> {
        Ok(())
    }

    /// End of input, or a gap in a live capture (adapter unplugged): emits whatever is still open
    /// (a truncated frame, trailing garbage, unanswered requests). After a gap, `push` is called
    /// again with the bytes that follow it, so the decoder must be ready to go on.
    fn finish(&mut self, out: &mut dyn RowOut) -> io::Result<()>;

    /// Frames with a valid check decoded so far.
    fn valid_frames(&self) -> u64;

    /// The `--stats` report (several lines, no trailing newline).
    fn stats(&self) -> String;

    /// One line naming what went wrong (CRC errors, truncated frames, garbage), or `None` when
    /// everything decoded cleanly.
    fn problems(&self) -> Option<String>;

    /// A hint printed once when bytes keep arriving but no frame is found (live sources).
    fn no_frames_hint(&self) -> &'static str {
        "check the baud rate and the wiring"
    }
}
