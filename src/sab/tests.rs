//! Decoder tests: every vector of `fixtures/sab.tsv`, the demo sessions, pairing and timing,
//! detection, and property tests (round trips, noise, chunking, a stray 0x54, mixed
//! request/response sessions).

use super::decoder::Reasm;
use super::detect::Reason;
use super::frame::{EventKind, Framing};
use super::header::Flags;
use super::map::push_payload;
use super::*;
use crate::fmt::{hex, parse_hex};
use crate::protocol::Decoder;
use crate::row::Class;
use crate::row::{Collected, OwnedRow};
use frame::OwnedEvent;
use proptest::prelude::*;

const VECTORS: &str = include_str!("../../fixtures/sab.tsv");

#[derive(Debug)]
struct Vector {
    protocol: String,
    name: String,
    address: u8,
    kind: String,
    header: u8,
    command: u8,
    payload: Vec<u8>,
    crc: u16,
    wire: Vec<u8>,
    wire_len: usize,
    note: String,
}

fn vectors() -> Vec<Vector> {
    let mut lines = VECTORS.lines();
    let head: Vec<&str> = lines.next().unwrap().split('\t').collect();
    assert_eq!(
        head,
        [
            "protocol",
            "name",
            "address",
            "kind",
            "header",
            "command",
            "payload_hex",
            "crc_hex",
            "wire_hex",
            "wire_len",
            "note",
            "source"
        ]
    );
    let byte = |s: &str| u8::from_str_radix(s, 16).unwrap();
    lines
        .filter(|l| !l.is_empty())
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            assert_eq!(c.len(), 12, "{l}");
            Vector {
                protocol: c[0].into(),
                name: c[1].into(),
                address: byte(c[2]),
                kind: c[3].into(),
                header: byte(c[4]),
                command: byte(c[5]),
                payload: parse_hex(c[6]).unwrap(),
                crc: u16::from_str_radix(c[7], 16).unwrap(),
                wire: parse_hex(c[8]).unwrap(),
                wire_len: c[9].parse().unwrap(),
                note: c[10].into(),
            }
        })
        .collect()
}

fn opts(framing: FramingChoice) -> Options {
    Options {
        framing,
        ..Options::default()
    }
}

fn choice(f: Framing) -> FramingChoice {
    match f {
        Framing::Sync => FramingChoice::Sync,
        Framing::Hdlc => FramingChoice::Hdlc,
    }
}

/// Decodes `chunks` (bytes with a time each) and returns the rows and the decoder.
fn decode_chunks(o: &Options, chunks: &[(&[u8], Option<u64>)]) -> (Vec<OwnedRow>, SabDecoder) {
    let mut d = SabDecoder::new(o.clone());
    let mut out = Collected::default();
    for (bytes, time) in chunks {
        d.push(bytes, *time, &mut out).unwrap();
    }
    d.finish(&mut out).unwrap();
    (out.rows, d)
}

fn decode(o: &Options, data: &[u8]) -> (Vec<OwnedRow>, SabDecoder) {
    decode_chunks(o, &[(data, None)])
}

fn col<'a>(row: &'a OwnedRow, name: &str) -> &'a str {
    let i = COLUMNS.iter().position(|c| *c == name).unwrap();
    &row.extra[i]
}

fn types(rows: &[OwnedRow]) -> Vec<&str> {
    rows.iter().map(|r| r.kind.as_str()).collect()
}

fn reassemble(framing: Framing, max_payload: usize, data: &[u8]) -> Vec<OwnedEvent> {
    let mut r = Reasm::new(framing, max_payload);
    let mut out = Vec::new();
    r.push(data, None, &mut |e| out.push(OwnedEvent::from(e)));
    r.finish(&mut |e| out.push(OwnedEvent::from(e)));
    out
}

fn framing_of(protocol: &str) -> Framing {
    match protocol {
        "sab1" => Framing::Sync,
        "sab2" => Framing::Hdlc,
        p => panic!("unknown protocol {p}"),
    }
}

#[test]
fn every_vector_decodes_as_listed() {
    let vs = vectors();
    assert_eq!(vs.len(), 18);
    for v in &vs {
        let ctx = format!("{} {}", v.protocol, v.name);
        let framing = framing_of(&v.protocol);
        assert_eq!(v.wire.len(), v.wire_len, "{ctx}");
        assert_eq!(
            v.header,
            header::header(Flags::of(v.header), v.address),
            "{ctx}"
        );

        // The reassembler: header, command, payload and CRC as listed.
        let evs = reassemble(framing, hdlc::DEFAULT_MAX_PAYLOAD, &v.wire);
        assert_eq!(evs.len(), 1, "{ctx}: {evs:?}");
        let e = &evs[0];
        assert_eq!(e.kind, EventKind::Frame, "{ctx}");
        let mut body = vec![v.header, v.command];
        body.extend_from_slice(&v.payload);
        assert_eq!(e.body, body, "{ctx}");
        assert_eq!(e.crc, Some((v.crc, v.crc)), "{ctx}");
        assert_eq!(e.wire, v.wire, "{ctx}");

        // The encoder reproduces the bytes.
        let mut enc = Vec::new();
        sample::frame(
            &mut enc,
            framing,
            Flags::of(v.header),
            v.address,
            v.command,
            &v.payload,
        );
        assert_eq!(enc, v.wire, "{ctx}");

        // The table, with the framing forced and detected.
        for choice in [choice(framing), FramingChoice::Auto] {
            let (rows, d) = decode(&opts(choice), &v.wire);
            let ctx = format!("{ctx} ({choice:?})");
            assert_eq!(d.framing(), Some(framing), "{ctx}");
            let r = &rows[0];
            let want_type = match v.kind.as_str() {
                "REQUEST" => "Request",
                "ACK" => "ACK",
                "NACK" => "NACK",
                k => panic!("{k}"),
            };
            assert_eq!(r.kind, want_type, "{ctx}");
            assert_eq!(r.id, Some(v.address as u32), "{ctx}");
            assert_eq!(col(r, "Addr"), format!("0x{:02X}", v.address), "{ctx}");
            assert_eq!(r.sensor_no, format!("0x{:02X}", v.command), "{ctx}");
            assert!(r.data.starts_with(&hex(&v.payload)), "{ctx}: {}", r.data);
            assert_eq!(r.raw, v.wire, "{ctx}");
            assert_eq!(col(r, "Framing"), framing.name(), "{ctx}");
            assert_eq!(r.micros, Some(0), "{ctx}");
            let note = col(r, "Note");
            assert!(
                note.starts_with(&format!("framing {}:", framing.name())),
                "{ctx}: {note}"
            );
            if let Some(err) = v.note.strip_prefix("error=") {
                assert!(note.contains(&format!("NACK {err}")), "{ctx}: {note}");
            }
            if want_type == "Request" {
                // Alone in the capture: no response before its end.
                assert_eq!(types(&rows), ["Request", "Timeout"], "{ctx}");
                assert!(col(&rows[1], "Note").contains("end of the capture"));
            } else {
                assert_eq!(rows.len(), 1, "{ctx}");
                assert!(note.contains("no matching request"), "{ctx}: {note}");
            }
            assert_eq!(d.counters().valid_frames, 1, "{ctx}");
        }

        // The other framing finds no valid frame in these bytes.
        let (rows, d) = decode(&opts(choice(framing.other())), &v.wire);
        assert_eq!(d.counters().valid_frames, 0, "{ctx}: {rows:?}");
    }
}

#[test]
fn payload_readings() {
    let mut s = String::new();
    push_payload(&mut s, &[0xAA, 0xBA]);
    assert_eq!(s, "AA BA (47786, -17750)");
    s.clear();
    push_payload(&mut s, &[0x78, 0x56, 0x34, 0x12]);
    assert_eq!(s, "78 56 34 12 (305419896)");
    s.clear();
    push_payload(&mut s, &[0xEF, 0xBE, 0xAD, 0xDE]);
    assert_eq!(s, "EF BE AD DE (3735928559, -559038737)");
    s.clear();
    push_payload(&mut s, &[0x55]);
    assert_eq!(s, "55 (85)");
    s.clear();
    push_payload(&mut s, &[1, 2, 3]);
    assert_eq!(s, "01 02 03");
    s.clear();
    push_payload(&mut s, &[]);
    assert_eq!(s, "");
}

#[test]
fn all_vectors_of_one_framing_lock_detection() {
    for protocol in ["sab1", "sab2"] {
        let framing = framing_of(protocol);
        let wire: Vec<u8> = vectors()
            .iter()
            .filter(|v| v.protocol == protocol)
            .flat_map(|v| v.wire.clone())
            .collect();
        let (auto, d) = decode(&opts(FramingChoice::Auto), &wire);
        assert_eq!(d.framing(), Some(framing));
        let (reason_framing, reason) = d.counters().framings[0];
        assert_eq!(reason_framing, framing);
        assert!(
            matches!(reason, Reason::Locked { .. }),
            "{protocol}: {reason:?}"
        );
        // Detection loses nothing: the rows equal the forced decode but for the note.
        let (forced, _) = decode(&opts(choice(framing)), &wire);
        assert_eq!(strip_first_note(&auto), strip_first_note(&forced));
        assert!(col(&auto[0], "Note").contains("detected (3 valid frames against 0"));
    }
}

/// Rows without the framing note of the first row.
fn strip_first_note(rows: &[OwnedRow]) -> Vec<OwnedRow> {
    let mut rows = rows.to_vec();
    if let Some(r) = rows.first_mut() {
        let i = COLUMNS.iter().position(|c| *c == "Note").unwrap();
        let note = &mut r.extra[i];
        if note.starts_with("framing ") {
            *note = note.split_once("; ").map_or("", |x| x.1).to_owned();
        }
    }
    rows
}

fn fixture_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

#[test]
fn demo_sessions_match_the_fixtures() {
    for (framing, name) in [
        (Framing::Sync, "sab1-session.bin"),
        (Framing::Hdlc, "sab2-session.bin"),
    ] {
        let bytes = sample::session(framing);
        let path = fixture_path(name);
        if std::env::var_os("BUSNOOP_REGENERATE").is_some() {
            std::fs::write(&path, &bytes).unwrap();
        }
        let on_disk = std::fs::read(&path).unwrap_or_default();
        assert!(
            on_disk == bytes,
            "{name} differs from sample::session(); run \
             `BUSNOOP_REGENERATE=1 cargo test demo_sessions` and commit it"
        );

        let (rows, d) = decode(&opts(FramingChoice::Auto), &bytes);
        assert_eq!(d.framing(), Some(framing));
        let noise = match framing {
            Framing::Sync => "Garbage",
            Framing::Hdlc => "Runt",
        };
        assert_eq!(
            types(&rows),
            [
                "Request", "ACK", "Request", "ACK", "Request", "ACK", "Request", "NACK", "Request",
                "NACK", "Request", "Timeout", "Request", "ACK", noise, "Request", "BadCRC",
                "Timeout", "Request", "ACK", "Request", "NACK", "Request", "Timeout"
            ],
            "{name}"
        );
        let c = d.counters();
        assert_eq!(c.timeouts, 3);
        assert_eq!(c.nacks, 3);
        assert_eq!(c.bad_crc, 1);
        assert_eq!(c.unpaired + c.late + c.repeats, 0);
        assert_eq!(c.per[5].nack_codes, [(0x01, 1), (0x02, 1)]);
        assert_eq!(c.per[1].nack_codes, [(0x21, 1)]);
        assert!(col(&rows[21], "Note").contains("user 0x21"));
        assert!(col(&rows[11], "Note").contains("before the next request"));
        assert!(col(&rows[23], "Note").contains("end of the capture"));
        // Every response is paired and carries a response time.
        for r in rows.iter().filter(|r| r.kind == "ACK" || r.kind == "NACK") {
            assert!(!col(r, "Resp ms").is_empty(), "{r:?}");
        }
        if framing == Framing::Sync {
            // `00 54 20`: the false 0x54 was rescanned; modm would have lost two frames.
            assert_eq!(rows[14].data, "00 54 20");
            assert!(col(&rows[14], "Note").contains("1 false 0x54"));
            assert_eq!(c.false_syncs, 1);
        }
    }
}

#[test]
fn response_time_from_reconstructed_time() {
    // 115200 baud, 10 bits per byte: request (5 bytes) + ACK (7 bytes) = 12 bytes = 1041.7 µs.
    let mut w = Vec::new();
    sync::encode(&mut w, 0x05, 0x10, &[]);
    sync::encode(&mut w, 0xC5, 0x10, &[1, 2]);
    let (rows, _) = decode(&opts(FramingChoice::Sync), &w);
    assert_eq!(types(&rows), ["Request", "ACK"]);
    assert_eq!(col(&rows[1], "Resp ms"), "1.041");
    assert_eq!(rows[1].micros, Some(434)); // byte 5
    // At 9600 baud the same bytes take 12.5 ms: past the 10 ms timeout.
    let o = Options {
        baud: 9600,
        ..opts(FramingChoice::Sync)
    };
    let (rows, d) = decode(&o, &w);
    // The ACK starts at 5.2 ms and ends at 12.5 ms: the master's timer ran out while it was on
    // the wire, so the Timeout row (at 10 ms) follows it.
    assert_eq!(types(&rows), ["Request", "ACK", "Timeout"]);
    assert_eq!(rows[1].micros, Some(5_208));
    assert_eq!(rows[2].micros, Some(10_000));
    assert_eq!(col(&rows[1], "Resp ms"), "12.500");
    assert!(col(&rows[1], "Note").contains("late: after the master's 10 ms timeout"));
    assert_eq!(d.counters().late, 1);
    // With a longer timeout it is in time again.
    let o = Options {
        timeout_micros: 20_000,
        ..o
    };
    let (rows, _) = decode(&o, &w);
    assert_eq!(types(&rows), ["Request", "ACK"]);
}

#[test]
fn timed_sources_time_out_by_the_clock() {
    let mut req = Vec::new();
    hdlc::encode(&mut req, 0x05, 0x10, &[]);
    let mut ack = Vec::new();
    hdlc::encode(&mut ack, 0xC5, 0x10, &[7]);
    let o = opts(FramingChoice::Hdlc);
    // In time.
    let (rows, _) = decode_chunks(&o, &[(&req, Some(1_000)), (&ack, Some(3_500))]);
    assert_eq!(types(&rows), ["Request", "ACK"]);
    assert_eq!(col(&rows[1], "Resp ms"), "2.500");
    assert_eq!(rows[1].micros, Some(3_500));
    // Late: the Timeout row comes first, at the deadline.
    let (rows, _) = decode_chunks(&o, &[(&req, Some(1_000)), (&ack, Some(16_000))]);
    assert_eq!(types(&rows), ["Request", "Timeout", "ACK"]);
    assert_eq!(rows[1].micros, Some(11_000));
    assert_eq!(col(&rows[1], "Note"), "no response within 10 ms");
    assert_eq!(col(&rows[2], "Resp ms"), "15.000");
    assert_eq!(rows[2].class, Class::Warning);
    // Something else arrives after the deadline: the Timeout row is placed before it.
    let (rows, _) = decode_chunks(&o, &[(&req, Some(1_000)), (&req, Some(30_000))]);
    assert_eq!(types(&rows), ["Request", "Timeout", "Request", "Timeout"]);
    assert_eq!(rows[1].micros, Some(11_000));
    // Live source going quiet: idle() reports the timeout.
    let mut d = SabDecoder::new(o.clone());
    let mut out = Collected::default();
    d.push(&req, Some(1_000), &mut out).unwrap();
    d.idle(5_000, &mut out).unwrap();
    assert_eq!(types(&out.rows), ["Request"]);
    d.idle(12_000, &mut out).unwrap();
    assert_eq!(types(&out.rows), ["Request", "Timeout"]);
    d.finish(&mut out).unwrap();
    assert_eq!(out.rows.len(), 2, "reported once");
}

#[test]
fn unpaired_repeated_and_reserved() {
    let mut w = Vec::new();
    let f = Framing::Hdlc;
    sample::frame(&mut w, f, Flags::Ack, 3, 1, &[]); // no request
    sample::frame(&mut w, f, Flags::Request, 3, 1, &[]);
    sample::frame(&mut w, f, Flags::Ack, 3, 2, &[]); // wrong command
    sample::frame(&mut w, f, Flags::Ack, 3, 1, &[]);
    sample::frame(&mut w, f, Flags::Ack, 3, 1, &[]); // a second answer
    sample::frame(&mut w, f, Flags::Reserved, 4, 9, &[]);
    sample::frame(&mut w, f, Flags::Nack, 4, 9, &[0x05]);
    let (rows, d) = decode(&opts(FramingChoice::Hdlc), &w);
    assert_eq!(
        types(&rows),
        ["ACK", "Request", "ACK", "ACK", "ACK", "Reserved", "NACK"]
    );
    assert!(col(&rows[0], "Note").contains("no matching request"));
    assert!(col(&rows[2], "Note").contains("the master waits for address 3 command 0x01"));
    assert!(col(&rows[3], "Note").is_empty(), "{:?}", rows[3]);
    assert!(col(&rows[4], "Note").contains("repeated response"));
    assert!(col(&rows[5], "Note").contains("reserved flag bits"));
    assert!(col(&rows[6], "Note").contains("NACK reserved 0x05"));
    assert!(!col(&rows[6], "Resp ms").is_empty());
    let c = d.counters();
    assert_eq!((c.unpaired, c.repeats, c.timeouts), (2, 1, 0));
    assert_eq!(c.per[3].times.count, 1);
}

#[test]
fn names_for_devices_and_commands() {
    let o = Options {
        devices: vec![("sonar".into(), 5)],
        commands: vec![("distance".into(), 0x10)],
        ..opts(FramingChoice::Auto)
    };
    let (rows, _) = decode(&o, &sample::session(Framing::Sync));
    assert_eq!(rows[2].device, "sonar");
    assert_eq!(rows[2].sensor, "distance");
    assert_eq!(rows[0].device, "");
    assert_eq!(rows[0].sensor, "");
    let timeout = &rows[23];
    assert_eq!(
        (timeout.device.as_str(), timeout.sensor.as_str()),
        ("sonar", "distance")
    );
}

#[test]
fn bad_crc_rows_say_what_they_would_have_been() {
    let (rows, _) = decode(
        &opts(FramingChoice::Sync),
        &parse_hex("54 04 12 34 EF BE AD DE EF").unwrap(),
    );
    assert_eq!(types(&rows), ["BadCRC"]);
    assert_eq!(rows[0].class, Class::Error);
    assert_eq!(rows[0].id, Some(0x12));
    assert!(col(&rows[0], "Note").contains("CRC-8 0xEF, expected 0xEE; read as Request"));
    // The other reading of the CRC: SYNC covered (0xE6 per sab.md).
    let (rows, _) = decode(
        &opts(FramingChoice::Sync),
        &parse_hex("54 04 12 34 EF BE AD DE E6").unwrap(),
    );
    assert!(col(&rows[0], "Note").contains("matches if SYNC is covered"));
    let (rows, _) = decode(
        &opts(FramingChoice::Hdlc),
        &parse_hex("7E 12 34 EF BE AD DE 1A 96 7E").unwrap(),
    );
    assert!(col(&rows[0], "Note").contains("CRC-16 0x961A, expected 0x951A"));
}

#[test]
fn sab2_errors_become_rows() {
    let mut w = parse_hex("11 22 7E 7E 01 7E 01 02 7D 7E").unwrap();
    hdlc::encode(&mut w, 0x01, 0x02, &(0..40).collect::<Vec<u8>>());
    w.push(0x7E);
    w.extend(std::iter::repeat_n(0x33, 300));
    w.extend_from_slice(&[0x7E, 0x01, 0x02]);
    let (rows, d) = decode(&opts(FramingChoice::Hdlc), &w);
    assert_eq!(
        types(&rows),
        [
            "Garbage",
            "Runt",
            "Abort",
            "Request",
            "Overlong",
            "Timeout",
            "Truncated"
        ]
    );
    // The 300 noise bytes take 26 ms: the request's deadline passes inside them.
    assert_eq!(col(&rows[5], "Note"), "no response within 10 ms");
    assert!(col(&rows[0], "Note").contains("before the first 0x7E"));
    assert!(col(&rows[3], "Note").contains("overlong: 40-byte payload"));
    assert!(col(&rows[4], "Note").contains("300 bytes between flags"));
    assert!(rows[4].data.ends_with(" …"));
    let c = d.counters();
    assert_eq!(
        (c.runts, c.aborts, c.overlong, c.truncated, c.garbage_bytes),
        (1, 1, 2, 1, 2)
    );
    let p = d.problems().line().unwrap();
    assert!(
        p.contains("1 runt") && p.contains("2 overlong frames"),
        "{p}"
    );
}

#[test]
fn garbage_only_input_is_reported_not_fatal() {
    let (rows, d) = decode(&opts(FramingChoice::Auto), &[0u8; 100]);
    assert!(rows.iter().all(|r| r.kind == "Garbage"));
    assert_eq!(d.counters().garbage_bytes, 100);
    assert!(col(&rows[0], "Note").contains("no valid frame of either framing"));
    let p = d.problems().line().unwrap();
    assert!(p.starts_with("SAB: no valid frame"), "{p}");
    // No input at all: no rows, no complaint.
    let (rows, d) = decode(&opts(FramingChoice::Auto), &[]);
    assert!(rows.is_empty());
    assert_eq!(d.problems().line(), None);
    assert!(d.stats().to_string().contains("not decided"));
}

#[test]
fn hold_limit_then_switch_to_the_other_framing() {
    // 16 KiB of zeros: no frame of either kind; detection gives up (SAB2 on a tie).
    let mut w = vec![0u8; detect::HOLD_BYTES];
    let sync_start = w.len();
    for i in 0..10u8 {
        sync::encode(&mut w, 0x05, i, &[i]);
    }
    let (rows, d) = decode(&opts(FramingChoice::Auto), &w);
    assert_eq!(d.framing(), Some(Framing::Sync));
    let f = &d.counters().framings;
    assert_eq!(f.len(), 2, "{f:?}");
    assert_eq!(f[0], (Framing::Hdlc, Reason::HoldFull { sync: 0, hdlc: 0 }));
    assert_eq!(f[1].0, Framing::Sync);
    let Reason::Switched { at } = f[1].1 else {
        panic!("{f:?}")
    };
    // The sixth sync frame triggers the switch; it and the following frames are decoded.
    assert_eq!(at, sync_start as u64 + 6 * 6);
    let sync_rows: Vec<&OwnedRow> = rows.iter().filter(|r| r.kind != "Garbage").collect();
    assert!(col(sync_rows[0], "Note").contains("switched at byte"));
    assert_eq!(sync_rows[0].sensor_no, "0x05");
    // Requests 5..=9, each closed by the next one (or by the end of the capture).
    assert_eq!(sync_rows.len(), 10, "{rows:#?}");
    assert!(sync_rows.iter().all(|r| col(r, "Framing") == "sync"));
    assert!(
        rows.iter()
            .take_while(|r| r.kind == "Garbage")
            .all(|r| col(r, "Framing") == "hdlc")
    );
}

#[test]
fn a_gap_closes_what_is_open_and_decoding_goes_on() {
    // The driver calls finish() when a live adapter disappears, then push() again after it.
    let mut w = Vec::new();
    sync::encode(&mut w, 0x05, 0x10, &[1, 2, 3]);
    for choice in [FramingChoice::Sync, FramingChoice::Auto] {
        let mut d = SabDecoder::new(opts(choice));
        let mut out = Collected::default();
        d.push(&[0x99], None, &mut out).unwrap();
        d.push(&w, None, &mut out).unwrap(); // a request
        d.push(&w[..4], None, &mut out).unwrap(); // cut by the gap
        d.finish(&mut out).unwrap();
        assert_eq!(
            types(&out.rows),
            ["Garbage", "Request", "Truncated", "Timeout"],
            "{choice:?}"
        );
        d.push(&w, None, &mut out).unwrap();
        d.push(&w, None, &mut out).unwrap();
        d.finish(&mut out).unwrap();
        assert_eq!(
            types(&out.rows[4..]),
            ["Request", "Timeout", "Request", "Timeout"],
            "{choice:?}"
        );
        assert_eq!(d.counters().valid_frames, 3);
        assert_eq!(d.framing(), Some(Framing::Sync));
    }
}

// ---------------------------------------------------------------------------------------
// Property tests

/// Payload bytes biased towards the special bytes of both framings.
fn payload_byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        6 => any::<u8>(),
        1 => Just(sync::SYNC),
        1 => Just(hdlc::FLAG),
        1 => Just(hdlc::ESCAPE),
        1 => Just(0x20u8),
    ]
}

fn payload(max: usize) -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(payload_byte(), 0..=max)
}

/// `(header, command, payload)`.
fn frame_parts(max: usize) -> impl Strategy<Value = (u8, u8, Vec<u8>)> {
    (any::<u8>(), payload_byte(), payload(max))
}

fn framing() -> impl Strategy<Value = Framing> {
    prop_oneof![Just(Framing::Sync), Just(Framing::Hdlc)]
}

/// Splits `data` at `cuts` (taken modulo the length) into chunks.
fn chunks<'a>(data: &'a [u8], cuts: &[usize]) -> Vec<&'a [u8]> {
    let mut at: Vec<usize> = cuts
        .iter()
        .map(|c| if data.is_empty() { 0 } else { c % data.len() })
        .collect();
    at.push(0);
    at.push(data.len());
    at.sort_unstable();
    at.dedup();
    at.windows(2).map(|w| &data[w[0]..w[1]]).collect()
}

fn reassemble_chunked(framing: Framing, data: &[u8], cuts: &[usize]) -> Vec<OwnedEvent> {
    let mut r = Reasm::new(framing, hdlc::DEFAULT_MAX_PAYLOAD);
    let mut out = Vec::new();
    for c in chunks(data, cuts) {
        r.push(c, None, &mut |e| out.push(OwnedEvent::from(e)));
    }
    r.finish(&mut |e| out.push(OwnedEvent::from(e)));
    out
}

/// Checks what must hold for any input: events in order, their bytes are the input's, every
/// frame passes an independent CRC check, SAB v1 events tile the input.
fn check_events(framing: Framing, data: &[u8], evs: &[OwnedEvent]) -> Result<(), TestCaseError> {
    let mut next = 0u64;
    for e in evs {
        prop_assert!(
            e.start_pos < e.end_pos && e.end_pos <= data.len() as u64,
            "{e:?}"
        );
        let span = &data[e.start_pos as usize..e.end_pos as usize];
        prop_assert_eq!(e.wire_len, span.len() as u64);
        prop_assert!(span.starts_with(&e.wire));
        match framing {
            Framing::Sync => {
                prop_assert_eq!(e.start_pos, next, "SAB v1 events must tile the input");
                next = e.end_pos;
            }
            Framing::Hdlc => {
                // Frames share at most their delimiter with the previous one.
                prop_assert!(e.start_pos + 1 >= next, "{:?}", e);
                next = e.end_pos;
            }
        }
        if e.kind == EventKind::Frame {
            match framing {
                Framing::Sync => {
                    let n = span.len();
                    prop_assert_eq!(span[0], sync::SYNC);
                    prop_assert_eq!(span[1] as usize + sync::OVERHEAD, n);
                    prop_assert_eq!(check_crc8(&span[1..]), 0);
                }
                Framing::Hdlc => {
                    prop_assert_eq!(span[0], hdlc::FLAG);
                    prop_assert_eq!(span[span.len() - 1], hdlc::FLAG);
                    let body = unstuff(&span[1..span.len() - 1]);
                    prop_assert!(body.len() >= 4);
                    prop_assert_eq!(check_crc16(&body), 0);
                    prop_assert_eq!(&body[..body.len() - 2], &e.body[..]);
                }
            }
        }
    }
    if framing == Framing::Sync {
        prop_assert_eq!(
            next,
            data.len() as u64,
            "SAB v1 events must cover every byte"
        );
    }
    Ok(())
}

/// Independent bit-loop CRC-8/MAXIM-DOW residue (sab.md §2: reflected poly 0x8C, init 0).
fn check_crc8(bytes: &[u8]) -> u8 {
    let mut crc = 0u8;
    for &b in bytes {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0x8C
            } else {
                crc >> 1
            };
        }
    }
    crc
}

/// Independent bit-loop CRC-16/MODBUS residue (reflected poly 0xA001, init 0xFFFF).
fn check_crc16(bytes: &[u8]) -> u16 {
    let mut crc = 0xFFFFu16;
    for &b in bytes {
        crc ^= b as u16;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xA001
            } else {
                crc >> 1
            };
        }
    }
    crc
}

/// Unstuffs like modm (an escape re-arms on a second escape).
fn unstuff(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut esc = false;
    for &b in bytes {
        if b == hdlc::ESCAPE {
            esc = true;
        } else if esc {
            esc = false;
            out.push(b ^ 0x20);
        } else {
            out.push(b);
        }
    }
    out
}

/// Encodes frames; returns the bytes and each frame's span.
fn encode_all(
    framing: Framing,
    frames: &[(u8, u8, Vec<u8>)],
    noise: &[Vec<u8>],
) -> (Vec<u8>, Vec<(u64, u64)>) {
    let mut w = Vec::new();
    let mut spans = Vec::new();
    for (i, (h, c, p)) in frames.iter().enumerate() {
        if let Some(n) = noise.get(i) {
            w.extend_from_slice(n);
        }
        let start = w.len() as u64;
        match framing {
            Framing::Sync => sync::encode(&mut w, *h, *c, p),
            Framing::Hdlc => hdlc::encode(&mut w, *h, *c, p),
        }
        spans.push((start, w.len() as u64));
    }
    if let Some(n) = noise.get(frames.len()) {
        w.extend_from_slice(n);
    }
    (w, spans)
}

/// A transaction of a session: a request and maybe a response.
#[derive(Clone, Debug)]
struct Tx {
    addr: u8,
    cmd: u8,
    req: Vec<u8>,
    /// `None` = no response; `Some(None)` = NACK; `Some(Some(payload))` = ACK.
    resp: Option<Result<Vec<u8>, u8>>,
}

fn tx() -> impl Strategy<Value = Tx> {
    (
        0u8..64,
        payload_byte(),
        payload(6),
        prop_oneof![
            1 => Just(None),
            3 => payload(8).prop_map(|p| Some(Ok(p))),
            1 => any::<u8>().prop_map(|c| Some(Err(c))),
        ],
    )
        .prop_map(|(addr, cmd, req, resp)| Tx {
            addr,
            cmd,
            req,
            resp,
        })
}

/// Encodes a session; returns the bytes and the expected `(type, resp micros)` rows at the
/// given baud rate (requests and responses back to back, reconstructed time).
fn session(framing: Framing, txs: &[Tx], baud: u32) -> (Vec<u8>, Vec<(String, Option<u64>)>) {
    let ns = |pos: usize| pos as u128 * 10_000_000_000 / baud as u128;
    let mut w = Vec::new();
    let mut rows = Vec::new();
    for (i, t) in txs.iter().enumerate() {
        let start = w.len();
        sample::frame(&mut w, framing, Flags::Request, t.addr, t.cmd, &t.req);
        rows.push(("Request".to_owned(), None));
        match &t.resp {
            None => {
                let _ = i;
                rows.push(("Timeout".to_owned(), None));
            }
            Some(r) => {
                let (flags, p, kind) = match r {
                    Ok(p) => (Flags::Ack, p.clone(), "ACK"),
                    Err(code) => (Flags::Nack, vec![*code], "NACK"),
                };
                sample::frame(&mut w, framing, flags, t.addr, t.cmd, &p);
                rows.push((
                    kind.to_owned(),
                    Some(((ns(w.len()) - ns(start)) / 1000) as u64),
                ));
            }
        }
    }
    (w, rows)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn round_trip(framing in framing(), frames in prop::collection::vec(frame_parts(32), 1..12)) {
        let (w, spans) = encode_all(framing, &frames, &[]);
        let evs = reassemble(framing, hdlc::DEFAULT_MAX_PAYLOAD, &w);
        check_events(framing, &w, &evs)?;
        prop_assert_eq!(evs.len(), frames.len());
        for ((e, (h, c, p)), span) in evs.iter().zip(&frames).zip(&spans) {
            prop_assert_eq!(e.kind, EventKind::Frame);
            prop_assert_eq!(e.body[0], *h);
            prop_assert_eq!(e.body[1], *c);
            prop_assert_eq!(&e.body[2..], &p[..]);
            prop_assert_eq!((e.start_pos, e.end_pos), *span);
        }
    }

    #[test]
    fn random_bytes_never_panic_and_frames_are_valid(
        data in prop::collection::vec(payload_byte(), 0..600),
        cuts in prop::collection::vec(any::<usize>(), 0..8),
    ) {
        for framing in [Framing::Sync, Framing::Hdlc] {
            let evs = reassemble_chunked(framing, &data, &cuts);
            check_events(framing, &data, &evs)?;
            prop_assert_eq!(&evs, &reassemble(framing, hdlc::DEFAULT_MAX_PAYLOAD, &data));
        }
        // The SAB v1 buffer stays bounded.
        let mut r = sync::Reassembler::new();
        for &b in &data {
            r.step(b, None, &mut |_| {});
            prop_assert!(r.held() <= sync::CAPACITY);
        }
        for choice in [FramingChoice::Auto, FramingChoice::Sync, FramingChoice::Hdlc] {
            let (rows, _) = decode(&opts(choice), &data);
            prop_assert!(rows.iter().all(|r| r.micros.is_some()));
        }
    }

    #[test]
    fn chunk_split_invariance(
        framing in framing(),
        frames in prop::collection::vec(frame_parts(10), 0..8),
        noise in prop::collection::vec(prop::collection::vec(payload_byte(), 0..6), 0..9),
        cuts in prop::collection::vec(any::<usize>(), 1..12),
    ) {
        let (w, _) = encode_all(framing, &frames, &noise);
        for f in [Framing::Sync, Framing::Hdlc] {
            prop_assert_eq!(reassemble_chunked(f, &w, &cuts), reassemble(f, hdlc::DEFAULT_MAX_PAYLOAD, &w));
        }
        for choice in [FramingChoice::Auto, choice(framing)] {
            let o = opts(choice);
            let whole = decode(&o, &w).0;
            let parts: Vec<(&[u8], Option<u64>)> =
                chunks(&w, &cuts).into_iter().map(|c| (c, None)).collect();
            prop_assert_eq!(&decode_chunks(&o, &parts).0, &whole);
        }
    }

    #[test]
    fn chunk_split_invariance_with_times(
        framing in framing(),
        txs in prop::collection::vec(tx(), 1..8),
        segs in prop::collection::vec(any::<usize>(), 1..10),
        cuts in prop::collection::vec(any::<usize>(), 1..12),
        gaps in prop::collection::vec(0u64..30_000, 10),
    ) {
        let (w, _) = session(framing, &txs, DEFAULT_BAUD);
        // Times per segment; the chunking splits segments further (same time per byte).
        let segments = chunks(&w, &segs);
        let mut t = 0;
        let mut timed = Vec::new();
        for (i, s) in segments.iter().enumerate() {
            t += gaps[i % gaps.len()];
            timed.push((*s, Some(t)));
        }
        let mut fine = Vec::new();
        for (s, time) in &timed {
            for c in chunks(s, &cuts) {
                fine.push((c, *time));
            }
        }
        for choice in [FramingChoice::Auto, choice(framing)] {
            let o = opts(choice);
            prop_assert_eq!(&decode_chunks(&o, &fine).0, &decode_chunks(&o, &timed).0);
        }
    }

    #[test]
    fn noise_between_frames(
        framing in framing(),
        frames in prop::collection::vec(frame_parts(32), 1..10),
        noise in prop::collection::vec(prop::collection::vec(payload_byte(), 0..40), 0..11),
    ) {
        let (w, spans) = encode_all(framing, &frames, &noise);
        let evs = reassemble(framing, hdlc::DEFAULT_MAX_PAYLOAD, &w);
        check_events(framing, &w, &evs)?;
        let valid: Vec<&OwnedEvent> = evs.iter().filter(|e| e.kind == EventKind::Frame).collect();
        for &(s, e) in &spans {
            let found = valid.iter().any(|v| (v.start_pos, v.end_pos) == (s, e));
            match framing {
                // Every 0x7E ends a frame: noise can never hide a real frame.
                Framing::Hdlc => prop_assert!(found, "lost the frame at {s}..{e}: {evs:?}"),
                // Only a CRC-valid false frame that starts earlier and overlaps can.
                Framing::Sync => prop_assert!(
                    found || valid.iter().any(|v| v.start_pos < s && v.end_pos > s),
                    "lost the frame at {s}..{e}: {evs:?}"
                ),
            }
        }
    }

    #[test]
    fn noise_without_sync_bytes_loses_nothing_in_sab1(
        frames in prop::collection::vec(frame_parts(32), 1..10),
        noise in prop::collection::vec(
            prop::collection::vec(any::<u8>().prop_filter("no 0x54", |b| *b != sync::SYNC), 0..40),
            0..11),
    ) {
        let (w, spans) = encode_all(Framing::Sync, &frames, &noise);
        let evs = reassemble(Framing::Sync, 32, &w);
        let got: Vec<(u64, u64)> = evs
            .iter()
            .filter(|e| e.kind == EventKind::Frame)
            .map(|e| (e.start_pos, e.end_pos))
            .collect();
        prop_assert_eq!(got, spans);
        let garbage: u64 = evs
            .iter()
            .filter(|e| e.kind == EventKind::Garbage)
            .map(|e| e.wire_len)
            .sum();
        let used = noise.iter().take(frames.len() + 1);
        prop_assert_eq!(garbage, used.map(|n| n.len() as u64).sum::<u64>());
        prop_assert!(evs.iter().all(|e| matches!(e.kind, EventKind::Frame | EventKind::Garbage)));
    }

    #[test]
    fn stray_sync_in_front_of_a_frame_is_never_lost(
        frames in prop::collection::vec(frame_parts(32), 1..10),
        strays in prop::collection::vec(any::<bool>(), 10),
    ) {
        // A lone 0x54 right before a frame: its LENGTH would be 0x54 > 32.
        let noise: Vec<Vec<u8>> = strays
            .iter()
            .map(|&s| if s { vec![sync::SYNC] } else { vec![] })
            .collect();
        let (w, spans) = encode_all(Framing::Sync, &frames, &noise);
        let evs = reassemble(Framing::Sync, 32, &w);
        let got: Vec<(u64, u64)> = evs
            .iter()
            .filter(|e| e.kind == EventKind::Frame)
            .map(|e| (e.start_pos, e.end_pos))
            .collect();
        prop_assert_eq!(got, spans);
        // The same through the decoder with detection.
        let (rows, d) = decode(&opts(FramingChoice::Auto), &w);
        prop_assert_eq!(d.framing(), Some(Framing::Sync));
        prop_assert_eq!(d.counters().valid_frames, frames.len() as u64);
        let garbage = rows.iter().filter(|r| r.kind == "Garbage").count();
        prop_assert!(garbage <= frames.len());
    }

    #[test]
    fn stray_sync_with_a_plausible_length(
        frames in prop::collection::vec(frame_parts(32), 2..8),
        length in 0u8..=32,
        before in 0usize..8,
    ) {
        // `54 LEN` that modm would follow into the frames behind it.
        let mut noise = vec![vec![]; frames.len() + 1];
        noise[before % frames.len()] = vec![sync::SYNC, length];
        let (w, spans) = encode_all(Framing::Sync, &frames, &noise);
        let evs = reassemble(Framing::Sync, 32, &w);
        let valid: Vec<&OwnedEvent> = evs.iter().filter(|e| e.kind == EventKind::Frame).collect();
        for &(s, e) in &spans {
            let found = valid.iter().any(|v| (v.start_pos, v.end_pos) == (s, e));
            // Lost only to a CRC-valid false frame (1 in 256 per candidate).
            prop_assert!(found || valid.iter().any(|v| v.start_pos < s && v.end_pos > s));
        }
    }

    #[test]
    fn mixed_sessions_pair_requests_and_responses(
        framing in framing(),
        txs in prop::collection::vec(tx(), 1..16),
        cuts in prop::collection::vec(any::<usize>(), 0..6),
    ) {
        let (w, expected) = session(framing, &txs, DEFAULT_BAUD);
        let parts: Vec<(&[u8], Option<u64>)> =
            chunks(&w, &cuts).into_iter().map(|c| (c, None)).collect();
        let o = Options { timeout_micros: 1_000_000, ..opts(choice(framing)) };
        let (rows, d) = decode_chunks(&o, &parts);
        let got: Vec<(String, Option<u64>)> = rows
            .iter()
            .map(|r| {
                let resp = col(r, "Resp ms");
                (r.kind.clone(), (!resp.is_empty()).then(|| {
                    let (ms, frac) = resp.split_once('.').unwrap();
                    ms.parse::<u64>().unwrap() * 1000 + frac.parse::<u64>().unwrap()
                }))
            })
            .collect();
        prop_assert_eq!(&got, &expected);
        let c = d.counters();
        let unanswered = txs.iter().filter(|t| t.resp.is_none()).count() as u64;
        prop_assert_eq!(c.timeouts, unanswered);
        prop_assert_eq!(c.unpaired + c.late + c.repeats, 0);
        // Timeout rows carry the request's address and command.
        let mut i = 0;
        for t in &txs {
            prop_assert_eq!(rows[i].id, Some(t.addr as u32));
            prop_assert_eq!(&rows[i + 1].sensor_no, &format!("0x{:02X}", t.cmd));
            prop_assert_eq!(rows[i + 1].id, Some(t.addr as u32));
            i += 2;
        }

        // Detection finds the same rows (no row lost while undecided).
        let o = Options { framing: FramingChoice::Auto, ..o };
        let (auto, d) = decode_chunks(&o, &parts);
        let f = d.counters().framings[0];
        if f.0 == framing {
            prop_assert_eq!(strip_first_note(&auto), strip_first_note(&rows));
        } else {
            // Only possible when the other framing found CRC-valid frames by chance.
            let other = match f.1 {
                Reason::EndOfInput { sync, hdlc } | Reason::Locked { sync, hdlc } =>
                    if framing == Framing::Sync { hdlc } else { sync },
                _ => 0,
            };
            prop_assert!(other > 0, "{f:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    // The self dev-dependency turns the checks on; a published crate's tests go without them.
    #[cfg(feature = "selfcheck")]
    #[test]
    fn selfcheck_on_random_sessions_and_noise(
        framing in framing(),
        txs in prop::collection::vec(tx(), 0..6),
        noise in prop::collection::vec(payload_byte(), 0..80),
        at in any::<usize>(),
    ) {
        let (mut w, _) = session(framing, &txs, DEFAULT_BAUD);
        let at = if w.is_empty() { 0 } else { at % w.len() };
        w.splice(at..at, noise);
        crate::selfcheck::sab(&w);
    }
}

#[test]
fn every_stray_length_byte_before_the_modm_test_frames() {
    // Exhaustive version of the property above for the three modm unit-test frames.
    let frames: Vec<Vec<u8>> = vectors()
        .iter()
        .filter(|v| v.protocol == "sab1")
        .map(|v| v.wire.clone())
        .collect();
    let mut lost_to_chance = 0;
    for length in 0..=255u8 {
        let mut w = vec![sync::SYNC, length];
        let mut spans = Vec::new();
        for f in &frames {
            spans.push((w.len() as u64, (w.len() + f.len()) as u64));
            w.extend_from_slice(f);
        }
        let evs = reassemble(Framing::Sync, 32, &w);
        let valid: Vec<(u64, u64)> = evs
            .iter()
            .filter(|e| e.kind == EventKind::Frame)
            .map(|e| (e.start_pos, e.end_pos))
            .collect();
        if valid == spans {
            continue;
        }
        // The only excuse: the false candidate passed its CRC.
        assert_eq!(valid[0].0, 0, "length {length:#04X}: {evs:?}");
        lost_to_chance += 1;
    }
    assert!(lost_to_chance <= 2, "{lost_to_chance}");
}

#[test]
fn framing_switches_back_and_forth_keep_a_bounded_list() {
    // 300 blocks of 8 frames, alternating framings: a switch at every block.
    let mut w = Vec::new();
    for b in 0..300u32 {
        for i in 0..8u8 {
            if b % 2 == 0 {
                sync::encode(&mut w, 0x05, i, &[i]);
            } else {
                hdlc::encode(&mut w, 0x05, i, &[i]);
            }
        }
    }
    let (_, d) = decode(&opts(FramingChoice::Auto), &w);
    let c = d.counters();
    assert!(
        c.framings.len() <= stats::MAX_FRAMINGS,
        "{}",
        c.framings.len()
    );
    assert!(c.framings_omitted > 250, "{}", c.framings_omitted);
    assert_eq!(
        c.framings.len() as u64 + c.framings_omitted,
        300,
        "every choice is listed or counted"
    );
    let report = d.stats().to_string();
    assert!(report.contains(" more framing switches"), "{report}");
}

/// The Value of every row of the demo session: (Type, part name, Value, Unit).
fn values_of(rows: &[OwnedRow]) -> Vec<(String, String, String, String)> {
    rows.iter()
        .map(|r| {
            let (name, text) = r.parts.first().map_or((String::new(), String::new()), |p| {
                (p.0.clone(), p.2.clone())
            });
            (r.kind.clone(), name, text, col(r, "Unit").to_owned())
        })
        .collect()
}

#[test]
fn default_values_of_requests_and_acks() {
    for framing in [Framing::Sync, Framing::Hdlc] {
        let o = Options {
            commands: vec![("distance".into(), 0x10)],
            ..opts(choice(framing))
        };
        let (rows, _) = decode(&o, &sample::session(framing));
        let v = values_of(&rows);
        let s =
            |a: &str, b: &str, c: &str| (a.to_owned(), b.to_owned(), c.to_owned(), String::new());
        // A write's payload: the request's number, named `.req`.
        assert_eq!(v[0], s("Request", "0x02.req", "85"));
        assert_eq!(v[1], s("ACK", "", ""));
        // A read: the ACK's number, named by --command.
        assert_eq!(v[3], s("ACK", "distance", "291"));
        // An argument and an answer: two quantities, two names; unsigned.
        assert_eq!(v[4], s("Request", "0x34.req", "3735928559"));
        assert_eq!(v[5], s("ACK", "0x34", "305419896"));
        // A NACK's payload is an error code, not a number.
        assert_eq!(v[7], s("NACK", "", ""));
        assert_eq!(v[8], s("Request", "distance.req", "1"));
        assert_eq!(v[9], s("NACK", "", ""));
        assert_eq!(v[13], s("ACK", "0x02", "125"));
        // A frame whose check failed carries no number.
        let bad = rows.iter().find(|r| r.kind == "BadCRC").unwrap();
        assert!(bad.parts.is_empty(), "{bad:?}");
        assert!(bad.data.ends_with("(6)"));
        for r in &rows {
            assert!(r.parts.len() <= 1);
            if let Some(p) = r.parts.first() {
                assert!(matches!(r.kind.as_str(), "Request" | "ACK"), "{r:?}");
                p.2.parse::<f64>().unwrap();
            }
        }
    }
}

#[test]
fn declared_values_are_typed_scaled_and_have_units() {
    let mut w = Vec::new();
    let f = Framing::Hdlc;
    sample::frame(&mut w, f, Flags::Request, 5, 0x10, &[]);
    sample::frame(&mut w, f, Flags::Ack, 5, 0x10, &291u16.to_le_bytes());
    sample::frame(&mut w, f, Flags::Request, 0x12, 0x34, &[2]);
    sample::frame(&mut w, f, Flags::Ack, 0x12, 0x34, &(-12.5f32).to_le_bytes());
    // Not an f32: the declared size does not fit.
    sample::frame(&mut w, f, Flags::Request, 0x12, 0x34, &[2]);
    sample::frame(&mut w, f, Flags::Ack, 0x12, 0x34, &[1, 2]);
    sample::frame(&mut w, f, Flags::Request, 0x12, 0x34, &[2]);
    sample::frame(&mut w, f, Flags::Ack, 0x12, 0x34, &f32::NAN.to_le_bytes());
    // A write with a signed value.
    sample::frame(&mut w, f, Flags::Request, 1, 0x02, &(-300i16).to_le_bytes());
    sample::frame(&mut w, f, Flags::Ack, 1, 0x02, &[]);
    let d = |command, direction, ty, scale, unit: &str| Declared {
        command,
        direction,
        ty,
        scale,
        unit: unit.into(),
    };
    let o = Options {
        commands: vec![("distance".into(), 0x10)],
        values: vec![
            d(
                0x10,
                Direction::Both,
                ValueType::U16,
                Scale {
                    mantissa: 1,
                    decimals: 2,
                },
                "m",
            ),
            d(0x34, Direction::Ack, ValueType::F32, Scale::ONE, "deg"),
            d(
                0x02,
                Direction::Both,
                ValueType::I16,
                Scale {
                    mantissa: 1,
                    decimals: 1,
                },
                "mm/s",
            ),
        ],
        ..opts(FramingChoice::Hdlc)
    };
    let (rows, _) = decode(&o, &w);
    let v = values_of(&rows);
    let s = |a: &str, b: &str, c: &str, u: &str| (a.into(), b.into(), c.into(), u.into());
    // A query's empty payload is no mistake.
    assert_eq!(v[0], s("Request", "", "", ""));
    assert!(!col(&rows[0], "Note").contains("--value"));
    assert_eq!(v[1], s("ACK", "distance", "2.91", "m"));
    assert_eq!(rows[1].data, "23 01 (2.91 m)");
    // The request direction of 0x34 is not declared: the default rule.
    assert_eq!(v[2], s("Request", "0x34.req", "2", ""));
    assert_eq!(v[3], s("ACK", "0x34", "-12.5", "deg"));
    assert_eq!(rows[3].data, "00 00 48 C1 (-12.5 deg)");
    assert_eq!(v[5], s("ACK", "", "", ""));
    assert_eq!(rows[5].data, "01 02 (513)");
    assert_eq!(
        col(&rows[5], "Note"),
        "2 payload bytes, --value declares f32 (4): no value"
    );
    assert_eq!(v[7], s("ACK", "", "", ""));
    assert_eq!(col(&rows[7], "Note"), "f32 NaN or infinite: no value");
    assert_eq!(v[8], s("Request", "0x02.req", "-30.0", "mm/s"));
    assert_eq!(rows[8].data, "D4 FE (-30.0 mm/s)");
}

/// Events of one framing fed byte by byte with [`sync::Reassembler::step`] /
/// [`hdlc::Reassembler::step`] (the reference for the slice paths of `push`).
fn stepped(framing: Framing, chunks: &[(&[u8], Option<u64>)]) -> Vec<OwnedEvent> {
    let mut out = Vec::new();
    let mut emit = |e: &frame::Event<'_>| out.push(OwnedEvent::from(e));
    match framing {
        Framing::Sync => {
            let mut r = sync::Reassembler::new();
            for (c, t) in chunks {
                for &b in *c {
                    r.step(b, *t, &mut emit);
                }
            }
            r.finish(&mut emit);
        }
        Framing::Hdlc => {
            let mut r = hdlc::Reassembler::new(hdlc::DEFAULT_MAX_PAYLOAD);
            for (c, t) in chunks {
                for &b in *c {
                    r.step(b, *t, &mut emit);
                }
            }
            r.finish(&mut emit);
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// `push` reads runs and frames in place; its events (times included) are those of
    /// feeding the same bytes one at a time.
    #[test]
    fn slice_push_equals_byte_steps(
        framing in framing(),
        frames in prop::collection::vec(frame_parts(32), 0..10),
        noise in prop::collection::vec(prop::collection::vec(payload_byte(), 0..90), 0..11),
        cuts in prop::collection::vec(any::<usize>(), 0..12),
    ) {
        let (w, _) = encode_all(framing, &frames, &noise);
        let parts: Vec<(&[u8], Option<u64>)> = chunks(&w, &cuts)
            .into_iter()
            .enumerate()
            .map(|(i, c)| (c, (i % 3 != 2).then_some(i as u64 * 7)))
            .collect();
        for f in [Framing::Sync, Framing::Hdlc] {
            let mut pushed = Vec::new();
            let mut r = Reasm::new(f, hdlc::DEFAULT_MAX_PAYLOAD);
            for (c, t) in &parts {
                r.push(c, *t, &mut |e| pushed.push(OwnedEvent::from(e)));
            }
            r.finish(&mut |e| pushed.push(OwnedEvent::from(e)));
            prop_assert_eq!(&pushed, &stepped(f, &parts), "{:?}", f);
        }
    }

    /// SAB v1 candidates that fail, read in place by `push` (a LENGTH above 32, a bad CRC, a
    /// false 0x54 whose span holds a valid frame, a frame whose CRC byte is damaged): the
    /// events are those of the backtracking byte by byte.
    #[test]
    fn sync_failed_candidates_in_place_equal_byte_steps(
        frames in prop::collection::vec((frame_parts(8), any::<bool>()), 1..10),
        prefixes in prop::collection::vec(
            prop::collection::vec(prop_oneof![
                2 => Just(sync::SYNC),
                2 => 0u8..=40,
                1 => any::<u8>(),
            ], 0..6),
            0..11,
        ),
        cuts in prop::collection::vec(any::<usize>(), 0..6),
    ) {
        let mut w = Vec::new();
        for (i, ((h, c, p), damaged)) in frames.iter().enumerate() {
            if let Some(n) = prefixes.get(i) {
                w.extend_from_slice(n);
            }
            sync::encode(&mut w, *h, *c, p);
            if *damaged {
                *w.last_mut().unwrap() ^= 0x01;
            }
        }
        let parts: Vec<(&[u8], Option<u64>)> = chunks(&w, &cuts)
            .into_iter()
            .enumerate()
            .map(|(i, c)| (c, Some(i as u64)))
            .collect();
        let mut pushed = Vec::new();
        let mut r = sync::Reassembler::new();
        for (c, t) in &parts {
            r.push(c, *t, &mut |e| pushed.push(OwnedEvent::from(e)));
        }
        r.finish(&mut |e| pushed.push(OwnedEvent::from(e)));
        prop_assert_eq!(&pushed, &stepped(Framing::Sync, &parts));
    }

    /// The background framing reads blocks ahead of the chosen one; busnoop still switches at
    /// the same byte and writes the same rows as when every byte comes alone (one-byte pushes
    /// are the byte-by-byte order: chosen framing first, then the background one).
    #[test]
    fn shadow_blocks_equal_byte_order(
        first in prop::collection::vec(frame_parts(12), 3..8),
        second in prop::collection::vec(frame_parts(12), 0..12),
        noise in prop::collection::vec(prop::collection::vec(payload_byte(), 0..6), 0..6),
        framing in framing(),
    ) {
        let (mut w, _) = encode_all(framing, &first, &noise);
        let (w2, _) = encode_all(framing.other(), &second, &noise);
        w.extend_from_slice(&w2);
        let (w3, _) = encode_all(framing, &second, &[]);
        w.extend_from_slice(&w3);
        let o = opts(FramingChoice::Auto);
        let whole = decode(&o, &w).0;
        let bytes: Vec<(&[u8], Option<u64>)> = w.chunks(1).map(|c| (c, None)).collect();
        prop_assert_eq!(&decode_chunks(&o, &bytes).0, &whole);
    }
}

#[test]
fn shadow_blocks_switch_at_the_same_byte_in_long_captures() {
    // Longer than a block of the background framing, switching back and forth.
    let mut w = Vec::new();
    for round in 0..6u8 {
        let framing = if round % 2 == 0 {
            Framing::Hdlc
        } else {
            Framing::Sync
        };
        for i in 0..400u32 {
            let p = i.to_le_bytes();
            match framing {
                Framing::Sync => sync::encode(&mut w, 0x05 + round, 0x10, &p),
                Framing::Hdlc => hdlc::encode(&mut w, 0xC5, 0x7E, &p),
            }
        }
    }
    let o = opts(FramingChoice::Auto);
    let whole = decode(&o, &w).0;
    let bytes: Vec<(&[u8], Option<u64>)> = w.chunks(1).map(|c| (c, None)).collect();
    let (by_byte, d) = decode_chunks(&o, &bytes);
    assert_eq!(by_byte, whole);
    assert!(
        d.counters().framings.len() >= 6,
        "{:?}",
        d.counters().framings
    );
}

/// Rows' stamps never change the table: both framings, named devices and commands, every flag
/// (requests, ACKs, NACKs, reserved), timeouts (requests without an answer), bad CRCs, noise,
/// and the fixture sessions.
#[test]
fn stamps_never_change_the_table() {
    let noise = crate::testing::noise(3_000, 11);
    for framing in [Framing::Sync, Framing::Hdlc] {
        let mut bytes = Vec::new();
        let enc = |out: &mut Vec<u8>, h: u8, c: u8, p: &[u8]| match framing {
            Framing::Sync => sync::encode(out, h, c, p),
            Framing::Hdlc => hdlc::encode(out, h, c, p),
        };
        for i in 0..400usize {
            let addr = (i % 7) as u8;
            let cmd = [0x03, 0x10, 0x11, 0x34][i % 4];
            let payload = &noise[i..i + (i % 5)];
            let flags = [Flags::Request, Flags::Ack, Flags::Nack, Flags::Reserved][(i / 4) % 4];
            enc(
                &mut bytes,
                header::header(Flags::Request, addr),
                cmd,
                payload,
            );
            if i % 9 != 0 {
                enc(
                    &mut bytes,
                    header::header(flags, addr),
                    cmd,
                    &payload[..payload.len().min(1)],
                );
            }
            if i % 37 == 0 {
                let at = bytes.len() - 2;
                bytes[at] ^= 0x21;
                bytes.extend_from_slice(&noise[i..i + 9]);
            }
        }
        let mut o = opts(choice(framing));
        o.devices = vec![("arm".into(), 1), ("gripper".into(), 2)];
        o.commands = vec![("distance".into(), 0x10)];
        let chunks: Vec<&[u8]> = bytes.chunks(61).collect();
        let n = crate::testing::assert_stamps_hold(&mut SabDecoder::new(o), &chunks);
        assert!(n > 600, "{framing:?}: {n} rows with a stamp");
    }
    for f in ["fixtures/sab1-session.bin", "fixtures/sab2-session.bin"] {
        let bytes = std::fs::read(f).unwrap();
        let chunks: Vec<&[u8]> = bytes.chunks(17).collect();
        let n =
            crate::testing::assert_stamps_hold(&mut SabDecoder::new(Options::default()), &chunks);
        assert!(n > 0, "{f}");
    }
}
