//! Property tests of the serial decoder: any split of the bytes into chunks gives the same
//! rows, a damaged telegram costs nothing after the next one, garbage never panics.

use super::*;

/// Splits segments at random points (a chunk never mixes two times).
fn rechunk(segments: &[(Vec<u8>, Option<u64>)], cuts: &[usize]) -> Vec<(Vec<u8>, Option<u64>)> {
    let mut out = Vec::new();
    let mut c = cuts.iter().cycle();
    for (bytes, time) in segments {
        let mut rest = &bytes[..];
        while !rest.is_empty() {
            let n = (*c.next().unwrap_or(&1)).clamp(1, rest.len());
            out.push((rest[..n].to_vec(), *time));
            rest = &rest[n..];
        }
    }
    out
}

fn any_mode() -> impl Strategy<Value = SMode> {
    prop_oneof![
        Just(SMode::Data),
        Just(SMode::Secure),
        Just(SMode::Break),
        Just(SMode::Parity)
    ]
}

/// Session properties run with a fixed seed by default, so that a CI run is repeatable: break
/// and parity modes have rare readings that a CRC cannot tell apart (docs/sbus.md), which a
/// random seed would hit now and then. `PROPTEST_RNG_SEED` and `PROPTEST_CASES` explore more.
fn session_config() -> ProptestConfig {
    let mut c = ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(48),
    );
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        c.rng_seed = proptest::test_runner::RngSeed::Fixed(0x5B05_0004);
    }
    c
}

proptest! {
    #![proptest_config(session_config())]

    #[test]
    fn chunking_does_not_change_rows(
        mode in any_mode(),
        timed in any::<bool>(),
        seed in any::<u64>(),
        cuts in proptest::collection::vec(1usize..40, 1..20),
    ) {
        let g = session(mode, timed, seed, 25);
        let whole: Vec<(Vec<u8>, Option<u64>)> = if timed {
            g.segments.clone()
        } else {
            vec![(g.segments.iter().flat_map(|s| s.0.clone()).collect(), None)]
        };
        let a = run(&mut decoder(mode), &whole);
        let b = run(&mut decoder(mode), &rechunk(&g.segments, &cuts));
        prop_assert_eq!(&a, &b);
        prop_assert_eq!(sigs(&a), g.expect);
        // auto mode too
        let c = run(&mut SerialDecoder::new(Options::default()), &rechunk(&whole, &cuts));
        let d = run(&mut SerialDecoder::new(Options::default()), &whole);
        prop_assert_eq!(c, d);
    }

    #[test]
    fn recovery_at_the_next_telegram(
        mode in any_mode(),
        seed in any::<u64>(),
        garbage in proptest::collection::vec(any::<u8>(), 1..200),
    ) {
        // Data and secure modes recover at the next frame start even without time. Break and
        // parity modes have no frame marker: recovery needs the silence before the telegram.
        let g = session(mode, true, seed, 12);
        let mut segs = vec![(garbage, Some(0))];
        segs.extend(g.segments.iter().map(|(b, t)| (b.clone(), t.map(|t| t + 5_000_000))));
        if matches!(mode, SMode::Data | SMode::Secure) {
            // untimed: one chunk
            let all: Vec<u8> = segs.iter().flat_map(|s| s.0.clone()).collect();
            let rows = run(&mut decoder(mode), &[(all, None)]);
            let got = sigs(&rows);
            prop_assume!(!got.is_empty());
            // every generated row after the garbage, ignoring untimed differences: the
            // late-response case needs time, so compare only when the session has none.
            if !g.expect.iter().any(|s| s.0 == "Timeout") {
                prop_assert!(got.ends_with(&g.expect), "{}", show(&rows));
            }
        }
        let rows = run(&mut decoder(mode), &segs);
        let got = sigs(&rows);
        if !got.ends_with(&g.expect) {
            let off = got.len().saturating_sub(g.expect.len());
            let first = (0..g.expect.len()).find(|&i| got.get(off + i) != Some(&g.expect[i])).unwrap_or(0);
            prop_assert!(false, "expected {:?} at row {}\n{}", &g.expect[first..(first + 3).min(g.expect.len())], off + first, show(&rows[(off + first).saturating_sub(3)..(off + first + 4).min(rows.len())]));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn garbage_never_panics(
        mode in any_mode(),
        data in proptest::collection::vec(any::<u8>(), 0..700),
        cut in 1usize..64,
    ) {
        let segs: Vec<(Vec<u8>, Option<u64>)> =
            data.chunks(cut).enumerate().map(|(i, c)| (c.to_vec(), Some(i as u64 * 7_000))).collect();
        run(&mut decoder(mode), &segs);
        run(&mut SerialDecoder::new(Options::default()), &[(data.clone(), None)]);
        // biased garbage: frame bytes, DLE, ACK/NAK and break characters
        let biased: Vec<u8> = data.iter().map(|b| match b % 6 {
            0 => FS, 1 => DLE, 2 => 0x06, 3 => 0x00, _ => *b }).collect();
        run(&mut decoder(mode), &[(biased.clone(), None)]);
        let mut e = PcapBytes::new(EtherDecoder::new(&Options::default()));
        run(&mut e, &[(data.clone(), None)]);
        // the fuzz targets' invariants: every byte in exactly one row, chunking does not matter
        // (with the self dev-dependency's feature; a published crate's tests go without)
        #[cfg(feature = "selfcheck")]
        {
            crate::selfcheck::sbus_serial(&data);
            crate::selfcheck::sbus_serial(&biased);
            crate::selfcheck::sbus_ether(&data);
        }
    }
}
