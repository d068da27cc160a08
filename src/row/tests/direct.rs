//! Rows written straight into the table ([`crate::row::direct`]) and rows written as
//! [`crate::row::Row`]s give the same table, byte for byte, with the same statistics: every
//! protocol and every way `detect` reads it, over every fixture and fuzz seed, and over the
//! fuzz corpora of the protocols that write rows straight, in every format, with and without
//! `--raw` (`testing::assert_direct_rows_match`).

use std::path::{Path, PathBuf};

use crate::protocol::{Decoder, InputKind, PcapBytes, Probe, Protocol};
use crate::testing::{Boxed, DECODERS_PER_MATCH, assert_direct_rows_match};

fn files(dir: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut out = Vec::new();
    let mut todo = vec![dir];
    while let Some(d) = todo.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The input's kind by its first bytes (as the sources tell them, for what matters here).
fn kind_of(bytes: &[u8]) -> InputKind {
    match bytes.get(..4) {
        Some([0xD4, 0xC3, 0xB2, 0xA1] | [0xA1, 0xB2, 0xC3, 0xD4])
        | Some([0x4D, 0x3C, 0xB2, 0xA1] | [0xA1, 0xB2, 0x3C, 0x4D]) => InputKind::Pcap,
        Some([0x0A, 0x0D, 0x0D, 0x0A]) => InputKind::Pcapng,
        _ => InputKind::Raw,
    }
}

/// Every variant of `protocol` over `file`, in pieces of 113 bytes with times and (`whole`)
/// in one piece without: returns the rows written straight.
fn check(protocol: &Protocol, file: &Path, whole: bool) -> u64 {
    let bytes = std::fs::read(file).unwrap();
    let kind = kind_of(&bytes);
    let probe = Probe {
        input: kind,
        line: protocol.line,
    };
    // A capture the protocol does not read as one itself is read as the sources read a
    // recording: packets of its bytes.
    let packets = kind != InputKind::Raw && !protocol.accepts.contains(&kind);
    let timed: Vec<(&[u8], Option<u64>)> = bytes
        .chunks(113)
        .enumerate()
        .map(|(i, c)| (c, Some(i as u64 * 977)))
        .collect();
    // Every use of `make` needs a fresh decoder, and `variants` builds one of every variant:
    // they are built ahead, one call for all variants, not one call for each decoder used
    // (S-Bus's three serial modes: a third of the building, the most costly part of this test
    // in a debug build). `make` builds one more when the pool runs out.
    let n = (protocol.variants)(&probe).len();
    let mut fresh: Vec<Vec<Box<dyn Decoder>>> = (0..n).map(|_| Vec::new()).collect();
    for _ in 0..DECODERS_PER_MATCH * (1 + usize::from(whole)) {
        for (v, variant) in (protocol.variants)(&probe).into_iter().enumerate() {
            fresh[v].push(variant.decoder);
        }
    }
    let mut direct = 0;
    for (v, pool) in fresh.into_iter().enumerate() {
        let pool = std::cell::RefCell::new(pool);
        let make = || -> Box<dyn Decoder> {
            let d = pool
                .borrow_mut()
                .pop()
                .unwrap_or_else(|| (protocol.variants)(&probe).swap_remove(v).decoder);
            if packets {
                Box::new(PcapBytes::new(Boxed(d)))
            } else {
                d
            }
        };
        let what = format!("{} variant {v} on {}", protocol.name, file.display());
        direct += assert_direct_rows_match(&make, &timed, &what);
        if whole {
            direct += assert_direct_rows_match(&make, &[(&bytes, None)], &what);
        }
    }
    direct
}

#[test]
fn every_protocol_on_the_fixtures_and_seeds() {
    let mut inputs = files("fixtures");
    inputs.extend(files("fuzz/seeds"));
    inputs.retain(|p| p.extension().is_none_or(|x| x != "md"));
    assert!(inputs.len() > 30, "{} inputs", inputs.len());
    for protocol in crate::protocols::PROTOCOLS {
        let direct: u64 = inputs.iter().map(|f| check(protocol, f, true)).sum();
        if matches!(
            protocol.command,
            "sport" | "sbus" | "futaba" | "crsf" | "sab2" | "ibus" | "ghst" | "fport"
        ) {
            assert!(
                direct > 1000,
                "{}: {direct} rows written straight",
                protocol.name
            );
        }
    }
}

/// The fuzz corpora of the protocols that write rows straight, each with its protocol.
#[test]
fn the_fuzz_corpora() {
    let corpora: &[(&str, &Protocol)] = &[
        ("fuzz/corpus/sport", &crate::sport::PROTOCOL),
        ("fuzz/corpus/recording", &crate::sport::PROTOCOL),
        ("fuzz/corpus/sbus_ether", &crate::sbus::PROTOCOL),
        ("fuzz/corpus/sbus_serial", &crate::sbus::PROTOCOL),
        ("fuzz/corpus/futaba", &crate::futaba::PROTOCOL),
        ("fuzz/corpus/crsf", &crate::crsf::PROTOCOL),
        ("fuzz/corpus/sab", &crate::sab::PROTOCOL),
        ("fuzz/corpus/ibus", &crate::ibus::PROTOCOL),
        ("fuzz/corpus/ghst", &crate::ghst::PROTOCOL),
        ("fuzz/corpus/fport", &crate::fport::PROTOCOL),
    ];
    for (dir, protocol) in corpora {
        let direct: u64 = files(dir).iter().map(|f| check(protocol, f, false)).sum();
        assert!(direct > 0, "{dir}: no row written straight");
    }
}
