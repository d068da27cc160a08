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

mod properties;
mod values;

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

/// Frames of `framing` (random payloads of 0 to 32 bytes, seeded), back to back or with up to
/// 11 random bytes after each (`noise`), damaged at `rate` (a byte flipped, or dropped when
/// `drop`): how many of the frames no damage touched were not found, and how many there were.
fn corruption_sweep(framing: Framing, rate: f64, drop: bool, noise: bool) -> (usize, usize) {
    let mut x = 0x5AB1u64;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let mut wire = Vec::new();
    let mut spans = Vec::new();
    for _ in 0..20_000 {
        let len = (next() % 33) as usize;
        let payload: Vec<u8> = (0..len).map(|_| next() as u8).collect();
        let start = wire.len();
        match framing {
            Framing::Sync => sync::encode(&mut wire, next() as u8 & 0x3F, next() as u8, &payload),
            Framing::Hdlc => hdlc::encode(&mut wire, next() as u8 & 0x3F, next() as u8, &payload),
        }
        spans.push((start, wire.len()));
        if noise {
            for _ in 0..next() % 12 {
                wire.push(next() as u8);
            }
        }
    }
    // Damage, keeping where every input byte went.
    let mut out = Vec::with_capacity(wire.len());
    let mut at = Vec::with_capacity(wire.len() + 1);
    let mut hit = vec![false; wire.len()];
    for (i, &b) in wire.iter().enumerate() {
        let damaged = (next() % 1_000_000) as f64 / 1e6 < rate;
        hit[i] = damaged;
        at.push(out.len());
        if damaged && drop {
            continue;
        }
        out.push(if damaged { b ^ (1 << (next() % 8)) } else { b });
    }
    at.push(out.len());
    let found: std::collections::HashSet<(u64, u64)> = reassemble(framing, 32, &out)
        .iter()
        .filter(|e| e.kind == EventKind::Frame)
        .map(|e| (e.start_pos, e.end_pos))
        .collect();
    let intact: Vec<(usize, usize)> = spans
        .into_iter()
        .filter(|&(s, e)| !hit[s..e].iter().any(|&h| h))
        .collect();
    let lost = intact
        .iter()
        .filter(|&&(s, e)| !found.contains(&(at[s] as u64, at[e] as u64)))
        .count();
    (lost, intact.len())
}

/// Issue 32: SAB2 lost no intact frame up to 5 % flipped or dropped bytes, SAB v1 lost some
/// from 0.1 % / 0.05 % on: a damaged frame whose CRC-8 passed by chance (1 in 256) hid the next
/// frame's 0x54. 20 000 frames back to back and with noise between them: SAB2 loses none at
/// 0.1, 1 and 5 %; SAB v1 at most one in 10 000 intact frames at 0.1 and 1 % (it lost 2 and 9
/// back to back before) and at most one in 400 at 5 % dropped (23 of 7641 before).
#[test]
fn corruption_sweep_loses_next_to_no_intact_frame() {
    for framing in [Framing::Sync, Framing::Hdlc] {
        for noise in [false, true] {
            for rate in [0.001, 0.01, 0.05] {
                for drop in [false, true] {
                    let (lost, intact) = corruption_sweep(framing, rate, drop, noise);
                    let what = format!("{framing:?} rate {rate} drop {drop} noise {noise}");
                    assert!(intact > 5000, "{what}: {intact}");
                    let bound = match (framing, rate) {
                        (Framing::Hdlc, _) => 0,
                        (Framing::Sync, r) if r < 0.02 => intact / 10_000,
                        (Framing::Sync, _) => intact / 400,
                    };
                    assert!(
                        lost <= bound,
                        "{what}: {lost} of {intact} intact frames lost"
                    );
                }
            }
        }
    }
}
