//! `busnoop detect` on a serial port: listen passively at each baud rate, score what was heard.

use super::*;

/// One listen: a line setting (speed and character format) and what arrived.
pub(super) struct Listen {
    pub(super) line: Line,
    pub(super) batches: Vec<Batch>,
    pub(super) bytes: u64,
}

/// The line settings to listen at: each protocol's character format at each of its rates (or at
/// each of `bauds`, when given), once each, by format (in the order of the protocol table, so
/// 8N1 first) and then speed. A UART set to 8N1 loses the characters of an 8E2 line, so every
/// protocol is heard in its own format.
pub(super) fn listen_lines(bauds: &[u32]) -> Vec<Line> {
    let mut out: Vec<Line> = Vec::new();
    let mut formats: Vec<String> = Vec::new();
    for p in PROTOCOLS {
        let rates = if bauds.is_empty() { p.rates } else { bauds };
        if !formats.contains(&p.line.format()) {
            formats.push(p.line.format());
        }
        for &baud in rates {
            let line = Line { baud, ..p.line };
            if !out.contains(&line) {
                out.push(line);
            }
        }
    }
    out.sort_by_key(|l| (formats.iter().position(|f| *f == l.format()), l.baud));
    out
}

/// What a live detection heard: the report `busnoop detect` prints, and the winner.
pub(super) struct Heard {
    pub(super) text: String,
    pub(super) result: Result<Chosen, Failure>,
}

/// `busnoop detect /dev/ttyUSB0`: listens at each line setting in turn, passively (the device
/// is opened read-only, as for a capture), and ranks every (setting, protocol) pair.
pub(super) fn live(path: &Path, args: &Options) -> Result<Heard, LiveError> {
    let lines = listen_lines(&args.bauds);
    let listen = Duration::from_millis(args.listen_ms);
    // Ctrl-C, SIGTERM, SIGHUP and an unplug end the listening; what was heard is still judged.
    let stop = crate::signal::Stop::install().map_err(|e| {
        LiveError::Failed(Failure::Internal(format!(
            "cannot install signal handlers: {e}"
        )))
    })?;
    let mut listens = Vec::new();
    let mut ended = None;
    for &line in &lines {
        if let Some(sig) = stop.signal() {
            ended = Some(Ended::Signal(sig));
            break;
        }
        let cfg = SerialConfig {
            line,
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
                "busnoop: listening to {} for {} ms at each of {} line settings (speed and \
                 character format)",
                path.display(),
                args.listen_ms,
                lines.len()
            );
        }
        let (heard, end) = listen_once(port.as_mut(), path, line, listen, &stop);
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
        return Err(LiveError::Failed(end.failure(path, &listens, lines.len())));
    }
    let mut text = format!("{}: a serial line\n", path.display());
    let report = judge_live(&listens);
    for (l, best) in listens.iter().zip(&report.per_rate) {
        text.push_str(&format!(
            "  {:>7} baud {}: {:>7} bytes",
            l.line.baud,
            l.line.format(),
            l.bytes
        ));
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
            "no bytes arrived at any line setting in {} ms each: check the wiring (the adapter's \
             RX to the bus line, GND to ground) and that the bus is talking",
            args.listen_ms
        ))),
        Some(i) => {
            let r = report.per_rate[*i].as_ref().expect("the winner's row");
            let baud = listens[*i].line.baud;
            found_text(&mut text, r, path, Some(baud));
            Ok(Chosen::of(r, Some(baud)))
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
    // Cut short (a signal, the adapter gone): the report of what was heard, then that failure.
    let result = match ended {
        Some(end) => Err(end.failure(path, &listens, lines.len())),
        None => result,
    };
    Ok(Heard { text, result })
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
            "after listening at {} of {rates} line settings; the verdict is on what was heard",
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
    line: Line,
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
        line,
        batches,
        bytes,
    };
    (heard, ended)
}

/// The outcome of a live detection.
pub(super) struct LiveReport {
    /// The best candidate at each line setting, when one was recognised.
    pub(super) per_rate: Vec<Option<Ranked>>,
    /// The line setting of the winner (its row in `per_rate`).
    pub(super) best: Option<usize>,
}

/// Ranks every listen's bytes against the protocols of its character format; the winner is the
/// best share over all settings, ties (a pty, or a line that looks the same at two rates) going
/// to the protocol's own default rate.
pub(super) fn judge_live(listens: &[Listen]) -> LiveReport {
    let mut per_rate: Vec<Option<Ranked>> = Vec::new();
    for l in listens {
        let ranked = rank(
            candidates(InputKind::Serial, Some(l.line)),
            &l.batches,
            InputKind::Serial,
        );
        let best = ranked.into_iter().next().filter(|r| r.score.recognised());
        per_rate.push(best);
    }
    let key = |i: usize, r: &Ranked| {
        let share = (r.score.share() * 50.0).round() as i64; // 2 % steps
        let default = i64::from(listens[i].line.baud == r.protocol.line.baud);
        (share, default, r.score.frames)
    };
    let best = per_rate
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.as_ref().map(|r| (i, key(i, r))))
        .max_by_key(|&(_, k)| k)
        .map(|(i, _)| i);
    LiveReport { per_rate, best }
}
