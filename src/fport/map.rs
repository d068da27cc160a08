//! Frames onto the log table (`docs/fport.md`, "The table"): control frames with their
//! channels in µs, telemetry frames through the S.Port table, OTA frames, broken frames and
//! garbage.

use super::Framing;
use super::frame::{Check, Event, Frame, Garbage, Role};
use super::stats::Stats;
use super::table::{RECEIVER, V1_PHYS, V1_REQUEST_PHYS};
use super::wire::{
    self, FLAG_CH17, FLAG_CH18, FLAG_FAILSAFE, FLAG_FRAME_LOST, OTA_DATA, OTA_START, OTA_STOP,
    PAYLOAD_LEN, V1_CONTROL_LEN, V1_TELEMETRY_LEN, V2_CONTROL_8, V2_CONTROL_16, V2_CONTROL_24,
    V2_TELEMETRY_LEN,
};
use crate::fmt::{push_0x, push_hex, push_u64};
use crate::numbers::{Numbers, push_uint};
use crate::row::{Class, Latch, Parts, Row, RowOut, RowResult, kind};
use crate::sport::{names, values::SportNumbers};

/// Channels shown in the Data cell of a control row (in whole µs); the rest follow as `…`.
const DATA_CHANNELS: usize = 8;

/// `CH1` … `CH24`.
const CH: [&str; 24] = [
    "CH1", "CH2", "CH3", "CH4", "CH5", "CH6", "CH7", "CH8", "CH9", "CH10", "CH11", "CH12", "CH13",
    "CH14", "CH15", "CH16", "CH17", "CH18", "CH19", "CH20", "CH21", "CH22", "CH23", "CH24",
];

/// Scratch buffers reused for every row.
#[derive(Default)]
struct Scratch {
    sensor_no: String,
    sensor: String,
    data: String,
    note: String,
    /// An S.Port payload's numbers.
    sport: SportNumbers,
    /// A control frame's numbers: 24 channels, two flag channels, frame lost, failsafe, RSSI.
    control: Numbers<32>,
}

impl Scratch {
    fn clear(&mut self) {
        self.sensor_no.clear();
        self.sensor.clear();
        self.data.clear();
        self.note.clear();
        self.sport.clear();
        self.control.clear();
    }

    fn note(&mut self) -> &mut String {
        crate::row::note_part(&mut self.note)
    }
}

/// The cells of a row besides the scratch buffers.
struct Cells {
    id: Option<u32>,
    device: &'static str,
    kind: &'static str,
    class: Class,
    unit: &'static str,
    frame: &'static str,
    /// Which numbers are the row's parts.
    parts: Which,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Which {
    None,
    Sport,
    Control,
}

/// Maps frames onto rows and keeps the statistics.
pub struct Mapper {
    sc: Scratch,
    pub stats: Stats,
    /// Line speed and bits per byte, for the time of sources without time.
    baud: u32,
    /// The control rows' texts of the channels after the sticks, from the row before.
    held: super::direct::Held,
}

impl Mapper {
    pub fn new(baud: u32) -> Self {
        Mapper {
            sc: Scratch::default(),
            stats: Stats::default(),
            baud: baud.max(1),
            held: Default::default(),
        }
    }

    /// Writes the row of one event (a write error stays in the latch).
    pub fn event(&mut self, framing: Framing, ev: Event<'_>, out: &mut Latch<'_>) {
        if out.stopped() {
            return;
        }
        let _ = match ev {
            Event::Frame(f) => {
                if super::direct::frame(
                    &mut self.stats,
                    &mut self.held,
                    self.baud,
                    framing,
                    &f,
                    out,
                ) {
                    return;
                }
                self.frame(framing, &f, out)
            }
            Event::Garbage(g) => self.garbage(&g, out),
        };
    }

    /// Time of a row: the source's, or 10 bits per byte at the line's speed.
    pub(super) fn micros(&self, time: Option<u64>, offset: u64) -> u64 {
        super::table::micros(time, offset, self.baud)
    }

    fn frame(&mut self, framing: Framing, f: &Frame<'_>, out: &mut dyn RowOut) -> RowResult {
        self.sc.clear();
        let cells = match f.check {
            Check::Ok => self.valid(framing, f),
            Check::Bad | Check::Cut => self.broken(framing, f),
        };
        let micros = self.micros(f.time, f.offset);
        let sc = &self.sc;
        let extra = [cells.unit, cells.frame, sc.note.as_str()];
        let row = |parts: &[crate::row::Part<'_>], out: &mut dyn RowOut| {
            out.row(&Row {
                stamp: 0,
                micros: Some(micros),
                id: cells.id,
                device: cells.device,
                kind: cells.kind,
                class: cells.class,
                sensor_no: &sc.sensor_no,
                sensor: &sc.sensor,
                data: &sc.data,
                extra: &extra,
                parts: Parts::List(parts),
                raw: f.raw,
            })
        };
        match cells.parts {
            Which::None => row(&[], out),
            Which::Sport => sc.sport.with_parts(|p| row(p, out)),
            Which::Control => sc.control.with_parts(|p| row(p, out)),
        }
    }

    fn valid(&mut self, framing: Framing, f: &Frame<'_>) -> Cells {
        self.stats.valid();
        let len = f.body[0];
        let kind = f.kind().unwrap_or(0);
        let cells = match (framing, f.role) {
            (Framing::V1, Role::Control) if len == V1_CONTROL_LEN => self.control(16, f),
            (Framing::V2, Role::Control) => match (len, kind) {
                (V2_CONTROL_8, 0xFF) => self.control(8, f),
                (V2_CONTROL_16, 0xFF) => self.control(16, f),
                (V2_CONTROL_24, 0xFF) => self.control(24, f),
                _ => self.ota_control(f),
            },
            (Framing::V1, Role::Downlink | Role::Uplink) if len == V1_TELEMETRY_LEN => {
                self.telemetry(framing, f)
            }
            (Framing::V2, Role::Downlink | Role::Uplink) => self.telemetry(framing, f),
            _ => self.unknown(f),
        };
        if f.unusual_escape {
            self.stats.unusual_escapes += 1;
            self.sc
                .note()
                .push_str("unusual escape (0x7D not followed by 0x5E/0x5D)");
        }
        if f.pad {
            self.sc
                .note()
                .push_str("after a 0xFF pad byte (ArduPilot's FPort pad option)");
        }
        cells
    }

    /// A control frame with `n` channels.
    fn control(&mut self, n: usize, f: &Frame<'_>) -> Cells {
        let st = &mut self.stats;
        st.control[n / 8 - 1] += 1;
        let sc = &mut self.sc;
        let data = f.data();
        let bytes = wire::channel_bytes(n);
        let mut ch = [0u16; 24];
        wire::unpack_channels(&data[..bytes.min(data.len())], &mut ch[..n]);
        let flags = data.get(bytes).copied().unwrap_or(0);
        let rssi = data.get(bytes + 1).copied().unwrap_or(0);
        for (i, &raw) in ch[..n].iter().enumerate() {
            let milli = wire::micros_milli(raw);
            let (v, prec) = trimmed(milli, 3);
            sc.control.fixed(CH[i], "µs", v, prec);
            // Data: the first channels in whole µs as Betaflight shows them (the pretty table
            // keeps a cell of up to 60 characters aligned); every channel exactly in the parts.
            if i < DATA_CHANNELS {
                if i > 0 {
                    sc.data.push(' ');
                }
                push_uint(&mut sc.data, (milli / 1000) as u64);
            } else if i == DATA_CHANNELS {
                sc.data.push_str(" …");
            }
        }
        let bit = |mask: u8| i64::from(flags & mask != 0);
        if n <= 16 {
            sc.control.int("CH17", "", bit(FLAG_CH17));
            sc.control.int("CH18", "", bit(FLAG_CH18));
        }
        sc.control.int("FrameLost", "", bit(FLAG_FRAME_LOST));
        sc.control.int("Failsafe", "", bit(FLAG_FAILSAFE));
        sc.control.int("RSSI", "", i64::from(rssi));
        st.rssi(rssi);
        let mut class = Class::Plain;
        if flags & FLAG_FRAME_LOST != 0 {
            st.frame_lost += 1;
            class = Class::Warning;
        }
        if flags & FLAG_FAILSAFE != 0 {
            st.failsafe += 1;
            class = Class::Warning;
        }
        sc.sensor.push_str("Channels");
        if flags != 0 {
            let note = sc.note();
            note.push_str("flags ");
            push_0x(note, flags);
            let names = [
                (FLAG_CH17, if n <= 16 { "CH17" } else { "bit 0" }),
                (FLAG_CH18, if n <= 16 { "CH18" } else { "bit 1" }),
                (FLAG_FRAME_LOST, "frame lost"),
                (FLAG_FAILSAFE, "failsafe"),
                (0xF0, "unknown bits"),
            ];
            let mut sep = ":";
            for (mask, name) in names {
                if flags & mask != 0 {
                    note.push_str(sep);
                    note.push(' ');
                    note.push_str(name);
                    sep = ",";
                }
            }
        }
        let note = sc.note();
        note.push_str("raw");
        for &raw in &ch[..n] {
            note.push(' ');
            push_uint(note, u64::from(raw));
        }
        Cells {
            id: None,
            device: RECEIVER,
            kind: "Control",
            class,
            unit: "µs",
            frame: "Control",
            parts: Which::Control,
        }
    }

    /// An F.Port 2 OTA control frame.
    fn ota_control(&mut self, f: &Frame<'_>) -> Cells {
        self.stats.ota += 1;
        let sc = &mut self.sc;
        let kind = f.kind().unwrap_or(0);
        let data = f.data();
        sc.sensor.push_str("OTA");
        push_hex(&mut sc.data, data);
        let note = sc.note();
        note.push_str("firmware update over the air, ");
        push_u64(note, data.len() as u64);
        note.push_str(" data bytes");
        if kind == OTA_START && data.len() >= 2 {
            // INAV: the first two bytes are the shortest answer delay and the longest answer
            // time, in 100 µs (0 or out of range: its defaults).
            note.push_str(", answer delay ");
            push_u64(note, u64::from(data[0]) * 100);
            note.push_str(" µs, answer time ");
            push_u64(note, u64::from(data[1]) * 100);
            note.push_str(" µs");
        }
        if f.ota_resized {
            sc.note()
                .push_str("read with the data size of its type, not of its length byte (INAV)");
        }
        Cells {
            id: None,
            device: RECEIVER,
            kind: ota_kind(kind),
            class: Class::Plain,
            unit: "",
            frame: "Control",
            parts: Which::None,
        }
    }

    /// The physical ID byte of a telemetry frame (F.Port 2: the S.Port header byte with its
    /// check bits), or what F.Port v1 implies.
    fn phys_byte(framing: Framing, f: &Frame<'_>) -> u8 {
        match framing {
            Framing::V2 => f.kind().unwrap_or(0),
            Framing::V1 => match (f.role, f.data().first()) {
                (Role::Downlink, Some(0x30 | 0x31)) => V1_REQUEST_PHYS,
                _ => V1_PHYS,
            },
        }
    }

    fn telemetry(&mut self, framing: Framing, f: &Frame<'_>) -> Cells {
        let phys_byte = Self::phys_byte(framing, f);
        let phys = phys_byte & 0x1F;
        let mut payload = [0u8; PAYLOAD_LEN];
        let data = f.data();
        payload.copy_from_slice(&data[..PAYLOAD_LEN.min(data.len())]);
        let prim = payload[0];
        let downlink = f.role == Role::Downlink;
        let frame = if downlink { "Downlink" } else { "Uplink" };
        let st = &mut self.stats;
        let ps = &mut st.per[phys as usize];
        let sc = &mut self.sc;
        let mut class = Class::Plain;
        let mut parts = Which::Sport;
        let mut unit = "";
        let kind = if framing == Framing::V2 && (OTA_START..=OTA_STOP).contains(&prim) {
            st.ota += 1;
            parts = Which::None;
            sc.sensor.push_str("OTA");
            push_hex(&mut sc.data, &payload[1..]);
            let note = sc.note();
            note.push_str("firmware update over the air");
            if prim == OTA_DATA {
                // INAV reads the value as the address of the control frame's 32 bytes.
                let addr = u32::from_le_bytes([payload[3], payload[4], payload[5], payload[6]]);
                note.push_str(", data address ");
                push_u64(note, u64::from(addr));
            }
            if downlink {
                ps.requests += 1;
            } else {
                ps.answers += 1;
                ps.other += 1;
            }
            ota_kind(prim)
        } else {
            unit = crate::sport::payload_cells(
                phys,
                payload,
                &mut sc.sensor_no,
                &mut sc.sensor,
                &mut sc.data,
                &mut sc.note,
                &mut sc.sport,
            );
            let name = names::frame_type(prim);
            if downlink {
                if prim == 0x00 {
                    ps.polls += 1;
                } else {
                    ps.requests += 1;
                }
            } else {
                ps.answers += 1;
                match prim {
                    0x00 => ps.null += 1,
                    0x10 => ps.data += 1,
                    _ => ps.other += 1,
                }
            }
            match (downlink, prim, name) {
                // A poll: an ID and no Type, as S.Port shows one (`--hide-polls`).
                (true, 0x00, _) => "",
                (false, 0x00, Some(n)) => {
                    class = Class::Quiet;
                    n
                }
                (_, _, Some(n)) => n,
                (_, _, None) => {
                    class = Class::Warning;
                    let note = sc.note();
                    note.push_str("unknown frame type ");
                    push_0x(note, prim);
                    "Unknown"
                }
            }
        };
        if framing == Framing::V2 && !crate::sport::wire::header_ok(phys_byte) {
            // As `busnoop sport` for the same S.Port payload: a header byte with wrong check
            // bits leaves the frame without numbers (wide, plot, JSON parts), its text stays.
            parts = Which::None;
            st.check_bits += 1;
            let note = sc.note();
            note.push_str("non-standard check bits (physical ID byte ");
            push_0x(note, phys_byte);
            note.push(')');
            if matches!(class, Class::Plain | Class::Quiet) {
                class = Class::Warning;
            }
        }
        if f.guessed {
            st.guessed += 1;
            sc.note()
                .push_str("direction guessed: no control frame before it");
        }
        Cells {
            id: Some(u32::from(phys)),
            device: names::device(phys),
            kind,
            class,
            unit,
            frame,
            parts,
        }
    }

    /// A frame whose checksum passed but whose type or length is not known.
    fn unknown(&mut self, f: &Frame<'_>) -> Cells {
        self.stats.unknown += 1;
        let sc = &mut self.sc;
        push_hex(&mut sc.data, f.data());
        let note = sc.note();
        note.push_str("unknown frame: type ");
        push_0x(note, f.kind().unwrap_or(0));
        note.push_str(", length ");
        push_0x(note, f.body[0]);
        Cells {
            id: None,
            device: "",
            kind: "Unknown",
            class: Class::Warning,
            unit: "",
            frame: "",
            parts: Which::None,
        }
    }

    /// A frame failing its checksum, or cut short.
    fn broken(&mut self, framing: Framing, f: &Frame<'_>) -> Cells {
        let st = &mut self.stats;
        st.broken = true;
        let body = f.body;
        let kind = if f.check == Check::Bad {
            st.crc_errors += 1;
            kind::BAD_CRC
        } else {
            st.truncated += 1;
            kind::TRUNCATED
        };
        let (frame, name) = match f.role {
            Role::Control => ("Control", "control frame"),
            Role::Downlink => ("Downlink", "downlink frame"),
            Role::Uplink => ("Uplink", "uplink frame"),
            Role::Unknown => ("", "frame"),
        };
        let telemetry = matches!(f.role, Role::Downlink | Role::Uplink);
        let id = match framing {
            Framing::V2 if telemetry => f.kind().map(|b| u32::from(b & 0x1F)),
            Framing::V1 if telemetry => Some(u32::from(Self::phys_byte(framing, f))),
            _ => None,
        };
        let sc = &mut self.sc;
        push_hex(&mut sc.data, body);
        let note = sc.note();
        if f.check == Check::Bad {
            // v1 sums from the length byte, F.Port 2 from the type byte.
            let from = match framing {
                Framing::V1 => 0,
                Framing::V2 => 1,
            };
            let n = body.len();
            note.push_str("checksum ");
            push_0x(note, body[n - 1]);
            note.push_str(", expected ");
            push_0x(note, wire::checksum(&body[from.min(n - 1)..n - 1]));
            note.push_str(" (");
            note.push_str(name);
            note.push(')');
        } else {
            let expected = match framing {
                Framing::V1 => body.first().map(|&l| l as usize + 2),
                Framing::V2 => body.first().map(|&l| match (l, body.get(1)) {
                    (V2_TELEMETRY_LEN, _) => 10,
                    (l, _) => l as usize + 3,
                }),
            };
            push_u64(note, body.len() as u64);
            if let Some(e) = expected {
                note.push_str(" of ");
                push_u64(note, e as u64);
            }
            note.push_str(" bytes before the ");
            note.push_str(name);
            note.push_str(" was cut");
        }
        if f.unusual_escape {
            st.unusual_escapes += 1;
            sc.note()
                .push_str("unusual escape (0x7D not followed by 0x5E/0x5D)");
        }
        Cells {
            id,
            device: id.map_or("", |i| names::device(i as u8)),
            kind,
            class: Class::Error,
            unit: "",
            frame,
            parts: Which::None,
        }
    }

    fn garbage(&mut self, g: &Garbage<'_>, out: &mut dyn RowOut) -> RowResult {
        let st = &mut self.stats;
        st.garbage_bytes += g.bytes.len() as u64;
        st.garbage_runs += 1;
        st.broken = true;
        let micros = self.micros(g.time, g.offset);
        let sc = &mut self.sc;
        sc.clear();
        push_hex(&mut sc.data, g.bytes);
        push_u64(&mut sc.note, g.bytes.len() as u64);
        sc.note.push_str(" bytes outside any frame");
        let extra = ["", "", sc.note.as_str()];
        out.row(&Row {
            stamp: 0,
            micros: Some(micros),
            id: None,
            device: "",
            kind: kind::GARBAGE,
            class: Class::Error,
            sensor_no: "",
            sensor: "",
            data: &sc.data,
            extra: &extra,
            parts: Parts::NONE,
            raw: g.bytes,
        })
    }
}

/// The Type of an OTA frame.
fn ota_kind(kind: u8) -> &'static str {
    match kind {
        OTA_START => "OtaStart",
        OTA_DATA => "OtaData",
        _ => "OtaStop",
    }
}

/// `v / 10^prec` with the trailing zeros of the fraction dropped (`1500625, 3` stays,
/// `1500000, 3` becomes `1500, 0`).
fn trimmed(mut v: i64, mut prec: u8) -> (i64, u8) {
    while prec > 0 && v % 10 == 0 {
        v /= 10;
        prec -= 1;
    }
    (v, prec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trims_the_fraction() {
        assert_eq!(trimmed(1_500_000, 3), (1500, 0));
        assert_eq!(trimmed(1_500_625, 3), (1_500_625, 3));
        assert_eq!(trimmed(1_500_500, 3), (15_005, 1));
        assert_eq!(trimmed(987_500, 3), (9875, 1));
    }
}
