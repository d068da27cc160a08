//! The register map of a plant: slave names, and registers by slave and wire address with a
//! name, a type, a word order, a scale and a unit, so that responses read as values with units
//! (`Flow temperature=61.5 °C`) instead of `R100=615` (docs/modbus.md, "The register map").
//!
//! The map is plain data. [`RegisterMap::from_toml`] reads it from the `[modbus]` table of the
//! project file (its `slaves` and `registers` tables):
//!
//! ```toml
//! [modbus.slaves]
//! Boiler = 1
//!
//! [modbus.registers]
//! "1/100" = { name = "Flow temperature", type = "i16", scale = 0.1, unit = "°C" }
//! "Boiler/102" = { name = "Power", type = "f32", order = "CDAB", unit = "kW", table = "input" }
//! "*/0" = "Status"          # a name alone: u16, every slave
//! ```

use std::collections::BTreeMap;

use crate::fmt::{push_fixed, push_i64};

/// How the registers of one value are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RegType {
    U16,
    I16,
    U32,
    I32,
    F32,
}

impl RegType {
    pub const ALL: [(&'static str, RegType); 5] = [
        ("u16", RegType::U16),
        ("i16", RegType::I16),
        ("u32", RegType::U32),
        ("i32", RegType::I32),
        ("f32", RegType::F32),
    ];

    /// Registers (16-bit words) of one value.
    pub fn words(self) -> usize {
        match self {
            RegType::U16 | RegType::I16 => 1,
            _ => 2,
        }
    }
}

/// The order of a value's bytes on the wire, in the usual letters: `A` is the value's most
/// significant byte. Modbus sends each register high byte first and most devices send the high
/// register first (`ABCD`); many send the low register first (`CDAB`, "word swap"); a few swap
/// the bytes in each register (`BADC`) or both (`DCBA`). A 16-bit value reads `AB` or, with a
/// byte swap (`BADC`, `DCBA`), `BA`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WordOrder {
    Abcd,
    Cdab,
    Badc,
    Dcba,
}

impl WordOrder {
    pub const ALL: [(&'static str, WordOrder); 4] = [
        ("ABCD", WordOrder::Abcd),
        ("CDAB", WordOrder::Cdab),
        ("BADC", WordOrder::Badc),
        ("DCBA", WordOrder::Dcba),
    ];

    /// The value's bytes, most significant first, from its registers as received (`w[0]`
    /// first on the wire; one or two words).
    pub fn bytes(self, w: &[u16]) -> [u8; 4] {
        let swap = matches!(self, WordOrder::Badc | WordOrder::Dcba);
        let b = |x: u16| {
            let [h, l] = x.to_be_bytes();
            if swap { [l, h] } else { [h, l] }
        };
        match *w {
            [x] => {
                let [h, l] = b(x);
                [0, 0, h, l]
            }
            [x, y, ..] => {
                let (hi, lo) = match self {
                    WordOrder::Abcd | WordOrder::Badc => (x, y),
                    WordOrder::Cdab | WordOrder::Dcba => (y, x),
                };
                let ([a, bb], [c, d]) = (b(hi), b(lo));
                [a, bb, c, d]
            }
            [] => [0; 4],
        }
    }
}

/// Which registers an entry names: holding registers (functions 3, 6, 16, 23), input
/// registers (function 4), or both (the default; most devices map one space).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Table {
    Any,
    Holding,
    Input,
}

/// A decimal scale, exact: `mantissa / 10^decimals` (`0.1` = 1 / 10^1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Scale {
    pub mantissa: i64,
    /// 0..=9.
    pub decimals: u8,
}

impl Scale {
    pub const ONE: Scale = Scale {
        mantissa: 1,
        decimals: 0,
    };

    pub fn as_f64(self) -> f64 {
        self.mantissa as f64 / 10f64.powi(self.decimals as i32)
    }

    /// A scale from its decimal text (`0.1`, `-2.5`, `1e-3`): at most 9 decimals and a
    /// mantissa below 10^9.
    pub fn parse(text: &str) -> Option<Scale> {
        let x: f64 = text.parse().ok()?;
        Self::of(x)
    }

    /// The exact decimal of `x` (its shortest text): `0.1` is 1/10, not 0.1000000000000000055.
    pub fn of(x: f64) -> Option<Scale> {
        if !x.is_finite() || x == 0.0 {
            return None;
        }
        let text = format!("{x}");
        let (neg, digits) = match text.strip_prefix('-') {
            Some(d) => (true, d),
            None => (false, text.as_str()),
        };
        let (whole, frac) = digits.split_once('.').unwrap_or((digits, ""));
        let frac = frac.trim_end_matches('0');
        if frac.len() > 9 {
            return None;
        }
        let all = format!("{whole}{frac}");
        let m: i64 = all.parse().ok()?;
        if m >= 1_000_000_000 {
            return None;
        }
        Some(Scale {
            mantissa: if neg { -m } else { m },
            decimals: frac.len() as u8,
        })
    }
}

/// One named register (or register pair).
#[derive(Clone, Debug, PartialEq)]
pub struct Register {
    /// `None`: every slave (`*`).
    pub slave: Option<u8>,
    pub table: Table,
    /// 0-based wire address of its first register.
    pub address: u16,
    pub name: String,
    pub ty: RegType,
    pub order: WordOrder,
    pub scale: Scale,
    pub unit: String,
}

/// What [`Register::read`] made of a value's words.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reading {
    /// A number: its text was appended.
    Number(f64),
    /// An f32 that is NaN or infinite (its text was appended, no number).
    NotFinite,
}

impl Register {
    /// Reads the value from its words (`ty.words()` of them), appending its text (plain
    /// decimal: integers exactly, scaled without rounding; an f32 in its shortest text).
    pub fn read(&self, words: &[u16], text: &mut String) -> Reading {
        let b = self.order.bytes(words);
        let int = match self.ty {
            RegType::U16 => u16::from_be_bytes([b[2], b[3]]) as i64,
            RegType::I16 => i16::from_be_bytes([b[2], b[3]]) as i64,
            RegType::U32 => u32::from_be_bytes(b) as i64,
            RegType::I32 => i32::from_be_bytes(b) as i64,
            RegType::F32 => {
                let f = f32::from_be_bytes(b);
                let v = if self.scale == Scale::ONE {
                    f
                } else {
                    (f as f64 * self.scale.as_f64()) as f32
                };
                if !v.is_finite() {
                    text.push_str(if v.is_nan() { "NaN" } else { "inf" });
                    return Reading::NotFinite;
                }
                let v = if v == 0.0 { 0.0 } else { v };
                use std::fmt::Write as _;
                let _ = write!(text, "{v}");
                return Reading::Number(v as f64);
            }
        };
        if self.scale == Scale::ONE {
            push_i64(text, int);
            return Reading::Number(int as f64);
        }
        // |int| < 2^32 and |mantissa| < 10^9: the product fits an i64.
        let raw = int * self.scale.mantissa;
        push_fixed(text, raw, self.scale.decimals);
        Reading::Number(raw as f64 / 10f64.powi(self.scale.decimals as i32))
    }
}

/// Slave names and named registers. Empty by default (registers read `R<addr>`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RegisterMap {
    /// (name, address).
    pub slaves: Vec<(String, u8)>,
    registers: Vec<Register>,
    /// (slave, or 255 for every slave; address) → indexes into `registers`.
    index: BTreeMap<(u8, u16), Vec<usize>>,
}

/// The slave key of registers that apply to every slave.
const EVERY: u8 = 255;

/// A mistake in the map: the table (`slaves` or `registers`), the entry, what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapError {
    pub table: &'static str,
    pub entry: Option<String>,
    pub what: String,
}

impl MapError {
    fn new(table: &'static str, entry: Option<&str>, what: impl Into<String>) -> Self {
        MapError {
            table,
            entry: entry.map(str::to_owned),
            what: what.into(),
        }
    }
}

impl std::fmt::Display for MapError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[modbus.{}] ", self.table)?;
        if let Some(e) = &self.entry {
            write!(f, "{e:?}: ")?;
        }
        f.write_str(&self.what)
    }
}

impl RegisterMap {
    /// A map of these slaves and registers; names must be unique per slave (they become the
    /// keys of a row's numbers) and an address may be named once per slave and table.
    pub fn new(slaves: Vec<(String, u8)>, registers: Vec<Register>) -> Result<Self, MapError> {
        let mut map = RegisterMap {
            slaves,
            registers: Vec::new(),
            index: BTreeMap::new(),
        };
        for r in registers {
            let key = format!(
                "{}/{}",
                r.slave.map_or("*".to_owned(), |s| s.to_string()),
                r.address
            );
            map.add(r)
                .map_err(|e| MapError::new("registers", Some(&key), e))?;
        }
        Ok(map)
    }

    fn add(&mut self, r: Register) -> Result<(), String> {
        let key = (r.slave.unwrap_or(EVERY), r.address);
        let who = match r.slave {
            Some(s) => format!("slave {s}"),
            None => "every slave".to_owned(),
        };
        if r.name.is_empty() {
            return Err(format!(
                "register {} of {who}: the name is empty",
                r.address
            ));
        }
        if let Some(same) = self
            .registers
            .iter()
            .find(|o| o.slave == r.slave && o.name == r.name)
        {
            return Err(format!(
                "the name {:?} is given to registers {} and {} of {who}",
                r.name, same.address, r.address
            ));
        }
        let clash = |a: Table, b: Table| a == Table::Any || b == Table::Any || a == b;
        if let Some(ix) = self.index.get(&key)
            && ix.iter().any(|&i| clash(self.registers[i].table, r.table))
        {
            return Err(format!("register {} of {who} is named twice", r.address));
        }
        self.index
            .entry(key)
            .or_default()
            .push(self.registers.len());
        self.registers.push(r);
        Ok(())
    }

    pub fn is_empty(&self) -> bool {
        self.registers.is_empty() && self.slaves.is_empty()
    }

    /// Every register, in the order given.
    pub fn registers(&self) -> &[Register] {
        &self.registers
    }

    /// The register named at `address` of `slave` in `table` (an entry for the slave before
    /// one for every slave), with its index.
    pub fn lookup(&self, slave: u8, table: Table, address: u16) -> Option<(usize, &Register)> {
        if self.registers.is_empty() {
            return None;
        }
        for s in [slave, EVERY] {
            if let Some(ix) = self.index.get(&(s, address)) {
                for &i in ix {
                    let r = &self.registers[i];
                    if r.table == Table::Any || table == Table::Any || r.table == table {
                        return Some((i, r));
                    }
                }
            }
        }
        None
    }

    /// The register with index `i` (from [`Self::lookup`]).
    pub fn get(&self, i: usize) -> Option<&Register> {
        self.registers.get(i)
    }

    /// The name of a slave, if one was given.
    pub fn slave_name(&self, slave: u8) -> Option<&str> {
        self.slaves
            .iter()
            .rev()
            .find(|(_, a)| *a == slave)
            .map(|(n, _)| n.as_str())
    }

    /// Reads the map from the `[modbus]` table of a project file: its `slaves` (name =
    /// address) and `registers` ("SLAVE/ADDRESS" = a table or a name). Other keys of the
    /// table are not the map's and are left alone.
    pub fn from_toml(section: &toml::Table) -> Result<Self, MapError> {
        let mut slaves = Vec::new();
        if let Some(s) = section.get("slaves") {
            let s = s.as_table().ok_or(MapError::new(
                "slaves",
                None,
                "expected a table of NAME = ADDRESS",
            ))?;
            for (name, v) in s {
                let addr =
                    v.as_integer()
                        .filter(|a| (1..=247).contains(a))
                        .ok_or(MapError::new(
                            "slaves",
                            Some(name),
                            "the address must be a number from 1 to 247",
                        ))?;
                slaves.push((name.clone(), addr as u8));
            }
        }
        let mut registers = Vec::new();
        if let Some(r) = section.get("registers") {
            let r = r.as_table().ok_or(MapError::new(
                "registers",
                None,
                "expected a table of \"SLAVE/ADDRESS\" = { name = … }",
            ))?;
            for (key, v) in r {
                let at = |e: String| MapError::new("registers", Some(key), e);
                let (slave, address) = parse_key(key, &slaves).map_err(at)?;
                registers.push(parse_entry(slave, address, v).map_err(at)?);
            }
        }
        RegisterMap::new(slaves, registers)
    }

    /// Reads the map from the text of a project file (its `[modbus]` table; none: empty).
    pub fn parse(text: &str) -> Result<Self, String> {
        let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| e.to_string())?;
        match doc.get("modbus") {
            Some(toml::Value::Table(m)) => Self::from_toml(m).map_err(|e| e.to_string()),
            Some(_) => Err("[modbus] must be a table".into()),
            None => Ok(RegisterMap::default()),
        }
    }
}

/// A number in decimal or `0x` hex.
fn number(s: &str) -> Option<u32> {
    let s = s.trim();
    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16).ok(),
        None => s.parse().ok(),
    }
}

/// `SLAVE/ADDRESS`: the slave by address (1-247, or 0 for broadcasts), by a name of
/// `[modbus.slaves]`, or `*` for every slave; the 0-based wire address (0-65535).
fn parse_key(key: &str, slaves: &[(String, u8)]) -> Result<(Option<u8>, u16), String> {
    let (s, a) = key
        .rsplit_once('/')
        .ok_or("expected \"SLAVE/ADDRESS\" (\"1/100\", \"Boiler/100\", \"*/100\")".to_owned())?;
    let address = number(a)
        .and_then(|a| u16::try_from(a).ok())
        .ok_or(format!("the address {a:?} is not a number from 0 to 65535"))?;
    let slave = match s.trim() {
        "*" => None,
        s => match number(s) {
            Some(n) if n <= 247 => Some(n as u8),
            Some(_) => return Err(format!("slave {s} is not an address from 0 to 247")),
            None => Some(
                slaves
                    .iter()
                    .rev()
                    .find(|(n, _)| n == s)
                    .map(|(_, a)| *a)
                    .ok_or(format!("{s:?} is no slave of [modbus.slaves]"))?,
            ),
        },
    };
    Ok((slave, address))
}

/// An entry: a name alone, or `{ name, type, order, scale, unit, table }`.
fn parse_entry(slave: Option<u8>, address: u16, v: &toml::Value) -> Result<Register, String> {
    let mut r = Register {
        slave,
        table: Table::Any,
        address,
        name: String::new(),
        ty: RegType::U16,
        order: WordOrder::Abcd,
        scale: Scale::ONE,
        unit: String::new(),
    };
    if let Some(name) = v.as_str() {
        r.name = name.to_owned();
        return Ok(r);
    }
    let t = v
        .as_table()
        .ok_or("expected a name or a table { name = …, type = …, … }".to_owned())?;
    let text = |k: &str| -> Result<Option<&str>, String> {
        match t.get(k) {
            None => Ok(None),
            Some(v) => v.as_str().map(Some).ok_or(format!("{k} must be a text")),
        }
    };
    for k in t.keys() {
        if !["name", "type", "order", "scale", "unit", "table"].contains(&k.as_str()) {
            return Err(format!(
                "unknown key {k:?} (expected name, type, order, scale, unit, table)"
            ));
        }
    }
    r.name = text("name")?
        .ok_or("name is missing".to_owned())?
        .to_owned();
    if let Some(ty) = text("type")? {
        r.ty = RegType::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(ty))
            .map(|(_, t)| *t)
            .ok_or(format!(
                "type {ty:?}: expected \"u16\", \"i16\", \"u32\", \"i32\" or \"f32\""
            ))?;
    }
    if let Some(o) = text("order")? {
        r.order = WordOrder::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(o))
            .map(|(_, w)| *w)
            .ok_or(format!(
                "order {o:?}: expected \"ABCD\", \"CDAB\", \"BADC\" or \"DCBA\""
            ))?;
    }
    if let Some(s) = t.get("scale") {
        let x = s
            .as_float()
            .or_else(|| s.as_integer().map(|i| i as f64))
            .ok_or("scale must be a number".to_owned())?;
        r.scale = Scale::of(x).ok_or(format!(
            "scale {x}: a number other than 0 with at most 9 decimals and 9 digits"
        ))?;
    }
    if let Some(u) = text("unit")? {
        r.unit = u.to_owned();
    }
    if let Some(tb) = text("table")? {
        r.table = match tb.to_ascii_lowercase().as_str() {
            "holding" => Table::Holding,
            "input" => Table::Input,
            _ => return Err(format!("table {tb:?}: expected \"holding\" or \"input\"")),
        };
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reg(ty: RegType, order: WordOrder, scale: Scale) -> Register {
        Register {
            slave: Some(1),
            table: Table::Any,
            address: 0,
            name: "x".into(),
            ty,
            order,
            scale,
            unit: String::new(),
        }
    }

    fn read(r: &Register, w: &[u16]) -> (Reading, String) {
        let mut s = String::new();
        (r.read(w, &mut s), s)
    }

    #[test]
    fn types_and_word_orders() {
        use RegType::*;
        use WordOrder::*;
        let one = Scale::ONE;
        assert_eq!(read(&reg(U16, Abcd, one), &[0xFFFF]).1, "65535");
        assert_eq!(read(&reg(I16, Abcd, one), &[0xFFFF]).1, "-1");
        assert_eq!(read(&reg(I16, Badc, one), &[0x9CFF]).1, "-100");
        assert_eq!(read(&reg(U32, Abcd, one), &[0x0001, 0x0002]).1, "65538");
        assert_eq!(read(&reg(U32, Cdab, one), &[0x0002, 0x0001]).1, "65538");
        assert_eq!(read(&reg(U32, Badc, one), &[0x0100, 0x0200]).1, "65538");
        assert_eq!(read(&reg(U32, Dcba, one), &[0x0200, 0x0100]).1, "65538");
        assert_eq!(read(&reg(I32, Abcd, one), &[0xFFFF, 0xFFFE]).1, "-2");
        // 123.456 as f32 = 0x42F6E979
        let f = reg(F32, Abcd, one);
        assert_eq!(read(&f, &[0x42F6, 0xE979]).1, "123.456");
        assert_eq!(read(&reg(F32, Cdab, one), &[0xE979, 0x42F6]).1, "123.456");
        assert_eq!(read(&reg(F32, Badc, one), &[0xF642, 0x79E9]).1, "123.456");
        assert_eq!(read(&reg(F32, Dcba, one), &[0x79E9, 0xF642]).1, "123.456");
        assert_eq!(read(&f, &[0x7FC0, 0]).0, Reading::NotFinite);
        // the sigrok wizmodbus capture: 0x46AD2038 … read as f32 ABCD
        assert_eq!(read(&f, &[0x46AD, 0x2038]).1, "22160.11");
    }

    #[test]
    fn scales_are_exact() {
        let s = Scale::of(0.1).unwrap();
        assert_eq!(
            s,
            Scale {
                mantissa: 1,
                decimals: 1
            }
        );
        assert_eq!(
            read(&reg(RegType::I16, WordOrder::Abcd, s), &[615]).1,
            "61.5"
        );
        assert_eq!(
            read(&reg(RegType::I16, WordOrder::Abcd, s), &[0xFFF6]).1,
            "-1.0"
        );
        let s = Scale::of(-0.25).unwrap();
        assert_eq!(
            read(&reg(RegType::U16, WordOrder::Abcd, s), &[3]).1,
            "-0.75"
        );
        assert_eq!(
            Scale::of(1e-3),
            Some(Scale {
                mantissa: 1,
                decimals: 3
            })
        );
        assert_eq!(
            Scale::of(100.0),
            Some(Scale {
                mantissa: 100,
                decimals: 0
            })
        );
        assert_eq!(Scale::of(0.0), None);
        assert_eq!(Scale::of(1e-12), None);
        assert_eq!(
            Scale::parse("2.5"),
            Some(Scale {
                mantissa: 25,
                decimals: 1
            })
        );
    }

    const MAP: &str = r#"
[modbus]
baud = 9600

[modbus.slaves]
Boiler = 1
Pump = 0x02

[modbus.registers]
"1/100" = { name = "Flow temperature", type = "i16", scale = 0.1, unit = "°C" }
"Boiler/102" = { name = "Power", type = "f32", order = "cdab", unit = "kW", table = "input" }
"*/0" = "Status"
"2/0x10" = { name = "Speed", type = "u32", scale = 1, unit = "rpm" }
"#;

    #[test]
    fn map_from_the_project_file() {
        let m = RegisterMap::parse(MAP).unwrap();
        assert_eq!(m.slave_name(1), Some("Boiler"));
        assert_eq!(m.slave_name(2), Some("Pump"));
        assert_eq!(m.slave_name(3), None);
        let (_, r) = m.lookup(1, Table::Holding, 100).unwrap();
        assert_eq!(
            (r.name.as_str(), r.ty, r.unit.as_str()),
            ("Flow temperature", RegType::I16, "°C")
        );
        assert!(m.lookup(1, Table::Holding, 102).is_none());
        let (_, p) = m.lookup(1, Table::Input, 102).unwrap();
        assert_eq!((p.ty, p.order), (RegType::F32, WordOrder::Cdab));
        assert_eq!(m.lookup(7, Table::Input, 0).unwrap().1.name, "Status");
        assert_eq!(m.lookup(2, Table::Holding, 16).unwrap().1.name, "Speed");
        assert!(m.lookup(1, Table::Holding, 16).is_none());
        assert!(RegisterMap::parse("[sport]\nbaud = 1").unwrap().is_empty());
    }

    #[test]
    fn map_mistakes_are_named() {
        let err = |text: &str| RegisterMap::parse(text).unwrap_err();
        let e = err("[modbus.registers]\n\"1-100\" = \"x\"");
        assert!(
            e.contains("\"1-100\"") && e.contains("SLAVE/ADDRESS"),
            "{e}"
        );
        let e = err("[modbus.registers]\n\"Tank/1\" = \"x\"");
        assert!(e.contains("no slave"), "{e}");
        let e = err("[modbus.registers]\n\"1/1\" = { name = \"x\", type = \"u8\" }");
        assert!(e.contains("type \"u8\""), "{e}");
        let e = err("[modbus.registers]\n\"1/1\" = { name = \"x\", order = \"ACBD\" }");
        assert!(e.contains("order"), "{e}");
        let e = err("[modbus.registers]\n\"1/1\" = { name = \"x\", scale = 0 }");
        assert!(e.contains("scale"), "{e}");
        let e = err("[modbus.registers]\n\"1/1\" = { name = \"x\", units = \"V\" }");
        assert!(e.contains("unknown key \"units\""), "{e}");
        let e = err("[modbus.registers]\n\"1/1\" = { type = \"u16\" }");
        assert!(e.contains("name is missing"), "{e}");
        let e = err("[modbus.registers]\n\"1/70000\" = \"x\"");
        assert!(e.contains("65535"), "{e}");
        let e = err("[modbus.registers]\n\"1/1\" = \"x\"\n\"1/2\" = \"x\"");
        assert!(e.contains("given to registers"), "{e}");
        let e = err("[modbus.registers]\n\"1/1\" = \"x\"\n\"1/0x1\" = \"y\"");
        assert!(e.contains("named twice"), "{e}");
        let e = err("[modbus.slaves]\nBoiler = 300");
        assert!(e.contains("1 to 247"), "{e}");
        // holding and input registers of one address may have names of their own
        let ok = "[modbus.registers]\n\"1/1\" = { name = \"a\", table = \"input\" }\n\
                  \"1/0x1\" = { name = \"b\", table = \"holding\" }";
        assert!(RegisterMap::parse(ok).is_ok());
    }
}
