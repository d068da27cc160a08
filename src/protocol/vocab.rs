//! What a protocol's table can show: the values of its ID, Type, Sensor and Device columns and
//! the names of its numbers, so that filters and names are checked before the run
//! (`crate::filter`), `--sensor` and `plot --sensor` accept either name of a sensor, and a
//! filter that cannot apply to the protocol is refused with the reason.

use std::ops::RangeInclusive;

use crate::row::kind;

/// One sensor with both of its names: the Sensor column's (the S-Port_Snoop sample's `Volts`,
/// `Cels`) and the names of the numbers it carries (JSON `parts`, `--wide` columns and `plot`
/// series: EdgeTX's `VFAS`, `Cell1` … `Cell6`). Either selects the same rows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sensor {
    /// The Sensor column.
    pub column: String,
    /// The names of its numbers; empty when the rows carry none, or when they are named as in
    /// the Sensor column.
    pub parts: Vec<String>,
}

impl Sensor {
    /// A sensor whose numbers carry its column name (or none).
    pub fn named(column: &str) -> Sensor {
        Sensor {
            column: column.to_owned(),
            parts: Vec::new(),
        }
    }

    /// Whether `name` is one of its names (case-insensitive).
    pub fn is(&self, name: &str) -> bool {
        self.column.eq_ignore_ascii_case(name)
            || self.parts.iter().any(|p| p.eq_ignore_ascii_case(name))
    }
}

/// What a protocol's table can show, for checking filters and names before the run.
#[derive(Debug)]
pub struct Vocab {
    /// Valid values of the ID column; `None`: its rows have no ID (`--id`, `--not-id` and
    /// `--name` are refused).
    pub ids: Option<RangeInclusive<u32>>,
    /// What the ID is, in messages ("physical ID", "station", "address").
    pub id_name: &'static str,
    /// A hint for an ID outside the range (S.Port: "0xA1 is the poll byte of ID 1").
    pub id_hint: fn(u32) -> Option<String>,
    /// Every value of the Type column (the shared kinds of [`crate::row::kind`] included).
    pub types: &'static [&'static str],
    /// The protocol polls: a poll nobody answered is a row with an ID and an empty Type
    /// (`--hide-polls`, `--type Poll`), and `--wide` writes a line per poll cycle.
    pub polls: bool,
    /// The protocol has keep-alive rows (`Class::Quiet`, `--hide-null`).
    pub keepalives: bool,
    /// The sensors the table can show without options, each with both names.
    pub sensors: fn() -> Vec<Sensor>,
    /// What the Sensor # column looks like, for the hint.
    pub sensor_no_text: &'static str,
    /// Whether a value could appear in the Sensor # column.
    pub sensor_no: fn(&str) -> bool,
    /// The Sensor # column holds hex numbers: `--sensor 0210` and `210` match `0x0210`.
    pub sensor_no_hex: bool,
    /// The Device column without names: the name at an ID, or `None` when the protocol's
    /// devices are not known in advance (Ether-S-Bus shows PLC addresses).
    pub devices: Option<fn(u32) -> &'static str>,
}

/// The name a poll row answers to in `--type`.
pub const POLL: &str = "Poll";

/// The Type names every protocol's rows can have: broken frames, garbage and busnoop's own
/// rows (adapter gaps).
pub const SHARED_TYPES: &[&str] = &[
    kind::BAD_CRC,
    kind::TRUNCATED,
    kind::GARBAGE,
    kind::LINK_DOWN,
    kind::LINK_UP,
];

impl Vocab {
    /// A protocol without IDs, polls, keep-alives, sensor names or devices, whose rows have only
    /// the shared types: the start of a protocol's own vocabulary (`..Vocab::BASE`).
    pub const BASE: Vocab = Vocab {
        ids: None,
        id_name: "ID",
        id_hint: no_hint,
        types: SHARED_TYPES,
        polls: false,
        keepalives: false,
        sensors: Vec::new,
        sensor_no_text: "is empty",
        sensor_no: nothing,
        sensor_no_hex: false,
        devices: None,
    };
}

/// No hint for an ID outside the range.
pub fn no_hint(_: u32) -> Option<String> {
    None
}

fn nothing(_: &str) -> bool {
    false
}

/// A hex number of at most `digits` digits, with or without `0x` (`0210`, `0xF101`, `34`): the
/// Sensor # column of protocols that show a code in hex.
pub fn hex_digits(s: &str, digits: usize) -> bool {
    let h = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    !h.is_empty() && h.len() <= digits && h.bytes().all(|b| b.is_ascii_hexdigit())
}

/// The candidate closest to `word` (case-insensitive edit distance, at most a third of the
/// word's length and at least 1), for "did you mean …".
pub fn did_you_mean<'a>(word: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let w = word.to_ascii_lowercase();
    let limit = (w.chars().count() / 3).max(1);
    candidates
        .map(|c| (distance(&w, &c.to_ascii_lowercase()), c))
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// Edit distance over characters, a swap of two neighbours counting as one edit (optimal
/// string alignment).
fn distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let w = b.len() + 1;
    let mut d = vec![0usize; (a.len() + 1) * w];
    for (i, row) in d.chunks_mut(w).enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[..w].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut v = (d[(i - 1) * w + j - 1] + cost)
                .min(d[(i - 1) * w + j] + 1)
                .min(d[i * w + j - 1] + 1);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                v = v.min(d[(i - 2) * w + j - 2] + 1);
            }
            d[i * w + j] = v;
        }
    }
    d[a.len() * w + b.len()]
}

/// A list of names for a message, on one short line: sorted, each once, and cut after about
/// 80 characters with the number of names left out.
pub fn short_list(names: &[&str]) -> String {
    let mut all: Vec<&str> = names.to_vec();
    all.sort_unstable_by_key(|s| s.to_ascii_lowercase());
    all.dedup_by(|a, b| a.eq_ignore_ascii_case(b));
    let mut out = String::new();
    for (i, n) in all.iter().enumerate() {
        if !out.is_empty() && out.len() + n.len() > 80 {
            out.push_str(&format!(", … ({} more)", all.len() - i));
            return out;
        }
        if !out.is_empty() {
            out.push_str(", ");
        }
        out.push_str(n);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions_and_short_lists() {
        let names = ["VFAS", "Volts", "Curr", "Cels", "RxBt"];
        assert_eq!(did_you_mean("VFAZ", names.iter().copied()), Some("VFAS"));
        assert_eq!(did_you_mean("vlots", names.iter().copied()), Some("Volts"));
        assert_eq!(did_you_mean("Temperature", names.iter().copied()), None);
        assert_eq!(short_list(&["b", "A", "a"]), "A, b");
        let many: Vec<String> = (0..100).map(|i| format!("Name{i}")).collect();
        let many: Vec<&str> = many.iter().map(String::as_str).collect();
        let line = short_list(&many);
        assert!(line.len() < 110 && line.ends_with("more)"), "{line}");
    }

    #[test]
    fn a_sensor_answers_to_both_names() {
        let s = Sensor {
            column: "Volts".into(),
            parts: vec!["VFAS".into()],
        };
        assert!(s.is("volts") && s.is("vfas") && !s.is("Curr"));
        assert!(hex_digits("0x0210", 4) && hex_digits("210", 4) && !hex_digits("12345", 4));
        assert!(!hex_digits("0x", 2) && !hex_digits("g1", 2));
    }
}
