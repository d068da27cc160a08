//! Several sources at once (`busnoop PROTO SRC1 SRC2 …`, or a recording of several ports): every
//! source opened before anything is written, one decoder per port built through the descriptor,
//! one table with a `Port` column, merged by time ([`crate::merge`]); the summary, the
//! statistics and the wrong-protocol advice per port.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::{
    CaptureArgs, QUIET_REPORT, StatsFormat, is_dash, open_source, open_table, option_notes,
    unusable,
};
use crate::detect::{Advice, Tee, advise};
use crate::exit::Failure;
use crate::filter::Selection;
use crate::merge::{self, How, Merged, Port, PortRecorder};
use crate::pace::{Paced, Pacer};
use crate::protocol::{Decoder, InputKind, Line, Protocol};
use crate::record::{RecordFormat, Recorder, line_description};
use crate::row::PORT_COLUMN;
use crate::signal::Stop;
use crate::source::recording::RecordingReader;
use crate::source::serial::SerialConfig;
use crate::source::{self, ChunkReader, Input, Progress};
use crate::time::Anchor;
use crate::top::Top;
use crate::top::view::Info;

/// The start of a recording read to list its ports (interface descriptions come first).
const HEAD: u64 = 64 * 1024;

/// Whether `input` is a recording of several ports.
pub(super) fn several_ports(input: &Input) -> bool {
    recorded_ports(input).len() > 1
}

/// The ports of a recording file (a pcapng with several serial-line interfaces): each
/// interface's ID and name. Empty for any other input, and for a pipe, which cannot be read once
/// per port.
fn recorded_ports(input: &Input) -> Vec<(u32, Option<String>)> {
    use crate::pcap::linktype::{RTAC_SERIAL, USER0};
    let Input::File(path) = input else {
        return Vec::new();
    };
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return Vec::new();
    }
    let mut head = Vec::new();
    let read = std::fs::File::open(path).and_then(|f| f.take(HEAD).read_to_end(&mut head));
    if read.is_err() || source::detect(&head, true) != Some(InputKind::Recording) {
        return Vec::new();
    }
    crate::pcap::pcapng_interfaces(&head)
        .into_iter()
        .enumerate()
        .filter(|(_, i)| matches!(i.link_type, RTAC_SERIAL | USER0))
        .map(|(at, i)| (at as u32, i.name))
        .collect()
}

/// Builds a port's decoder for its kind of input and the line (the same options for every
/// port, through the descriptor's `Options::decoder`).
type DecoderFor<'a> = dyn Fn(InputKind, &Line) -> Result<Box<dyn Decoder>, Failure> + 'a;

/// A source opened, before its decoder runs.
struct Opening {
    /// The `Port` cell.
    name: String,
    /// The file or device it reads.
    source: PathBuf,
    kind: InputKind,
    reader: Box<dyn ChunkReader>,
    progress: Option<Progress>,
}

/// Decodes every source (and every port of a recording of several) into one table.
pub(super) fn run(
    args: &CaptureArgs,
    protocol: &Protocol,
    serial: &SerialConfig,
    trace: &crate::source::logic::Options,
    selection: &Selection,
    decoder_for: &DecoderFor<'_>,
    stop: &Stop,
) -> Result<(), Failure> {
    check(args)?;
    let clock = Instant::now();
    let opened = open_all(args, protocol, serial, trace, clock)?;
    let live = opened[0].kind == InputKind::Serial;
    if let Some(o) = opened
        .iter()
        .find(|o| (o.kind == InputKind::Serial) != live)
    {
        let device = if live { o } else { &opened[0] };
        return Err(Failure::Usage(format!(
            "{} is a serial device and {} is not: sources decoded at once are all devices \
             (a live capture) or all files",
            device.source.display(),
            opened
                .iter()
                .find(|o| o.kind != InputKind::Serial)
                .map_or(String::new(), |o| o.source.display().to_string())
        )));
    }
    if args.live.record.is_some()
        && let Some(o) = opened
            .iter()
            .find(|o| matches!(o.kind, InputKind::Pcap | InputKind::Pcapng))
    {
        return Err(Failure::Usage(format!(
            "--record with several sources keeps serial lines, one interface per port; {} is \
             a network capture (mergecap merges captures of packets)",
            o.source.display()
        )));
    }
    let line = serial.line;
    // Notes once per kind of input.
    let mut kinds: Vec<InputKind> = Vec::new();
    for o in &opened {
        if !kinds.contains(&o.kind) {
            kinds.push(o.kind);
        }
    }
    let mut notes: Vec<String> = kinds
        .iter()
        .flat_map(|&k| option_notes(&args.output, k))
        .collect();
    notes.dedup();
    let untimed: Vec<&str> = opened
        .iter()
        .filter(|o| o.kind == InputKind::Raw)
        .map(|o| o.name.as_str())
        .collect();
    if !untimed.is_empty() {
        notes.push(format!(
            "{} carr{} no times: {} merged by Millis reconstructed at the line's rate, not as \
             they happened (record with --record FILE.pcapng to keep the times)",
            untimed.join(", "),
            if untimed.len() == 1 { "ies" } else { "y" },
            if untimed.len() == opened.len() {
                "the rows are"
            } else {
                "their rows are"
            }
        ));
    }
    let mut ports = Vec::new();
    let mut kept = Vec::new();
    let mut facts: Vec<(InputKind, PathBuf)> = Vec::new();
    for o in opened {
        let (reader, k): (Box<dyn ChunkReader>, _) = if o.kind == InputKind::Serial {
            (o.reader, None)
        } else {
            let (tee, k) = Tee::new(o.reader);
            (Box::new(tee), Some(k))
        };
        let decoder = decoder_for(o.kind, &line)?;
        kept.push(k);
        facts.push((o.kind, o.source));
        ports.push(Port {
            name: o.name,
            decoder,
            feed: source::spawn(reader, o.progress),
            recorder: None,
            offset: 0,
        });
    }
    // Files: each port's start on one clock, the earliest being time 0.
    let anchor = if live {
        None
    } else {
        let anchors: Vec<Option<Anchor>> = ports.iter().map(|p| p.feed.anchor(stop)).collect();
        let (common, offsets) = align(&anchors);
        if common.is_none() && anchors.iter().flatten().count() > 1 {
            notes.push(
                "the sources' start times are of different kinds (a radio's local time and a \
                 capture's instant): each port's Millis count from its own start"
                    .into(),
            );
        }
        for (p, o) in ports.iter_mut().zip(offsets) {
            p.offset = o;
        }
        common.or_else(|| anchors.iter().flatten().next().copied())
    };
    let shared = match &args.live.record {
        Some(path) => {
            let timed = facts.iter().all(|(k, _)| *k != InputKind::Raw);
            let mut r = Recorder::create(path, crate::record::Content::Line { timed })?;
            for (p, (kind, _)) in ports.iter().zip(&facts) {
                r.describe_port(
                    &p.name,
                    &line_description(protocol.name, &line),
                    *kind != InputKind::Raw,
                );
            }
            Some(Arc::new(Mutex::new(r)))
        }
        None => None,
    };
    if let Some(shared) = &shared {
        for (i, p) in ports.iter_mut().enumerate() {
            p.recorder = Some(PortRecorder {
                shared: shared.clone(),
                port: i as u32,
                offset: p.offset,
                anchor: if live { None } else { anchor },
            });
        }
    }
    for note in notes {
        eprintln!("busnoop: note: {note}");
    }
    let out = &args.output;
    let mut extra = vec![PORT_COLUMN];
    extra.extend_from_slice(ports[0].decoder.columns());
    let widths = pretty_widths(protocol.pretty_widths, &ports);
    let mut table = open_table(
        out,
        args.run.quiet,
        &extra,
        &widths,
        live,
        protocol.vocab.polls,
    )?;
    if let Some(t) = &mut table {
        t.header().map_err(Failure::from)?;
    }
    let speed = out.speed.unwrap_or(if out.top { 1.0 } else { 0.0 });
    let pacer = if live { None } else { Pacer::new(speed) };
    let how = How {
        stop,
        protocol: protocol.name,
        live,
        anchor: if live { None } else { anchor },
        clock: live.then_some(clock),
        selection,
        quiet: QUIET_REPORT.load(std::sync::atomic::Ordering::Relaxed),
    };
    let merged = if out.top {
        let names: Vec<&str> = ports.iter().map(|p| p.name.as_str()).collect();
        let info = Info {
            protocol: protocol.name.to_owned(),
            source: names.join(" + "),
            baud: live.then_some(line.baud),
            speed: pacer.as_ref().map(Pacer::speed),
            live,
            vocab: Some(protocol.vocab),
            names: selection.names.clone(),
            sensors: selection.sensors.clone(),
        };
        let mut view = Top::open(table.as_mut(), &extra, info, pacer)
            .map_err(|e| Failure::Output(format!("cannot set up the terminal for --top: {e}")))?;
        let merged = merge::merge(&mut ports, &mut view, how);
        if merged.result.is_ok() {
            view.hold();
        }
        // Leaves the alternate screen and gives stderr back (with what was written to it).
        drop(view);
        merged
    } else {
        let table = table.as_mut().expect("a table without --top");
        match pacer {
            Some(pacer) => merge::merge(
                &mut ports,
                &mut Paced {
                    inner: table,
                    tap: pacer,
                },
                how,
            ),
            None => merge::merge(&mut ports, table, how),
        }
    };
    let Merged {
        mut result,
        rows,
        hidden,
        frames,
    } = merged;
    if let Some(shared) = &shared {
        let recorded = merge::finish_recording(shared);
        if result.is_ok() {
            result = recorded;
        }
    }
    let stats = match (out.stats, out.stats_format) {
        (false, _) => None,
        (true, Some(StatsFormat::Json)) => Some(StatsFormat::Json),
        (true, _) => Some(StatsFormat::Text),
    };
    report(&ports, stats, protocol.name, &rows, &hidden, &result);
    // The wrong-protocol advice, per file: a note for a port that decoded nothing while another
    // did, "nothing decoded" (exit 10) only when no port decoded a frame.
    let mut nothing = Vec::new();
    let mut poor = Vec::new();
    let mut advised = 0;
    for (i, p) in ports.iter().enumerate() {
        let frames = frames[i].max(p.decoder.valid_frames());
        let Some(k) = &kept[i] else { continue };
        advised += 1;
        if result.is_err()
            || !(frames == 0
                || (p.decoder.problems().line().is_some()
                    && rows[i].saturating_sub(frames) * 4 >= frames))
        {
            continue;
        }
        let Ok(k) = k.lock() else { continue };
        let (kind, source) = &facts[i];
        match advise(protocol, *kind, &k, frames, source) {
            Advice::Fine => {}
            Advice::Poor(m) if args.run.lenient => {
                eprintln!("busnoop: note: {}", named(&p.name, source, &m));
            }
            Advice::Poor(m) => {
                eprintln!("busnoop: {}", named(&p.name, source, &m));
                poor.push(p.name.clone());
            }
            Advice::NothingDecoded(m) => nothing.push(named(&p.name, source, &m)),
        }
    }
    if !nothing.is_empty() && nothing.len() == advised && advised == ports.len() {
        return Err(Failure::NothingDecoded(nothing.join("; ")));
    }
    for m in nothing {
        eprintln!("busnoop: note: {m}");
    }
    if let Some(mut plot) = table.as_mut().and_then(crate::sink::Table::take_plot)
        && let Err(f) = plot.draw()
    {
        if result.is_ok() {
            return Err(f);
        }
        eprintln!("busnoop: {f}");
    }
    if result.is_ok() && !poor.is_empty() {
        return Err(Failure::Poor(format!(
            "most of the input of {} is not valid {} frames (exit code 13; --lenient accepts \
             such a run)",
            poor.join(", "),
            protocol.name
        )));
    }
    result
}

/// Usage errors of several sources, before any is opened.
fn check(args: &CaptureArgs) -> Result<(), Failure> {
    if args.live.export.is_some() {
        return Err(Failure::Usage(
            "--export takes one source; export each port in a run of its own".into(),
        ));
    }
    if let Some(p) = &args.live.record
        && (is_dash(p) || RecordFormat::for_path(p)? != RecordFormat::Pcapng)
    {
        return Err(Failure::Usage(format!(
            "--record {}: with several sources the recording is FILE.pcapng, which keeps the \
             ports apart (one interface per port, named by its source)",
            p.display()
        )));
    }
    let sources: Vec<&PathBuf> = args.sources().collect();
    if sources.iter().filter(|s| is_dash(s)).count() > 1 {
        return Err(Failure::Usage(
            "standard input (`-`) can be one source only".into(),
        ));
    }
    for (i, a) in sources.iter().enumerate() {
        let same = |b: &&PathBuf| {
            *a == *b
                || std::fs::canonicalize(a)
                    .is_ok_and(|x| std::fs::canonicalize(b).is_ok_and(|y| x == y))
        };
        if sources[..i].iter().any(same) {
            return Err(Failure::Usage(format!(
                "{} is given twice; each source is read once",
                a.display()
            )));
        }
    }
    Ok(())
}

/// Opens every source, in order, before anything is written: a missing or unusable one ends the
/// run here. A recording of several ports becomes one source per port. Serial devices count
/// their capture time from `clock`.
fn open_all(
    args: &CaptureArgs,
    protocol: &Protocol,
    serial: &SerialConfig,
    trace: &crate::source::logic::Options,
    clock: Instant,
) -> Result<Vec<Opening>, Failure> {
    let mut opened: Vec<Opening> = Vec::new();
    for source in args.sources() {
        let input = Input::parse(source);
        let recorded = recorded_ports(&input);
        if recorded.len() > 1 {
            if !protocol.reads(InputKind::Recording) {
                return Err(in_source(source, unusable(InputKind::Recording, protocol)));
            }
            for (interface, name) in recorded {
                let (o, progress) = source::open(&input)?;
                let reader = RecordingReader::new(o).interface(interface);
                opened.push(Opening {
                    name: name.unwrap_or_else(|| format!("{}#{interface}", source.display())),
                    source: source.clone(),
                    kind: InputKind::Recording,
                    reader: Box::new(reader),
                    progress: Some(progress),
                });
            }
            continue;
        }
        let keep = match input {
            Input::Device(_) => 0,
            _ => crate::detect::ADVICE_BYTES as u64,
        };
        // A trace read once per channel asked for: each channel a port (`trace.sr:RX`).
        let channels: Vec<Option<&String>> = if args.live.channel.len() > 1 {
            args.live.channel.iter().map(Some).collect()
        } else {
            vec![args.live.channel.first()]
        };
        if channels.len() > 1 && !matches!(input, Input::File(_)) {
            return Err(Failure::Usage(format!(
                "several --channel values read the trace once per channel: {} must be a file",
                source.display()
            )));
        }
        for channel in channels {
            let trace = crate::source::logic::Options {
                channel: channel.cloned(),
                ..trace.clone()
            };
            let (kind, reader, progress) = open_source(
                input.clone(),
                serial,
                &trace,
                args.live.reconnect,
                keep,
                Some(clock),
            )?;
            tracing::info!("{}: {:?}", source.display(), kind);
            if !protocol.reads(kind) {
                return Err(in_source(source, unusable(kind, protocol)));
            }
            if channel.is_some() && kind != InputKind::Trace {
                return Err(Failure::Usage(format!(
                    "--channel picks a wire of a logic-analyzer trace; {} is not one",
                    source.display()
                )));
            }
            let name = match channel {
                Some(c) if args.live.channel.len() > 1 => format!("{}:{c}", source.display()),
                _ => source.display().to_string(),
            };
            opened.push(Opening {
                name,
                source: source.clone(),
                kind,
                reader,
                progress,
            });
        }
    }
    // Two ports of one name (two recordings of the same device) are told apart.
    for i in 1..opened.len() {
        let mut n = 2;
        let base = opened[i].name.clone();
        while opened[..i].iter().any(|o| o.name == opened[i].name) {
            opened[i].name = format!("{base}#{n}");
            n += 1;
        }
    }
    Ok(opened)
}

/// A failure about one of several sources, naming it.
fn in_source(source: &Path, f: Failure) -> Failure {
    match f {
        Failure::Input(m) => Failure::Input(format!("{}: {m}", source.display())),
        f => f,
    }
}

/// `message` about port `name` of `source`: named by the port when the message does not say
/// which.
fn named(name: &str, source: &Path, message: &str) -> String {
    if message.contains(name) || name == source.display().to_string() {
        message.to_owned()
    } else {
        format!("{name}: {message}")
    }
}

/// The common clock of files: the earliest start is time 0, each port's offset how much later
/// its own start is. Ports without a start (raw bytes) start at 0. `None` (and no offsets)
/// when the starts cannot be compared (a radio's local time and an instant).
fn align(anchors: &[Option<Anchor>]) -> (Option<Anchor>, Vec<u64>) {
    let known: Vec<Anchor> = anchors.iter().flatten().copied().collect();
    let zero = vec![0; anchors.len()];
    let Some(&first) = known.first() else {
        return (None, zero);
    };
    let micros = |a: Anchor| match (a, first) {
        (Anchor::Instant(t), Anchor::Instant(_)) => Some(t.timestamp_micros()),
        (Anchor::Naive(t), Anchor::Naive(_)) => Some(t.and_utc().timestamp_micros()),
        _ => None,
    };
    let Some(times) = known
        .iter()
        .map(|&a| micros(a))
        .collect::<Option<Vec<i64>>>()
    else {
        return (None, zero);
    };
    let (at, _) = times
        .iter()
        .enumerate()
        .min_by_key(|&(_, t)| *t)
        .expect("one start at least");
    let start = times[at];
    let offsets = anchors
        .iter()
        .map(|a| a.and_then(micros).map_or(0, |t| (t - start) as u64))
        .collect();
    (Some(known[at]), offsets)
}

/// The pretty widths: the protocol's for the base columns, then the Port column as wide as the
/// longest port name (up to 24), then the protocol's for its own columns.
fn pretty_widths(protocol: &[usize], ports: &[Port]) -> Vec<usize> {
    let base = protocol.len().min(8);
    let mut widths = protocol[..base].to_vec();
    if protocol.len() > 8 {
        let longest = ports.iter().map(|p| p.name.chars().count()).max();
        widths.push(longest.unwrap_or(4).clamp(4, 24));
        widths.extend_from_slice(&protocol[8..]);
    }
    widths
}

/// The end-of-run summary of several ports on stderr: per port the statistics (`--stats`) and
/// the problems line, then the interruption once; the JSON statistics are one object with each
/// port's under `ports`.
fn report(
    ports: &[Port],
    stats: Option<StatsFormat>,
    protocol: &str,
    rows: &[u64],
    hidden: &[u64],
    result: &Result<(), Failure>,
) {
    if QUIET_REPORT.load(std::sync::atomic::Ordering::Relaxed) {
        return;
    }
    // Written at the very end (`main`), after the failure's message if any.
    if crate::stats_json::wanted() {
        let reports: Vec<crate::stats_json::PortReport<'_>> = ports
            .iter()
            .enumerate()
            .map(|(i, p)| crate::stats_json::PortReport {
                port: &p.name,
                report: p.decoder.stats(),
                rows: rows[i],
                hidden: hidden[i],
                valid_frames: p.decoder.valid_frames(),
                problems: p.decoder.problems(),
            })
            .collect();
        crate::stats_json::record_ports(protocol, &reports);
    }
    if matches!(result, Err(Failure::BrokenPipe)) {
        return;
    }
    for (i, p) in ports.iter().enumerate() {
        let (rows, hidden) = (rows[i], hidden[i]);
        if stats == Some(StatsFormat::Text) {
            if hidden > 0 {
                eprintln!(
                    "{protocol} statistics, port {} ({rows} rows, {} shown, {hidden} hidden by \
                     filters)",
                    p.name,
                    rows - hidden
                );
            } else {
                eprintln!("{protocol} statistics, port {} ({rows} rows)", p.name);
            }
            eprintln!("{}", p.decoder.stats());
        }
        let problems = p.decoder.problems().line();
        if !matches!(result, Err(Failure::Output(_)))
            && stats != Some(StatsFormat::Json)
            && let Some(line) = &problems
        {
            eprintln!("busnoop: {}: {line}", p.name);
        }
    }
    if let Err(Failure::Signal(i)) = result {
        eprintln!(
            "busnoop: interrupted after {} rows; all decoded rows were written{}",
            rows.iter().sum::<u64>(),
            i.input_note()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use chrono::{DateTime, NaiveDate};

    #[test]
    fn files_share_the_earliest_start() {
        let t = |us: i64| {
            Some(Anchor::Instant(
                DateTime::from_timestamp_micros(us).unwrap(),
            ))
        };
        let (common, offsets) = align(&[t(5_000_000), None, t(2_000_000)]);
        assert_eq!(common, t(2_000_000));
        assert_eq!(offsets, [3_000_000, 0, 0]);
        assert_eq!(align(&[None, None]), (None, vec![0, 0]));
        let naive = NaiveDate::from_ymd_opt(2024, 1, 1)
            .unwrap()
            .and_hms_opt(0, 0, 0)
            .unwrap();
        let (common, offsets) = align(&[t(1), Some(Anchor::Naive(naive))]);
        assert_eq!((common, offsets), (None, vec![0, 0]));
    }

    #[test]
    fn the_port_column_sits_between_the_base_columns_and_the_protocols() {
        assert_eq!(pretty_widths(&[1, 2, 3], &[]), [1, 2, 3]);
        assert_eq!(
            pretty_widths(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10], &[]),
            [1, 2, 3, 4, 5, 6, 7, 8, 4, 9, 10]
        );
    }
}
