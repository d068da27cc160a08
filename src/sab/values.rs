//! The numbers of SAB payloads: the Value column, the JSON `parts`, the wide table's columns and
//! the plot's series (`docs/sab.md`, "Values").
//!
//! SAB carries raw struct bytes without type information, so a payload is read by a rule:
//!
//! * **Default**: a payload of 1, 2 or 4 bytes is an unsigned little-endian integer (what the
//!   Data column already reads, `23 01 (291)`).
//! * **Declared** (`--value CMD=TYPE[*SCALE][:UNIT]`, `[sab2.values]`): the payload is one value
//!   of that type, little endian (modm's byte order on AVR and ARM), times the scale, with a unit.
//!
//! Only valid `Request` and `ACK` frames carry a number (a NACK's payload is an error code; a
//! frame with reserved flags or a failed check carries none). The number is named after the
//! command (its `--command` name, else its code `0x10`); a request's payload (a write's new value,
//! or a query's argument) is a different quantity from the answer's and is named `CMD.req`.
//!
//! The declarations are plain data: the command line parses them (`src/cli/`).

use crate::fmt::{push_fixed, push_i64, push_u64};

/// A payload type: one little-endian value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
}

impl ValueType {
    /// Every type with its name, as the options write it.
    pub const ALL: [(&'static str, ValueType); 7] = [
        ("u8", ValueType::U8),
        ("i8", ValueType::I8),
        ("u16", ValueType::U16),
        ("i16", ValueType::I16),
        ("u32", ValueType::U32),
        ("i32", ValueType::I32),
        ("f32", ValueType::F32),
    ];

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, t)| *t == self)
            .map_or("", |(n, _)| n)
    }

    /// Payload bytes of one value.
    pub fn size(self) -> usize {
        match self {
            ValueType::U8 | ValueType::I8 => 1,
            ValueType::U16 | ValueType::I16 => 2,
            ValueType::U32 | ValueType::I32 | ValueType::F32 => 4,
        }
    }
}

/// A decimal scale factor, exact: `mantissa / 10^decimals` (`0.01` = 1 / 10^2).
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
}

/// Which frames of a command a declaration applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Requests and ACKs (`--value speed=…`).
    Both,
    /// Requests only (`--value speed.req=…`).
    Request,
    /// ACKs only (`--value speed.ack=…`).
    Ack,
}

/// One declaration: how the payloads of a command are read.
#[derive(Clone, Debug, PartialEq)]
pub struct Declared {
    pub command: u8,
    pub direction: Direction,
    pub ty: ValueType,
    pub scale: Scale,
    /// `m`, `deg`, or "".
    pub unit: String,
}

/// The rules of a run: the declarations by command and direction.
#[derive(Clone, Debug)]
pub(super) struct Values {
    /// Index: command * 2 + (0 request, 1 ACK).
    declared: Vec<Option<Declared>>,
}

/// What [`Values::read`] made of a payload.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Reading {
    /// A number: its text was appended, here is its value.
    Number(f64),
    /// A declared type whose size the payload does not have: (declared type, payload length).
    WrongSize(ValueType, usize),
    /// A declared f32 that is NaN or infinite: no number.
    NotFinite,
    /// No number (an undeclared payload of another length than 1, 2 or 4).
    None,
}

impl Values {
    /// The declarations, later ones and direction-specific ones winning.
    pub(super) fn new(declared: &[Declared]) -> Self {
        let mut table = vec![None; 512];
        // Both first, then the specific ones over them.
        for pass in [true, false] {
            for d in declared {
                if (d.direction == Direction::Both) != pass {
                    continue;
                }
                let i = d.command as usize * 2;
                if d.direction != Direction::Ack {
                    table[i] = Some(d.clone());
                }
                if d.direction != Direction::Request {
                    table[i + 1] = Some(d.clone());
                }
            }
        }
        Values { declared: table }
    }

    /// The declaration for a request (`ack` false) or ACK of `command`.
    pub(super) fn declared(&self, command: u8, ack: bool) -> Option<&Declared> {
        self.declared[command as usize * 2 + usize::from(ack)].as_ref()
    }

    /// Reads `payload` of a request or ACK of `command`, appending the number's text to `text`.
    /// An empty payload (a query, an ACK of a write) carries no number and is never wrong.
    pub(super) fn read(
        &self,
        command: u8,
        ack: bool,
        payload: &[u8],
        text: &mut String,
    ) -> Reading {
        if payload.is_empty() {
            return Reading::None;
        }
        match self.declared(command, ack) {
            Some(d) => read_typed(d.ty, d.scale, payload, text),
            None => read_default(payload, text),
        }
    }
}

/// The default rule: 1, 2 or 4 bytes, an unsigned little-endian integer.
pub(super) fn read_default(payload: &[u8], text: &mut String) -> Reading {
    let v = match *payload {
        [a] => a as u64,
        [a, b] => u16::from_le_bytes([a, b]) as u64,
        [a, b, c, d] => u32::from_le_bytes([a, b, c, d]) as u64,
        _ => return Reading::None,
    };
    push_u64(text, v);
    Reading::Number(v as f64)
}

/// One value of type `ty` times `scale`, in plain decimal with the wire's precision: integers
/// exactly (`291` × 0.01 = `2.91`), an f32 with the shortest text that reads back as the same
/// f32 (scaled in f64 and rounded to f32 again: an f32 has about 7 significant digits).
pub(super) fn read_typed(
    ty: ValueType,
    scale: Scale,
    payload: &[u8],
    text: &mut String,
) -> Reading {
    if payload.len() != ty.size() {
        return Reading::WrongSize(ty, payload.len());
    }
    let b = payload;
    let int = match ty {
        ValueType::U8 => b[0] as i64,
        ValueType::I8 => b[0] as i8 as i64,
        ValueType::U16 => u16::from_le_bytes([b[0], b[1]]) as i64,
        ValueType::I16 => i16::from_le_bytes([b[0], b[1]]) as i64,
        ValueType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64,
        ValueType::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64,
        ValueType::F32 => {
            let f = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            if !f.is_finite() {
                return Reading::NotFinite;
            }
            let v = if scale == Scale::ONE {
                f
            } else {
                (f as f64 * scale.as_f64()) as f32
            };
            if !v.is_finite() {
                return Reading::NotFinite;
            }
            // `-0` is a number, but a spreadsheet cell "0" says the same.
            let v = if v == 0.0 { 0.0 } else { v };
            use std::fmt::Write as _;
            let _ = write!(text, "{v}");
            return Reading::Number(v as f64);
        }
    };
    if scale == Scale::ONE {
        push_i64(text, int);
        return Reading::Number(int as f64);
    }
    // |int| < 2^32 and |mantissa| < 10^9: the product fits an i64.
    let raw = int * scale.mantissa;
    push_fixed(text, raw, scale.decimals);
    Reading::Number(raw as f64 / 10f64.powi(scale.decimals as i32))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn typed(ty: ValueType, scale: Scale, payload: &[u8]) -> (Reading, String) {
        let mut s = String::new();
        let r = read_typed(ty, scale, payload, &mut s);
        (r, s)
    }

    fn scale(mantissa: i64, decimals: u8) -> Scale {
        Scale { mantissa, decimals }
    }

    #[test]
    fn default_rule_reads_1_2_4_bytes_unsigned() {
        for (payload, text) in [
            (&[0x55][..], "85"),
            (&[0x23, 0x01], "291"),
            (&[0xFF, 0xFF], "65535"),
            (&[0xEF, 0xBE, 0xAD, 0xDE], "3735928559"),
        ] {
            let mut s = String::new();
            let r = read_default(payload, &mut s);
            assert_eq!(s, text);
            assert_eq!(r, Reading::Number(text.parse().unwrap()));
        }
        for none in [&[][..], &[1, 2, 3], &[1, 2, 3, 4, 5], &[0; 8]] {
            let mut s = String::new();
            assert_eq!(read_default(none, &mut s), Reading::None);
            assert!(s.is_empty());
        }
    }

    #[test]
    fn typed_integers_are_little_endian_and_scaled_exactly() {
        assert_eq!(
            typed(ValueType::U16, scale(1, 2), &[0x23, 0x01]),
            (Reading::Number(2.91), "2.91".into())
        );
        assert_eq!(
            typed(ValueType::I16, Scale::ONE, &[0xFF, 0xFF]),
            (Reading::Number(-1.0), "-1".into())
        );
        assert_eq!(
            typed(ValueType::I16, scale(1, 1), &[0x9C, 0xFF]),
            (Reading::Number(-10.0), "-10.0".into())
        );
        assert_eq!(
            typed(ValueType::I8, scale(5, 1), &[0x81]),
            (Reading::Number(-63.5), "-63.5".into())
        );
        assert_eq!(
            typed(ValueType::U8, scale(25, 0), &[0xFF]),
            (Reading::Number(6375.0), "6375".into())
        );
        assert_eq!(
            typed(ValueType::I32, Scale::ONE, &[0xEF, 0xBE, 0xAD, 0xDE]),
            (Reading::Number(-559038737.0), "-559038737".into())
        );
        let (r, s) = typed(ValueType::U32, scale(-999_999_999, 9), &[0xFF; 4]);
        assert_eq!(s, "-4294967290.705032705");
        let Reading::Number(v) = r else { panic!() };
        assert!((v + 4294967290.705033).abs() < 1e-5);
    }

    #[test]
    fn typed_f32_has_the_shortest_exact_text() {
        let bytes = 3.918f32.to_le_bytes();
        assert_eq!(
            typed(ValueType::F32, Scale::ONE, &bytes),
            (Reading::Number(3.918f32 as f64), "3.918".into())
        );
        assert_eq!(typed(ValueType::F32, scale(1000, 0), &bytes).1, "3918");
        assert_eq!(
            typed(ValueType::F32, Scale::ONE, &(-0.0f32).to_le_bytes()).1,
            "0"
        );
        assert_eq!(
            typed(ValueType::F32, Scale::ONE, &f32::NAN.to_le_bytes()).0,
            Reading::NotFinite
        );
        assert_eq!(
            typed(ValueType::F32, Scale::ONE, &f32::INFINITY.to_le_bytes()).0,
            Reading::NotFinite
        );
        assert_eq!(
            typed(
                ValueType::F32,
                scale(1_000_000_000, 0),
                &f32::MAX.to_le_bytes()
            )
            .0,
            Reading::NotFinite
        );
        // Every text parses back as the number (a spreadsheet reads it).
        for f in [1e-30f32, 1e30, -123.456, f32::MIN_POSITIVE, f32::MAX] {
            let (r, s) = typed(ValueType::F32, Scale::ONE, &f.to_le_bytes());
            assert_eq!(s.parse::<f32>().unwrap(), f, "{s}");
            assert_eq!(r, Reading::Number(f as f64));
        }
    }

    #[test]
    fn wrong_sizes_are_reported() {
        assert_eq!(
            typed(ValueType::F32, Scale::ONE, &[1, 2]).0,
            Reading::WrongSize(ValueType::F32, 2)
        );
        assert_eq!(
            typed(ValueType::U8, Scale::ONE, &[]).0,
            Reading::WrongSize(ValueType::U8, 0)
        );
    }

    #[test]
    fn specific_directions_win_over_both() {
        let d = |direction, ty| Declared {
            command: 0x34,
            direction,
            ty,
            scale: Scale::ONE,
            unit: String::new(),
        };
        let v = Values::new(&[
            d(Direction::Request, ValueType::U8),
            d(Direction::Both, ValueType::F32),
        ]);
        assert_eq!(v.declared(0x34, false).unwrap().ty, ValueType::U8);
        assert_eq!(v.declared(0x34, true).unwrap().ty, ValueType::F32);
        assert!(v.declared(0x35, true).is_none());
        let mut s = String::new();
        assert_eq!(v.read(0x35, true, &[7], &mut s), Reading::Number(7.0));
        assert_eq!(v.read(0x34, true, &[], &mut s), Reading::None);
    }
}
