use super::*;
use crate::fmt::parse_hex;
use crate::sab::frame::OwnedEvent;

fn events(data: &[u8]) -> Vec<OwnedEvent> {
    let mut r = Reassembler::new();
    let mut out = Vec::new();
    r.push(data, None, &mut |e| out.push(OwnedEvent::from(e)));
    r.finish(&mut |e| out.push(OwnedEvent::from(e)));
    out
}

fn kinds(evs: &[OwnedEvent]) -> Vec<(EventKind, String)> {
    evs.iter()
        .map(|e| (e.kind, crate::fmt::hex(&e.wire)))
        .collect()
}

#[test]
fn crc_catalogue_check_value() {
    assert_eq!(crc8(b"123456789"), 0xA1);
}

/// Four bytes a step gives the `crc` crate's CRC-8/MAXIM-DOW at every length, for bytes of
/// every value.
#[test]
fn crc_steps_equal_the_crate() {
    let crate_crc = crc::Crc::<u8>::new(&crc::CRC_8_MAXIM_DOW);
    let bytes: Vec<u8> = (0..40u32).map(|i| (i * 37 + 11) as u8).collect();
    for len in 0..=bytes.len() {
        for flip in [0u8, 0x55, 0xFF] {
            let b: Vec<u8> = bytes[..len].iter().map(|x| x ^ flip).collect();
            assert_eq!(crc8(&b), crate_crc.checksum(&b), "{len} {flip:#x}");
        }
    }
}

#[test]
fn modm_unit_test_frames() {
    // sab.md §2: modm test/modm/communication/sab/interface_test.cpp.
    let mut out = Vec::new();
    encode(&mut out, 0x12, 0x34, &0xDEAD_BEEFu32.to_le_bytes());
    assert_eq!(out, parse_hex("54 04 12 34 EF BE AD DE EE").unwrap());
    out.clear();
    encode(&mut out, 0xFF, 0x56, &0xBAAAu16.to_le_bytes());
    assert_eq!(out, parse_hex("54 02 FF 56 AA BA 87").unwrap());
    out.clear();
    encode(
        &mut out,
        0x86,
        0x78,
        &parse_hex("FF FF 0C 78 56 34 12").unwrap(),
    );
    assert_eq!(
        out,
        parse_hex("54 07 86 78 FF FF 0C 78 56 34 12 C1").unwrap()
    );
    // SYNC is not covered: including it would give E6 / 75 / E4.
    assert_eq!(crc8(&parse_hex("54 04 12 34 EF BE AD DE").unwrap()), 0xE6);
}

#[test]
fn decodes_a_frame() {
    let ev = events(&parse_hex("54 04 12 34 EF BE AD DE EE").unwrap());
    assert_eq!(ev.len(), 1);
    assert_eq!(ev[0].kind, EventKind::Frame);
    assert_eq!(ev[0].body, parse_hex("12 34 EF BE AD DE").unwrap());
    assert_eq!(ev[0].crc, Some((0xEE, 0xEE)));
    assert_eq!((ev[0].start_pos, ev[0].end_pos), (0, 9));
}

#[test]
fn false_sync_with_plausible_length_does_not_hide_the_frame() {
    // modm would swallow 35 bytes after `54 20` and lose both frames.
    let mut wire = parse_hex("54 20").unwrap();
    encode(&mut wire, 0x05, 0x10, &[]);
    encode(&mut wire, 0xC5, 0x10, &[1, 2]);
    let ev = events(&wire);
    assert_eq!(
        kinds(&ev),
        [
            (EventKind::Garbage, "54 20".into()),
            (EventKind::Frame, "54 00 05 10 62".into()),
            (EventKind::Frame, crate::fmt::hex(&wire[7..])),
        ]
    );
    assert_eq!(ev[0].false_syncs, 1);
}

#[test]
fn stray_sync_right_before_a_frame() {
    let mut wire = vec![SYNC];
    encode(&mut wire, 0x12, 0x34, &0xDEAD_BEEFu32.to_le_bytes());
    let ev = events(&wire);
    assert_eq!(ev.len(), 2);
    assert_eq!(ev[0].kind, EventKind::Garbage);
    assert_eq!(ev[0].wire, [SYNC]);
    assert_eq!(ev[0].bad_lengths, 1);
    assert_eq!(ev[1].kind, EventKind::Frame);
    assert_eq!(ev[1].start_pos, 1);
}

#[test]
fn bad_crc_then_frame() {
    let mut wire = parse_hex("54 00 05 10 63").unwrap();
    encode(&mut wire, 0x85, 0x10, &[0x01]);
    let ev = events(&wire);
    assert_eq!(
        kinds(&ev),
        [
            (EventKind::BadCrc, "54 00 05 10 63".into()),
            (EventKind::Frame, "54 01 85 10 01 6A".into()),
        ]
    );
    assert_eq!(ev[0].crc, Some((0x63, 0x62)));
}

#[test]
fn corrupt_frame_inside_a_false_candidate_is_still_a_bad_frame() {
    // A false `54 10` whose span covers a corrupted frame and the start of a valid one.
    let mut wire = parse_hex("54 10 54 00 05 10 63").unwrap();
    encode(&mut wire, 0x12, 0x34, &0xDEAD_BEEFu32.to_le_bytes());
    let ev = events(&wire);
    assert_eq!(
        kinds(&ev),
        [
            (EventKind::Garbage, "54 10".into()),
            (EventKind::BadCrc, "54 00 05 10 63".into()),
            (EventKind::Frame, "54 04 12 34 EF BE AD DE EE".into()),
        ]
    );
}

#[test]
fn truncated_at_the_end() {
    let ev = events(&parse_hex("54 04 12 34 EF").unwrap());
    assert_eq!(
        kinds(&ev),
        [(EventKind::Truncated, "54 04 12 34 EF".into())]
    );
    assert_eq!(
        kinds(&events(&[SYNC])),
        [(EventKind::Truncated, "54".into())]
    );
    // A frame inside a truncated candidate is still found.
    let mut wire = parse_hex("54 20").unwrap();
    encode(&mut wire, 0x01, 0x02, &[]);
    let ev = events(&wire);
    assert_eq!(ev[0].kind, EventKind::Garbage);
    assert_eq!(ev[1].kind, EventKind::Frame);
}

/// A damaged frame whose wrong LENGTH reaches into the next frame and whose CRC-8 passes
/// there by chance (1 in 256), followed by two good frames: the damaged one is taken for a
/// false 0x54 (garbage), and both good frames come out.
fn swallowing(extra: usize) -> (Vec<u8>, usize, usize) {
    let mut wire = Vec::new();
    encode(&mut wire, 0x05, 0x10, &[1, 2, 3]);
    let first = wire.len();
    let mut payload = vec![0x20, 0x21, 0x22, 0x23, 0x24, 0x25];
    // The damaged frame's LENGTH says 3 + extra: it ends inside the next frame's payload,
    // at payload[extra - 5], whose value is made the CRC-8 it expects.
    wire[1] = 3 + extra as u8;
    let at = extra - 5;
    let mut second = Vec::new();
    encode(&mut second, 0x85, 0x11, &payload);
    let mut probe = wire[1..].to_vec();
    probe.extend_from_slice(&second[..4 + at]);
    payload[at] = crc8(&probe);
    second.clear();
    encode(&mut second, 0x85, 0x11, &payload);
    wire.extend_from_slice(&second);
    let good = wire.len();
    encode(&mut wire, 0x05, 0x12, &[9]);
    (wire, first, good)
}

#[test]
fn a_damaged_frame_that_passes_its_crc_by_chance_does_not_hide_the_next() {
    for extra in 5..11 {
        let (wire, first, good) = swallowing(extra);
        let ev = events(&wire);
        assert_eq!(
            kinds(&ev),
            [
                (EventKind::Garbage, crate::fmt::hex(&wire[..first])),
                (EventKind::Frame, crate::fmt::hex(&wire[first..good])),
                (EventKind::Frame, crate::fmt::hex(&wire[good..])),
            ],
            "extra {extra}"
        );
        assert_eq!(ev[0].false_syncs, 1);
        // The same byte by byte.
        let mut r = Reassembler::new();
        let mut out = Vec::new();
        for &b in &wire {
            r.push(&[b], None, &mut |e| out.push(OwnedEvent::from(e)));
        }
        r.finish(&mut |e| out.push(OwnedEvent::from(e)));
        assert_eq!(kinds(&out), kinds(&ev), "extra {extra}, byte by byte");
    }
}

/// A valid frame whose payload happens to hold a valid frame start that reaches beyond it
/// stays a frame when a valid frame follows it right after its end.
#[test]
fn a_frame_followed_by_a_frame_keeps_a_chance_start_inside_it() {
    // The inner candidate `54 02 ..` starts in the payload and ends in the next frame.
    let mut wire = Vec::new();
    let mut payload = vec![0x11, SYNC, 0x02, 0x33];
    encode(&mut wire, 0x05, 0x10, &payload);
    let mut next = Vec::new();
    encode(&mut next, 0x05, 0x12, &[7, 8, 9]);
    // Make `54 02 33 CRC(..) next[0..3]` check: its CRC byte is next[2].
    for v in 0..=255u8 {
        payload[3] = v;
        wire.clear();
        encode(&mut wire, 0x05, 0x10, &payload);
        let mut inner = vec![0x02, v, wire[wire.len() - 1]];
        inner.extend_from_slice(&next[..2]);
        if crc8(&inner) == next[2] {
            break;
        }
    }
    let first = wire.len();
    wire.extend_from_slice(&next);
    let ev = events(&wire);
    assert_eq!(
        kinds(&ev),
        [
            (EventKind::Frame, crate::fmt::hex(&wire[..first])),
            (EventKind::Frame, crate::fmt::hex(&wire[first..])),
        ]
    );
}

#[test]
fn garbage_rows_are_bounded() {
    let data = vec![0x11; 150];
    let ev = events(&data);
    let lens: Vec<usize> = ev.iter().map(|e| e.wire.len()).collect();
    assert_eq!(lens, [64, 64, 22]);
    assert!(ev.iter().all(|e| e.kind == EventKind::Garbage));
    assert!(ev[0].wire.iter().all(|&b| b == 0x11));
    assert_eq!(ev[2].start_pos, 128);
}

#[test]
fn worst_case_memory() {
    // Back-to-back false candidates of the largest length.
    let mut r = Reassembler::new();
    let mut max = 0;
    for i in 0..10_000u32 {
        let b = if i % 2 == 0 { SYNC } else { 0x20 };
        r.step(b, None, &mut |_| {});
        max = max.max(r.held());
    }
    assert!(max <= CAPACITY, "{max}");
    assert!(
        max > MAX_FRAME,
        "the test should exercise the nested case ({max})"
    );
}
