//! The protocol-independent driver: messages from a source → decoder → table, with signals.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

use crate::decoder::Decoder;
use crate::exit::Failure;
use crate::sink::Table;
use crate::source::Message;

/// How often the driver wakes up without data (to notice signals and let decoders time out).
const TICK: Duration = Duration::from_millis(50);

/// SIGINT/SIGTERM catcher. The first signal asks busnoop to stop cleanly; a second one of the
/// same kind ends the process at once.
#[derive(Clone)]
pub struct Stop {
    signal: Arc<AtomicUsize>,
}

impl Stop {
    /// Installs the handlers.
    pub fn install() -> std::io::Result<Stop> {
        let signal = Arc::new(AtomicUsize::new(0));
        for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
            let armed = Arc::new(AtomicBool::new(false));
            // Second signal: exit immediately with the conventional code.
            signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, armed.clone())?;
            signal_hook::flag::register(sig, armed)?;
            signal_hook::flag::register_usize(sig, signal.clone(), sig as usize)?;
        }
        Ok(Stop { signal })
    }

    /// A stop that never fires (tests, benchmarks).
    pub fn never() -> Stop {
        Stop {
            signal: Arc::new(AtomicUsize::new(0)),
        }
    }

    /// The signal received, if any.
    pub fn signal(&self) -> Option<i32> {
        match self.signal.load(Ordering::Relaxed) {
            0 => None,
            s => Some(s as i32),
        }
    }

    /// Asks the driver to stop as if `sig` had arrived.
    pub fn raise(&self, sig: i32) {
        self.signal.store(sig as usize, Ordering::Relaxed);
    }
}

/// Feeds every message from `rx` through `decoder` into `table` until the source ends, fails,
/// or a signal arrives. Rows are flushed after every batch, so live output appears as soon as
/// a frame completes. Whatever happens, every row decoded so far is written before returning.
pub fn drive(
    decoder: &mut dyn Decoder,
    rx: &Receiver<Message>,
    table: &mut Table,
    stop: &Stop,
) -> Result<(), Failure> {
    let result = drive_inner(decoder, rx, table, stop);
    // Flush whatever is open, even after an error of the source.
    let finish = match &result {
        Err(Failure::Output(_)) | Err(Failure::BrokenPipe) => Ok(()),
        _ => decoder.finish(table).map_err(|_| ()),
    };
    let close = table.close();
    match (result, finish, close) {
        (Err(f @ (Failure::Output(_) | Failure::BrokenPipe)), _, _) => Err(f),
        (_, _, Err(e)) => Err(e.into()),
        (r, _, Ok(())) => r,
    }
}

fn drive_inner(
    decoder: &mut dyn Decoder,
    rx: &Receiver<Message>,
    table: &mut Table,
    stop: &Stop,
) -> Result<(), Failure> {
    let mut last_time: Option<u64> = None;
    loop {
        if let Some(sig) = stop.signal() {
            // Decode what was already received, then stop.
            while let Ok(msg) = rx.try_recv() {
                match msg {
                    Message::Data(b) => feed(decoder, &b, table, &mut last_time)?,
                    Message::Anchor(a) => table.set_anchor(Some(a)),
                    _ => break,
                }
            }
            return Err(Failure::Signal(sig));
        }
        match rx.recv_timeout(TICK) {
            Ok(Message::Data(b)) => {
                feed(decoder, &b, table, &mut last_time)?;
                table.flush()?;
            }
            Ok(Message::Anchor(a)) => table.set_anchor(Some(a)),
            Ok(Message::Warning(w)) => {
                table.flush()?;
                eprintln!("busnoop: warning: {w}");
            }
            Ok(Message::End) => return Ok(()),
            Ok(Message::Failed(f)) => return Err(f),
            Err(RecvTimeoutError::Timeout) => {
                if let Some(t) = last_time {
                    decoder.idle(t, table).map_err(|_| output_error(table))?;
                }
                table.flush()?;
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(Failure::Internal(
                    "the reader thread stopped unexpectedly".into(),
                ));
            }
        }
    }
}

fn feed(
    decoder: &mut dyn Decoder,
    batch: &crate::source::Batch,
    table: &mut Table,
    last_time: &mut Option<u64>,
) -> Result<(), Failure> {
    for (bytes, time) in batch.segments() {
        if time.is_some() {
            *last_time = time;
        }
        decoder
            .push(bytes, time, table)
            .map_err(|_| output_error(table))?;
    }
    Ok(())
}

/// The error a table stored when a row could not be written.
fn output_error(table: &mut Table) -> Failure {
    match table.flush() {
        Err(e) => e.into(),
        Ok(()) => Failure::Internal("a row could not be written".into()),
    }
}
