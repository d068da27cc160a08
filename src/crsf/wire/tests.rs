use super::*;
use crate::fmt::{hex, parse_hex};

/// An owned event, for comparing.
#[derive(Debug, PartialEq, Eq)]
pub struct Owned {
    kind: Kind,
    wire: String,
    offset: u64,
    time: Option<u64>,
    false_starts: u32,
}

fn run_chunks(chunks: &[&[u8]]) -> Vec<Owned> {
    let mut r = Reassembler::new(&CRSF_ADDRESSES);
    let mut out = Vec::new();
    let mut keep = |e: &Event<'_>| {
        out.push(Owned {
            kind: e.kind,
            wire: hex(e.wire),
            offset: e.offset,
            time: e.time,
            false_starts: e.false_starts,
        })
    };
    for c in chunks {
        r.push(c, None, &mut keep);
    }
    r.finish(&mut keep);
    out
}

/// Decodes whole, byte by byte and in chunks of 7 and 13; all must agree.
fn events(data: &[u8]) -> Vec<Owned> {
    let whole = run_chunks(&[data]);
    let bytes: Vec<&[u8]> = data.chunks(1).collect();
    assert_eq!(run_chunks(&bytes), whole, "byte by byte");
    for n in [7, 13] {
        let c: Vec<&[u8]> = data.chunks(n).collect();
        assert_eq!(run_chunks(&c), whole, "chunks of {n}");
    }
    whole
}

fn kinds(evs: &[Owned]) -> Vec<(Kind, usize)> {
    evs.iter()
        .map(|e| (e.kind, e.wire.split(' ').count()))
        .collect()
}

fn h(s: &str) -> Vec<u8> {
    parse_hex(s).unwrap()
}

#[test]
fn crc_eight_bytes_a_step_is_the_crc_byte_by_byte() {
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let data: Vec<u8> = (0..200)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    for a in 0..40 {
        for b in a..data.len() {
            let slow = data[a..b].iter().fold(0, |c, &v| CRC_D5[(c ^ v) as usize]);
            assert_eq!(crc8(&data[a..b]), slow, "{a}..{b}");
        }
    }
}

#[test]
fn crc_catalogue_check_values() {
    // CRC-8/DVB-S2's catalogue check value, and the first entries of the TBS tables.
    assert_eq!(crc8(b"123456789"), 0xBC);
    assert_eq!((CRC_D5[1], CRC_D5[2], CRC_D5[255]), (0xD5, 0x7F, 0xF9));
    assert_eq!((CRC_BA[1], CRC_BA[2], CRC_BA[255]), (0xBA, 0xCE, 0x44));
}

#[test]
fn public_vectors_pass_their_crcs() {
    // Betaflight rx_crsf_unittest.cc "capturedData" (two RC frames), the subset frame and
    // the baud-rate negotiation; EdgeTX tests/crossfire.cpp link statistics.
    for f in [
        "00 18 16 BD 08 9F F4 AE F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 6C",
        "00 18 16 BD 08 9F F4 AA F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 94",
        "C8 09 17 24 00 A0 D9 E9 FF 0F D1",
        "C8 0C 32 C8 EC 0A 70 01 00 1E 84 80 22 72",
        "00 0C 14 00 00 00 00 FF 01 03 00 00 00 F4",
    ] {
        let b = h(f);
        let n = b.len();
        assert_eq!(crc8(&b[2..n - 1]), b[n - 1], "{f}");
        let mut again = Vec::new();
        encode(&mut again, b[0], b[2], &b[3..n - 1]);
        assert_eq!(again, b);
    }
    // The command's inner CRC (0xBA) covers type … data: 0x22.
    let cmd = h("C8 0C 32 C8 EC 0A 70 01 00 1E 84 80 22 72");
    assert_eq!(command_crc8(&cmd[2..12]), 0x22);
    let mut again = Vec::new();
    encode_command(
        &mut again,
        0xC8,
        0xC8,
        0xEC,
        0x0A,
        0x70,
        &h("01 00 1E 84 80"),
    );
    assert_eq!(again, cmd);
}

#[test]
fn channels_unpack_as_betaflight_asserts() {
    let f = h("00 18 16 BD 08 9F F4 AE F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 6C");
    let mut ch = [0u16; 16];
    unpack_bits(&f[3..25], 11, 16, &mut ch);
    assert_eq!(&ch[..4], &[189, 993, 978, 983]);
    // TestCrsfFrameStatusUnpacking's hand-packed payload.
    let p = h("FF FF 00 00 58 01 00 F0 01 60 E2 00 00 00 00 00 00 00 00 00 00 00");
    unpack_bits(&p, 11, 16, &mut ch);
    assert_eq!(&ch[..8], &[0x7FF, 0x1F, 0, 172, 0, 992, 0, 1811]);
    assert!(ch[8..].iter().all(|&c| c == 0));
    assert_eq!(pack_bits(&ch, 11), p);
    // Subset frame: 4 channels of 11 bits after the configuration byte.
    let s = h("C8 09 17 24 00 A0 D9 E9 FF 0F D1");
    let mut sub = [0u16; 4];
    unpack_bits(&s[4..10], 11, 4, &mut sub);
    assert_eq!(sub, [0, 820, 1959, 2047]);
}

/// EdgeTX tests/crossfire.cpp frameParser_badFrames: a frame, three random bytes, a frame,
/// the bad-CRC frame `EA 02 00 01`, a frame. EdgeTX asserts the three frames (0x14, 0x21 and
/// 0x1F long) and nothing else; `00 35` is a broadcast candidate of length 53 that the second
/// frame proves false, so it costs one byte.
#[test]
fn edgetx_bad_frames_stream() {
    let f1 = h("EA 14 FF 11 FD 05 00 00 13 01 01 2A 00 00 00 00 00 00 01 5D 98 B4");
    let f2 = h(
        "EA 21 FF 1E FD 12 00 00 14 01 01 4A 00 00 00 00 00 00 00 00 00 00 \
                8F C2 35 3F FD C7 D1 3C 4C 01 92 3F 31",
    );
    let f3 = h(
        "EA 1F FF 1C FD 10 00 00 15 01 01 24 00 00 35 7D F2 40 E8 03 E8 03 DC 05 \
                DC 05 E1 05 E1 05 2A FE 5F",
    );
    let mut s = f1.clone();
    s.extend(h("00 35 A4"));
    s.extend(&f2);
    s.extend(h("EA 02 00 01"));
    s.extend(&f3);
    let ev = events(&s);
    assert_eq!(
        kinds(&ev),
        [
            (Kind::Frame, 0x14 + 2),
            (Kind::Garbage, 3),
            (Kind::Frame, 0x21 + 2),
            (Kind::BadCrc, 4),
            (Kind::Frame, 0x1F + 2),
        ]
    );
    assert_eq!(ev[1].false_starts, 1);
    assert_eq!(ev[2].offset, 25);
    // EdgeTX's Lua FIFO gets len … last payload byte: the third frame's last is 0xFE.
    assert!(ev[4].wire.ends_with("FE 5F"));
}

/// frameParser_incompleteFrames: two frames and the first 7 bytes of a third in one call,
/// the rest of it and the start of a fourth (`EA 0A 0B`) in the next. Three frames; the
/// fourth is held, and cut by the end of the input here.
#[test]
fn edgetx_incomplete_frames_stream() {
    let first = h(
        "EA 14 FF 11 FD 05 00 00 13 01 01 2A 00 00 00 00 00 00 01 5D 98 B4 \
                   EA 21 FF 1E FD 12 00 00 14 01 01 4A 00 00 00 00 00 00 00 00 00 00 \
                   8F C2 35 3F FD C7 D1 3C 4C 01 92 3F 31 \
                   EA 1F FF 1C FD 10 00",
    );
    let cont = h(
        "00 15 01 01 24 00 00 35 7D F2 40 E8 03 E8 03 DC 05 DC 05 E1 05 E1 05 2A \
                  FE 5F EA 0A 0B",
    );
    let ev = run_chunks(&[&first, &cont]);
    assert_eq!(
        kinds(&ev),
        [
            (Kind::Frame, 22),
            (Kind::Frame, 35),
            (Kind::Frame, 33),
            (Kind::Truncated, 3),
        ]
    );
    let mut r = Reassembler::new(&CRSF_ADDRESSES);
    r.push(&first, None, &mut |_| {});
    assert_eq!(
        r.held(),
        7,
        "EdgeTX asserts 7 bytes held after the first call"
    );
    r.push(&cont, None, &mut |_| {});
    assert_eq!(r.held(), 3);
    let mut all = first.clone();
    all.extend(&cont);
    assert_eq!(events(&all), ev);
}

/// frameParser_length: lengths 0xFE and 0x3F (63) are not frames, even when cut; the valid
/// 11-byte frames around them all come out (EdgeTX: three frames of length 9).
#[test]
fn edgetx_length_streams() {
    let f = h("EA 09 FF 11 FD 05 00 00 13 01 8C");
    let mut s = h("2A FE 5F 00");
    s.extend(&f);
    s.extend(h("2A 3F 5F 00"));
    s.extend(&f);
    s.extend(h("2A 3F 5F 00"));
    s.extend(&f);
    let ev = events(&s);
    assert_eq!(
        kinds(&ev),
        [
            (Kind::Garbage, 4),
            (Kind::Frame, 11),
            (Kind::Garbage, 4),
            (Kind::Frame, 11),
            (Kind::Garbage, 4),
            (Kind::Frame, 11),
        ]
    );
    // 0xEA with a length byte of 63 is no candidate either.
    let ev = events(&h("EA 3F 00 00 EA 09 FF 11 FD 05 00 00 13 01 8C"));
    assert_eq!(kinds(&ev), [(Kind::Garbage, 4), (Kind::Frame, 11)]);
}

/// frameParser_multipleJumboFrames: a 64-byte frame split before its CRC, then a 63-byte
/// one: both come out whole.
#[test]
fn edgetx_jumbo_frames() {
    let mut j1 = vec![0xEA, 0x3E, 0xFE];
    j1.extend([0u8; 59]);
    j1.push(0xFB);
    let mut j2 = vec![0x8D, 0xEA, 0x3D, 0xFE];
    j2.extend([0u8; 58]);
    j2.extend([0xF0, 0x57]);
    assert_eq!((j1.len(), j2.len()), (63, 64));
    let ev = run_chunks(&[&j1, &j2]);
    assert_eq!(kinds(&ev), [(Kind::Frame, 64), (Kind::Frame, 63)]);
    assert!(ev[0].wire.ends_with("FB 8D") && ev[1].wire.ends_with("F0 57"));
    let mut r = Reassembler::new(&CRSF_ADDRESSES);
    r.push(&j1, None, &mut |_| {});
    assert_eq!(r.held(), 63);
}

#[test]
fn bad_crc_then_frame_and_truncated_at_the_end() {
    let mut good = Vec::new();
    encode(&mut good, 0xC8, 0x08, &[0, 33, 1, 40, 0, 4, 210, 67]);
    let mut bad = good.clone();
    bad[5] ^= 0x10;
    let mut s = bad.clone();
    s.extend(&good);
    s.extend(&good[..5]);
    let ev = events(&s);
    assert_eq!(
        kinds(&ev),
        [(Kind::BadCrc, 12), (Kind::Frame, 12), (Kind::Truncated, 5)]
    );
    assert_eq!(ev[2].offset, 24);
    // A lone address byte at the end is a truncated frame too.
    assert_eq!(kinds(&events(&[0xC8])), [(Kind::Truncated, 1)]);
}

#[test]
fn corrupt_frame_inside_a_false_candidate_is_still_a_bad_frame() {
    // A false candidate `C8 10` spanning a corrupted frame and the start of a valid one.
    let mut good = Vec::new();
    encode(&mut good, 0xEA, 0x07, &[0x01, 0x02]);
    let mut s = h("C8 10 EE 04 07 01 02 00");
    s.extend(&good);
    let ev = events(&s);
    assert_eq!(
        kinds(&ev),
        [(Kind::Garbage, 2), (Kind::BadCrc, 6), (Kind::Frame, 6)]
    );
}

#[test]
fn garbage_rows_are_bounded_and_keep_every_byte() {
    let noise = crate::testing::noise(5_000, 3);
    let ev = events(&noise);
    let total: usize = ev.iter().map(|e| e.wire.split(' ').count()).sum();
    assert_eq!(total, noise.len());
    assert!(
        ev.iter()
            .all(|e| e.kind != Kind::Garbage || e.wire.split(' ').count() <= GARBAGE_ROW_MAX)
    );
    assert!(ev.iter().any(|e| e.kind == Kind::BadCrc));
    let offsets_grow = ev.windows(2).all(|w| w[0].offset < w[1].offset);
    assert!(offsets_grow);
}

#[test]
fn memory_is_bounded() {
    // Back-to-back false candidates of the largest length, and noise.
    let mut r = Reassembler::new(&CRSF_ADDRESSES);
    let mut max = 0;
    for (i, n) in crate::testing::noise(20_000, 9).into_iter().enumerate() {
        let b = match i % 3 {
            0 => 0xC8,
            1 => 62,
            _ => n,
        };
        r.step(b, None, &mut |_| {});
        max = max.max(r.held());
    }
    assert!(max <= CAPACITY, "{max}");
    assert!(
        max > MAX_FRAME,
        "the nested case should be exercised ({max})"
    );
}

#[test]
fn times_are_those_of_the_first_byte() {
    let mut f = Vec::new();
    encode(&mut f, 0xC8, 0x07, &[0x00, 0x10]);
    let mut r = Reassembler::new(&CRSF_ADDRESSES);
    let mut times = Vec::new();
    r.push(&f[..3], Some(100), &mut |e| times.push(e.time));
    r.push(&f[3..], Some(200), &mut |e| times.push(e.time));
    r.push(&f, Some(300), &mut |e| times.push(e.time));
    r.finish(&mut |e| times.push(e.time));
    assert_eq!(times, [Some(100), Some(300)]);
}
