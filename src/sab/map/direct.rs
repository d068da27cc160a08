//! SAB's rows written straight into the table ([`crate::row::direct`]): the cells the
//! [`Mapper`](super::Mapper) puts into a [`Row`](crate::row::Row) otherwise.

use super::text::{DATA1, DOT_DECIMALS3, int_reading};
use super::{Flags, Framing, Names, RowParts, Scratch};
use crate::fmt::hex_0x;
use crate::row::{Cells, Fmt, Mark, Parts, WriteRow};

/// A row of the scratch buffers, written straight into the table ([`crate::row::direct`]):
/// the cells of the [`Row`](crate::row::Row) [`Mapper::put`](super::Mapper::put) builds otherwise.
pub(super) struct ScratchRow<'a> {
    pub(super) p: &'a RowParts<'a>,
    pub(super) sc: &'a Scratch,
    pub(super) addr: &'a str,
    pub(super) device: &'a str,
    pub(super) sensor_no: &'a str,
    pub(super) sensor: &'a str,
    pub(super) unit: &'a str,
    pub(super) parts: Parts<'a>,
}

impl WriteRow for ScratchRow<'_> {
    #[inline]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let (p, sc) = (self.p, self.sc);
        if c.stamp(p.stamp) {
            c.id(p.id.map(u32::from));
            c.text(self.device);
            c.text(p.kind);
            c.text(self.sensor_no);
            c.text(self.sensor);
            c.stamp_end();
        }
        c.text(&sc.data);
        c.value_text(self.parts.first().map(|p| p.text));
        c.text(self.unit);
        c.text(self.addr);
        c.text(&sc.resp);
        c.text(p.framing.name());
        c.text(&sc.note);
        c.row_parts(self.parts);
    }
}

/// A valid frame's row written straight into the table, its Data cell (the payload and its
/// integer reading, [`push_data`](super::text::push_data)), Value and response time formatted in place: the cells
/// [`Mapper::frame`](super::Mapper::frame) puts into a [`Row`](crate::row::Row) otherwise, for frames without a declared type.
pub(super) struct FrameRow<'a> {
    pub(super) stamp: u32,
    pub(super) addr: u8,
    pub(super) command: u8,
    pub(super) flags: Flags,
    /// A request or an ACK: its reading is the row's number.
    pub(super) numbered: bool,
    pub(super) payload: &'a [u8],
    /// Response time (µs) of a paired response.
    pub(super) resp: Option<u64>,
    pub(super) framing: Framing,
    pub(super) names: &'a Names,
    pub(super) note: &'a str,
}

impl WriteRow for FrameRow<'_> {
    #[inline(always)]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let (addr, command) = (self.addr, self.command);
        if c.stamp(self.stamp) {
            c.id(Some(u32::from(addr)));
            c.text(self.names.device(addr));
            c.text(self.flags.type_name());
            c.text(hex_0x(command));
            c.text(self.names.command(command));
            c.stamp_end();
        }
        let payload = self.payload;
        let mut mark = None;
        let reading = int_reading(payload);
        if payload.is_empty() {
            c.empty();
        } else {
            // A negative signed reading is written after the unsigned one (`B5 (181, -75)`):
            // the cell then holds a comma (CSV quotes it), known before it is written.
            let signed = matches!(reading, Some((_, s)) if s < 0);
            if signed {
                c.begin_listed();
            } else {
                c.begin();
            }
            if let [b] = *payload {
                // `XX (` and the number's digits
                let text = DATA1[b as usize].as_bytes();
                let a = c.here() + 4;
                if signed {
                    c.put_listed(text);
                } else {
                    c.put_ascii(text);
                }
                let digits = 1 + u32::from(b >= 10) + u32::from(b >= 100);
                mark = Some(Mark::new(a, a + digits));
            } else {
                c.hex_bytes(payload);
                if let Some((unsigned, signed)) = reading {
                    c.put_ascii(b" (");
                    let a = c.here();
                    c.dec(u64::from(unsigned));
                    mark = Some(Mark::new(a, c.here()));
                    if signed < 0 {
                        c.put_listed(b", -");
                        c.dec(u64::from(signed.unsigned_abs()));
                    }
                    c.put_ascii(b")");
                }
            }
            c.end();
        }
        let number = if self.numbered { mark } else { None };
        c.value(number);
        c.empty();
        c.text(hex_0x(addr));
        match self.resp {
            Some(micros) => {
                // `push_ms3`
                let micros = micros.min(i64::MAX as u64);
                let (ms, f) = (micros / 1000, (micros % 1000) as usize);
                c.begin();
                if ms < 10 {
                    c.put_ascii(&[b'0' + ms as u8]);
                } else {
                    c.dec(ms);
                }
                c.put_ascii(&DOT_DECIMALS3.as_bytes()[4 * f..4 * f + 4]);
                c.end();
            }
            None => c.empty(),
        }
        c.text(self.framing.name());
        c.text(self.note);
        if let Some(m) = number {
            c.part(self.names.part(command, self.flags == Flags::Ack), m);
        }
    }
}

/// A `Timeout` row closed by the next request or the end of the capture, written straight
/// into the table: the cells [`Mapper::timeout_row`](super::Mapper::timeout_row) puts into a
/// [`Row`](crate::row::Row) otherwise.
pub(super) struct TimeoutRow<'a> {
    pub(super) stamp: u32,
    pub(super) addr: u8,
    pub(super) command: u8,
    /// Closed by the end of the capture (else by the next request).
    pub(super) end: bool,
    /// µs waited.
    pub(super) waited: u64,
    pub(super) framing: Framing,
    pub(super) names: &'a Names,
}

impl WriteRow for TimeoutRow<'_> {
    #[inline]
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        let (addr, command) = (self.addr, self.command);
        if c.stamp(self.stamp) {
            c.id(Some(u32::from(addr)));
            c.text(self.names.device(addr));
            c.text(crate::row::kind::TIMEOUT);
            c.text(hex_0x(command));
            c.text(self.names.command(command));
            c.stamp_end();
        }
        c.empty();
        c.value(None);
        c.empty();
        c.text(hex_0x(addr));
        c.empty();
        c.text(self.framing.name());
        // `push_ms` (three decimals)
        let micros = self.waited.min(i64::MAX as u64);
        let f = (micros % 1000) as usize;
        c.begin();
        c.str(if self.end {
            "no response before the end of the capture (after "
        } else {
            "no response before the next request (after "
        });
        c.dec(micros / 1000);
        c.str(&DOT_DECIMALS3[4 * f..4 * f + 4]);
        c.str(" ms)");
        c.end();
    }
}
