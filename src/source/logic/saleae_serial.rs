//! Saleae's async-serial analyzer exports: characters that Saleae Logic already decoded, one a
//! line, with the time their start bit began.
//!
//! * Logic 1.x: `Time [s],Value,Parity Error,Framing Error`, lines such as `1.028028,0x04,,`;
//!   a non-empty error column flags the character.
//! * Logic 2 (the analyzer's data table): `name,type,start_time,duration,data[,…]`, lines such
//!   as `"Async Serial","data",0.0006025,2.375e-05,0xC8`; only `data` rows count, and a
//!   non-empty column whose header names an error flags the character (a value naming parity
//!   makes it a parity error, anything else a framing error). Several analyzers in one table
//!   are told apart by `name`, which `--channel` chooses (the first one otherwise).
//!
//! Values are read as hexadecimal (`0x41`), binary (`0b01000001`), decimal (`65`) or a single
//! character (`A`, `'A'`); the hexadecimal display is the exact one. The rate and the
//! character format are Saleae's, so `--baud` and the protocol's line do not apply.

use std::collections::VecDeque;
use std::sync::mpsc::SyncSender;

use super::{Char, Chars, Lines, Options, parse_seconds, split_fields};
use crate::exit::{Failure, count};
use crate::source::{Message, Opened};

const MAX_LINE: usize = 4096;
/// Lines handled per read at most.
const LINES_PER_READ: usize = 16 * 1024;

/// Where the columns are.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Layout {
    time: usize,
    value: usize,
    /// The analyzer's name and the row's type (Logic 2).
    name: Option<usize>,
    kind: Option<usize>,
    /// Error columns: (column, parity).
    errors: Vec<(usize, bool)>,
}

/// A Saleae async-serial export as characters.
pub struct SerialCsv {
    lines: Lines,
    name: String,
    channel: Option<String>,
    layout: Option<Layout>,
    /// The analyzer read (Logic 2 tables): the one chosen, or the first seen.
    analyzer: Option<String>,
    /// Rows of other analyzers skipped.
    others: u64,
    origin: Option<i128>,
    last: u64,
    bad_lines: u64,
    fields: Vec<(usize, usize)>,
    /// Characters read.
    chars: u64,
    /// The analyzer names seen (at most 16), for the message when the chosen one is missing.
    names: Vec<String>,
    /// The current line, copied out of the line reader.
    scratch: Vec<u8>,
}

impl SerialCsv {
    pub fn new(opened: Opened, opts: &Options) -> Self {
        let name = opened.name.clone();
        SerialCsv {
            lines: Lines::new(opened, MAX_LINE),
            name,
            channel: opts.channel.clone(),
            layout: None,
            analyzer: opts.channel.clone(),
            others: 0,
            origin: None,
            last: 0,
            bad_lines: 0,
            fields: Vec::new(),
            chars: 0,
            names: Vec::new(),
            scratch: Vec::new(),
        }
    }

    fn layout(&self, line: &[u8]) -> Result<Layout, Failure> {
        let names: Vec<String> = self
            .fields
            .iter()
            .map(|&(a, b)| String::from_utf8_lossy(&line[a..b]).to_ascii_lowercase())
            .collect();
        let find = |want: &str| names.iter().position(|n| n == want);
        let errors = names
            .iter()
            .enumerate()
            .filter(|(_, n)| n.contains("error"))
            .map(|(i, n)| (i, n.contains("parity")))
            .collect();
        let layout = if let (Some(time), Some(value)) = (find("start_time"), find("data")) {
            Layout {
                time,
                value,
                name: find("name"),
                kind: find("type"),
                errors,
            }
        } else if let (Some(time), Some(value)) = (
            names.iter().position(|n| n.starts_with("time")),
            find("value"),
        ) {
            Layout {
                time,
                value,
                name: None,
                kind: None,
                errors,
            }
        } else {
            return Err(Failure::Input(format!(
                "{}: not a Saleae async-serial export (no time and value columns)",
                self.name
            )));
        };
        if self.channel.is_some() && layout.name.is_none() {
            return Err(Failure::Usage(format!(
                "{}: an export of one async-serial analyzer has no channels to choose from",
                self.name
            )));
        }
        Ok(layout)
    }

    /// The character of a data line, or why it is none (`Ok(None)`: a row to skip).
    fn parse(&mut self, line: &[u8], layout: &Layout) -> Result<Option<Char>, String> {
        let field = |i: usize| self.fields.get(i).map_or(&b""[..], |&(a, b)| &line[a..b]);
        if let Some(k) = layout.kind
            && field(k) != b"data"
        {
            return Ok(None);
        }
        if let Some(n) = layout.name {
            let name = String::from_utf8_lossy(field(n));
            if self.names.len() < 16 && !self.names.iter().any(|s| *s == name) {
                self.names.push(name.clone().into_owned());
            }
            match &self.analyzer {
                Some(a) if *a != name => {
                    self.others += 1;
                    return Ok(None);
                }
                Some(_) => {}
                None => self.analyzer = Some(name.into_owned()),
            }
        }
        let time = field(layout.time);
        let ps = parse_seconds(time)
            .ok_or_else(|| format!("{:?} is not a time", String::from_utf8_lossy(time)))?;
        let value = field(layout.value);
        let value = parse_value(value)
            .ok_or_else(|| format!("{:?} is not a byte", String::from_utf8_lossy(value)))?;
        let mut framing = false;
        let mut parity = false;
        for &(col, is_parity) in &layout.errors {
            let v = field(col).to_ascii_lowercase();
            if v.is_empty() {
                continue;
            }
            if is_parity || v.windows(6).any(|w| w == b"parity") {
                parity = true;
            } else {
                framing = true;
            }
        }
        let origin = *self.origin.get_or_insert(ps.min(0));
        let micros = u64::try_from((ps - origin) / 1_000_000).map_err(|_| "time out of range")?;
        if micros < self.last {
            return Err("the time goes back".into());
        }
        self.last = micros;
        Ok(Some(Char {
            micros,
            value,
            framing,
            parity,
            brk: None,
        }))
    }
}

/// `0x41`, `0b01000001`, `65`, `A`, `'A'` as a byte.
fn parse_value(v: &[u8]) -> Option<u8> {
    let v = v.trim_ascii();
    let text = std::str::from_utf8(v).ok()?;
    if let Some(h) = text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        return u8::from_str_radix(h, 16).ok();
    }
    if let Some(b) = text.strip_prefix("0b").or_else(|| text.strip_prefix("0B")) {
        return u8::from_str_radix(b, 2).ok();
    }
    if !text.is_empty() && text.bytes().all(|b| b.is_ascii_digit()) {
        return text.parse().ok();
    }
    let inner = text
        .strip_prefix('\'')
        .and_then(|t| t.strip_suffix('\''))
        .unwrap_or(text);
    match inner.as_bytes() {
        [c] => Some(*c),
        _ => None,
    }
}

impl Chars for SerialCsv {
    fn read(
        &mut self,
        out: &mut VecDeque<super::Char>,
        tx: &SyncSender<Message>,
    ) -> Result<bool, Failure> {
        for _ in 0..LINES_PER_READ {
            let next = self
                .lines
                .next_line()
                .map_err(|e| Failure::Input(format!("cannot read {}: {e}", self.name)))?;
            let Some((line, long, _)) = next else {
                if self.layout.is_none() {
                    return Err(Failure::Input(format!("{}: no header line", self.name)));
                }
                if let Some(want) = &self.channel
                    && self.chars == 0
                {
                    return Err(Failure::Usage(format!(
                        "{}: no rows of the analyzer {want:?}; the table has {}",
                        self.name,
                        self.names.join(", ")
                    )));
                }
                return Ok(false);
            };
            if line.trim_ascii().is_empty() {
                continue;
            }
            let mut line_buf = std::mem::take(&mut self.scratch);
            line_buf.clear();
            line_buf.extend_from_slice(line);
            split_fields(&line_buf, &mut self.fields);
            let Some(layout) = self.layout.take() else {
                let layout = self.layout(&line_buf);
                self.scratch = line_buf;
                self.layout = Some(layout?);
                continue;
            };
            let parsed = if long {
                Err("over 4 KiB long".to_string())
            } else {
                self.parse(&line_buf, &layout)
            };
            self.layout = Some(layout);
            self.scratch = line_buf;
            match parsed {
                Ok(Some(c)) => {
                    self.chars += 1;
                    out.push_back(c)
                }
                Ok(None) => {}
                Err(why) => {
                    self.bad_lines += 1;
                    if self.bad_lines <= 3 {
                        let _ = tx.send(Message::Warning(format!(
                            "{}: line {} skipped: {why}",
                            self.name, self.lines.number
                        )));
                    }
                }
            }
        }
        Ok(true)
    }

    fn summary(&self) -> Vec<String> {
        let mut s = Vec::new();
        if self.bad_lines > 3 {
            s.push(format!(
                "{} skipped",
                count(self.bad_lines, "unreadable line", "unreadable lines")
            ));
        }
        if self.others > 0 && self.channel.is_none() {
            s.push(format!(
                "{} of other analyzers skipped (--channel NAME to read another)",
                count(self.others, "row", "rows")
            ));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_in_every_display() {
        assert_eq!(parse_value(b"0x04"), Some(4));
        assert_eq!(parse_value(b"0XFF"), Some(255));
        assert_eq!(parse_value(b"0b101"), Some(5));
        assert_eq!(parse_value(b"65"), Some(65));
        assert_eq!(parse_value(b"A"), Some(b'A'));
        assert_eq!(parse_value(b"'A'"), Some(b'A'));
        assert_eq!(parse_value(b"256"), None);
        assert_eq!(parse_value(b""), None);
        assert_eq!(parse_value(b"0x"), None);
        assert_eq!(parse_value(b"AB"), None);
    }
}
