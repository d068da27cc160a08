//! Futaba frames and slots onto the log table (documented in `docs/futaba.md`), and the
//! statistics.

use super::names::{
    CH_NAMES, CHANNELS_TYPE, RX_VOLTAGE, SLOT_NAMES, SLOT_TYPE, device, group_text,
};
use super::wire::{self, Broken, CHANNELS, Event, FRAME_LEN, SLOT_LEN};
use crate::fmt::{hex_0x, push_0x, push_0x16, push_hex};
use crate::numbers::{Numbers, push_uint};
use crate::row::{Class, Latch, Parts, Row, RowOut, RowResult, kind};
use crate::stats::{Column, Problems, Report};

/// Numbers of a channel row: 16 channels, CH17, CH18, FrameLost, Failsafe.
const PARTS: usize = CHANNELS + 4;

/// Counters kept while decoding (`--stats`).
#[derive(Clone, Debug, Default)]
pub struct Stats {
    pub sbus: u64,
    /// SBUS2 frames by the slot group they announce.
    pub sbus2: [u64; 4],
    /// SBUS2 frames at INAV's fast pace (end byte 08).
    pub fast: u64,
    pub frame_lost: u64,
    pub failsafe: u64,
    /// Answers per slot, and the last raw value.
    pub slots: [u64; 32],
    pub slot_last: [u16; 32],
    /// Slots answered after a frame that announced another group.
    pub slot_mismatch: u64,
    pub truncated: u64,
    pub wrong_end: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    last_frame: Option<u64>,
    interval_sum: u64,
    intervals: u64,
    interval_max: u64,
}

impl Stats {
    pub fn frames(&self) -> u64 {
        self.sbus + self.sbus2.iter().sum::<u64>() + self.fast
    }

    pub fn slot_answers(&self) -> u64 {
        self.slots.iter().sum()
    }
}

/// Maps events onto rows; keeps the scratch buffers and the statistics.
pub(super) struct Mapper {
    /// Line speed, for the times of sources without time.
    baud: u32,
    /// Microseconds a byte takes when that is a whole number (100000 and 200000 baud): the
    /// times of untimed sources without a division.
    byte_micros: Option<u64>,
    data: String,
    note: String,
    nums: Numbers<PARTS>,
    pub stats: Stats,
}

impl Mapper {
    pub fn new(baud: u32) -> Self {
        Mapper {
            baud: baud.max(1),
            byte_micros: {
                let bit_micros = u64::from(wire::BITS_PER_CHAR) * 1_000_000;
                let baud = u64::from(baud.max(1));
                (bit_micros % baud == 0).then_some(bit_micros / baud)
            },
            data: String::new(),
            note: String::new(),
            nums: Numbers::default(),
            stats: Stats::default(),
        }
    }

    /// The row's time: the source's, or the byte's place on the wire at the line's rate.
    fn micros(&self, time: Option<u64>, offset: u64) -> u64 {
        match time {
            Some(t) => t,
            None => match self.byte_micros.and_then(|m| offset.checked_mul(m)) {
                Some(us) => us,
                None => crate::protocol::untimed_micros(offset, wire::BITS_PER_CHAR, self.baud),
            },
        }
    }

    fn clear(&mut self) {
        self.data.clear();
        self.note.clear();
        self.nums.clear();
    }

    /// Writes the row of one event (a write error stays in the latch).
    pub fn event(&mut self, ev: Event<'_>, out: &mut Latch<'_>) {
        if out.stopped() {
            return;
        }
        let _ = match ev {
            Event::Frame {
                offset,
                time,
                bytes,
            } => {
                let micros = self.micros(time, offset);
                if let Some(d) = out.direct(super::COLUMNS) {
                    self.frame_stats(micros, time.is_some(), bytes);
                    super::direct::frame(d, micros, bytes);
                    return;
                }
                self.frame(micros, time.is_some(), bytes, out)
            }
            Event::Slot {
                offset,
                time,
                bytes,
                group,
                ..
            } => {
                let micros = self.micros(time, offset);
                if let Some(d) = out.direct(super::COLUMNS) {
                    let (n, other) = self.slot_stats(*bytes, group);
                    super::direct::slot(d, micros, bytes, n, other);
                    return;
                }
                self.slot(micros, *bytes, group, out)
            }
            Event::Broken {
                offset,
                time,
                why,
                bytes,
            } => self.broken(self.micros(time, offset), why, bytes, out),
        };
    }

    /// Counts a frame.
    fn frame_stats(&mut self, micros: u64, timed: bool, f: &[u8; FRAME_LEN]) {
        let st = &mut self.stats;
        let (flags, end) = (f[23], f[24]);
        match wire::slot_group(end) {
            Some(g) => st.sbus2[usize::from(g)] += 1,
            None if end == wire::END_FAST => st.fast += 1,
            None => st.sbus += 1,
        }
        if timed {
            if let Some(last) = st.last_frame {
                let d = micros.saturating_sub(last);
                st.interval_sum += d;
                st.intervals += 1;
                st.interval_max = st.interval_max.max(d);
            }
            st.last_frame = Some(micros);
        }
        let lost = flags & wire::FLAG_FRAME_LOST != 0;
        let failsafe = flags & wire::FLAG_FAILSAFE != 0;
        st.frame_lost += u64::from(lost);
        st.failsafe += u64::from(failsafe);
    }

    fn frame(
        &mut self,
        micros: u64,
        timed: bool,
        f: &[u8; FRAME_LEN],
        out: &mut dyn RowOut,
    ) -> RowResult {
        self.clear();
        self.frame_stats(micros, timed, f);
        let (flags, end) = (f[23], f[24]);
        let lost = flags & wire::FLAG_FRAME_LOST != 0;
        let failsafe = flags & wire::FLAG_FAILSAFE != 0;

        let raw = wire::channels(f);
        for (i, &r) in raw.iter().enumerate() {
            let us = wire::micros(r);
            if i > 0 {
                self.data.push(' ');
            }
            push_uint(&mut self.data, u64::from(us));
            self.nums.int(CH_NAMES[i], "us", i64::from(us));
        }
        let bit = |b: u8| i64::from(flags & b != 0);
        self.nums.int("CH17", "", bit(wire::FLAG_CH17));
        self.nums.int("CH18", "", bit(wire::FLAG_CH18));
        self.nums.int("FrameLost", "", bit(wire::FLAG_FRAME_LOST));
        self.nums.int("Failsafe", "", bit(wire::FLAG_FAILSAFE));

        let n = &mut self.note;
        for (name, b) in [
            ("CH17=", wire::FLAG_CH17),
            (" CH18=", wire::FLAG_CH18),
            (" FrameLost=", wire::FLAG_FRAME_LOST),
            (" Failsafe=", wire::FLAG_FAILSAFE),
        ] {
            n.push_str(name);
            n.push(if flags & b != 0 { '1' } else { '0' });
        }
        if flags & 0xF0 != 0 {
            n.push_str("; unused flag bits set (flags ");
            push_0x(n, flags);
            n.push(')');
        }
        match wire::slot_group(end) {
            Some(g) => {
                n.push_str("; ");
                n.push_str(group_text(g));
                n.push_str(" follow");
            }
            None if end == wire::END_FAST => n.push_str("; SBUS2 fast pace, no slots"),
            None => {}
        }
        n.push_str("; raw");
        for r in raw {
            n.push(' ');
            push_uint(n, u64::from(r));
        }
        let class = if lost || failsafe {
            Class::Warning
        } else {
            Class::Plain
        };
        let sensor = if end == wire::END_SBUS {
            "SBUS"
        } else {
            "SBUS2"
        };
        let extra = ["us", self.note.as_str()];
        let data = self.data.as_str();
        self.nums.with_parts(|parts| {
            out.row(&Row {
                stamp: 0,
                micros: Some(micros),
                id: None,
                device: "",
                kind: CHANNELS_TYPE,
                class,
                sensor_no: hex_0x(end),
                sensor,
                data,
                extra: &extra,
                parts: Parts::List(parts),
                raw: f,
            })
        })
    }

    /// Counts a slot answer: its slot number, and the group the frame before announced when
    /// that was another.
    fn slot_stats(&mut self, b: [u8; SLOT_LEN], group: u8) -> (u8, Option<u8>) {
        // The reassembler hands on slot ids only.
        let n = wire::slot_number(b[0]).unwrap_or(0);
        let st = &mut self.stats;
        st.slots[usize::from(n)] += 1;
        st.slot_last[usize::from(n)] = u16::from_be_bytes([b[1], b[2]]);
        if n / wire::SLOTS_PER_GROUP != group {
            st.slot_mismatch += 1;
            return (n, Some(group));
        }
        (n, None)
    }

    fn slot(
        &mut self,
        micros: u64,
        b: [u8; SLOT_LEN],
        group: u8,
        out: &mut dyn RowOut,
    ) -> RowResult {
        self.clear();
        let (n, other) = self.slot_stats(b, group);
        let value = u16::from_be_bytes([b[1], b[2]]);
        push_0x16(&mut self.data, value);
        self.nums
            .int(SLOT_NAMES[usize::from(n)], "", i64::from(value));
        let note = &mut self.note;
        if n == 0 {
            note.push_str("receiver voltage slot, raw value");
        } else {
            note.push_str("raw value (the sensor is assigned on the transmitter)");
        }
        let mut class = Class::Plain;
        if other.is_some() {
            class = Class::Warning;
            note.push_str("; answered after a frame announcing ");
            note.push_str(group_text(group));
        }
        let extra = ["", self.note.as_str()];
        let data = self.data.as_str();
        self.nums.with_parts(|parts| {
            out.row(&Row {
                stamp: 0,
                micros: Some(micros),
                id: Some(u32::from(n)),
                device: device(u32::from(n)),
                kind: SLOT_TYPE,
                class,
                sensor_no: hex_0x(b[0]),
                sensor: if n == 0 { RX_VOLTAGE } else { "" },
                data,
                extra: &extra,
                parts: Parts::List(parts),
                raw: &b,
            })
        })
    }

    fn broken(&mut self, micros: u64, why: Broken, b: &[u8], out: &mut dyn RowOut) -> RowResult {
        self.clear();
        let st = &mut self.stats;
        push_hex(&mut self.data, b);
        let note = &mut self.note;
        let len = b.len() as u64;
        let mut id = None;
        let kind = match why {
            Broken::Cut => {
                st.truncated += 1;
                push_uint(note, len);
                note.push_str(" of 25 bytes before the next frame start: frame cut short");
                kind::TRUNCATED
            }
            Broken::WrongEnd => {
                st.wrong_end += 1;
                note.push_str("0x0F and 24 bytes, but the last is ");
                push_0x(note, b[FRAME_LEN - 1]);
                note.push_str(", not an end byte (00, 04, 14, 24, 34, 08): not a frame");
                kind::GARBAGE
            }
            Broken::AtEnd if b[0] == wire::START => {
                st.truncated += 1;
                push_uint(note, len);
                note.push_str(" of 25 bytes before the input ended");
                kind::TRUNCATED
            }
            Broken::AtEnd | Broken::SlotCut => {
                st.truncated += 1;
                let n = wire::slot_number(b[0]).unwrap_or(0);
                id = Some(u32::from(n));
                push_uint(note, len);
                note.push_str(if why == Broken::SlotCut {
                    " of 3 bytes of a slot answer, then a frame"
                } else {
                    " of 3 bytes of a slot answer before the input ended"
                });
                kind::TRUNCATED
            }
            Broken::Garbage => {
                st.garbage_bytes += len;
                st.garbage_runs += 1;
                push_uint(note, len);
                note.push_str(if len == 1 {
                    " byte outside frames and slots"
                } else {
                    " bytes outside frames and slots"
                });
                kind::GARBAGE
            }
        };
        let extra = ["", self.note.as_str()];
        out.row(&Row {
            stamp: 0,
            micros: Some(micros),
            id,
            device: id.map_or("", device),
            kind,
            class: Class::Error,
            sensor_no: "",
            sensor: "",
            data: &self.data,
            extra: &extra,
            parts: Parts::NONE,
            raw: b,
        })
    }

    /// The `--stats` report.
    pub fn report(&self) -> Report {
        let st = &self.stats;
        let mut r = Report::new(&[
            Column::right("Slot", 4),
            Column::left("ID", 4).gap(2),
            Column::left("Device", 8).gap(2),
            Column::right("Answers", 8),
            Column::right("Last raw", 9).text(),
        ]);
        let g = &st.sbus2;
        r.head.push(format!(
            "frames: SBUS {}, SBUS2 {} (announcing slots 0-7 {}, 8-15 {}, 16-23 {}, 24-31 {}), \
             SBUS2 fast pace {}",
            st.sbus,
            g.iter().sum::<u64>(),
            g[0],
            g[1],
            g[2],
            g[3],
            st.fast
        ));
        r.head.push(format!(
            "frame lost set in {} frames, failsafe in {}",
            st.frame_lost, st.failsafe
        ));
        if st.intervals > 0 {
            r.head.push(format!(
                "frame interval: mean {:.1} ms, max {:.1} ms",
                st.interval_sum as f64 / st.intervals as f64 / 1000.0,
                st.interval_max as f64 / 1000.0
            ));
        }
        for (n, &count) in st.slots.iter().enumerate() {
            if count == 0 {
                continue;
            }
            let mut id = String::new();
            push_0x(&mut id, wire::slot_id(n as u8));
            let mut last = String::new();
            push_0x16(&mut last, st.slot_last[n]);
            r.row(vec![
                n.to_string(),
                id,
                device(n as u32).to_owned(),
                count.to_string(),
                last,
            ]);
        }
        r.totals.push(format!(
            "valid frames {}, slot answers {}, truncated {}, wrong end bytes {}, garbage {}, slots answered in another group's turn {}",
            st.frames(),
            st.slot_answers(),
            st.truncated,
            st.wrong_end,
            crate::stats::garbage(st.garbage_bytes, st.garbage_runs),
            st.slot_mismatch
        ));
        r
    }

    pub fn problems(&self) -> Problems {
        let st = &self.stats;
        let mut p = Problems::new("Futaba SBUS");
        p.count(
            "truncated_frames",
            st.truncated,
            "truncated frame",
            "truncated frames",
        )
        .count(
            "wrong_end_bytes",
            st.wrong_end,
            "frame with a wrong end byte",
            "frames with a wrong end byte",
        )
        .garbage(st.garbage_bytes, st.garbage_runs)
        .in_valid(st.frames(), "valid frame", "valid frames");
        p
    }
}
