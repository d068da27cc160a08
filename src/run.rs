//! The protocol-independent driver: messages from a source → decoder → table (and recording),
//! with signals, adapter gaps and the "no frames" hint.

use std::sync::mpsc::RecvTimeoutError;
use std::time::{Duration, Instant};

use crate::exit::{Failure, Interrupt};
use crate::filter::{Select, Selection};
use crate::protocol::Decoder;
use crate::record::Keep;
use crate::row::{Class, Row};
use crate::signal::Stop;
use crate::sink::Sink;
use crate::source::capture::Captured;
use crate::source::{Batch, Feed, Message};

/// The decoder's rows go through the filter and the names into the table (straight into the
/// table when neither is set, see [`Select::out`]). The `Select` is a temporary that lives until
/// the end of the statement that uses it.
macro_rules! select {
    ($d:expr) => {
        Select {
            table: $d.table,
            selection: $d.selection,
        }
        .out()
    };
}

/// How often the driver wakes up without data (to notice signals and let decoders time out).
const TICK: Duration = Duration::from_millis(20);

/// After this long with bytes but no valid frame, the user gets a hint once.
const NO_FRAMES_AFTER: Duration = Duration::from_secs(3);
/// ... provided at least this many bytes arrived.
const NO_FRAMES_BYTES: u64 = 256;

/// Untimed bytes are decoded in pieces of at most this many, with a look for a signal between
/// them, so that one large batch cannot delay the stop (decoders give the same rows however
/// their input is cut).
const UNIT: usize = 4096;

/// After this long without a single byte from a live port, the user gets a hint once.
const SILENT_AFTER: Duration = Duration::from_secs(5);

/// What the driver needs besides the decoder and the table.
pub struct Context<'a> {
    pub stop: &'a Stop,
    /// Keep what came off the wire.
    pub recorder: Option<&'a mut (dyn Keep + 'static)>,
    /// Protocol name for messages ("S.Port").
    pub protocol: &'a str,
    /// The source is a live serial device: decoders get `idle` calls with the current time.
    pub live: bool,
    /// The source's name, for the hint about a silent port.
    pub source: &'a str,
    /// Filters and names between the decoder and the table.
    pub selection: &'a Selection,
    /// No notices on stderr (a capture Wireshark runs through the extcap: it shows whatever
    /// comes there as an error).
    pub quiet: bool,
}

/// Feeds every message from `feed` through `decoder` into `table` until the source ends, fails,
/// or a signal arrives. Rows are flushed after every batch, so live output appears as soon as
/// a frame completes. A signal stops the decoding within one [`UNIT`] of input, whatever the
/// input rate; the reader thread then reads no more. Whatever happens, every row decoded so far
/// is written before returning.
pub fn drive(
    decoder: &mut dyn Decoder,
    feed: &Feed,
    table: &mut dyn Sink,
    ctx: Context<'_>,
) -> Result<(), Failure> {
    let mut state = Driver {
        decoder,
        table,
        recorder: ctx.recorder,
        protocol: ctx.protocol,
        live: ctx.live,
        source: ctx.source,
        started: Instant::now(),
        silent_hinted: false,
        selection: ctx.selection,
        quiet: ctx.quiet,
        clock: None,
        bytes: 0,
        first_byte: None,
        hinted: false,
        down_at: None,
        input_decoded: 0,
    };
    let result = state.run(feed, ctx.stop);
    feed.halt();
    let result = match result {
        Err(Failure::Signal(mut i)) => {
            if let Some(p) = &feed.progress {
                i.input = Some(unread_note(state.input_decoded, p));
            }
            Err(Failure::Signal(i))
        }
        r => r,
    };
    let Driver {
        decoder,
        table,
        recorder,
        selection,
        ..
    } = state;
    // Flush whatever is open, even after an error of the source.
    let output_gone = matches!(result, Err(Failure::Output(_) | Failure::BrokenPipe));
    if !output_gone {
        let _ = decoder.finish(Select { table, selection }.out());
    }
    let recorded = match recorder {
        Some(r) => r.finish(),
        None => Ok(()),
    };
    let close = table.close();
    let result = match result {
        Err(Failure::Disconnected { path, .. }) => Err(Failure::Disconnected {
            path,
            frames: decoder.valid_frames(),
        }),
        r => r,
    };
    match (result, recorded, close) {
        (Err(f @ (Failure::Output(_) | Failure::BrokenPipe)), _, _) => Err(f),
        (_, _, Err(e)) => Err(e.into()),
        (Ok(()), Err(f), _) => Err(f),
        (r, _, Ok(())) => r,
    }
}

struct Driver<'a> {
    decoder: &'a mut dyn Decoder,
    table: &'a mut dyn Sink,
    recorder: Option<&'a mut (dyn Keep + 'static)>,
    protocol: &'a str,
    live: bool,
    source: &'a str,
    started: Instant,
    silent_hinted: bool,
    selection: &'a Selection,
    quiet: bool,
    /// Maps capture time to this process's clock: the instant of capture time 0.
    clock: Option<Instant>,
    bytes: u64,
    first_byte: Option<Instant>,
    hinted: bool,
    down_at: Option<u64>,
    /// Files and streams: input bytes (as read, before any parsing) whose content reached the
    /// decoder.
    input_decoded: u64,
}

/// What was decoded of a file or stream and what was left, when a signal stopped busnoop.
fn unread_note(decoded: u64, p: &crate::source::Progress) -> String {
    let read = p.read().max(decoded);
    match p.size {
        Some(size) => {
            let decoded = decoded.min(size);
            format!(
                "{decoded} of {size} bytes of the input decoded, {} not decoded",
                size - decoded
            )
        }
        None => format!(
            "{decoded} bytes of the input decoded, {} more read but not decoded, the rest left unread",
            read - decoded
        ),
    }
}

impl Driver<'_> {
    fn run(&mut self, feed: &Feed, stop: &Stop) -> Result<(), Failure> {
        loop {
            if let Some(sig) = stop.signal() {
                return Err(Failure::Signal(Interrupt::new(sig)));
            }
            if self.table.quit() {
                return Ok(());
            }
            match feed.recv_timeout(TICK) {
                Ok(Message::Data(b)) => {
                    let fed = self.feed(&b, stop)?;
                    self.input_decoded += fed as u64;
                    self.flush()?;
                    if fed < b.bytes.len() {
                        // Stopped inside the batch: where it ended in the input bounds the count.
                        if let Ok(Message::ReadUpTo(n)) = feed.try_recv() {
                            self.input_decoded = self.input_decoded.min(n);
                        }
                        let sig = stop.signal().unwrap_or(libc::SIGINT);
                        return Err(Failure::Signal(Interrupt::new(sig)));
                    }
                }
                Ok(Message::Packets(c)) => {
                    let whole = self.packets(&c, stop)?;
                    self.flush()?;
                    if !whole {
                        let sig = stop.signal().unwrap_or(libc::SIGINT);
                        return Err(Failure::Signal(Interrupt::new(sig)));
                    }
                }
                Ok(Message::CaptureError(e)) => self
                    .decoder
                    .capture_error(&e, select!(self))
                    .map_err(Failure::from)?,
                Ok(Message::ReadUpTo(n)) => {
                    // Exact for raw bytes; parsed inputs (logs, recordings) take up more room
                    // than the wire bytes they hold.
                    self.input_decoded = n;
                }
                Ok(Message::Anchor(a)) => self.anchor(a)?,
                Ok(Message::Warning(w)) => {
                    self.table.flush()?;
                    eprintln!("busnoop: warning: {w}");
                }
                Ok(Message::Note {
                    micros,
                    kind,
                    class,
                    data,
                    gap,
                }) => self.note(micros, kind, class, &data, gap)?,
                Ok(Message::LinkDown { micros }) => self.link_down(micros)?,
                Ok(Message::LinkUp { micros, path }) => self.link_up(micros, &path)?,
                Ok(Message::End) => return Ok(()),
                Ok(Message::Failed(f)) => return Err(f),
                Err(RecvTimeoutError::Timeout) => {
                    if self.live
                        && let Some(zero) = self.clock
                    {
                        let now = zero.elapsed().as_micros() as u64;
                        self.decoder
                            .idle(now, select!(self))
                            .map_err(Failure::from)?;
                    }
                    self.watch();
                    self.flush()?;
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(Failure::Internal(
                        "the reader thread stopped unexpectedly".into(),
                    ));
                }
            }
        }
    }

    fn anchor(&mut self, a: crate::time::Anchor) -> Result<(), Failure> {
        self.table.set_anchor(Some(a));
        if let Some(r) = self.recorder.as_deref_mut() {
            r.start(Some(a))?;
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<(), Failure> {
        if let Some(r) = self.recorder.as_deref_mut() {
            r.flush()?;
        }
        self.table.flush()?;
        Ok(())
    }

    /// Decodes `batch`, looking for a signal between segments and between [`UNIT`]s of untimed
    /// bytes; returns how many of its bytes were decoded (all of them unless a signal came).
    fn feed(&mut self, batch: &Batch, stop: &Stop) -> Result<usize, Failure> {
        let now = Instant::now();
        let mut fed = 0;
        'segments: for (bytes, time) in batch.segments() {
            if self.clock.is_none()
                && let Some(t) = time
            {
                self.clock = now.checked_sub(Duration::from_micros(t));
            }
            if bytes.is_empty() {
                self.push(bytes, time)?;
                continue;
            }
            // Timed bytes stay whole: a decoder may spread a chunk's time over its bytes.
            let unit = if time.is_some() {
                bytes.len().max(1)
            } else {
                UNIT
            };
            for piece in bytes.chunks(unit) {
                if stop.signal().is_some() {
                    break 'segments;
                }
                self.push(piece, time)?;
                fed += piece.len();
            }
        }
        self.bytes += fed as u64;
        if fed > 0 {
            self.first_byte.get_or_insert(now);
        }
        self.watch();
        Ok(fed)
    }

    /// Decodes (and records) the packets of a capture, looking for a signal between packets;
    /// false when a signal stopped it (the packets' input then does not count as decoded).
    /// A packet is recorded just before it is decoded, so that the recording holds the
    /// packets the table shows, however the run ends.
    fn packets(&mut self, c: &Captured, stop: &Stop) -> Result<bool, Failure> {
        if let Some(r) = self.recorder.as_deref_mut() {
            r.capture_link_type(c.link_type);
        }
        let mut whole = true;
        for p in c.packets.iter() {
            if stop.signal().is_some() {
                whole = false;
                break;
            }
            if let Some(r) = self.recorder.as_deref_mut() {
                r.packet(&p)?;
            }
            self.decoder
                .packet(&p, select!(self))
                .map_err(Failure::from)?;
        }
        if let Some(w) = self.recorder.as_deref_mut().and_then(|r| r.take_warning()) {
            self.table.flush()?;
            eprintln!("busnoop: warning: {w}");
        }
        Ok(whole)
    }

    fn push(&mut self, bytes: &[u8], time: Option<u64>) -> Result<(), Failure> {
        if let Some(r) = self.recorder.as_deref_mut() {
            r.data(bytes, time)?;
        }
        self.decoder
            .push(bytes, time, select!(self))
            .map_err(Failure::from)
    }

    /// Bytes keep arriving but nothing decodes: say so once, with the likely causes.
    /// Live sources only: a replayed file has no wiring to check.
    fn watch(&mut self) {
        if self.live && self.bytes == 0 && !self.silent_hinted {
            let waited = self.started.elapsed();
            if waited >= SILENT_AFTER {
                self.silent_hinted = true;
                let _ = self.table.flush();
                eprintln!(
                    "busnoop: no bytes from {} in {:.0} s: check RX wiring and that the bus is \
                     powered",
                    self.source,
                    waited.as_secs_f64()
                );
            }
        }
        if !self.live
            || self.hinted
            || self.bytes < NO_FRAMES_BYTES
            || self.decoder.valid_frames() > 0
        {
            return;
        }
        let Some(first) = self.first_byte else {
            return;
        };
        let waited = first.elapsed();
        if waited >= NO_FRAMES_AFTER {
            self.hinted = true;
            let _ = self.table.flush();
            eprintln!(
                "busnoop: {} bytes in {:.0} s but no valid {} frame: {}",
                self.bytes,
                waited.as_secs_f64(),
                self.protocol,
                self.decoder.no_frames_hint()
            );
        }
    }

    fn link_down(&mut self, micros: u64) -> Result<(), Failure> {
        if let Some(r) = self.recorder.as_deref_mut() {
            r.link(false, micros)?;
        }
        // Close what the unplug cut off; the decoder goes on after the gap.
        self.decoder.finish(select!(self)).map_err(Failure::from)?;
        self.down_at = Some(micros);
        let data = format!(
            "adapter disconnected after {}; waiting for it",
            crate::exit::count(self.decoder.valid_frames(), "frame", "frames")
        );
        self.info_row(micros, "LinkDown", &data)?;
        self.flush()?;
        // Wireshark shows an extcap's stderr as an error: the row and the capture say it.
        if !self.quiet {
            eprintln!("busnoop: {data} (--reconnect)");
        }
        Ok(())
    }

    fn link_up(&mut self, micros: u64, path: &std::path::Path) -> Result<(), Failure> {
        if let Some(r) = self.recorder.as_deref_mut() {
            r.link(true, micros)?;
        }
        let gap = self
            .down_at
            .take()
            .map_or(0.0, |d| micros.saturating_sub(d) as f64 / 1e6);
        let data = format!("adapter back at {} after {gap:.1} s", path.display());
        self.info_row(micros, "LinkUp", &data)?;
        self.flush()?;
        if !self.quiet {
            eprintln!("busnoop: {data}");
        }
        Ok(())
    }

    /// A row a source adds to the log (see [`Message::Note`]).
    fn note(
        &mut self,
        micros: Option<u64>,
        kind: &str,
        class: Class,
        data: &str,
        gap: bool,
    ) -> Result<(), Failure> {
        if gap {
            self.decoder.finish(select!(self)).map_err(Failure::from)?;
        }
        let row = Row {
            stamp: 0,
            kind,
            class,
            data,
            ..Row::empty(micros)
        };
        select!(self).row(&row).map_err(Failure::from)
    }

    /// A row busnoop itself adds to the log (gaps).
    fn info_row(&mut self, micros: u64, kind: &str, data: &str) -> Result<(), Failure> {
        let row = Row {
            stamp: 0,
            kind,
            class: Class::Info,
            data,
            ..Row::empty(Some(micros))
        };
        select!(self).row(&row).map_err(Failure::from)
    }
}
