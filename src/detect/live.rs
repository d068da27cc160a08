//! `busnoop detect` on a serial port: listen passively at each baud rate, score what was heard.

use super::*;

/// One baud rate's listen.
pub(super) struct Listen {
    pub(super) baud: u32,
    pub(super) batches: Vec<Batch>,
    pub(super) bytes: u64,
}

/// `busnoop detect /dev/ttyUSB0`: listens at each rate in turn, passively (the device is
/// opened read-only, as for a capture), and ranks every (rate, protocol) pair.
pub(super) fn live(path: &Path, args: &Options) -> Result<(), LiveError> {
    let bauds: Vec<u32> = if args.bauds.is_empty() {
        USUAL_BAUDS.to_vec()
    } else {
        args.bauds.clone()
    };
    let listen = Duration::from_millis(args.listen_ms);
    // Ctrl-C, SIGTERM, SIGHUP and an unplug end the listening; what was heard is still judged.
    let stop = crate::signal::Stop::install().map_err(|e| {
        LiveError::Failed(Failure::Internal(format!(
            "cannot install signal handlers: {e}"
        )))
    })?;
    let mut listens = Vec::new();
    let mut ended = None;
    for &baud in &bauds {
        if let Some(sig) = stop.signal() {
            ended = Some(Ended::Signal(sig));
            break;
        }
        let cfg = SerialConfig {
            line: Line::n81(baud),
            lines: args.dtr_rts,
        };
        let mut port = match serial::open(path, &cfg) {
            Ok(p) => p,
            Err(e) if serial::is_not_a_tty(&e) && listens.is_empty() => {
                return Err(LiveError::NotATty);
            }
            // Gone between two rates.
            Err(_) if !listens.is_empty() && !path.exists() => {
                ended = Some(Ended::Gone);
                break;
            }
            Err(e) => return Err(LiveError::Failed(serial::open_failure(path, &e))),
        };
        // Said once the device is known to be a serial port (/dev/zero is read as a file).
        if listens.is_empty() {
            eprintln!(
                "busnoop: listening to {} for {} ms at each of {} baud rates",
                path.display(),
                args.listen_ms,
                bauds.len()
            );
        }
        let (heard, end) = listen_once(port.as_mut(), path, baud, listen, &stop);
        listens.push(heard);
        if end.is_some() {
            ended = end;
            break;
        }
    }
    if listens.iter().all(|l| l.bytes == 0)
        && let Some(end) = ended
    {
        // Nothing heard to judge.
        return Err(LiveError::Failed(end.failure(path, &listens, bauds.len())));
    }
    let mut text = format!("{}: a serial line\n", path.display());
    let report = judge_live(&listens);
    for (l, best) in listens.iter().zip(&report.per_rate) {
        text.push_str(&format!("  {:>7} baud: {:>7} bytes", l.baud, l.bytes));
        match best {
            Some(r) => text.push_str(&format!(
                ", best {} ({} in {} frames)\n",
                r.label,
                percent(r.score.share()),
                r.score.frames
            )),
            None => text.push('\n'),
        }
    }
    let result = match &report.best {
        _ if listens.iter().all(|l| l.bytes == 0) => Err(Failure::NothingDecoded(format!(
            "no bytes arrived at any rate in {} ms each: check the wiring (the adapter's RX to \
             the bus line, GND to ground) and that the bus is talking",
            args.listen_ms
        ))),
        Some((i, r)) => {
            found_text(&mut text, r, path, Some(listens[*i].baud));
            Ok(())
        }
        None => {
            text.push_str("verdict: no known protocol at any of these rates\n");
            Err(Failure::NoProtocol(format!(
                "no known protocol on {}: bytes arrive but nothing decodes at any rate tried \
                 (another protocol, an unusual baud rate, or a line that needs inverting)",
                path.display()
            )))
        }
    };
    crate::exit::write_stdout(text.as_bytes()).map_err(LiveError::Failed)?;
    match ended {
        Some(end) => Err(LiveError::Failed(end.failure(path, &listens, bauds.len()))),
        None => result.map_err(LiveError::Failed),
    }
}

/// What ended the listening before every rate was heard.
#[derive(Clone, Copy, Debug)]
enum Ended {
    Signal(i32),
    /// The device went away (unplugged).
    Gone,
}

impl Ended {
    /// The failure to end with, after the evidence of what was heard; a signal's line is
    /// written here (the failure of a signal has none of its own).
    fn failure(self, path: &Path, listens: &[Listen], rates: usize) -> Failure {
        let heard = format!(
            "after listening at {} of {rates} baud rates; the verdict is on what was heard",
            listens.len()
        );
        match self {
            Ended::Signal(sig) => {
                eprintln!("busnoop: interrupted {heard}");
                Failure::Signal(crate::exit::Interrupt::new(sig))
            }
            Ended::Gone => {
                Failure::Unplugged(format!("{} went away (unplugged?) {heard}", path.display()))
            }
        }
    }
}

/// Reads `port` for `listen`, stamping every read with its time since the start; a signal
/// or the device going away ends it early, with what was heard so far.
fn listen_once(
    port: &mut dyn serialport::SerialPort,
    path: &Path,
    baud: u32,
    listen: Duration,
    stop: &crate::signal::Stop,
) -> (Listen, Option<Ended>) {
    use std::io::ErrorKind::*;
    let start = Instant::now();
    let mut batches = Vec::new();
    let mut bytes = 0u64;
    let mut buf = [0u8; 4096];
    let mut ended = None;
    while start.elapsed() < listen {
        if let Some(sig) = stop.signal() {
            ended = Some(Ended::Signal(sig));
            break;
        }
        match port.read(&mut buf) {
            Ok(0) => {
                ended = Some(Ended::Gone);
                break;
            }
            Ok(n) => {
                let t = start.elapsed().as_micros() as u64;
                if (bytes as usize) < SCAN_BYTES {
                    batches.push(Batch::single(buf[..n].to_vec(), Some(t)));
                }
                bytes += n as u64;
            }
            Err(e) if matches!(e.kind(), TimedOut | WouldBlock | Interrupted) => {}
            Err(e) => {
                tracing::info!("{}: {e}", path.display());
                ended = Some(Ended::Gone);
                break;
            }
        }
    }
    let heard = Listen {
        baud,
        batches,
        bytes,
    };
    (heard, ended)
}

/// The outcome of a live detection.
pub(super) struct LiveReport {
    /// The best candidate at each rate, when one was recognised.
    pub(super) per_rate: Vec<Option<Ranked>>,
    /// Index of the rate and the winner.
    pub(super) best: Option<(usize, Ranked)>,
}

/// Ranks every rate's bytes; the winner is the best share over all rates, ties (a pty, or a
/// line that looks the same at two rates) going to the protocol's own default rate.
pub(super) fn judge_live(listens: &[Listen]) -> LiveReport {
    let mut per_rate: Vec<Option<Ranked>> = Vec::new();
    for l in listens {
        let ranked = rank(
            candidates(Kind::Serial, Some(l.baud)),
            &l.batches,
            Kind::Serial,
        );
        let best = ranked.into_iter().next().filter(|r| r.score.recognised());
        per_rate.push(best);
    }
    let key = |i: usize, r: &Ranked| {
        let share = (r.score.share() * 50.0).round() as i64; // 2 % steps
        let default = i64::from(listens[i].baud == r.protocol.line.baud);
        (share, default, r.score.frames)
    };
    let best_i = per_rate
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.as_ref().map(|r| (i, key(i, r))))
        .max_by_key(|&(_, k)| k)
        .map(|(i, _)| i);
    let best = best_i.and_then(|i| per_rate[i].take().map(|r| (i, r)));
    LiveReport { per_rate, best }
}
