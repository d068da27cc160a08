//! Lines of a text log, and which log it is: the pure reassembler of `busnoop log`.
//!
//! Bytes come in any split; whole lines go out, each with every byte since the line before
//! (blank lines before it included), so that every byte is in exactly one row. A line longer
//! than [`MAX_LINE`] is not a log line: its bytes go out as garbage pieces of at most
//! [`GARBAGE_ROW_MAX`] bytes, cut at fixed places from the line's start, and so does every byte
//! before the header line. Nothing here allocates per line once the buffer has grown.

use crate::row::GARBAGE_ROW_MAX;

/// The longest line read as a log line (an EdgeTX CSV line with 60 sensors is about 400 bytes).
pub const MAX_LINE: usize = 16 << 10;

/// Which log the header line names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A radio's SD-card log (EdgeTX, OpenTX): `Date,Time,` then one column per sensor, named as
    /// the radio names it, with its unit in parentheses (`RxBt(V)`; OpenTX 2.0 had none).
    RadioCsv,
    /// S-Port_Snoop's log table, tab-separated: `Counter, Millis, ID, Device, Type, Sensor #,
    /// Sensor, Data` (busnoop's own TSV adds `Value` and its protocol's columns).
    SnoopTable,
}

impl Format {
    /// The format a header line starts, if it is one.
    pub fn of_header(line: &str) -> Option<Format> {
        let line = line.strip_prefix('\u{feff}').unwrap_or(line);
        if line.starts_with("Date,Time,") {
            Some(Format::RadioCsv)
        } else if line.starts_with("Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData") {
            Some(Format::SnoopTable)
        } else {
            None
        }
    }

    /// The field separator.
    pub fn separator(self) -> char {
        match self {
            Format::RadioCsv => ',',
            Format::SnoopTable => '\t',
        }
    }
}

/// What the reassembler hands on.
#[derive(Debug, PartialEq, Eq)]
pub enum Event<'a> {
    /// The header line (without the line end); its bytes go with the first line's row.
    Header { text: &'a str },
    /// A line after the header: its text and every byte since the last row.
    Line { text: &'a str, raw: &'a [u8] },
    /// Bytes that are no log line (before the header, a line too long or not text), at most
    /// [`GARBAGE_ROW_MAX`] of them.
    Garbage(&'a [u8]),
}

/// Splits bytes into lines.
#[derive(Debug, Default)]
pub struct Lines {
    /// Bytes of the line being read, after the bytes that go with it (blank lines, the header).
    buf: Vec<u8>,
    /// Where the line being read starts in `buf`.
    line_start: usize,
    /// Inside a line longer than [`MAX_LINE`]: its bytes are garbage up to its end.
    overlong: bool,
    /// The header: the log's format; `None` before it.
    format: Option<Format>,
}

impl Lines {
    pub fn new() -> Self {
        Lines::default()
    }

    /// The format of the header seen, if any.
    pub fn format(&self) -> Option<Format> {
        self.format
    }

    /// Feeds bytes; every line they complete goes to `emit`.
    pub fn push(&mut self, data: &[u8], emit: &mut dyn FnMut(Event<'_>)) {
        let mut rest = data;
        while !rest.is_empty() {
            let room = MAX_LINE - self.buf.len();
            let take = match rest.iter().position(|&b| b == b'\n') {
                Some(i) if i < room => i + 1,
                _ => room.min(rest.len()),
            };
            self.buf.extend_from_slice(&rest[..take]);
            rest = &rest[take..];
            if self.buf.last() == Some(&b'\n') {
                self.line(emit);
            } else if self.buf.len() == MAX_LINE {
                // No line end within MAX_LINE: not a log line.
                self.overlong = true;
                garbage(&self.buf, emit);
                self.buf.clear();
                self.line_start = 0;
            }
        }
    }

    /// The end of the input: a last line without its line end is a line; blank lines (and a
    /// header without lines) at the end are in no row.
    pub fn finish(&mut self, emit: &mut dyn FnMut(Event<'_>)) {
        if self.buf[self.line_start..]
            .iter()
            .any(|b| !b.is_ascii_whitespace())
        {
            self.line(emit);
        }
        self.buf.clear();
        self.line_start = 0;
        self.overlong = false;
    }

    /// The line in `buf` (ending in `\n`, or the last one).
    fn line(&mut self, emit: &mut dyn FnMut(Event<'_>)) {
        if self.overlong {
            self.overlong = false;
            garbage(&self.buf, emit);
            self.buf.clear();
            self.line_start = 0;
            return;
        }
        let Ok(text) = std::str::from_utf8(&self.buf[self.line_start..]) else {
            garbage(&self.buf, emit);
            self.buf.clear();
            self.line_start = 0;
            return;
        };
        let text = text.trim_end_matches(['\r', '\n']);
        if text.trim().is_empty() {
            // A blank line: its bytes go with the next line.
            self.line_start = self.buf.len();
            return;
        }
        match self.format {
            Some(_) => emit(Event::Line {
                text,
                raw: &self.buf,
            }),
            None => match Format::of_header(text) {
                Some(f) => {
                    self.format = Some(f);
                    emit(Event::Header { text });
                    self.line_start = self.buf.len();
                    return;
                }
                None => garbage(&self.buf, emit),
            },
        }
        self.buf.clear();
        self.line_start = 0;
    }
}

/// `bytes` as garbage events of at most [`GARBAGE_ROW_MAX`] bytes.
fn garbage(bytes: &[u8], emit: &mut dyn FnMut(Event<'_>)) {
    for piece in bytes.chunks(GARBAGE_ROW_MAX) {
        emit(Event::Garbage(piece));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn events(chunks: &[&[u8]]) -> Vec<String> {
        let mut l = Lines::new();
        let mut out = Vec::new();
        let mut emit = |e: Event<'_>| out.push(format!("{e:?}"));
        for c in chunks {
            l.push(c, &mut emit);
        }
        l.finish(&mut emit);
        out
    }

    #[test]
    fn lines_in_any_split() {
        let text =
            b"junk\nDate,Time,RSSI\n\n2014-07-11,22:41:00.570,90\r\n2014-07-11,22:41:00.670,91";
        let whole = events(&[text]);
        assert_eq!(whole.len(), 4, "{whole:#?}");
        assert!(whole[0].starts_with("Garbage("));
        assert_eq!(whole[1], "Header { text: \"Date,Time,RSSI\" }");
        // The header's and the blank line's bytes go with the first line.
        assert!(
            whole[2].starts_with("Line { text: \"2014-07-11,22:41:00.570,90\", raw: [68, 97"),
            "{whole:#?}"
        );
        assert!(whole[3].contains("text: \"2014-07-11,22:41:00.670,91\""));
        let bytes: Vec<&[u8]> = text.chunks(1).collect();
        assert_eq!(events(&bytes), whole);
        let threes: Vec<&[u8]> = text.chunks(3).collect();
        assert_eq!(events(&threes), whole);
    }

    #[test]
    fn a_line_too_long_is_garbage_cut_at_fixed_places() {
        let mut text = b"Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\n".to_vec();
        text.extend(std::iter::repeat_n(b'x', MAX_LINE + 100));
        text.extend(b"\n1\t12\t0\tVario\tNull\t\t\t\n");
        let whole = events(&[&text]);
        let garbage = whole.iter().filter(|e| e.starts_with("Garbage(")).count();
        // The header, the line up to MAX_LINE (256 pieces), the rest of it (149 bytes: 3).
        assert_eq!(garbage, MAX_LINE / GARBAGE_ROW_MAX + 3);
        assert!(whole.last().unwrap().contains("Vario"));
        let pieces: Vec<&[u8]> = text.chunks(1000).collect();
        assert_eq!(events(&pieces), whole);
    }

    #[test]
    fn headers() {
        assert_eq!(
            Format::of_header("Date,Time,SWR,RSSI"),
            Some(Format::RadioCsv)
        );
        assert_eq!(
            Format::of_header("\u{feff}Date,Time,1RSS(dB)"),
            Some(Format::RadioCsv)
        );
        assert_eq!(
            Format::of_header("Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue"),
            Some(Format::SnoopTable)
        );
        assert_eq!(Format::of_header("Time [s],Channel 0"), None);
    }
}
