//! Property tests for the F.Port reassemblers and decoder: chunking never changes the output
//! (whole, byte by byte, random splits, with and without times), any input decodes without a
//! panic with every byte in exactly one row, garbage never hides a later frame, and a flipped
//! bit never goes unnoticed.

mod common;

use busnoop::fport::{self, Options, Variant, wire};
use busnoop::row::{Class, OwnedRow};
use common::decode;
use proptest::prelude::*;

/// One item of F.Port v1 traffic.
#[derive(Clone, Debug)]
enum V1Item {
    Control([u16; 16], u8, u8),
    Poll,
    Downlink([u8; 7]),
    /// An answer: 0 delimited, 1 bare (Betaflight), 2 after a 0xFF pad (ArduPilot).
    Uplink([u8; 7], u8),
    /// A frame with one byte of its body changed (the checksum fails or the length is off).
    Corrupt(usize, u8),
    Noise(Vec<u8>),
}

/// One item of F.Port 2 traffic.
#[derive(Clone, Debug)]
enum V2Item {
    Control(Vec<u16>, u8, u8),
    Telemetry(u8, [u8; 7]),
    Ota(u8, u8),
    Corrupt(usize, u8),
    Cut(usize),
    Noise(Vec<u8>),
}

/// Bytes rich in what needs stuffing or looks like a frame start.
fn tricky() -> impl Strategy<Value = u8> {
    prop_oneof![
        Just(0x7Eu8),
        Just(0x7D),
        Just(0x5E),
        Just(0x08),
        Just(0x18),
        Just(0xFF),
        any::<u8>()
    ]
}

fn payload() -> impl Strategy<Value = [u8; 7]> {
    (
        prop_oneof![
            Just(0x10u8),
            Just(0x00),
            Just(0x30),
            Just(0x32),
            any::<u8>()
        ],
        prop::array::uniform6(tricky()),
    )
        .prop_map(|(k, rest)| {
            let mut p = [k; 7];
            p[1..].copy_from_slice(&rest);
            p
        })
}

fn v1_item() -> impl Strategy<Value = V1Item> {
    prop_oneof![
        3 => (prop::array::uniform16(0u16..2048), any::<u8>(), any::<u8>())
            .prop_map(|(c, f, r)| V1Item::Control(c, f, r)),
        2 => Just(V1Item::Poll),
        1 => payload().prop_map(V1Item::Downlink),
        3 => (payload(), 0u8..3).prop_map(|(p, s)| V1Item::Uplink(p, s)),
        1 => (any::<usize>(), 1u8..=255).prop_map(|(i, x)| V1Item::Corrupt(i, x)),
        1 => prop::collection::vec(any::<u8>(), 1..30).prop_map(V1Item::Noise),
    ]
}

fn v2_item() -> impl Strategy<Value = V2Item> {
    prop_oneof![
        3 => (prop::collection::vec(0u16..2048, 1..25), any::<u8>(), any::<u8>())
            .prop_map(|(c, f, r)| V2Item::Control(c, f, r)),
        4 => ((0u8..28).prop_map(busnoop::sport::wire::header_for), payload())
            .prop_map(|(h, p)| V2Item::Telemetry(h, p)),
        1 => (0u8..3, any::<u8>()).prop_map(|(k, b)| V2Item::Ota(k, b)),
        1 => (any::<usize>(), 1u8..=255).prop_map(|(i, x)| V2Item::Corrupt(i, x)),
        1 => (1usize..26).prop_map(V2Item::Cut),
        1 => prop::collection::vec(any::<u8>(), 1..30).prop_map(V2Item::Noise),
    ]
}

fn encode_v1(item: &V1Item, out: &mut Vec<u8>) {
    match item {
        V1Item::Control(c, f, r) => wire::encode_v1_control(out, c, *f, *r),
        V1Item::Poll => wire::encode_v1_telemetry(out, wire::V1_DOWNLINK, &[0; 7]),
        V1Item::Downlink(p) => wire::encode_v1_telemetry(out, wire::V1_DOWNLINK, p),
        V1Item::Uplink(p, style) => {
            let mut f = Vec::new();
            wire::encode_v1_telemetry(&mut f, wire::V1_UPLINK, p);
            match style {
                0 => out.extend_from_slice(&f),
                1 => out.extend_from_slice(&f[1..f.len() - 1]),
                _ => {
                    out.push(0xFF);
                    out.extend_from_slice(&f[1..f.len() - 1]);
                }
            }
        }
        V1Item::Corrupt(i, x) => {
            let mut f = Vec::new();
            wire::encode_v1_control(&mut f, &[992; 16], 0, 100);
            let i = 1 + i % (f.len() - 2);
            f[i] ^= x;
            out.extend_from_slice(&f);
        }
        V1Item::Noise(b) => out.extend_from_slice(b),
    }
}

fn encode_v2(item: &V2Item, out: &mut Vec<u8>) {
    match item {
        V2Item::Control(c, f, r) => wire::encode_v2_control(out, c, *f, *r),
        V2Item::Telemetry(h, p) => wire::encode_v2_telemetry(out, *h, p),
        V2Item::Ota(k, b) => {
            let kind = wire::OTA_START + k;
            let len = if kind == wire::OTA_DATA { 0x20 } else { 0x18 };
            wire::encode_v2(out, len, kind, &vec![*b; len as usize]);
        }
        V2Item::Corrupt(i, x) => {
            let mut f = Vec::new();
            wire::encode_v2_control(&mut f, &[992; 16], 0, 100);
            let i = i % f.len();
            f[i] ^= x;
            out.extend_from_slice(&f);
        }
        V2Item::Cut(n) => {
            let mut f = Vec::new();
            wire::encode_v2_control(&mut f, &[992; 16], 0, 100);
            out.extend_from_slice(&f[..*n]);
        }
        V2Item::Noise(b) => out.extend_from_slice(b),
    }
}

fn rows(variant: Variant, pieces: &[(&[u8], Option<u64>)]) -> Vec<OwnedRow> {
    let mut d = fport::decoder(Options {
        variant,
        baud: None,
    });
    decode(d.as_mut(), pieces.iter().copied())
}

/// Splits `bytes` at the given cut points (taken modulo the length).
fn split<'a>(bytes: &'a [u8], cuts: &[usize]) -> Vec<&'a [u8]> {
    if bytes.is_empty() {
        return vec![bytes];
    }
    let mut points: Vec<usize> = cuts.iter().map(|c| c % bytes.len()).collect();
    points.push(0);
    points.push(bytes.len());
    points.sort_unstable();
    points.dedup();
    points.windows(2).map(|w| &bytes[w[0]..w[1]]).collect()
}

/// Whole, byte by byte and split at `cuts`: the same rows, every byte in one row.
fn same_however_split(variant: Variant, bytes: &[u8], cuts: &[usize]) -> Result<(), TestCaseError> {
    let whole = rows(variant, &[(bytes, None)]);
    let singles: Vec<(&[u8], Option<u64>)> = bytes.chunks(1).map(|c| (c, None)).collect();
    prop_assert_eq!(&whole, &rows(variant, &singles));
    let pieces: Vec<(&[u8], Option<u64>)> =
        split(bytes, cuts).into_iter().map(|c| (c, None)).collect();
    prop_assert_eq!(&whole, &rows(variant, &pieces));
    let total: usize = whole.iter().map(|r| r.raw.len()).sum();
    prop_assert_eq!(total, bytes.len());
    Ok(())
}

fn is_clean(r: &OwnedRow) -> bool {
    matches!(r.class, Class::Plain | Class::Quiet)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn v1_chunking_never_changes_the_output(
        items in prop::collection::vec(v1_item(), 0..40),
        cuts in prop::collection::vec(any::<usize>(), 0..30),
    ) {
        let mut bytes = Vec::new();
        for it in &items {
            encode_v1(it, &mut bytes);
        }
        for variant in [Variant::V1, Variant::Auto] {
            same_however_split(variant, &bytes, &cuts)?;
        }
    }

    #[test]
    fn v2_chunking_never_changes_the_output(
        items in prop::collection::vec(v2_item(), 0..40),
        cuts in prop::collection::vec(any::<usize>(), 0..30),
    ) {
        let mut bytes = Vec::new();
        for it in &items {
            encode_v2(it, &mut bytes);
        }
        for variant in [Variant::V2, Variant::Auto] {
            same_however_split(variant, &bytes, &cuts)?;
        }
    }

    #[test]
    fn chunking_never_changes_timed_output(
        v1 in prop::collection::vec((v1_item(), 0u64..20_000), 0..25),
        v2 in prop::collection::vec((v2_item(), 0u64..20_000), 0..25),
        cuts in prop::collection::vec(any::<usize>(), 0..8),
    ) {
        // Each item arrives at its own time; splitting an item's bytes into several chunks
        // with that time must not change anything.
        let mut t = 0;
        let mut segments: Vec<(Vec<u8>, u64)> = Vec::new();
        for (it, gap) in &v1 {
            t += gap;
            let mut b = Vec::new();
            encode_v1(it, &mut b);
            segments.push((b, t));
        }
        for (it, gap) in &v2 {
            t += gap;
            let mut b = Vec::new();
            encode_v2(it, &mut b);
            segments.push((b, t));
        }
        let whole: Vec<(&[u8], Option<u64>)> =
            segments.iter().map(|(b, t)| (b.as_slice(), Some(*t))).collect();
        let mut pieces = Vec::new();
        for (b, t) in &segments {
            for p in split(b, &cuts) {
                pieces.push((p, Some(*t)));
            }
        }
        for variant in [Variant::V1, Variant::V2, Variant::Auto] {
            prop_assert_eq!(rows(variant, &whole), rows(variant, &pieces));
        }
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..1500)) {
        for variant in [Variant::V1, Variant::V2, Variant::Fbus, Variant::Auto] {
            let r = rows(variant, &[(&bytes, None)]);
            prop_assert_eq!(r.iter().map(|r| r.raw.len()).sum::<usize>(), bytes.len());
        }
    }

    #[test]
    fn garbage_never_hides_a_later_v1_frame(
        garbage in prop::collection::vec(any::<u8>(), 0..300),
        frames in prop::collection::vec(payload(), 1..8),
    ) {
        let mut bytes = garbage.clone();
        let mut wires = Vec::new();
        for p in &frames {
            let mut w = Vec::new();
            wire::encode_v1_telemetry(&mut w, wire::V1_UPLINK, p);
            bytes.extend_from_slice(&w);
            wires.push(w);
        }
        let mut rows = rows(Variant::V1, &[(&bytes, None)]);
        // When the garbage ends with something read as a frame, the first frame's opening
        // 0x7E closes it: that frame begins without one, does not take the 0x7E after it as
        // its closing one, and so one 0x7E is left alone at the end.
        if rows.last().is_some_and(|r| r.kind == "Garbage" && r.raw == [wire::START]) {
            rows.pop();
        }
        prop_assert!(rows.len() >= frames.len());
        let tail = &rows[rows.len() - frames.len()..];
        for (r, (w, p)) in tail.iter().zip(wires.iter().zip(&frames)) {
            // The frame's own bytes; its opening 0x7E may have closed a frame the garbage
            // happened to end with, or a lone 0x7E the garbage ended with stays with it.
            let lone = [&[wire::START][..], w].concat();
            let n = w.len();
            prop_assert!(
                r.raw == *w || r.raw == w[1..] || r.raw == w[1..n - 1] || r.raw == lone,
                "{:?}",
                r
            );
            prop_assert_eq!(r.id, Some(27));
            prop_assert_eq!(&r.extra[1], "Uplink");
            let kind = busnoop::sport::names::frame_type(p[0]).unwrap_or("Unknown");
            prop_assert_eq!(r.kind.as_str(), kind);
        }
    }

    #[test]
    fn garbage_never_hides_a_later_v2_frame(
        garbage in prop::collection::vec(any::<u8>().prop_filter("no control frame type", |b| *b < 0xF0), 0..300),
        frames in prop::collection::vec((0u8..28, payload()), 1..8),
    ) {
        let mut bytes = garbage.clone();
        let mut wires = Vec::new();
        for (phys, p) in &frames {
            let mut w = Vec::new();
            wire::encode_v2_control(&mut w, &[992; 16], 0, 100);
            wire::encode_v2_telemetry(&mut w, busnoop::sport::wire::header_for(*phys), p);
            bytes.extend_from_slice(&w);
            wires.push(w);
        }
        let rows = rows(Variant::V2, &[(&bytes, None)]);
        prop_assert!(rows.len() >= 2 * frames.len());
        let tail = &rows[rows.len() - 2 * frames.len()..];
        for (pair, (w, (phys, _))) in tail.chunks(2).zip(wires.iter().zip(&frames)) {
            prop_assert_eq!(&pair[0].kind, "Control");
            prop_assert_eq!(&pair[0].raw[..], &w[..27]);
            prop_assert_eq!(&pair[1].raw[..], &w[27..]);
            prop_assert_eq!(&pair[1].extra[1], "Downlink");
            prop_assert_eq!(pair[1].id, Some(*phys as u32));
            prop_assert!(is_clean(&pair[0]));
        }
    }

    #[test]
    fn a_flipped_wire_bit_is_always_flagged(
        v2 in any::<bool>(),
        first in prop::array::uniform16(0u16..2048),
        second in payload(),
        bit in any::<usize>(),
    ) {
        // A control frame, then a telemetry frame with one bit of its wire bytes flipped,
        // wherever it falls (delimiters, length, type, stuffed payload, checksum).
        let mut bytes = Vec::new();
        let variant = if v2 {
            wire::encode_v2_control(&mut bytes, &first, 0, 100);
            Variant::V2
        } else {
            wire::encode_v1_control(&mut bytes, &first, 0, 100);
            Variant::V1
        };
        let split_at = bytes.len();
        if v2 {
            wire::encode_v2_telemetry(&mut bytes, 0x1B, &second);
        } else {
            wire::encode_v1_telemetry(&mut bytes, wire::V1_UPLINK, &second);
        }
        let bit = bit % ((bytes.len() - split_at) * 8);
        bytes[split_at + bit / 8] ^= 1 << (bit % 8);
        let rows = rows(variant, &[(&bytes, None)]);
        prop_assert!(is_clean(&rows[0]) || rows[0].class == Class::Warning);
        prop_assert_eq!(&rows[0].raw[..], &bytes[..split_at]);
        prop_assert!(rows.len() >= 2);
        prop_assert!(
            rows[1..].iter().any(|r| r.class == Class::Error),
            "corruption went unnoticed: {:?}", &rows[1..]
        );
    }
}
