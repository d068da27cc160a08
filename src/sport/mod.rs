//! FrSky S.Port (Smart Port): reassembly, the log table mapping, and statistics.
//!
//! The table mapping and the timing rule are documented in `docs/sport.md`.

mod args;
mod direct;
pub mod names;
pub(crate) mod passthrough;
pub(crate) mod values;
pub(crate) mod vocab;
pub mod wire;

use crate::fmt::{push_0x, push_hex, push_hex_u8, push_u64};
use crate::numbers::push_uint;
use crate::protocol::{Decoder, Export, Front, InputKind, Line, Probe, Protocol, Variant};
use crate::row::{Class, Row};
use crate::row::{Latch, RowOut, RowResult};
use crate::stats::{Column, Problems, Report};
use wire::{BODY_LEN, Body, Event, Garbage, Reassembler, Slot};

/// Poll slot length used to reconstruct Millis for sources without time.
pub const SLOT_MICROS: u64 = 12_000;

/// Default serial speed.
pub const DEFAULT_BAUD: u32 = 57_600;

/// FrSky S.Port: 57600 baud 8N1, inverted on the wire (the adapter must invert, see
/// docs/live.md).
pub const PROTOCOL: Protocol = Protocol {
    name: "S.Port",
    command: "sport",
    aliases: &[],
    summary: "FrSky S.Port: polls `7E id`, 8-byte responses, byte stuffing, sum CRC (57600 baud)",
    about: "FrSky S.Port (Smart Port) telemetry: the receiver polls `7E id`, sensors answer with \
            8-byte frames (byte stuffing, sum CRC). 57600 baud 8N1, inverted on the wire: the \
            adapter must invert (docs/live.md). The table follows the S-Port_Snoop sample.",
    examples: "Examples:\n  busnoop sport /dev/ttyUSB0\n  busnoop sport flight.log --hide-polls \
               --sensor VFAS\n  busnoop sport capture.bin -o capture.csv",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, an EdgeTX/OpenTX S.Port debug log, a busnoop \
                  .pcap or .pcapng recording) or `-` for standard input. File kinds are \
                  recognised by content.",
    line: Line::n81(DEFAULT_BAUD),
    inverted: true,
    rates: &[DEFAULT_BAUD],
    accepts: &[
        InputKind::Raw,
        InputKind::Serial,
        InputKind::EdgeTxLog,
        InputKind::Recording,
    ],
    accepts_text: "raw wire bytes, EdgeTX logs or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 3, 10, 9, 8, 10, 30, 4, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[],
    export: Some(Export {
        linktype: crate::pcap::linktype::USER0,
        linktype_name: "USER0",
        dissector: "busnoop-sport.lua",
        extcap: "FrSky S.Port (busnoop)",
        wrap: None,
    }),
};

/// `detect` reads S.Port one way (the inverted line is tried for every inverted protocol).
fn variants(_: &Probe) -> Vec<Variant> {
    vec![Variant {
        label: "S.Port",
        args: &[],
        decoder: decoder(),
    }]
}

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Note"];

#[derive(Clone, Debug, Default)]
struct PhysStats {
    polls: u64,
    null: u64,
    data: u64,
    other: u64,
    crc_errors: u64,
    truncated: u64,
    /// The time of the last poll (when `polls > 0`).
    last_poll: u64,
    interval_sum: u64,
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

impl PhysStats {
    /// Counts a poll of `phys` at `micros` (and the interval since its last one) in `per`.
    #[inline]
    fn poll(per: &mut [PhysStats], phys: u8, micros: u64) -> &mut PhysStats {
        let ps = &mut per[usize::from(phys & 0x1F)];
        if ps.polls > 0 {
            let d = micros.saturating_sub(ps.last_poll);
            ps.interval_sum += d;
            ps.interval_max = ps.interval_max.max(d);
        }
        ps.polls += 1;
        ps.last_poll = micros;
        ps
    }

    /// Frames the ID sent: each counts as exactly one of these.
    fn answers(&self) -> u64 {
        self.null + self.data + self.other + self.crc_errors
    }

    /// Intervals between its polls.
    fn intervals(&self) -> u64 {
        self.polls.saturating_sub(1)
    }
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

/// The `Sensor #` texts (`0x0210`) by app ID, each built once: a direct-mapped cache of 256
/// entries (a capture carries a few dozen app IDs; an entry another ID took is built again).
struct IdTexts {
    slots: Vec<(u32, String)>,
}

impl Default for IdTexts {
    fn default() -> Self {
        IdTexts {
            slots: vec![(u32::MAX, String::new()); 256],
        }
    }
}

impl IdTexts {
    fn get(&mut self, app_id: u16) -> &str {
        let i = (app_id as u32).wrapping_mul(0x9E37_79B1) >> 24;
        let (key, text) = &mut self.slots[i as usize];
        if *key != app_id as u32 {
            *key = app_id as u32;
            text.clear();
            values::push_sensor_no(text, app_id);
        }
        text
    }
}

/// Scratch buffers reused for every row.
#[derive(Default)]
struct Scratch {
    /// The `Sensor #` column's app ID (the text is in [`IdTexts`]).
    sensor_no: Option<u16>,
    sensor: String,
    data: String,
    note: String,
    nums: values::SportNumbers,
}

impl Scratch {
    fn clear(&mut self) {
        self.sensor_no = None;
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
    ids: IdTexts,
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
            Event::Slot(s) if direct::slot(self, s, out) => Ok(()),
            Event::Slot(s) => self.slot_row(s, out),
            Event::Garbage(g) => self.garbage_row(g, out),
        };
    }

    /// A slot's row as a [`crate::row::Row`] (the rows [`direct::slot`] leaves): out of line,
    /// so that the common rows' path does not pay for its registers and stack.
    #[inline(never)]
    fn slot_row(&mut self, s: &Slot, out: &mut dyn RowOut) -> RowResult {
        let micros = s.time.unwrap_or(s.index * SLOT_MICROS);
        let phys = s.phys();
        let sc = &mut self.scratch;
        sc.clear();
        let st = &mut self.stats;
        let ps = PhysStats::poll(&mut st.per, phys, micros);

        let mut class = Class::Plain;
        let mut cols = values::Decoded::built("");
        // The row's stamp (`Row::stamp`): its cells ID to Sensor follow from the physical ID,
        // the frame's type, whether its check passed and its app ID (a hub sensor's name from
        // the app ID's low byte; the GPS date/time frame's from its value too), or for the rows
        // without a frame type from the body alone.
        let mut stamp = 1 << 31 | u32::from(phys);
        let kind: &str = match s.body {
            Body::None => "",
            Body::Truncated { bytes, len } => {
                ps.truncated += 1;
                st.truncated += 1;
                class = Class::Error;
                stamp |= 1 << 5;
                push_hex(&mut sc.data, &bytes[..len as usize]);
                push_uint(&mut sc.note, len as u64);
                sc.note.push_str(" of ");
                push_uint(&mut sc.note, BODY_LEN as u64);
                sc.note.push_str(" bytes before the frame was cut");
                crate::row::kind::TRUNCATED
            }
            Body::Complete(b) => {
                if st.last_body == Some(b) {
                    st.repeats += 1;
                }
                st.last_body = Some(b);
                // The app ID and the value from the body as one word (the compiler put them
                // together from single bytes otherwise: 25 instructions a frame).
                let word = u64::from_le_bytes(b);
                let app_id = (word >> 8) as u16;
                let value = (word >> 24) as u32;
                let ok = wire::crc_ok(&b);
                // Firmware-update frames (`7E FF 50 …` from the radio, `7E 5E 50 …` from the
                // device) carry their own checksum instead of the S.Port sum (EdgeTX
                // `radio/src/io/frsky_firmware_update.cpp`).
                let firmware = b[0] == 0x50 && matches!(s.header, 0xFF | 0x5E);
                stamp = if firmware {
                    1 << 31 | 2 << 5 | u32::from(phys)
                } else {
                    1 << 30
                        | u32::from(phys)
                        | u32::from(b[0]) << 5
                        | u32::from(ok) << 13
                        | u32::from(app_id) << 14
                        | u32::from(values::sensor_from_value(app_id, value)) << 31
                };
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
                    cols = describe(b[0], s.header, app_id, value, sc);
                    if !ok {
                        // A number that failed its check is not one to chart: Data shows it,
                        // Value stays empty.
                        if cols.data_is_value {
                            sc.data.push_str(sc.nums.first_text());
                            cols.data_is_value = false;
                        }
                        sc.nums.clear();
                        let expected = wire::crc(&b[..7]);
                        let type_name = names::frame_type(b[0]).unwrap_or("unknown");
                        let note = crate::row::note_part(&mut sc.note);
                        note.push_str("CRC ");
                        push_0x(note, b[7]);
                        note.push_str(", expected ");
                        push_0x(note, expected);
                        note.push_str(" (");
                        note.push_str(type_name);
                        note.push_str(" frame)");
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
                                let note = crate::row::note_part(&mut sc.note);
                                note.push_str("unknown frame type ");
                                push_0x(note, b[0]);
                                "Unknown"
                            }
                        }
                    }
                }
            }
        };
        // The CRC does not cover the header byte: with its check bits wrong, the physical ID
        // is not to be trusted, so the frame carries no number (wide, plot, JSON parts); its
        // row still shows the decoded text and the note (M6, issue 32).
        let trusted = wire::header_ok(s.header);
        if !trusted {
            st.check_bits += 1;
            let note = crate::row::note_part(&mut sc.note);
            note.push_str("non-standard check bits (header ");
            push_0x(note, s.header);
            note.push(')');
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
        let extra = [cols.unit, sc.note.as_str()];
        let sensor_no = match sc.sensor_no {
            Some(app_id) => self.ids.get(app_id),
            None => "",
        };
        let sensor = cols.sensor.unwrap_or(&sc.sensor);
        let data = if cols.data_is_value {
            sc.nums.first_text()
        } else {
            &sc.data
        };
        sc.nums.with_parts(|parts| {
            out.row(&Row {
                stamp,
                micros: Some(micros),
                id: Some(phys as u32),
                device: names::device(phys),
                kind,
                class,
                sensor_no,
                sensor,
                data,
                extra: &extra,
                parts: if trusted {
                    parts.into()
                } else {
                    crate::row::Parts::NONE
                },
                raw: s.wire(),
            })
        })
    }

    #[inline(never)]
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
            sc.note.push_str(if g.bytes().len() == 1 {
                " byte"
            } else {
                " bytes"
            });
            sc.note.push_str(if g.after_slot.is_some() {
                " after a complete frame"
            } else {
                " before the first 0x7E"
            });
        }
        let extra = ["", sc.note.as_str()];
        out.row(&Row {
            stamp: 0,
            micros: Some(micros),
            id: None,
            device: "",
            kind: crate::row::kind::GARBAGE,
            class: Class::Error,
            sensor_no: "",
            sensor: "",
            data: &sc.data,
            extra: &extra,
            parts: crate::row::Parts::NONE,
            raw: g.bytes(),
        })
    }
}

/// Fills Sensor #, Sensor, Data and Note for a complete frame of type `kind`; returns the unit
/// and what of Sensor and Data is not in the buffers ([`values::Decoded`]). Inlined into the
/// row's code for the two frames of almost every row: data frames go straight to
/// [`values::decode_row`], and a keep-alive of zeros (a third of a typical capture) has
/// nothing to show; every other frame is [`describe_other`]'s.
#[inline]
fn describe(kind: u8, header: u8, app_id: u16, value: u32, sc: &mut Scratch) -> values::Decoded {
    match kind {
        0x10 => {
            sc.sensor_no = Some(app_id);
            values::decode_row(
                header & 0x1F,
                app_id,
                value,
                &mut sc.sensor,
                &mut sc.data,
                &mut sc.nums,
            )
        }
        0x00 if app_id == 0 && value == 0 => values::Decoded::built(""),
        _ => describe_other(kind, header, app_id, value, sc),
    }
}

/// [`describe`] for the frames other than data frames and keep-alives of zeros.
#[inline(never)]
fn describe_other(
    kind: u8,
    header: u8,
    app_id: u16,
    value: u32,
    sc: &mut Scratch,
) -> values::Decoded {
    match kind {
        0x00 => {
            // Keep-alive: the sample leaves Sensor #/Sensor/Data empty; Pawelsky-style sensors
            // name the app ID due next, which is worth showing.
            if app_id != 0 {
                sc.sensor_no = Some(app_id);
                values::label(app_id, &mut sc.sensor);
            }
            if value != 0 {
                push_value_hex(&mut sc.data, value);
                sc.note("keep-alive with a non-zero value");
            }
            values::Decoded::built("")
        }
        0x20 | 0x21 => {
            sc.sensor_no = Some(app_id);
            values::label(app_id, &mut sc.sensor);
            push_value_hex(&mut sc.data, value);
            sc.note(names::frame_type_long(kind));
            values::Decoded::built("")
        }
        0x30..=0x32 => {
            sc.sensor_no = Some(app_id);
            values::label(app_id, &mut sc.sensor);
            let mut payload = [0u8; 6];
            payload[..2].copy_from_slice(&app_id.to_le_bytes());
            payload[2..].copy_from_slice(&value.to_le_bytes());
            push_hex(&mut sc.data, &payload);
            config_note(kind, header, value, sc);
            values::Decoded::built("")
        }
        _ => {
            let mut payload = [0u8; 6];
            payload[..2].copy_from_slice(&app_id.to_le_bytes());
            payload[2..].copy_from_slice(&value.to_le_bytes());
            push_hex(&mut sc.data, &payload);
            values::Decoded::built("")
        }
    }
}

/// The cells this table shows for a frame body `[type][app ID LE16][value LE32]` from physical
/// ID `phys` whose check passed, for protocols that carry S.Port payloads (F.Port, FBUS): the
/// Sensor #, Sensor, Data and Note cells and the numbers are written into the (cleared)
/// buffers; returns the unit.
pub(crate) fn payload_cells(
    phys: u8,
    body: [u8; 7],
    sensor_no: &mut String,
    sensor: &mut String,
    data: &mut String,
    note: &mut String,
    nums: &mut values::SportNumbers,
) -> &'static str {
    let mut sc = Scratch {
        sensor_no: None,
        sensor: std::mem::take(sensor),
        data: std::mem::take(data),
        note: std::mem::take(note),
        nums: std::mem::take(nums),
    };
    let app_id = u16::from_le_bytes([body[1], body[2]]);
    let value = u32::from_le_bytes([body[3], body[4], body[5], body[6]]);
    let d = describe(body[0], phys & 0x1F, app_id, value, &mut sc);
    sc.sensor.push_str(d.sensor.unwrap_or(""));
    if d.data_is_value {
        sc.data.push_str(sc.nums.first_text());
    }
    if let Some(id) = sc.sensor_no {
        values::push_sensor_no(sensor_no, id);
    }
    (*sensor, *data, *note, *nums) = (sc.sensor, sc.data, sc.note, sc.nums);
    d.unit
}

/// `value=0x` and the value as eight upper-case hex digits.
fn push_value_hex(out: &mut String, value: u32) {
    out.push_str("value=0x");
    for b in value.to_be_bytes() {
        push_hex_u8(out, b);
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
    let note = crate::row::note_part(&mut sc.note);
    match (kind, field) {
        (0x30, 0x01) => note.push_str("config: read physical ID"),
        (0x31, 0x01) => {
            note.push_str("config: set physical ID to ");
            push_u64(note, arg as u64);
        }
        (0x32, 0x01) => {
            note.push_str("config: physical ID is ");
            push_u64(note, arg as u64);
        }
        _ => {
            note.push_str(names::frame_type_long(kind));
            note.push_str(" field ");
            push_0x(note, field);
        }
    }
}

impl Decoder for SportDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let (re, table) = (&mut self.re, &mut self.table);
        Latch::with(out, |out| re.push(data, time, &mut |e| table.event(e, out)))
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let (re, table) = (&mut self.re, &mut self.table);
        Latch::with(out, |out| re.finish(&mut |e| table.event(e, out)))
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
            Column::right("Trunc", 6).key("truncated"),
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
                p.answers(),
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
            total.null += p.null;
            total.data += p.data;
            total.other += p.other;
            total.crc_errors += p.crc_errors;
            total.truncated += p.truncated;
            let (mean, max) = if p.intervals() > 0 {
                (
                    format!(
                        "{:.1}",
                        p.interval_sum as f64 / p.intervals() as f64 / 1000.0
                    ),
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
        r.total_row(cells);
        r.totals.push(format!(
            "valid frames {}, garbage {}, non-standard check bits {}, unusual escapes {}, repeated frames {}",
            st.valid_frames,
            crate::stats::garbage(st.garbage_bytes, st.garbage_runs),
            st.check_bits,
            st.unusual_escapes,
            st.repeats
        ));
        r.counts(&[
            ("valid_frames", st.valid_frames),
            ("garbage_bytes", st.garbage_bytes),
            ("garbage_runs", st.garbage_runs),
            ("non_standard_check_bits", st.check_bits),
            ("unusual_escapes", st.unusual_escapes),
            ("repeated_frames", st.repeats),
        ]);
        r
    }

    fn problems(&self) -> Problems {
        let st = &self.table.stats;
        let mut p = Problems::new("S.Port");
        p.count("crc_errors", st.crc_errors, "CRC error", "CRC errors")
            .count(
                "truncated_frames",
                st.truncated,
                "truncated frame",
                "truncated frames",
            )
            .garbage(st.garbage_bytes, st.garbage_runs)
            .count(
                "unusual_escapes",
                st.unusual_escapes,
                "unusual escape",
                "unusual escapes",
            )
            .in_valid(st.valid_frames, "valid frame", "valid frames");
        p
    }

    fn no_frames_hint(&self) -> &'static str {
        "wrong baud rate (S.Port runs at 57600, the TX16S/F16 mirror at 115200) or the signal is \
         not inverted (S.Port needs an inverting adapter or an FTDI with inverted RX, see docs/live.md)"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The problems line counts in words: "1 valid frame", not "1 valid frames".
    #[test]
    fn the_problems_line_says_one_valid_frame() {
        let mut d = SportDecoder::new();
        let mut bytes = Vec::new();
        wire::encode_frame(&mut bytes, wire::header_for(8), 0x10, 0x0300, 1);
        let mut body = [0x10, 0x00, 0x03, 1, 2, 3, 4, 0];
        body[7] = wire::crc(&body[..7]) ^ 1;
        wire::encode_raw(&mut bytes, wire::header_for(8), &body);
        crate::testing::assert_stamps_hold(&mut d, &[&bytes]);
        assert_eq!(
            d.problems().line().unwrap(),
            "S.Port: 1 CRC error in 1 valid frame"
        );
    }

    /// Every app ID range of the value tables, frame types with and without a name, bad CRCs,
    /// firmware frames, odd headers, truncated frames and noise, each app ID with several
    /// values: a row's stamp never changes the table (the GPS date/time frame, whose Sensor its
    /// value decides, included).
    #[test]
    fn stamps_never_change_the_table() {
        let noise = crate::testing::noise(4_000, 7);
        let mut n = noise.iter().copied().cycle();
        let mut next = || n.next().unwrap_or(0);
        let mut bytes = Vec::new();
        let app_bases: Vec<u16> = (0..=0xFFu16)
            .map(|hi| hi << 8)
            .chain([
                0x0850, 0x0851, 0x0300, 0x0800, 0x5000, 0x5003, 0x5008, 0x0B20,
            ])
            .collect();
        for (i, &base) in app_bases.iter().enumerate() {
            // One sensor per app ID range; its data frames first with a zero lowest value byte,
            // then with a non-zero one (the GPS date/time frame names Time, then Date).
            let phys = (i % 28) as u8;
            let app_id = base | u16::from(next() & 0x1F);
            for k in 0..6u8 {
                let value = u32::from_le_bytes([
                    if k == 0 { 0 } else { next() | 1 },
                    next(),
                    next(),
                    next(),
                ]);
                let kind = [0x10, 0x10, 0x10, 0x00, 0x32, 0x77][usize::from(k)];
                wire::encode_frame(&mut bytes, wire::header_for(phys), kind, app_id, value);
                if k == 2 {
                    // The same frame with a bad CRC, and a firmware frame.
                    let mut body = [kind, app_id as u8, (app_id >> 8) as u8, 1, 2, 3, 4, 0];
                    body[7] = wire::crc(&body[..7]) ^ 1;
                    wire::encode_raw(&mut bytes, wire::header_for(phys), &body);
                    body[0] = 0x50;
                    wire::encode_raw(&mut bytes, 0xFF, &body);
                }
            }
            wire::encode_poll(&mut bytes, wire::header_for((i % 28) as u8));
            wire::encode_poll(&mut bytes, 0x1A);
            if i % 16 == 0 {
                bytes.extend_from_slice(&noise[i..i + 12]);
            }
        }
        // A frame cut short at the end.
        bytes.extend_from_slice(&[wire::START, wire::header_for(3), 0x10, 0x00]);
        let chunks: Vec<&[u8]> = bytes.chunks(97).collect();
        let stamped = crate::testing::assert_stamps_hold(&mut SportDecoder::new(), &chunks);
        assert!(stamped > 2_000, "{stamped} rows with a stamp");
    }
}
