//! FrSky S.Port (Smart Port): reassembly, the log table mapping, and statistics.
//!
//! The table mapping and the timing rule are documented in `docs/sport.md`.

pub mod names;
pub(crate) mod passthrough;
pub(crate) mod values;
pub(crate) mod vocab;
pub mod wire;

use std::fmt::Write as _;

use crate::fmt::{push_hex, push_u64};
use crate::protocol::{Decoder, Kind, Line, Protocol};
use crate::row::{Class, Row};
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Column, Problems, Report};
use wire::{BODY_LEN, Body, Event, Garbage, Reassembler, Slot};

/// Poll slot length used to reconstruct Millis for sources without time.
pub const SLOT_MICROS: u64 = 12_000;

/// Default serial speed.
pub const DEFAULT_BAUD: u32 = 57_600;

/// What the command line needs to know: 57600 baud 8N1 (inverted on the wire: the adapter must
/// invert, see docs/live.md).
pub const PROTOCOL: Protocol = Protocol {
    name: "S.Port",
    command: "sport",
    line: Line::n81(DEFAULT_BAUD),
    accepts: &[Kind::Raw, Kind::Serial, Kind::EdgeTxLog, Kind::Recording],
    accepts_text: "raw wire bytes, EdgeTX logs or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 10, 30, 4, 0],
    vocab: &vocab::VOCAB,
};

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Note"];

#[derive(Clone, Debug, Default)]
struct PhysStats {
    polls: u64,
    answers: u64,
    null: u64,
    data: u64,
    other: u64,
    crc_errors: u64,
    truncated: u64,
    last_poll: Option<u64>,
    interval_sum: u64,
    intervals: u64,
    interval_max: u64,
}

/// Counters kept while decoding (`--stats`).
#[derive(Clone, Debug)]
pub struct Stats {
    per: Vec<PhysStats>,
    pub valid_frames: u64,
    pub crc_errors: u64,
    pub truncated: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    pub check_bits: u64,
    pub unusual_escapes: u64,
    pub repeats: u64,
    last_body: Option<[u8; BODY_LEN]>,
}

impl Default for Stats {
    fn default() -> Self {
        Stats {
            per: vec![PhysStats::default(); 32],
            valid_frames: 0,
            crc_errors: 0,
            truncated: 0,
            garbage_bytes: 0,
            garbage_runs: 0,
            check_bits: 0,
            unusual_escapes: 0,
            repeats: 0,
            last_body: None,
        }
    }
}

/// Scratch buffers reused for every row.
#[derive(Default)]
struct Scratch {
    sensor_no: String,
    sensor: String,
    data: String,
    note: String,
    nums: values::SportNumbers,
}

impl Scratch {
    fn clear(&mut self) {
        self.sensor_no.clear();
        self.sensor.clear();
        self.data.clear();
        self.note.clear();
        self.nums.clear();
    }

    fn note(&mut self, text: &str) {
        crate::row::note_part(&mut self.note).push_str(text);
    }
}

/// The S.Port decoder: reassembler + table mapping + statistics.
#[derive(Default)]
pub struct SportDecoder {
    re: Reassembler,
    table: Mapper,
}

/// Maps reassembled slots onto rows and keeps the statistics.
#[derive(Default)]
struct Mapper {
    scratch: Scratch,
    stats: Stats,
}

impl SportDecoder {
    pub fn new() -> Self {
        Self::default()
    }
}

/// The S.Port decoder (every input kind [`PROTOCOL`] accepts is a byte stream).
pub fn decoder() -> Box<dyn Decoder> {
    Box::new(SportDecoder::new())
}

impl Mapper {
    /// Writes the row of one event (a write error stays in the latch).
    fn event(&mut self, ev: Event<'_>, out: &mut Latch<'_>) {
        if out.stopped() {
            return;
        }
        let _ = match ev {
            Event::Slot(s) => self.slot_row(s, out),
            Event::Garbage(g) => self.garbage_row(g, out),
        };
    }

    fn slot_row(&mut self, s: &Slot, out: &mut dyn RowOut) -> RowResult {
        let micros = s.time.unwrap_or(s.index * SLOT_MICROS);
        let phys = s.phys();
        let sc = &mut self.scratch;
        sc.clear();
        let st = &mut self.stats;
        let ps = &mut st.per[phys as usize];
        ps.polls += 1;
        if let Some(last) = ps.last_poll {
            let d = micros.saturating_sub(last);
            ps.interval_sum += d;
            ps.intervals += 1;
            ps.interval_max = ps.interval_max.max(d);
        }
        ps.last_poll = Some(micros);

        let mut class = Class::Plain;
        let mut unit = "";
        let kind: &str = match s.body {
            Body::None => "",
            Body::Truncated { bytes, len } => {
                ps.truncated += 1;
                st.truncated += 1;
                class = Class::Error;
                push_hex(&mut sc.data, &bytes[..len as usize]);
                let _ = write!(
                    sc.note,
                    "{len} of {BODY_LEN} bytes before the frame was cut"
                );
                crate::row::kind::TRUNCATED
            }
            Body::Complete(b) => {
                ps.answers += 1;
                if st.last_body == Some(b) {
                    st.repeats += 1;
                }
                st.last_body = Some(b);
                let app_id = u16::from_le_bytes([b[1], b[2]]);
                let value = u32::from_le_bytes([b[3], b[4], b[5], b[6]]);
                let ok = wire::crc_ok(&b);
                // Firmware-update frames (`7E FF 50 …` from the radio, `7E 5E 50 …` from the
                // device) carry their own checksum instead of the S.Port sum (EdgeTX
                // `radio/src/io/frsky_firmware_update.cpp`).
                let firmware = b[0] == 0x50 && matches!(s.header, 0xFF | 0x5E);
                if firmware {
                    ps.other += 1;
                    st.valid_frames += 1;
                    push_hex(&mut sc.data, &b[1..]);
                    sc.note("firmware update frame, own checksum not checked");
                    "FwUpdate"
                } else {
                    if ok {
                        st.valid_frames += 1;
                        match b[0] {
                            0x00 => ps.null += 1,
                            0x10 => ps.data += 1,
                            _ => ps.other += 1,
                        }
                    } else {
                        ps.crc_errors += 1;
                        st.crc_errors += 1;
                        class = Class::Error;
                    }
                    unit = describe(b[0], s.header, app_id, value, sc);
                    if !ok {
                        // A number that failed its check is not one to chart: Data shows it,
                        // Value stays empty.
                        sc.nums.clear();
                        let expected = wire::crc(&b[..7]);
                        let type_name = names::frame_type(b[0]).unwrap_or("unknown");
                        let mut note = String::new();
                        let _ = write!(
                            note,
                            "CRC 0x{:02X}, expected 0x{expected:02X} ({type_name} frame)",
                            b[7]
                        );
                        sc.note(&note);
                        crate::row::kind::BAD_CRC
                    } else {
                        match names::frame_type(b[0]) {
                            Some(n) => {
                                if b[0] == 0x00 {
                                    class = Class::Quiet;
                                }
                                n
                            }
                            None => {
                                class = Class::Warning;
                                let mut note = String::new();
                                let _ = write!(note, "unknown frame type 0x{:02X}", b[0]);
                                sc.note(&note);
                                "Unknown"
                            }
                        }
                    }
                }
            }
        };
        if !wire::header_ok(s.header) {
            st.check_bits += 1;
            let mut note = String::new();
            let _ = write!(note, "non-standard check bits (header 0x{:02X})", s.header);
            sc.note(&note);
            if class == Class::Plain || class == Class::Quiet {
                class = Class::Warning;
            }
        }
        if s.unusual_escape {
            st.unusual_escapes += 1;
            sc.note("unusual escape (0x7D not followed by 0x5E/0x5D)");
            if class != Class::Error {
                class = Class::Warning;
            }
        }
        let extra = [unit, sc.note.as_str()];
        sc.nums.with_parts(|parts| {
            out.row(&Row {
                micros: Some(micros),
                id: Some(phys as u32),
                device: names::device(phys),
                kind,
                class,
                sensor_no: &sc.sensor_no,
                sensor: &sc.sensor,
                data: &sc.data,
                extra: &extra,
                parts,
                raw: s.wire(),
            })
        })
    }

    fn garbage_row(&mut self, g: &Garbage, out: &mut dyn RowOut) -> RowResult {
        let micros = g
            .time
            .unwrap_or(g.after_slot.map_or(0, |i| i * SLOT_MICROS));
        let sc = &mut self.scratch;
        sc.clear();
        self.stats.garbage_bytes += g.bytes().len() as u64;
        self.stats.garbage_runs += 1;
        push_hex(&mut sc.data, g.bytes());
        if g.bytes() == [wire::START] {
            sc.note.push_str("0x7E without a header byte");
        } else {
            push_u64(&mut sc.note, g.bytes().len() as u64);
            sc.note.push_str(if g.after_slot.is_some() {
                " bytes after a complete frame"
            } else {
                " bytes before the first 0x7E"
            });
        }
        let extra = ["", sc.note.as_str()];
        out.row(&Row {
            micros: Some(micros),
            id: None,
            device: "",
            kind: crate::row::kind::GARBAGE,
            class: Class::Error,
            sensor_no: "",
            sensor: "",
            data: &sc.data,
            extra: &extra,
            parts: &[],
            raw: g.bytes(),
        })
    }
}

/// Fills Sensor #, Sensor, Data and Note for a complete frame of type `kind`; returns the unit.
fn describe(kind: u8, header: u8, app_id: u16, value: u32, sc: &mut Scratch) -> &'static str {
    match kind {
        0x10 => {
            values::push_sensor_no(&mut sc.sensor_no, app_id);
            values::decode_numbers(
                header & 0x1F,
                app_id,
                value,
                &mut sc.sensor,
                &mut sc.data,
                &mut sc.nums,
            )
        }
        0x00 => {
            // Keep-alive: the sample leaves Sensor #/Sensor/Data empty; Pawelsky-style sensors
            // name the app ID due next, which is worth showing.
            if app_id != 0 {
                values::push_sensor_no(&mut sc.sensor_no, app_id);
                values::label(app_id, &mut sc.sensor);
            }
            if value != 0 {
                let _ = write!(sc.data, "value=0x{value:08X}");
                sc.note("keep-alive with a non-zero value");
            }
            ""
        }
        0x20 | 0x21 => {
            values::push_sensor_no(&mut sc.sensor_no, app_id);
            values::label(app_id, &mut sc.sensor);
            let _ = write!(sc.data, "value=0x{value:08X}");
            sc.note(names::frame_type_long(kind));
            ""
        }
        0x30..=0x32 => {
            values::push_sensor_no(&mut sc.sensor_no, app_id);
            values::label(app_id, &mut sc.sensor);
            let mut payload = [0u8; 6];
            payload[..2].copy_from_slice(&app_id.to_le_bytes());
            payload[2..].copy_from_slice(&value.to_le_bytes());
            push_hex(&mut sc.data, &payload);
            config_note(kind, header, value, sc);
            ""
        }
        _ => {
            let mut payload = [0u8; 6];
            payload[..2].copy_from_slice(&app_id.to_le_bytes());
            payload[2..].copy_from_slice(&value.to_le_bytes());
            push_hex(&mut sc.data, &payload);
            ""
        }
    }
}

/// Notes for read/write/reply frames: FrSky configuration fields, or MSP/MAVlite traffic.
fn config_note(kind: u8, header: u8, value: u32, sc: &mut Scratch) {
    let phys = header & 0x1F;
    if phys == 13 {
        sc.note("uplink (MSP/MAVlite request)");
        return;
    }
    if kind == 0x32 && matches!(phys, 7 | 20 | 27) {
        sc.note("downlink (MSP/MAVlite reply)");
        return;
    }
    let field = value as u8;
    let arg = value >> 8;
    let mut note = String::new();
    match (kind, field) {
        (0x30, 0x01) => note.push_str("config: read physical ID"),
        (0x31, 0x01) => {
            let _ = write!(note, "config: set physical ID to {arg}");
        }
        (0x32, 0x01) => {
            let _ = write!(note, "config: physical ID is {arg}");
        }
        _ => {
            let _ = write!(note, "{} field 0x{field:02X}", names::frame_type_long(kind));
        }
    }
    sc.note(&note);
}

impl Decoder for SportDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        let table = &mut self.table;
        self.re.push(data, time, &mut |e| table.event(e, &mut out));
        out.result()
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        let table = &mut self.table;
        self.re.finish(&mut |e| table.event(e, &mut out));
        out.result()
    }

    fn valid_frames(&self) -> u64 {
        self.table.stats.valid_frames
    }

    fn stats(&self) -> Report {
        let st = &self.table.stats;
        let mut r = Report::new(&[
            Column::right("ID", 3),
            Column::left("Device", 10).gap(2),
            Column::right("Polls", 8),
            Column::right("Answers", 8),
            Column::right("Null", 8),
            Column::right("Data", 8),
            Column::right("Other", 6),
            Column::right("BadCRC", 7),
            Column::right("Trunc", 6),
            Column::right("Mean ms", 8),
            Column::right("Max ms", 8),
        ]);
        r.head.push(
            "Polls: polls of the ID; Answers: frames it sent; Mean ms, Max ms: poll interval \
             (time between two polls of the ID)"
                .into(),
        );
        let counts = |p: &PhysStats| {
            [
                p.polls,
                p.answers,
                p.null,
                p.data,
                p.other,
                p.crc_errors,
                p.truncated,
            ]
            .map(|n| n.to_string())
        };
        let mut total = PhysStats::default();
        for (phys, p) in st.per.iter().enumerate() {
            if p.polls == 0 {
                continue;
            }
            total.polls += p.polls;
            total.answers += p.answers;
            total.null += p.null;
            total.data += p.data;
            total.other += p.other;
            total.crc_errors += p.crc_errors;
            total.truncated += p.truncated;
            let (mean, max) = if p.intervals > 0 {
                (
                    format!("{:.1}", p.interval_sum as f64 / p.intervals as f64 / 1000.0),
                    format!("{:.1}", p.interval_max as f64 / 1000.0),
                )
            } else {
                ("-".into(), "-".into())
            };
            let mut cells = vec![phys.to_string(), names::device(phys as u8).to_owned()];
            cells.extend(counts(p));
            cells.extend([mean, max]);
            r.row(cells);
        }
        let mut cells = vec!["all".to_owned(), String::new()];
        cells.extend(counts(&total));
        r.row(cells);
        r.totals.push(format!(
            "valid frames {}, garbage {} bytes in {} runs, non-standard check bits {}, unusual escapes {}, repeated frames {}",
            st.valid_frames,
            st.garbage_bytes,
            st.garbage_runs,
            st.check_bits,
            st.unusual_escapes,
            st.repeats
        ));
        r
    }

    fn problems(&self) -> Problems {
        let st = &self.table.stats;
        let mut p = Problems::new("S.Port");
        p.count(st.crc_errors, "CRC error", "CRC errors")
            .count(st.truncated, "truncated frame", "truncated frames")
            .garbage(st.garbage_bytes, st.garbage_runs)
            .count(st.unusual_escapes, "unusual escape", "unusual escapes")
            // "in 1 valid frames": the count is not made singular (as it always was).
            .in_valid(st.valid_frames, "valid frames", "valid frames");
        p
    }

    fn no_frames_hint(&self) -> &'static str {
        "wrong baud rate (S.Port runs at 57600, the TX16S/F16 mirror at 115200) or the signal is \
         not inverted (S.Port needs an inverting adapter or an FTDI with inverted RX, see docs/live.md)"
    }
}
