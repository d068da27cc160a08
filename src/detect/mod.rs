//! `busnoop detect SOURCE`: which protocol is on this wire?
//!
//! Every protocol of [`crate::protocols::PROTOCOLS`] that reads the input's kind is tried in
//! each of its variants (S-Bus modes, SAB framings, S.Port on an inverted line), each through
//! the protocol's own `decoder(...)`, on the first [`SCAN_BYTES`] of a file or on a few
//! seconds of a serial port at each usual baud rate. A variant's score is the share of the
//! input's bytes that lie inside frames with a valid check; the evidence (frames, CRC errors,
//! truncated frames, garbage, the bytes frames start with) is printed with the verdict and the
//! command to run.
//!
//! The same scoring tells a user who picked the wrong protocol ([`advise()`], after a run).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::exit::Failure;
use crate::protocol::{Decoder, InputKind, Line, Probe, Protocol};
use crate::protocols::PROTOCOLS;
use crate::row::{Class, Row, RowOut, RowResult, kind as row_kind};
use crate::source::serial::{self, ModemLines, SerialConfig};
use crate::source::{Batch, Chunk, ChunkReader, Input, Message};

/// How much of a file is examined.
pub const SCAN_BYTES: usize = 2 << 20;

/// What a run keeps of its input for [`advise()`]: enough frames of any protocol to tell them
/// apart, small enough that scoring it against every candidate after a run with problems costs
/// well under a tenth of a second (S-Bus break mode, the slowest candidate, searches CRCs).
pub const ADVICE_BYTES: usize = 16 << 10;

/// A frame-looking variant must find at least this many frames to count.
const MIN_FRAMES: u64 = 3;
/// Below this share of the bytes in valid frames, nothing is recognised.
const MIN_SHARE: f64 = 0.10;
/// A second protocol is named (a mixed input) when it covers at least this share of the bytes
/// that the first one leaves.
const MIXED_SHARE: f64 = 0.15;

/// What `busnoop detect` examines and how (the command line's `detect` options).
#[derive(Clone, Debug)]
pub struct Options {
    /// A capture file, `-` for standard input, or a serial device.
    pub source: PathBuf,
    /// Serial devices: how long to listen at each baud rate.
    pub listen_ms: u64,
    /// Serial devices: the baud rates to try (empty: the usual ones).
    pub bauds: Vec<u32>,
    /// Serial devices: DTR and RTS, as for the protocol commands.
    pub dtr_rts: ModemLines,
    /// Logic-analyzer traces: the channel to read (`--channel`).
    pub channel: Option<String>,
}

/// One way of reading the bytes: a protocol, with options.
pub struct Candidate {
    pub protocol: &'static Protocol,
    /// "S-Bus break mode".
    pub label: String,
    /// Options to add to the protocol's command for this variant.
    pub args: &'static [&'static str],
    /// The bytes are inverted (an inverted line read through an adapter that does not invert).
    pub inverted: bool,
    decoder: Box<dyn Decoder>,
}

/// The variants of every protocol that reads inputs of `kind` (each protocol's own, see
/// `Protocol::variants`), on a line of `line`'s format and speed, or on each protocol's own
/// line when `line` is `None` (files). A protocol whose line is inverted is also tried on the
/// bytes inverted, as a plain adapter reads them.
pub fn candidates(kind: InputKind, line: Option<Line>) -> Vec<Candidate> {
    let mut out = Vec::new();
    let byte_stream = matches!(
        kind,
        InputKind::Raw | InputKind::Serial | InputKind::Recording
    );
    for &p in PROTOCOLS {
        // A line read in another character format gives this protocol nothing but noise.
        if !p.reads(kind) || line.is_some_and(|l| !l.same_format(&p.line)) {
            continue;
        }
        let line = line.unwrap_or(p.line);
        let probe = Probe { input: kind, line };
        let flip = p.inverted && byte_stream;
        for inverted in [false, true] {
            if inverted && !flip {
                continue;
            }
            for v in (p.variants)(&probe) {
                out.push(Candidate {
                    protocol: p,
                    label: if inverted {
                        format!("{}, inverted line", v.label)
                    } else {
                        v.label.to_owned()
                    },
                    args: v.args,
                    inverted,
                    decoder: v.decoder,
                });
            }
        }
    }
    out
}

/// The evidence for one candidate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Score {
    /// Frames with a valid check.
    pub frames: u64,
    /// Bytes inside those frames.
    pub valid_bytes: u64,
    /// The bytes examined.
    pub total: u64,
    pub crc_errors: u64,
    pub truncated: u64,
    /// Bytes inside frames with a bad check or cut short.
    pub bad_bytes: u64,
    pub garbage_bytes: u64,
    /// The first byte of valid frames, most frequent first, with counts (at most 3).
    pub starts: Vec<(u8, u64)>,
    /// Packets of a network capture: one valid packet is evidence enough.
    pub network: bool,
}

impl Score {
    /// Share of the examined bytes inside valid frames (0 to 1).
    pub fn share(&self) -> f64 {
        if self.total == 0 {
            0.0
        } else {
            (self.valid_bytes as f64 / self.total as f64).min(1.0)
        }
    }

    /// Enough valid frames to mean something.
    fn recognised(&self) -> bool {
        let min = if self.network { 1 } else { MIN_FRAMES };
        self.frames >= min && self.share() >= MIN_SHARE
    }
}

/// A candidate after the scan.
pub struct Ranked {
    pub protocol: &'static Protocol,
    pub label: String,
    pub args: &'static [&'static str],
    pub inverted: bool,
    pub score: Score,
    /// Which bytes (by position) lay inside valid frames.
    coverage: Vec<u64>,
    /// The channel of a logic-analyzer trace that was read (`--channel`), for the command.
    pub channel: Option<String>,
}

impl Ranked {
    /// Bytes this candidate covers that `other` does not.
    fn beyond(&self, other: &Ranked) -> u64 {
        self.coverage
            .iter()
            .zip(other.coverage.iter().chain(std::iter::repeat(&0)))
            .map(|(a, b)| u64::from((a & !b).count_ones()))
            .sum()
    }

    /// The command that decodes this, for `source`.
    pub fn command(&self, source: &Path, baud: Option<u32>) -> String {
        let mut s = format!("busnoop {}", self.protocol.command);
        for a in self.args {
            s.push(' ');
            s.push_str(a);
        }
        if let Some(b) = baud.filter(|&b| b != self.protocol.line.baud) {
            s.push_str(&format!(" --baud {b}"));
        }
        if let Some(c) = &self.channel {
            s.push_str(" --channel ");
            s.push_str(&shell_quote(Path::new(c)));
        }
        s.push(' ');
        s.push_str(&shell_quote(source));
        s
    }
}

/// Counts the rows of one candidate.
struct Tally {
    score: Score,
    starts: [u64; 256],
    /// Position in the input of the next row's bytes.
    cursor: u64,
    coverage: Vec<u64>,
}

impl Tally {
    fn new(total: u64) -> Self {
        Tally {
            score: Score {
                total,
                ..Score::default()
            },
            starts: [0; 256],
            cursor: 0,
            coverage: vec![0; (total as usize).div_ceil(64)],
        }
    }

    fn finish(mut self) -> (Score, Vec<u64>) {
        let mut starts: Vec<(u8, u64)> = (0..=255u8)
            .map(|b| (b, self.starts[b as usize]))
            .filter(|&(_, n)| n > 0)
            .collect();
        starts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        starts.truncate(3);
        self.score.starts = starts;
        (self.score, self.coverage)
    }
}

impl RowOut for Tally {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        let n = row.raw.len() as u64;
        let s = &mut self.score;
        match row.kind {
            row_kind::BAD_CRC => {
                s.crc_errors += 1;
                s.bad_bytes += n;
            }
            row_kind::TRUNCATED => {
                s.truncated += 1;
                s.bad_bytes += n;
            }
            row_kind::GARBAGE => s.garbage_bytes += n,
            _ => {}
        }
        let valid = n > 0 && !matches!(row.class, Class::Error | Class::Info);
        if valid {
            s.frames += 1;
            s.valid_bytes += n;
            self.starts[row.raw[0] as usize] += 1;
            for i in self.cursor..(self.cursor + n).min(s.total) {
                self.coverage[(i / 64) as usize] |= 1 << (i % 64);
            }
        }
        self.cursor += n;
        Ok(())
    }
}

/// Feeds `segments` (bytes with their times) through every candidate and ranks them, best
/// first. `total` is the number of bytes for the share (the wire bytes; for network captures,
/// where the file holds more than the payloads, the payload bytes the decoder saw).
pub fn rank(mut candidates: Vec<Candidate>, batches: &[Batch], kind: InputKind) -> Vec<Ranked> {
    let wire: u64 = batches.iter().map(|b| b.bytes.len() as u64).sum();
    let network = matches!(kind, InputKind::Pcap | InputKind::Pcapng);
    let mut ranked: Vec<Ranked> = candidates
        .drain(..)
        .map(|mut c| {
            let mut tally = Tally::new(if network { 0 } else { wire });
            let mut flipped = Vec::new();
            for b in batches {
                for (bytes, time) in b.segments() {
                    let bytes = if c.inverted {
                        flipped.clear();
                        flipped.extend(bytes.iter().map(|b| !b));
                        &flipped[..]
                    } else {
                        bytes
                    };
                    let _ = c.decoder.push(bytes, time, &mut tally);
                }
            }
            let _ = c.decoder.finish(&mut tally);
            if network {
                // The payloads: every one is in exactly one row.
                tally.score.total = tally.cursor;
                tally.score.network = true;
            }
            let (score, coverage) = tally.finish();
            Ranked {
                protocol: c.protocol,
                label: c.label,
                args: c.args,
                inverted: c.inverted,
                score,
                coverage,
                channel: None,
            }
        })
        .collect();
    ranked.sort_by(|a, b| {
        b.score
            .share()
            .total_cmp(&a.score.share())
            .then(b.score.frames.cmp(&a.score.frames))
    });
    ranked
}

/// What the scan concluded.
#[derive(Debug, PartialEq)]
pub enum Verdict {
    /// No bytes at all.
    Empty,
    /// Nothing decodes well enough.
    Unknown,
    /// The best candidate (index into the ranking), and a second protocol that covers bytes
    /// the first leaves, when the input is mixed.
    Found(usize, Option<usize>),
}

/// The verdict on a ranking.
pub fn verdict(ranked: &[Ranked]) -> Verdict {
    let Some(best) = ranked.first() else {
        return Verdict::Unknown;
    };
    if best.score.total == 0 {
        return Verdict::Empty;
    }
    if !best.score.recognised() {
        return Verdict::Unknown;
    }
    let mixed = ranked.iter().enumerate().skip(1).find(|(_, r)| {
        r.protocol.command != best.protocol.command
            && r.score.recognised()
            && r.beyond(best) as f64 >= MIXED_SHARE * r.score.total as f64
    });
    Verdict::Found(0, mixed.map(|(i, _)| i))
}

fn percent(share: f64) -> String {
    let p = share * 100.0;
    if p > 0.0 && p < 0.1 {
        "<0.1%".into()
    } else {
        format!("{p:.1}%")
    }
}

/// `7E ×30, 00 ×2`.
fn starts_text(starts: &[(u8, u64)]) -> String {
    let parts: Vec<String> = starts
        .iter()
        .map(|(b, n)| format!("{b:02X} ×{n}"))
        .collect();
    if parts.is_empty() {
        "-".into()
    } else {
        parts.join(", ")
    }
}

/// The evidence table, one line per candidate (the label column as wide as the longest label).
pub fn evidence(ranked: &[Ranked]) -> String {
    let w = ranked
        .iter()
        .map(|r| r.label.chars().count())
        .max()
        .unwrap_or(0)
        .max(24);
    let mut s = format!(
        "  {:<w$} {:>9} {:>8} {:>7} {:>9} {:>8}  {}\n",
        "candidate", "in frames", "frames", "CRC err", "truncated", "garbage", "frames start with"
    );
    for r in ranked {
        let sc = &r.score;
        s.push_str(&format!(
            "  {:<w$} {:>9} {:>8} {:>7} {:>9} {:>8}  {}\n",
            r.label,
            percent(sc.share()),
            sc.frames,
            sc.crc_errors,
            sc.truncated,
            sc.garbage_bytes,
            starts_text(&sc.starts)
        ));
    }
    s
}

/// The fix for an inverted line read without inversion, with the byte that gave it away (the
/// most frequent first byte of the frames found once the bytes were inverted back).
pub fn inverted_fix(r: &Ranked) -> String {
    let seen = match r.score.starts.first() {
        Some(&(b, _)) => format!(
            "0x{:02X} arrives where {}'s 0x{b:02X} belongs, ",
            !b, r.protocol.name
        ),
        None => String::new(),
    };
    format!(
        "the line is inverted: {seen}so the adapter does not invert. Set \"invert RXD\" on an \
         FTDI adapter (FT_PROG, or `ftdi_eeprom`), or put a one-transistor inverter before RX \
         (docs/live.md)"
    )
}

/// The input's kind and its first [`SCAN_BYTES`] (fewer when it ends), and the signal that cut
/// the reading short: SIGINT/SIGTERM end the wait of a slow pipe (`cat /dev/ttyUSB0 | busnoop
/// detect -`), and what arrived is judged.
fn read_prefix(
    input: &Input,
    trace: &crate::source::logic::Options,
) -> Result<(InputKind, Vec<Batch>, Option<i32>), Failure> {
    let stop = crate::signal::Stop::install()
        .map_err(|e| Failure::Internal(format!("cannot install signal handlers: {e}")))?;
    let (opened, progress) = crate::source::open(input)?;
    let kind = opened.kind;
    let reader: Box<dyn ChunkReader> = match kind {
        InputKind::EdgeTxLog => Box::new(crate::source::edgetx::EdgeTxReader::new(opened)),
        InputKind::Recording => Box::new(crate::source::recording::RecordingReader::new(opened)),
        InputKind::Trace => crate::source::logic::reader(opened, trace)?,
        _ => Box::new(crate::source::RawReader::new(opened)),
    };
    let feed = crate::source::spawn(reader, Some(progress));
    let mut batches = Vec::new();
    let mut bytes = 0;
    let signal = loop {
        if let Some(sig) = stop.signal() {
            // What arrived before the signal is judged too.
            while let Ok(Message::Data(b)) = feed.try_recv() {
                batches.push(b);
            }
            break Some(sig);
        }
        match feed.recv_timeout(Duration::from_millis(50)) {
            Ok(Message::Data(b)) => {
                bytes += b.bytes.len();
                batches.push(b);
                if bytes >= SCAN_BYTES {
                    break None;
                }
            }
            Ok(Message::End) | Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break None,
            Ok(Message::Failed(f)) => return Err(f),
            Ok(_) | Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
        }
    };
    feed.halt();
    Ok((kind, batches, signal))
}

fn kind_text(kind: InputKind) -> &'static str {
    match kind {
        InputKind::Raw => "raw bytes",
        InputKind::EdgeTxLog => "an EdgeTX/OpenTX S.Port log",
        InputKind::Pcap | InputKind::Pcapng => "a network capture",
        InputKind::Recording => "a busnoop recording",
        InputKind::Serial => "a serial line",
        InputKind::Trace => "a logic-analyzer trace",
    }
}

/// What the first megabytes of a file or pipe say: its kind, every candidate ranked, the bytes
/// examined and the signal that cut the reading short.
struct Scan {
    kind: InputKind,
    ranked: Vec<Ranked>,
    examined: u64,
    signal: Option<i32>,
}

/// Ranks every candidate on the start of `input`. A logic-analyzer trace is read through the
/// software UART once per character format of the protocols (the rate measured), each
/// protocol's candidates on the bytes of its own format; standard input can be read once only,
/// so there the first format is tried.
fn scan(input: &Input, channel: Option<&str>) -> Result<Scan, Failure> {
    let mut formats: Vec<Line> = Vec::new();
    for p in PROTOCOLS {
        if p.reads(InputKind::Trace) && !formats.iter().any(|f| f.same_format(&p.line)) {
            formats.push(p.line);
        }
    }
    let trace = |line: Line| crate::source::logic::Options {
        line,
        baud: None,
        channel: channel.map(str::to_owned),
    };
    let first = formats.first().copied().unwrap_or(Line::n81(115_200));
    let (kind, batches, signal) = read_prefix(input, &trace(first))?;
    let examined = batches.iter().map(|b| b.bytes.len() as u64).sum();
    if kind != InputKind::Trace {
        let ranked = rank(candidates(kind, None), &batches, kind);
        return Ok(Scan {
            kind,
            ranked,
            examined,
            signal,
        });
    }
    let of_format = |f: &Line| {
        candidates(kind, None)
            .into_iter()
            .filter(|c| c.protocol.line.same_format(f))
            .collect::<Vec<_>>()
    };
    let mut ranked = rank(of_format(&first), &batches, kind);
    for f in formats.iter().skip(1) {
        if signal.is_some() || matches!(input, Input::Stdin) {
            break;
        }
        let (_, batches, _) = read_prefix(input, &trace(*f))?;
        ranked.extend(rank(of_format(f), &batches, kind));
    }
    ranked.sort_by(|a, b| {
        b.score
            .share()
            .total_cmp(&a.score.share())
            .then(b.score.frames.cmp(&a.score.frames))
    });
    for r in &mut ranked {
        r.channel = channel.map(str::to_owned);
    }
    Ok(Scan {
        kind,
        ranked,
        examined,
        signal,
    })
}

/// The protocol of a file or pipe (`busnoop plot` without `--protocol`): the detect verdict on
/// its first megabytes, with the options of the variant found.
pub fn protocol_of(source: &Path) -> Result<(&'static Protocol, &'static [&'static str]), Failure> {
    let input = Input::parse(source);
    let Scan { ranked, signal, .. } = scan(&input, None)?;
    if let Some(sig) = signal {
        return Err(Failure::Signal(crate::exit::Interrupt::new(sig)));
    }
    let name = source.display();
    match verdict(&ranked) {
        Verdict::Found(i, _) => Ok((ranked[i].protocol, ranked[i].args)),
        _ => Err(Failure::NoProtocol(format!(
            "no known protocol in {name}; name it with --protocol {} (busnoop detect {name} \
             shows the evidence)",
            crate::protocols::commands()
        ))),
    }
}

/// Runs `busnoop detect`.
pub fn run(args: &Options) -> Result<(), Failure> {
    let input = Input::parse(&args.source);
    if let Input::Device(path) = &input {
        match live(path, args) {
            Err(LiveError::NotATty) => {}
            Err(LiveError::Failed(f)) => return Err(f),
            Ok(heard) => {
                crate::exit::write_stdout(heard.text.as_bytes())?;
                return heard.result.map(|_| ());
            }
        }
    }
    let examined = examine(&input, &args.source, args.channel.as_deref())?;
    crate::exit::write_stdout(examined.text.as_bytes())?;
    if let Some(sig) = examined.signal {
        eprintln!(
            "busnoop: interrupted after {} bytes; the verdict is on them",
            examined.bytes
        );
        return Err(Failure::Signal(crate::exit::Interrupt::new(sig)));
    }
    examined.result.map(|_| ())
}

/// A detection's report (what `busnoop detect` prints) and its outcome: the winner, or the
/// failure that says why there is none.
struct Report {
    text: String,
    result: Result<Chosen, Failure>,
    /// Files and pipes: the bytes examined, and the signal that cut the reading short.
    bytes: u64,
    signal: Option<i32>,
}

/// What `busnoop SOURCE` (no subcommand) decodes as: the detect verdict's winner.
#[derive(Clone, Debug)]
pub struct Chosen {
    pub protocol: &'static Protocol,
    /// The variant's options (`--mode parity`).
    pub args: &'static [&'static str],
    /// A live port: the speed it was heard at.
    pub baud: Option<u32>,
    /// Its label ("S-Bus parity mode").
    pub label: String,
    /// Why: "100.0% of the bytes in 30 valid frames".
    pub why: String,
    /// The bytes are inverted: not decodable as they are.
    pub inverted: bool,
    /// Another protocol fits about as well, or the input is mixed: the second one's label.
    pub rival: Option<String>,
}

impl Chosen {
    fn of(r: &Ranked, baud: Option<u32>) -> Chosen {
        Chosen {
            protocol: r.protocol,
            args: r.args,
            baud,
            label: r.label.clone(),
            why: format!(
                "{} of the bytes in {}",
                percent(r.score.share()),
                crate::exit::count(r.score.frames, "valid frame", "valid frames")
            ),
            inverted: r.inverted,
            rival: None,
        }
    }
}

/// A candidate of another protocol this close (share of the bytes) to the winner makes the
/// verdict too weak for `busnoop SOURCE` to decode on its own.
const RIVAL_MARGIN: f64 = 0.05;

/// Detects the protocol of `source` for `busnoop SOURCE`: a file's first megabytes, or a serial
/// port listened to at each usual speed (`bauds` when given). `Ok` with the winner, which
/// may still be unusable as it is (inverted bytes, a rival); `Err` with the detect report
/// printed on stderr when nothing fits.
pub fn choose(source: &Path, bauds: &[u32], dtr_rts: ModemLines) -> Result<Chosen, Failure> {
    let input = Input::parse(source);
    let report = match &input {
        Input::Device(path) => {
            let args = Options {
                source: source.to_owned(),
                listen_ms: 1500,
                bauds: bauds.to_vec(),
                dtr_rts,
                channel: None,
            };
            match live(path, &args) {
                Ok(heard) => Some(Report {
                    text: heard.text,
                    result: heard.result,
                    bytes: 0,
                    signal: None,
                }),
                Err(LiveError::NotATty) => None,
                Err(LiveError::Failed(f)) => return Err(f),
            }
        }
        _ => None,
    };
    let report = match report {
        Some(r) => r,
        None => examine(&input, source, None)?,
    };
    if let Some(sig) = report.signal {
        return Err(Failure::Signal(crate::exit::Interrupt::new(sig)));
    }
    let unusable = match &report.result {
        Ok(c) => c.inverted || c.rival.is_some(),
        Err(Failure::NoProtocol(_)) => true,
        Err(_) => false,
    };
    if unusable {
        use std::io::Write as _;
        let _ = std::io::stderr().write_all(report.text.as_bytes());
    }
    report.result
}

/// `busnoop detect` on a file or pipe: reads its start, ranks the candidates, writes the
/// report.
fn examine(input: &Input, source: &Path, channel: Option<&str>) -> Result<Report, Failure> {
    let Scan {
        kind,
        ranked,
        examined,
        signal,
    } = scan(input, channel)?;
    let name = source.display();
    let mut text = format!(
        "{name}: {}, {} examined{}\n",
        kind_text(kind),
        crate::exit::count(examined, "byte", "bytes"),
        if examined as usize >= SCAN_BYTES {
            " (the start of the input)"
        } else {
            ""
        }
    );
    let v = if examined == 0 {
        Verdict::Empty
    } else {
        verdict(&ranked)
    };
    if v != Verdict::Empty {
        text.push_str(&evidence(&ranked));
    }
    let result = match v {
        Verdict::Empty => Err(Failure::NothingDecoded(advise::empty_input(
            &name.to_string(),
            kind,
        ))),
        Verdict::Unknown => {
            text.push_str("verdict: no known protocol");
            match ranked.first() {
                Some(b) if b.score.frames > 0 => text.push_str(&format!(
                    " (at best {} of the bytes in {} {} frames)",
                    percent(b.score.share()),
                    b.score.frames,
                    b.label
                )),
                _ => text.push_str(" (not one valid frame of any)"),
            }
            text.push('\n');
            Err(Failure::NoProtocol(format!(
                "no known protocol in {name}: another protocol, a capture made at the wrong \
                 baud rate, or not a capture at all"
            )))
        }
        Verdict::Found(i, mixed) => {
            let best = &ranked[i];
            found_text(&mut text, best, source, None);
            let mut chosen = Chosen::of(best, None);
            if let Some(j) = mixed {
                let other = &ranked[j];
                text.push_str(&format!(
                    "also: {} in {} of the bytes ({} frames): the input is mixed\nrun:  {}\n",
                    other.label,
                    percent(other.beyond(best) as f64 / other.score.total.max(1) as f64),
                    other.score.frames,
                    other.command(source, None)
                ));
                chosen.rival = Some(other.label.clone());
            } else if let Some(r) = ranked.iter().find(|r| {
                r.protocol.command != best.protocol.command
                    && r.score.recognised()
                    && r.score.share() + RIVAL_MARGIN >= best.score.share()
            }) {
                chosen.rival = Some(r.label.clone());
            }
            Ok(chosen)
        }
    };
    Ok(Report {
        text,
        result,
        bytes: examined,
        signal,
    })
}

/// "verdict: …" and "run: …" for the winner.
fn found_text(text: &mut String, best: &Ranked, source: &Path, baud: Option<u32>) {
    let at = baud.map_or(String::new(), |b| format!(" at {b} baud"));
    text.push_str(&format!(
        "verdict: {}{at} ({} of the bytes in {} valid frames",
        best.label,
        percent(best.score.share()),
        best.score.frames
    ));
    if best.score.crc_errors > 0 {
        text.push_str(", ");
        text.push_str(&crate::exit::count(
            best.score.crc_errors,
            "CRC error",
            "CRC errors",
        ));
    }
    text.push_str(")\n");
    if best.inverted {
        text.push_str(&format!("fix:  {}\n", inverted_fix(best)));
        if baud.is_none() {
            text.push_str(
                "      this capture holds the inverted bytes; invert them back before decoding: \
                 python3 -c \"import sys; sys.stdout.buffer.write(bytes(255 - b for b in \
                 sys.stdin.buffer.read()))\" < CAPTURE > fixed.bin\n",
            );
        }
        text.push_str(&format!("then: {}\n", best.command(source, baud)));
    } else {
        text.push_str(&format!("run:  {}\n", best.command(source, baud)));
    }
}

enum LiveError {
    /// A character device that is not a terminal: read it as a file.
    NotATty,
    Failed(Failure),
}

/// A path as a shell word: as it is when it holds only safe characters, else single-quoted.
pub fn shell_quote(p: &Path) -> String {
    let s = p.to_string_lossy();
    if !s.is_empty()
        && s.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"/._-+,:@%=".contains(&b))
    {
        s.into_owned()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

mod advise;
mod live;

pub use advise::{Advice, Tee, advise};
use live::live;

#[cfg(test)]
mod tests;
