//! Unit tests of the data-mode framer: events out for bytes in.

use super::super::testing::{Ev, T, bytewise, feed};
use super::*;
use crate::row::GARBAGE_ROW_MAX;
use crate::sbus::telegram::{encode_data, encode_secure};
use crate::sbus::tests::{SMode, session};

fn run(bytes: &[u8]) -> (usize, Vec<Ev>) {
    feed(&mut DataFramer::new(None), &[(bytes.to_vec(), None)])
}

fn data(at: u8, payload: &[u8], basis: CrcBasis) -> Vec<u8> {
    let mut v = Vec::new();
    encode_data(&mut v, at, payload, basis);
    v
}

fn request(body: &[u8]) -> T {
    T::Request {
        station: body[0],
        cmd: body[1],
        body: body[2..].to_vec(),
    }
}

#[test]
fn request_response_and_ack_end_by_their_length() {
    // station 1 reads 4 registers from R0 (16 data bytes), then a write is ACKed
    let req = data(AT_REQUEST, &[1, 6, 3, 0, 0], CrcBasis::Both);
    let resp_data: Vec<u8> = (1..=16).collect();
    let resp = data(AT_RESPONSE, &resp_data, CrcBasis::Both);
    let ack = data(AT_ACKNAK, &[0, 0], CrcBasis::Both);
    let wire = [req.clone(), resp.clone(), ack.clone()].concat();
    let (before, evs) = run(&wire);
    // every telegram is complete when its last byte arrives: nothing waits for the end
    assert_eq!(before, 3, "{evs:?}");
    assert_eq!(evs.len(), 3, "{evs:?}");
    assert_eq!(evs[0].tele(), Some(&request(&[1, 6, 3, 0, 0])));
    assert_eq!(evs[0].wire(), req);
    assert_eq!(evs[0].offset(), 0);
    assert_eq!(
        evs[1].tele(),
        Some(&T::Response {
            data: resp_data.clone()
        })
    );
    assert_eq!(evs[1].offset(), req.len() as u64);
    assert_eq!(
        evs[2].tele(),
        Some(&T::AckNak {
            code: 0,
            short: None
        })
    );
    assert_eq!(evs[2].wire(), ack);
    for e in &evs {
        assert_eq!(e.crc(), CrcCheck::Ok(CrcBasis::Both));
        assert!(matches!(e, Ev::Frame { problem: None, .. }), "{e:?}");
    }
}

#[test]
fn secure_telegram_keeps_its_header() {
    let mut wire = Vec::new();
    encode_secure(
        &mut wire,
        0x10,
        2,
        AT_REQUEST,
        &[5, 6, 0, 0, 0],
        CrcBasis::Both,
    );
    let (before, evs) = run(&wire);
    assert_eq!((before, evs.len()), (1, 1), "{evs:?}");
    assert_eq!(evs[0].tele(), Some(&request(&[5, 6, 0, 0, 0])));
    assert_eq!(evs[0].wire(), wire);
    let Ev::Frame { secure, .. } = &evs[0] else {
        panic!("{evs:?}")
    };
    let s = secure.expect("secure header");
    assert_eq!((s.at, s.len, s.seq, s.actual), (0x10, 9, 2, 9));
    assert!(s.len_ok());
}

#[test]
fn dle_pairs_are_undone_and_both_crc_readings_are_accepted() {
    // read R181: the address 0x00B5 travels as C5 00; the answer holds B5 and C5 as data
    for basis in [CrcBasis::Escaped, CrcBasis::Unescaped] {
        let req = data(AT_REQUEST, &[5, 6, 0, 0, FS], basis);
        assert!(req.windows(2).any(|w| w == [DLE, 0x00]), "{req:02X?}");
        let resp = data(AT_RESPONSE, &[FS, DLE, 0, 1], basis);
        let (before, evs) = run(&[req.clone(), resp.clone()].concat());
        assert_eq!((before, evs.len()), (2, 2), "{basis:?} {evs:?}");
        assert_eq!(evs[0].tele(), Some(&request(&[5, 6, 0, 0, FS])));
        assert_eq!(evs[0].wire(), req, "the wire keeps the DLE pairs");
        assert_eq!(evs[0].crc(), CrcCheck::Ok(basis));
        assert_eq!(
            evs[1].tele(),
            Some(&T::Response {
                data: vec![FS, DLE, 0, 1]
            })
        );
        assert_eq!(evs[1].crc(), CrcCheck::Ok(basis));
    }
}

#[test]
fn a_dle_pair_only_in_the_crc_leaves_both_readings_equal() {
    // Both CRC readings are worked out in one pass when no DLE pair precedes the CRC; a
    // pair inside the CRC field itself must not change that.
    let mut seen = 0;
    for x in 0..=255u8 {
        let payload = [1, 6, 3, 0, x];
        let mut logical = vec![FS, AT_REQUEST];
        logical.extend_from_slice(&payload);
        let crc = crc16(&logical).to_be_bytes();
        if payload.contains(&FS) || payload.contains(&DLE) {
            continue;
        }
        if !crc.contains(&FS) && !crc.contains(&DLE) {
            continue;
        }
        seen += 1;
        let wire = data(AT_REQUEST, &payload, CrcBasis::Both);
        assert!(wire.len() > logical.len() + 2, "{wire:02X?}");
        let (before, evs) = run(&[wire.clone(), wire.clone()].concat());
        assert_eq!((before, evs.len()), (2, 2), "{evs:?}");
        for e in &evs {
            assert_eq!(e.tele(), Some(&request(&payload)));
            assert_eq!(e.wire(), wire);
            assert_eq!(e.crc(), CrcCheck::Ok(CrcBasis::Both), "{x:02X}");
        }
    }
    assert!(seen > 0);
}

#[test]
fn a_length_known_from_the_body_ends_the_telegram_at_its_crc() {
    // write 2 registers: the count byte tells the length; the telegram ends at its CRC,
    // byte by byte or at once, and a wrong CRC keeps it open until the next B5
    let req = data(
        AT_REQUEST,
        &[3, 0x0E, 9, 0, 7, 1, 2, 3, 4, 5, 6, 7, 8],
        CrcBasis::Both,
    );
    let single: Vec<(Vec<u8>, Option<u64>)> = req.iter().map(|&b| (vec![b], None)).collect();
    for segments in [vec![(req.clone(), None)], single] {
        let mut evs = Vec::new();
        let mut f = DataFramer::new(None);
        for (bytes, t) in &segments {
            f.push(bytes, *t, &mut |e| evs.push(Ev::of(e)));
        }
        assert_eq!(evs.len(), 1, "{evs:?}");
        assert_eq!(evs[0].wire(), req);
        assert_eq!(evs[0].crc(), CrcCheck::Ok(CrcBasis::Both));
    }
    let mut bad = req.clone();
    *bad.last_mut().unwrap() ^= 0x40;
    let (before, evs) = run(&[bad.clone(), vec![0x11, 0x22]].concat());
    assert_eq!((before, evs.len()), (0, 1), "{evs:?}");
    assert_eq!(evs[0].wire().len(), bad.len() + 2);
}

#[test]
fn invalid_dle_pair_is_a_problem() {
    // C5 02 is no DLE pair: the C5 is kept as data and the telegram flagged
    let mut wire = vec![FS, AT_REQUEST, 5, 6, 0, 0, DLE, 0x02];
    let crc = crc16(&wire);
    wire.extend_from_slice(&crc.to_be_bytes());
    let (_, evs) = run(&wire);
    assert_eq!(evs.len(), 1, "{evs:?}");
    let Ev::Frame { problem, tele, .. } = &evs[0] else {
        panic!("{evs:?}")
    };
    assert_eq!(
        *problem,
        Some("invalid DLE pair (C5 not followed by 00 or 01)")
    );
    assert!(
        matches!(
            tele,
            T::Request {
                station: 5,
                cmd: 6,
                ..
            }
        ),
        "{tele:?}"
    );
}

#[test]
fn bad_crc_is_reported_and_the_next_telegram_decodes() {
    let mut bad = data(AT_REQUEST, &[1, 6, 3, 0, 0], CrcBasis::Both);
    let n = bad.len();
    bad[n - 1] ^= 0x01;
    let good = data(AT_REQUEST, &[2, 6, 1, 0, 0x64], CrcBasis::Both);
    let (_, evs) = run(&[bad.clone(), good.clone()].concat());
    assert_eq!(evs.len(), 2, "{evs:?}");
    // the bad telegram ends at the next B5
    assert_eq!(evs[0].wire(), bad);
    assert_eq!(evs[0].tele(), Some(&request(&[1, 6, 3, 0, 0])));
    let want = crc16(&bad[..n - 2]);
    assert_eq!(
        evs[0].crc(),
        CrcCheck::Bad {
            got: want ^ 0x01,
            escaped: want,
            unescaped: want
        }
    );
    assert_eq!(evs[1].tele(), Some(&request(&[2, 6, 1, 0, 0x64])));
    assert_eq!(evs[1].crc(), CrcCheck::Ok(CrcBasis::Both));
    assert_eq!(evs[1].offset(), bad.len() as u64);
}

#[test]
fn truncated_telegram_comes_out_at_finish() {
    let req = data(AT_REQUEST, &[1, 6, 3, 0, 0], CrcBasis::Both);
    // cut inside the header: too short to mean anything
    let (before, evs) = run(&req[..2]);
    assert_eq!(before, 0, "an open telegram waits for more bytes");
    assert_eq!(evs.len(), 1, "{evs:?}");
    assert!(
        matches!(
            &evs[0],
            Ev::Frame {
                tele: T::Broken,
                problem: Some("cut short"),
                crc: CrcCheck::None,
                ..
            }
        ),
        "{evs:?}"
    );
    assert_eq!(evs[0].wire(), &req[..2]);
    // cut inside the CRC: read with the CRC it has, which fails
    let (before, evs) = run(&req[..req.len() - 1]);
    assert_eq!((before, evs.len()), (0, 1), "{evs:?}");
    assert!(matches!(evs[0].crc(), CrcCheck::Bad { .. }), "{evs:?}");
    assert_eq!(evs[0].wire(), &req[..req.len() - 1]);
}

#[test]
fn a_gap_ends_an_open_telegram() {
    let req = data(AT_REQUEST, &[1, 6, 3, 0, 0], CrcBasis::Both);
    let mut f = DataFramer::new(Some(10_000));
    let segments = [
        (req[..4].to_vec(), Some(0)),
        (req[4..].to_vec(), Some(50_000)),
    ];
    let (_, evs) = feed(&mut f, &segments);
    assert_eq!(evs.len(), 2, "{evs:?}");
    assert_eq!(evs[0].wire(), &req[..4]);
    assert!(
        matches!(
            evs[1],
            Ev::Garbage {
                time: Some(50_000),
                offset: 4,
                ..
            }
        ),
        "{evs:?}"
    );
}

#[test]
fn garbage_before_a_telegram_then_resync() {
    let noise: Vec<u8> = (0..GARBAGE_ROW_MAX as u8 + 6)
        .map(|i| i.wrapping_mul(7))
        .collect();
    assert!(!noise.contains(&FS));
    let req = data(AT_REQUEST, &[1, 6, 3, 0, 0], CrcBasis::Both);
    let (_, evs) = run(&[noise.clone(), req.clone()].concat());
    // garbage in runs of at most GARBAGE_ROW_MAX bytes, then the telegram
    assert_eq!(evs.len(), 3, "{evs:?}");
    assert!(matches!(&evs[0], Ev::Garbage { offset: 0, .. }));
    assert_eq!(evs[0].wire(), &noise[..GARBAGE_ROW_MAX]);
    assert!(matches!(&evs[1], Ev::Garbage { .. }));
    assert_eq!(evs[1].offset(), GARBAGE_ROW_MAX as u64);
    assert_eq!(evs[1].wire(), &noise[GARBAGE_ROW_MAX..]);
    assert_eq!(evs[2].tele(), Some(&request(&[1, 6, 3, 0, 0])));
    assert_eq!(evs[2].offset(), noise.len() as u64);
}

#[test]
fn byte_by_byte_gives_the_same_events_as_whole_segments() {
    for mode in [SMode::Data, SMode::Secure] {
        for (timed, seed) in [(true, 3), (false, 4)] {
            let g = session(mode, timed, seed, 25);
            let gap = timed.then_some(20_000);
            let (_, whole) = feed(&mut DataFramer::new(gap), &g.segments);
            let (_, single) = feed(&mut DataFramer::new(gap), &bytewise(&g.segments));
            assert!(whole.len() > 25, "{mode:?}: {} events", whole.len());
            assert_eq!(whole, single, "{mode:?} timed {timed}");
            // and all in one push (times dropped)
            if !timed {
                let all: Vec<u8> = g.segments.iter().flat_map(|s| s.0.clone()).collect();
                assert_eq!(run(&all).1, whole, "{mode:?} in one push");
            }
        }
    }
}

#[test]
fn whole_telegrams_read_as_byte_by_byte() {
    // The fast path (`whole_telegram`) against the byte-by-byte path (one byte per push,
    // where it never applies): sessions of both modes, then with bytes flipped, dropped
    // and inserted (B5, C5, a DLE pair's second byte, anything), fed whole and in random
    // chunks.
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = |n: u64| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x % n
    };
    let mut fast_taken = 0;
    for seed in 0..40 {
        let mode = if seed % 4 == 3 {
            SMode::Secure
        } else {
            SMode::Data
        };
        let g = session(mode, false, seed, 30);
        let mut all: Vec<u8> = g.segments.iter().flat_map(|s| s.0.clone()).collect();
        let clean = seed % 5 == 0;
        if !clean {
            for _ in 0..1 + rnd(12) {
                let at = rnd(all.len() as u64 + 1) as usize;
                let b = [FS, DLE, 0x00, 0x01, 0x02, rnd(256) as u8][rnd(6) as usize];
                match rnd(3) {
                    0 if at < all.len() => all[at] = b,
                    1 if at < all.len() => {
                        all.remove(at);
                    }
                    _ => all.insert(at, b),
                }
            }
        }
        // a telegram near the longest kept: a response of 1000 data bytes to nothing
        if seed % 7 == 6 {
            all.extend(data(AT_RESPONSE, &[0x33; 1000], CrcBasis::Both));
        }
        let (_, slow) = run_segments(&bytewise(&[(all.clone(), None)]));
        let (_, whole) = run(&all);
        assert_eq!(whole, slow, "seed {seed}");
        let mut chunks = Vec::new();
        let mut at = 0;
        while at < all.len() {
            let n = (1 + rnd(40) as usize).min(all.len() - at);
            chunks.push((all[at..at + n].to_vec(), None));
            at += n;
        }
        assert_eq!(run_segments(&chunks).1, slow, "seed {seed}, chunked");
        fast_taken += slow.iter().filter(|e| e.crc().ok()).count();
    }
    assert!(fast_taken > 500, "{fast_taken}");
}

fn run_segments(segments: &[(Vec<u8>, Option<u64>)]) -> (usize, Vec<Ev>) {
    feed(&mut DataFramer::new(None), segments)
}

#[test]
fn every_raw_b5_starts_a_new_telegram() {
    // In data mode a raw B5 is only ever a frame start (B5 and C5 inside a telegram travel as
    // DLE pairs), so no telegram can hold a bare B5 after its FS. The break-mode request of
    // station B5 with its many raw B5 bytes is, read as data mode, 17 frames, none valid:
    // the bad CRCs and cut telegrams are reported, and every byte is in exactly one of them.
    let wire = crate::selfcheck::tests::STATION_B5_REQUEST;
    let (_, evs) = run(&wire);
    let starts = wire.iter().filter(|&&b| b == FS).count();
    assert_eq!(evs.len(), starts, "{evs:?}");
    let mut at = 0;
    for e in &evs {
        assert!(matches!(e, Ev::Frame { .. }), "{e:?}");
        assert_eq!(e.offset(), at as u64, "{e:?}");
        assert_eq!(e.wire()[0], FS, "{e:?}");
        assert!(!e.wire()[1..].contains(&FS), "a bare B5 inside {e:?}");
        assert!(!e.crc().ok(), "{e:?}");
        at += e.wire().len();
    }
    assert_eq!(at, wire.len());
}

#[test]
fn the_eight_byte_scan_finds_the_first_b5_or_c5() {
    // each byte value at each place, among bytes next to B5 and C5, one or two marked
    for at in 0..8usize {
        for b in 0..=255u8 {
            for second in [None, Some((at + 3) % 8), Some((at + 1) % 8)] {
                let mut v = [0xB4u8; 8];
                v[at] = b;
                v[(at + 1) % 8] = 0xC6;
                if let Some(s) = second {
                    v[s] = [FS, DLE][s % 2];
                }
                let want = v.iter().position(|&x| x == FS || x == DLE).unwrap_or(8);
                assert_eq!(plain_prefix(u64::from_le_bytes(v)), want, "{v:02X?}");
            }
        }
    }
}

#[test]
fn the_crc_field_is_found_behind_dle_pairs() {
    // wire bytes after the FS, and where the CRC field starts
    let cases: [(&[u8], usize); 6] = [
        (&[1, 2, 3, 4], 2),
        (&[1, 2, DLE, 0, 4], 2),
        (&[1, 2, 3, DLE, 1], 2),
        (&[1, 2, DLE, 0, DLE, 1], 2),
        (&[1, DLE, 1, DLE, 0, DLE, 1], 3),
        (&[DLE, 0, 1, 2], 2),
    ];
    for (wire, want) in cases {
        assert_eq!(crc_field_at(wire, wire.len()), want, "{wire:02X?}");
    }
}
