//! The common F.Port rows written straight into the table ([`crate::row::direct`]): control
//! frames of 16 channels (F.Port v1, and F.Port 2 / FBUS), and on an F.Port v1 line the
//! receiver's null polls and the flight controller's data answers of the common S.Port
//! sensors (plain scalars and GPS coordinates, as `busnoop sport` writes them straight), each
//! with a good checksum, without an unusual escape or a pad byte. Every other row (and every
//! row when the table lends no [`crate::row::Direct`]) goes through the mapper as a
//! [`crate::row::Row`]; both give the same bytes (`testing::assert_direct_rows_match`).

use super::Framing;
use super::frame::{Check, Frame, Role};
use super::stats::Stats;
use super::table::{self, COLUMNS, RECEIVER, V1_PHYS};
use super::wire::{
    self, FLAG_CH17, FLAG_CH18, FLAG_FAILSAFE, FLAG_FRAME_LOST, V1_CONTROL_LEN, V1_TELEMETRY_LEN,
    V2_CHANNELS, V2_CONTROL_16, V2_TELEMETRY_LEN,
};
use crate::row::{Cells, Class, Fmt, Latch, Mark, PartNames, RowOut, WriteRow};
use crate::sport::names;
use crate::sport::values::{self, Common};
use crate::sport::wire::header_ok;

/// What the row shows.
#[derive(Clone, Copy)]
enum What {
    /// A control frame: its 16 channels, flags and RSSI.
    Control([u16; 16], u8, u8),
    /// The receiver's null poll of a physical ID.
    Poll(u8),
    /// A device's answer (physical ID) of a common sensor.
    Data(u8, u16, u32, Common),
}

struct FportRow<'h> {
    what: What,
    held: &'h Held,
}

/// The texts of the channels a control frame carries after the sticks (CH5 on: switches and
/// knobs, which seldom change), kept from the control row before and made again when one
/// changes: CH5-CH8 in whole µs after a blank (the Data cell's end but for its ` …`),
/// CH5-CH16 raw after a blank (the Note's end).
#[derive(Default)]
pub(super) struct Held {
    aux: Option<[u16; 12]>,
    whole: String,
    raw: String,
}

impl Held {
    #[inline]
    fn update(&mut self, ch: &[u16; 16]) {
        let mut aux = [0u16; 12];
        aux.copy_from_slice(&ch[4..]);
        if self.aux != Some(aux) {
            self.make(aux);
        }
    }

    #[cold]
    #[inline(never)]
    fn make(&mut self, aux: [u16; 12]) {
        let t = texts();
        self.aux = Some(aux);
        self.whole.clear();
        for &r in &aux[..4] {
            self.whole.push_str(t.whole[usize::from(r)]);
        }
        self.raw.clear();
        for &r in &aux {
            self.raw.push_str(t.raw[usize::from(r)]);
        }
    }
}

/// The channels' texts, made once: whole µs after a blank (the Data cell), exact µs (Value
/// and parts), raw after a blank (the Note).
struct Texts {
    whole: Vec<&'static str>,
    exact: Vec<&'static str>,
    raw: Vec<&'static str>,
}

fn texts() -> &'static Texts {
    static T: std::sync::OnceLock<Texts> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let leak = |f: &dyn Fn(u16, &mut String)| -> Vec<&'static str> {
            (0..2048u16)
                .map(|r| {
                    let mut s = String::new();
                    f(r, &mut s);
                    &*Box::leak(s.into_boxed_str())
                })
                .collect()
        };
        Texts {
            whole: leak(&|r, s| {
                s.push(' ');
                crate::fmt::push_u64(s, (wire::micros_milli(r) / 1000) as u64);
            }),
            exact: leak(&|r, s| {
                let (mut v, mut prec) = (wire::micros_milli(r), 3u8);
                while prec > 0 && v % 10 == 0 {
                    v /= 10;
                    prec -= 1;
                }
                crate::fmt::push_fixed(s, v, prec);
            }),
            raw: leak(&|r, s| {
                s.push(' ');
                crate::fmt::push_u64(s, u64::from(r));
            }),
        }
    })
}

const CH: [&str; 16] = [
    "CH1", "CH2", "CH3", "CH4", "CH5", "CH6", "CH7", "CH8", "CH9", "CH10", "CH11", "CH12", "CH13",
    "CH14", "CH15", "CH16",
];

impl WriteRow for FportRow<'_> {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        match self.what {
            What::Control(ch, flags, rssi) => {
                if c.stamp(1 << 31 | 1) {
                    c.id(None);
                    c.text(RECEIVER);
                    c.text("Control");
                    c.empty();
                    c.text("Channels");
                    c.stamp_end();
                }
                let t = texts();
                // Digits, blanks and the ellipsis: a plain cell, not looked at again.
                c.begin();
                c.put_ascii(&t.whole[usize::from(ch[0])].as_bytes()[1..]);
                for &r in &ch[1..4] {
                    c.put_ascii(t.whole[usize::from(r)].as_bytes());
                }
                c.put_ascii(self.held.whole.as_bytes());
                c.put_glyphs(" …");
                c.end();
                c.value_text(Some(t.exact[usize::from(ch[0])]));
                c.text("µs");
                c.text("Control");
                c.begin();
                if flags != 0 {
                    c.str("flags 0x");
                    c.hex2(flags);
                    let names = [
                        (FLAG_CH17, "CH17"),
                        (FLAG_CH18, "CH18"),
                        (FLAG_FRAME_LOST, "frame lost"),
                        (FLAG_FAILSAFE, "failsafe"),
                        (0xF0, "unknown bits"),
                    ];
                    let mut sep = ": ";
                    for (mask, name) in names {
                        if flags & mask != 0 {
                            c.str(sep);
                            c.str(name);
                            sep = ", ";
                        }
                    }
                    c.str("; ");
                }
                // Digits and blanks: without flags the cell is plain, not looked at again.
                c.put_ascii(b"raw");
                for &r in &ch[..4] {
                    c.put_ascii(t.raw[usize::from(r)].as_bytes());
                }
                c.put_ascii(self.held.raw.as_bytes());
                c.end();
                static PARTS: PartNames<21> = PartNames::new([
                    "CH1",
                    "CH2",
                    "CH3",
                    "CH4",
                    "CH5",
                    "CH6",
                    "CH7",
                    "CH8",
                    "CH9",
                    "CH10",
                    "CH11",
                    "CH12",
                    "CH13",
                    "CH14",
                    "CH15",
                    "CH16",
                    "CH17",
                    "CH18",
                    "FrameLost",
                    "Failsafe",
                    "RSSI",
                ]);
                debug_assert!(PARTS.names()[..16] == CH);
                let bit = |mask: u8| if flags & mask != 0 { "1" } else { "0" };
                let mut texts = [""; 21];
                for (text, &r) in texts.iter_mut().zip(&ch) {
                    *text = t.exact[usize::from(r)];
                }
                texts[16] = bit(FLAG_CH17);
                texts[17] = bit(FLAG_CH18);
                texts[18] = bit(FLAG_FRAME_LOST);
                texts[19] = bit(FLAG_FAILSAFE);
                texts[20] = &t.raw[usize::from(rssi)][1..];
                c.parts_text(&PARTS, &texts);
            }
            What::Poll(phys) => {
                if c.stamp(1 << 31 | 2 | u32::from(phys) << 8) {
                    c.id(Some(u32::from(phys)));
                    c.text(names::device(phys));
                    c.empty();
                    c.empty();
                    c.empty();
                    c.stamp_end();
                }
                c.empty();
                c.value(None);
                c.empty();
                c.text("Downlink");
                c.empty();
            }
            What::Data(phys, app_id, value, common) => {
                let sensor = match common {
                    Common::Scalar { s, .. } => s.label,
                    _ => "GPS",
                };
                let gps_lon = matches!(common, Common::Gps) && value & 0x8000_0000 != 0;
                let stamp =
                    1 << 30 | u32::from(phys) << 17 | u32::from(app_id) << 1 | u32::from(gps_lon);
                if c.stamp(stamp) {
                    c.id(Some(u32::from(phys)));
                    c.text(names::device(phys));
                    c.text("Data");
                    c.begin();
                    c.str("0x");
                    c.hex2((app_id >> 8) as u8);
                    c.hex2(app_id as u8);
                    c.end();
                    c.text(sensor);
                    c.stamp_end();
                }
                c.begin();
                let (name, unit, m) = match common {
                    Common::Scalar { s, raw, prec } => {
                        let a = c.here();
                        c.fixed(raw, prec);
                        (s.name, s.unit, Mark::new(a, c.here()))
                    }
                    _ => {
                        // As `sport::values::gps`.
                        let e7 = (i64::from(value & 0x3FFF_FFFF) * 100 + 3) / 6;
                        let v = if value & 0x4000_0000 != 0 { -e7 } else { e7 };
                        c.str(if gps_lon { "lon=" } else { "lat=" });
                        let a = c.here();
                        c.fixed(v, 7);
                        let name = if gps_lon { "Lon" } else { "Lat" };
                        (name, "deg", Mark::new(a, c.here()))
                    }
                };
                c.end();
                c.value(Some(m));
                c.text(unit);
                c.text("Uplink");
                c.empty();
                c.part(name, m);
            }
        }
    }
}

/// Writes the frame's row straight into the table when it is a common row and the table lends
/// its output, keeping the statistics as the mapper does; `false` leaves the frame (and the
/// statistics) to the mapper.
#[inline]
pub(super) fn frame(
    stats: &mut Stats,
    held: &mut Held,
    baud: u32,
    framing: Framing,
    f: &Frame<'_>,
    out: &mut Latch<'_>,
) -> bool {
    if f.check != Check::Ok || f.unusual_escape || f.pad || f.guessed {
        return false;
    }
    let len = f.body[0];
    let data = f.data();
    let what = match (framing, f.role) {
        (Framing::V1, Role::Control) if len == V1_CONTROL_LEN => control(data),
        (Framing::V2, Role::Control) if len == V2_CONTROL_16 && f.kind() == Some(V2_CHANNELS) => {
            control(data)
        }
        (Framing::V1, Role::Downlink) if len == V1_TELEMETRY_LEN && data == [0; 7] => {
            Some(What::Poll(V1_PHYS))
        }
        (Framing::V1, Role::Uplink) if len == V1_TELEMETRY_LEN && data[0] == 0x10 => {
            answer(V1_PHYS, data)
        }
        // F.Port 2: the physical ID byte with valid check bits (as `busnoop sport`).
        (Framing::V2, Role::Downlink | Role::Uplink)
            if len == V2_TELEMETRY_LEN && f.kind().is_some_and(header_ok) =>
        {
            let phys = f.body[1] & 0x1F;
            match (f.role, data) {
                (Role::Downlink, [0, 0, 0, 0, 0, 0, 0]) => Some(What::Poll(phys)),
                (Role::Uplink, [0x10, ..]) => answer(phys, data),
                _ => None,
            }
        }
        _ => None,
    };
    let Some(what) = what else {
        return false;
    };
    let Some(direct) = out.direct(COLUMNS) else {
        return false;
    };
    let micros = table::micros(f.time, f.offset, baud);
    let st = stats;
    st.valid();
    let mut class = Class::Plain;
    match what {
        What::Control(ch, flags, rssi) => {
            held.update(&ch);
            st.control[1] += 1;
            st.rssi(rssi);
            if flags & FLAG_FRAME_LOST != 0 {
                st.frame_lost += 1;
                class = Class::Warning;
            }
            if flags & FLAG_FAILSAFE != 0 {
                st.failsafe += 1;
                class = Class::Warning;
            }
        }
        What::Poll(phys) => st.per[usize::from(phys)].polls += 1,
        What::Data(phys, ..) => {
            let ps = &mut st.per[usize::from(phys)];
            ps.answers += 1;
            ps.data += 1;
        }
    }
    direct.row(Some(micros), class, f.raw, &FportRow { what, held });
    true
}

/// A data answer (`data`: the S.Port payload `10 [app ID] [value]`) of a common sensor.
#[inline(always)]
fn answer(phys: u8, data: &[u8]) -> Option<What> {
    let app_id = u16::from_le_bytes([*data.get(1)?, *data.get(2)?]);
    let value = u32::from_le_bytes(data.get(3..7)?.try_into().ok()?);
    match values::common(phys, app_id, value) {
        Some(c @ (Common::Scalar { .. } | Common::Gps)) => Some(What::Data(phys, app_id, value, c)),
        _ => None,
    }
}

/// A control frame's 16 channels, flags and RSSI.
#[inline(always)]
fn control(data: &[u8]) -> Option<What> {
    const BYTES: usize = wire::channel_bytes(16);
    let (&flags, &rssi) = (data.get(BYTES)?, data.get(BYTES + 1)?);
    // As `wire::unpack_channels`, for a fixed count: the 22 bytes padded to 24, each channel
    // from three bytes at a place known when compiled (no bounds checks, unrolled).
    let mut p = [0u8; BYTES + 2];
    p[..BYTES].copy_from_slice(data.get(..BYTES)?);
    let mut ch = [0u16; 16];
    for (i, c) in ch.iter_mut().enumerate() {
        let (byte, shift) = (i * 11 / 8, i * 11 % 8);
        let word = u32::from_le_bytes([p[byte], p[byte + 1], p[byte + 2], 0]);
        *c = ((word >> shift) & 0x7FF) as u16;
    }
    Some(What::Control(ch, flags, rssi))
}
