//! Several sources at once (`busnoop PROTO SRC1 SRC2 …`): one table, ordered by time, with a
//! `Port` column.
//!
//! Each port runs the one-source driver ([`crate::run::drive`]) in a thread of its own, with its
//! own decoder, on its own feed: signals, gaps (`--reconnect` makes only the unplugged port wait),
//! notes and hints work per port as for one source. Its rows go, copied ([`rows::Rows`]) and in
//! batches over a bounded channel, to this thread, which merges them into the one sink through
//! the filters (so that the Counter is the row's number in the merged table):
//!
//! * **Live ports** (serial devices) share one clock (capture time 0 is one instant for all of
//!   them) and are merged by the same rule, except that a row waits at most [`HOLD`] of capture
//!   time for the other ports: a quiet port never holds the table back longer, and a row a
//!   decoder hands on later than that (an unanswered poll known only at the next one after a
//!   long pause) is written when it comes.
//! * **Files and streams** are merged by the rows' times (a k-way merge): the earliest row waits
//!   until every other port that has not ended has a row queued (or ends), so that no later row
//!   can be earlier. Rows of the same time go in the order of the ports. Each port holds at most a
//!   few batches, so memory stays bounded however long the inputs are.
//!
//! A row's time is its `Millis` moved onto the common clock (a port's start, from its capture's
//! first time, minus the earliest port's: `offset`); a row without a time takes its port's time
//! before it. Every row decoded is written, whatever ends the run (the end of the inputs, a
//! signal, a failing port, which stops the others, or the sink's failure, after which the rest
//! are dropped).

mod rows;

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, sync_channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crate::exit::{Failure, Interrupt};
use crate::filter::{Select, Selection};
use crate::pcap::Packet;
use crate::protocol::Decoder;
use crate::record::{Keep, Recorder};
use crate::row::{Class, OutputError, Row, RowOut, RowResult};
use crate::run::{Context, drive};
use crate::signal::Stop;
use crate::sink::Sink;
use crate::source::Feed;
use crate::time::Anchor;
pub use rows::Rows;

/// How often the merge wakes up without rows (to redraw `--top`, notice its `q`).
const TICK: Duration = Duration::from_millis(20);

/// How long past its time a live row waits for the rows of the other ports that may be earlier
/// (decoders hand a frame's row on when the frame is whole, an unanswered S.Port poll at the next
/// poll, 12 ms later).
pub const HOLD: Duration = Duration::from_millis(100);

/// A port hands its rows on in batches of at most this many (and at every flush of its driver:
/// after each input batch, and on idle ticks).
const BATCH_ROWS: usize = 1024;

/// Batches a port may be ahead of the merge.
const AHEAD: usize = 4;

/// One source of a merged run.
pub struct Port {
    /// The `Port` cell: the source as given on the command line (or a recorded port's name).
    pub name: String,
    pub decoder: Box<dyn Decoder>,
    pub feed: Feed,
    /// Its share of the recording (`--record`).
    pub recorder: Option<PortRecorder>,
    /// µs from the common capture start to this port's start.
    pub offset: u64,
}

/// What the merge did, per port (in the order of the ports).
pub struct Merged {
    pub result: Result<(), Failure>,
    /// Rows of each port, hidden ones included.
    pub rows: Vec<u64>,
    /// Rows of each port a filter hid.
    pub hidden: Vec<u64>,
    /// Rows of each port that were whole frames (wire bytes, not an error or a note).
    pub frames: Vec<u64>,
}

/// What a port's thread sends.
enum Up {
    Rows(Rows),
    Anchor(Anchor),
    End(Result<(), Failure>),
}

/// How the ports are merged.
pub struct How<'a> {
    pub stop: &'a Stop,
    /// Protocol name for messages.
    pub protocol: &'a str,
    /// The ports are serial devices.
    pub live: bool,
    /// The common capture start when it is known before the run (files); otherwise the first
    /// port's start is the table's.
    pub anchor: Option<Anchor>,
    /// Live: the instant of capture time 0 of every port.
    pub clock: Option<Instant>,
    pub selection: &'a Selection,
    /// No notices on stderr ([`crate::run::Context::quiet`]).
    pub quiet: bool,
}

/// Decodes every port in its own thread and writes their rows, merged, into `sink` through the
/// filters of `how.selection`.
pub fn merge(ports: &mut [Port], sink: &mut dyn Sink, how: How<'_>) -> Merged {
    let driven = Driven {
        stop: how.stop,
        protocol: how.protocol,
        live: how.live,
        quiet: how.quiet,
    };
    let How {
        live,
        anchor,
        clock,
        selection,
        ..
    } = how;
    if anchor.is_some() {
        sink.set_anchor(anchor);
    }
    let n = ports.len();
    let quit = AtomicBool::new(false);
    let names: Vec<String> = ports.iter().map(|p| p.name.clone()).collect();
    let mut merger = Merger {
        queues: (0..n).map(|_| Queue::default()).collect(),
        tally: Tally {
            sink,
            port: 0,
            rows: vec![0; n],
            hidden: vec![0; n],
            frames: vec![0; n],
        },
        selection,
        names,
        quit: &quit,
        clock,
        anchored: anchor.is_some(),
        failure: None,
        output: None,
        interrupts: Vec::new(),
    };
    std::thread::scope(|scope| {
        let mut receivers = Vec::new();
        let shared = live.then(|| sync_channel(AHEAD * n));
        for (i, port) in ports.iter_mut().enumerate() {
            let tx = match &shared {
                Some((tx, _)) => tx.clone(),
                None => {
                    let (tx, rx) = sync_channel(AHEAD);
                    receivers.push(rx);
                    tx
                }
            };
            let quit = &quit;
            std::thread::Builder::new()
                .name(format!("busnoop-port-{i}"))
                .spawn_scoped(scope, move || run_port(i, port, tx, quit, &driven))
                .expect("spawn port thread");
        }
        match shared {
            Some((tx, rx)) => {
                drop(tx);
                merger.live(&rx);
            }
            None => merger.files(&receivers),
        }
    });
    let closed = merger.tally.sink.close();
    let result = merger.result(closed);
    Merged {
        result,
        rows: merger.tally.rows,
        hidden: merger.tally.hidden,
        frames: merger.tally.frames,
    }
}

/// What every port's driver is told ([`How`]'s part of it).
#[derive(Clone, Copy)]
struct Driven<'a> {
    stop: &'a Stop,
    protocol: &'a str,
    live: bool,
    quiet: bool,
}

/// A port's thread: the driver, with its rows going to the merge.
fn run_port(
    i: usize,
    port: &mut Port,
    tx: SyncSender<(usize, Up)>,
    quit: &AtomicBool,
    driven: &Driven<'_>,
) {
    let Driven {
        stop,
        protocol,
        live,
        quiet,
    } = *driven;
    let mut sink = PortSink {
        port: i,
        offset: port.offset,
        last: port.offset,
        rows: Rows::default(),
        tx,
        quit,
    };
    let everything = Selection::default();
    let ctx = Context {
        stop,
        recorder: port.recorder.as_mut().map(|r| r as &mut dyn Keep),
        protocol,
        live,
        source: &port.name,
        selection: &everything,
        quiet,
    };
    let result = drive(port.decoder.as_mut(), &port.feed, &mut sink, ctx);
    sink.send();
    let _ = sink.tx.send((i, Up::End(result)));
}

/// The sink of a port's driver: keeps its rows and hands them on in batches.
struct PortSink<'a> {
    port: usize,
    offset: u64,
    /// The time of the port's last row (for a row without one).
    last: u64,
    rows: Rows,
    tx: SyncSender<(usize, Up)>,
    quit: &'a AtomicBool,
}

impl PortSink<'_> {
    fn send(&mut self) {
        if !self.rows.is_empty() {
            let like = self.rows.like();
            let rows = std::mem::replace(&mut self.rows, like);
            // The merge takes everything until every port has ended.
            let _ = self.tx.send((self.port, Up::Rows(rows)));
        }
    }
}

impl RowOut for PortSink<'_> {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        if let Some(us) = row.micros {
            self.last = us.saturating_add(self.offset);
        }
        self.rows.push(row, self.offset, self.last);
        if self.rows.len() >= BATCH_ROWS {
            self.send();
        }
        Ok(())
    }
}

impl Sink for PortSink<'_> {
    fn flush(&mut self) -> Result<(), OutputError> {
        self.send();
        Ok(())
    }
    fn close(&mut self) -> Result<(), OutputError> {
        self.send();
        Ok(())
    }
    fn set_anchor(&mut self, anchor: Option<Anchor>) {
        if let Some(a) = anchor {
            self.send();
            let _ = self.tx.send((self.port, Up::Anchor(a)));
        }
    }
    fn quit(&self) -> bool {
        self.quit.load(Ordering::Relaxed)
    }
    /// The port's driver has no filter: the merge's filters count what they hide.
    fn skip(&mut self) {}
}

/// A port's share of the recording: its bytes and gaps on its own interface, at its times on
/// the common clock.
pub struct PortRecorder {
    pub shared: Arc<Mutex<Recorder>>,
    pub port: u32,
    pub offset: u64,
    /// The common capture start (files); `None`: the first port's (live ports).
    pub anchor: Option<Anchor>,
}

impl PortRecorder {
    fn lock(&self) -> MutexGuard<'_, Recorder> {
        self.shared.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Keep for PortRecorder {
    fn start(&mut self, anchor: Option<Anchor>) -> Result<(), Failure> {
        let anchor = self.anchor.or(anchor);
        self.lock().start(anchor)
    }
    fn data(&mut self, bytes: &[u8], micros: Option<u64>) -> Result<(), Failure> {
        let micros = micros.map(|m| m.saturating_add(self.offset));
        self.lock().port_data(self.port, bytes, micros)
    }
    fn link(&mut self, up: bool, micros: u64) -> Result<(), Failure> {
        let micros = micros.saturating_add(self.offset);
        self.lock().port_link(self.port, up, micros)
    }
    fn capture_link_type(&mut self, link_type: Option<u32>) {
        self.lock().capture_link_type(link_type)
    }
    fn packet(&mut self, p: &Packet<'_>) -> Result<(), Failure> {
        self.lock().packet(p)
    }
    fn take_warning(&mut self) -> Option<String> {
        self.lock().take_warning()
    }
    fn flush(&mut self) -> Result<(), Failure> {
        self.lock().flush()
    }
    /// Flushes; the recording is finished once, after every port ([`finish_recording`]).
    fn finish(&mut self) -> Result<(), Failure> {
        self.lock().flush()
    }
}

/// Finishes the recording the ports shared.
pub fn finish_recording(shared: &Arc<Mutex<Recorder>>) -> Result<(), Failure> {
    shared.lock().unwrap_or_else(|e| e.into_inner()).finish()
}

/// The sink with the rows of each port counted.
struct Tally<'a> {
    sink: &'a mut dyn Sink,
    /// The port of the rows written now.
    port: usize,
    rows: Vec<u64>,
    hidden: Vec<u64>,
    frames: Vec<u64>,
}

impl RowOut for Tally<'_> {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        self.rows[self.port] += 1;
        if !row.raw.is_empty() && !matches!(row.class, Class::Error | Class::Info) {
            self.frames[self.port] += 1;
        }
        self.sink.row(row)
    }
}

impl Sink for Tally<'_> {
    fn flush(&mut self) -> Result<(), OutputError> {
        self.sink.flush()
    }
    fn close(&mut self) -> Result<(), OutputError> {
        self.sink.close()
    }
    fn set_anchor(&mut self, anchor: Option<Anchor>) {
        self.sink.set_anchor(anchor)
    }
    fn quit(&self) -> bool {
        self.sink.quit()
    }
    fn skip(&mut self) {
        self.rows[self.port] += 1;
        self.hidden[self.port] += 1;
        self.sink.skip()
    }
}

/// The rows of one port waiting to be written.
#[derive(Default)]
struct Queue {
    batches: VecDeque<Rows>,
    /// The next row of the first batch.
    next: usize,
    ended: bool,
}

impl Queue {
    /// The merge time of its next row.
    fn head(&self) -> Option<u64> {
        self.batches.front().map(|b| b.at(self.next))
    }
}

struct Merger<'a, 's> {
    queues: Vec<Queue>,
    tally: Tally<'s>,
    selection: &'a Selection,
    names: Vec<String>,
    quit: &'a AtomicBool,
    /// Live: the instant of capture time 0.
    clock: Option<Instant>,
    anchored: bool,
    /// The first failure of a port (a signal aside).
    failure: Option<Failure>,
    /// The sink's failure: no row is written after it.
    output: Option<OutputError>,
    /// The ports a signal stopped, with what each left unread.
    interrupts: Vec<(usize, Interrupt)>,
}

impl Merger<'_, '_> {
    /// Files and streams: each port's own channel; a port is waited for only while it has no
    /// row queued, so the earliest row of all is known before it is written.
    fn files(&mut self, receivers: &[Receiver<(usize, Up)>]) {
        loop {
            for (p, rx) in receivers.iter().enumerate() {
                while !self.queues[p].ended && self.queues[p].batches.is_empty() {
                    match rx.recv_timeout(TICK) {
                        Ok((p, up)) => self.take(p, up),
                        Err(RecvTimeoutError::Timeout) => self.tick(),
                        Err(RecvTimeoutError::Disconnected) => self.queues[p].ended = true,
                    }
                }
            }
            if !self.write_ready() {
                return;
            }
            self.flush();
        }
    }

    /// Live ports: one channel for all; rows are written in time order, each waiting at most
    /// [`HOLD`] for the other ports.
    fn live(&mut self, rx: &Receiver<(usize, Up)>) {
        loop {
            match rx.recv_timeout(TICK) {
                Ok((p, up)) => {
                    self.take(p, up);
                    while let Ok((p, up)) = rx.try_recv() {
                        self.take(p, up);
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    self.write_ready();
                    return;
                }
            }
            self.write_ready();
            self.flush();
            // A port's `End` is the last thing it sends: everything before it is written.
            if self.queues.iter().all(|q| q.ended) {
                return;
            }
        }
    }

    fn take(&mut self, p: usize, up: Up) {
        match up {
            Up::Rows(rows) => {
                if self.output.is_none() {
                    self.queues[p].batches.push_back(rows);
                }
            }
            Up::Anchor(a) => {
                // The ports' clocks are one: the first start is the table's.
                if !self.anchored {
                    self.anchored = true;
                    self.tally.set_anchor(Some(a));
                }
            }
            Up::End(result) => {
                self.queues[p].ended = true;
                match result {
                    Ok(()) => {}
                    Err(Failure::Signal(i)) => self.interrupts.push((p, i)),
                    Err(f) => {
                        // A failing source ends the run: the other ports stop too.
                        self.quit.store(true, Ordering::Relaxed);
                        self.failure.get_or_insert(f);
                    }
                }
            }
        }
    }

    /// Writes rows in time order while every port that has not ended has a row queued (live:
    /// or the earliest row's time is [`HOLD`] past). False when every port has ended and every
    /// row is written.
    fn write_ready(&mut self) -> bool {
        let now = self.clock.map(|c| c.elapsed().as_micros() as u64);
        loop {
            let mut first: Option<(u64, usize)> = None;
            let mut waiting = false;
            for (p, q) in self.queues.iter().enumerate() {
                match q.head() {
                    Some(at) if first.is_none_or(|(t, _)| at < t) => first = Some((at, p)),
                    Some(_) => {}
                    None => waiting |= !q.ended,
                }
            }
            let Some((at, p)) = first else {
                return !self.queues.iter().all(|q| q.ended);
            };
            let held = now.is_some_and(|now| now >= at.saturating_add(HOLD.as_micros() as u64));
            if waiting && !held {
                return true;
            }
            self.write_next(p);
        }
    }

    /// Writes the next row of port `p`.
    fn write_next(&mut self, p: usize) {
        let q = &mut self.queues[p];
        let Some(batch) = q.batches.front() else {
            return;
        };
        let i = q.next;
        if self.output.is_none() {
            self.tally.port = p;
            let (tally, selection) = (&mut self.tally, self.selection);
            let written = batch.with_row(i, &self.names[p], |row| {
                Select {
                    table: tally,
                    selection,
                }
                .out()
                .row(row)
            });
            if let Err(e) = written {
                self.fail(e);
            }
        }
        let q = &mut self.queues[p];
        q.next += 1;
        if q.next >= q.batches.front().map_or(0, Rows::len) {
            q.batches.pop_front();
            q.next = 0;
        }
    }

    /// The sink failed: nothing more is written, the ports stop.
    fn fail(&mut self, e: OutputError) {
        self.quit.store(true, Ordering::Relaxed);
        for q in &mut self.queues {
            q.batches.clear();
            q.next = 0;
        }
        self.output.get_or_insert(e);
    }

    fn flush(&mut self) {
        if self.output.is_none()
            && let Err(e) = self.tally.flush()
        {
            self.fail(e);
        }
        if self.tally.quit() {
            self.quit.store(true, Ordering::Relaxed);
        }
    }

    /// Time passed without rows: the sink is flushed (`--top` redraws and reads its keys).
    fn tick(&mut self) {
        self.flush();
    }

    /// The run's outcome: the sink's failure first, then a port's, then a signal (with what
    /// each port left unread).
    fn result(&mut self, closed: Result<(), OutputError>) -> Result<(), Failure> {
        if let Some(e) = self.output.take() {
            return Err(e.into());
        }
        if let Some(f) = self.failure.take() {
            return Err(f);
        }
        closed?;
        let Some((_, first)) = self.interrupts.first() else {
            return Ok(());
        };
        let mut interrupt = Interrupt::new(first.signal);
        let notes: Vec<String> = self
            .interrupts
            .iter()
            .filter_map(|(p, i)| i.input.as_ref().map(|n| format!("{}: {n}", self.names[*p])))
            .collect();
        if !notes.is_empty() {
            interrupt.input = Some(notes.join("; "));
        }
        Err(Failure::Signal(interrupt))
    }
}
