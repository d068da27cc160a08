use super::*;
use crate::protocol::{InputKind, Line, Parity};
use write::{Levels, Noise, Signal};

/// What a reader made of a trace.
#[derive(Debug, Default)]
struct Out {
    /// Characters with their µs.
    chars: Vec<(u8, u64)>,
    /// Rows: (µs, text), and the index of the character they precede.
    notes: Vec<(u64, String, usize)>,
    warnings: Vec<String>,
    failure: Option<String>,
}

fn opened(data: &[u8]) -> Opened {
    let split = data.len().min(crate::source::DETECT_LEN);
    Opened {
        kind: InputKind::Trace,
        prefix: data[..split].to_vec(),
        reader: Box::new(io::Cursor::new(data[split..].to_vec())),
        name: "trace".into(),
    }
}

fn run(data: &[u8], opts: &Options) -> Out {
    let (tx, rx) = std::sync::mpsc::sync_channel(1024);
    let mut out = Out::default();
    let take = |out: &mut Out| {
        for m in rx.try_iter() {
            match m {
                Message::Data(b) => {
                    for (bytes, t) in b.segments() {
                        for &x in bytes {
                            out.chars.push((x, t.unwrap()));
                        }
                    }
                }
                Message::Note { micros, data, .. } => {
                    out.notes.push((micros.unwrap(), data, out.chars.len()))
                }
                Message::Warning(w) => out.warnings.push(w),
                other => panic!("{other:?}"),
            }
        }
    };
    match reader(opened(data), opts) {
        Err(f) => out.failure = Some(f.to_string()),
        Ok(mut r) => loop {
            let next = r.next_batch(&tx);
            take(&mut out);
            match next {
                Ok(Some(c)) => {
                    tx.send(c.into()).unwrap();
                    take(&mut out);
                }
                Ok(None) => break,
                Err(f) => {
                    out.failure = Some(f.to_string());
                    break;
                }
            }
        },
    }
    take(&mut out);
    out
}

fn fixture(name: &str) -> Vec<u8> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/logic")
        .join(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn bytes(out: &Out) -> Vec<u8> {
    out.chars.iter().map(|c| c.0).collect()
}

#[test]
fn flowmeter_session_gives_the_bytes_beside_it() {
    let opts = Options {
        channel: Some("RXTX".into()),
        ..Options::new(Line::n81(9600))
    };
    let out = run(&fixture("flowmeter_graph_tool.sr"), &opts);
    assert_eq!(out.failure, None);
    assert_eq!(bytes(&out), fixture("flowmeter-graph-tool.bin"));
    assert_eq!(out.warnings, Vec::<String>::new());
    // Without --channel: the only one of its 8 probes that moves.
    let auto = run(
        &fixture("flowmeter_graph_tool.sr"),
        &Options::new(Line::n81(9600)),
    );
    assert_eq!(auto.chars, out.chars);
    assert_eq!(
        auto.warnings,
        [
            "trace: reading channel 2 (RXTX), the only one of 8 that changes level; --channel to \
          choose another"
        ]
    );
}

#[test]
fn wizmodbus_bus_channel_gives_the_bytes_beside_it() {
    let opts = Options {
        channel: Some("BA+".into()),
        ..Options::new(Line::n81(9600))
    };
    let out = run(&fixture("wizmodbus.sr"), &opts);
    assert_eq!(out.failure, None);
    assert_eq!(bytes(&out), fixture("wizmodbus-bus.bin"));
}

#[test]
fn brainchild_two_inverted_lines_merged_give_the_bytes_beside_them() {
    let line = Line {
        parity: Parity::Even,
        ..Line::n81(19200)
    };
    let mut merged = Vec::new();
    for ch in ["0", "1"] {
        let opts = Options {
            channel: Some(ch.into()),
            ..Options::new(line)
        };
        let out = run(&fixture("brainchild-io-16do.sr"), &opts);
        eprintln!(
            "{ch}: {:?} {:?} {:?}",
            out.warnings, out.failure, &out.notes
        );
        merged.extend(out.chars);
    }
    merged.sort_by_key(|c| c.1);
    let got: Vec<u8> = merged.iter().map(|c| c.0).collect();
    assert_eq!(got, fixture("brainchild.bin"));
}

/// Bytes 0..=255 and a few more, with idle gaps of 0 to 3 bits between them.
fn traffic(line: &Line, baud: f64) -> Vec<(u64, u8)> {
    let bytes: Vec<u8> = (0..=255u8).chain([0x7E, 0x00, 0xFF, 0x55]).collect();
    let bit = 1e9 / baud;
    let mut t = 1_000_000.0; // 1 ms of idle line first
    bytes
        .iter()
        .enumerate()
        .map(|(i, &b)| {
            let at = (t as u64, b);
            t += (f64::from(line.bits_per_char()) + (i % 4) as f64) * bit;
            at
        })
        .collect()
}

/// The trace's end: 5 ms after the last character.
fn end_ns(chars: &[(u64, u8)]) -> u64 {
    chars.last().map_or(0, |c| c.0) + 5_000_000
}

/// Every container a trace can be written in: (what, bytes).
fn containers(levels: &Levels, rate: u64) -> Vec<(&'static str, Vec<u8>)> {
    let ch = [("RX", levels)];
    let period_ps = 1_000_000_000_000 / rate;
    vec![
        ("sr stored", write::sr(&ch, rate, 1000, false)),
        ("sr deflated", write::sr(&ch, rate, 1 << 20, true)),
        ("vcd", write::vcd(&ch, rate, period_ps)),
        ("vcd ps", write::vcd(&ch, rate, 1)),
        ("saleae csv", write::saleae_csv(&ch, rate)),
    ]
}

#[test]
fn every_container_decodes_back_to_the_bytes_and_their_times() {
    let e1 = Line {
        parity: Parity::Even,
        ..Line::n81(19_200)
    };
    let e2 = Line {
        parity: Parity::Even,
        stop_bits: 2,
        ..Line::n81(100_000)
    };
    let o1 = Line {
        parity: Parity::Odd,
        data_bits: 7,
        ..Line::n81(9600)
    };
    let cases = [
        (Line::n81(9600), 1_000_000, false),
        (Line::n81(57_600), 4_000_000, true),
        (e2, 1_000_000, true),
        (e1, 2_000_000, false),
        (o1, 500_000, false),
        (Line::n81(115_200), 1_000_000, false),
    ];
    for (line, rate, inverted) in cases {
        let signal = Signal {
            line,
            baud: f64::from(line.baud),
            inverted,
        };
        let mut sent = traffic(&line, signal.baud);
        let mask = ((1u16 << line.data_bits) - 1) as u8;
        for c in &mut sent {
            c.1 &= mask;
        }
        let lv = write::levels(&signal, &sent, rate, end_ns(&sent), &Noise::default());
        let want: Vec<(u8, u64)> = sent
            .iter()
            .map(|c| c.1)
            .zip(lv.start_micros(rate))
            .collect();
        for (what, data) in containers(&lv, rate) {
            let out = run(&data, &Options::new(line));
            let case = format!("{what}, {line:?} at {rate} Hz, inverted {inverted}");
            assert_eq!(out.failure, None, "{case}");
            assert_eq!(out.chars, want, "{case}");
            assert_eq!(out.notes, [], "{case}");
            let said_inverted = out.warnings.iter().any(|w| w.contains("inverted"));
            assert_eq!(said_inverted, inverted, "{case}: {:?}", out.warnings);
            assert_eq!(
                out.warnings.len(),
                usize::from(inverted),
                "{case}: {:?}",
                out.warnings
            );
        }
    }
}

#[test]
fn jitter_is_read_through_and_a_glitch_gives_a_framing_error_row_not_a_lost_frame() {
    let line = Line::n81(57_600);
    let signal = Signal {
        line,
        baud: 57_600.0,
        inverted: true,
    };
    let sent = traffic(&line, signal.baud);
    let bit = 1e9 / signal.baud;
    // A pulse over the middle of character 10's stop bit, and a short one on the idle line
    // before character 20 (which has 2 idle bits before it... and 1 ms before the first).
    let stop = sent[10].0 as f64 + 9.5 * bit;
    let noise = Noise {
        jitter: 0.08,
        seed: 7,
        glitches: vec![
            ((stop - 0.2 * bit) as u64, (0.4 * bit) as u64),
            (500_000, (0.3 * bit) as u64),
        ],
    };
    let rate = 4_000_000;
    let lv = write::levels(&signal, &sent, rate, end_ns(&sent), &noise);
    let starts = lv.start_micros(rate);
    for (what, data) in containers(&lv, rate) {
        let out = run(&data, &Options::new(line));
        assert_eq!(out.failure, None, "{what}");
        let got: Vec<u8> = bytes(&out);
        let want: Vec<u8> = sent.iter().map(|c| c.1).collect();
        assert_eq!(got, want, "{what}");
        let times: Vec<u64> = out.chars.iter().map(|c| c.1).collect();
        assert_eq!(times, starts, "{what}");
        assert_eq!(
            out.notes,
            [(
                starts[10],
                format!("framing error (character 0x{:02X})", sent[10].1),
                10
            )],
            "{what}"
        );
        let summary = out.warnings.last().unwrap();
        assert!(summary.contains("1 framing error"), "{what}: {summary}");
        assert!(summary.contains("1 glitch"), "{what}: {summary}");
    }
}

#[test]
fn baud_rates_are_measured_within_2_percent() {
    for &baud in &[
        1200u32, 2400, 4800, 9600, 19_200, 38_400, 57_600, 100_000, 115_200, 230_400, 250_000,
        420_000, 460_800, 921_600, 1_000_000,
    ] {
        for (skew, oversample) in [(1.0, 8), (1.015, 10), (0.985, 16), (1.008, 12), (1.0, 50)] {
            let line = Line::n81(baud);
            let real = f64::from(baud) * skew;
            let signal = Signal {
                line,
                baud: real,
                inverted: false,
            };
            let rate = u64::from(baud) * oversample;
            let sent = traffic(&line, real);
            let lv = write::levels(&signal, &sent, rate, end_ns(&sent), &Noise::default());
            let m = uart::measure(&lv.changes, TimeBase::rate(rate)).unwrap();
            let err = m.baud / real - 1.0;
            assert!(
                err.abs() < 0.02,
                "{baud} x{skew} at {rate} Hz: measured {}",
                m.baud
            );
            // A sender 1.5 % off may be nearer another usual rate (250000 and 256000).
            if (skew - 1.0f64).abs() < 0.01 {
                assert_eq!(uart::snap(m.baud), Some(baud), "{baud} x{skew}: {}", m.baud);
            }
        }
    }
}

#[test]
fn a_rate_that_does_not_fit_the_protocol_is_measured_and_said_unless_baud_is_given() {
    let line = Line::n81(9600);
    let signal = Signal {
        line,
        baud: 9600.0,
        inverted: false,
    };
    let sent = traffic(&line, 9600.0);
    let lv = write::levels(&signal, &sent, 1_000_000, end_ns(&sent), &Noise::default());
    let data = write::sr(&[("RX", &lv)], 1_000_000, 1 << 20, true);
    let want: Vec<u8> = sent.iter().map(|c| c.1).collect();
    // The protocol says 19200: the pulses say 9600.
    let out = run(&data, &Options::new(Line::n81(19_200)));
    assert_eq!(bytes(&out), want);
    assert_eq!(out.warnings.len(), 1, "{:?}", out.warnings);
    assert!(
        out.warnings[0].contains("runs at 9600 baud") && out.warnings[0].contains("19200"),
        "{:?}",
        out.warnings
    );
    // --baud 9600: no word about it.
    let opts = Options {
        baud: Some(9600),
        ..Options::new(Line::n81(19_200))
    };
    let out = run(&data, &opts);
    assert_eq!(bytes(&out), want);
    assert_eq!(out.warnings, Vec::<String>::new());
    // --baud 19200 is obeyed, with a word that the pulses disagree.
    let opts = Options {
        baud: Some(19_200),
        ..Options::new(Line::n81(9600))
    };
    let out = run(&data, &opts);
    assert_ne!(bytes(&out), want);
    assert!(
        out.warnings[0].contains("look like 9600 baud"),
        "{:?}",
        out.warnings
    );
}

#[test]
fn a_break_is_a_row_and_a_zero() {
    let line = Line::n81(9600);
    let signal = Signal {
        line,
        baud: 9600.0,
        inverted: false,
    };
    let sent = traffic(&line, 9600.0);
    let brk_at = sent.last().unwrap().0 + 2_000_000;
    let noise = Noise {
        glitches: vec![(brk_at, 3_000_000)],
        ..Noise::default()
    };
    let mut after = sent.clone();
    after.push((brk_at + 4_000_000, 0x42));
    let lv = write::levels(&signal, &after, 1_000_000, end_ns(&after), &noise);
    let out = run(
        &write::vcd(&[("RX", &lv)], 1_000_000, 1_000_000),
        &Options::new(line),
    );
    let n = sent.len();
    assert_eq!(out.chars[n], (0, brk_at.div_ceil(1000)));
    assert_eq!(out.chars[n + 1].0, 0x42);
    assert_eq!(
        out.notes,
        [(
            brk_at.div_ceil(1000),
            "break on the line (3.000 ms)".to_string(),
            n
        )]
    );
}

/// Two lines (RX, TX) and an idle one (EN), as sigrok, VCD and Saleae CSV.
/// Traces by container name.
type Files = Vec<(&'static str, Vec<u8>)>;

fn two_lines() -> (Files, Vec<u8>, Vec<u8>) {
    let line = Line::n81(9600);
    let signal = Signal {
        line,
        baud: 9600.0,
        inverted: false,
    };
    let rx = write::back_to_back(&line, 9600.0, b"request", 1_000_000, 1.0);
    let tx = write::back_to_back(&line, 9600.0, b"answer", 20_000_000, 0.5);
    let end = 40_000_000;
    let rx_l = write::levels(&signal, &rx, 1_000_000, end, &Noise::default());
    let tx_l = write::levels(&signal, &tx, 1_000_000, end, &Noise::default());
    let idle = write::levels(&signal, &[], 1_000_000, end, &Noise::default());
    let ch = [("RX", &rx_l), ("EN", &idle), ("TX", &tx_l)];
    let files = vec![
        ("sr", write::sr(&ch, 1_000_000, 5000, true)),
        ("vcd", write::vcd(&ch, 1_000_000, 1_000_000)),
        ("csv", write::saleae_csv(&ch, 1_000_000)),
    ];
    (files, b"request".to_vec(), b"answer".to_vec())
}

#[test]
fn channels_are_chosen_by_name_or_number_and_never_guessed_between_two() {
    let (files, rx, tx) = two_lines();
    let line = Line::n81(9600);
    for (what, data) in &files {
        let pick = |c: &str| {
            run(
                data,
                &Options {
                    channel: Some(c.into()),
                    ..Options::new(line)
                },
            )
        };
        assert_eq!(bytes(&pick("RX")), rx, "{what}");
        assert_eq!(bytes(&pick("TX")), tx, "{what}");
        assert_eq!(bytes(&pick("2")), tx, "{what}");
        assert_eq!(bytes(&pick("0")), rx, "{what}");
        let none = pick("EN");
        assert_eq!(bytes(&none), b"", "{what}");
        assert!(none.warnings[0].contains("never changes level"), "{what}");
        let missing = pick("CLK");
        assert_eq!(
            missing.failure.as_deref(),
            Some("trace: no channel \"CLK\"; its channels: 0 RX, 1 EN, 2 TX"),
            "{what}"
        );
        let out = run(data, &Options::new(line));
        assert_eq!(
            out.failure.as_deref(),
            Some(
                "trace: the trace has 3 channels and several change level (*): choose one \
                 with --channel NAME|N: 0 RX*, 1 EN, 2 TX*"
            ),
            "{what}"
        );
    }
}

#[test]
fn the_only_channel_that_moves_is_read_and_said() {
    let line = Line::n81(9600);
    let signal = Signal {
        line,
        baud: 9600.0,
        inverted: false,
    };
    let sent = traffic(&line, 9600.0);
    let lv = write::levels(&signal, &sent, 1_000_000, end_ns(&sent), &Noise::default());
    let idle = write::levels(&signal, &[], 1_000_000, end_ns(&sent), &Noise::default());
    let want: Vec<(u8, u64)> = sent
        .iter()
        .map(|c| c.1)
        .zip(lv.start_micros(1_000_000))
        .collect();
    let ch = [("D0", &idle), ("D1", &idle), ("UART", &lv), ("D3", &idle)];
    for data in [
        write::sr(&ch, 1_000_000, 777, false),
        write::vcd(&ch, 1_000_000, 1_000_000),
        write::saleae_csv(&ch, 1_000_000),
    ] {
        let out = run(&data, &Options::new(line));
        assert_eq!(out.chars, want);
        assert_eq!(
            out.warnings,
            [
                "trace: reading channel 2 (UART), the only one of 4 that changes level; \
              --channel to choose another"
            ]
        );
    }
}

#[test]
fn saleae_async_serial_exports_are_characters_with_their_errors() {
    let chars = [
        (1_028_028, 0x04, false, false),
        (1_028_124, 0xF0, true, false),
        (1_028_219, 0x0B, false, true),
        (1_028_315, 0xFF, false, false),
    ];
    let out = run(
        &write::saleae_serial(&chars),
        &Options::new(Line::n81(115_200)),
    );
    assert_eq!(out.failure, None);
    assert_eq!(
        out.chars,
        [
            (0x04, 1_028_028),
            (0xF0, 1_028_124),
            (0x0B, 1_028_219),
            (0xFF, 1_028_315)
        ]
    );
    assert_eq!(
        out.notes,
        [
            (1_028_124, "framing error (character 0xF0)".to_string(), 1),
            (1_028_219, "parity error (character 0x0B)".to_string(), 2)
        ]
    );
    // Logic 2's data table, two analyzers, a start row, a negative time first.
    let table = "name,type,start_time,duration,data,error\n\
                 \"RX\",\"data\",-0.5,8.68e-05,0x7E,\n\
                 \"TX\",\"data\",-0.4,8.68e-05,0x01,\n\
                 \"RX\",\"start\",-0.3,0,,\n\
                 \"RX\",\"data\",0.0001,8.68e-05,0xA1,framing\n\
                 \"RX\",\"data\",0.0002,8.68e-05,'x',\n";
    let out = run(table.as_bytes(), &Options::new(Line::n81(115_200)));
    assert_eq!(out.chars, [(0x7E, 0), (0xA1, 500_100), (b'x', 500_200)]);
    assert_eq!(out.notes.len(), 1);
    assert!(
        out.warnings[0].contains("1 row of other analyzers skipped"),
        "{:?}",
        out.warnings
    );
    let tx = run(
        table.as_bytes(),
        &Options {
            channel: Some("TX".into()),
            ..Options::new(Line::n81(115_200))
        },
    );
    assert_eq!(tx.chars, [(0x01, 0)]);
    let none = run(
        table.as_bytes(),
        &Options {
            channel: Some("SPI".into()),
            ..Options::new(Line::n81(115_200))
        },
    );
    assert_eq!(
        none.failure.as_deref(),
        Some("trace: no rows of the analyzer \"SPI\"; the table has RX, TX")
    );
}

#[test]
fn traces_are_recognised_by_content() {
    let sr = write::sr(&[("RX", &Levels::default())], 1000, 10, false);
    let vcd = write::vcd(&[("RX", &Levels::default())], 1000, 1);
    let csv = write::saleae_csv(&[("RX", &Levels::default())], 1000);
    let serial = write::saleae_serial(&[(1, 2, false, false)]);
    let table = b"name,type,start_time,duration,data\n";
    for (data, want) in [
        (&sr[..], Container::Sigrok),
        (&vcd[..], Container::Vcd),
        (&csv[..], Container::SaleaeDigital),
        (&serial[..], Container::SaleaeSerial),
        (&table[..], Container::SaleaeSerial),
        (b"\xEF\xBB\xBF\n  $timescale 1 ns $end", Container::Vcd),
        (
            b"Time[s], Channel 0, Channel 1\n0,1,1\n",
            Container::SaleaeDigital,
        ),
    ] {
        assert_eq!(
            recognise(data, false),
            Some(Some(want)),
            "{:?}",
            &data[..20]
        );
        // Decided from the first bytes that tell, never changed by more.
        for n in 1..data.len().min(64) {
            let early = recognise(&data[..n], false);
            assert!(
                early.is_none() || early == Some(Some(want)),
                "{n}: {early:?}"
            );
        }
    }
    for other in [
        &b"\x7E\x98\x10"[..],
        b"2014-07-11,22:41:01.340: 7E 00",
        b"$GPGGA,123519",
        b"Time,Value\n",
        b"PKZIP",
        b"",
    ] {
        assert_eq!(recognise(other, true), Some(None), "{other:?}");
    }
    assert_eq!(recognise(b"PK\x03", false), None);
    assert_eq!(recognise(b"Time [", false), None);
    assert_eq!(recognise(b"$time", false), None);
}

#[test]
fn broken_and_cut_traces_are_clean_failures() {
    let (files, ..) = two_lines();
    let opts = Options {
        channel: Some("RX".into()),
        ..Options::new(Line::n81(9600))
    };
    for (what, data) in &files {
        // Where a sigrok session's central directory starts (not needed for its samples).
        let directory = memchr::memmem::find(data, b"PK\x01\x02").unwrap_or(data.len());
        for n in (0..data.len()).step_by(data.len() / 97 + 1) {
            // Never a panic; a sigrok session cut before its end says so.
            let out = run(&data[..n], &opts);
            if *what == "sr" && n > 0 && n <= directory {
                assert!(
                    out.failure.is_some(),
                    "{what} cut at {n}: {:?}",
                    out.chars.len()
                );
            }
        }
        let mut flipped = data.clone();
        // Damage after the first bytes, which tell the container.
        for i in (flipped.len() / 4..flipped.len()).step_by(13) {
            flipped[i] ^= 0x5A;
        }
        let _ = run(&flipped, &opts);
    }
    let out = run(b"PK\x03\x04garbage", &opts);
    assert!(
        out.failure
            .as_deref()
            .unwrap()
            .starts_with("trace: not a usable sigrok session: "),
        "{out:?}"
    );
    let mut z = zip::ZipWriter::new(io::Cursor::new(Vec::new()));
    z.start_file("readme.txt", zip::write::SimpleFileOptions::default())
        .unwrap();
    io::Write::write_all(&mut z, b"hello").unwrap();
    let plain_zip = z.finish().unwrap().into_inner();
    assert_eq!(
        run(&plain_zip, &opts).failure.as_deref(),
        Some("trace: not a usable sigrok session: a zip archive without sigrok metadata")
    );
    let out = run(b"$timescale 1 ns $end\n$var wire 1 ! RX $end\n", &opts);
    assert_eq!(
        out.failure.as_deref(),
        Some("trace: not a usable VCD file: the file ends before $enddefinitions")
    );
    let out = run(b"Time [s],RX\n0.0,1\n0.1,0\n0.05,1\n", &opts);
    assert_eq!(
        out.failure.as_deref(),
        Some("trace: line 4: the time goes back")
    );
}

#[test]
fn seconds_are_read_exactly() {
    assert_eq!(parse_seconds(b"0.000104000"), Some(104_000_000));
    assert_eq!(parse_seconds(b"1.028028"), Some(1_028_028_000_000));
    assert_eq!(parse_seconds(b"-0.5"), Some(-500_000_000_000));
    assert_eq!(parse_seconds(b"8.68e-05"), Some(86_800_000));
    assert_eq!(parse_seconds(b"2E3"), Some(2_000_000_000_000_000));
    assert_eq!(parse_seconds(b"0.0000000000019"), Some(1));
    assert_eq!(parse_seconds(b" 12 "), Some(12_000_000_000_000));
    for bad in [
        &b""[..],
        b".",
        b"1.2.3",
        b"x",
        b"1e",
        b"1e99999999999",
        b"--1",
    ] {
        assert_eq!(parse_seconds(bad), None, "{bad:?}");
    }
    assert_eq!(parse_seconds(b"1e2147483647"), None);
    assert_eq!(parse_seconds(b"1e-2147483648"), Some(0));
}

proptest::proptest! {
    /// The UART gives the same characters however its edges are split between reads.
    #[test]
    fn the_uart_does_not_depend_on_the_split(
        steps in proptest::collection::vec((1u64..40, proptest::bool::ANY), 1..300),
        cuts in proptest::collection::vec(0u64..4000, 0..20),
        parity in 0u8..3,
        inverted in proptest::bool::ANY,
    ) {
        let line = Line {
            parity: [Parity::None, Parity::Even, Parity::Odd][usize::from(parity)],
            ..Line::n81(100_000)
        };
        let mut t = 0;
        let mut high = true;
        let mut edges = vec![(0, true)];
        for (dt, flip) in steps {
            t += dt;
            if flip {
                high = !high;
                edges.push((t, high));
            }
        }
        let end = t + 500;
        let decode = |cuts: &[u64]| {
            let mut u = uart::Uart::new(&line, 100_000, TimeBase::rate(1_000_000), !inverted);
            let mut out = Vec::new();
            let mut cuts = cuts.to_vec();
            cuts.sort_unstable();
            let mut c = cuts.iter().peekable();
            for &(t, h) in &edges {
                while let Some(&&at) = c.peek() {
                    if at > t {
                        break;
                    }
                    u.advance(at, &mut |e| out.push(e));
                    c.next();
                }
                u.edge(t, h, &mut |e| out.push(e));
            }
            u.finish(end, &mut |e| out.push(e));
            out
        };
        proptest::prop_assert_eq!(decode(&[]), decode(&cuts));
    }
}

/// The fuzz seeds of `fuzz/seeds/logic_trace/`: one small trace of each container, each with its
/// bytes. `BUSNOOP_REGENERATE=1 cargo test --lib fuzz_seeds` rewrites them.
fn seeds() -> Vec<(&'static str, Vec<u8>, Vec<u8>)> {
    let sport = [0x7E, 0x98, 0x10, 0x05, 0xF1, 0x5A, 0x00, 0x00, 0x00, 0x0B];
    let modbus = [0x01, 0x03, 0x00, 0x00, 0x00, 0x02, 0xC4, 0x0B];
    let inv = Signal {
        line: Line::n81(57_600),
        baud: 57_600.0,
        inverted: true,
    };
    let norm = Signal {
        line: Line::n81(57_600),
        baud: 57_600.0,
        inverted: false,
    };
    let at = |line: &Line, bytes: &[u8]| {
        write::back_to_back(line, f64::from(line.baud), bytes, 50_000, 0.0)
    };
    let s = at(&inv.line, &sport);
    let m = at(&norm.line, &modbus);
    let end = 3_000_000;
    let sp = write::levels(&inv, &s, 500_000, end, &Noise::default());
    let mb = write::levels(&norm, &m, 500_000, end, &Noise::default());
    let idle = write::levels(&norm, &[], 500_000, end, &Noise::default());
    let serial: Vec<(u64, u8, bool, bool)> = m
        .iter()
        .enumerate()
        .map(|(i, c)| (c.0 / 1000, c.1, i == 3, i == 5))
        .collect();
    vec![
        (
            "sport-inverted.sr",
            write::sr(&[("RX", &sp)], 500_000, 2000, false),
            sport.to_vec(),
        ),
        (
            "modbus-two-channels.sr",
            write::sr(&[("EN", &idle), ("RX", &mb)], 500_000, 1 << 20, true),
            modbus.to_vec(),
        ),
        (
            "sport-inverted.vcd",
            write::vcd(&[("D0", &sp)], 500_000, 2_000_000),
            sport.to_vec(),
        ),
        (
            "modbus-saleae.csv",
            write::saleae_csv(&[("Channel 0", &mb)], 500_000),
            modbus.to_vec(),
        ),
        (
            "modbus-saleae-serial.csv",
            write::saleae_serial(&serial),
            modbus.to_vec(),
        ),
    ]
}

#[test]
fn fuzz_seeds_are_current_and_decode() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/logic_trace");
    let regenerate = std::env::var_os("BUSNOOP_REGENERATE").is_some();
    for (name, data, want) in seeds() {
        let out = run(&data, &Options::new(Line::n81(57_600)));
        assert_eq!(bytes(&out), want, "{name}: {:?}", out.failure);
        let path = dir.join(name);
        if regenerate {
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(&path, &data).unwrap();
        }
        let stored = std::fs::read(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (BUSNOOP_REGENERATE=1 writes it)", path.display()));
        assert!(
            stored == data,
            "{name} differs: BUSNOOP_REGENERATE=1 rewrites it"
        );
    }
}
