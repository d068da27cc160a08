use super::*;
use crate::protocol::{Kind, Line, Parity};
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
        kind: Kind::Raw,
        prefix: data[..split].to_vec(),
        reader: Box::new(io::Cursor::new(data[split..].to_vec())),
        name: "trace".into(),
    }
}

fn run(data: &[u8], opts: &Options) -> Out {
    let (tx, rx) = std::sync::mpsc::sync_channel(1 << 20);
    let mut out = Out::default();
    match reader(opened(data), opts) {
        Err(f) => out.failure = Some(f.to_string()),
        Ok(mut r) => loop {
            match r.next_batch(&tx) {
                Ok(Some(c)) => tx.send(c.into()).unwrap(),
                Ok(None) => break,
                Err(f) => {
                    out.failure = Some(f.to_string());
                    break;
                }
            }
        },
    }
    drop(tx);
    for m in rx.iter() {
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
