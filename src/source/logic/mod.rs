//! Logic-analyzer traces as sources: sigrok sessions (`.sr`), VCD, Saleae Logic CSV exports of
//! digital transitions ([`sr`], [`vcd`], [`saleae`]) read through the software UART
//! ([`uart`]), and Saleae's async-serial analyzer exports ([`saleae_serial`]), which already
//! hold characters with their times.
//!
//! Every character comes out with the exact time its start bit began (µs since the trace's
//! time 0), one batch mark per character. Framing and parity errors and breaks become rows
//! (`LineEvent`, as a busnoop recording's RTAC line events do) at their character, which is
//! still handed on (a break as 0x00, as a Linux tty reads one).
//!
//! The reader picks the channel (`--channel NAME|N`, else the only channel, else the only one
//! that changes level), reads ahead up to [`LOOKAHEAD`] of its edges to find the idle level
//! (low: an inverted line, said on stderr) and to measure the bit rate from the shortest
//! pulses (used when the protocol's default rate does not fit, said on stderr; `--baud` wins),
//! then streams: memory stays flat however long the trace.

pub mod saleae;
pub mod saleae_serial;
pub mod sr;
mod text;
pub mod uart;
pub mod vcd;
#[cfg(any(test, feature = "selfcheck"))]
pub mod write;

pub use text::{Lines, parse_seconds, split_fields};

use std::collections::VecDeque;
use std::io::{self, Read};
use std::sync::mpsc::SyncSender;

use super::{Batch, Chunk, ChunkReader, Message, Opened};
use crate::exit::{Failure, count};
use crate::protocol::Line;
use uart::{Event, TimeBase, Uart};

/// The container formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    /// A sigrok session file (a zip: `metadata`, `logic-1-N` sample chunks).
    Sigrok,
    /// Value change dump.
    Vcd,
    /// Saleae Logic CSV export of digital transitions (`Time [s],Channel 0,…`).
    SaleaeDigital,
    /// Saleae's async-serial analyzer export: characters with times.
    SaleaeSerial,
}

/// What the input is, from its first bytes: `None` when more are needed to tell (and
/// `complete` says more may come), `Some(None)` when it is no trace.
pub fn recognise(prefix: &[u8], complete: bool) -> Option<Option<Container>> {
    let need_more = if complete { Some(None) } else { None };
    if prefix.len() < 4 {
        return if b"PK\x03\x04".starts_with(prefix) && !prefix.is_empty() {
            need_more
        } else {
            text_trace(prefix, complete)
        };
    }
    if prefix[..4] == *b"PK\x03\x04" {
        return Some(Some(Container::Sigrok));
    }
    text_trace(prefix, complete)
}

/// VCD and the Saleae CSV exports, by their first word or header line.
fn text_trace(prefix: &[u8], complete: bool) -> Option<Option<Container>> {
    let need_more = if complete { Some(None) } else { None };
    const BOM: &[u8] = b"\xEF\xBB\xBF";
    if prefix.len() < BOM.len() && BOM.starts_with(prefix) {
        return need_more;
    }
    let text = prefix.strip_prefix(BOM).unwrap_or(prefix);
    let Some(start) = text.iter().position(|b| !b.is_ascii_whitespace()) else {
        return need_more;
    };
    let text = &text[start..];
    if text[0] == b'$' {
        const WORDS: [&[u8]; 8] = [
            b"date",
            b"version",
            b"timescale",
            b"comment",
            b"scope",
            b"var",
            b"enddefinitions",
            b"dumpvars",
        ];
        let word_end = text[1..].iter().position(|b| b.is_ascii_whitespace());
        let Some(end) = word_end else {
            return if text.len() < 16 {
                need_more
            } else {
                Some(None)
            };
        };
        return Some(WORDS.contains(&&text[1..1 + end]).then_some(Container::Vcd));
    }
    // The header line of a Saleae export, up to the second field.
    let line_end = text.iter().position(|&b| b == b'\n').unwrap_or(text.len());
    let line = &text[..line_end];
    let whole = line_end < text.len() || complete;
    const LOGIC2_TABLE: &[u8] = b"name,type,start_time,duration,data";
    if line.starts_with(LOGIC2_TABLE) {
        return Some(Some(Container::SaleaeSerial));
    }
    let mut fields = line.split(|&b| b == b',');
    let first = trim(fields.next().unwrap_or_default());
    let time_column = matches!(first, b"Time [s]" | b"Time[s]");
    if !time_column {
        let could_be = [&b"Time [s]"[..], b"Time[s]", LOGIC2_TABLE]
            .iter()
            .any(|h| h.starts_with(line) && !line.is_empty());
        return if could_be && !whole {
            need_more
        } else {
            Some(None)
        };
    }
    match fields.next() {
        Some(second) if second.len() >= 5 || whole || fields.clone().next().is_some() => {
            Some(Some(if trim(second) == b"Value" {
                Container::SaleaeSerial
            } else {
                Container::SaleaeDigital
            }))
        }
        None if whole => Some(None),
        _ => need_more,
    }
}

/// `field` without surrounding blanks and double quotes.
fn trim(field: &[u8]) -> &[u8] {
    let f = field.trim_ascii();
    f.strip_prefix(b"\"")
        .and_then(|f| f.strip_suffix(b"\""))
        .unwrap_or(f)
}

/// How to read a trace (from the command line and the protocol).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Options {
    /// The protocol's line: data bits, parity, stop bits and its default baud rate.
    pub line: Line,
    /// `--baud`: this rate, not measured.
    pub baud: Option<u32>,
    /// `--channel NAME|N`.
    pub channel: Option<String>,
}

impl Options {
    /// The protocol's line; the rate measured, the channel found.
    #[cfg(any(test, feature = "selfcheck"))]
    pub fn new(line: Line) -> Self {
        Options {
            line,
            baud: None,
            channel: None,
        }
    }
}

/// One channel of a trace.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Channel {
    /// Its number for `--channel N`: the probe's bit in a sigrok sample, the column or the
    /// variable's place otherwise.
    pub number: usize,
    pub name: String,
}

/// What a container says before its samples.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Header {
    pub channels: Vec<Channel>,
    pub base: TimeBase,
    /// The sample rate (Hz), when the container has one.
    pub sample_rate: Option<u64>,
}

/// A level change: channel `slot` (its place in the selection) is at `high` from `tick` on. The
/// first edge of each channel is its level at the start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    pub tick: u64,
    pub slot: u16,
    pub high: bool,
}

/// What a read of a trace gives after its edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Every edge before this tick has been handed out.
    Upto(u64),
    /// The trace ends at this tick.
    End(u64),
}

/// A container of sampled levels.
pub trait Wave: Send {
    fn header(&self) -> &Header;
    /// The channels whose edges `read` hands out (places in `header().channels`); a channel
    /// kept from the previous selection goes on from its level, a new one starts with its
    /// level at its next read.
    fn select(&mut self, channels: &[usize]);
    /// Appends the next edges (a bounded number) to `out`.
    fn read(&mut self, out: &mut Vec<Edge>) -> Result<Step, Failure>;
}

/// A character with its time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Char {
    /// µs since the trace's time 0: the start of its start bit.
    pub micros: u64,
    pub value: u8,
    pub framing: bool,
    pub parity: bool,
    /// A break (read as 0x00) that lasted this many µs.
    pub brk: Option<u64>,
}

/// Something that yields characters: a wave through the UART, or an analyzer export.
pub trait Chars: Send {
    /// Appends the next characters (a bounded number) to `out`; `false` at the end. Notes for
    /// stderr go to `tx`.
    fn read(&mut self, out: &mut VecDeque<Char>, tx: &SyncSender<Message>)
    -> Result<bool, Failure>;
    /// What the reader ignored or guessed, for a warning at the end.
    fn summary(&self) -> Vec<String> {
        Vec::new()
    }
}

/// A batch is handed on at the latest when it holds this many characters.
const BATCH_CHARS: usize = 16 * 1024;

/// Reads of the trace that yield no character before an empty batch is handed on.
const QUIET_READS: usize = 16;

/// Streams a trace's characters as batches and their line errors as rows.
pub struct TraceReader {
    chars: Box<dyn Chars>,
    name: String,
    queue: VecDeque<Char>,
    ended: bool,
    /// A failure after some characters: reported once they are handed on.
    failure: Option<Failure>,
    framing: u64,
    parity: u64,
    breaks: u64,
}

impl TraceReader {
    fn new(chars: Box<dyn Chars>, name: String) -> Self {
        TraceReader {
            chars,
            name,
            queue: VecDeque::new(),
            ended: false,
            failure: None,
            framing: 0,
            parity: 0,
            breaks: 0,
        }
    }

    /// The row for a character with a line error, if it has one.
    fn note(&mut self, c: &Char) -> Option<Message> {
        let data = if let Some(us) = c.brk {
            self.breaks += 1;
            format!("break on the line ({})", millis(us))
        } else {
            self.framing += u64::from(c.framing);
            self.parity += u64::from(c.parity);
            let what = match (c.framing, c.parity) {
                (false, false) => return None,
                (true, false) => "framing error",
                (false, true) => "parity error",
                (true, true) => "framing and parity error",
            };
            format!("{what} (character 0x{:02X})", c.value)
        };
        Some(Message::Note {
            micros: Some(c.micros),
            kind: "LineEvent",
            class: crate::row::Class::Warning,
            data,
            gap: false,
        })
    }

    fn summary(&mut self, tx: &SyncSender<Message>) {
        let mut parts: Vec<String> = [
            (self.framing, "framing error", "framing errors"),
            (self.parity, "parity error", "parity errors"),
            (self.breaks, "break", "breaks"),
        ]
        .iter()
        .filter(|(n, ..)| *n > 0)
        .map(|&(n, one, many)| count(n, one, many))
        .collect();
        if !parts.is_empty() {
            let last = parts.len() - 1;
            parts[last].push_str(" (each is a row in the table)");
        }
        parts.extend(self.chars.summary());
        if !parts.is_empty() {
            let _ = tx.send(Message::Warning(format!(
                "{}: {}",
                self.name,
                parts.join("; ")
            )));
        }
    }

    /// Fills `batch` until it is worth sending, a line error's row must go out between its
    /// characters, or the trace ends.
    fn fill(&mut self, tx: &SyncSender<Message>, batch: &mut Batch) -> Result<(), Failure> {
        let mut reads = 0;
        loop {
            let Some(c) = self.queue.front().copied() else {
                // A long quiet stretch comes back empty now and then, so that progress and a
                // stop are seen.
                if !batch.bytes.is_empty() || self.ended || reads == QUIET_READS {
                    return Ok(());
                }
                reads += 1;
                self.ended = !self.chars.read(&mut self.queue, tx)?;
                continue;
            };
            if batch.bytes.len() >= BATCH_CHARS {
                return Ok(());
            }
            if c.framing || c.parity || c.brk.is_some() {
                if !batch.bytes.is_empty() {
                    return Ok(());
                }
                if let Some(note) = self.note(&c) {
                    let _ = tx.send(note);
                }
            }
            self.queue.pop_front();
            batch.marks.push((batch.bytes.len(), Some(c.micros)));
            batch.bytes.push(c.value);
        }
    }
}

/// `12.345 ms`.
fn millis(us: u64) -> String {
    format!("{}.{:03} ms", us / 1000, us % 1000)
}

impl ChunkReader for TraceReader {
    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Chunk>, Failure> {
        if let Some(f) = self.failure.take() {
            self.summary(tx);
            return Err(f);
        }
        let mut batch = Batch::default();
        match self.fill(tx, &mut batch) {
            // Characters, or none yet from a quiet stretch of the trace.
            Ok(()) if !batch.bytes.is_empty() || !self.ended || !self.queue.is_empty() => {
                Ok(Some(Chunk::Bytes(batch)))
            }
            Ok(()) => {
                self.summary(tx);
                Ok(None)
            }
            Err(f) if !batch.bytes.is_empty() => {
                self.failure = Some(f);
                Ok(Some(Chunk::Bytes(batch)))
            }
            Err(f) => {
                self.summary(tx);
                Err(f)
            }
        }
    }
}

/// The reader for a trace (recognised by [`recognise`]): its container's reader, through the
/// software UART where it holds levels.
pub fn reader(opened: Opened, opts: &Options) -> Result<Box<dyn ChunkReader>, Failure> {
    let container = recognise(&opened.prefix, true)
        .flatten()
        .ok_or_else(|| Failure::Input(format!("{}: not a logic-analyzer trace", opened.name)))?;
    let name = opened.name.clone();
    let chars: Box<dyn Chars> = match container {
        Container::SaleaeSerial => Box::new(saleae_serial::SerialCsv::new(opened, opts)),
        Container::Sigrok => Box::new(UartChars::new(
            Box::new(sr::SrWave::open(opened)?),
            opts,
            &name,
        )),
        Container::Vcd => Box::new(UartChars::new(
            Box::new(vcd::VcdWave::open(opened)?),
            opts,
            &name,
        )),
        Container::SaleaeDigital => Box::new(UartChars::new(
            Box::new(saleae::DigitalCsv::open(opened)?),
            opts,
            &name,
        )),
    };
    Ok(Box::new(TraceReader::new(chars, name)))
}

/// Edges of the chosen channel read ahead before decoding starts, to find its idle level and
/// its bit rate.
pub const LOOKAHEAD: usize = 2048;

/// Edges of all channels read ahead at most to find the one that changes level.
const LOOKAHEAD_ALL: usize = 64 * 1024;

/// A wave's chosen channel through the software UART.
pub struct UartChars {
    wave: Box<dyn Wave>,
    opts: Options,
    name: String,
    /// `None` until the channel, its idle level and its rate are settled.
    uart: Option<Uart>,
    base: TimeBase,
    /// Edges read ahead, not yet decoded.
    held: VecDeque<Edge>,
    /// Where the read-ahead stopped.
    held_step: Option<Step>,
    edges: Vec<Edge>,
    events: Vec<Event>,
    /// The channel's name, for messages.
    channel: String,
    cut: bool,
    done: bool,
}

impl UartChars {
    fn new(wave: Box<dyn Wave>, opts: &Options, name: &str) -> Self {
        let base = wave.header().base;
        UartChars {
            wave,
            opts: opts.clone(),
            name: name.to_owned(),
            uart: None,
            base,
            held: VecDeque::new(),
            held_step: None,
            edges: Vec::new(),
            events: Vec::new(),
            channel: String::new(),
            cut: false,
            done: false,
        }
    }

    /// Reads into `held` until `enough` says so or the trace ends.
    fn read_ahead(&mut self, enough: &dyn Fn(&VecDeque<Edge>) -> bool) -> Result<(), Failure> {
        while !matches!(self.held_step, Some(Step::End(_))) && !enough(&self.held) {
            self.edges.clear();
            let step = self.wave.read(&mut self.edges)?;
            self.held.extend(self.edges.drain(..));
            self.held_step = Some(step);
        }
        Ok(())
    }

    /// Chooses the channel, reads ahead, settles the idle level and the rate.
    fn settle(&mut self, tx: &SyncSender<Message>) -> Result<(), Failure> {
        let channels = self.wave.header().channels.clone();
        let chosen = match (&self.opts.channel, channels.len()) {
            (Some(want), _) => find_channel(&channels, want)
                .ok_or_else(|| self.no_such_channel(want, &channels))?,
            (None, 1) => 0,
            (None, 0) => {
                return Err(Failure::Input(format!(
                    "{}: the trace has no channel",
                    self.name
                )));
            }
            (None, n) => {
                // The one channel that changes level, if only one does.
                self.wave.select(&(0..n).collect::<Vec<_>>());
                self.read_ahead(&|held| {
                    held.len() >= LOOKAHEAD_ALL
                        || slot_counts(held, n).iter().any(|&c| c > LOOKAHEAD)
                })?;
                let counts = slot_counts(&self.held, n);
                let moving: Vec<usize> = (0..n).filter(|&i| counts[i] > 1).collect();
                if moving.len() != 1 {
                    return Err(self.choose_channel(&channels, &moving));
                }
                let only = moving[0];
                let _ = tx.send(Message::Warning(format!(
                    "{}: reading channel {} ({}), the only one of {n} that changes level; \
                     --channel to choose another",
                    self.name, channels[only].number, channels[only].name
                )));
                self.held.retain(|e| usize::from(e.slot) == only);
                for e in &mut self.held {
                    e.slot = 0;
                }
                only
            }
        };
        let ch = &channels[chosen];
        self.channel = format!("channel {} ({})", ch.number, ch.name);
        self.wave.select(&[chosen]);
        self.read_ahead(&|held| held.len() > LOOKAHEAD)?;
        let ticks: Vec<u64> = self.held.iter().map(|e| e.tick).collect();
        let levels: Vec<bool> = self.held.iter().map(|e| e.high).collect();
        let end = match self.held_step {
            Some(Step::Upto(t) | Step::End(t)) => t,
            None => 0,
        };
        if ticks.len() < 2 {
            let _ = tx.send(Message::Warning(format!(
                "{}: {} never changes level",
                self.name, self.channel
            )));
        }
        // The first edge is the level at the start, not a pulse.
        let measured = uart::measure(ticks.get(1..).unwrap_or_default(), self.base);
        let baud = self.baud(measured, tx);
        if let Some(rate) = self.wave.header().sample_rate
            && rate < 8 * u64::from(baud)
        {
            let _ = tx.send(Message::Warning(format!(
                "{}: the sample rate ({rate} Hz) is {:.1} times the baud rate ({baud}); \
                 sampling in the middle of each bit needs 8 times or more",
                self.name,
                rate as f64 / f64::from(baud)
            )));
        }
        let pairs: Vec<(u64, bool)> = ticks.iter().copied().zip(levels.iter().copied()).collect();
        let idle_high = uart::polarity(&self.opts.line, baud, self.base, &pairs, end)
            .or_else(|| uart::idle_level(&ticks, &levels, end))
            .unwrap_or(true);
        if !idle_high {
            let _ = tx.send(Message::Warning(format!(
                "{}: {} reads as an inverted line (idle low)",
                self.name, self.channel
            )));
        }
        self.uart = Some(Uart::new(&self.opts.line, baud, self.base, idle_high));
        Ok(())
    }

    /// The rate to read at: `--baud`, else the protocol's unless the pulses say otherwise.
    fn baud(&self, measured: Option<uart::Measured>, tx: &SyncSender<Message>) -> u32 {
        let default = self.opts.line.baud;
        let measured = measured.map(|m| {
            let rate = uart::snap(m.baud).unwrap_or(m.baud.round() as u32).max(1);
            (m, rate)
        });
        let differs = |r: u32| (f64::from(r) / f64::from(default.max(1)) - 1.0).abs() > 0.025;
        match (self.opts.baud, measured) {
            (Some(fixed), Some((m, rate)))
                if (f64::from(rate) / f64::from(fixed.max(1)) - 1.0).abs() > 0.025 =>
            {
                let _ = tx.send(Message::Warning(format!(
                    "{}: the pulses on {} look like {rate} baud ({:.0} measured from {} \
                     pulses), not the {fixed} of --baud",
                    self.name, self.channel, m.baud, m.pulses
                )));
                fixed
            }
            (Some(fixed), _) => fixed,
            (None, Some((m, rate))) if differs(rate) => {
                let _ = tx.send(Message::Warning(format!(
                    "{}: {} runs at {rate} baud ({:.0} measured from {} pulses), not the \
                     protocol's {default}; --baud to set the rate",
                    self.name, self.channel, m.baud, m.pulses
                )));
                rate
            }
            (None, _) => default,
        }
    }

    fn no_such_channel(&self, want: &str, channels: &[Channel]) -> Failure {
        Failure::Usage(format!(
            "{}: no channel {want:?}; its channels: {}",
            self.name,
            list(channels, &[])
        ))
    }

    fn choose_channel(&self, channels: &[Channel], moving: &[usize]) -> Failure {
        let why = if moving.is_empty() {
            "none changes level"
        } else {
            "several change level (*)"
        };
        Failure::Usage(format!(
            "{}: the trace has {} channels and {why}: choose one with --channel NAME|N: {}",
            self.name,
            channels.len(),
            list(channels, moving)
        ))
    }

    /// Decodes `edges` (of the chosen channel) into `out`.
    fn decode(&mut self, edges: &[Edge], step: Step, out: &mut VecDeque<Char>) {
        let Some(uart) = self.uart.as_mut() else {
            return;
        };
        let events = &mut self.events;
        let mut emit = |e| events.push(e);
        for e in edges {
            uart.edge(e.tick, e.high, &mut emit);
        }
        match step {
            Step::Upto(t) => uart.advance(t, &mut emit),
            Step::End(t) => self.cut |= uart.finish(t, &mut emit),
        }
        let base = self.base;
        out.extend(self.events.drain(..).map(|e| match e {
            Event::Char {
                tick,
                value,
                framing,
                parity,
            } => Char {
                micros: base.micros(tick),
                value,
                framing,
                parity,
                brk: None,
            },
            Event::Break { tick, end } => Char {
                micros: base.micros(tick),
                value: 0,
                framing: true,
                parity: false,
                brk: Some(base.micros(end).saturating_sub(base.micros(tick))),
            },
        }));
    }
}

/// Edges per slot among `held`.
fn slot_counts(held: &VecDeque<Edge>, n: usize) -> Vec<usize> {
    let mut counts = vec![0; n];
    for e in held {
        if let Some(c) = counts.get_mut(usize::from(e.slot)) {
            *c += 1;
        }
    }
    counts
}

/// `0 RX, 1 DE*, …` (`*` on the places in `mark`).
fn list(channels: &[Channel], mark: &[usize]) -> String {
    channels
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let star = if mark.contains(&i) { "*" } else { "" };
            if c.name == c.number.to_string() {
                format!("{}{star}", c.number)
            } else {
                format!("{} {}{star}", c.number, c.name)
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The place of the channel named `want`, else numbered `want`.
pub fn find_channel(channels: &[Channel], want: &str) -> Option<usize> {
    channels.iter().position(|c| c.name == want).or_else(|| {
        let n: usize = want.trim().parse().ok()?;
        channels.iter().position(|c| c.number == n)
    })
}

impl Chars for UartChars {
    fn read(
        &mut self,
        out: &mut VecDeque<Char>,
        tx: &SyncSender<Message>,
    ) -> Result<bool, Failure> {
        if self.done {
            return Ok(false);
        }
        if self.uart.is_none() {
            self.settle(tx)?;
            let held: Vec<Edge> = self.held.drain(..).collect();
            let step = self.held_step.take().unwrap_or(Step::Upto(0));
            self.decode(&held, step, out);
            self.done = matches!(step, Step::End(_));
            return Ok(true);
        }
        let mut edges = std::mem::take(&mut self.edges);
        edges.clear();
        let step = self.wave.read(&mut edges);
        let step = match step {
            Ok(s) => s,
            Err(f) => {
                self.edges = edges;
                return Err(f);
            }
        };
        self.decode(&edges, step, out);
        self.edges = edges;
        self.done = matches!(step, Step::End(_));
        Ok(true)
    }

    fn summary(&self) -> Vec<String> {
        let mut s = Vec::new();
        if let Some(u) = &self.uart
            && u.false_starts > 0
        {
            s.push(format!(
                "{}: {} ignored",
                self.channel,
                count(
                    u.false_starts,
                    "glitch (a start bit shorter than half a bit)",
                    "glitches (start bits shorter than half a bit)"
                )
            ));
        }
        if self.cut {
            s.push(format!(
                "{}: the trace ends inside a character, which is left out",
                self.channel
            ));
        }
        s
    }
}

/// The input as a reader again, its detection prefix first.
pub(crate) fn whole_input(opened: Opened) -> (Box<dyn Read + Send>, String) {
    let prefix = io::Cursor::new(opened.prefix);
    (Box::new(prefix.chain(opened.reader)), opened.name)
}

#[cfg(test)]
mod tests;
