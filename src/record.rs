//! Recordings: what came off the wire, kept while decoding (`--record FILE`). They are read
//! back by [`crate::source::recording`].
//!
//! * `FILE.pcap`: classic pcap, link type `RTAC_SERIAL` (250, [`crate::pcap::rtac`]), one record
//!   per read chunk with the chunk's arrival time, so a replay feeds the decoder exactly the bytes
//!   and times the live run saw and prints exactly the same rows. Each record carries the 12-byte
//!   RTAC serial header (time, event type, control lines), which Wireshark shows as "RTAC
//!   Serial". The first record (a status event, time 0 of the capture) marks the start; adapter
//!   unplug/replug are status events too.
//! * `FILE.pcapng`: the same RTAC serial records in pcapng: a section header naming busnoop, an
//!   interface description whose `if_name` is the device (or input file) and whose
//!   `if_description` names the protocol and baud rate, and one enhanced packet block per read
//!   chunk with its arrival time. Adapter unplug/replug records carry a comment (`opt_comment`)
//!   that Wireshark shows on the packet: where a reconnect gap starts and how long it lasted. It
//!   replays to the same rows as the `.pcap`. A run with several sources (`busnoop PROTO SRC1
//!   SRC2`) records one interface per port, named by its source, each with its own start record;
//!   its records go on the interface of their port ([`Recorder::describe_port`],
//!   [`Recorder::port_data`]), and a replay reads each interface as a port again.
//! * `FILE.bin` or `FILE.raw`: the raw bytes exactly as received, the same format as a raw
//!   capture (no times). So does a name without an extension that is a device or a FIFO
//!   (`/dev/null`); any other name is refused ([`RecordFormat::for_path`]), so that a typo never
//!   writes a format the user did not ask for.
//!
//! A network capture (pcap or pcapng input, [`Content::Packets`]) is recorded as its packets:
//! the input's link type, each packet's time, bytes and length on the wire, so that the
//! recording replays to the same rows and Wireshark shows the same traffic. `FILE.pcap` is a
//! classic pcap as tcpdump writes it (snap length 262144), `FILE.pcapng` a section header
//! naming busnoop, an interface description per interface of the input and enhanced packet
//! blocks. A nanosecond capture keeps its nanoseconds (a nanosecond pcap, `if_tsresol` 9).
//! Raw bytes cannot hold packets: `.bin` and `.raw` are refused for them ([`format_for`]), and
//! `--record -` (or a device or FIFO named without an extension) writes the packets as classic
//! pcap, as `tcpdump -w -` does.

use std::io;
use std::path::{Path, PathBuf};

use chrono::{DateTime, Utc};

use crate::exit::Failure;
use crate::pcap::{self, Packet, linktype, rtac};
use crate::row::OutputError;
use crate::sink::Output;
use crate::time::Anchor;

/// The pcapng `if_description` of a line: `FrSky S.Port, 57600 baud 8N1`.
pub fn line_description(protocol: &str, line: &crate::protocol::Line) -> String {
    use crate::protocol::Parity;
    let parity = match line.parity {
        Parity::None => 'N',
        Parity::Odd => 'O',
        Parity::Even => 'E',
    };
    format!(
        "{protocol}, {} baud {}{parity}{}",
        line.baud, line.data_bits, line.stop_bits
    )
}

/// Writes a recording while the capture is decoded.
pub struct Recorder {
    /// `None` for standard output.
    path: Option<PathBuf>,
    /// Whole records only: a full disk leaves the file ending with its last whole record.
    out: Output,
    format: RecordFormat,
    content: Content,
    anchor: Option<DateTime<Utc>>,
    /// The pcap record being written.
    scratch: Vec<u8>,
    /// The lines recorded: the device (or input) and its description, for the pcapng interface
    /// block, and whether its bytes have times; one per port, in port order (none: one
    /// unnamed line).
    lines: Vec<Described>,
    /// When each port's adapter went away (µs of the capture), for the gap's comment.
    down_since: Vec<Option<u64>>,
    /// Packets: the interfaces described so far (a pcapng's interface ID is the position here;
    /// a classic pcap has the one of its header). Empty until the first packet.
    links: Vec<Link>,
    /// Packets: the capture's link type as its headers told, for the header of a recording of
    /// a capture without packets.
    link_type: Option<u32>,
    /// Packets: a packet a classic pcap cannot hold (another link type than its header's) was
    /// left out; the user is told once.
    left_out: bool,
    /// A warning for the user, once (see [`Recorder::take_warning`]).
    warning: Option<String>,
}

/// A line of a recording: its pcapng `if_name` and `if_description`, and whether its bytes
/// have arrival times.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Described {
    name: Option<String>,
    description: Option<String>,
    timed: bool,
}

/// What a recording holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    /// The bytes of a serial line (or of a file or stream of them), with their arrival times
    /// when `timed`.
    Line { timed: bool },
    /// The packets of a network capture (a pcap or pcapng input).
    Packets,
}

impl Content {
    /// The format of `--record -`: a line's raw bytes, a capture's packets as classic pcap.
    fn on_stdout(self) -> RecordFormat {
        match self {
            Content::Line { .. } => RecordFormat::Raw,
            Content::Packets => RecordFormat::Pcap,
        }
    }
}

/// An interface of a recording of packets: the input's interface (its pcapng interface ID),
/// link type and whether its time stamps are finer than microseconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Link {
    interface: u32,
    link_type: u32,
    nanos: bool,
}

impl Link {
    fn of(p: &Packet<'_>) -> Link {
        Link {
            interface: p.interface,
            link_type: p.link_type,
            nanos: p.nanos.is_some(),
        }
    }
}

/// The format of a recording, from its file name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordFormat {
    Raw,
    Pcap,
    Pcapng,
}

/// The file names `--record` knows, for messages and help.
pub const KNOWN: &str = ".pcap (classic pcap with arrival times), .pcapng (pcapng with arrival \
                         times, device and baud), .bin or .raw (the raw bytes)";

impl RecordFormat {
    /// The format for `path` by its extension (any case); a name without an extension is raw
    /// bytes only when it is an existing device or FIFO (`/dev/null`). Anything else is a usage
    /// error naming the known extensions.
    pub fn for_path(path: &Path) -> Result<RecordFormat, Failure> {
        let ext = path.extension().and_then(|e| e.to_str());
        let is = |x: &str| ext.is_some_and(|e| e.eq_ignore_ascii_case(x));
        if is("pcap") {
            return Ok(RecordFormat::Pcap);
        }
        if is("pcapng") {
            return Ok(RecordFormat::Pcapng);
        }
        if is("bin") || is("raw") {
            return Ok(RecordFormat::Raw);
        }
        if ext.is_none() && std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
            return Ok(RecordFormat::Raw);
        }
        let what = match path.extension() {
            Some(e) => format!("the extension .{}", e.to_string_lossy()),
            None => "a name without an extension".to_string(),
        };
        Err(Failure::Usage(format!(
            "--record {}: {what} names no recording format; use {KNOWN}",
            path.display()
        )))
    }
}

/// The format of a recording of `content` at `path` (`None`: standard output): by the name
/// ([`RecordFormat::for_path`]); on standard output a line's raw bytes, or a capture's packets
/// as classic pcap (what `tcpdump -w -` writes, for the same pipes), and so on a device or FIFO
/// named without an extension (`--record >(tshark -r -)`). Packets have no raw form: `.bin`
/// or `.raw` for them is a usage error that names the formats that hold them, before anything
/// is written.
pub fn format_for(path: Option<&Path>, content: Content) -> Result<RecordFormat, Failure> {
    let format = match path {
        Some(p) => RecordFormat::for_path(p)?,
        None => content.on_stdout(),
    };
    if let (Some(p), RecordFormat::Raw, Content::Packets) = (path, format, content) {
        if p.extension().is_none() {
            return Ok(content.on_stdout());
        }
        return Err(Failure::Usage(format!(
            "--record {}: the input is a network capture, whose packets have no raw form; \
             record them as FILE.pcap or FILE.pcapng",
            p.display()
        )));
    }
    Ok(format)
}

impl Recorder {
    /// Creates the recording of `content` (its format checked first, `format_for`).
    pub fn create(path: &Path, content: Content) -> Result<Recorder, Failure> {
        let format = format_for(Some(path), content)?;
        let what = format!("cannot create recording {}", path.display());
        let out = crate::files::create_file(path)
            .and_then(|file| Output::file(file, path))
            .map_err(|e| Failure::from_create(&what, &e))?;
        Ok(Self::new(Some(path), out, format, content))
    }

    /// Records on standard output (`--record -`): a line's raw bytes, a capture's packets as
    /// classic pcap (`format_for`).
    pub fn stdout(content: Content) -> Recorder {
        Self::new(None, Output::stdout(), content.on_stdout(), content)
    }

    fn new(path: Option<&Path>, out: Output, format: RecordFormat, content: Content) -> Recorder {
        Recorder {
            path: path.map(Path::to_owned),
            out,
            format,
            content,
            anchor: None,
            scratch: Vec::new(),
            lines: Vec::new(),
            down_since: Vec::new(),
            links: Vec::new(),
            link_type: None,
            left_out: false,
            warning: None,
        }
    }

    /// Names the interface in a pcapng recording: `name` (the device path) becomes `if_name`,
    /// `description` (protocol and baud rate) `if_description`. Call before the first bytes.
    pub fn describe(&mut self, name: &str, description: &str) {
        let timed = self.content != Content::Line { timed: false };
        self.lines.clear();
        self.describe_port(name, description, timed);
    }

    /// Adds a port (several sources): the next interface of a pcapng recording, named `name`
    /// (its source) and `description`, whose bytes have times when `timed`. Its records go on
    /// that interface ([`Recorder::port_data`], [`Recorder::port_link`]). Call for every port,
    /// in port order, before the first bytes.
    pub fn describe_port(&mut self, name: &str, description: &str, timed: bool) {
        self.lines.push(Described {
            name: Some(name.to_string()),
            description: Some(description.to_string()),
            timed,
        });
    }

    /// The recording's format.
    pub fn format(&self) -> RecordFormat {
        self.format
    }

    /// A write error as the user sees it. A pipe whose reader went away (standard output, a
    /// FIFO, `--record >(tshark -r -)` and tshark quit) ends busnoop quietly, as the table's
    /// and the export's do.
    fn fail(&self, e: OutputError) -> Failure {
        let e = e.error;
        match &self.path {
            _ if e.kind() == io::ErrorKind::BrokenPipe => Failure::BrokenPipe,
            Some(p) => Failure::Output(format!("cannot write recording {}: {e}", p.display())),
            None => Failure::Output(format!(
                "cannot write the recording to standard output: {e}"
            )),
        }
    }

    /// The wall-clock time of the capture's start; writes the pcap headers of a line's
    /// recording (packets carry their own times; their headers come with the first one).
    pub fn start(&mut self, anchor: Option<Anchor>) -> Result<(), Failure> {
        let timed = match self.content {
            Content::Line { timed } => timed,
            Content::Packets => return Ok(()),
        };
        if self.anchor.is_some() {
            return Ok(());
        }
        let t = anchor.map_or_else(Utc::now, Anchor::as_utc);
        self.anchor = Some(t);
        if self.lines.is_empty() {
            self.lines.push(Described {
                name: None,
                description: None,
                timed,
            });
        }
        let mut header = Vec::with_capacity(256);
        match self.format {
            RecordFormat::Raw => return Ok(()),
            RecordFormat::Pcap => {
                pcap::write::header_with_snaplen(&mut header, linktype::RTAC_SERIAL, 65_535)
            }
            RecordFormat::Pcapng => {
                pcap::write_ng::section_header(&mut header);
                for line in &self.lines {
                    pcap::write_ng::interface(
                        &mut header,
                        linktype::RTAC_SERIAL as u16,
                        line.name.as_deref(),
                        line.description.as_deref(),
                    );
                }
            }
        }
        self.out.record(&header).map_err(|e| self.fail(e))?;
        // Each line's start: time 0 of the capture, and whether its bytes have times.
        for port in 0..self.lines.len() {
            let start = if self.lines[port].timed {
                rtac::START
            } else {
                rtac::START_UNTIMED
            };
            self.write_record(port as u32, t, 0, rtac::EVENT_STATUS, start, None)?;
        }
        Ok(())
    }

    /// Bytes that arrived at `micros`.
    pub fn data(&mut self, bytes: &[u8], micros: Option<u64>) -> Result<(), Failure> {
        self.port_data(0, bytes, micros)
    }

    /// Bytes of `port` (see [`Recorder::describe_port`]) that arrived at `micros`.
    pub fn port_data(
        &mut self,
        port: u32,
        bytes: &[u8],
        micros: Option<u64>,
    ) -> Result<(), Failure> {
        if self.content == Content::Packets {
            // Network captures come as packets only (`source::capture`).
            return Err(Failure::Internal("bytes for a recording of packets".into()));
        }
        self.start(None)?;
        let r = match self.format {
            RecordFormat::Raw => self.out.record(bytes),
            RecordFormat::Pcap | RecordFormat::Pcapng => {
                let anchor = self.anchor.unwrap_or_else(Utc::now);
                let micros = micros.unwrap_or(0);
                return self.write_record(port, anchor, micros, rtac::EVENT_RX_DATA, bytes, None);
            }
        };
        r.map_err(|e| self.fail(e))
    }

    /// The adapter went away (`up = false`) or came back.
    pub fn link(&mut self, up: bool, micros: u64) -> Result<(), Failure> {
        self.port_link(0, up, micros)
    }

    /// The adapter of `port` went away (`up = false`) or came back.
    pub fn port_link(&mut self, port: u32, up: bool, micros: u64) -> Result<(), Failure> {
        if self.format == RecordFormat::Raw || self.content == Content::Packets {
            return Ok(());
        }
        self.start(None)?;
        let at = port as usize;
        if self.down_since.len() <= at {
            self.down_since.resize(at + 1, None);
        }
        let comment = if up {
            let gap = self.down_since[at].take().map(|d| micros.saturating_sub(d));
            match gap {
                Some(g) => format!(
                    "busnoop: the adapter is back; reconnect gap of {}.{:06} s ends (bytes sent \
                     on the bus meanwhile were not seen)",
                    g / 1_000_000,
                    g % 1_000_000
                ),
                None => "busnoop: the adapter is back; reconnect gap ends".to_string(),
            }
        } else {
            self.down_since[at] = Some(micros);
            "busnoop: the adapter went away; reconnect gap begins".to_string()
        };
        let anchor = self.anchor.unwrap_or_else(Utc::now);
        // The device it is back at, so that a replay names it (not the recording).
        let mut payload = if up { rtac::LINK_UP } else { rtac::LINK_DOWN }.to_vec();
        let device = self.lines.get(at).and_then(|l| l.name.clone());
        if let (true, Some(device)) = (up, device) {
            payload.extend_from_slice(rtac::LINK_UP_AT);
            payload.extend_from_slice(device.as_bytes());
        }
        self.write_record(
            port,
            anchor,
            micros,
            rtac::EVENT_STATUS,
            &payload,
            Some(&comment),
        )
    }

    /// Writes one RTAC serial record at `micros` after `anchor` (in pcapng on the interface of
    /// `port`, with `comment`).
    fn write_record(
        &mut self,
        port: u32,
        anchor: DateTime<Utc>,
        micros: u64,
        event: u8,
        data: &[u8],
        comment: Option<&str>,
    ) -> Result<(), Failure> {
        // Plain µs arithmetic: a corrupt time cannot panic (pcap stamps hold what they can).
        let ts = (anchor.timestamp_micros()).saturating_add(micros.min(i64::MAX as u64) as i64);
        self.scratch.clear();
        if self.format == RecordFormat::Pcapng {
            let mut body = Vec::with_capacity(rtac::HEADER_LEN + data.len());
            rtac::payload(&mut body, ts, event, data);
            pcap::write_ng::packet(&mut self.scratch, port, ts, &body, comment);
        } else {
            rtac::record(&mut self.scratch, ts, event, data);
        }
        let r = self.out.record(&self.scratch);
        r.map_err(|e| self.fail(e))
    }

    /// The capture's link type as its headers told (`None`: not yet), for the header of a
    /// recording of a capture without packets ([`Recorder::finish`]).
    pub fn capture_link_type(&mut self, link_type: Option<u32>) {
        self.link_type = self.link_type.or(link_type);
    }

    /// Records a packet of a network capture: the headers first when it is the first packet
    /// (or, in pcapng, the first of its interface), then the packet, in one write so that the
    /// file never ends inside a record. A classic pcap holds one link type: a packet of another
    /// is left out, with a warning ([`Recorder::take_warning`]).
    pub fn packet(&mut self, p: &Packet<'_>) -> Result<(), Failure> {
        self.scratch.clear();
        let link = Link::of(p);
        let at = match self.format {
            RecordFormat::Pcapng => match self.links.iter().position(|l| *l == link) {
                Some(at) => at,
                None => self.describe_link(link),
            },
            RecordFormat::Pcap => match self.links.first() {
                None => self.describe_link(link),
                Some(l) if l.link_type == p.link_type => 0,
                Some(l) => {
                    self.leave_out(l.link_type, p.link_type);
                    return Ok(());
                }
            },
            // Refused by `format_for`.
            RecordFormat::Raw => return Ok(()),
        };
        let nanos = self.links.get(at).is_some_and(|l| l.nanos);
        match self.format {
            RecordFormat::Pcapng => {
                pcap::write_ng::captured(&mut self.scratch, at as u32, p, nanos)
            }
            _ => pcap::write::packet(&mut self.scratch, p, nanos),
        }
        let r = self.out.record(&self.scratch);
        r.map_err(|e| self.fail(e))
    }

    /// Appends to the scratch the headers a recording of packets needs for a new `link`: the
    /// file header (classic pcap), the section header before the first interface and the
    /// interface's description (pcapng). Returns the interface's position.
    fn describe_link(&mut self, link: Link) -> usize {
        let snaplen = pcap::write::SNAPLEN_PACKETS;
        if self.format == RecordFormat::Pcapng {
            if self.links.is_empty() {
                pcap::write_ng::section_header(&mut self.scratch);
            }
            pcap::write_ng::interface_block(
                &mut self.scratch,
                link.link_type as u16,
                snaplen,
                link.nanos,
                None,
                None,
            );
        } else {
            pcap::write::file_header(&mut self.scratch, link.link_type, snaplen, link.nanos);
        }
        self.links.push(link);
        self.links.len() - 1
    }

    /// A packet of `other` link type does not fit a classic pcap of `link_type`: the user is
    /// told once.
    fn leave_out(&mut self, link_type: u32, other: u32) {
        if !self.left_out {
            let name = self
                .path
                .as_deref()
                .map_or("-".into(), |p| p.display().to_string());
            self.warning = Some(format!(
                "--record {name}: a classic pcap holds one link type ({link_type}); packets of \
                 link type {other} are left out of it (a .pcapng recording keeps them all)"
            ));
        }
        self.left_out = true;
    }

    /// The warning to show the user, once.
    pub fn take_warning(&mut self) -> Option<String> {
        self.warning.take()
    }

    /// Writes everything buffered to the file.
    pub fn flush(&mut self) -> Result<(), Failure> {
        self.out.flush().map_err(|e| self.fail(e))
    }

    /// The end of the run: a recording of a capture without packets gets the headers of the
    /// capture's link type (a capture, like tcpdump's of a quiet interface), then everything
    /// is flushed.
    pub fn finish(&mut self) -> Result<(), Failure> {
        if self.content == Content::Packets
            && self.links.is_empty()
            && self.format != RecordFormat::Raw
            && let Some(link_type) = self.link_type
        {
            self.scratch.clear();
            self.describe_link(Link {
                interface: 0,
                link_type,
                nanos: false,
            });
            let r = self.out.record(&self.scratch);
            r.map_err(|e| self.fail(e))?;
        }
        self.flush()
    }
}

/// What the driver records through ([`crate::run::Context::recorder`]): a [`Recorder`], or one
/// port's share of one when several sources are decoded at once (`merge::PortRecorder`, which
/// puts the port's bytes on its own interface).
pub trait Keep: Send {
    /// See [`Recorder::start`].
    fn start(&mut self, anchor: Option<Anchor>) -> Result<(), Failure>;
    /// See [`Recorder::data`].
    fn data(&mut self, bytes: &[u8], micros: Option<u64>) -> Result<(), Failure>;
    /// See [`Recorder::link`].
    fn link(&mut self, up: bool, micros: u64) -> Result<(), Failure>;
    /// See [`Recorder::capture_link_type`].
    fn capture_link_type(&mut self, link_type: Option<u32>);
    /// See [`Recorder::packet`].
    fn packet(&mut self, p: &Packet<'_>) -> Result<(), Failure>;
    /// See [`Recorder::take_warning`].
    fn take_warning(&mut self) -> Option<String>;
    /// See [`Recorder::flush`].
    fn flush(&mut self) -> Result<(), Failure>;
    /// See [`Recorder::finish`].
    fn finish(&mut self) -> Result<(), Failure>;
}

impl Keep for Recorder {
    fn start(&mut self, anchor: Option<Anchor>) -> Result<(), Failure> {
        Recorder::start(self, anchor)
    }
    fn data(&mut self, bytes: &[u8], micros: Option<u64>) -> Result<(), Failure> {
        Recorder::data(self, bytes, micros)
    }
    fn link(&mut self, up: bool, micros: u64) -> Result<(), Failure> {
        Recorder::link(self, up, micros)
    }
    fn capture_link_type(&mut self, link_type: Option<u32>) {
        Recorder::capture_link_type(self, link_type)
    }
    fn packet(&mut self, p: &Packet<'_>) -> Result<(), Failure> {
        Recorder::packet(self, p)
    }
    fn take_warning(&mut self) -> Option<String> {
        Recorder::take_warning(self)
    }
    fn flush(&mut self) -> Result<(), Failure> {
        Recorder::flush(self)
    }
    fn finish(&mut self) -> Result<(), Failure> {
        Recorder::finish(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_recording_is_the_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.bin");
        let mut rec = Recorder::create(&path, Content::Line { timed: true }).unwrap();
        rec.data(&[1, 2], Some(5)).unwrap();
        rec.link(false, 6).unwrap();
        rec.data(&[3], Some(7)).unwrap();
        rec.flush().unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), [1, 2, 3]);
    }

    #[test]
    fn formats_by_extension_and_unknown_names_refused() {
        let f = |n: &str| RecordFormat::for_path(Path::new(n));
        assert_eq!(f("a.pcap").unwrap(), RecordFormat::Pcap);
        assert_eq!(f("a.PCAPNG").unwrap(), RecordFormat::Pcapng);
        assert_eq!(f("a.bin").unwrap(), RecordFormat::Raw);
        assert_eq!(f("a.Raw").unwrap(), RecordFormat::Raw);
        assert_eq!(f("/dev/null").unwrap(), RecordFormat::Raw);
        for bad in ["a.txt", "a.pcapn", "/nonexistent/recording"] {
            let Err(Failure::Usage(m)) = f(bad) else {
                panic!("{bad} accepted")
            };
            assert!(
                m.contains(".pcap (") && m.contains(".pcapng") && m.contains(".raw"),
                "{m}"
            );
        }
        assert!(
            Recorder::create(
                &std::env::temp_dir().join("busnoop-x.txt"),
                Content::Line { timed: true }
            )
            .is_err()
        );
    }

    #[test]
    fn pcapng_names_the_interface_and_comments_the_gap() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.pcapng");
        let mut rec = Recorder::create(&path, Content::Line { timed: true }).unwrap();
        rec.describe("/dev/ttyUSB0", "FrSky S.Port, 57600 baud 8N1");
        rec.start(None).unwrap();
        rec.data(&[0x7E, 0x1B], Some(5)).unwrap();
        rec.link(false, 1_000).unwrap();
        rec.link(true, 2_501_000).unwrap();
        rec.flush().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains("/dev/ttyUSB0") && text.contains("57600 baud"));
        assert!(text.contains("reconnect gap begins"), "{text}");
        assert!(text.contains("reconnect gap of 2.500000 s ends"), "{text}");
        assert_eq!(pcap::pcapng_link_type(&bytes), Some(linktype::RTAC_SERIAL));
        let mut got = Vec::new();
        let mut s = pcap::PcapStream::default();
        s.push(&bytes, &mut |p| {
            got.push(rtac::parse(p.data).map(|(e, _, d)| (e, d.to_vec())))
        })
        .unwrap();
        assert_eq!(
            got,
            [
                Some((rtac::EVENT_STATUS, rtac::START.to_vec())),
                Some((rtac::EVENT_RX_DATA, vec![0x7E, 0x1B])),
                Some((rtac::EVENT_STATUS, rtac::LINK_DOWN.to_vec())),
                Some((
                    rtac::EVENT_STATUS,
                    b"busnoop link up at /dev/ttyUSB0".to_vec()
                )),
            ]
        );
    }

    /// A packet of `link_type` on `interface`, stamped `micros` (and `nanos`).
    fn packet(interface: u32, link_type: u32, micros: i64, nanos: Option<u16>) -> Packet<'static> {
        Packet {
            ts_micros: micros,
            nanos,
            time: 0,
            link_type,
            data: b"pkt",
            orig_len: 60,
            interface,
            skipped: 0,
        }
    }

    /// Every packet of a capture: interface, link type, time (µs), bytes, length on the wire.
    fn read_back(bytes: &[u8]) -> Vec<(u32, u32, i64, Vec<u8>, u32)> {
        let mut got = Vec::new();
        let mut s = pcap::PcapStream::default();
        s.push(bytes, &mut |p| {
            got.push((
                p.interface,
                p.link_type,
                p.ts_micros,
                p.data.to_vec(),
                p.orig_len,
            ))
        })
        .unwrap();
        s.finish().unwrap();
        got
    }

    #[test]
    fn packets_of_several_interfaces_and_link_types() {
        let dir = tempfile::tempdir().unwrap();
        let packets = [
            packet(0, linktype::ETHERNET, 1_000_000, None),
            packet(1, linktype::LINUX_SLL2, 1_000_001, Some(5)),
            packet(0, linktype::ETHERNET, 1_000_002, None),
            packet(2, linktype::ETHERNET, 1_000_003, None),
        ];
        let record = |name: &str| {
            let path = dir.path().join(name);
            let mut rec = Recorder::create(&path, Content::Packets).unwrap();
            rec.start(None).unwrap();
            let mut warnings = Vec::new();
            for p in &packets {
                rec.packet(p).unwrap();
                rec.link(false, 5).unwrap();
                warnings.extend(rec.take_warning());
            }
            rec.finish().unwrap();
            (std::fs::read(&path).unwrap(), warnings)
        };
        // pcapng: an interface description for each of the input's interfaces.
        let (ng, warnings) = record("r.pcapng");
        assert!(warnings.is_empty(), "{warnings:?}");
        let want: Vec<_> = packets
            .iter()
            .map(|p| (p.interface, p.link_type, p.ts_micros, b"pkt".to_vec(), 60))
            .collect();
        assert_eq!(read_back(&ng), want);
        // pcap: the first link type only, the user told once.
        let (classic, warnings) = record("r.pcap");
        let want: Vec<_> = want
            .into_iter()
            .filter(|p| p.1 == linktype::ETHERNET)
            .map(|p| (0, p.1, p.2, p.3, p.4))
            .collect();
        assert_eq!(read_back(&classic), want);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].contains("link type 276 are left out"),
            "{}",
            warnings[0]
        );
    }

    #[test]
    fn packets_refuse_raw_and_go_to_standard_output_as_pcap() {
        let packets = Content::Packets;
        let line = Content::Line { timed: true };
        assert_eq!(format_for(None, packets).unwrap(), RecordFormat::Pcap);
        assert_eq!(format_for(None, line).unwrap(), RecordFormat::Raw);
        for name in ["a.bin", "a.raw", "/dev/null"] {
            let path = Path::new(name);
            assert_eq!(format_for(Some(path), line).unwrap(), RecordFormat::Raw);
            if name == "/dev/null" {
                // A device or FIFO is a stream, like standard output.
                assert_eq!(format_for(Some(path), packets).unwrap(), RecordFormat::Pcap);
                continue;
            }
            let Err(Failure::Usage(m)) = format_for(Some(path), packets) else {
                panic!("{name} accepted for packets")
            };
            assert!(m.contains("FILE.pcap or FILE.pcapng"), "{m}");
        }
        let pcapng = format_for(Some(Path::new("a.pcapng")), packets).unwrap();
        assert_eq!(pcapng, RecordFormat::Pcapng);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.bin");
        assert!(Recorder::create(&path, packets).is_err());
        assert!(!path.exists());
    }

    #[test]
    fn a_capture_without_packets_gets_its_header() {
        let dir = tempfile::tempdir().unwrap();
        for (name, known) in [("r.pcap", true), ("r.pcapng", true), ("n.pcap", false)] {
            let path = dir.path().join(name);
            let mut rec = Recorder::create(&path, Content::Packets).unwrap();
            rec.capture_link_type(known.then_some(linktype::LINUX_SLL));
            rec.capture_link_type(None);
            rec.finish().unwrap();
            let bytes = std::fs::read(&path).unwrap();
            let lt = pcap::link_type(&bytes).or(pcap::pcapng_link_type(&bytes));
            assert_eq!(lt, known.then_some(linktype::LINUX_SLL), "{name}");
            assert_eq!(read_back(&bytes), []);
        }
    }
}
