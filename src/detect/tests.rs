use super::advise::Kept;
use super::live::{Listen, judge_live};
use super::*;
use crate::testing::noise;

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fixtures")
            .join(name),
    )
    .unwrap()
}

fn untimed(bytes: &[u8]) -> Vec<Batch> {
    vec![Batch::single(bytes.to_vec(), None)]
}

/// The ranking of raw bytes and the verdict's winner (label), or `None`.
fn winner(bytes: &[u8]) -> (Option<String>, Option<String>) {
    let ranked = rank(
        candidates(InputKind::Raw, None),
        &untimed(bytes),
        InputKind::Raw,
    );
    match verdict(&ranked) {
        Verdict::Found(i, mixed) => (
            Some(ranked[i].label.clone()),
            mixed.map(|j| ranked[j].label.clone()),
        ),
        _ => (None, None),
    }
}

/// An S-Bus data-mode session: requests and responses of the SBC examples.
fn sbus_data_session() -> Vec<u8> {
    use crate::sbus::telegram::{CrcBasis, encode_data};
    let mut w = Vec::new();
    for i in 0..10u8 {
        encode_data(&mut w, 0, &[1, 6, 3, 0, i], CrcBasis::Escaped);
        encode_data(&mut w, 1, &[0, 0, 1, i], CrcBasis::Escaped);
    }
    w
}

/// An S-Bus break-mode session: a break (0x00) before each request.
fn sbus_break_session() -> Vec<u8> {
    use crate::sbus::telegram::{encode_break_request, encode_break_response};
    let mut w = Vec::new();
    for i in 0..10u8 {
        w.push(0);
        encode_break_request(&mut w, 2, 6, &[0, i, 0x0A]);
        encode_break_response(&mut w, &[0, 0, 1, i]);
    }
    w
}

#[test]
fn every_protocol_of_the_table_has_candidates() {
    for p in PROTOCOLS {
        let raw = candidates(InputKind::Raw, None);
        assert!(
            raw.iter().any(|c| c.protocol.command == p.command),
            "{} is not tried by detect",
            p.name
        );
    }
    // Network captures: only what reads them.
    let net = candidates(InputKind::Pcap, None);
    assert!(net.iter().all(|c| c.protocol.reads(InputKind::Pcap)));
    assert_eq!(net.len(), 1);
}

#[test]
fn each_fixture_names_its_protocol() {
    assert_eq!(
        winner(&fixture("sport-sample.bin")).0,
        Some("S.Port".to_owned())
    );
    assert_eq!(
        winner(&fixture("sab1-session.bin")).0,
        Some("SAB v1 (sync framing)".to_owned())
    );
    assert_eq!(
        winner(&fixture("sab2-session.bin")).0,
        Some("SAB2 (HDLC framing)".to_owned())
    );
    assert_eq!(
        winner(&sbus_data_session()).0,
        Some("S-Bus data mode".to_owned())
    );
    let (b, _) = winner(&sbus_break_session());
    assert!(
        b.as_deref()
            .is_some_and(|l| l.starts_with("S-Bus break") || l.starts_with("S-Bus parity")),
        "{b:?}"
    );
}

#[test]
fn the_evidence_names_frames_and_their_start_bytes() {
    let ranked = rank(
        candidates(InputKind::Raw, None),
        &untimed(&fixture("sport-sample.bin")),
        InputKind::Raw,
    );
    let s = &ranked[0].score;
    assert_eq!((s.frames, s.valid_bytes, s.total), (30, 220, 220));
    assert_eq!(s.starts, [(0x7E, 30)]);
    let text = evidence(&ranked);
    assert!(text.contains("S.Port  "), "{text}");
    assert!(text.contains("100.0%"), "{text}");
    assert!(text.contains("7E ×30"), "{text}");
    assert_eq!(text.lines().count(), 1 + ranked.len());
}

#[test]
fn random_bytes_are_no_known_protocol() {
    for seed in [1u64, 0x2545_F491_4F6C_DD1D, 0x9E37_79B9_7F4A_7C15] {
        let ranked = rank(
            candidates(InputKind::Raw, None),
            &untimed(&noise(100_000, seed)),
            InputKind::Raw,
        );
        assert_eq!(verdict(&ranked), Verdict::Unknown, "seed {seed}");
    }
}

#[test]
fn empty_input_is_empty() {
    let ranked = rank(candidates(InputKind::Raw, None), &[], InputKind::Raw);
    assert_eq!(verdict(&ranked), Verdict::Empty);
}

#[test]
fn a_truncated_file_still_names_its_protocol() {
    let sport = fixture("sport-sample.bin");
    assert_eq!(
        winner(&sport[..sport.len() / 2 + 3]).0,
        Some("S.Port".to_owned())
    );
    let sab = fixture("sab2-session.bin");
    assert_eq!(
        winner(&sab[5..sab.len() - 7]).0,
        Some("SAB2 (HDLC framing)".to_owned())
    );
}

#[test]
fn frames_among_garbage_are_found() {
    // A capture with noise around the frames (a line that was plugged in mid-byte).
    let mut bytes = noise(300, 7);
    bytes.extend(fixture("sport-sample.bin"));
    bytes.extend(noise(100, 8));
    let ranked = rank(
        candidates(InputKind::Raw, None),
        &untimed(&bytes),
        InputKind::Raw,
    );
    assert_eq!(verdict(&ranked), Verdict::Found(0, None));
    assert_eq!(ranked[0].label, "S.Port");
}

#[test]
fn a_mixed_file_names_both_protocols() {
    let mut bytes = fixture("sport-sample.bin");
    bytes.extend(fixture("sab1-session.bin"));
    let (first, second) = winner(&bytes);
    assert_eq!(first, Some("S.Port".to_owned()));
    assert_eq!(second, Some("SAB v1 (sync framing)".to_owned()));
    // S-Bus break mode reads S.Port's keep-alives, but only bytes S.Port covers: not mixed.
    assert_eq!(winner(&fixture("sport-sample.bin")).1, None);
}

#[test]
fn an_inverted_sport_line_is_recognised() {
    let inverted: Vec<u8> = fixture("sport-sample.bin").iter().map(|b| !b).collect();
    assert_eq!(inverted[0], 0x81, "0x81 where 0x7E belongs");
    let ranked = rank(
        candidates(InputKind::Raw, None),
        &untimed(&inverted),
        InputKind::Raw,
    );
    assert!(matches!(verdict(&ranked), Verdict::Found(0, _)));
    assert!(ranked[0].inverted);
    let mut text = String::new();
    found_text(
        &mut text,
        &ranked[0],
        Path::new("/dev/ttyUSB0"),
        Some(57_600),
    );
    assert!(
        text.contains("0x81 arrives where S.Port's 0x7E belongs"),
        "{text}"
    );
    assert!(text.contains("invert RXD"), "{text}");
    assert!(
        text.ends_with("then: busnoop sport /dev/ttyUSB0\n"),
        "{text}"
    );
}

#[test]
fn the_command_carries_options_and_a_quoted_path() {
    let ranked = rank(
        candidates(InputKind::Raw, None),
        &untimed(&fixture("sport-sample.bin")),
        InputKind::Raw,
    );
    assert_eq!(
        ranked[0].command(Path::new("my capture.bin"), None),
        "busnoop sport 'my capture.bin'"
    );
    assert_eq!(
        ranked[0].command(Path::new("/dev/ttyUSB0"), Some(115_200)),
        "busnoop sport --baud 115200 /dev/ttyUSB0"
    );
    assert_eq!(
        ranked[0].command(Path::new("/dev/ttyUSB0"), Some(57_600)),
        "busnoop sport /dev/ttyUSB0",
        "the protocol's own rate is not repeated"
    );
    let parity = rank(
        candidates(InputKind::Raw, None),
        &untimed(&sbus_break_session()),
        InputKind::Raw,
    )
    .into_iter()
    .find(|r| r.label == "S-Bus parity mode")
    .unwrap();
    assert_eq!(
        parity.command(Path::new("a.bin"), None),
        "busnoop sbus --mode parity a.bin"
    );
    assert_eq!(shell_quote(Path::new("it's")), "'it'\\''s'");
    assert_eq!(shell_quote(Path::new("")), "''");
}

fn listen(baud: u32, bytes: &[u8]) -> Listen {
    // Times as a line at that rate would give them, 10 bits per byte, in reads of 64 bytes.
    let batches = bytes
        .chunks(64)
        .enumerate()
        .map(|(i, c)| {
            let t = (i * 64) as u64 * 10 * 1_000_000 / u64::from(baud);
            Batch::single(c.to_vec(), Some(t))
        })
        .collect();
    Listen {
        line: Line::n81(baud),
        batches,
        bytes: bytes.len() as u64,
    }
}

#[test]
fn live_picks_the_rate_where_frames_decode() {
    // At the wrong rates a UART delivers garbage; at 57600 the S.Port frames.
    let sport = fixture("sport-sample.bin").repeat(4);
    let listens: Vec<Listen> = [
        9600, 19200, 38400, 57600, 100_000, 115_200, 230_400, 400_000, 420_000,
    ]
    .iter()
    .enumerate()
    .map(|(i, &b)| {
        if b == 57_600 {
            listen(b, &sport)
        } else {
            listen(b, &noise(600, i as u64 + 1))
        }
    })
    .collect();
    let report = judge_live(&listens);
    let i = report.best.expect("found");
    let best = report.per_rate[i]
        .as_ref()
        .expect("the winner keeps its row");
    assert_eq!(listens[i].line.baud, 57_600);
    assert_eq!(best.label, "S.Port");
    assert!(!best.inverted);
}

#[test]
fn live_ties_go_to_the_protocols_own_rate() {
    // A pty ignores the rate: every rate sees the same bytes.
    let sab = fixture("sab2-session.bin").repeat(3);
    let listens: Vec<Listen> = [9600, 57_600, 115_200, 420_000]
        .iter()
        .map(|&b| listen(b, &sab))
        .collect();
    let report = judge_live(&listens);
    let i = report.best.expect("found");
    let best = report.per_rate[i]
        .as_ref()
        .expect("the winner keeps its row");
    assert_eq!(best.protocol.command, "sab2");
    assert_eq!(listens[i].line.baud, 115_200);
}

#[test]
fn live_recognises_an_inverted_sport_line() {
    let inverted: Vec<u8> = fixture("sport-sample.bin")
        .repeat(4)
        .iter()
        .map(|b| !b)
        .collect();
    let listens = vec![
        listen(9600, &noise(500, 3)),
        listen(57_600, &inverted),
        listen(115_200, &noise(500, 4)),
    ];
    let report = judge_live(&listens);
    let i = report.best.expect("found");
    let best = report.per_rate[i]
        .as_ref()
        .expect("the winner keeps its row");
    assert_eq!(listens[i].line.baud, 57_600);
    assert!(best.inverted);
    assert_eq!(best.protocol.command, "sport");
}

#[test]
fn live_silence_or_noise_finds_nothing() {
    let listens = vec![listen(9600, &[]), listen(57_600, &noise(2000, 9))];
    assert!(judge_live(&listens).best.is_none());
}

fn kept(bytes: &[u8]) -> Kept {
    Kept {
        batches: untimed(bytes),
        total: bytes.len() as u64,
    }
}

#[test]
fn advice_after_a_run() {
    let src = Path::new("cap.bin");
    let sport = fixture("sport-sample.bin");
    // The right protocol: nothing to say.
    assert_eq!(
        advise(
            &crate::sport::PROTOCOL,
            InputKind::Raw,
            &kept(&sport),
            30,
            src
        ),
        Advice::Fine
    );
    // S-Bus reads 16 telegrams in it: a poor run, naming S.Port and the command.
    match advise(
        &crate::sbus::PROTOCOL,
        InputKind::Raw,
        &kept(&sport),
        24,
        src,
    ) {
        Advice::Poor(n) => {
            assert!(n.contains("it looks like S.Port"), "{n}");
            assert!(n.ends_with("try: busnoop sport cap.bin"), "{n}");
        }
        a => panic!("{a:?}"),
    }
    // SAB finds nothing: the failure, naming S.Port.
    match advise(&crate::sab::PROTOCOL, InputKind::Raw, &kept(&sport), 0, src) {
        Advice::NothingDecoded(m) => {
            assert!(
                m.starts_with("no SAB frame in cap.bin; it looks like S.Port"),
                "{m}"
            )
        }
        a => panic!("{a:?}"),
    }
    // Empty.
    assert_eq!(
        advise(&crate::sport::PROTOCOL, InputKind::Raw, &kept(&[]), 0, src),
        Advice::NothingDecoded("empty input: cap.bin holds no bytes".into())
    );
    // Noise: no protocol fits.
    match advise(
        &crate::sport::PROTOCOL,
        InputKind::Raw,
        &kept(&noise(20_000, 5)),
        0,
        Path::new("-"),
    ) {
        Advice::NothingDecoded(m) => assert_eq!(
            m,
            "no S.Port frame in standard input; `busnoop detect -` finds no known protocol in it"
        ),
        a => panic!("{a:?}"),
    }
    // Inverted S.Port given to sport: the fix.
    let inverted: Vec<u8> = sport.iter().map(|b| !b).collect();
    match advise(
        &crate::sport::PROTOCOL,
        InputKind::Raw,
        &kept(&inverted),
        0,
        src,
    ) {
        Advice::NothingDecoded(m) => assert!(m.contains("inverted"), "{m}"),
        a => panic!("{a:?}"),
    }
}

#[test]
fn every_descriptor_has_a_pretty_width_per_column() {
    // The widths of the protocol descriptor follow its decoders' columns (every variant).
    for kind in [InputKind::Raw, InputKind::Pcap] {
        for c in candidates(kind, None) {
            assert_eq!(
                c.protocol.pretty_widths.len(),
                crate::row::BASE_COLUMNS.len() + c.decoder.columns().len(),
                "{}",
                c.label
            );
        }
    }
}
