//! Property tests for the S.Port reassembler and decoder: chunking never changes the output,
//! garbage never panics and never hides a later frame, and every corrupted frame is flagged.

mod common;

use busnoop::row::Class;
use busnoop::row::OwnedRow;
use busnoop::sport::{SportDecoder, wire};
use common::{decode, sport_rows};
use proptest::prelude::*;

/// One item of bus traffic.
#[derive(Clone, Debug)]
enum Item {
    Poll(u8),
    Frame {
        phys: u8,
        kind: u8,
        app_id: u16,
        value: u32,
    },
    /// A frame whose CRC byte is wrong.
    Corrupt {
        phys: u8,
        body: [u8; 8],
    },
    /// Arbitrary bytes (may contain 0x7E and 0x7D).
    Noise(Vec<u8>),
}

fn item() -> impl Strategy<Value = Item> {
    let kinds = prop_oneof![
        Just(0x10u8),
        Just(0x00),
        Just(0x30),
        Just(0x32),
        any::<u8>()
    ];
    // App IDs and values rich in bytes that need stuffing.
    let tricky = prop_oneof![
        Just(0x7Eu8),
        Just(0x7D),
        Just(0x5E),
        Just(0x5D),
        any::<u8>()
    ];
    prop_oneof![
        4 => (0u8..28).prop_map(Item::Poll),
        6 => (0u8..28, kinds, any::<u16>(), prop::array::uniform4(tricky))
            .prop_map(|(phys, kind, app_id, v)| Item::Frame { phys, kind, app_id, value: u32::from_le_bytes(v) }),
        1 => (0u8..28, any::<[u8; 8]>()).prop_filter("CRC must be wrong", |(_, b)| !wire::crc_ok(b))
            .prop_map(|(phys, body)| Item::Corrupt { phys, body }),
        1 => prop::collection::vec(any::<u8>(), 1..40).prop_map(Item::Noise),
    ]
}

fn encode(item: &Item, out: &mut Vec<u8>) {
    match item {
        Item::Poll(p) => wire::encode_poll(out, wire::header_for(*p)),
        Item::Frame {
            phys,
            kind,
            app_id,
            value,
        } => wire::encode_frame(out, wire::header_for(*phys), *kind, *app_id, *value),
        Item::Corrupt { phys, body } => wire::encode_raw(out, wire::header_for(*phys), body),
        Item::Noise(b) => out.extend_from_slice(b),
    }
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

fn is_clean(r: &OwnedRow) -> bool {
    matches!(r.class, Class::Plain | Class::Quiet)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn chunking_never_changes_the_output(
        items in prop::collection::vec(item(), 0..60),
        cuts in prop::collection::vec(any::<usize>(), 0..40),
    ) {
        let mut bytes = Vec::new();
        for it in &items {
            encode(it, &mut bytes);
        }
        let whole = sport_rows(&bytes);
        let mut d = SportDecoder::new();
        let pieces = split(&bytes, &cuts);
        let chunked = decode(&mut d, pieces.iter().map(|p| (*p, None)));
        prop_assert_eq!(whole, chunked);
    }

    #[test]
    fn chunking_never_changes_timed_output(
        items in prop::collection::vec((item(), 0u64..20_000), 0..40),
        cuts in prop::collection::vec(any::<usize>(), 0..8),
    ) {
        // Each item arrives at its own time (as lines of an EdgeTX log do); splitting an item's
        // bytes into several chunks with that time must not change anything.
        let mut t = 0;
        let mut segments: Vec<(Vec<u8>, u64)> = Vec::new();
        for (it, gap) in &items {
            t += gap;
            let mut b = Vec::new();
            encode(it, &mut b);
            segments.push((b, t));
        }
        let mut d = SportDecoder::new();
        let whole = decode(&mut d, segments.iter().map(|(b, t)| (b.as_slice(), Some(*t))));
        let mut d = SportDecoder::new();
        let mut pieces = Vec::new();
        for (b, t) in &segments {
            for p in split(b, &cuts) {
                pieces.push((p, Some(*t)));
            }
        }
        let chunked = decode(&mut d, pieces);
        prop_assert_eq!(whole, chunked);
    }

    #[test]
    fn garbage_never_hides_a_later_frame(
        garbage in prop::collection::vec(any::<u8>(), 0..300),
        frames in prop::collection::vec((0u8..28, any::<u16>(), any::<u32>()), 1..10),
    ) {
        let mut bytes = garbage.clone();
        let mut wires = Vec::new();
        for (phys, app_id, value) in &frames {
            let mut w = Vec::new();
            wire::encode_frame(&mut w, wire::header_for(*phys), 0x10, *app_id, *value);
            bytes.extend_from_slice(&w);
            wires.push(w);
        }
        let rows = sport_rows(&bytes);
        prop_assert!(rows.len() >= frames.len());
        let tail = &rows[rows.len() - frames.len()..];
        for (r, (w, (phys, app_id, _))) in tail.iter().zip(wires.iter().zip(&frames)) {
            prop_assert_eq!(&r.raw, w);
            prop_assert_eq!(r.kind.as_str(), "Data");
            prop_assert_eq!(r.id, Some(*phys as u32));
            prop_assert_eq!(&r.sensor_no, &format!("0x{app_id:04X}"));
            prop_assert!(is_clean(r));
        }
        // Every garbage byte is accounted for: in a row's raw bytes, or the garbage was empty.
        let accounted: usize = rows[..rows.len() - frames.len()].iter().map(|r| r.raw.len()).sum();
        prop_assert_eq!(accounted, garbage.len());
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
        let rows = sport_rows(&bytes);
        // Nothing is lost: every input byte is in exactly one row's raw bytes.
        prop_assert_eq!(rows.iter().map(|r| r.raw.len()).sum::<usize>(), bytes.len());
    }

    #[test]
    fn a_flipped_body_bit_is_a_bad_crc(
        phys in 0u8..28,
        kind in prop_oneof![Just(0x10u8), Just(0x00), Just(0x32)],
        app_id in any::<u16>(),
        value in any::<u32>(),
        bit in 0usize..64,
    ) {
        let mut body = [0u8; 8];
        body[0] = kind;
        body[1..3].copy_from_slice(&app_id.to_le_bytes());
        body[3..7].copy_from_slice(&value.to_le_bytes());
        body[7] = wire::crc(&body[..7]);
        body[bit / 8] ^= 1 << (bit % 8);
        let mut bytes = Vec::new();
        wire::encode_raw(&mut bytes, wire::header_for(phys), &body);
        let rows = sport_rows(&bytes);
        prop_assert_eq!(rows.len(), 1);
        prop_assert_eq!(rows[0].kind.as_str(), "BadCRC");
        prop_assert_eq!(rows[0].class, Class::Error);
    }

    #[test]
    fn a_flipped_wire_bit_is_always_flagged(
        first in (0u8..28, any::<u16>(), any::<u32>()),
        second in (0u8..28, any::<u16>(), any::<u32>()),
        bit in any::<usize>(),
    ) {
        // Two frames; one bit of the second one's wire bytes is flipped, wherever it falls
        // (start byte, header, stuffed body, CRC).
        let mut bytes = Vec::new();
        wire::encode_frame(&mut bytes, wire::header_for(first.0), 0x10, first.1, first.2);
        let split_at = bytes.len();
        wire::encode_frame(&mut bytes, wire::header_for(second.0), 0x10, second.1, second.2);
        let bit = bit % ((bytes.len() - split_at) * 8);
        bytes[split_at + bit / 8] ^= 1 << (bit % 8);
        let rows = sport_rows(&bytes);
        prop_assert!(is_clean(&rows[0]));
        prop_assert_eq!(&rows[0].raw, &bytes[..split_at].to_vec());
        prop_assert!(rows.len() >= 2);
        prop_assert!(
            rows[1..].iter().any(|r| !is_clean(r)),
            "corruption went unnoticed: {:?}", &rows[1..]
        );
    }
}
