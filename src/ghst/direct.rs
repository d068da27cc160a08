//! The common GHST rows written straight into the table ([`crate::row::direct`]): the frames a
//! Ghost receiver and a Betaflight flight controller exchange all the time, in the layout their
//! senders write (ten payload bytes) — RC frames of the 12-bit scale (0x30-0x32: CH1-4 and four
//! aux channels; 0x33 to the flight controller: CH1-4 and the link), battery (0x23), GPS (0x25),
//! GPS 2 (0x26) and magnetometer/baro (0x27, at least the altitude flagged valid). Every other
//! row (and every row when the table lends no [`crate::row::Direct`]) goes through the mapper
//! as a [`crate::row::Row`]; both give the same bytes (`testing::assert_direct_rows_match`), as
//! [`super::values::describe`] writes them.

use super::names;
use crate::crsf::link::COLUMNS;
use crate::row::{Cells, Class, Fmt, Latch, Mark, PartNames, RowOut, WriteRow};

/// The frame types written here.
#[derive(Clone, Copy, PartialEq, Eq)]
enum What {
    /// 0x30-0x32: CH1-4 and four aux channels.
    Rc,
    /// 0x33 to the flight controller: CH1-4, link quality, RSSI, RF protocol, power.
    RcLink,
    Battery,
    Gps,
    Gps2,
    /// 0x27 with its flags (at least the altitude valid).
    MagBaro,
}

/// One row: a valid frame's address, type, what it is and its payload (ten bytes).
struct GhstRow<'a> {
    addr: u8,
    ty: u8,
    what: What,
    p: &'a [u8; 10],
}

/// Numbers as text after a blank (` 1493.25`), each padded to 8 bytes with its length, for one
/// fixed-size copy.
type Padded = ([u8; 8], u8);

/// The texts of the RC frames' numbers, made once: the 12-bit channels in µs and raw, the aux
/// channels in µs and raw.
struct Texts {
    us12: Box<[Padded; 4096]>,
    raw12: Box<[Padded; 4096]>,
    aux_us: [Padded; 256],
    raw8: [Padded; 256],
}

fn padded(s: &str) -> Padded {
    let mut t = [0u8; 8];
    t[0] = b' ';
    t[1..=s.len()].copy_from_slice(s.as_bytes());
    (t, s.len() as u8 + 1)
}

fn texts() -> &'static Texts {
    static T: std::sync::OnceLock<Texts> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let mut t = Texts {
            us12: Box::new([([0; 8], 0); 4096]),
            raw12: Box::new([([0; 8], 0); 4096]),
            aux_us: [([0; 8], 0); 256],
            raw8: [([0; 8], 0); 256],
        };
        let mut s = String::new();
        for v in 0..4096u16 {
            s.clear();
            crate::fmt::push_fixed(&mut s, super::primary_us100(v, false), 2);
            t.us12[usize::from(v)] = padded(&s);
            t.raw12[usize::from(v)] = padded(&v.to_string());
        }
        for a in 0..=255u8 {
            t.aux_us[usize::from(a)] = padded(&super::aux_us(a, false).to_string());
            t.raw8[usize::from(a)] = padded(&a.to_string());
        }
        t
    })
}

/// Appends `text` (8 bytes, `len` of them meant) to `buf` at `n`; the new end.
#[inline(always)]
fn put(buf: &mut [u8; 96], n: usize, (text, len): &Padded) -> usize {
    if let Some(room) = buf.get_mut(n..n + 8) {
        room.copy_from_slice(text);
    }
    (n + usize::from(*len)).min(buf.len() - 8)
}

/// The four 12-bit channels packed little-endian in the first six bytes.
#[inline(always)]
fn primaries(p: &[u8; 10]) -> [u16; 4] {
    let w = |a: u8, b: u8| u16::from(a) | u16::from(b) << 8;
    [
        w(p[0], p[1]) & 0xFFF,
        w(p[1], p[2]) >> 4,
        w(p[3], p[4]) & 0xFFF,
        w(p[4], p[5]) >> 4,
    ]
}

fn le_u16(p: &[u8], at: usize) -> i64 {
    i64::from(u16::from_le_bytes([p[at], p[at + 1]]))
}

fn le_i16(p: &[u8], at: usize) -> i64 {
    i64::from(i16::from_le_bytes([p[at], p[at + 1]]))
}

fn le_i32(p: &[u8], at: usize) -> i64 {
    i64::from(i32::from_le_bytes([p[at], p[at + 1], p[at + 2], p[at + 3]]))
}

/// Writes `name=` and the number (`raw / 10^prec`) and its unit into the Data cell; the
/// number's mark.
#[inline(always)]
fn num<F: Fmt>(c: &mut Cells<'_, '_, F>, name: &str, raw: i64, prec: u8, unit: &str) -> Mark {
    c.str(name);
    let a = c.here();
    if prec == 0 {
        c.dec_i(raw);
    } else {
        c.fixed(raw, prec);
    }
    let m = Mark::new(a, c.here());
    c.str(unit);
    m
}

/// The text of a small number (for the JSON parts not in the Data cell).
fn small(v: i64, buf: &mut [u8; 8]) -> &str {
    let mut n = 0;
    if v < 0 {
        buf[0] = b'-';
        n = 1;
    }
    let m = v.unsigned_abs();
    for d in [100, 10, 1] {
        if m >= d || d == 1 {
            buf[n] = b'0' + (m / d % 10) as u8;
            n += 1;
        }
    }
    std::str::from_utf8(&buf[..n]).unwrap_or_default()
}

const NAMES: [&str; 16] = [
    "CH1", "CH2", "CH3", "CH4", "CH5", "CH6", "CH7", "CH8", "CH9", "CH10", "CH11", "CH12", "CH13",
    "CH14", "CH15", "CH16",
];

impl GhstRow<'_> {
    #[inline(always)]
    fn rc<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let p = self.p;
        let t = texts();
        let raw = primaries(p);
        let link = self.what == What::RcLink;
        let count = if link { 4 } else { 8 };
        // Data: the µs texts (each after a blank) in one piece, without the first blank.
        let mut buf = [0u8; 96];
        let mut at = [(0u32, 0u32); 8];
        let mut n = 0;
        for (k, a) in at.iter_mut().enumerate().take(count) {
            let text = if k < 4 {
                &t.us12[usize::from(raw[k])]
            } else {
                &t.aux_us[usize::from(p[2 + k])]
            };
            a.0 = n as u32 + 1;
            n = put(&mut buf, n, text);
            a.1 = n as u32;
        }
        c.begin();
        let a = c.here().saturating_sub(1);
        c.put_ascii(&buf[1..n]);
        let marks = at.map(|(s, e)| Mark::new(a + s, a + e));
        c.end();
        c.value(Some(marks[0]));
        c.text("us");
        // Note: the raw values, then the aux ones or the RF protocol, then the scale.
        buf[..3].copy_from_slice(b"raw");
        let mut n = 3;
        for &r in &raw {
            n = put(&mut buf, n, &t.raw12[usize::from(r)]);
        }
        c.begin();
        c.put_ascii(&buf[..n]);
        if link {
            c.str("; RF protocol ");
            c.str(names::rf_protocol(p[8]));
        } else {
            buf[..9].copy_from_slice(b"; aux raw");
            let mut n = 9;
            for &r in &p[6..10] {
                n = put(&mut buf, n, &t.raw8[usize::from(r)]);
            }
            c.put_ascii(&buf[..n]);
        }
        c.str("; 12-bit scale");
        c.end();
        let first = match self.ty & 0x0F {
            0 => 4,
            1 => 8,
            _ => 12,
        };
        // CH1 to CH4, then the aux channels from `first`.
        static LISTS: [PartNames<8>; 3] = [
            PartNames::new(["CH1", "CH2", "CH3", "CH4", "CH5", "CH6", "CH7", "CH8"]),
            PartNames::new(["CH1", "CH2", "CH3", "CH4", "CH9", "CH10", "CH11", "CH12"]),
            PartNames::new(["CH1", "CH2", "CH3", "CH4", "CH13", "CH14", "CH15", "CH16"]),
        ];
        let list = &LISTS[first / 4 - 1];
        debug_assert!(
            (0..8).all(|k| list.names()[k] == NAMES[if k < 4 { k } else { first + k - 4 }])
        );
        c.parts_marked(list, &marks[..count]);
        if link {
            static LINK: PartNames<4> = PartNames::new(["RQly", "RSSI", "RFMD", "TPWR"]);
            let mut b = [[0u8; 8]; 4];
            let [b0, b1, b2, b3] = &mut b;
            c.parts_text(
                &LINK,
                &[
                    small(p[6].into(), b0),
                    small(-i64::from(p[7]), b1),
                    small(p[8].into(), b2),
                    small((p[9] as i8).into(), b3),
                ],
            );
        }
    }
}

impl WriteRow for GhstRow<'_> {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let p = self.p;
        let (kind, sensor, unit) = match self.what {
            What::Rc => ("RC", "CH1", "us"),
            What::RcLink => ("RCLink", "CH1", "us"),
            What::Battery => ("Battery", "RxBt", "V"),
            What::Gps => ("GPS", "GPS", "deg"),
            What::Gps2 => ("GPS2", "GSpd", "km/h"),
            What::MagBaro if p[9] & 1 != 0 => ("MagBaro", "MHdg", "deg"),
            What::MagBaro => ("MagBaro", "BAlt", "m"),
        };
        let variant = u32::from(self.what == What::MagBaro && p[9] & 1 == 0) << 16;
        if c.stamp(1 << 31 | variant | u32::from(self.addr) << 8 | u32::from(self.ty)) {
            c.id(Some(u32::from(self.addr)));
            c.text(names::device(self.addr));
            c.text(kind);
            c.begin();
            c.str("0x");
            c.hex2(self.ty);
            c.end();
            c.text(sensor);
            c.stamp_end();
        }
        match self.what {
            What::Rc | What::RcLink => self.rc(c),
            What::Battery => {
                c.begin();
                let m0 = num(c, "RxBt=", le_u16(p, 0), 2, "V");
                let m1 = num(c, " Curr=", le_u16(p, 2), 2, "A");
                let m2 = num(c, " Capa=", le_u16(p, 4) * 10, 0, "mAh");
                let m3 = num(c, " RxV=", p[6].into(), 1, "V");
                c.end();
                c.value(Some(m0));
                c.text(unit);
                c.empty();
                c.part_static("RxBt", m0);
                c.part_static("Curr", m1);
                c.part_static("Capa", m2);
                c.part_static("RxV", m3);
            }
            What::Gps => {
                c.begin();
                let m0 = num(c, "Lat=", le_i32(p, 0), 7, "deg");
                let m1 = num(c, " Lon=", le_i32(p, 4), 7, "deg");
                let m2 = num(c, " Alt=", le_i16(p, 8), 0, "m");
                c.end();
                c.value(Some(m0));
                c.text(unit);
                c.empty();
                c.part_static("Lat", m0);
                c.part_static("Lon", m1);
                c.part_static("Alt", m2);
            }
            What::Gps2 => {
                c.begin();
                let m0 = num(c, "GSpd=", (le_u16(p, 0) * 36 + 50) / 100, 1, "km/h");
                let m1 = num(c, " Hdg=", le_u16(p, 2), 1, "deg");
                let m2 = num(c, " Sats=", p[4].into(), 0, "");
                let m3 = num(c, " Dist=", le_u16(p, 5) * 10, 0, "m");
                let m4 = num(c, " HDir=", le_u16(p, 7), 1, "deg");
                c.end();
                c.value(Some(m0));
                c.text(unit);
                c.text(match p[9] & 3 {
                    0 => "no fix, no home",
                    1 => "fix, no home",
                    2 => "no fix, home set",
                    _ => "fix, home set",
                });
                c.part_static("GSpd", m0);
                c.part_static("Hdg", m1);
                c.part_static("Sats", m2);
                c.part_static("Dist", m3);
                c.part_static("HDir", m4);
            }
            What::MagBaro => {
                let flags = p[9];
                let mut marks = [("", Mark::default()); 3];
                let mut k = 0;
                c.begin();
                if flags & 1 != 0 {
                    marks[k] = ("MHdg", num(c, "MHdg=", le_i16(p, 0), 1, "deg"));
                    k += 1;
                }
                let sep = if k > 0 { " BAlt=" } else { "BAlt=" };
                marks[k] = ("BAlt", num(c, sep, le_i16(p, 2), 0, "m"));
                k += 1;
                if flags & 4 != 0 {
                    marks[k] = ("VSpd", num(c, " VSpd=", (p[4] as i8).into(), 2, "m/s"));
                    k += 1;
                }
                c.end();
                c.value(Some(marks[0].1));
                c.text(unit);
                if flags & 7 != 7 {
                    c.begin();
                    c.str("flags 0x");
                    c.hex2(flags);
                    c.str(": only the fields flagged valid are shown");
                    c.end();
                } else {
                    c.empty();
                }
                for &(name, m) in &marks[..k] {
                    c.part_static(name, m);
                }
            }
        }
    }
}

/// What a valid frame of type `ty` to `addr` with payload `p` is, when it is one of the common
/// rows.
#[inline]
fn what(addr: u8, ty: u8, p: &[u8; 10]) -> Option<What> {
    Some(match ty {
        0x30..=0x32 => What::Rc,
        0x33 if addr == names::FC => What::RcLink,
        0x23 => What::Battery,
        0x25 => What::Gps,
        0x26 => What::Gps2,
        0x27 if p[9] & 2 != 0 => What::MagBaro,
        _ => return None,
    })
}

/// Writes the row of a valid frame (`wire`: address to CRC) straight into the table when it is
/// a common row and the table lends its output: `Some` with the link-quality sample it carries
/// (the mapper keeps the statistics); `None` leaves the frame to the mapper.
#[inline]
pub(super) fn frame(wire: &[u8], micros: u64, out: &mut Latch<'_>) -> Option<Option<u8>> {
    let (&addr, rest) = wire.split_first()?;
    let (&ty, _) = rest.get(1..)?.split_first()?;
    let p: &[u8; 10] = wire.get(3..wire.len() - 1)?.try_into().ok()?;
    let what = what(addr, ty, p)?;
    let direct = out.direct(COLUMNS)?;
    direct.row(
        Some(micros),
        Class::Plain,
        wire,
        &GhstRow { addr, ty, what, p },
    );
    Some((what == What::RcLink).then(|| p[6]))
}
