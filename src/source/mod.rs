//! Sources: where bytes come from, with their arrival times.
//!
//! A source runs in its own reader thread and hands [`Batch`]es of bytes to the decoder over a
//! bounded channel, so memory stays flat however large the capture is. Input files and
//! standard input are recognised by their content, not by their name ([`detect`]).

pub mod edgetx;
pub mod serial;

use std::fs::File;
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread;

use crate::exit::Failure;
use crate::protocol::Kind;
use crate::time::Anchor;

/// Read size for raw inputs.
pub const READ_SIZE: usize = 64 * 1024;

/// Bytes plus the times at which they arrived.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Batch {
    pub bytes: Vec<u8>,
    /// `(offset, time)`: bytes from `offset` up to the next mark arrived at `time`
    /// (µs since the capture started, `None` when the source has no time). Sorted; the first
    /// mark is at offset 0.
    pub marks: Vec<(usize, Option<u64>)>,
}

impl Batch {
    /// One run of bytes with one time.
    pub fn single(bytes: Vec<u8>, time: Option<u64>) -> Self {
        Batch {
            bytes,
            marks: vec![(0, time)],
        }
    }

    /// The batch as `(bytes, time)` segments.
    pub fn segments(&self) -> impl Iterator<Item = (&[u8], Option<u64>)> {
        self.marks
            .iter()
            .enumerate()
            .map(move |(i, &(start, time))| {
                let end = self.marks.get(i + 1).map_or(self.bytes.len(), |m| m.0);
                (&self.bytes[start..end], time)
            })
    }
}

/// What a reader thread sends.
#[derive(Debug)]
pub enum Message {
    /// The wall-clock time at the capture's start became known.
    Anchor(Anchor),
    Data(Batch),
    /// A note for the user (unreadable log lines and the like); printed on stderr.
    Warning(String),
    /// A row busnoop adds to the table itself (a time jump in a log, an event of a recording),
    /// at its place among the data.
    Note {
        micros: Option<u64>,
        /// The `Type` column.
        kind: &'static str,
        class: crate::row::Class,
        data: String,
        /// The data before and after do not join (a time jump, lost data): frames still open
        /// are closed first, as at the end of the input.
        gap: bool,
    },
    /// The adapter disappeared (live capture with `--reconnect`, or a recording of one).
    LinkDown {
        micros: u64,
    },
    /// The adapter is back, at `path`.
    LinkUp {
        micros: u64,
        path: PathBuf,
    },
    /// The source ended normally.
    End,
    /// The source failed.
    Failed(Failure),
}

/// Something that yields batches; runs inside the reader thread.
pub trait ChunkReader: Send {
    /// The next batch, or `None` at the end of the input.
    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Batch>, Failure>;
}

/// Bytes read at most to tell the kinds apart (leading blank lines of a log included).
pub const DETECT_LEN: usize = 256;

/// Decides what `prefix` (the first bytes of the input) is. With fewer than [`DETECT_LEN`]
/// bytes the answer may change as more arrive, unless `complete` says there are no more.
pub fn detect(prefix: &[u8], complete: bool) -> Option<Kind> {
    const PCAP: [[u8; 4]; 4] = [
        [0xD4, 0xC3, 0xB2, 0xA1],
        [0xA1, 0xB2, 0xC3, 0xD4],
        [0x4D, 0x3C, 0xB2, 0xA1],
        [0xA1, 0xB2, 0x3C, 0x4D],
    ];
    if prefix.len() >= 4 {
        if PCAP.iter().any(|m| prefix[..4] == m[..]) {
            if prefix.len() < 24 && !complete {
                return None;
            }
            return Some(match crate::record::pcap_link_type(prefix) {
                Some(crate::record::LINKTYPE_RTAC_SERIAL | crate::record::LINKTYPE_USER0) => {
                    Kind::Recording
                }
                _ => Kind::Pcap,
            });
        }
        if prefix[..4] == [0x0A, 0x0D, 0x0D, 0x0A] {
            return Some(Kind::Pcapng);
        }
    }
    match edgetx::looks_like_log(prefix) {
        Some(true) => Some(Kind::EdgeTxLog),
        Some(false) => Some(Kind::Raw),
        None if complete => Some(Kind::Raw),
        None => None,
    }
}

/// The SOURCE argument.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Input {
    Stdin,
    File(PathBuf),
    /// A serial device (a character device, or a path that looks like one).
    Device(PathBuf),
}

impl Input {
    /// Any OS path (not only UTF-8); `-` is standard input.
    pub fn parse(arg: &Path) -> Input {
        if arg.as_os_str() == "-" {
            return Input::Stdin;
        }
        let path = arg.to_path_buf();
        if serial::is_device_path(&path) {
            Input::Device(path)
        } else {
            Input::File(path)
        }
    }
}

/// An opened input with its first bytes already read for detection.
pub struct Opened {
    pub kind: Kind,
    pub prefix: Vec<u8>,
    pub reader: Box<dyn Read + Send>,
    pub name: String,
}

/// Opens a file or standard input and detects its kind.
pub fn open(input: &Input) -> Result<Opened, Failure> {
    let (mut reader, name, path): (Box<dyn Read + Send>, String, Option<&Path>) = match input {
        Input::Stdin => (Box::new(io::stdin()), "standard input".into(), None),
        Input::File(p) | Input::Device(p) => {
            let meta = std::fs::metadata(p).map_err(|e| Failure::from_input_io(p, &e))?;
            if meta.is_dir() {
                return Err(Failure::IsDirectory(p.clone()));
            }
            let f = File::open(p).map_err(|e| Failure::from_input_io(p, &e))?;
            (Box::new(f), p.display().to_string(), Some(p.as_path()))
        }
    };
    let mut prefix = Vec::with_capacity(DETECT_LEN);
    let mut buf = [0u8; DETECT_LEN];
    let kind = loop {
        if let Some(k) = detect(&prefix, false) {
            break k;
        }
        if prefix.len() >= DETECT_LEN {
            break detect(&prefix, true).unwrap_or(Kind::Raw);
        }
        let want = DETECT_LEN - prefix.len();
        match reader.read(&mut buf[..want]) {
            Ok(0) => break detect(&prefix, true).unwrap_or(Kind::Raw),
            Ok(n) => prefix.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => {
                return Err(match path {
                    Some(p) => Failure::from_input_io(p, &e),
                    None => Failure::Input(format!("cannot read standard input: {e}")),
                });
            }
        }
    };
    Ok(Opened {
        kind,
        prefix,
        reader,
        name,
    })
}

/// Reads raw bytes without time.
pub struct RawReader {
    prefix: Option<Vec<u8>>,
    reader: Box<dyn Read + Send>,
    name: String,
}

impl RawReader {
    pub fn new(opened: Opened) -> Self {
        RawReader {
            prefix: Some(opened.prefix).filter(|p| !p.is_empty()),
            reader: opened.reader,
            name: opened.name,
        }
    }
}

impl ChunkReader for RawReader {
    fn next_batch(&mut self, _tx: &SyncSender<Message>) -> Result<Option<Batch>, Failure> {
        if let Some(p) = self.prefix.take() {
            return Ok(Some(Batch::single(p, None)));
        }
        let mut buf = vec![0u8; READ_SIZE];
        loop {
            match self.reader.read(&mut buf) {
                Ok(0) => return Ok(None),
                Ok(n) => {
                    buf.truncate(n);
                    return Ok(Some(Batch::single(buf, None)));
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Failure::Input(format!("cannot read {}: {e}", self.name))),
            }
        }
    }
}

/// Runs `reader` in a thread; batches arrive on the returned channel, followed by `End` or
/// `Failed`. The channel is bounded so a fast reader waits for the decoder.
pub fn spawn(mut reader: Box<dyn ChunkReader>) -> Receiver<Message> {
    let (tx, rx) = sync_channel(16);
    thread::Builder::new()
        .name("busnoop-reader".into())
        .spawn(move || {
            loop {
                match reader.next_batch(&tx) {
                    Ok(Some(b)) => {
                        if tx.send(Message::Data(b)).is_err() {
                            return;
                        }
                    }
                    Ok(None) => {
                        let _ = tx.send(Message::End);
                        return;
                    }
                    Err(f) => {
                        let _ = tx.send(Message::Failed(f));
                        return;
                    }
                }
            }
        })
        .expect("spawn reader thread");
    rx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_by_content() {
        assert_eq!(
            detect(b"2014-07-11,22:41:01.340: 7E 00\n", false),
            Some(Kind::EdgeTxLog)
        );
        assert_eq!(detect(&[0x7E, 0x00, 0x7E, 0xA1], false), Some(Kind::Raw));
        let mut pcap = vec![0xD4, 0xC3, 0xB2, 0xA1];
        assert_eq!(detect(&pcap, false), None, "needs the link type");
        assert_eq!(detect(&pcap, true), Some(Kind::Pcap));
        pcap.extend_from_slice(&[0; 16]);
        pcap.extend_from_slice(&1u32.to_le_bytes());
        assert_eq!(detect(&pcap, false), Some(Kind::Pcap));
        pcap[20] = 250;
        assert_eq!(detect(&pcap, false), Some(Kind::Recording));
        assert_eq!(detect(&[0x0A, 0x0D, 0x0D, 0x0A], false), Some(Kind::Pcapng));
        assert_eq!(detect(b"2014-07", false), None);
        assert_eq!(detect(b"2014-07", true), Some(Kind::Raw));
        assert_eq!(detect(b"", true), Some(Kind::Raw));
    }

    #[test]
    fn segments_split_at_marks() {
        let b = Batch {
            bytes: vec![1, 2, 3, 4],
            marks: vec![(0, Some(5)), (1, None), (3, Some(9))],
        };
        let segs: Vec<_> = b.segments().collect();
        assert_eq!(
            segs,
            [
                (&[1u8][..], Some(5)),
                (&[2, 3][..], None),
                (&[4][..], Some(9))
            ]
        );
    }
}
