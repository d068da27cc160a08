//! Before a run: the checks of what the options ask for this input and output, opening the
//! source (a serial device, a file or pipe, a capture, a trace) and the table.

use std::io::IsTerminal;
use std::path::Path;

use super::*;

/// The table (`None` with `--top` and no `-o`: the view is the only output): `extra`, the
/// columns after the base ones (the decoder's, after `Port` with several sources); `widths`, the
/// pretty widths of the first columns; `live`: the source is a serial device.
pub(super) fn open_table(
    out: &OutputArgs,
    quiet: bool,
    extra: &[&'static str],
    widths: &[usize],
    live: bool,
    polls: bool,
) -> Result<Option<Table>, Failure> {
    // With --top and no -o, the view is the only output.
    Ok(match (out.top, out.output_file()) {
        (true, None) => None,
        (_, file) => {
            let output = match file {
                Some(p) => Output::create(p).map_err(|e| {
                    Failure::from_create(&format!("cannot create {}", p.display()), &e)
                })?,
                // -q: the table is counted (the summary, the exit code) but written nowhere.
                None if quiet => Output::create(Path::new("/dev/null"))
                    .map_err(|e| Failure::Output(format!("cannot open /dev/null: {e}")))?,
                None => Output::stdout(),
            };
            let to_terminal = file.is_none() && !quiet && std::io::stdout().is_terminal();
            let no_color_env = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
            let mut table = Table::new(output, out.table_options(to_terminal, no_color_env), extra);
            table.set_pretty_widths(widths);
            table.set_preface(out.preface.clone());
            if to_terminal && !out.no_fit {
                table.fit_terminal();
            }
            if let Some(p) = &out.plot {
                table.set_plot(p.clone());
            }
            if out.wide {
                // CSV or TSV: check_wide refused the others before anything was opened.
                // Protocols without a poll cycle step by frame.
                let step = match out.every {
                    Some(ms) => crate::sink::wide::Step::Every(ms * 1000),
                    None if polls => crate::sink::wide::Step::PollCycle,
                    None => crate::sink::wide::Step::Frame,
                };
                if out.raw || out.time == TimeMode::Abs {
                    eprintln!(
                        "busnoop: note: --wide has no Raw or Time column (--raw, --time abs); its \
                         Date and Time columns come with any source that has wall-clock time"
                    );
                }
                let max = out
                    .max_columns
                    .map_or(crate::sink::wide::MAX_COLUMNS, |n| n as usize);
                table.set_wide(step, live, max);
            }
            Some(table)
        }
    })
}

/// Notes on options that cannot do what they ask for this input or output: `--time abs` on a
/// source without times, `--utc` on times without a zone (or without `--time abs`), an `-o`
/// extension that names no format.
pub(super) fn option_notes(out: &OutputArgs, kind: InputKind) -> Vec<String> {
    let mut notes = Vec::new();
    if out.time == TimeMode::Abs && kind == InputKind::Raw {
        notes.push(
            "--time abs: raw wire bytes carry no wall-clock time, so the Time column stays \
             empty (a recording made with --record FILE.pcap keeps the times)"
                .to_string(),
        );
    }
    if out.time == TimeMode::Abs && kind == InputKind::Trace {
        notes.push(
            "--time abs: a logic-analyzer trace carries no wall-clock time busnoop can trust, so \
             the Time column stays empty; Millis counts from the start of the trace"
                .to_string(),
        );
    }
    if out.utc && out.time != TimeMode::Abs {
        notes.push("--utc has an effect only with --time abs".to_string());
    } else if out.utc && kind == InputKind::EdgeTxLog {
        notes.push(
            "--utc: an EdgeTX log's times have no time zone; they are shown as logged".to_string(),
        );
    }
    if out.format.is_none()
        && let Some(p) = out.output_file()
        && let Some(ext) = p.extension()
        && Format::from_path(p).is_none()
    {
        notes.push(format!(
            "-o {}: .{} is not a format busnoop writes; the table is TSV (tab-separated). Use \
             .csv, .tsv, .jsonl or .txt, or --format",
            p.display(),
            ext.to_string_lossy()
        ));
    }
    notes
}

/// Notes on the options of a serial line given for another source: they change nothing there,
/// and a warning (not a usage error) lets one command line serve a device and its recordings.
pub(super) fn source_notes(args: &CaptureArgs, kind: InputKind) -> Vec<String> {
    let mut notes = Vec::new();
    let live = &args.live;
    if kind == InputKind::Serial {
        if args.output.speed.is_some() {
            notes.push(
                "--speed has no effect on a serial port: rows come as the bus sends them".into(),
            );
        }
        return notes;
    }
    let what = match kind {
        InputKind::Pcap | InputKind::Pcapng => "a network capture",
        InputKind::Recording => "a recording",
        InputKind::EdgeTxLog => "an EdgeTX log",
        _ => "a file or pipe",
    };
    // Raw bytes carry no times: --baud and --line set the bits per byte they are given; a
    // logic-analyzer trace is read through a UART they set.
    let timed = !matches!(kind, InputKind::Raw | InputKind::Trace);
    if timed && live.baud.is_some() {
        notes.push(format!(
            "--baud has no effect on {what}: its times are its own (only a serial port and raw \
             bytes, whose times it sets, use it)"
        ));
    }
    if timed && live.line.is_some() {
        notes.push(format!(
            "--line has no effect on {what}: its bytes were framed when they were captured"
        ));
    }
    if live.reconnect {
        notes.push(format!(
            "--reconnect has no effect on {what}: only a serial adapter can be unplugged"
        ));
    }
    if live.dtr_rts != serial::ModemLines::default() {
        notes.push(format!(
            "--dtr-rts has no effect on {what}: only a serial port has DTR and RTS lines"
        ));
    }
    notes
}

/// `--reconnect` on an adapter that is not plugged in yet: waits for SOURCE to appear (a
/// `/dev/serial/by-id/…` name, a `/dev/ttyUSB0`), saying so once; a signal ends the wait.
/// `Some` with the input once it appeared, `None` when it was there.
pub(super) fn wait_for_adapter(source: &Path) -> Result<Option<Input>, Failure> {
    if is_dash(source) || std::fs::metadata(source).is_ok() {
        return Ok(None);
    }
    eprintln!(
        "busnoop: waiting for {} to appear (--reconnect; Ctrl-C to stop)",
        source.display()
    );
    loop {
        if let Some(sig) = crate::signal::Stop::received() {
            return Err(Failure::Signal(crate::exit::Interrupt::new(sig)));
        }
        if std::fs::metadata(source).is_ok() {
            eprintln!("busnoop: {} is there", source.display());
            return Ok(Some(Input::parse(source)));
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
}

/// `--top` draws on standard output, which must be a terminal and carry nothing else.
pub(super) fn check_top(args: &CaptureArgs, record_to_stdout: bool) -> Result<(), Failure> {
    if !args.output.top {
        return Ok(());
    }
    if args.output.output.as_deref().is_some_and(is_dash) {
        return Err(Failure::Usage(
            "--top draws on standard output; write the table with -o FILE".into(),
        ));
    }
    if record_to_stdout {
        return Err(Failure::Usage(
            "--top draws on standard output; record to a file (--record FILE.pcap)".into(),
        ));
    }
    if !std::io::stdout().is_terminal() {
        return Err(Failure::Usage(
            "--top needs a terminal on standard output; without one, write the table (drop \
             --top, or -o FILE)"
                .into(),
        ));
    }
    Ok(())
}

/// `--wide` writes CSV or TSV. Checked with the other usage errors, before the input is opened
/// and before anything is opened for writing: found later, the table file, the recording and
/// the export had already been emptied. With `--top` and no `-o` there is no table to widen.
pub(super) fn check_wide(out: &OutputArgs) -> Result<(), Failure> {
    let file = out.output_file();
    if !out.wide || (out.top && file.is_none()) {
        return Ok(());
    }
    let to_terminal = file.is_none() && std::io::stdout().is_terminal();
    if matches!(out.table_format(to_terminal), Format::Csv | Format::Tsv) {
        Ok(())
    } else {
        Err(Failure::Usage(
            "--wide writes CSV or TSV; add -f csv (or -o FILE.csv)".into(),
        ))
    }
}

/// Opens SOURCE and returns its kind with the reader for it; `keep_input`: a capture's reader
/// also hands on up to this many of its input bytes (for `--record`, the wrong-protocol check).
/// `clock`: the instant a serial device's capture time counts from (several ports: one clock
/// for all), else when it is opened.
pub(super) fn open_source(
    input: Input,
    cfg: &serial::SerialConfig,
    trace: &source::logic::Options,
    reconnect: bool,
    keep_input: u64,
    clock: Option<std::time::Instant>,
) -> Result<source::Reading, Failure> {
    if let Input::Device(path) = &input {
        match serial::open(path, cfg) {
            Ok(port) => {
                if let Some(w) = serial::latency_warning(path, std::path::Path::new("/sys")) {
                    eprintln!("busnoop: note: {w}");
                }
                let mut reader = SerialReader::new(path, port, *cfg, reconnect);
                if let Some(start) = clock {
                    reader = reader.starting_at(start);
                }
                return Ok((InputKind::Serial, Box::new(reader), None));
            }
            // A character device that is not a terminal (/dev/null, /dev/zero): read it as a file.
            Err(e) if serial::is_not_a_tty(&e) => {}
            Err(e) => return Err(serial::open_failure(path, &e)),
        }
    }
    let (opened, progress) = source::open(&input)?;
    let kind = opened.kind;
    let reader: Box<dyn ChunkReader> = match kind {
        InputKind::EdgeTxLog => Box::new(source::edgetx::EdgeTxReader::new(opened)),
        InputKind::Recording => Box::new(source::recording::RecordingReader::new(opened)),
        InputKind::Pcap | InputKind::Pcapng => {
            Box::new(source::capture::CaptureReader::new(opened, keep_input))
        }
        InputKind::Raw | InputKind::Serial => Box::new(source::RawReader::new(opened)),
        InputKind::Trace => source::logic::reader(opened, trace)?,
    };
    Ok((kind, reader, Some(progress)))
}
