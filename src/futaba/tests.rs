//! The Futaba decoder as a whole: rows, values, statistics, chunking.

use super::wire::{self, CHANNELS, encode_frame, encode_slot};
use super::*;
use crate::row::{Class, Collected, OwnedRow, kind};
use proptest::prelude::*;

fn rows_of(chunks: &[&[u8]], time: bool) -> (Vec<OwnedRow>, FutabaDecoder) {
    let mut d = FutabaDecoder::new(&Options::default());
    let mut out = Collected::default();
    for (i, c) in chunks.iter().enumerate() {
        d.push(c, time.then_some(i as u64 * 7_000), &mut out)
            .unwrap();
    }
    d.finish(&mut out).unwrap();
    (out.rows, d)
}

fn rows(bytes: &[u8]) -> Vec<OwnedRow> {
    rows_of(&[bytes], false).0
}

fn part<'a>(r: &'a OwnedRow, name: &str) -> &'a str {
    r.parts
        .iter()
        .find(|p| p.0 == name)
        .map(|p| p.2.as_str())
        .unwrap_or_else(|| panic!("no part {name} in {r:?}"))
}

#[test]
fn a_frame_is_one_row_with_channels_in_microseconds_and_flags() {
    let mut ch = [1000u16; CHANNELS];
    ch[0] = 200;
    ch[1] = 1800;
    ch[15] = 173;
    let mut b = Vec::new();
    encode_frame(
        &mut b,
        &ch,
        wire::FLAG_CH18 | wire::FLAG_FRAME_LOST,
        wire::END_SBUS,
    );
    let r = rows(&b);
    assert_eq!(r.len(), 1);
    let r = &r[0];
    assert_eq!(r.kind, "Channels");
    assert_eq!(r.id, None);
    assert_eq!((r.sensor_no.as_str(), r.sensor.as_str()), ("0x00", "SBUS"));
    assert_eq!(r.value(), "1005");
    assert_eq!(part(r, "CH1"), "1005");
    assert_eq!(part(r, "CH2"), "2005");
    assert_eq!(part(r, "CH3"), "1505");
    assert_eq!(part(r, "CH16"), "988");
    assert_eq!(r.parts[0].1, "us");
    assert_eq!(
        (
            part(r, "CH17"),
            part(r, "CH18"),
            part(r, "FrameLost"),
            part(r, "Failsafe")
        ),
        ("0", "1", "1", "0")
    );
    assert_eq!(r.parts.len(), 20);
    assert!(r.data.starts_with("1005 2005 1505 "), "{}", r.data);
    assert!(
        r.extra[1].starts_with("CH17=0 CH18=1 FrameLost=1 Failsafe=0; raw 200 1800 1000"),
        "{}",
        r.extra[1]
    );
    assert_eq!(r.extra[0], "us");
    assert_eq!(r.class, Class::Warning, "frame lost is worth a look");
    assert_eq!(r.raw, b);
}

#[test]
fn sbus2_slots_are_rows_with_the_slot_number_as_id() {
    let ch = [992u16; CHANNELS];
    let mut b = Vec::new();
    encode_frame(&mut b, &ch, 0, 0x04);
    encode_slot(&mut b, 0, 0x8032);
    encode_slot(&mut b, 3, 0x4019);
    encode_frame(&mut b, &ch, wire::FLAG_FAILSAFE, 0x14);
    encode_slot(&mut b, 2, 7); // slot 2 after a frame announcing slots 8-15
    let r = rows(&b);
    let kinds: Vec<&str> = r.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(kinds, ["Channels", "Slot", "Slot", "Channels", "Slot"]);
    assert!(r[0].extra[1].contains("slots 0-7 follow"));
    assert_eq!(
        (r[0].sensor.as_str(), r[0].sensor_no.as_str()),
        ("SBUS2", "0x04")
    );
    let s = &r[1];
    assert_eq!(s.id, Some(0));
    assert_eq!((s.device.as_str(), s.sensor.as_str()), ("Receiver", "RxV"));
    assert_eq!((s.sensor_no.as_str(), s.data.as_str()), ("0x03", "0x8032"));
    assert_eq!(s.parts, [("Slot0".into(), "".into(), "32818".into())]);
    assert_eq!(r[2].id, Some(3));
    assert_eq!(r[2].sensor_no, "0xC3");
    assert_eq!(r[2].device, "Sensor");
    assert_eq!(r[2].value(), "16409");
    assert_eq!(r[3].class, Class::Warning, "failsafe");
    assert_eq!(part(&r[3], "Failsafe"), "1");
    assert_eq!(r[4].class, Class::Warning);
    assert!(
        r[4].extra[1].contains("announcing slots 8-15"),
        "{:?}",
        r[4]
    );
}

#[test]
fn broken_input_is_rows_and_counts() {
    let ch = [1000u16; CHANNELS];
    let mut good = Vec::new();
    encode_frame(&mut good, &ch, 0, 0);
    let mut b = vec![0x12, 0x34];
    b.extend(&good[..12]); // cut
    b.extend(&good);
    let mut wrong = good.clone();
    wrong[24] = 0xA5;
    b.extend(&wrong);
    b.extend(&good);
    b.extend(&good[..7]);
    let (r, d) = rows_of(&[&b], false);
    let kinds: Vec<&str> = r.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(
        kinds,
        [
            kind::GARBAGE,
            kind::TRUNCATED,
            "Channels",
            kind::GARBAGE,
            "Channels",
            kind::TRUNCATED
        ]
    );
    assert!(
        r[3].extra[1].contains("0xA5, not an end byte"),
        "{:?}",
        r[3]
    );
    assert!(
        r.iter()
            .filter(|r| r.kind != "Channels")
            .all(|r| r.class == Class::Error)
    );
    assert!(
        r.iter()
            .filter(|r| r.class == Class::Error)
            .all(|r| r.parts.is_empty())
    );
    let total: usize = r.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, b.len());
    let st = d.counters();
    assert_eq!((st.truncated, st.wrong_end, st.garbage_bytes), (2, 1, 2));
    let line = d.problems().line().unwrap();
    assert_eq!(
        line,
        "Futaba SBUS: 2 truncated frames, 1 frame with a wrong end byte, 2 garbage bytes \
         skipped (1 run) in 2 valid frames"
    );
    let text = d.stats().to_string();
    assert!(text.contains("frames: SBUS 2, SBUS2 0"), "{text}");
}

#[test]
fn times_reconstructed_at_the_line_rate_or_taken_from_the_source() {
    let mut b = Vec::new();
    for _ in 0..3 {
        encode_frame(&mut b, &[1000; CHANNELS], 0, 0);
    }
    // 25 bytes of 12 bits at 100000 baud: 3 ms a frame.
    let millis: Vec<_> = rows(&b).iter().map(|r| r.millis()).collect();
    assert_eq!(millis, [Some(0), Some(3), Some(6)]);
    let chunks: Vec<&[u8]> = b.chunks(25).collect();
    let (r, d) = rows_of(&chunks, true);
    let millis: Vec<_> = r.iter().map(|r| r.millis()).collect();
    assert_eq!(millis, [Some(0), Some(7), Some(14)]);
    assert!(d.stats().to_string().contains("mean 7.0 ms"));
}

#[test]
fn stats_list_the_slots_answered() {
    let mut b = Vec::new();
    encode_frame(&mut b, &[1000; CHANNELS], 0, 0x24);
    encode_slot(&mut b, 16, 0x1234);
    encode_slot(&mut b, 17, 0x00FF);
    let (_, d) = rows_of(&[&b], false);
    let text = d.stats().to_string();
    assert!(text.contains("0x0B"), "{text}");
    assert!(text.contains("0x1234"), "{text}");
    assert_eq!(d.valid_frames(), 3);
    assert!(d.problems().is_empty());
}

/// Random traffic: frames of each kind, slots, noise.
fn traffic() -> impl Strategy<Value = Vec<u8>> {
    let item = prop_oneof![
        (
            prop::array::uniform16(0u16..2048),
            any::<u8>(),
            prop::sample::select(vec![0x00u8, 0x04, 0x14, 0x24, 0x34, 0x08])
        )
            .prop_map(|(ch, flags, end)| {
                let mut v = Vec::new();
                encode_frame(&mut v, &ch, flags, end);
                v
            }),
        (0u8..32, any::<u16>()).prop_map(|(n, value)| {
            let mut v = Vec::new();
            encode_slot(&mut v, n, value);
            v
        }),
        prop::collection::vec(any::<u8>(), 0..40),
        prop::collection::vec(prop::sample::select(vec![0x0Fu8, 0x00, 0x04, 0x03]), 0..30),
    ];
    prop::collection::vec(item, 0..25).prop_map(|v| v.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Whole, byte by byte and in random pieces: the same rows, every byte in exactly one row.
    #[test]
    fn chunking_never_changes_the_rows(bytes in traffic(), cuts in prop::collection::vec(1usize..60, 1..40)) {
        let whole = rows(&bytes);
        let singles: Vec<&[u8]> = bytes.chunks(1).collect();
        prop_assert_eq!(&rows_of(&singles, false).0, &whole);
        let mut pieces = Vec::new();
        let mut rest = &bytes[..];
        let mut i = 0;
        while !rest.is_empty() {
            let n = cuts[i % cuts.len()].min(rest.len());
            pieces.push(&rest[..n]);
            rest = &rest[n..];
            i += 1;
        }
        prop_assert_eq!(&rows_of(&pieces, false).0, &whole);
        let total: usize = whole.iter().map(|r| r.raw.len()).sum();
        prop_assert_eq!(total, bytes.len());
    }

    /// A good frame after any junk is still found.
    #[test]
    fn a_frame_after_junk_is_found(junk in prop::collection::vec(any::<u8>(), 0..80), ch in prop::array::uniform16(0u16..2048)) {
        let mut b = junk.clone();
        let mut f = Vec::new();
        encode_frame(&mut f, &ch, 0, 0);
        b.extend(&f);
        b.extend(&f);
        let r = rows(&b);
        // The last frame's bytes: whatever the junk did to the first copy, the second is a row.
        let last = r.last().unwrap();
        prop_assert_eq!(&last.kind, "Channels");
        prop_assert_eq!(&last.raw, &f);
    }
}
