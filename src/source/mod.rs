//! Sources: where bytes come from, with their arrival times.
//!
//! A source runs in its own reader thread and hands [`Batch`]es of bytes (or, for captures of
//! network traffic, [`capture::Captured`] packets) to the decoder over a bounded channel, so
//! memory stays flat however large the capture is. Input files and standard input are
//! recognised by their content, not by their name ([`detect`]); containers (EdgeTX logs,
//! recordings, pcap and pcapng) are opened here, so decoders see bytes or packets with their
//! times, and the capture's start comes as [`Message::Anchor`].

pub mod capture;
pub mod edgetx;
pub mod logic;
pub mod recording;
pub mod serial;

use std::fs::File;
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TryRecvError, sync_channel};
use std::thread;
use std::time::Duration;

use crate::exit::Failure;
use crate::protocol::InputKind;
use crate::time::Anchor;

/// Read size for files and streams (a read of a pipe or a port returns what is there, so
/// this size adds no delay). Large enough that a reader thread sharing one core with the
/// decoder hands over few batches (each a wake-up and a switch between the two), small enough
/// that a batch stays in the cache: 256 KiB took 6 % less CPU time than 64 KiB on one core
/// (Ether-S-Bus to TSV, issue 16), 1 MiB more than 256 KiB.
pub const READ_SIZE: usize = 256 * 1024;

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

    /// Its first `n` bytes (all of it when shorter), with their times.
    pub fn prefix(&self, n: usize) -> Batch {
        let n = n.min(self.bytes.len());
        Batch {
            bytes: self.bytes[..n].to_vec(),
            marks: self
                .marks
                .iter()
                .copied()
                .filter(|&(at, _)| at < n || at == 0)
                .collect(),
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

/// What a reader yields: bytes with their times, or packets of a capture.
#[derive(Debug)]
pub enum Chunk {
    Bytes(Batch),
    Packets(capture::Captured),
}

impl From<Batch> for Chunk {
    fn from(b: Batch) -> Self {
        Chunk::Bytes(b)
    }
}

impl From<Chunk> for Message {
    fn from(c: Chunk) -> Self {
        match c {
            Chunk::Bytes(b) => Message::Data(b),
            Chunk::Packets(p) => Message::Packets(p),
        }
    }
}

/// What a reader thread sends.
#[derive(Debug)]
pub enum Message {
    /// The wall-clock time at the capture's start became known.
    Anchor(Anchor),
    Data(Batch),
    /// Packets of a capture of network traffic, with their times.
    Packets(capture::Captured),
    /// The capture container is broken here (pcap/pcapng): no packets follow.
    CaptureError(crate::pcap::PcapError),
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
    /// Sent by [`spawn`] after each `Data` or `Packets` of a file or stream: the input had been
    /// read up to this many bytes when that batch was made (its bytes and everything before
    /// them).
    ReadUpTo(u64),
    /// The source ended normally.
    End,
    /// The source failed.
    Failed(Failure),
}

/// The row for the first of a run of packets or records stamped outside the calendar
/// ([`crate::pcap::in_calendar`]: a flipped bit, a wrong `if_tsresol`): it says so, at the time
/// of the packet before, which those packets get too.
pub fn time_out_of_range(ts_micros: i64, micros: Option<u64>) -> Message {
    Message::Note {
        micros,
        kind: crate::row::kind::TIME_JUMP,
        class: crate::row::Class::Warning,
        data: format!(
            "time stamp out of range ({} s since 1970, outside the years 1 to 9999): a corrupt \
             capture; its packets are shown at the time of the packet before",
            ts_micros.div_euclid(1_000_000)
        ),
        gap: false,
    }
}

/// The row for bytes of a capture the reader skipped right before a packet
/// ([`crate::pcap::Packet::skipped`]): a damaged record header, after which it resynchronised
/// at the next plausible record, or a packet it could not place.
pub fn skipped_note(bytes: u64, micros: Option<u64>) -> Message {
    Message::Note {
        micros,
        kind: crate::row::kind::GARBAGE,
        class: crate::row::Class::Error,
        data: format!(
            "{} of the capture skipped: a damaged record (or a packet of an interface that \
             cannot be placed); read on from the next plausible record",
            crate::exit::count(bytes, "byte", "bytes")
        ),
        // What was skipped may have held the rest of an open frame.
        gap: true,
    }
}

/// The warning at the end of a capture the reader had to skip parts of.
pub fn skipped_warning(name: &str, (bytes, times): (u64, u64)) -> Option<Message> {
    (bytes > 0).then(|| {
        Message::Warning(format!(
            "{name}: damaged capture: {} skipped in {}, each time read on from the next \
             plausible record",
            crate::exit::count(bytes, "byte", "bytes"),
            crate::exit::count(times, "place", "places")
        ))
    })
}

/// Something that yields batches; runs inside the reader thread.
pub trait ChunkReader: Send {
    /// The next batch, or `None` at the end of the input. Other messages (the anchor, notes,
    /// warnings) go straight to `tx`, before the batch they precede.
    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Chunk>, Failure>;

    /// How many batches the reader may be ahead of the decoder. Files and streams: one, of up
    /// to [`READ_SIZE`] bytes, which bounds the memory the queue holds (reading a batch takes
    /// a small part of the time decoding it does, so a deeper queue gained nothing measurable
    /// and cost 1 MB of peak memory). A live port
    /// reads a few bytes at a time and must not wait (its buffer would overflow): it says
    /// more.
    fn ahead(&self) -> usize {
        1
    }
}

/// Bytes read at most to tell the kinds apart (leading blank lines of a log included).
pub const DETECT_LEN: usize = 256;

/// Decides what `prefix` (the first bytes of the input) is. With fewer than [`DETECT_LEN`]
/// bytes the answer may change as more arrive, unless `complete` says there are no more.
pub fn detect(prefix: &[u8], complete: bool) -> Option<InputKind> {
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
            use crate::pcap::linktype::{RTAC_SERIAL, USER0};
            return Some(match crate::pcap::link_type(prefix) {
                Some(RTAC_SERIAL | USER0) => InputKind::Recording,
                _ => InputKind::Pcap,
            });
        }
        if prefix[..4] == [0x0A, 0x0D, 0x0D, 0x0A] {
            // A pcapng whose first interface is a serial line is a busnoop recording
            // (`--record FILE.pcapng`), not network traffic.
            use crate::pcap::linktype::{RTAC_SERIAL, USER0};
            return match crate::pcap::pcapng_first_interface(prefix) {
                Ok(Some(RTAC_SERIAL | USER0)) => Some(InputKind::Recording),
                Ok(_) => Some(InputKind::Pcapng),
                Err(crate::pcap::NeedMore) if complete || prefix.len() >= DETECT_LEN => {
                    Some(InputKind::Pcapng)
                }
                Err(crate::pcap::NeedMore) => None,
            };
        }
    }
    // Logic-analyzer traces: a zip (sigrok session), a VCD keyword, a Saleae CSV header.
    match logic::recognise(prefix, complete || prefix.len() >= DETECT_LEN) {
        Some(Some(_)) => return Some(InputKind::Trace),
        Some(None) => {}
        None => return None,
    }
    match edgetx::looks_like_log(prefix) {
        Some(true) => Some(InputKind::EdgeTxLog),
        Some(false) => Some(InputKind::Raw),
        None if complete => Some(InputKind::Raw),
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
    pub kind: InputKind,
    pub prefix: Vec<u8>,
    pub reader: Box<dyn Read + Send>,
    pub name: String,
}

/// How far a file or stream has been read, shared with the reader thread.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    /// Bytes read from the input so far (detection prefix included).
    read: Arc<AtomicU64>,
    /// The input's size, when it is a regular file.
    pub size: Option<u64>,
}

impl Progress {
    /// Bytes read from the input so far.
    pub fn read(&self) -> u64 {
        self.read.load(Ordering::Relaxed)
    }
}

/// A reader that counts the bytes it hands out.
struct Counted {
    inner: Box<dyn Read + Send>,
    read: Arc<AtomicU64>,
}

impl Read for Counted {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }
}

/// Opens a file or standard input and detects its kind. A FIFO is opened without waiting for
/// its writer, and every wait for the first bytes (a FIFO without a writer yet, a silent pipe)
/// ends on SIGINT/SIGTERM with [`Failure::Signal`] (see [`wait_readable`]).
pub fn open(input: &Input) -> Result<(Opened, Progress), Failure> {
    use std::os::fd::AsFd;
    // A duplicate of the descriptor to wait on (a FIFO or a pipe), so that the reader can own
    // the original.
    let dup = |fd: std::os::fd::BorrowedFd<'_>| fd.try_clone_to_owned().ok();
    let (reader, name, path, size, fd): (Box<dyn Read + Send>, String, Option<&Path>, _, _) =
        match input {
            Input::Stdin => {
                crate::files::protect_stdin();
                (
                    Box::new(io::stdin()),
                    "standard input".into(),
                    None,
                    regular_size(io::stdin().as_fd()),
                    dup(io::stdin().as_fd()),
                )
            }
            Input::File(p) | Input::Device(p) => {
                let meta = std::fs::metadata(p).map_err(|e| Failure::from_input_io(p, &e))?;
                if meta.is_dir() {
                    return Err(Failure::IsDirectory(p.clone()));
                }
                let f = open_file(p, &meta).map_err(|e| Failure::from_input_io(p, &e))?;
                // No output may be opened onto it, whatever its name by then.
                let f = crate::files::protect(f);
                let size = meta.is_file().then_some(meta.len());
                let fd = if meta.is_file() { None } else { dup(f.as_fd()) };
                (
                    Box::new(f),
                    p.display().to_string(),
                    Some(p.as_path()),
                    size,
                    fd,
                )
            }
        };
    let progress = Progress {
        read: Arc::default(),
        size,
    };
    let mut reader: Box<dyn Read + Send> = Box::new(Counted {
        inner: reader,
        read: progress.read.clone(),
    });
    let fail = |e: io::Error| match (crate::signal::Stop::received(), path) {
        (Some(sig), _) => Failure::Signal(crate::exit::Interrupt::new(sig)),
        (None, Some(p)) => Failure::from_input_io(p, &e),
        (None, None) => Failure::Input(format!("cannot read standard input: {e}")),
    };
    let mut prefix = Vec::with_capacity(DETECT_LEN);
    let mut buf = [0u8; DETECT_LEN];
    let kind = loop {
        if let Some(k) = detect(&prefix, false) {
            break k;
        }
        if prefix.len() >= DETECT_LEN {
            break detect(&prefix, true).unwrap_or(InputKind::Raw);
        }
        if let Some(fd) = &fd {
            wait_readable(fd.as_fd()).map_err(fail)?;
        }
        let want = DETECT_LEN - prefix.len();
        match reader.read(&mut buf[..want]) {
            Ok(0) => break detect(&prefix, true).unwrap_or(InputKind::Raw),
            Ok(n) => prefix.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(fail(e)),
        }
    };
    Ok((
        Opened {
            kind,
            prefix,
            reader,
            name,
        },
        progress,
    ))
}

/// The size of descriptor `fd` when it is a regular file (standard input redirected from one).
fn regular_size(fd: std::os::fd::BorrowedFd<'_>) -> Option<u64> {
    use nix::sys::stat::{SFlag, fstat};
    let st = fstat(fd).ok()?;
    if SFlag::from_bits_truncate(st.st_mode) & SFlag::S_IFMT != SFlag::S_IFREG {
        return None;
    }
    // What is left from the current offset (`busnoop - < file` starts at 0).
    let pos = nix::unistd::lseek(fd, 0, nix::unistd::Whence::SeekCur).unwrap_or(0);
    Some((st.st_size as u64).saturating_sub(pos.max(0) as u64))
}

/// Opens `path` for reading. A FIFO is opened non-blocking (a plain open waits for a writer
/// inside the kernel, where no signal can end it), then set back to blocking reads; the wait
/// for its writer is then [`wait_readable`]'s.
fn open_file(path: &Path, meta: &std::fs::Metadata) -> io::Result<File> {
    use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
    if !meta.file_type().is_fifo() {
        return File::open(path);
    }
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)?;
    crate::files::set_blocking(&f)?;
    Ok(f)
}

/// How often a wait for input looks for a signal.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Waits until a read of `fd` will not block: data, end of input or an error. A FIFO without a
/// writer would read as empty at once, but poll() waits in that case ("no writer yet" is not
/// the end of the input; POLLHUP comes only after a writer has opened and closed it). The
/// signal handlers restart interrupted reads, so this is what lets SIGINT/SIGTERM end the wait
/// (with an `Interrupted` error; the caller reports the signal).
fn wait_readable(fd: std::os::fd::BorrowedFd<'_>) -> io::Result<()> {
    use nix::poll::{PollFd, PollFlags, poll};
    loop {
        if crate::signal::Stop::received().is_some() {
            return Err(io::Error::new(
                io::ErrorKind::Interrupted,
                "stopped by a signal",
            ));
        }
        let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
        match poll(&mut fds, SIGNAL_POLL.as_millis() as u16) {
            Ok(n) if n > 0 => return Ok(()),
            Ok(_) | Err(nix::errno::Errno::EINTR) => {}
            Err(e) => return Err(e.into()),
        }
    }
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
    fn next_batch(&mut self, _tx: &SyncSender<Message>) -> Result<Option<Chunk>, Failure> {
        if let Some(p) = self.prefix.take() {
            return Ok(Some(Batch::single(p, None).into()));
        }
        let mut buf = vec![0u8; READ_SIZE];
        loop {
            match self.reader.read(&mut buf) {
                Ok(0) => return Ok(None),
                Ok(n) => {
                    buf.truncate(n);
                    return Ok(Some(Batch::single(buf, None).into()));
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Failure::Input(format!("cannot read {}: {e}", self.name))),
            }
        }
    }
}

/// An opened source: its kind, its reader, and for files and streams how far it was read.
pub type Reading = (InputKind, Box<dyn ChunkReader>, Option<Progress>);

/// The receiving end of a reader thread.
pub struct Feed {
    rx: Receiver<Message>,
    /// Messages taken by [`Feed::anchor`] before the driver runs, handed on first.
    early: std::cell::RefCell<std::collections::VecDeque<Message>>,
    /// Set by the driver when it stops: the reader thread reads no more.
    halt: Arc<AtomicBool>,
    /// For files and streams: how far the input was read.
    pub progress: Option<Progress>,
}

impl Feed {
    /// Tells the reader thread to stop reading (it finishes the read it is in, if any).
    pub fn halt(&self) {
        self.halt.store(true, Ordering::Relaxed);
    }

    /// The next message, waiting at most `timeout`.
    pub fn recv_timeout(&self, timeout: Duration) -> Result<Message, RecvTimeoutError> {
        match self.early.borrow_mut().pop_front() {
            Some(m) => Ok(m),
            None => self.rx.recv_timeout(timeout),
        }
    }

    /// The next message if one is there.
    pub fn try_recv(&self) -> Result<Message, TryRecvError> {
        match self.early.borrow_mut().pop_front() {
            Some(m) => Ok(m),
            None => self.rx.try_recv(),
        }
    }

    /// The wall-clock time of the input's start, when it has one: waits for the reader's first
    /// messages up to its first data (warnings may come first), keeping them for the driver.
    /// `None` for an input without one (raw bytes), and when `stop` is set meanwhile (the
    /// driver then ends on the signal).
    pub fn anchor(&self, stop: &crate::signal::Stop) -> Option<Anchor> {
        loop {
            let m = match self.rx.recv_timeout(Duration::from_millis(20)) {
                Ok(m) => m,
                Err(RecvTimeoutError::Timeout) if stop.signal().is_none() => continue,
                Err(_) => return None,
            };
            let found = match &m {
                Message::Anchor(a) => Some(Some(*a)),
                Message::Warning(_) => None,
                _ => Some(None),
            };
            self.early.borrow_mut().push_back(m);
            if let Some(a) = found {
                return a;
            }
        }
    }
}

impl Drop for Feed {
    fn drop(&mut self) {
        self.halt();
    }
}

/// Runs `reader` in a thread; batches (`Data`, `Packets`) arrive on the returned feed, each
/// followed by `ReadUpTo` when `progress` is given, then `End` or `Failed`. The channel is
/// bounded ([`ChunkReader::ahead`] batches) so a fast reader waits for the decoder; once the
/// feed halts, the thread reads nothing more.
pub fn spawn(mut reader: Box<dyn ChunkReader>, progress: Option<Progress>) -> Feed {
    // Room for each batch's `ReadUpTo` too.
    let (tx, rx) = sync_channel(reader.ahead().max(1) * 2);
    let halt = Arc::new(AtomicBool::new(false));
    let feed = Feed {
        rx,
        early: Default::default(),
        halt: halt.clone(),
        progress: progress.clone(),
    };
    thread::Builder::new()
        .name("busnoop-reader".into())
        .spawn(move || {
            while !halt.load(Ordering::Relaxed) {
                match reader.next_batch(&tx) {
                    Ok(Some(c)) => {
                        if tx.send(c.into()).is_err() {
                            return;
                        }
                        if let Some(p) = &progress
                            && tx.send(Message::ReadUpTo(p.read())).is_err()
                        {
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
    feed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_by_content() {
        assert_eq!(
            detect(b"2014-07-11,22:41:01.340: 7E 00\n", false),
            Some(InputKind::EdgeTxLog)
        );
        assert_eq!(
            detect(&[0x7E, 0x00, 0x7E, 0xA1], false),
            Some(InputKind::Raw)
        );
        let mut pcap = vec![0xD4, 0xC3, 0xB2, 0xA1];
        assert_eq!(detect(&pcap, false), None, "needs the link type");
        assert_eq!(detect(&pcap, true), Some(InputKind::Pcap));
        pcap.extend_from_slice(&[0; 16]);
        pcap.extend_from_slice(&1u32.to_le_bytes());
        assert_eq!(detect(&pcap, false), Some(InputKind::Pcap));
        pcap[20] = 250;
        assert_eq!(detect(&pcap, false), Some(InputKind::Recording));
        // pcapng: the first interface's link type tells a recording from network traffic.
        assert_eq!(detect(&[0x0A, 0x0D, 0x0D, 0x0A], false), None);
        assert_eq!(
            detect(&[0x0A, 0x0D, 0x0D, 0x0A], true),
            Some(InputKind::Pcapng)
        );
        let mut ng = Vec::new();
        crate::pcap::write_ng::section_header(&mut ng);
        assert_eq!(detect(&ng, false), None);
        let mut other = ng.clone();
        crate::pcap::write_ng::packet(&mut other, 0, 0, b"x", None);
        assert_eq!(detect(&other, false), Some(InputKind::Pcapng));
        let mut eth = ng.clone();
        crate::pcap::write_ng::interface(&mut eth, 1, None, None);
        assert_eq!(detect(&eth, false), Some(InputKind::Pcapng));
        crate::pcap::write_ng::interface(&mut ng, 250, Some("/dev/ttyUSB0"), None);
        assert_eq!(detect(&ng, false), Some(InputKind::Recording));
        // Logic-analyzer traces: a zip (sigrok session), a VCD, a Saleae export.
        assert_eq!(detect(b"PK\x03\x04\x14\x00", false), Some(InputKind::Trace));
        assert_eq!(
            detect(b"$timescale 1 us $end", false),
            Some(InputKind::Trace)
        );
        assert_eq!(detect(b"$times", false), None);
        assert_eq!(
            detect(b"Time [s],Channel 0\n0,1\n", false),
            Some(InputKind::Trace)
        );
        assert_eq!(
            detect(b"Time [s],Value,Parity", false),
            Some(InputKind::Trace)
        );
        assert_eq!(detect(b"$GPGGA,1", true), Some(InputKind::Raw));
        assert_eq!(detect(b"2014-07", false), None);
        assert_eq!(detect(b"2014-07", true), Some(InputKind::Raw));
        assert_eq!(detect(b"", true), Some(InputKind::Raw));
    }

    #[test]
    fn a_prefix_keeps_the_times_of_its_bytes() {
        let b = Batch {
            bytes: vec![1, 2, 3, 4, 5],
            marks: vec![(0, Some(10)), (2, Some(20)), (4, Some(30))],
        };
        let p = b.prefix(3);
        assert_eq!(p.bytes, [1, 2, 3]);
        let segs: Vec<_> = p.segments().map(|(s, t)| (s.to_vec(), t)).collect();
        assert_eq!(segs, [(vec![1, 2], Some(10)), (vec![3], Some(20))]);
        assert_eq!(b.prefix(99), b);
        assert_eq!(b.prefix(0).segments().count(), 1);
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
