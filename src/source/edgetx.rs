//! The EdgeTX/OpenTX S.Port debug log: one poll or frame per line,
//! `YYYY-MM-DD,HH:MM:SS.mmm: 7E A1 10 …` (hex bytes as on the wire, stuffing included; a line
//! may end in the middle of a frame). Millis counts from the first line.
//!
//! Millis never goes back: when the log's time does (the radio's clock was set, or two logs were
//! joined), a `TimeJump` row says by how much, Millis goes on from where it was, and the wall
//! time (`--time abs`) follows the log again from there (a new anchor).

use std::io::{self, Read};
use std::sync::mpsc::SyncSender;

use chrono::NaiveDateTime;

use super::{Batch, Chunk, ChunkReader, Message, Opened};
use crate::exit::Failure;
use crate::time::Anchor;

/// Length of the `YYYY-MM-DD,HH:MM:SS.mmm:` stamp.
const STAMP_LEN: usize = 24;
/// Longer lines are not log lines; they are skipped.
const MAX_LINE: usize = 4096;
/// A batch is sent once it holds this many bytes, or when the input has nothing more buffered.
const BATCH_BYTES: usize = 64 * 1024;
/// Time marks per batch at most (one per line with bytes): a log of one byte per line sends
/// batches of 256 KiB of marks, not 16 bytes of marks per byte up to [`BATCH_BYTES`].
const BATCH_MARKS: usize = 16 * 1024;

/// `Some(true)` when `prefix` starts like a log line, `Some(false)` when it cannot be one,
/// `None` when more bytes are needed to tell.
pub fn looks_like_log(prefix: &[u8]) -> Option<bool> {
    // Blank lines and a UTF-8 byte-order mark may come first (the EdgeTX sample starts with one
    // empty line).
    let prefix = prefix.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(prefix);
    let start = prefix.iter().position(|b| !b.is_ascii_whitespace())?;
    let prefix = &prefix[start..];
    // Shape: dddd-dd-dd,dd:dd:dd.ddd:
    const SHAPE: &[u8; STAMP_LEN] = b"dddd-dd-dd,dd:dd:dd.ddd:";
    for (i, &want) in SHAPE.iter().enumerate() {
        let &b = prefix.get(i)?;
        let ok = if want == b'd' {
            b.is_ascii_digit()
        } else {
            b == want
        };
        if !ok {
            return Some(false);
        }
    }
    Some(true)
}

/// A parsed log line.
#[derive(Debug, PartialEq, Eq)]
pub struct LogLine {
    pub time: NaiveDateTime,
    pub bytes: Vec<u8>,
}

/// Parses one line (without its line end). `None` if it is not a log line.
pub fn parse_line(line: &[u8]) -> Option<LogLine> {
    let text = std::str::from_utf8(line).ok()?.trim_end_matches('\r');
    if looks_like_log(text.as_bytes()) != Some(true) {
        return None;
    }
    let time =
        NaiveDateTime::parse_from_str(&text[..STAMP_LEN - 1], "%Y-%m-%d,%H:%M:%S%.3f").ok()?;
    let mut bytes = Vec::new();
    for tok in text[STAMP_LEN..].split_ascii_whitespace() {
        if tok.len() != 2 {
            return None;
        }
        bytes.push(u8::from_str_radix(tok, 16).ok()?);
    }
    Some(LogLine { time, bytes })
}

/// Streams a log file as batches, one time mark per line.
pub struct EdgeTxReader {
    reader: Box<dyn Read + Send>,
    name: String,
    /// Read buffer; `buf[pos..filled]` is unread.
    buf: Vec<u8>,
    pos: usize,
    filled: usize,
    eof: bool,
    line: Vec<u8>,
    overlong: bool,
    line_no: u64,
    /// The logged time of Millis 0 (moved when the log's time goes back).
    anchor: Option<NaiveDateTime>,
    /// The last line's time, µs since the anchor.
    last: u64,
    /// `line` holds a parsed line that must wait for the batch before it (a time jump changes
    /// the anchor, which applies from the next message on).
    held: bool,
    bad_lines: u64,
}

impl EdgeTxReader {
    pub fn new(opened: Opened) -> Self {
        let filled = opened.prefix.len();
        EdgeTxReader {
            reader: opened.reader,
            name: opened.name,
            buf: opened.prefix,
            pos: 0,
            filled,
            eof: false,
            line: Vec::new(),
            overlong: false,
            line_no: 0,
            anchor: None,
            last: 0,
            held: false,
            bad_lines: 0,
        }
    }

    fn fill(&mut self) -> Result<(), Failure> {
        self.pos = 0;
        // Zeroed once; later reads reuse the buffer and only `filled` bytes count.
        self.buf.resize(super::READ_SIZE, 0);
        loop {
            match self.reader.read(&mut self.buf) {
                Ok(n) => {
                    self.filled = n;
                    self.eof = n == 0;
                    return Ok(());
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => {
                    self.filled = 0;
                    return Err(Failure::Input(format!("cannot read {}: {e}", self.name)));
                }
            }
        }
    }

    /// Handles one complete line; adds its bytes to `batch`. Returns true when the line has to
    /// wait (in `line`, `held` set) until `batch` is sent.
    fn take_line(&mut self, batch: &mut Batch, tx: &SyncSender<Message>) -> bool {
        self.line_no += 1;
        let line = std::mem::take(&mut self.line);
        let overlong = std::mem::replace(&mut self.overlong, false);
        if line.iter().all(|b| b.is_ascii_whitespace()) && !overlong {
            self.line = line;
            self.line.clear();
            return false;
        }
        // A UTF-8 byte-order mark before the first line (an editor saved the log).
        let text = match self.line_no {
            1 => line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&line),
            _ => &line[..],
        };
        match parse_line(text).filter(|_| !overlong) {
            Some(l) => {
                let anchor = *self.anchor.get_or_insert_with(|| {
                    let _ = tx.send(Message::Anchor(Anchor::Naive(l.time)));
                    l.time
                });
                let since = (l.time - anchor).num_microseconds().unwrap_or(i64::MIN);
                let micros = if since >= self.last as i64 {
                    since as u64
                } else {
                    if !batch.bytes.is_empty() {
                        // Send the lines before the jump with the old anchor first.
                        self.line_no -= 1;
                        self.line = line;
                        self.held = true;
                        return true;
                    }
                    // `last` is at most the span of the log's own years: these cannot leave
                    // chrono's range, but stay checked all the same.
                    let last = chrono::Duration::microseconds(self.last as i64);
                    let before = anchor.checked_add_signed(last).unwrap_or(anchor);
                    let back = (before - l.time).num_microseconds().unwrap_or(i64::MAX);
                    let new_anchor = l.time.checked_sub_signed(last).unwrap_or(l.time);
                    self.anchor = Some(new_anchor);
                    let _ = tx.send(Message::Note {
                        micros: Some(self.last),
                        kind: crate::row::kind::TIME_JUMP,
                        class: crate::row::Class::Warning,
                        data: format!(
                            "the log's time goes back {:.3} s ({} -> {}) at line {}",
                            back as f64 / 1e6,
                            before.format("%Y-%m-%d %H:%M:%S%.3f"),
                            l.time.format("%Y-%m-%d %H:%M:%S%.3f"),
                            self.line_no
                        ),
                        gap: true,
                    });
                    // After the row, which is shown at the old time.
                    let _ = tx.send(Message::Anchor(Anchor::Naive(new_anchor)));
                    self.last
                };
                self.last = micros;
                // A line with no bytes leaves a mark with none after it: the next line's time
                // replaces it, so that a run of such lines costs nothing (M1, issue 32).
                match batch.marks.last_mut() {
                    Some(m) if m.0 == batch.bytes.len() => m.1 = Some(micros),
                    _ => batch.marks.push((batch.bytes.len(), Some(micros))),
                }
                batch.bytes.extend_from_slice(&l.bytes);
            }
            None => {
                self.bad_lines += 1;
                if self.bad_lines <= 3 {
                    let _ = tx.send(Message::Warning(format!(
                        "{}: line {} is not an EdgeTX log line, skipped",
                        self.name, self.line_no
                    )));
                }
            }
        }
        self.line = line;
        self.line.clear();
        false
    }
}

impl ChunkReader for EdgeTxReader {
    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Chunk>, Failure> {
        let mut batch = Batch::default();
        if std::mem::take(&mut self.held) {
            self.take_line(&mut batch, tx);
        }
        loop {
            if self.held {
                break;
            }
            if self.pos >= self.filled {
                // Send what we have before blocking on a slow pipe.
                if !batch.bytes.is_empty() {
                    break;
                }
                if self.eof {
                    if (!self.line.is_empty() || self.overlong) && self.take_line(&mut batch, tx) {
                        break;
                    }
                    if self.bad_lines > 3 {
                        let _ = tx.send(Message::Warning(format!(
                            "{}: {} lines in all were not EdgeTX log lines and were skipped",
                            self.name, self.bad_lines
                        )));
                        self.bad_lines = 0;
                    }
                    return Ok(if batch.bytes.is_empty() {
                        None
                    } else {
                        Some(batch.into())
                    });
                }
                self.fill()?;
                continue;
            }
            let rest = &self.buf[self.pos..self.filled];
            match rest.iter().position(|&b| b == b'\n') {
                Some(i) => {
                    if self.line.len() + i <= MAX_LINE {
                        self.line.extend_from_slice(&rest[..i]);
                    } else {
                        self.overlong = true;
                    }
                    self.pos += i + 1;
                    if self.take_line(&mut batch, tx)
                        || batch.bytes.len() >= BATCH_BYTES
                        || batch.marks.len() >= BATCH_MARKS
                    {
                        break;
                    }
                }
                None => {
                    if self.line.len() + rest.len() <= MAX_LINE {
                        self.line.extend_from_slice(rest);
                    } else {
                        self.overlong = true;
                        self.line.clear();
                    }
                    self.pos = self.filled;
                }
            }
        }
        Ok(Some(batch.into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_lines() {
        let l = parse_line(b"2014-07-11,22:41:01.770: 7E 98 10 05 F1 10 35 0F 96 0E\r").unwrap();
        assert_eq!(l.bytes.len(), 10);
        assert_eq!(l.time.to_string(), "2014-07-11 22:41:01.770");
        assert!(parse_line(b"2014-07-11,22:41:01.770: 7E 9").is_none());
        assert!(parse_line(b"hello").is_none());
        assert_eq!(
            looks_like_log(b"\r\n2014-07-11,22:41:01.340: 7E"),
            Some(true)
        );
        assert_eq!(looks_like_log(b"\r\n\r\n"), None);
        assert_eq!(looks_like_log(b"\r\n~"), Some(false));
        assert_eq!(
            parse_line(b"2014-07-11,22:41:01.770:").unwrap().bytes,
            Vec::<u8>::new()
        );
    }

    #[test]
    fn reads_batches_with_marks() {
        let text = b"2014-07-11,22:41:01.340: 7E 00\n\nnot a log line\n2014-07-11,22:41:01.350: 7E A1\n2014-07-11,22:41:01.360: 7E".to_vec();
        let opened = Opened {
            kind: super::super::InputKind::EdgeTxLog,
            prefix: Vec::new(),
            reader: Box::new(std::io::Cursor::new(text)),
            name: "t".into(),
        };
        let (tx, rx) = std::sync::mpsc::sync_channel(16);
        let mut r = EdgeTxReader::new(opened);
        let mut all = Batch::default();
        while let Some(Chunk::Bytes(b)) = r.next_batch(&tx).unwrap() {
            for (bytes, t) in b.segments() {
                all.marks.push((all.bytes.len(), t));
                all.bytes.extend_from_slice(bytes);
            }
        }
        assert_eq!(all.bytes, [0x7E, 0x00, 0x7E, 0xA1, 0x7E]);
        assert_eq!(
            all.marks,
            [(0, Some(0)), (2, Some(10_000)), (4, Some(20_000))]
        );
        let msgs: Vec<Message> = rx.try_iter().collect();
        assert!(matches!(msgs[0], Message::Anchor(_)));
        assert!(matches!(&msgs[1], Message::Warning(w) if w.contains("line 3")));
    }

    /// M1 (issue 32): lines with a time and no bytes added a mark each until 256 KiB of bytes
    /// came (memory about the size of the input; a pipe into `detect -` grew ~70 MB/s). A mark
    /// with no bytes after it now takes the later time instead.
    #[test]
    fn lines_without_bytes_add_no_marks() {
        let mut text = Vec::new();
        for i in 0..100_000u32 {
            let t = chrono::NaiveDate::from_ymd_opt(2014, 7, 11)
                .unwrap()
                .and_hms_opt(22, 0, 0)
                .unwrap()
                + chrono::Duration::milliseconds(i64::from(i));
            text.extend_from_slice(t.format("%Y-%m-%d,%H:%M:%S%.3f:\n").to_string().as_bytes());
        }
        text.extend_from_slice(b"2014-07-11,22:05:00.000: 7E 00\n");
        let msgs = messages(&text);
        let batches: Vec<&Batch> = msgs
            .iter()
            .filter_map(|m| match m {
                Message::Data(b) => Some(b),
                _ => None,
            })
            .collect();
        let marks = batches.iter().map(|b| b.marks.len()).max().unwrap();
        assert!(marks <= 2, "{marks} marks in one batch");
        let segments: Vec<_> = batches.iter().flat_map(|b| b.segments()).collect();
        assert_eq!(
            segments.last().unwrap(),
            &(&[0x7E, 0x00][..], Some(300_000_000))
        );
        // One byte per line: a mark per byte, in batches of at most BATCH_MARKS marks.
        let text = "2014-07-11,22:41:01.340: 7E\n".repeat(40_000);
        let msgs = messages(text.as_bytes());
        let marks = msgs.iter().filter_map(|m| match m {
            Message::Data(b) => Some(b.marks.len()),
            _ => None,
        });
        assert!(marks.max().unwrap() <= BATCH_MARKS);
    }

    /// Every message the reader sends, batches included, in order.
    fn messages(text: &[u8]) -> Vec<Message> {
        let opened = Opened {
            kind: super::super::InputKind::EdgeTxLog,
            prefix: Vec::new(),
            reader: Box::new(std::io::Cursor::new(text.to_vec())),
            name: "t".into(),
        };
        let (tx, rx) = std::sync::mpsc::sync_channel(1000);
        let mut r = EdgeTxReader::new(opened);
        while let Some(c) = r.next_batch(&tx).unwrap() {
            tx.send(c.into()).unwrap();
        }
        drop(tx);
        rx.iter().collect()
    }

    #[test]
    fn a_byte_order_mark_does_not_cost_the_first_line() {
        let msgs = messages(
            b"\xEF\xBB\xBF2014-07-11,22:41:01.340: 7E 00\n2014-07-11,22:41:01.350: 7E A1\n",
        );
        assert!(
            !msgs.iter().any(|m| matches!(m, Message::Warning(_))),
            "{msgs:?}"
        );
        let bytes: Vec<u8> = msgs
            .iter()
            .filter_map(|m| match m {
                Message::Data(b) => Some(b.bytes.clone()),
                _ => None,
            })
            .flatten()
            .collect();
        assert_eq!(bytes, [0x7E, 0x00, 0x7E, 0xA1]);
    }

    #[test]
    fn time_going_back_is_a_note_between_the_batches_and_a_new_anchor() {
        let msgs = messages(
            b"2014-07-11,22:41:05.000: 7E 00\n2014-07-11,22:41:05.100: 7E A1\n\
              2014-07-11,22:41:01.000: 7E 22\n2014-07-11,22:41:01.012: 7E 83",
        );
        let mut seen = Vec::new();
        for m in &msgs {
            match m {
                Message::Anchor(Anchor::Naive(a)) => seen.push(format!("anchor {a}")),
                Message::Data(b) => seen.push(format!("data {:?}", b.marks)),
                Message::Note {
                    micros, kind, gap, ..
                } => seen.push(format!("{kind} {micros:?} {gap}")),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(
            seen,
            [
                "anchor 2014-07-11 22:41:05".to_string(),
                "data [(0, Some(0)), (2, Some(100000))]".to_string(),
                "TimeJump Some(100000) true".to_string(),
                "anchor 2014-07-11 22:41:00.900".to_string(),
                "data [(0, Some(100000))]".to_string(),
                "data [(0, Some(112000))]".to_string(),
            ]
        );
        let note = msgs
            .iter()
            .find_map(|m| match m {
                Message::Note { data, .. } => Some(data.clone()),
                _ => None,
            })
            .unwrap();
        assert!(note.contains("goes back 4.100 s"), "{note}");
    }
}
