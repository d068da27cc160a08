//! The common CRSF rows written straight into the table ([`crate::row::direct`]): the frames an
//! ExpressLRS receiver and a Betaflight flight controller exchange all the time, in the layout
//! their senders write — RC channels (0x16, 22 bytes), link statistics (0x14, 10 bytes, a known
//! power index), battery (0x08, 8 bytes), GPS (0x02, 15 bytes), attitude (0x1E, 6 bytes) and
//! flight mode (0x21, one NUL at the end). Every other row (and every row when the table lends
//! no [`crate::row::Direct`]) goes through the mapper as a [`crate::row::Row`]; both give the
//! same bytes (`testing::assert_direct_rows_match`), as [`super::values::broadcast`] writes
//! them.

use super::link::COLUMNS;
use super::names;
use super::values::rssi_dbm;
use crate::row::{Cells, Class, Fmt, Latch, Mark, PartNames, RowOut, WriteRow};

/// The frame types written here.
#[derive(Clone, Copy, PartialEq, Eq)]
enum What {
    Rc,
    Link,
    Battery,
    Gps,
    Attitude,
    Mode,
}

/// One row: a valid frame's address, what it is and its payload.
struct CrsfRow<'a> {
    addr: u8,
    ty: u8,
    what: What,
    p: &'a [u8],
}

/// The text of every number below 2048 after a blank (` 1501`): each a slice of one string
/// made once, and each padded to 8 bytes with its length (for one fixed-size copy).
struct Texts {
    slices: Box<[&'static str; 2048]>,
    padded: Box<[([u8; 8], u8); 2048]>,
}

impl Texts {
    fn new(number: impl Fn(u16) -> i64) -> Self {
        let mut s = String::with_capacity(2048 * 5);
        let mut at = [0usize; 2049];
        for raw in 0..2048u16 {
            at[usize::from(raw)] = s.len();
            s.push(' ');
            crate::fmt::push_i64(&mut s, number(raw));
        }
        at[2048] = s.len();
        let s: &'static str = Box::leak(s.into_boxed_str());
        let mut slices = Box::new([""; 2048]);
        let mut padded = Box::new([([0u8; 8], 0u8); 2048]);
        for i in 0..2048 {
            let t = &s[at[i]..at[i + 1]];
            slices[i] = t;
            padded[i].0[..t.len()].copy_from_slice(t.as_bytes());
            padded[i].1 = t.len() as u8;
        }
        Texts { slices, padded }
    }

    /// ` <number>` of `raw` (below 2048).
    #[inline(always)]
    fn get(&self, raw: u16) -> &'static str {
        self.slices[usize::from(raw & 0x7FF)]
    }

    /// Appends ` <number>` of each of `raw` to `buf` from `n` on (room for 8 bytes more than
    /// the texts), noting where each number starts and ends; returns the end.
    #[inline(always)]
    fn list(
        &self,
        raw: &[u16; 16],
        buf: &mut [u8; 136],
        mut n: usize,
        at: &mut [(u32, u32); 16],
    ) -> usize {
        for (&r, at) in raw.iter().zip(at) {
            let (text, len) = &self.padded[usize::from(r & 0x7FF)];
            if let Some(room) = buf.get_mut(n..n + 8) {
                room.copy_from_slice(text);
            }
            at.0 = n as u32 + 1;
            n = (n + usize::from(*len)).min(buf.len() - 8);
            at.1 = n as u32;
        }
        n
    }
}

/// The channels' texts: µs on Betaflight's scale (`values::channel_us`) and raw, made once.
fn texts() -> &'static (Texts, Texts) {
    static T: std::sync::OnceLock<(Texts, Texts)> = std::sync::OnceLock::new();
    T.get_or_init(|| (Texts::new(super::values::channel_us), Texts::new(i64::from)))
}

/// The 16 channels of a 22-byte RC payload (11 bits each, little-endian).
#[inline(always)]
fn channels(p: &[u8]) -> [u16; 16] {
    let mut b = [0u8; 24];
    b[..22].copy_from_slice(&p[..22]);
    let mut raw = [0u16; 16];
    for (k, r) in raw.iter_mut().enumerate() {
        let bit = 11 * k;
        let at = bit >> 3;
        let x = u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        *r = ((x >> (bit & 7)) & 0x7FF) as u16;
    }
    raw
}

fn be_i16(p: &[u8], at: usize) -> i64 {
    i64::from(i16::from_be_bytes([p[at], p[at + 1]]))
}

fn be_u16(p: &[u8], at: usize) -> i64 {
    i64::from(u16::from_be_bytes([p[at], p[at + 1]]))
}

fn be_i32(p: &[u8], at: usize) -> i64 {
    i64::from(i32::from_be_bytes([p[at], p[at + 1], p[at + 2], p[at + 3]]))
}

/// Writes `name=` and the number (`raw / 10^prec`) and its unit into the Data cell; the
/// number's mark.
#[inline(always)]
fn num<F: Fmt>(c: &mut Cells<'_, '_, F>, name: &str, raw: i64, prec: u8, unit: &str) -> Mark {
    c.str(name);
    let a = c.here();
    if prec == 0 && raw.unsigned_abs() < 2048 {
        // A small integer (link statistics, percentages): its text from the table.
        if raw < 0 {
            c.str("-");
        }
        let t = texts().1.get(raw.unsigned_abs() as u16);
        c.str(t.get(1..).unwrap_or_default());
    } else if prec == 0 {
        c.dec_i(raw);
    } else {
        c.fixed(raw, prec);
    }
    let m = Mark::new(a, c.here());
    c.str(unit);
    m
}

impl WriteRow for CrsfRow<'_> {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let p = self.p;
        let (sensor, unit) = match self.what {
            What::Rc => ("CH1", "us"),
            What::Link => ("1RSS", "dBm"),
            What::Battery => ("RxBt", "V"),
            What::Gps => ("GPS", "deg"),
            What::Attitude => ("Ptch", "rad"),
            What::Mode => ("FM", ""),
        };
        if c.stamp(1 << 31 | u32::from(self.addr) << 8 | u32::from(self.ty)) {
            c.id(Some(u32::from(self.addr)));
            c.text(names::device(self.addr));
            c.text(names::frame_type(self.ty).unwrap_or("Unknown"));
            c.begin();
            c.str("0x");
            c.hex2(self.ty);
            c.end();
            c.text(sensor);
            c.stamp_end();
        }
        match self.what {
            What::Rc => {
                let raw = channels(p);
                let (us, numbers) = texts();
                // Data: the µs texts (each after a blank) in one piece, without the first blank.
                let mut buf = [0u8; 136];
                let mut at = [(0u32, 0u32); 16];
                let n = us.list(&raw, &mut buf, 0, &mut at);
                c.begin();
                // Where buf[0] would be in the line.
                let a = c.here().saturating_sub(1);
                c.put_ascii(&buf[1..n]);
                let marks = at.map(|(s, e)| Mark::new(a + s, a + e));
                c.end();
                c.value(Some(marks[0]));
                c.text(unit);
                // Note: `raw` and the raw values.
                buf[..3].copy_from_slice(b"raw");
                let n = numbers.list(&raw, &mut buf, 3, &mut at);
                c.begin();
                c.put_ascii(&buf[..n]);
                c.end();
                static NAMES: PartNames<16> = PartNames::new([
                    "CH1", "CH2", "CH3", "CH4", "CH5", "CH6", "CH7", "CH8", "CH9", "CH10", "CH11",
                    "CH12", "CH13", "CH14", "CH15", "CH16",
                ]);
                c.parts_marked(&NAMES, &marks);
            }
            What::Link => {
                let mw = i64::from(names::RF_POWER_MW[usize::from(p[6])]);
                // (the text before the number, the part's name, the number, its unit)
                let fields: [(&str, &str, i64, &str); 10] = [
                    ("1RSS=", "1RSS", rssi_dbm(p[0]), "dBm"),
                    (" 2RSS=", "2RSS", rssi_dbm(p[1]), "dBm"),
                    (" RQly=", "RQly", p[2].into(), "%"),
                    (" RSNR=", "RSNR", (p[3] as i8).into(), "dB"),
                    (" ANT=", "ANT", p[4].into(), ""),
                    (" RFMD=", "RFMD", p[5].into(), ""),
                    (" TPWR=", "TPWR", mw, "mW"),
                    (" TRSS=", "TRSS", rssi_dbm(p[7]), "dBm"),
                    (" TQly=", "TQly", p[8].into(), "%"),
                    (" TSNR=", "TSNR", (p[9] as i8).into(), "dB"),
                ];
                let mut marks = [Mark::default(); 10];
                c.begin();
                for (m, &(label, _, v, u)) in marks.iter_mut().zip(&fields) {
                    *m = num(c, label, v, 0, u);
                }
                c.end();
                c.value(Some(marks[0]));
                c.text(unit);
                c.empty();
                static NAMES: PartNames<10> = PartNames::new([
                    "1RSS", "2RSS", "RQly", "RSNR", "ANT", "RFMD", "TPWR", "TRSS", "TQly", "TSNR",
                ]);
                debug_assert!(NAMES.names().iter().zip(&fields).all(|(n, f)| *n == f.1));
                c.parts_marked(&NAMES, &marks);
            }
            What::Battery => {
                c.begin();
                let m0 = num(c, "RxBt=", be_i16(p, 0), 1, "V");
                let m1 = num(c, " Curr=", be_i16(p, 2), 1, "A");
                let capa = i64::from(p[4]) << 16 | i64::from(p[5]) << 8 | i64::from(p[6]);
                let m2 = num(c, " Capa=", capa, 0, "mAh");
                let m3 = num(c, " Bat%=", p[7].into(), 0, "%");
                c.end();
                c.value(Some(m0));
                c.text(unit);
                c.empty();
                static NAMES: PartNames<4> = PartNames::new(["RxBt", "Curr", "Capa", "Bat%"]);
                c.parts_marked(&NAMES, &[m0, m1, m2, m3]);
            }
            What::Gps => {
                c.begin();
                let m0 = num(c, "Lat=", be_i32(p, 0), 7, "deg");
                let m1 = num(c, " Lon=", be_i32(p, 4), 7, "deg");
                let m2 = num(c, " GSpd=", be_u16(p, 8), 1, "km/h");
                let m3 = num(c, " Hdg=", be_u16(p, 10), 2, "deg");
                let m4 = num(c, " Alt=", be_u16(p, 12) - 1000, 0, "m");
                let m5 = num(c, " Sats=", p[14].into(), 0, "");
                c.end();
                c.value(Some(m0));
                c.text(unit);
                c.empty();
                static NAMES: PartNames<6> =
                    PartNames::new(["Lat", "Lon", "GSpd", "Hdg", "Alt", "Sats"]);
                c.parts_marked(&NAMES, &[m0, m1, m2, m3, m4, m5]);
            }
            What::Attitude => {
                c.begin();
                let m0 = num(c, "Ptch=", be_i16(p, 0), 4, "rad");
                let m1 = num(c, " Roll=", be_i16(p, 2), 4, "rad");
                let m2 = num(c, " Yaw=", be_i16(p, 4), 4, "rad");
                c.end();
                c.value(Some(m0));
                c.text(unit);
                c.empty();
                static NAMES: PartNames<3> = PartNames::new(["Ptch", "Roll", "Yaw"]);
                c.parts_marked(&NAMES, &[m0, m1, m2]);
            }
            What::Mode => {
                // As `read::push_text`: printable ASCII, every other byte as `\xHH`.
                c.begin();
                for &b in &p[..p.len() - 1] {
                    if (0x20..0x7F).contains(&b) {
                        c.ascii(b);
                    } else {
                        c.str("\\x");
                        c.hex2(b);
                    }
                }
                c.end();
                c.empty_to_end();
            }
        }
    }
}

/// What a valid frame of type `ty` with payload `p` is, when it is one of the common rows.
#[inline]
fn what(ty: u8, p: &[u8]) -> Option<What> {
    Some(match (ty, p.len()) {
        (0x16, 22) => What::Rc,
        (0x14, 10) if usize::from(p[6]) < names::RF_POWER_MW.len() => What::Link,
        (0x08, 8) => What::Battery,
        (0x02, 15) => What::Gps,
        (0x1E, 6) => What::Attitude,
        (0x21, n) if n > 0 && p.iter().position(|&b| b == 0) == Some(n - 1) => What::Mode,
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
    let p = wire.get(3..wire.len() - 1)?;
    let what = what(ty, p)?;
    let direct = out.direct(COLUMNS)?;
    direct.row(
        Some(micros),
        Class::Plain,
        wire,
        &CrsfRow { addr, ty, what, p },
    );
    Some((what == What::Link).then(|| p[2]))
}
