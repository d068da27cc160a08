//! The content of a frame: the Data cell and the row's numbers ([`crate::row::Part`]) of every
//! public function, requests, responses and exceptions (the table mapping is documented in
//! `docs/modbus.md`).
//!
//! Numbers are named as the wire has them: a request's `start` and `count` (0-based wire
//! addresses), registers `R<addr>` and coils or discrete inputs `C<addr>` at their wire address
//! (a response takes the addresses from its request; an unpaired one counts from its first
//! value, `R+0`, `R+1`, …), or by the register map's names with their units.

use super::function::{self, MEI_DEVICE_ID};
use super::pairing::Req;
use super::regmap::{Reading, RegisterMap, Table};
use super::wire::Kind;
use crate::fmt::{push_0x16, push_hex, push_hex_u8};
use crate::numbers::push_uint;
use crate::row::Part;

/// The unit of a number: none, a constant, or a register of the map (by index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    None,
    Reg(u32),
}

#[derive(Clone, Copy, Debug)]
struct Slot {
    name: (u32, u32),
    text: (u32, u32),
    value: f64,
    unit: Unit,
}

/// The numbers of one row, in reusable buffers (no allocation once they have grown).
#[derive(Default)]
pub struct Nums {
    names: String,
    texts: String,
    slots: Vec<Slot>,
    /// The parts handed to the row, kept for their allocation.
    cache: Vec<Part<'static>>,
}

impl Nums {
    pub fn clear(&mut self) {
        self.names.clear();
        self.texts.clear();
        self.slots.clear();
    }

    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// A number named by `name`, its text written by `text` (which gives its value, or `None`
    /// for a text that is no number: then it is left out).
    pub fn push(
        &mut self,
        name: impl FnOnce(&mut String),
        unit: Unit,
        text: impl FnOnce(&mut String) -> Option<f64>,
    ) {
        let (n0, t0) = (self.names.len(), self.texts.len());
        name(&mut self.names);
        let Some(value) = text(&mut self.texts) else {
            self.names.truncate(n0);
            self.texts.truncate(t0);
            return;
        };
        self.slots.push(Slot {
            name: (n0 as u32, self.names.len() as u32),
            text: (t0 as u32, self.texts.len() as u32),
            value,
            unit,
        });
    }

    /// An unsigned integer named by a constant.
    pub fn uint(&mut self, name: &str, v: u64) {
        self.push(
            |s| s.push_str(name),
            Unit::None,
            |t| {
                push_uint(t, v);
                Some(v as f64)
            },
        );
    }

    /// A register or coil value named `<letter><addr>` (or `<letter>+<i>` without address).
    fn plain(&mut self, letter: char, addr: Option<u32>, index: usize, v: u16) {
        self.push(
            |s| {
                s.push(letter);
                match addr {
                    Some(a) => push_uint(s, a as u64),
                    None => {
                        s.push('+');
                        push_uint(s, index as u64);
                    }
                }
            },
            Unit::None,
            |t| {
                push_uint(t, v as u64);
                Some(v as f64)
            },
        );
    }

    fn unit(u: Unit, map: &RegisterMap) -> &str {
        match u {
            Unit::None => "",
            Unit::Reg(i) => map.get(i as usize).map_or("", |r| r.unit.as_str()),
        }
    }

    /// The first number's unit, or "".
    pub fn first_unit<'m>(&self, map: &'m RegisterMap) -> &'m str {
        self.slots.first().map_or("", |s| Self::unit(s.unit, map))
    }

    /// Appends `name=text[ unit]` of every number, separated by spaces.
    pub fn render(&self, map: &RegisterMap, out: &mut String) {
        for (i, s) in self.slots.iter().enumerate() {
            if i > 0 || !out.is_empty() {
                out.push(' ');
            }
            out.push_str(&self.names[s.name.0 as usize..s.name.1 as usize]);
            out.push('=');
            out.push_str(&self.texts[s.text.0 as usize..s.text.1 as usize]);
            let u = Self::unit(s.unit, map);
            if !u.is_empty() {
                out.push(' ');
                out.push_str(u);
            }
        }
    }

    /// Calls `f` with the numbers as [`Part`]s.
    pub fn with_parts<R>(&mut self, map: &RegisterMap, f: impl FnOnce(&[Part<'_>]) -> R) -> R {
        let Nums {
            names,
            texts,
            slots,
            cache,
        } = self;
        let mut parts: Vec<Part<'_>> = std::mem::take(cache);
        parts.clear();
        parts.extend(slots.iter().map(|s| Part {
            name: &names[s.name.0 as usize..s.name.1 as usize],
            unit: Self::unit(s.unit, map),
            text: &texts[s.text.0 as usize..s.text.1 as usize],
            value: s.value,
        }));
        let r = f(&parts);
        parts.clear();
        // The same allocation back, as parts that borrow nothing (in-place collect).
        *cache = parts.into_iter().map(|_| Part::EMPTY).collect();
        r
    }
}

/// Scratch buffers for the content of one row.
#[derive(Default)]
pub struct Content {
    pub data: String,
    pub note: String,
    pub nums: Nums,
    words: Vec<u16>,
}

impl Content {
    pub fn clear(&mut self) {
        self.data.clear();
        self.note.clear();
        self.nums.clear();
    }

    pub fn note(&mut self, text: &str) {
        crate::row::note_part(&mut self.note).push_str(text);
    }

    pub fn note_with(&mut self, f: impl FnOnce(&mut String)) {
        f(crate::row::note_part(&mut self.note));
    }
}

pub(super) fn word(b: &[u8], i: usize) -> u16 {
    match (b.get(i), b.get(i + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]),
        _ => 0,
    }
}

/// What a response needs of a request: the request `pdu` (address, function, data; no CRC).
pub fn request_info(pdu: &[u8]) -> Req {
    let (slave, function) = (pdu[0], pdu[1]);
    let (start, count) = match function {
        1..=4 | 15 | 16 | 23 => (word(pdu, 2), word(pdu, 4)),
        5 | 6 | 22 => (word(pdu, 2), 1),
        8 | 24 => (word(pdu, 2), 0),
        43 => (pdu.get(4).copied().unwrap_or(0) as u16, 0),
        _ => (0, 0),
    };
    Req {
        slave,
        function,
        start,
        count,
    }
}

/// Registers `words` from `start` (none: unpaired) as numbers: named by the map where it names
/// them (a value of two registers only when both are here), `R<addr>` otherwise.
fn registers(c: &mut Content, map: &RegisterMap, slave: u8, table: Table, start: Option<u16>) {
    let words = std::mem::take(&mut c.words);
    let n = words.len();
    let mut i = 0;
    while i < n {
        let addr = start.map(|s| s as u32 + i as u32);
        if let Some(a) = addr.and_then(|a| u16::try_from(a).ok())
            && let Some((ix, r)) = map.lookup(slave, table, a)
            && i + r.ty.words() <= n
        {
            let w = &words[i..i + r.ty.words()];
            c.nums.push(
                |s| s.push_str(&r.name),
                Unit::Reg(ix as u32),
                |t| match r.read(w, t) {
                    Reading::Number(v) => Some(v),
                    Reading::NotFinite => None,
                },
            );
            i += r.ty.words();
            continue;
        }
        c.nums.plain('R', addr, i, words[i]);
        i += 1;
    }
    c.words = words;
}

/// Coils or discrete inputs: `count` bits of `bytes`, the first in bit 0 of the first byte.
fn coils(c: &mut Content, bytes: &[u8], start: Option<u16>, count: usize) {
    for i in 0..count.min(bytes.len() * 8) {
        let v = (bytes[i / 8] >> (i % 8)) & 1;
        c.nums
            .plain('C', start.map(|s| s as u32 + i as u32), i, v as u16);
    }
}

fn load_words(c: &mut Content, bytes: &[u8]) {
    c.words.clear();
    c.words.extend(
        bytes
            .chunks_exact(2)
            .map(|p| u16::from_be_bytes([p[0], p[1]])),
    );
}

/// The table a function's registers are in.
fn table_of(function: u8) -> Table {
    if function == 4 {
        Table::Input
    } else {
        Table::Holding
    }
}

/// Describes a checked frame's content `pdu` (address, function, data; no CRC) of `kind`;
/// `req`: the request a response was paired with.
pub fn describe(pdu: &[u8], kind: Kind, req: Option<&Req>, map: &RegisterMap, c: &mut Content) {
    let (slave, fc) = (pdu[0], pdu[1]);
    let d = &pdu[2..];
    match kind {
        Kind::Exception => {
            let code = d.first().copied().unwrap_or(0);
            c.nums.uint("code", code as u64);
            match function::exception_name(code) {
                "" => c.data.push_str("unknown exception"),
                n => c.data.push_str(n),
            }
            c.data.push_str(" (");
            push_uint(&mut c.data, code as u64);
            c.data.push(')');
        }
        Kind::Request => request(slave, fc, d, map, c),
        Kind::Unknown => push_hex(&mut c.data, d),
        Kind::Response => response(slave, fc, d, req.filter(|r| r.function == fc), map, c),
    }
}

fn start_count(c: &mut Content, d: &[u8]) -> (u16, u16) {
    let (start, count) = (word(d, 0), word(d, 2));
    c.nums.uint("start", start as u64);
    c.nums.uint("count", count as u64);
    (start, count)
}

pub(super) fn count_note(c: &mut Content, count: u16, max: u16) {
    if count == 0 || count > max {
        c.note_with(|n| {
            n.push_str("count ");
            push_uint(n, count as u64);
            n.push_str(" outside 1-");
            push_uint(n, max as u64);
        });
    }
}

fn request(slave: u8, fc: u8, d: &[u8], map: &RegisterMap, c: &mut Content) {
    match fc {
        1..=4 => {
            let (_, count) = start_count(c, d);
            count_note(c, count, if fc <= 2 { 2000 } else { 125 });
        }
        5 => {
            let (addr, v) = (word(d, 0), word(d, 2));
            c.nums.uint("start", addr as u64);
            c.nums.uint("count", 1);
            coil_value(c, addr, v);
        }
        6 => {
            let addr = word(d, 0);
            c.nums.uint("start", addr as u64);
            c.nums.uint("count", 1);
            load_words(c, d.get(2..4).unwrap_or_default());
            registers(c, map, slave, Table::Holding, Some(addr));
        }
        8 => diagnostics(c, d),
        15 => {
            let (start, count) = start_count(c, d);
            count_note(c, count, 1968);
            let bytes = d.get(5..).unwrap_or_default();
            byte_count_note(c, d.get(4), (count as usize).div_ceil(8));
            coils(c, bytes, Some(start), count as usize);
        }
        16 => {
            let (start, count) = start_count(c, d);
            count_note(c, count, 123);
            byte_count_note(c, d.get(4), 2 * count as usize);
            load_words(c, d.get(5..).unwrap_or_default());
            registers(c, map, slave, Table::Holding, Some(start));
        }
        20 => file_records(c, d.get(1..).unwrap_or_default(), false),
        21 => file_records(c, d.get(1..).unwrap_or_default(), true),
        22 => mask_write(c, d),
        23 => {
            let (_, count) = start_count(c, d);
            count_note(c, count, 125);
            let (ws, wc) = (word(d, 4), word(d, 6));
            c.nums.uint("write_start", ws as u64);
            c.nums.uint("write_count", wc as u64);
            count_note(c, wc, 121);
            byte_count_note(c, d.get(8), 2 * wc as usize);
            load_words(c, d.get(9..).unwrap_or_default());
            registers(c, map, slave, Table::Holding, Some(ws));
        }
        24 => c.nums.uint("start", word(d, 0) as u64),
        43 => {
            let (code, object) = (d.get(1).copied(), d.get(2).copied());
            c.nums.uint("read_code", code.unwrap_or(0) as u64);
            c.nums.uint("object", object.unwrap_or(0) as u64);
            c.data.push_str(match code {
                Some(1) => "basic",
                Some(2) => "regular",
                Some(3) => "extended",
                Some(4) => "one object",
                _ => "unknown read code",
            });
        }
        // 7, 11, 12, 17: no data
        _ => {}
    }
    c.nums.render(map, &mut c.data);
}

fn coil_value(c: &mut Content, addr: u16, v: u16) {
    match v {
        0xFF00 | 0x0000 => c.nums.plain('C', Some(addr as u32), 0, u16::from(v != 0)),
        _ => coil_note(c, v),
    }
}

/// The note of a coil written with a value other than 0xFF00 and 0x0000.
pub(super) fn coil_note(c: &mut Content, v: u16) {
    c.note_with(|n| {
        n.push_str("coil value ");
        push_0x16(n, v);
        n.push_str(" is neither 0xFF00 (on) nor 0x0000 (off)");
    });
}

pub(super) fn byte_count_note(c: &mut Content, got: Option<&u8>, want: usize) {
    if let Some(&g) = got
        && g as usize != want
    {
        c.note_with(|n| {
            n.push_str("byte count ");
            push_uint(n, g as u64);
            n.push_str(", the count needs ");
            push_uint(n, want as u64);
        });
    }
}

fn diagnostics(c: &mut Content, d: &[u8]) {
    let sub = word(d, 0);
    c.data.push_str(match function::diagnostic_name(sub) {
        "" => "sub-function",
        n => n,
    });
    c.nums.uint("sub", sub as u64);
    c.nums.uint("data", word(d, 2) as u64);
}

fn mask_write(c: &mut Content, d: &[u8]) {
    c.nums.uint("start", word(d, 0) as u64);
    c.nums.uint("and", word(d, 2) as u64);
    c.nums.uint("or", word(d, 4) as u64);
}

/// Read/Write File Record sub-requests (7 bytes each, and the record data when `data`), or
/// Read File Record sub-responses (`len`, reference type 6, data).
fn file_records(c: &mut Content, mut d: &[u8], data: bool) {
    let mut first = true;
    while d.len() >= 7 {
        let (file, record, len) = (word(d, 1), word(d, 3), word(d, 5) as usize);
        if !first {
            c.data.push_str("; ");
        }
        first = false;
        c.data.push_str("file ");
        push_uint(&mut c.data, file as u64);
        c.data.push_str(" record ");
        push_uint(&mut c.data, record as u64);
        c.data.push_str(" length ");
        push_uint(&mut c.data, len as u64);
        if d[0] != 6 {
            c.note("reference type is not 6");
        }
        d = &d[7..];
        if data {
            let n = (2 * len).min(d.len());
            c.data.push_str(": ");
            push_hex(&mut c.data, &d[..n]);
            d = &d[n..];
        }
    }
}

fn response(slave: u8, fc: u8, d: &[u8], req: Option<&Req>, map: &RegisterMap, c: &mut Content) {
    match fc {
        1 | 2 => {
            let bytes = d.get(1..).unwrap_or_default();
            let count = match req {
                Some(r) => {
                    byte_count_note(c, d.first(), (r.count as usize).div_ceil(8));
                    r.count as usize
                }
                None => bytes.len() * 8,
            };
            coils(c, bytes, req.map(|r| r.start), count);
        }
        3 | 4 | 23 => {
            let bytes = d.get(1..).unwrap_or_default();
            if let Some(r) = req
                && bytes.len() != 2 * r.count as usize
            {
                byte_count_note(c, d.first(), 2 * r.count as usize);
            }
            load_words(c, bytes);
            registers(c, map, slave, table_of(fc), req.map(|r| r.start));
        }
        5 => coil_value(c, word(d, 0), word(d, 2)),
        6 => {
            load_words(c, d.get(2..4).unwrap_or_default());
            registers(c, map, slave, Table::Holding, Some(word(d, 0)));
        }
        7 => {
            let s = d.first().copied().unwrap_or(0);
            c.nums.uint("status", s as u64);
        }
        8 => diagnostics(c, d),
        11 => {
            c.nums.uint("status", word(d, 0) as u64);
            c.nums.uint("events", word(d, 2) as u64);
        }
        12 => {
            c.nums.uint("status", word(d, 1) as u64);
            c.nums.uint("events", word(d, 3) as u64);
            c.nums.uint("messages", word(d, 5) as u64);
            if let Some(ev) = d.get(7..)
                && !ev.is_empty()
            {
                c.data.push_str("log ");
                push_hex(&mut c.data, ev);
            }
        }
        15 | 16 => {
            start_count(c, d);
        }
        17 => {
            c.data.push_str("server ID ");
            push_hex(&mut c.data, d.get(1..).unwrap_or_default());
        }
        20 => {
            let mut r = d.get(1..).unwrap_or_default();
            let mut first = true;
            while let [len, _ty, rest @ ..] = r {
                let n = (*len as usize).saturating_sub(1).min(rest.len());
                if !first {
                    c.data.push_str("; ");
                }
                first = false;
                c.data.push_str("record: ");
                push_hex(&mut c.data, &rest[..n]);
                r = &rest[n..];
            }
        }
        21 => file_records(c, d.get(1..).unwrap_or_default(), true),
        22 => mask_write(c, d),
        24 => {
            let n = word(d, 2);
            c.nums.uint("count", n as u64);
            for (i, v) in d.get(4..).unwrap_or_default().chunks_exact(2).enumerate() {
                let v = u16::from_be_bytes([v[0], v[1]]);
                c.nums.push(
                    |s| {
                        s.push_str("fifo");
                        push_uint(s, i as u64);
                    },
                    Unit::None,
                    |t| {
                        push_uint(t, v as u64);
                        Some(v as f64)
                    },
                );
            }
        }
        43 => device_id(c, d),
        _ => {}
    }
    c.nums.render(map, &mut c.data);
}

/// Read Device Identification objects as `Name="text"` in the Data cell.
fn device_id(c: &mut Content, d: &[u8]) {
    // d: MEI type, read code, conformity, more follows, next object, number, objects
    if d.first() != Some(&MEI_DEVICE_ID) {
        return;
    }
    let mut r = d.get(6..).unwrap_or_default();
    if d.get(3) == Some(&0xFF) {
        c.note("more objects follow");
    }
    while let [id, len, rest @ ..] = r {
        let n = (*len as usize).min(rest.len());
        if !c.data.is_empty() {
            c.data.push(' ');
        }
        match object_name(*id) {
            "" => {
                c.data.push_str("object");
                push_hex_u8(&mut c.data, *id);
            }
            name => c.data.push_str(name),
        }
        c.data.push_str("=\"");
        for &b in &rest[..n] {
            match b {
                b'"' | b'\\' => {
                    c.data.push('\\');
                    c.data.push(b as char);
                }
                0x20..=0x7E => c.data.push(b as char),
                _ => {
                    c.data.push_str("\\x");
                    push_hex_u8(&mut c.data, b);
                }
            }
        }
        c.data.push('"');
        r = &rest[n..];
    }
}

/// The standard objects of Read Device Identification.
fn object_name(id: u8) -> &'static str {
    match id {
        0 => "VendorName",
        1 => "ProductCode",
        2 => "MajorMinorRevision",
        3 => "VendorUrl",
        4 => "ProductName",
        5 => "ModelName",
        6 => "UserApplicationName",
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_reuse_their_allocation() {
        let map = RegisterMap::default();
        let mut n = Nums::default();
        for i in 0..40 {
            n.uint("x", i);
        }
        assert_eq!(n.with_parts(&map, |p| p.len()), 40);
        assert!(n.cache.capacity() >= 40, "the parts' buffer is kept");
        let cap = n.cache.capacity();
        n.clear();
        n.uint("start", 7);
        let text = n.with_parts(&map, |p| format!("{}={}", p[0].name, p[0].text));
        assert_eq!(text, "start=7");
        assert_eq!(n.cache.capacity(), cap);
    }
}
