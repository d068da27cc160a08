//! The command line's names for values of types that live outside it (`--format`,
//! `--dtr-rts`): clap stays in `cli/`, the sink and the serial source do not know it.

use clap::ValueEnum;
use clap::builder::PossibleValue;

use crate::sink::Format;
use crate::source::serial::ModemLines;

impl ValueEnum for Format {
    fn value_variants<'a>() -> &'a [Self] {
        &[Format::Pretty, Format::Tsv, Format::Csv, Format::Jsonl]
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(match self {
            Format::Pretty => {
                PossibleValue::new("pretty").help("Aligned, coloured columns for a terminal")
            }
            Format::Tsv => PossibleValue::new("tsv").help("Tab-separated values with a header row"),
            Format::Csv => PossibleValue::new("csv")
                .help("Comma-separated values (RFC 4180) with a header row"),
            Format::Jsonl => PossibleValue::new("jsonl").help("One JSON object per row"),
        })
    }
}

impl ValueEnum for ModemLines {
    fn value_variants<'a>() -> &'a [Self] {
        &[ModemLines::Low, ModemLines::Keep]
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(match self {
            ModemLines::Low => PossibleValue::new("low").help(
                "Drop DTR and RTS right after opening and keep them low (they then stay low on \
                 close)",
            ),
            ModemLines::Keep => PossibleValue::new("keep").help(
                "Leave them as the driver sets them (Linux: raised on open, dropped on close when \
                 the port's HUPCL is set), for adapters powered or enabled by DTR/RTS",
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every variant has its name, and the names read back (what the derive gave).
    #[test]
    fn names_read_back() {
        for f in Format::value_variants() {
            let name = f.to_possible_value().unwrap().get_name().to_owned();
            assert_eq!(Format::from_str(&name, false), Ok(*f));
        }
        assert_eq!(Format::from_str("JSONL", true), Ok(Format::Jsonl));
        for m in ModemLines::value_variants() {
            let name = m.to_possible_value().unwrap().get_name().to_owned();
            assert_eq!(ModemLines::from_str(&name, false), Ok(*m));
        }
    }
}
