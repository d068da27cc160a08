//! iBUS frames, exchanges and broken bytes onto the log table (documented in `docs/ibus.md`),
//! and the statistics.

use super::names::CH_NAMES;
pub use super::names::{CHANNELS, DISCOVER, MEASURE, OTHER, SENSOR_TYPE, UNKNOWN};
use super::sensors::{self, SensorType};
use super::wire::{self, Broken, Event, Located};
use crate::fmt::{hex_0x, push_0x, push_0x16, push_hex};
use crate::numbers::{Numbers, push_uint};
use crate::row::{Class, Latch, Parts, Row, RowOut, RowResult, kind};
use crate::stats::{Column, Problems, Report};

/// Numbers of a row: at most the 18 channels of an RC frame.
const PARTS: usize = wire::RC_CHANNELS_MAX;

/// Addresses on the sensor bus (the low nibble of the command byte; sensors use 1-15).
pub const ADDRESSES: usize = 16;

/// What the table learned about an address.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Learned {
    /// The type code, from a type answer (or the options).
    pub code: u8,
    /// The value width the sensor announced (0 when given by the options).
    pub size: u8,
}

/// Counters of one address.
#[derive(Clone, Debug, Default)]
pub struct AddrStats {
    /// Polls by command: discover, type, measure, other.
    pub polls: [u64; 4],
    pub answered: u64,
    pub bad_crc: u64,
    /// The last measurement: the type it was read in and its value bytes.
    pub last: Option<LastValue>,
}

/// A measurement's value bytes (the first 4 of `len`) and the type they were read in.
#[derive(Clone, Copy, Debug, Default)]
pub struct LastValue {
    pub learned: Option<Learned>,
    pub bytes: [u8; 4],
    pub len: u8,
}

impl LastValue {
    fn new(learned: Option<Learned>, value: &[u8]) -> Self {
        let mut bytes = [0u8; 4];
        let n = value.len().min(4);
        bytes[..n].copy_from_slice(&value[..n]);
        LastValue {
            learned,
            bytes,
            len: value.len() as u8,
        }
    }

    /// As the Data column showed it, with the unit.
    pub fn text(&self) -> String {
        let mut value = [0u8; wire::MAX_LEN];
        value[..4].copy_from_slice(&self.bytes);
        let value = &value[..usize::from(self.len)];
        let mut nums: Numbers<PARTS> = Numbers::default();
        let (mut data, mut note) = (String::new(), String::new());
        let unit = measure_cells(self.learned, value, &mut nums, &mut data, &mut note);
        if !unit.is_empty() {
            data.push(' ');
            data.push_str(unit);
        }
        data
    }
}

/// The Data text, numbers and notes of a measurement read in the type `learned`; returns the
/// unit.
fn measure_cells(
    learned: Option<Learned>,
    value: &[u8],
    nums: &mut Numbers<PARTS>,
    data: &mut String,
    note: &mut String,
) -> &'static str {
    let ty: Option<&SensorType> = learned.and_then(|l| sensors::sensor_type(l.code));
    if learned.is_some() && ty.is_none() {
        // A type code busnoop does not know: raw, named by the type.
        let r = sensors::raw(value);
        nums.int("Raw", "", i64::from(r));
        data.push_str("0x");
        for &b in value.iter().take(4).rev() {
            crate::fmt::push_hex_u8(data, b);
        }
        crate::row::note_part(note).push_str("type not in Betaflight's or EdgeTX's tables: raw");
        ""
    } else {
        sensors::decode(ty, value, nums, data, note)
    }
}

/// Counters kept while decoding (`--stats`).
#[derive(Clone, Debug, Default)]
pub struct Stats {
    pub per: [AddrStats; ADDRESSES],
    pub valid_frames: u64,
    pub rc_frames: u64,
    /// RC frames carrying channels 15-18 in the high nibbles.
    pub rc_18: u64,
    /// Answers whose poll was not seen (the capture started between them).
    pub stray_answers: u64,
    pub unknown: u64,
    pub bad_crc: u64,
    pub truncated: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
}

impl Stats {
    pub fn unanswered(&self) -> u64 {
        self.per
            .iter()
            .map(|a| a.polls.iter().sum::<u64>() - a.answered)
            .sum()
    }
}

/// Maps events onto rows; keeps the scratch buffers, the types learned and the statistics.
pub(super) struct Mapper {
    baud: u32,
    types: [Option<Learned>; ADDRESSES],
    data: String,
    note: String,
    raw: Vec<u8>,
    nums: Numbers<PARTS>,
    pub stats: Stats,
}

/// The command index of the statistics (discover, type, measure, other).
fn cmd_index(cmd: u8) -> usize {
    match cmd {
        wire::CMD_DISCOVER => 0,
        wire::CMD_TYPE => 1,
        wire::CMD_MEASURE => 2,
        _ => 3,
    }
}

fn cmd_words(cmd: u8) -> &'static str {
    match cmd {
        wire::CMD_DISCOVER => "discover",
        wire::CMD_TYPE => "type query",
        wire::CMD_MEASURE => "measurement",
        _ => "command",
    }
}

impl Mapper {
    pub fn new(baud: u32, preset: &[(u8, u8)]) -> Self {
        let mut types = [None; ADDRESSES];
        for &(addr, code) in preset {
            if let Some(t) = types.get_mut(usize::from(addr)) {
                *t = Some(Learned { code, size: 0 });
            }
        }
        Mapper {
            baud: baud.max(1),
            types,
            data: String::new(),
            note: String::new(),
            raw: Vec::new(),
            nums: Numbers::default(),
            stats: Stats::default(),
        }
    }

    /// The type learned for an address.
    pub fn learned(&self, addr: u8) -> Option<Learned> {
        self.types[usize::from(addr & 0x0F)]
    }

    fn micros(&self, at: &Located<'_>) -> u64 {
        match at.time {
            Some(t) => t,
            None => crate::protocol::untimed_micros(at.offset, wire::BITS_PER_CHAR, self.baud),
        }
    }

    fn clear(&mut self) {
        self.data.clear();
        self.note.clear();
        self.raw.clear();
        self.nums.clear();
    }

    fn note(&mut self, text: &str) {
        crate::row::note_part(&mut self.note).push_str(text);
    }

    /// Writes the row of one event (a write error stays in the latch).
    pub fn event(&mut self, ev: Event<'_>, out: &mut Latch<'_>) {
        if out.stopped() {
            return;
        }
        let _ = match ev {
            Event::Exchange { poll, answer } => self.exchange(poll, answer, out),
            Event::Frame(f) => self.frame(f, out),
            Event::Broken { at, why } => self.broken(at, why, out),
        };
    }

    /// The Sensor # and Sensor of an address whose type is known.
    fn sensor_cells(&self, addr: u8) -> (&'static str, &'static str) {
        match self.learned(addr) {
            Some(l) => (
                hex_0x(l.code),
                sensors::sensor_type(l.code).map_or("", |t| t.name),
            ),
            None => ("", ""),
        }
    }

    fn exchange(
        &mut self,
        poll: Located<'_>,
        answer: Option<Located<'_>>,
        out: &mut dyn RowOut,
    ) -> RowResult {
        let micros = self.micros(&poll);
        let cmd = poll.bytes[1] >> 4;
        let addr = poll.bytes[1] & 0x0F;
        let st = &mut self.stats.per[usize::from(addr)];
        st.polls[cmd_index(cmd)] += 1;
        self.stats.valid_frames += 1;
        let Some(a) = answer else {
            self.clear();
            self.raw.extend_from_slice(poll.bytes);
            let n = crate::row::note_part(&mut self.note);
            n.push_str(cmd_words(cmd));
            if cmd_index(cmd) == 3 {
                n.push(' ');
                push_0x(n, poll.bytes[1] & 0xF0);
            }
            n.push_str(" poll, no answer");
            let (sensor_no, sensor) = self.sensor_cells(addr);
            return self.write(
                out,
                micros,
                Some(addr),
                "",
                Class::Plain,
                sensor_no,
                sensor,
                "",
            );
        };
        st.answered += 1;
        self.stats.valid_frames += 1;
        if cmd == wire::CMD_MEASURE
            && let Some(t) = self.direct_type(addr, a.bytes)
            && let Some(d) = out.direct(super::COLUMNS)
        {
            let value = &a.bytes[2..a.bytes.len() - 2];
            let learned = self.learned(addr);
            self.stats.per[usize::from(addr)].last = Some(LastValue::new(learned, value));
            let mut raw = [0u8; 12];
            raw[..4].copy_from_slice(poll.bytes);
            raw[4..4 + a.bytes.len()].copy_from_slice(a.bytes);
            let r = sensors::raw(value);
            super::direct::measure(d, micros, addr, t, r, &raw[..4 + a.bytes.len()]);
            return Ok(());
        }
        self.clear();
        self.raw.extend_from_slice(poll.bytes);
        self.raw.extend_from_slice(a.bytes);
        match cmd {
            wire::CMD_DISCOVER => {
                self.data.push_str("present");
                self.note("the sensor echoed the poll");
                let (sensor_no, sensor) = self.sensor_cells(addr);
                self.write(
                    out,
                    micros,
                    Some(addr),
                    "",
                    Class::Plain,
                    sensor_no,
                    sensor,
                    DISCOVER,
                )
            }
            wire::CMD_TYPE => self.type_answer(micros, addr, a.bytes, out),
            wire::CMD_MEASURE => self.measurement(micros, addr, a.bytes, out),
            _ => {
                push_hex(&mut self.data, &a.bytes[2..a.bytes.len() - 2]);
                let n = crate::row::note_part(&mut self.note);
                n.push_str("command ");
                push_0x(n, poll.bytes[1] & 0xF0);
                n.push_str(" answered");
                self.write(out, micros, Some(addr), "", Class::Warning, "", "", OTHER)
            }
        }
    }

    /// The type of an address whose measurement answer `a` is decoded in units, which the
    /// direct rows write: a known type, not raw, with the width it expects.
    fn direct_type(&self, addr: u8, a: &[u8]) -> Option<&'static SensorType> {
        let t = sensors::sensor_type(self.learned(addr)?.code)?;
        (sensors::width(t.enc)? == a.len() - 4).then_some(t)
    }

    /// `06 9a [type][size] chk`: the address's type, learned from here on.
    fn type_answer(&mut self, micros: u64, addr: u8, a: &[u8], out: &mut dyn RowOut) -> RowResult {
        let (code, size) = (a[2], a[3]);
        let before = self.types[usize::from(addr)];
        self.types[usize::from(addr)] = Some(Learned { code, size });
        let ty = sensors::sensor_type(code);
        let name = ty.map_or("", |t| t.name);
        match ty {
            Some(t) => {
                self.data.push_str(t.name);
                self.note(t.long);
            }
            None => {
                push_0x(&mut self.data, code);
                self.note("type not in Betaflight's or EdgeTX's tables");
            }
        }
        self.data.push_str(", ");
        push_uint(&mut self.data, u64::from(size));
        self.data.push_str(" bytes");
        if let Some(b) = before
            && b.code != code
        {
            let n = crate::row::note_part(&mut self.note);
            n.push_str("type changed from ");
            push_0x(n, b.code);
        }
        self.write(
            out,
            micros,
            Some(addr),
            "",
            Class::Plain,
            hex_0x(code),
            name,
            SENSOR_TYPE,
        )
    }

    /// `06 Aa [LE16] chk` or `08 Aa [LE32] chk`: the value in the address's type.
    fn measurement(&mut self, micros: u64, addr: u8, a: &[u8], out: &mut dyn RowOut) -> RowResult {
        let learned = self.learned(addr);
        let value = &a[2..a.len() - 2];
        let unit = measure_cells(
            learned,
            value,
            &mut self.nums,
            &mut self.data,
            &mut self.note,
        );
        self.stats.per[usize::from(addr)].last = Some(LastValue::new(learned, value));
        let (sensor_no, sensor) = self.sensor_cells(addr);
        self.write(
            out,
            micros,
            Some(addr),
            unit,
            Class::Plain,
            sensor_no,
            sensor,
            MEASURE,
        )
    }

    /// A valid frame that is no poll and answers none.
    fn frame(&mut self, f: Located<'_>, out: &mut dyn RowOut) -> RowResult {
        let micros = self.micros(&f);
        let b = f.bytes;
        self.stats.valid_frames += 1;
        if b.len() == usize::from(wire::RC_LEN)
            && b[1] == wire::RC_CMD
            && let Some(d) = out.direct(super::COLUMNS)
        {
            self.stats.rc_frames += 1;
            if super::direct::rc(d, micros, b) {
                self.stats.rc_18 += 1;
            }
            return Ok(());
        }
        self.clear();
        self.raw.extend_from_slice(b);
        if b.len() == usize::from(wire::RC_LEN) {
            if b[1] != wire::RC_CMD {
                let n = crate::row::note_part(&mut self.note);
                n.push_str("command byte ");
                push_0x(n, b[1]);
                n.push_str(", not 0x40 (read as channels, as Betaflight does)");
            }
            return self.rc(micros, b, out);
        }
        let cmd = b[1] >> 4;
        let addr = b[1] & 0x0F;
        if b.len() == 6 && cmd == wire::CMD_TYPE {
            self.stats.stray_answers += 1;
            self.note("answer without its poll");
            return self.type_answer(micros, addr, b, out);
        }
        if b.len() > wire::MIN_LEN && cmd == wire::CMD_MEASURE {
            self.stats.stray_answers += 1;
            self.note("answer without its poll");
            return self.measurement(micros, addr, b, out);
        }
        self.stats.unknown += 1;
        push_hex(&mut self.data, &b[1..b.len() - 2]);
        self.note("a valid frame of no known kind");
        self.write(out, micros, None, "", Class::Warning, "", "", UNKNOWN)
    }

    /// `20 40` + 14 channel slots: channels 1-14, and 15-18 when the high nibbles carry them.
    fn rc(&mut self, micros: u64, b: &[u8], out: &mut dyn RowOut) -> RowResult {
        self.stats.rc_frames += 1;
        let (ch, high) = wire::rc_channels(b);
        let n = if high {
            self.stats.rc_18 += 1;
            wire::RC_CHANNELS_MAX
        } else {
            wire::RC_SLOTS
        };
        for (i, &c) in ch[..n].iter().enumerate() {
            if i > 0 {
                self.data.push(' ');
            }
            push_uint(&mut self.data, u64::from(c));
            self.nums.int(CH_NAMES[i], "us", i64::from(c));
        }
        self.note(if high {
            "18 channels (15-18 from the high nibbles)"
        } else {
            "14 channels"
        });
        self.write(out, micros, None, "us", Class::Plain, "", "", CHANNELS)
    }

    fn broken(&mut self, at: Located<'_>, why: Broken, out: &mut dyn RowOut) -> RowResult {
        self.clear();
        let micros = self.micros(&at);
        let b = at.bytes;
        self.raw.extend_from_slice(b);
        push_hex(&mut self.data, b);
        // The sensor address of a poll or answer (RC frames and garbage have none).
        let sensor_frame = b.len() >= 2 && wire::known_header(b[0], b[1]) && b[0] != wire::RC_LEN;
        let addr = sensor_frame.then(|| b[1] & 0x0F);
        let what = match (b.first(), b.get(1)) {
            (Some(&wire::RC_LEN), _) => "RC frame",
            (Some(4), Some(&c)) => cmd_words_poll(c >> 4),
            (Some(_), Some(&c)) if c >> 4 == wire::CMD_TYPE => "type answer",
            (Some(_), Some(_)) => "measurement answer",
            _ => "frame",
        };
        let kind = match why {
            Broken::BadCheck => {
                self.stats.bad_crc += 1;
                if let Some(a) = addr {
                    self.stats.per[usize::from(a)].bad_crc += 1;
                }
                let n = crate::row::note_part(&mut self.note);
                n.push_str("checksum ");
                push_0x16(n, wire::carried(b));
                n.push_str(", expected ");
                push_0x16(n, wire::checksum(&b[..b.len() - 2]));
                n.push_str(" (");
                n.push_str(what);
                n.push(')');
                kind::BAD_CRC
            }
            Broken::Cut | Broken::AtEnd => {
                self.stats.truncated += 1;
                let n = crate::row::note_part(&mut self.note);
                push_uint(n, b.len() as u64);
                n.push_str(" of ");
                push_uint(n, u64::from(b[0]));
                n.push_str(" bytes of a ");
                n.push_str(what);
                n.push_str(if why == Broken::Cut {
                    ", then a frame starts"
                } else {
                    " before the input ended"
                });
                kind::TRUNCATED
            }
            Broken::Garbage => {
                self.stats.garbage_bytes += b.len() as u64;
                self.stats.garbage_runs += 1;
                let n = crate::row::note_part(&mut self.note);
                push_uint(n, b.len() as u64);
                n.push_str(if b.len() == 1 {
                    " byte outside frames"
                } else {
                    " bytes outside frames"
                });
                kind::GARBAGE
            }
        };
        self.write(out, micros, addr, "", Class::Error, "", "", kind)
    }

    /// Writes the row from the scratch buffers.
    #[allow(clippy::too_many_arguments)]
    fn write(
        &self,
        out: &mut dyn RowOut,
        micros: u64,
        addr: Option<u8>,
        unit: &str,
        class: Class,
        sensor_no: &str,
        sensor: &str,
        kind: &str,
    ) -> RowResult {
        let extra = [unit, self.note.as_str()];
        self.nums.with_parts(|parts| {
            out.row(&Row {
                stamp: 0,
                micros: Some(micros),
                id: addr.map(u32::from),
                device: "",
                kind,
                class,
                sensor_no,
                sensor,
                data: &self.data,
                extra: &extra,
                parts: Parts::List(parts),
                raw: &self.raw,
            })
        })
    }

    /// The `--stats` report.
    pub fn report(&self) -> Report {
        let st = &self.stats;
        let mut r = Report::new(&[
            Column::right("ID", 3),
            Column::left("Sensor", 6).gap(2),
            Column::right("Discover", 8),
            Column::right("Type", 6),
            Column::right("Measure", 8),
            Column::right("Answered", 8),
            Column::right("NoAnswer", 8),
            Column::right("BadCRC", 7),
            Column::left("Last value", 0).gap(2),
        ]);
        r.head.push(
            "polls of each address by command; Answered: polls with an answer; NoAnswer: polls \
             without one (a daisy-chained sensor's own polls, or no sensor there)"
                .into(),
        );
        r.head.push(format!(
            "RC frames {} ({} with channels 15-18)",
            st.rc_frames, st.rc_18
        ));
        for (addr, a) in st.per.iter().enumerate() {
            let polls: u64 = a.polls.iter().sum();
            if polls == 0 && a.bad_crc == 0 {
                continue;
            }
            let sensor = self.learned(addr as u8).map_or(String::new(), |l| {
                match sensors::sensor_type(l.code) {
                    Some(t) => t.name.to_owned(),
                    None => format!("0x{:02X}", l.code),
                }
            });
            r.row(vec![
                addr.to_string(),
                sensor,
                (a.polls[0]).to_string(),
                (a.polls[1]).to_string(),
                (a.polls[2]).to_string(),
                a.answered.to_string(),
                (polls - a.answered).to_string(),
                a.bad_crc.to_string(),
                a.last.map_or(String::new(), |l| l.text()),
            ]);
        }
        r.totals.push(format!(
            "valid frames {}, unanswered polls {}, answers without their poll {}, unknown frames \
             {}, bad checksums {}, truncated {}, garbage {}",
            st.valid_frames,
            st.unanswered(),
            st.stray_answers,
            st.unknown,
            st.bad_crc,
            st.truncated,
            crate::stats::garbage(st.garbage_bytes, st.garbage_runs)
        ));
        r
    }

    pub fn problems(&self) -> Problems {
        let st = &self.stats;
        let mut p = Problems::new("FlySky iBUS");
        p.count(
            "crc_errors",
            st.bad_crc,
            "checksum error",
            "checksum errors",
        )
        .count(
            "truncated_frames",
            st.truncated,
            "truncated frame",
            "truncated frames",
        )
        .garbage(st.garbage_bytes, st.garbage_runs)
        .in_valid(st.valid_frames, "valid frame", "valid frames");
        p
    }
}

/// A poll's command in words, for the Note of a broken poll.
fn cmd_words_poll(cmd: u8) -> &'static str {
    match cmd {
        wire::CMD_DISCOVER => "discover poll",
        wire::CMD_TYPE => "type query",
        wire::CMD_MEASURE => "measurement poll",
        _ => "poll",
    }
}
