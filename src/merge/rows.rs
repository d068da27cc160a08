//! Rows kept between a port's decoder and the merge: every cell copied into two buffers (text
//! and wire bytes), so that a batch of rows costs a handful of allocations, whatever its size.

use crate::row::{Class, Part, Row};

/// Extra cells and numbers of a row given back without allocating.
const ON_STACK: usize = 8;

/// Where a cell's text is in [`Rows::text`].
type Span = (u32, u32);

/// One kept row: its cells as spans of the batch's buffers.
#[derive(Clone, Debug)]
struct Kept {
    micros: Option<u64>,
    /// The time the merge orders it by: `micros`, or the time of the port's row before it.
    at: u64,
    id: Option<u32>,
    class: Class,
    /// Device, Type, Sensor #, Sensor, Data.
    cells: [Span; 5],
    /// Its extra cells: `extras[from..to]`.
    extra: (u32, u32),
    /// Its numbers: `parts[from..to]`.
    parts: (u32, u32),
    raw: (u32, u32),
}

/// A number of a kept row.
#[derive(Clone, Debug)]
struct KeptPart {
    name: Span,
    unit: Span,
    text: Span,
    value: f64,
}

/// A batch of rows of one port, in the order its decoder wrote them.
#[derive(Clone, Debug, Default)]
pub struct Rows {
    text: String,
    raw: Vec<u8>,
    extras: Vec<Span>,
    parts: Vec<KeptPart>,
    rows: Vec<Kept>,
}

impl Rows {
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// An empty batch with the room this one took (a port's batches are alike).
    pub fn like(&self) -> Rows {
        Rows {
            text: String::with_capacity(self.text.len()),
            raw: Vec::with_capacity(self.raw.len()),
            extras: Vec::with_capacity(self.extras.len()),
            parts: Vec::with_capacity(self.parts.len()),
            rows: Vec::with_capacity(self.rows.len()),
        }
    }

    fn put(&mut self, s: &str) -> Span {
        let from = self.text.len() as u32;
        self.text.push_str(s);
        (from, self.text.len() as u32)
    }

    fn cut(&self, (from, to): Span) -> &str {
        &self.text[from as usize..to as usize]
    }

    /// Keeps a copy of `row`, `offset` µs later (the port's start on the common clock); `at`:
    /// its time for the merge.
    pub fn push(&mut self, row: &Row<'_>, offset: u64, at: u64) {
        let cells = [
            self.put(row.device),
            self.put(row.kind),
            self.put(row.sensor_no),
            self.put(row.sensor),
            self.put(row.data),
        ];
        let from = self.extras.len() as u32;
        for e in row.extra {
            let s = self.put(e);
            self.extras.push(s);
        }
        let extra = (from, self.extras.len() as u32);
        let from = self.parts.len() as u32;
        for p in row.parts {
            let part = KeptPart {
                name: self.put(p.name),
                unit: self.put(p.unit),
                text: self.put(p.text),
                value: p.value,
            };
            self.parts.push(part);
        }
        let parts = (from, self.parts.len() as u32);
        let from = self.raw.len() as u32;
        self.raw.extend_from_slice(row.raw);
        self.rows.push(Kept {
            micros: row.micros.map(|m| m.saturating_add(offset)),
            at,
            id: row.id,
            class: row.class,
            cells,
            extra,
            parts,
            raw: (from, self.raw.len() as u32),
        });
    }

    /// The merge time of row `i`.
    pub fn at(&self, i: usize) -> u64 {
        self.rows[i].at
    }

    /// Row `i` as a [`Row`] whose first extra cell is `port`, handed to `f`. Its stamp is 0:
    /// the stamps of two decoders make no promise to each other.
    pub fn with_row<R>(&self, i: usize, port: &str, f: impl FnOnce(&Row<'_>) -> R) -> R {
        let k = &self.rows[i];
        // Rows have a few cells and numbers: on the stack, in a vector only when there are more.
        let extras = &self.extras[k.extra.0 as usize..k.extra.1 as usize];
        let mut few = [""; ON_STACK];
        let many: Vec<&str>;
        let extra: &[&str] = if extras.len() < ON_STACK {
            few[0] = port;
            for (cell, &s) in few[1..].iter_mut().zip(extras) {
                *cell = self.cut(s);
            }
            &few[..=extras.len()]
        } else {
            many = std::iter::once(port)
                .chain(extras.iter().map(|&s| self.cut(s)))
                .collect();
            &many
        };
        let kept = &self.parts[k.parts.0 as usize..k.parts.1 as usize];
        let part = |p: &KeptPart| Part {
            name: self.cut(p.name),
            unit: self.cut(p.unit),
            text: self.cut(p.text),
            value: p.value,
        };
        let mut few_parts = [Part::EMPTY; ON_STACK];
        let many_parts: Vec<Part<'_>>;
        let parts: &[Part<'_>] = if kept.len() <= ON_STACK {
            for (slot, p) in few_parts.iter_mut().zip(kept) {
                *slot = part(p);
            }
            &few_parts[..kept.len()]
        } else {
            many_parts = kept.iter().map(part).collect();
            &many_parts
        };
        let [device, kind, sensor_no, sensor, data] = k.cells.map(|c| self.cut(c));
        f(&Row {
            micros: k.micros,
            id: k.id,
            device,
            kind,
            class: k.class,
            sensor_no,
            sensor,
            data,
            extra,
            parts: parts.into(),
            raw: &self.raw[k.raw.0 as usize..k.raw.1 as usize],
            stamp: 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::row::{Collected, RowOut};

    #[test]
    fn a_kept_row_comes_back_with_its_port_and_every_cell() {
        let parts = [
            Part {
                name: "Cell1",
                unit: "V",
                text: "3.90",
                value: 3.9,
            },
            Part {
                name: "Cell2",
                unit: "V",
                text: "3.91",
                value: 3.91,
            },
        ];
        let row = Row {
            micros: Some(1500),
            id: Some(8),
            device: "FLVSS",
            kind: "Data",
            class: Class::Warning,
            sensor_no: "0300",
            sensor: "Cels",
            data: "3.90 3.91",
            extra: &["x", ""],
            parts: parts[..].into(),
            raw: &[0x7E, 0x28],
            stamp: 77,
        };
        let mut rows = Rows::default();
        rows.push(&Row::empty(None), 0, 0);
        rows.push(&row, 1_000_000, 1_001_500);
        assert_eq!((rows.len(), rows.at(1)), (2, 1_001_500));
        let mut got = Collected::default();
        rows.with_row(1, "/dev/ttyUSB1", |r| {
            assert_eq!(r.stamp, 0);
            got.row(r).unwrap()
        });
        let r = &got.rows[0];
        assert_eq!(r.micros, Some(1_001_500));
        assert_eq!((r.id, r.class), (Some(8), Class::Warning));
        assert_eq!(
            [&r.device, &r.kind, &r.sensor_no, &r.sensor, &r.data],
            ["FLVSS", "Data", "0300", "Cels", "3.90 3.91"]
        );
        assert_eq!(r.extra, ["/dev/ttyUSB1", "x", ""]);
        assert_eq!(r.parts.len(), 2);
        assert_eq!(r.parts[1], ("Cell2".into(), "V".into(), "3.91".into()));
        assert_eq!(r.raw, [0x7E, 0x28]);
    }
}
