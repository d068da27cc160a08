//! Logic-analyzer traces on the command line (docs/logic.md): every protocol reads a trace of its
//! traffic exactly as it reads the same bytes with the same times; `--channel`, `--baud`, what
//! stderr says, `detect`, and the real sigrok sessions of `fixtures/logic/`.

mod common;

use std::path::{Path, PathBuf};

use busnoop::protocol::{InputKind, Line};
use busnoop::protocols::PROTOCOLS;
use busnoop::selfcheck::trace_writer::{self as tw, Levels, Noise, Signal};
use busnoop::{RecordContent, Recorder};
use common::{busnoop, fixture, ok, read_tsv, text};

/// Wire bytes of each protocol's traffic. A protocol added to the table needs its byte file
/// here: this test reads a trace of it.
fn traffic(command: &str) -> Vec<u8> {
    match command {
        "sport" => std::fs::read(fixture("sport-sample.bin")).unwrap(),
        "sab2" => std::fs::read(fixture("sab2-session.bin")).unwrap(),
        "sbus" => read_tsv("sbus.tsv")
            .iter()
            .filter(|v| v["mode"] == "data" && v["crc_ok"] == "yes")
            .flat_map(|v| busnoop::fmt::parse_hex(&v["hex_on_wire"]).unwrap())
            .collect(),
        "crsf" => std::fs::read(fixture("crsf-fc-to-rx.bin")).unwrap(),
        "ghst" => std::fs::read(fixture("ghst-mixed.bin")).unwrap()[..4096].to_vec(),
        "futaba" => std::fs::read(fixture("futaba-session.bin")).unwrap(),
        "ibus" => std::fs::read(fixture("ibus-sensors.bin")).unwrap(),
        "fport" => std::fs::read(fixture("fport-v1-session.bin")).unwrap(),
        "modbus" => std::fs::read(fixture("modbus-gen.bin")).unwrap(),
        // S-Port_Snoop prints its table on the Arduino's serial port.
        "log" => std::fs::read(fixture("sport-snoop-sample.tsv")).unwrap(),
        other => panic!("no traffic for {other}: add a byte file of it to traffic()"),
    }
}

/// A sample rate of at least 8 times `baud` that a VCD can name exactly.
fn rate_for(baud: u32) -> u64 {
    [1_000_000, 2_000_000, 4_000_000, 5_000_000, 10_000_000]
        .into_iter()
        .find(|&r| r >= 8 * u64::from(baud))
        .unwrap()
}

/// `bytes` on `line`: characters with 1 to 3 idle bits between them and a pause of 3 ms after
/// every 16th, from 2 ms on.
fn timed(line: &Line, bytes: &[u8]) -> Vec<(u64, u8)> {
    let bit = 1e9 / f64::from(line.baud);
    let mut t = 2_000_000.0;
    bytes
        .iter()
        .enumerate()
        .map(|(i, &b)| {
            let at = (t as u64, b);
            t += (f64::from(line.bits_per_char()) + 1.0 + (i % 3) as f64) * bit;
            if i % 16 == 15 {
                t += 3e6;
            }
            at
        })
        .collect()
}

/// A busnoop recording of `bytes` at `micros` each.
fn recording(path: &Path, bytes: &[u8], micros: &[u64]) {
    let mut r = Recorder::create(path, RecordContent::Line { timed: true }).unwrap();
    r.start(None).unwrap();
    for (b, t) in bytes.iter().zip(micros) {
        r.data(&[*b], Some(*t)).unwrap();
    }
    r.finish().unwrap();
}

fn run(args: &[&str], source: &Path) -> std::process::Output {
    busnoop().args(args).arg(source).output().unwrap()
}

#[test]
fn every_protocol_reads_a_trace_as_the_same_bytes_with_the_same_times() {
    let dir = tempfile::tempdir().unwrap();
    for (i, p) in PROTOCOLS
        .iter()
        .filter(|p| p.reads(InputKind::Serial))
        .enumerate()
    {
        let bytes = traffic(p.command);
        let line = p.line;
        let sent = timed(&line, &bytes);
        let signal = Signal {
            line,
            baud: f64::from(line.baud),
            inverted: p.inverted,
        };
        let rate = rate_for(line.baud);
        let end = sent.last().unwrap().0 + 5_000_000;
        let lv = tw::levels(&signal, &sent, rate, end, &Noise::default());
        let ch = [("RX", &lv)];
        // A different container for each protocol.
        let (name, data) = match i % 3 {
            0 => ("trace.sr", tw::sr(&ch, rate, 100_000, true)),
            1 => ("trace.vcd", tw::vcd(&ch, rate, 1_000_000_000_000 / rate)),
            _ => ("trace.csv", tw::saleae_csv(&ch, rate)),
        };
        let trace = dir.path().join(format!("{}-{name}", p.command));
        std::fs::write(&trace, data).unwrap();
        let rec = dir.path().join(format!("{}.pcap", p.command));
        recording(&rec, &bytes, &lv.start_micros(rate));
        let from_trace = run(&[p.command, "-f", "tsv", "--raw"], &trace);
        let from_rec = run(&[p.command, "-f", "tsv", "--raw"], &rec);
        assert_eq!(
            ok(&from_trace),
            ok(&from_rec),
            "{}: {}",
            p.command,
            text(&from_trace.stderr)
        );
        assert!(ok(&from_trace).lines().count() > 5, "{}", p.command);
        // stderr: an inverted line is said; the rate is the protocol's.
        let said = text(&from_trace.stderr);
        assert_eq!(
            said.contains("inverted line"),
            p.inverted,
            "{}: {said}",
            p.command
        );
        assert!(!said.contains("baud"), "{}: {said}", p.command);
        // And the raw byte file of the same traffic gives the same frames (its Millis are
        // rebuilt, so they and the time-derived columns are left out).
        let raw = dir.path().join(format!("{}.bin", p.command));
        std::fs::write(&raw, &bytes).unwrap();
        let from_raw = run(&[p.command, "-f", "tsv", "--raw"], &raw);
        let frames = |out: &std::process::Output| -> Vec<String> {
            ok(out)
                .lines()
                .map(|l| {
                    let c: Vec<&str> = l.split('\t').collect();
                    format!("{}\t{}", c[2..8].join("\t"), c.last().unwrap())
                })
                .collect()
        };
        assert_eq!(frames(&from_trace), frames(&from_raw), "{}", p.command);
    }
}

/// A trace file of two lines (RX with S.Port polls at 57600 inverted, TX with other bytes) and
/// an idle one.
fn two_lines(dir: &Path) -> PathBuf {
    let line = Line::n81(57_600);
    let signal = Signal {
        line,
        baud: 57_600.0,
        inverted: true,
    };
    let polls: Vec<u8> = (0..40).flat_map(|_| [0x7E, 0xA1]).collect();
    let rx = tw::levels(
        &signal,
        &timed(&line, &polls),
        1_000_000,
        400_000_000,
        &Noise::default(),
    );
    let tx = tw::levels(
        &signal,
        &timed(&line, b"not a frame"),
        1_000_000,
        400_000_000,
        &Noise::default(),
    );
    let idle = tw::levels(&signal, &[], 1_000_000, 400_000_000, &Noise::default());
    let path = dir.join("two.sr");
    std::fs::write(
        &path,
        tw::sr(
            &[("RX", &rx), ("EN", &idle), ("TX", &tx)],
            1_000_000,
            1 << 20,
            true,
        ),
    )
    .unwrap();
    path
}

/// `--channel RX,TX`: each channel a port of its own, merged by time with a Port column; each
/// port's rows are those of its channel read alone.
#[test]
fn several_channels_are_several_ports() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_lines(dir.path());
    let both = run(&["sport", "--channel", "RX,TX", "-f", "tsv"], &path);
    let repeated = run(
        &["sport", "--channel", "0", "--channel", "TX", "-f", "tsv"],
        &path,
    );
    let both = ok(&both);
    let header: Vec<&str> = both.lines().next().unwrap().split('\t').collect();
    let port = header
        .iter()
        .position(|c| *c == "Port")
        .expect("a Port column");
    let millis = header.iter().position(|c| *c == "Millis").unwrap();
    // The same ports, named by what was asked for.
    assert_eq!(
        ok(&repeated)
            .replace(":0\t", ":RX\t")
            .replace(":0\n", ":RX\n"),
        both
    );
    for (channel, id) in [("RX", 0), ("TX", 2)] {
        let alone = run(&["sport", "--channel", &id.to_string(), "-f", "tsv"], &path);
        // (TX alone carries no frame: exit 10, its garbage row still written)
        let alone: Vec<String> = text(&alone.stdout)
            .lines()
            .skip(1)
            .map(|l| l.split('\t').skip(1).collect::<Vec<_>>().join("\t"))
            .collect();
        let want = format!("{}:{channel}", path.display());
        let mine: Vec<String> = both
            .lines()
            .skip(1)
            .filter(|l| l.split('\t').nth(port) == Some(want.as_str()))
            .map(|l| {
                let c: Vec<&str> = l.split('\t').collect();
                c[1..port]
                    .iter()
                    .chain(&c[port + 1..])
                    .copied()
                    .collect::<Vec<_>>()
                    .join("\t")
            })
            .collect();
        assert!(!mine.is_empty(), "{channel}: {both}");
        assert_eq!(mine, alone, "{channel}");
    }
    // Merged by time.
    let times: Vec<f64> = both
        .lines()
        .skip(1)
        .map(|l| l.split('\t').nth(millis).unwrap().parse().unwrap())
        .collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]), "{both}");
    // A pipe cannot be read once per channel.
    let piped = busnoop()
        .args(["sport", "--channel", "RX,TX", "-"])
        .stdin(std::fs::File::open(&path).unwrap())
        .output()
        .unwrap();
    assert_eq!(piped.status.code(), Some(2), "{}", text(&piped.stderr));
    assert!(text(&piped.stderr).contains("must be a file"));
}

#[test]
fn channel_is_chosen_by_name_or_number_and_asked_for_when_several_move() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_lines(dir.path());
    let by_name = run(&["sport", "--channel", "RX", "-f", "tsv"], &path);
    let by_number = run(&["sport", "--channel", "0", "-f", "tsv"], &path);
    assert_eq!(ok(&by_name), ok(&by_number));
    assert_eq!(ok(&by_name).lines().count(), 41, "40 polls and the header");
    assert!(text(&by_name.stderr).contains("channel 0 (RX) reads as an inverted line (idle low)"));
    let none = run(&["sport"], &path);
    assert_eq!(none.status.code(), Some(2), "{}", text(&none.stderr));
    assert!(
        text(&none.stderr).contains(
            "the trace has 3 channels and several change level (*): choose one with --channel \
             NAME|N: 0 RX*, 1 EN, 2 TX*"
        ),
        "{}",
        text(&none.stderr)
    );
    let missing = run(&["sport", "--channel", "CLK"], &path);
    assert_eq!(missing.status.code(), Some(2));
    assert!(text(&missing.stderr).contains("no channel \"CLK\"; its channels: 0 RX, 1 EN, 2 TX"));
    // --channel on something that is not a trace.
    let bin = run(&["sport", "--channel", "RX"], &fixture("sport-sample.bin"));
    assert_eq!(bin.status.code(), Some(2));
    assert!(text(&bin.stderr).contains("--channel picks a wire of a logic-analyzer trace"));
}

#[test]
fn detect_reads_a_trace_and_names_the_channel_in_its_command() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_lines(dir.path());
    let out = run(&["detect", "--channel", "RX"], &path);
    let said = ok(&out);
    assert!(
        said.contains("a logic-analyzer trace, 80 bytes examined"),
        "{said}"
    );
    assert!(said.contains("verdict: S.Port (100.0%"), "{said}");
    assert!(
        said.contains(&format!(
            "run:  busnoop sport --channel RX {}",
            path.display()
        )),
        "{said}"
    );
}

#[test]
fn the_rate_is_measured_when_the_protocol_default_does_not_fit_and_baud_wins() {
    let dir = tempfile::tempdir().unwrap();
    // S.Port polls at 115200 (a TX16S mirror), the protocol's default being 57600.
    let line = Line::n81(115_200);
    let polls: Vec<u8> = (0..30).flat_map(|_| [0x7E, 0x98]).collect();
    let lv: Levels = tw::levels(
        &Signal {
            line,
            baud: 115_200.0,
            inverted: false,
        },
        &timed(&line, &polls),
        2_000_000,
        200_000_000,
        &Noise::default(),
    );
    let path = dir.path().join("mirror.vcd");
    std::fs::write(&path, tw::vcd(&[("D0", &lv)], 2_000_000, 500_000)).unwrap();
    let measured = run(&["sport", "-f", "tsv"], &path);
    assert_eq!(ok(&measured).lines().count(), 31);
    assert!(
        text(&measured.stderr).contains("runs at 115200 baud")
            && text(&measured.stderr).contains("not the protocol's 57600"),
        "{}",
        text(&measured.stderr)
    );
    let given = run(&["sport", "-f", "tsv", "--baud", "115200"], &path);
    assert_eq!(ok(&given), ok(&measured));
    assert!(
        !text(&given.stderr).contains("baud"),
        "{}",
        text(&given.stderr)
    );
    let abs = run(
        &["sport", "-f", "tsv", "--baud", "115200", "--time", "abs"],
        &path,
    );
    assert!(
        text(&abs.stderr).contains("a logic-analyzer trace carries no wall-clock time"),
        "{}",
        text(&abs.stderr)
    );
}

#[test]
fn a_broken_session_is_a_clean_error_after_the_rows_before_it() {
    let dir = tempfile::tempdir().unwrap();
    let data = std::fs::read(fixture("logic/brainchild-io-16do.sr")).unwrap();
    let cut = dir.path().join("cut.sr");
    std::fs::write(&cut, &data[..data.len() / 2]).unwrap();
    let out = run(&["sbus", "--channel", "0"], &cut);
    // Exit code 9: the input could not be used.
    assert_eq!(out.status.code(), Some(9), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr)
            .contains("cut.sr: not a usable sigrok session: the archive ends early (cut short?)"),
        "{}",
        text(&out.stderr)
    );
    common::no_panic(&out);
}

#[test]
fn the_real_sessions_record_the_bytes_beside_them() {
    // --record of a trace keeps the characters the UART read, with their times.
    let dir = tempfile::tempdir().unwrap();
    for (sr, channel, line, bin) in [
        (
            "flowmeter_graph_tool.sr",
            "RXTX",
            "9600-8N1",
            "flowmeter-graph-tool.bin",
        ),
        ("wizmodbus.sr", "BA+", "9600-8N1", "wizmodbus-bus.bin"),
    ] {
        let raw = dir.path().join(format!("{sr}.raw"));
        let out = busnoop()
            .args(["sbus", "--channel", channel, "--line", line, "--record"])
            .arg(&raw)
            .arg(fixture(&format!("logic/{sr}")))
            .output()
            .unwrap();
        common::no_panic(&out);
        assert_eq!(
            std::fs::read(&raw).unwrap(),
            std::fs::read(fixture(&format!("logic/{bin}"))).unwrap(),
            "{sr}: {}",
            text(&out.stderr)
        );
    }
}
