//! Property tests for the CRSF and GHST decoders: chunking never changes the output (whole,
//! byte by byte, random splits, timed segments), every byte is in exactly one row, the rows are
//! those of the naive reading of the resync rule (`busnoop::selfcheck`), a bad or cut frame
//! never costs the good frame after it, and noise never panics.

mod common;

use busnoop::crsf::wire;
use busnoop::row::OwnedRow;
use common::decode;
use proptest::prelude::*;

/// One item of traffic.
#[derive(Clone, Debug)]
enum Item {
    /// A valid frame: address, type, payload.
    Frame(u8, u8, Vec<u8>),
    /// A frame with its CRC byte changed.
    BadCrc(u8, u8, Vec<u8>, u8),
    /// The first bytes of a frame.
    Cut(u8, u8, Vec<u8>, usize),
    /// Bytes that start no CRSF candidate.
    Noise(Vec<u8>),
    /// Any bytes.
    Raw(Vec<u8>),
}

fn addr() -> impl Strategy<Value = u8> {
    prop_oneof![
        Just(0xC8u8),
        Just(0xEA),
        Just(0xEE),
        Just(0xEC),
        Just(0x00),
        Just(0x82),
        Just(0x89),
        Just(0x80)
    ]
}

fn ty() -> impl Strategy<Value = u8> {
    prop_oneof![
        Just(0x16u8),
        Just(0x14),
        Just(0x08),
        Just(0x02),
        Just(0x1E),
        Just(0x21),
        Just(0x17),
        Just(0x29),
        Just(0x32),
        Just(0x7A),
        Just(0x10),
        Just(0x13),
        Just(0x23),
        Just(0x31),
        any::<u8>()
    ]
}

fn payload() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(any::<u8>(), 0..=60)
}

fn item() -> impl Strategy<Value = Item> {
    let not_start: Vec<u8> = (0..=255u8)
        .filter(|b| !wire::CRSF_ADDRESSES[*b as usize] && !(0x80..=0x89).contains(b))
        .collect();
    prop_oneof![
        8 => (addr(), ty(), payload()).prop_map(|(a, t, p)| Item::Frame(a, t, p)),
        1 => (addr(), ty(), payload(), 1u8..=255).prop_map(|(a, t, p, x)| Item::BadCrc(a, t, p, x)),
        1 => (addr(), ty(), payload(), 1usize..63).prop_map(|(a, t, p, n)| Item::Cut(a, t, p, n)),
        1 => prop::collection::vec(prop::sample::select(not_start), 1..80).prop_map(Item::Noise),
        1 => prop::collection::vec(any::<u8>(), 1..40).prop_map(Item::Raw),
    ]
}

fn encode(item: &Item, out: &mut Vec<u8>) {
    match item {
        Item::Frame(a, t, p) => wire::encode(out, *a, *t, p),
        Item::BadCrc(a, t, p, x) => {
            wire::encode(out, *a, *t, p);
            *out.last_mut().unwrap() ^= x;
        }
        Item::Cut(a, t, p, n) => {
            let mut f = Vec::new();
            wire::encode(&mut f, *a, *t, p);
            out.extend_from_slice(&f[..(*n).min(f.len() - 1)]);
        }
        Item::Noise(b) | Item::Raw(b) => out.extend_from_slice(b),
    }
}

fn split<'a>(bytes: &'a [u8], cuts: &[usize]) -> Vec<&'a [u8]> {
    if bytes.is_empty() {
        return vec![bytes];
    }
    let mut points: Vec<usize> = cuts.iter().map(|c| c % bytes.len()).collect();
    points.extend([0, bytes.len()]);
    points.sort_unstable();
    points.dedup();
    points.windows(2).map(|w| &bytes[w[0]..w[1]]).collect()
}

fn crsf_rows(pieces: &[&[u8]]) -> Vec<OwnedRow> {
    let mut d = busnoop::crsf::decoder(Default::default());
    decode(&mut *d, pieces.iter().map(|p| (*p, None)))
}

fn ghst_rows(pieces: &[&[u8]]) -> Vec<OwnedRow> {
    let mut d = busnoop::ghst::decoder(Default::default());
    decode(&mut *d, pieces.iter().map(|p| (*p, None)))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn chunking_never_changes_the_output(
        items in prop::collection::vec(item(), 0..40),
        cuts in prop::collection::vec(any::<usize>(), 0..40),
    ) {
        let mut bytes = Vec::new();
        for it in &items {
            encode(it, &mut bytes);
        }
        let bytewise: Vec<&[u8]> = bytes.chunks(1).collect();
        for rows in [crsf_rows, ghst_rows] {
            let whole = rows(&[&bytes]);
            prop_assert_eq!(&whole, &rows(&split(&bytes, &cuts)));
            prop_assert_eq!(&whole, &rows(&bytewise));
            let total: usize = whole.iter().map(|r| r.raw.len()).sum();
            prop_assert_eq!(total, bytes.len());
        }
        busnoop::selfcheck::crsf(&bytes);
        busnoop::selfcheck::ghst(&bytes);
    }

    #[test]
    fn chunking_never_changes_timed_output(
        items in prop::collection::vec((item(), 0u64..5_000), 0..30),
        cuts in prop::collection::vec(any::<usize>(), 0..6),
    ) {
        let mut t = 0;
        let mut segments = Vec::new();
        for (it, gap) in &items {
            t += gap;
            let mut b = Vec::new();
            encode(it, &mut b);
            segments.push((b, t));
        }
        let mut d = busnoop::crsf::decoder(Default::default());
        let whole = decode(&mut *d, segments.iter().map(|(b, t)| (b.as_slice(), Some(*t))));
        let mut pieces = Vec::new();
        for (b, t) in &segments {
            for p in split(b, &cuts) {
                pieces.push((p, Some(*t)));
            }
        }
        let mut d = busnoop::crsf::decoder(Default::default());
        prop_assert_eq!(whole, decode(&mut *d, pieces));
    }

    /// A bad frame, a cut frame or noise costs at most its own bytes: the good frame after it
    /// comes out whole (unless the broken bytes happen to make a frame with a passing CRC that
    /// reaches into it, one chance in 256, which the test skips).
    #[test]
    fn a_bad_candidate_never_costs_the_good_frame_after_it(
        bad in item(),
        good in (addr(), ty(), payload()),
    ) {
        let mut bytes = Vec::new();
        encode(&bad, &mut bytes);
        let at = bytes.len();
        wire::encode(&mut bytes, good.0, good.1, &good.2);
        let rows = crsf_rows(&[&bytes]);
        let mut pos = 0;
        let mut found = false;
        let mut swallowed = false;
        for r in &rows {
            if pos == at && r.raw == bytes[at..] {
                found = true;
            }
            if pos < at && pos + r.raw.len() > at && !matches!(r.kind.as_str(), "BadCRC" | "Truncated" | "Garbage") {
                swallowed = true;
            }
            pos += r.raw.len();
        }
        prop_assume!(!swallowed);
        if wire::CRSF_ADDRESSES[good.0 as usize] {
            prop_assert!(found, "{:?}", rows);
        }
    }
}
