//! The numbers of a row ([`crate::row::Part`]): every protocol writes them into a reusable
//! [`Numbers`] while it builds a row, and hands them to the row as a slice, without allocating
//! once the buffers have grown.
//!
//! A number is kept twice: as plain decimal text with the sensor's full wire precision (`3.918`,
//! never `3.92` and never `3.9180000000000001`), which the sinks print as it is, and as an `f64`
//! for the wide export and plots.

use crate::row::Part;

/// Appends `raw / 10^prec` exactly as [`crate::fmt::push_fixed`] does (`6543, 2` → `65.43`,
/// `-150, 2` → `-1.50`, `5, 3` → `0.005`): the magnitude's digits once (`itoa`), then the
/// point placed in them, or leading zeros put before them.
pub fn push_decimal(out: &mut String, raw: i64, prec: u8) {
    let prec = prec as usize;
    if prec > 18 {
        crate::fmt::push_fixed(out, raw, prec as u8);
        return;
    }
    let mut buf = itoa::Buffer::new();
    let digits = buf.format(raw.unsigned_abs());
    out.reserve(digits.len() + prec + 3);
    if raw < 0 {
        out.push('-');
    }
    if prec == 0 {
        out.push_str(digits);
    } else if digits.len() > prec {
        let (whole, frac) = digits.split_at(digits.len() - prec);
        out.push_str(whole);
        out.push('.');
        out.push_str(frac);
    } else {
        out.push_str("0.");
        out.push_str(&ZEROS[..prec - digits.len()]);
        out.push_str(digits);
    }
}

/// Leading zeros of a fraction (up to 18 places).
const ZEROS: &str = "000000000000000000";

/// Appends an unsigned integer in decimal; a single digit without going through `itoa`.
#[inline]
pub fn push_uint(out: &mut String, v: u64) {
    if v < 10 {
        out.push(char::from(b'0' + v as u8));
    } else {
        out.push_str(itoa::Buffer::new().format(v));
    }
}

/// A number's name: a constant (most sensors), or a range of the names buffer (names built
/// per row, `Cell3`, `0x5100`).
#[derive(Clone, Copy)]
enum Name {
    Static(&'static str),
    Built(u32, u32),
}

impl Default for Name {
    fn default() -> Self {
        Name::Static("")
    }
}

/// One number being built: its name and ranges into the buffers.
#[derive(Clone, Copy, Default)]
struct Slot {
    name: Name,
    unit: &'static str,
    text: (u32, u32),
    value: f64,
}

/// The numbers of one row, at most `N` (further numbers are dropped and counted in
/// [`Numbers::dropped`]; protocols choose `N` larger than anything a frame can carry).
pub struct Numbers<const N: usize> {
    names: String,
    text: String,
    slots: [Slot; N],
    len: usize,
    dropped: usize,
}

impl<const N: usize> Default for Numbers<N> {
    fn default() -> Self {
        Numbers {
            names: String::new(),
            text: String::new(),
            slots: [Slot::default(); N],
            len: 0,
            dropped: 0,
        }
    }
}

const POW10: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];

impl<const N: usize> Numbers<N> {
    pub fn clear(&mut self) {
        self.names.clear();
        self.text.clear();
        self.len = 0;
        self.dropped = 0;
    }

    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Numbers that did not fit (none in practice: `N` is the most a frame carries).
    #[cfg(test)]
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// The first number's text (the `Value` column), or "".
    pub fn first_text(&self) -> &str {
        match self.len {
            0 => "",
            _ => self.range(&self.text, self.slots[0].text),
        }
    }

    /// The text of the number added last, or "" (to copy it into a Data cell).
    pub fn last_text(&self) -> &str {
        match self.len {
            0 => "",
            n => self.range(&self.text, self.slots[n - 1].text),
        }
    }

    /// The first number's unit, or "".
    pub fn first_unit(&self) -> &'static str {
        if self.len == 0 {
            ""
        } else {
            self.slots[0].unit
        }
    }

    fn range<'a>(&self, s: &'a str, (a, b): (u32, u32)) -> &'a str {
        &s[a as usize..b as usize]
    }

    /// Starts a number named `name` and returns its slot, or `None` when full.
    #[inline]
    fn start(&mut self, name: Name, unit: &'static str) -> Option<usize> {
        if self.len == N {
            self.dropped += 1;
            return None;
        }
        let i = self.len;
        self.slots[i] = Slot {
            name,
            unit,
            text: (0, 0),
            value: 0.0,
        };
        Some(i)
    }

    /// Writes a name with `name` into the names buffer.
    fn build_name(&mut self, name: impl FnOnce(&mut String)) -> Name {
        let a = self.names.len() as u32;
        name(&mut self.names);
        Name::Built(a, self.names.len() as u32)
    }

    /// `raw / 10^prec`, named with `name`.
    pub fn fixed_with(
        &mut self,
        name: impl FnOnce(&mut String),
        unit: &'static str,
        raw: i64,
        prec: u8,
    ) {
        if self.len == N {
            self.dropped += 1;
            return;
        }
        let name = self.build_name(name);
        self.push_fixed(name, unit, raw, prec);
    }

    /// `raw / 10^prec`.
    pub fn fixed(&mut self, name: &'static str, unit: &'static str, raw: i64, prec: u8) {
        self.push_fixed(Name::Static(name), unit, raw, prec);
    }

    #[inline]
    fn push_fixed(&mut self, name: Name, unit: &'static str, raw: i64, prec: u8) {
        let Some(i) = self.start(name, unit) else {
            return;
        };
        let a = self.text.len() as u32;
        push_decimal(&mut self.text, raw, prec);
        let b = self.text.len() as u32;
        let value = raw as f64 / POW10[(prec as usize).min(9)];
        self.slots[i].text = (a, b);
        self.slots[i].value = value;
        self.len += 1;
    }

    /// An integer.
    pub fn int(&mut self, name: &'static str, unit: &'static str, v: i64) {
        self.fixed(name, unit, v, 0);
    }

    /// An integer named with `name`.
    pub fn int_with(&mut self, name: impl FnOnce(&mut String), unit: &'static str, v: i64) {
        self.fixed_with(name, unit, v, 0);
    }

    /// An unsigned integer of up to 64 bits (exact text; the `f64` may round above 2^53).
    #[cfg(test)]
    pub fn uint(&mut self, name: &'static str, unit: &'static str, v: u64) {
        match i64::try_from(v) {
            Ok(v) => self.int(name, unit, v),
            Err(_) => {
                let Some(i) = self.start(Name::Static(name), unit) else {
                    return;
                };
                let a = self.text.len() as u32;
                crate::fmt::push_u64(&mut self.text, v);
                let b = self.text.len() as u32;
                self.slots[i].text = (a, b);
                self.slots[i].value = v as f64;
                self.len += 1;
            }
        }
    }

    /// Calls `f` with the numbers as [`Part`]s (built on the stack). A single number (most
    /// rows that have any) is one part, without filling an array of `N` first.
    pub fn with_parts<R>(&self, f: impl FnOnce(&[Part<'_>]) -> R) -> R {
        match self.len {
            0 => f(&[]),
            1 => f(&[self.part(&self.slots[0])]),
            len => {
                let mut parts = [Part::EMPTY; N];
                for (p, s) in parts.iter_mut().zip(&self.slots[..len]) {
                    *p = self.part(s);
                }
                f(&parts[..len])
            }
        }
    }

    /// The [`Part`] of one slot.
    #[inline]
    fn part(&self, s: &Slot) -> Part<'_> {
        Part {
            name: match s.name {
                Name::Static(n) => n,
                Name::Built(a, b) => self.range(&self.names, (a, b)),
            },
            unit: s.unit,
            text: self.range(&self.text, s.text),
            value: s.value,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_matches_push_fixed() {
        let raws = [
            0,
            1,
            -1,
            5,
            9,
            10,
            99,
            100,
            6543,
            -150,
            1959 * 2,
            123_456_789,
            i64::MAX,
            i64::MIN,
            i64::MIN + 1,
        ];
        // Every digit count, both signs, and the powers of ten around each.
        let mut raws = raws.to_vec();
        let mut p: i64 = 1;
        for _ in 0..19 {
            raws.extend([p - 1, p, p + 1, -p, -(p - 1), p * 7 / 3]);
            p = p.saturating_mul(10);
        }
        for raw in raws {
            for prec in 0..=18 {
                let (mut a, mut b) = (String::from("x"), String::from("x"));
                crate::fmt::push_fixed(&mut a, raw, prec);
                push_decimal(&mut b, raw, prec);
                assert_eq!(a, b, "{raw} prec {prec}");
            }
        }
        for v in [0, 1, 9, 10, 11, 255, u64::MAX] {
            let mut s = String::new();
            push_uint(&mut s, v);
            assert_eq!(s, v.to_string());
        }
    }

    #[test]
    fn text_and_value_agree() {
        let mut n = Numbers::<4>::default();
        n.fixed("Cell1", "V", 3918, 3);
        n.fixed("Alt", "m", -150, 2);
        n.uint("big", "", u64::MAX);
        n.int("x", "", 7);
        n.int("dropped", "", 8);
        assert_eq!(n.len(), 4);
        assert_eq!(n.dropped(), 1);
        assert_eq!(n.first_text(), "3.918");
        assert_eq!(n.first_unit(), "V");
        n.with_parts(|p| {
            assert_eq!(p.len(), 4);
            assert_eq!(
                (p[0].name, p[0].text, p[0].value),
                ("Cell1", "3.918", 3.918)
            );
            assert_eq!((p[1].name, p[1].text, p[1].value), ("Alt", "-1.50", -1.5));
            assert_eq!(p[2].text, "18446744073709551615");
            for part in p {
                let parsed: f64 = part.text.parse().unwrap();
                assert_eq!(parsed, part.value, "{}", part.text);
            }
        });
        // One number (the path without the array) and two give the parts alike.
        for count in 1..=2 {
            let mut m = Numbers::<4>::default();
            m.fixed("Alt", "m", -150, 2);
            if count == 2 {
                m.int_with(|s| s.push_str("Cell3"), "V", 7);
            }
            m.with_parts(|p| {
                assert_eq!(p.len(), count);
                assert_eq!((p[0].name, p[0].unit, p[0].text), ("Alt", "m", "-1.50"));
                assert_eq!(p[0].value, -1.5);
                if count == 2 {
                    assert_eq!((p[1].name, p[1].unit, p[1].text), ("Cell3", "V", "7"));
                }
            });
            let mut one = Numbers::<4>::default();
            one.int_with(|s| s.push_str("0x5100"), "", 42);
            one.with_parts(|p| {
                assert_eq!(p.len(), 1);
                assert_eq!((p[0].name, p[0].text, p[0].value), ("0x5100", "42", 42.0));
            });
        }
        n.clear();
        assert!(n.is_empty());
        assert_eq!(n.first_text(), "");
        n.with_parts(|p| assert!(p.is_empty()));
    }
}
