//! The common S.Port rows written straight into the table ([`crate::row::direct`]): polls
//! without an answer, keep-alives, and data frames of the plain scalar sensors, FLVSS cells and
//! GPS coordinates, each with a good CRC and header and without an unusual escape. Every other
//! row (and every row when the table lends no [`crate::row::Direct`]) goes through the mapper
//! as a [`crate::row::Row`]; both give the same bytes (`testing::assert_direct_rows_match`).

use super::values::{self, Common};
use super::wire::{Body, Slot};
use super::{COLUMNS, Mapper, SLOT_MICROS, names, wire};
use crate::row::{Cells, Class, Fmt, Latch, Mark, RowOut, WriteRow};

/// What the row shows.
#[derive(Clone, Copy)]
enum What {
    /// A poll without an answer.
    Poll,
    /// A keep-alive of zeros.
    Null,
    /// A data frame of a common sensor.
    Data(u16, u32, Common),
}

/// One row.
struct SportRow {
    phys: u8,
    stamp: u32,
    what: What,
}

impl WriteRow for SportRow {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let phys = self.phys;
        if c.stamp(self.stamp) {
            c.id(Some(u32::from(phys)));
            c.text(names::device(phys));
            match self.what {
                What::Poll => {
                    c.empty();
                    c.empty();
                    c.empty();
                }
                What::Null => {
                    c.text("Null");
                    c.empty();
                    c.empty();
                }
                What::Data(app_id, _, common) => {
                    c.text("Data");
                    c.begin();
                    c.str("0x");
                    c.hex2((app_id >> 8) as u8);
                    c.hex2(app_id as u8);
                    c.end();
                    c.text(match common {
                        Common::Scalar { s, .. } => s.label,
                        Common::Cells => "Cels",
                        Common::Gps => "GPS",
                    });
                }
            }
            c.stamp_end();
        }
        let What::Data(_, value, common) = self.what else {
            c.empty_to_end();
            return;
        };
        c.begin();
        match common {
            Common::Scalar { s, raw, prec } => {
                let (name, unit) = (s.name, s.unit);
                let a = c.here();
                c.fixed(raw, prec);
                let m = Mark::new(a, c.here());
                c.end();
                c.value(Some(m));
                c.text(unit);
                c.empty();
                c.part(name, m);
            }
            Common::Cells => {
                // As `values::cells`: the first cell, and the second when its index is below
                // the count.
                let index = value & 0x0F;
                let count = (value >> 4) & 0x0F;
                let (k0, n0) = values::cell_key_name(index);
                c.str(values::cell_count_text(value));
                c.str(k0);
                let a = c.here();
                c.fixed(i64::from(((value >> 8) & 0x0FFF) * 2), 3);
                let m0 = Mark::new(a, c.here());
                let second = (index + 1 < count).then(|| {
                    let (k1, n1) = values::cell_key_name(index + 1);
                    c.str(k1);
                    let a = c.here();
                    c.fixed(i64::from((value >> 20) * 2), 3);
                    (n1, Mark::new(a, c.here()))
                });
                c.end();
                c.value(Some(m0));
                c.text("V");
                c.empty();
                c.part(n0, m0);
                if let Some((n1, m1)) = second {
                    c.part(n1, m1);
                }
            }
            Common::Gps => {
                // As `values::gps`.
                let lon = value & 0x8000_0000 != 0;
                let e7 = (i64::from(value & 0x3FFF_FFFF) * 100 + 3) / 6;
                let v = if value & 0x4000_0000 != 0 { -e7 } else { e7 };
                c.str(if lon { "lon=" } else { "lat=" });
                let a = c.here();
                c.fixed(v, 7);
                let m = Mark::new(a, c.here());
                c.end();
                c.value(Some(m));
                c.text("deg");
                c.empty();
                c.part(if lon { "Lon" } else { "Lat" }, m);
            }
        }
    }
}

/// Writes the slot's row straight into the table when it is a common row and the table lends
/// its output, keeping the statistics as the mapper does; `false` leaves the slot (and the
/// statistics) to the mapper.
#[inline]
pub(super) fn slot(map: &mut Mapper, s: &Slot, out: &mut Latch<'_>) -> bool {
    if !wire::header_ok(s.header) || s.unusual_escape {
        return false;
    }
    let phys = s.phys();
    let (what, stamp, class) = match s.body {
        Body::None => (What::Poll, 1 << 31 | u32::from(phys), Class::Plain),
        Body::Complete(b) => {
            let word = u64::from_le_bytes(b);
            let app_id = (word >> 8) as u16;
            let value = (word >> 24) as u32;
            // Firmware frames (type 0x50 from 0xFF/0x5E) are not type 0x00 or 0x10.
            if !wire::crc_ok(&b) {
                return false;
            }
            let stamp = |kind: u8| {
                1 << 30
                    | u32::from(phys)
                    | u32::from(kind) << 5
                    | 1 << 13
                    | u32::from(app_id) << 14
                    | u32::from(values::sensor_from_value(app_id, value)) << 31
            };
            match b[0] {
                0x00 if app_id == 0 && value == 0 => (What::Null, stamp(0), Class::Quiet),
                0x10 => match values::common(phys, app_id, value) {
                    Some(common) => (What::Data(app_id, value, common), stamp(0x10), Class::Plain),
                    None => return false,
                },
                _ => return false,
            }
        }
        Body::Truncated { .. } => return false,
    };
    let Some(direct) = out.direct(COLUMNS) else {
        return false;
    };
    let micros = s.time.unwrap_or(s.index * SLOT_MICROS);
    // The statistics, as the mapper keeps them for these rows.
    let st = &mut map.stats;
    if let Body::Complete(b) = s.body {
        if st.last_body == Some(b) {
            st.repeats += 1;
        }
        st.last_body = Some(b);
        st.valid_frames += 1;
    }
    let ps = super::PhysStats::poll(&mut st.per, phys, micros);
    match what {
        What::Poll => {}
        What::Null => ps.null += 1,
        What::Data(..) => ps.data += 1,
    }
    direct.row(
        Some(micros),
        class,
        s.wire(),
        &SportRow { phys, stamp, what },
    );
    true
}
