//! Unit tests of the break/parity-mode framer: events out for bytes in.

use super::super::testing::{Ev, T, bytewise, feed};
use super::*;
use crate::sbus::telegram::{CrcBasis, encode_break_request, encode_break_response};
use crate::sbus::tests::{SMode, session};

/// SM0 without times.
fn run(bytes: &[u8]) -> Vec<Ev> {
    feed(
        &mut BreakFramer::new(false, None, None),
        &[(bytes.to_vec(), None)],
    )
    .1
}

/// A break character and a request.
fn request(station: u8, cmd: u8, body: &[u8]) -> Vec<u8> {
    let mut v = vec![0x00];
    encode_break_request(&mut v, station, cmd, body);
    v
}

fn response(data: &[u8]) -> Vec<u8> {
    let mut v = Vec::new();
    encode_break_response(&mut v, data);
    v
}

fn is_request(e: &Ev, station: u8, cmd: u8, body: &[u8]) -> bool {
    e.tele()
        == Some(&T::Request {
            station,
            cmd,
            body: body.to_vec(),
        })
}

#[test]
fn request_response_and_ack_character() {
    // station 2: read R10 (answered with 4 bytes), write O10 = 1 (answered with ACK 06)
    let read = request(2, 6, &[0, 0, 0x0A]);
    let resp = response(&[0x12, 0x34, 0x56, 0x78]);
    let write = request(2, 0x0D, &[3, 0, 0x0A, 0, 1]);
    assert_eq!(
        write[1..],
        [2, 0x0D, 3, 0, 0x0A, 0, 1, 0x17, 0x92],
        "RACOM's seed"
    );
    let wire = [read.clone(), resp.clone(), write.clone(), vec![ACK_CHAR]].concat();
    let evs = run(&wire);
    assert_eq!(evs.len(), 4, "{evs:?}");
    assert!(is_request(&evs[0], 2, 6, &[0, 0, 0x0A]), "{evs:?}");
    assert_eq!(
        evs[0].wire(),
        read,
        "the break character belongs to the request"
    );
    assert!(matches!(
        evs[0],
        Ev::Frame {
            break_before: true,
            ..
        }
    ));
    assert_eq!(
        evs[1].tele(),
        Some(&T::Response {
            data: vec![0x12, 0x34, 0x56, 0x78]
        })
    );
    assert_eq!(evs[1].offset(), read.len() as u64);
    assert!(is_request(&evs[2], 2, 0x0D, &[3, 0, 0x0A, 0, 1]), "{evs:?}");
    assert_eq!(
        evs[3].tele(),
        Some(&T::AckNak {
            code: 0,
            short: Some((ACK_CHAR, false))
        })
    );
    for e in &evs[..3] {
        assert_eq!(e.crc(), CrcCheck::Ok(CrcBasis::Both), "{e:?}");
    }
    assert_eq!(evs[3].crc(), CrcCheck::None);
}

#[test]
fn parity_mode_has_no_break_characters() {
    let mut wire = Vec::new();
    encode_break_request(&mut wire, 2, 6, &[0, 0, 0x0A]);
    encode_break_response(&mut wire, &[0x12, 0x34, 0x56, 0x78]);
    let (_, evs) = feed(&mut BreakFramer::new(true, None, None), &[(wire, None)]);
    assert_eq!(evs.len(), 2, "{evs:?}");
    assert!(is_request(&evs[0], 2, 6, &[0, 0, 0x0A]), "{evs:?}");
    assert!(matches!(
        evs[0],
        Ev::Frame {
            break_before: false,
            ..
        }
    ));
    assert!(matches!(evs[1].tele(), Some(T::Response { .. })), "{evs:?}");
}

#[test]
fn fs_and_dle_bytes_travel_raw() {
    // no DLE escaping in break mode: B5 and C5 are plain data bytes
    let read = request(5, 6, &[0, 0, 0xB5]);
    let resp = response(&[0xB5, 0xC5, 0x01, 0x02]);
    let evs = run(&[read.clone(), resp.clone()].concat());
    assert_eq!(evs.len(), 2, "{evs:?}");
    assert!(is_request(&evs[0], 5, 6, &[0, 0, 0xB5]), "{evs:?}");
    assert_eq!(evs[0].wire().len(), 1 + 2 + 3 + 2);
    assert_eq!(
        evs[1].tele(),
        Some(&T::Response {
            data: vec![0xB5, 0xC5, 0x01, 0x02]
        })
    );
    assert_eq!(evs[1].wire(), resp);
}

#[test]
fn bad_crc_request_is_reported_before_the_next_request() {
    let mut bad = request(2, 6, &[0, 0, 0x0A]);
    let n = bad.len();
    bad[n - 1] ^= 0x40;
    let good = request(3, 6, &[0, 0, 0x0B]);
    let evs = run(&[bad.clone(), good.clone()].concat());
    assert_eq!(evs.len(), 2, "{evs:?}");
    assert!(is_request(&evs[0], 2, 6, &[0, 0, 0x0A]), "{evs:?}");
    assert_eq!(evs[0].wire(), bad);
    assert!(matches!(evs[0].crc(), CrcCheck::Bad { .. }), "{evs:?}");
    assert!(is_request(&evs[1], 3, 6, &[0, 0, 0x0B]), "{evs:?}");
    assert_eq!(evs[1].crc(), CrcCheck::Ok(CrcBasis::Both));
}

#[test]
fn truncated_request_becomes_garbage_at_finish() {
    let read = request(2, 6, &[0, 0, 0x0A]);
    let cut = &read[..5];
    let (before, evs) = feed(
        &mut BreakFramer::new(false, None, None),
        &[(cut.to_vec(), None)],
    );
    assert_eq!(before, 0, "the framer waits for the rest of the request");
    // without framing bytes a cut request cannot be told from noise
    assert_eq!(evs.len(), 1, "{evs:?}");
    assert!(matches!(&evs[0], Ev::Garbage { offset: 0, .. }), "{evs:?}");
    assert_eq!(evs[0].wire(), cut);
}

#[test]
fn garbage_then_resync_at_a_request() {
    let noise = vec![0xFF, 0xEE, 0xDD, 0xB5, 0xC5];
    let read = request(2, 6, &[0, 0, 0x0A]);
    let resp = response(&[0x12, 0x34, 0x56, 0x78]);
    let evs = run(&[noise.clone(), read.clone(), resp].concat());
    assert_eq!(evs.len(), 3, "{evs:?}");
    assert!(matches!(&evs[0], Ev::Garbage { offset: 0, .. }), "{evs:?}");
    assert_eq!(evs[0].wire(), noise);
    assert!(is_request(&evs[1], 2, 6, &[0, 0, 0x0A]), "{evs:?}");
    assert_eq!(evs[1].offset(), noise.len() as u64);
    assert!(matches!(evs[2].tele(), Some(T::Response { .. })), "{evs:?}");
}

#[test]
fn a_gap_ends_what_is_open() {
    // a request cut by a silence longer than the gap: its bytes are garbage, and the
    // request after the silence is read on its own
    let read = request(2, 6, &[0, 0, 0x0A]);
    let segments = [(read[..5].to_vec(), Some(0)), (read.clone(), Some(100_000))];
    let (_, evs) = feed(&mut BreakFramer::new(false, Some(10_000), None), &segments);
    assert_eq!(evs.len(), 2, "{evs:?}");
    assert!(
        matches!(&evs[0], Ev::Garbage { time: Some(0), .. }),
        "{evs:?}"
    );
    assert!(is_request(&evs[1], 2, 6, &[0, 0, 0x0A]), "{evs:?}");
    assert!(matches!(
        evs[1],
        Ev::Frame {
            time: Some(100_000),
            offset: 5,
            ..
        }
    ));
}

#[test]
fn byte_by_byte_gives_the_same_events_as_whole_segments() {
    for (mode, parity) in [(SMode::Break, false), (SMode::Parity, true)] {
        for (timed, seed) in [(true, 5), (false, 6)] {
            let g = session(mode, timed, seed, 25);
            let (gap, timeout) = if timed {
                (Some(20_000), Some(375_000))
            } else {
                (None, None)
            };
            let new = || BreakFramer::new(parity, gap, timeout);
            let (_, whole) = feed(&mut new(), &g.segments);
            let (_, single) = feed(&mut new(), &bytewise(&g.segments));
            assert!(whole.len() > 25, "{mode:?}: {} events", whole.len());
            assert_eq!(whole, single, "{mode:?} timed {timed}");
            if !timed {
                let all: Vec<u8> = g.segments.iter().flat_map(|s| s.0.clone()).collect();
                assert_eq!(run_with(parity, &all), whole, "{mode:?} in one push");
            }
        }
    }
}

fn run_with(parity: bool, bytes: &[u8]) -> Vec<Ev> {
    feed(
        &mut BreakFramer::new(parity, None, None),
        &[(bytes.to_vec(), None)],
    )
    .1
}

#[test]
fn station_b5_with_raw_b5_and_c5_is_one_request() {
    // No FS and no DLE in SM0/SM1: a telegram may start with B5 (station 181) and hold any
    // number of raw B5 and C5 bytes, its CRC included (`B5 C5` here). The selfcheck once read
    // such a row as data mode and took it for a bad CRC accepted
    // (`selfcheck::tests::a_break_mode_telegram_of_station_b5_is_checked_as_break_mode`).
    let wire = crate::selfcheck::tests::STATION_B5_REQUEST;
    for parity in [false, true] {
        let (_, evs) = feed(
            &mut BreakFramer::new(parity, None, None),
            &[(wire.to_vec(), None)],
        );
        assert_eq!(evs.len(), 1, "parity {parity}: {evs:?}");
        assert!(
            is_request(&evs[0], 0xB5, 0xAC, &wire[2..83]),
            "parity {parity}: {evs:?}"
        );
        assert_eq!(evs[0].wire(), wire);
        assert_eq!(evs[0].crc(), CrcCheck::Ok(CrcBasis::Both));
    }
}
