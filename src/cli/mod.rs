//! Command line: argument parsing, wiring source → decoder → sink, messages and exit codes.

use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

use crate::exit::{Failure, code};
use crate::filter::Selection;
use crate::pace::{Paced, Pacer};
use crate::protocol::{Decoder, InputKind, Line, Protocol, Setup};
use crate::record::{Content, Recorder};
use crate::run::{Context, drive};
use crate::signal::Stop;
use crate::sink::limit::{Limit, Stops};
use crate::sink::{Format, Output, Table};
use crate::source::serial::{self, SerialReader};
use crate::source::{self, ChunkReader, Input};
use crate::top::Top;
use crate::top::view::Info;

mod args;
mod bare;
mod choices;
mod extcap;
mod manual;
mod many;
mod open;
mod paths;
pub mod project;

pub use args::*;
use open::{
    check_top, check_wide, open_source, open_table, option_notes, source_notes, wait_for_adapter,
};
use paths::check_distinct;

/// Entry point of the binary.
pub fn main() -> ExitCode {
    // Wireshark runs an extcap with its own options first (`busnoop --extcap-interfaces`):
    // a symlink to busnoop in the extcap folder is `busnoop extcap …`.
    let mut argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if argv
        .get(1)
        .and_then(|a| a.to_str())
        .is_some_and(|a| a.starts_with("--extcap-") || a == "--capture")
    {
        argv.insert(1, "extcap".into());
    }
    // `busnoop FILE`: detect first, then decode as the protocol found.
    let argv = match bare::arrange(argv) {
        bare::Words::Clap(argv) => argv,
        bare::Words::Bare { argv, at } => match bare::resolve(argv, at) {
            Ok(argv) => argv,
            Err(f) => {
                if !f.is_quiet() {
                    eprintln!("busnoop: {f}");
                }
                return ExitCode::from(f.exit_code());
            }
        },
    };
    let (parsed, verbose) = match Parsed::from(argv) {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() {
                code::USAGE
            } else {
                code::OK
            });
        }
    };
    init_tracing(verbose);
    let (code, message) = match run(parsed) {
        Ok(()) => (code::OK, String::new()),
        Err(f) => {
            if !f.is_quiet() {
                eprintln!("busnoop: {f}");
            }
            (f.exit_code(), f.to_string())
        }
    };
    // The statistics as JSON: after every other message, whatever the end.
    ExitCode::from(crate::stats_json::finish(code, &message))
}

fn init_tracing(verbose: u8) {
    use tracing_subscriber::EnvFilter;
    let default = match verbose {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    // Colour codes only on a terminal (and not with NO_COLOR): `-v 2>log` stays plain text.
    let ansi = std::io::stderr().is_terminal()
        && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty());
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(ansi)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}

/// `busnoop plot`: the protocol's command with its rows going to a plot.
fn plot(a: &PlotArgs) -> Result<(), Failure> {
    crate::plot::check(&a.output)?;
    let (command, extra): (&str, &[&str]) = match &a.protocol {
        Some(p) => (p.as_str(), &[]),
        None => {
            // Detection reads the input's start, then the plot reads the input again: a pipe
            // (standard input, a FIFO) would have given its bytes to the detection only.
            use std::os::unix::fs::FileTypeExt;
            let pipe = is_dash(&a.source)
                || std::fs::metadata(&a.source).is_ok_and(|m| m.file_type().is_fifo());
            if pipe {
                return Err(Failure::Usage(format!(
                    "plot {}: a pipe can be read only once, so its protocol cannot be \
                     detected before it is plotted; name it with --protocol {}",
                    a.source.display(),
                    crate::protocols::commands()
                )));
            }
            let (p, args) = crate::detect::protocol_of(&a.source)?;
            (p.command, args)
        }
    };
    // The protocol's own options: the user's, and the detected variant's where the user gave
    // none of that name.
    let given = |name: &str| {
        a.protocol_args.iter().any(|u| {
            u.to_str()
                .is_some_and(|u| u.split('=').next() == Some(name))
        })
    };
    let mut argv: Vec<std::ffi::OsString> = vec!["busnoop".into(), command.into()];
    let mut skip_value = false;
    for e in extra {
        if e.starts_with("--") {
            skip_value = given(e.split('=').next().unwrap_or(e));
            if skip_value {
                continue;
            }
        } else if std::mem::take(&mut skip_value) {
            continue;
        }
        argv.push(e.into());
    }
    argv.extend(a.protocol_args.iter().cloned());
    argv.push("--".into());
    argv.push(a.source.clone().into());
    let (Parsed::Protocol(mut run), _) = Parsed::from(argv).map_err(|e| {
        Failure::Usage(format!(
            "plot: the options after -- are {command}'s: {}",
            e.to_string()
                .lines()
                .next()
                .unwrap_or("")
                .trim_start_matches("error: ")
        ))
    })?
    else {
        return Err(Failure::Internal(format!(
            "plot: {command} is not a protocol"
        )));
    };
    // The table's selection and project file; `--sensor` names the series instead.
    let sensors: Vec<String> = a
        .select
        .sensor
        .iter()
        .flat_map(|s| s.split(','))
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::to_owned)
        .collect();
    run.capture.select = project::SelectArgs {
        sensor: Vec::new(),
        ..a.select.clone()
    };
    let vocab = (run.protocol.vocab.sensors)();
    let mut wanted = Vec::new();
    for name in &sensors {
        wanted.push(name.clone());
        // A Sensor column name plots its numbers (`Volts` → VFAS, `Cels` → every cell); a
        // number's name only that number.
        for s in vocab.iter().filter(|s| s.column.eq_ignore_ascii_case(name)) {
            wanted.push(s.column.clone());
            wanted.extend(s.parts.iter().cloned());
        }
    }
    run.capture.output.plot = Some(crate::plot::PlotSpec {
        sensors,
        wanted,
        path: a.output.clone(),
        title: format!(
            "{} ({command})",
            a.source.file_name().map_or_else(
                || a.source.display().to_string(),
                |n| n.to_string_lossy().into_owned()
            )
        ),
        from: a.from,
        to: a.to,
    });
    run_protocol(run)
}

/// Runs a parsed command line.
pub fn run(parsed: Parsed) -> Result<(), Failure> {
    match parsed {
        Parsed::Protocol(r) => run_protocol(r),
        Parsed::Other(Command::Ports) => list_ports(),
        Parsed::Other(Command::Extcap(a)) => extcap::run(&a),
        Parsed::Other(Command::Detect(a)) => crate::detect::run(&a.options()),
        Parsed::Other(Command::Plot(a)) => plot(&a),
        Parsed::Other(Command::Completions { shell }) => manual::completions(shell),
        Parsed::Other(Command::Man { dir }) => manual::man(dir.as_deref()),
    }
}

/// A protocol's subcommand: the project file's section under the command line, the filters
/// and names, then the capture.
fn run_protocol(run: Box<Run>) -> Result<(), Failure> {
    let Run {
        protocol,
        mut capture,
        mut options,
    } = *run;
    let file = project::File::load(&capture.select)?;
    if let Some(f) = &file {
        let empty = toml::Table::new();
        options.configure(&f.own_keys(protocol, &empty))?;
    }
    options.check()?;
    let section = file
        .as_ref()
        .and_then(|f| Some((f.section(protocol)?, f.name())));
    let sel = project::selection(
        &capture.select,
        protocol,
        section,
        &options.names(),
        &options.sensors(),
    )?;
    prepare(&mut capture, section);
    // Say what the project file changes: it filters and names rows without a word otherwise.
    if let Some(f) = &file
        && let Some(set) = f.settings(protocol)
    {
        // Said on stderr once the outputs are checked (a refused -o is the only message).
        capture.output.preface = Some(format!("project file {}: {set}", f.name().display()));
    }
    if let Some(p) = &capture.output.stats_json {
        check_stats_file(p, &capture.source)?;
    }
    crate::stats_json::expect(
        crate::stats_json::Destinations {
            stderr: capture.output.stats_format == Some(StatsFormat::Json),
            file: capture.output.stats_json.clone(),
        },
        protocol.name,
    );
    let names: Vec<(String, u32)> = sel
        .names
        .pairs()
        .map(|(n, id)| (n.to_owned(), id))
        .collect();
    let default_line = options.line(protocol.line);
    run_capture(&capture, protocol, default_line, &sel, |input, line| {
        options.decoder(&Setup {
            input,
            line: *line,
            names: &names,
        })
    })
}

/// `--stats-json FILE`: its folder exists, and it is not the input (it is written at the end,
/// when the input was read).
fn check_stats_file(path: &Path, source: &Path) -> Result<(), Failure> {
    crate::files::check_folder(path)?;
    let same = std::fs::canonicalize(path)
        .ok()
        .is_some_and(|p| std::fs::canonicalize(source).is_ok_and(|s| s == p));
    if same {
        return Err(Failure::Usage(format!(
            "--stats-json {} is the input: writing it would destroy the capture; write \
             somewhere else",
            path.display()
        )));
    }
    Ok(())
}

/// The project file's defaults under the command line's options; `--stats-format` implies
/// `--stats`.
fn prepare(capture: &mut CaptureArgs, section: Option<(&project::Section, &Path)>) {
    if let Some((s, _)) = section {
        project::apply_defaults(s, &mut capture.output, &mut capture.live.baud);
    }
    if capture.output.stats_format.is_some() {
        capture.output.stats = true;
    }
}

/// The failure for an input of a kind `protocol` cannot read.
fn unusable(kind: InputKind, protocol: &Protocol) -> Failure {
    let what = match kind {
        InputKind::Pcap | InputKind::Pcapng => "a pcap of network traffic",
        InputKind::EdgeTxLog => "an EdgeTX/OpenTX S.Port log",
        InputKind::Recording => "a busnoop recording",
        InputKind::Raw | InputKind::Serial => "raw serial data",
        InputKind::Trace => "a logic-analyzer trace",
    };
    // The subcommands that do read it (`busnoop sbus` for an Ether-S-Bus pcap).
    let readers: Vec<String> = crate::protocols::PROTOCOLS
        .iter()
        .filter(|p| p.reads(kind))
        .map(|p| format!("busnoop {}", p.command))
        .collect();
    let instead = match readers.len() {
        0 => String::new(),
        _ => format!("; {} reads it", readers.join(" or ")),
    };
    Failure::Input(format!(
        "this is {what}; {} captures are {}{instead}",
        protocol.name, protocol.accepts_text
    ))
}

/// `-` as a file name: standard input or output.
pub(crate) fn is_dash(p: &Path) -> bool {
    p.as_os_str() == "-"
}

/// Opens SOURCE (a device, a file or standard input), picks the reader for its kind, asks
/// `decoder_for` for the protocol decoder, decodes everything into the table and prints the
/// summary. Several sources (or a recording of several ports) go to [`many::run`].
pub fn run_capture(
    args: &CaptureArgs,
    protocol: &Protocol,
    default_line: Line,
    selection: &Selection,
    decoder_for: impl Fn(InputKind, &Line) -> Result<Box<dyn Decoder>, Failure>,
) -> Result<(), Failure> {
    let record_to_stdout = args.live.record.as_deref().is_some_and(is_dash);
    if record_to_stdout && args.output.output_file().is_none() {
        return Err(Failure::Usage(
            "--record - needs -o FILE: standard output already carries the table".into(),
        ));
    }
    check_top(args, record_to_stdout)?;
    check_wide(&args.output)?;
    // The clash with the input first: the capture-name hint below would point at it again.
    // The table's file is the image for `busnoop plot`.
    let input = Input::parse(&args.source);
    let table_file = match &args.output.plot {
        Some(p) => Some(p.path.as_path()),
        None => args.output.output_file(),
    };
    for source in args.sources() {
        check_distinct(
            &Input::parse(source),
            table_file,
            args.live.record.as_deref(),
            args.live.export.as_deref(),
            project::File::path(&args.select).as_deref(),
        )?;
    }
    // `>&-`: the table or the recording on standard output would vanish with exit 0.
    if ((table_file.is_none() && !args.output.top) || record_to_stdout)
        && crate::files::stdout_was_closed()
    {
        return Err(Failure::Output(
            "standard output is closed (>&-): what goes there would be lost; give -o FILE, or \
             send it somewhere (>FILE, >/dev/null)"
                .into(),
        ));
    }
    if let Some(p) = args.live.record.as_deref().filter(|p| !is_dash(p)) {
        crate::record::RecordFormat::for_path(p)?;
    }
    if let Some(line) = args.output.preface.as_deref()
        && let Some(line) = line.strip_prefix("project file ")
        && !QUIET_REPORT.load(std::sync::atomic::Ordering::Relaxed)
    {
        eprintln!("busnoop: using {line} (--no-config ignores it)");
    }
    if let Some(p) = args.live.export.as_deref() {
        crate::export::check(p, protocol)?;
    }
    // A missing folder in any output name, before the input is opened or any output created.
    for p in [
        table_file,
        args.live.record.as_deref(),
        args.live.export.as_deref(),
    ]
    .into_iter()
    .flatten()
    .filter(|p| !is_dash(p))
    {
        crate::files::check_folder(p)?;
    }
    if let Some(p) = args.output.output_file()
        && p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
            ["pcap", "pcapng", "bin"]
                .iter()
                .any(|c| e.eq_ignore_ascii_case(c))
        })
    {
        return Err(Failure::Usage(format!(
            "-o writes the decoded table (pretty, tsv, csv or jsonl); to keep the bytes from the \
             wire use --record {}",
            p.display()
        )));
    }
    let stop = Stop::install()
        .map_err(|e| Failure::Internal(format!("cannot install signal handlers: {e}")))?;
    let mut line = default_line;
    // A trace's rate is measured unless it is given (--baud, or a speed in --line).
    let mut fixed_baud = args.live.baud;
    if let Some(l) = &args.live.line {
        line = line
            .parse_over(l)
            .map_err(|e| Failure::Usage(format!("--line {e}")))?;
        if !BAUD_RANGE.contains(&i64::from(line.baud)) {
            return Err(Failure::Usage(format!(
                "--line {l}: the speed is out of range: from 50 to 12000000 baud"
            )));
        }
        if line.baud != default_line.baud {
            fixed_baud = fixed_baud.or(Some(line.baud));
        }
    }
    if let Some(b) = args.live.baud {
        line.baud = b;
    }
    let serial = serial::SerialConfig {
        line,
        lines: args.live.dtr_rts,
    };
    let trace = source::logic::Options {
        line,
        baud: fixed_baud,
        channel: args.live.channel.first().cloned(),
    };
    if !args.more.is_empty() || args.live.channel.len() > 1 || many::several_ports(&input) {
        return many::run(
            args,
            protocol,
            &serial,
            &trace,
            selection,
            &decoder_for,
            &stop,
        );
    }
    let input = match args.live.reconnect {
        true => wait_for_adapter(&args.source)?.unwrap_or(input),
        false => input,
    };
    if matches!(input, Input::Stdin) && std::io::stdin().is_terminal() {
        // Nothing is piped in: the user would type the bytes, or wait forever without a word.
        eprintln!("busnoop: reading standard input (Ctrl-D to end)");
    }
    // A capture reader hands on its first input bytes for the wrong-protocol check after the
    // run (which looks at the first ADVICE_BYTES only); a recording keeps its packets.
    let keep_input = if matches!(input, Input::Device(_)) {
        0
    } else {
        crate::detect::ADVICE_BYTES as u64
    };
    let (kind, reader, progress) = open_source(
        input,
        &serial,
        &trace,
        args.live.reconnect,
        keep_input,
        None,
    )?;
    if !args.live.channel.is_empty() && kind != InputKind::Trace {
        return Err(Failure::Usage(format!(
            "--channel picks a wire of a logic-analyzer trace; {} is not one",
            args.source.display()
        )));
    }
    tracing::info!("{}: {:?}", args.source.display(), kind);
    if !protocol.reads(kind) {
        return Err(unusable(kind, protocol));
    }
    if args.live.export.is_some() && matches!(kind, InputKind::Pcap | InputKind::Pcapng) {
        // Only a serial line needs re-wrapping: network captures are Wireshark's already.
        return Err(Failure::Usage(format!(
            "--export re-wraps the frames of a serial line; {} is a network capture, which \
             Wireshark opens as it is",
            args.source.display()
        )));
    }
    // Before anything else is written: a recording of packets refuses a raw name.
    let content = match kind {
        InputKind::Pcap | InputKind::Pcapng => Content::Packets,
        InputKind::Serial | InputKind::EdgeTxLog | InputKind::Recording | InputKind::Trace => {
            Content::Line { timed: true }
        }
        InputKind::Raw => Content::Line { timed: false },
    };
    let mut recorder = match &args.live.record {
        Some(_) if record_to_stdout => Some(Recorder::stdout(content)),
        Some(p) => {
            let mut r = Recorder::create(p, content)?;
            if content != Content::Packets {
                r.describe(
                    &args.source.to_string_lossy(),
                    &crate::record::line_description(protocol.name, &line),
                );
            }
            Some(r)
        }
        None => None,
    };
    for note in option_notes(&args.output, kind)
        .into_iter()
        .chain(source_notes(args, kind))
    {
        eprintln!("busnoop: note: {note}");
    }
    // Files and streams: keep their start, to tell a wrong protocol afterwards.
    let (reader, kept): (Box<dyn ChunkReader>, _) = if kind == InputKind::Serial {
        (reader, None)
    } else {
        let (tee, kept) = crate::detect::Tee::new(reader);
        (Box::new(tee), Some(kept))
    };
    let mut decoder = decoder_for(kind, &line)?;
    let mut export = match &args.live.export {
        Some(p) => Some(crate::export::Exporter::create(
            p,
            protocol,
            &args.source.to_string_lossy(),
            &crate::record::line_description(protocol.name, &line),
        )?),
        None => None,
    };
    let out = &args.output;
    let mut table = open_table(
        out,
        args.run.quiet,
        decoder.columns(),
        protocol.pretty_widths,
        kind == InputKind::Serial,
        protocol.vocab.polls,
    )?;
    let live = kind == InputKind::Serial;
    let stops = Stops {
        count: args.run.count,
        duration: args.run.duration,
        idle: args.run.until_idle,
    };
    let speed = out.speed.unwrap_or(if out.top { 1.0 } else { 0.0 });
    let pacer = if live { None } else { Pacer::new(speed) };
    let rx = source::spawn(reader, progress);
    let source_name = args.source.display().to_string();
    let ctx = Context {
        stop: &stop,
        recorder: recorder.as_mut().map(|r| r as &mut dyn crate::record::Keep),
        protocol: protocol.name,
        live,
        source: &source_name,
        selection,
        quiet: QUIET_REPORT.load(std::sync::atomic::Ordering::Relaxed),
    };
    if let Some(t) = &mut table {
        t.header().map_err(Failure::from)?;
    }
    let (result, rows) = if out.top {
        let info = Info {
            protocol: protocol.name.to_owned(),
            source: source_name.clone(),
            baud: live.then_some(line.baud),
            speed: pacer.as_ref().map(Pacer::speed),
            live,
            vocab: Some(protocol.vocab),
            names: selection.names.clone(),
            sensors: selection.sensors.clone(),
        };
        let columns = decoder.columns().to_vec();
        let mut view = Top::open(table.as_mut(), &columns, info, pacer)
            .map_err(|e| Failure::Output(format!("cannot set up the terminal for --top: {e}")))?;
        let mut exporting;
        let sink: &mut dyn crate::sink::Sink = match export.as_mut() {
            Some(export) => {
                exporting = crate::export::Exporting {
                    inner: &mut view,
                    tap: export,
                };
                &mut exporting
            }
            None => &mut view,
        };
        let mut limit = None;
        let sink = Limit::around(&mut limit, sink, stops, live);
        let result = drive(decoder.as_mut(), &rx, sink, ctx);
        if result.is_ok() {
            view.hold();
        }
        let rows = view.rows();
        // Leaves the alternate screen and gives stderr back (with what was written to it).
        drop(view);
        (result, rows)
    } else {
        let table = table.as_mut().expect("a table without --top");
        let mut exporting;
        let sink: &mut dyn crate::sink::Sink = match export.as_mut() {
            Some(export) => {
                exporting = crate::export::Exporting {
                    inner: &mut *table,
                    tap: export,
                };
                &mut exporting
            }
            None => &mut *table,
        };
        let mut paced;
        let sink: &mut dyn crate::sink::Sink = match pacer {
            Some(pacer) => {
                paced = Paced {
                    inner: sink,
                    tap: pacer,
                };
                &mut paced
            }
            None => sink,
        };
        let mut limit = None;
        let sink = Limit::around(&mut limit, sink, stops, live);
        let result = drive(decoder.as_mut(), &rx, sink, ctx);
        (result, table.rows())
    };
    let stats = match (out.stats, out.stats_format) {
        (false, _) => None,
        (true, Some(StatsFormat::Json)) => Some(StatsFormat::Json),
        (true, _) => Some(StatsFormat::Text),
    };
    let hidden = table.as_ref().map_or(0, Table::skipped);
    report(
        decoder.as_ref(),
        stats,
        protocol.name,
        rows,
        hidden,
        &result,
    );
    // Frames that decoded: the table counts its frame rows, the decoder its valid frames.
    // (Rows a filter hid are not in the table's count; the decoder's count has them.)
    let frames = table
        .as_ref()
        .map_or(0, |t| t.frames())
        .max(decoder.valid_frames());
    let mut poor = None;
    // A clean run, or one with a few bad frames among many good ones, needs no second look;
    // otherwise (nothing decoded, or a fifth or more of the rows are not frames: errors, garbage,
    // timeouts) the start of the input is scored against every protocol (`busnoop detect`'s
    // scoring, on the first 16 KiB).
    if result.is_ok()
        && let Some(kept) = kept
        && (frames == 0
            || (decoder.problems().line().is_some() && rows.saturating_sub(frames) * 4 >= frames))
        && let Ok(kept) = kept.lock()
    {
        use crate::detect::{Advice, advise};
        match advise(protocol, kind, &kept, frames, &args.source) {
            Advice::Fine => {}
            Advice::Poor(m) if args.run.lenient => eprintln!("busnoop: note: {m}"),
            Advice::Poor(m) => {
                eprintln!("busnoop: {m}");
                poor = Some(Failure::Poor(format!(
                    "most of the input is not valid {} frames (exit code 13; --lenient accepts \
                     such a run)",
                    protocol.name
                )));
            }
            Advice::NothingDecoded(m) => return Err(Failure::NothingDecoded(m)),
        }
    }
    // `busnoop plot`: drawn once the input is read, also after Ctrl-C (what was read so far),
    // whose exit code then stays.
    if let Some(mut plot) = table.as_mut().and_then(Table::take_plot)
        && let Err(f) = plot.draw()
    {
        if result.is_ok() {
            return Err(f);
        }
        eprintln!("busnoop: {f}");
    }
    match poor {
        Some(f) if result.is_ok() => Err(f),
        _ => result,
    }
}

/// `busnoop ports`.
fn list_ports() -> Result<(), Failure> {
    let ports = serial::list_ports();
    if ports.is_empty() {
        eprintln!("busnoop: no serial ports found");
        return Ok(());
    }
    let mut text = String::new();
    text.push_str("PORT\tTYPE\tVID:PID\tSERIAL\tMANUFACTURER\tPRODUCT\tBY-ID\n");
    for p in ports {
        let vid_pid = p
            .vid_pid
            .map_or(String::new(), |(v, pid)| format!("{v:04x}:{pid:04x}"));
        text.push_str(&format!(
            "{}\t{}\t{}\t{}\t{}\t{}\t{}\n",
            p.name,
            p.kind,
            vid_pid,
            p.serial_number.unwrap_or_default(),
            p.manufacturer.unwrap_or_default(),
            p.product.unwrap_or_default(),
            p.by_id.map(|b| b.display().to_string()).unwrap_or_default()
        ));
    }
    crate::exit::write_stdout(text.as_bytes())
}

/// Set for a capture Wireshark runs (`busnoop extcap --capture`): Wireshark shows whatever an
/// extcap writes on stderr as an error when the capture stops, so the end-of-run summary
/// ([`report`]) is left out. Failures are still reported.
pub(crate) static QUIET_REPORT: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// The end-of-run summary on stderr: the full statistics with --stats, otherwise one line when
/// something went wrong.
fn report(
    decoder: &dyn Decoder,
    stats: Option<StatsFormat>,
    protocol: &str,
    rows: u64,
    hidden: u64,
    result: &Result<(), Failure>,
) {
    if QUIET_REPORT.load(std::sync::atomic::Ordering::Relaxed) {
        return;
    }
    // Written at the very end (`main`), after the failure's message if any.
    if crate::stats_json::wanted() {
        crate::stats_json::record(
            &decoder.stats(),
            protocol,
            rows,
            hidden,
            decoder.valid_frames(),
            &decoder.problems(),
        );
    }
    if matches!(result, Err(Failure::BrokenPipe)) {
        return;
    }
    if stats == Some(StatsFormat::Text) {
        if hidden > 0 {
            eprintln!(
                "{protocol} statistics ({rows} rows, {} shown, {hidden} hidden by filters)",
                rows - hidden
            );
        } else {
            eprintln!("{protocol} statistics ({rows} rows)");
        }
        eprintln!("{}", decoder.stats());
    }
    // Filters that are each fine but together keep nothing (`--type Null --errors`).
    if rows > 0 && hidden == rows && result.is_ok() {
        eprintln!("busnoop: note: the filters hid all {rows} rows");
    }
    // When the output failed, the one line that matters is the write error (printed last).
    let problems = decoder.problems();
    if !matches!(result, Err(Failure::Output(_)))
        && stats != Some(StatsFormat::Json)
        && let Some(p) = problems.line()
    {
        eprintln!("busnoop: {p}");
    }
    if let Err(Failure::Signal(i)) = result {
        eprintln!(
            "busnoop: interrupted after {rows} rows; all decoded rows were written{}",
            i.input_note()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(extra: &[&str]) -> OutputArgs {
        let mut argv = vec!["busnoop", "sport", "x"];
        argv.extend_from_slice(extra);
        match Parsed::from(argv).unwrap().0 {
            Parsed::Protocol(r) => r.capture.output,
            Parsed::Other(_) => unreachable!(),
        }
    }

    /// The command line lists every protocol of the table first, in its order, each with its
    /// aliases, and parses each one's subcommand into that protocol.
    #[test]
    fn every_protocol_of_the_table_has_its_subcommand() {
        let table: Vec<&str> = crate::protocols::PROTOCOLS
            .iter()
            .map(|p| p.command)
            .collect();
        let mut cmd = args::command();
        cmd.build();
        let mut subs: Vec<&clap::Command> = cmd.get_subcommands().collect();
        subs.sort_by_key(|c| c.get_display_order());
        let names: Vec<&str> = subs.iter().map(|c| c.get_name()).collect();
        assert_eq!(names[..table.len()], table[..]);
        for p in crate::protocols::PROTOCOLS {
            for name in std::iter::once(p.command).chain(p.aliases.iter().copied()) {
                match Parsed::from(["busnoop", name, "x"]).unwrap().0 {
                    Parsed::Protocol(r) => assert_eq!(r.protocol.command, p.command),
                    Parsed::Other(_) => panic!("{name}"),
                }
            }
        }
    }

    #[test]
    fn format_defaults() {
        assert_eq!(args(&[]).table_options(true, false).format, Format::Pretty);
        assert_eq!(args(&[]).table_options(false, false).format, Format::Tsv);
        assert_eq!(
            args(&["-o", "a.csv"]).table_options(false, false).format,
            Format::Csv
        );
        assert_eq!(
            args(&["-o", "a.bin"]).table_options(false, false).format,
            Format::Tsv
        );
        assert_eq!(
            args(&["-o", "a.csv", "-f", "jsonl"])
                .table_options(false, false)
                .format,
            Format::Jsonl
        );
    }

    #[test]
    fn colour_follows_terminal_no_color_and_the_option() {
        assert!(args(&[]).table_options(true, false).color);
        assert!(
            !args(&[]).table_options(true, true).color,
            "NO_COLOR turns auto off"
        );
        assert!(
            !args(&[]).table_options(false, false).color,
            "not a terminal"
        );
        assert!(
            args(&["-f", "pretty", "--color", "always"])
                .table_options(false, true)
                .color
        );
        assert!(!args(&["--color", "never"]).table_options(true, false).color);
        assert!(
            !args(&["-f", "tsv", "--color", "always"])
                .table_options(true, false)
                .color
        );
    }
}
