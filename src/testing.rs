//! Helpers shared by the unit tests (the integration tests have their own in `tests/common`).

/// Deterministic pseudo-random bytes (xorshift).
pub(crate) fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect()
}

/// Decodes `chunks` with `decoder` into the table in every format, once with the rows' stamps
/// ([`crate::row::Row::stamp`]) and once with every stamp 0, and asserts that both tables are
/// the same: a decoder's stamps never change its output. (Debug builds also compare each span
/// copied by its stamp with the cells written again, so a stamp that lies fails there first.)
/// Returns how many rows carried a stamp.
pub(crate) fn assert_stamps_hold(
    decoder: &mut dyn crate::protocol::Decoder,
    chunks: &[&[u8]],
) -> usize {
    use crate::row::{Row, RowOut, RowResult};
    use crate::sink::{Format, Table};

    struct Both {
        stamped: Vec<Table>,
        plain: Vec<Table>,
        with_stamp: usize,
    }
    impl RowOut for Both {
        fn row(&mut self, row: &Row<'_>) -> RowResult {
            self.with_stamp += usize::from(row.stamp != 0);
            for t in &mut self.stamped {
                t.write(row)?;
            }
            for t in &mut self.plain {
                t.write(&Row { stamp: 0, ..*row })?;
            }
            Ok(())
        }
    }
    let formats = [
        (Format::Tsv, false),
        (Format::Csv, false),
        (Format::Jsonl, false),
        (Format::Pretty, true),
    ];
    let tables = || {
        formats
            .iter()
            .map(|&(format, color)| memory_table(format, color, decoder.columns()))
            .collect::<Vec<_>>()
    };
    let mut both = Both {
        stamped: tables(),
        plain: tables(),
        with_stamp: 0,
    };
    for (i, chunk) in chunks.iter().enumerate() {
        decoder
            .push(chunk, Some(i as u64 * 1_000), &mut both)
            .unwrap();
    }
    decoder.finish(&mut both).unwrap();
    for ((s, p), (format, _)) in both.stamped.iter_mut().zip(&mut both.plain).zip(formats) {
        s.flush().unwrap();
        p.flush().unwrap();
        assert_eq!(
            String::from_utf8_lossy(s.output().memory_contents()),
            String::from_utf8_lossy(p.output().memory_contents()),
            "{format:?}"
        );
    }
    both.with_stamp
}

/// A table in memory with the Raw column (`--raw`), for the sink's tests.
pub(crate) fn memory_table(
    format: crate::sink::Format,
    color: bool,
    extra: &[&'static str],
) -> crate::sink::Table {
    let opts = crate::sink::TableOptions {
        format,
        color,
        raw: true,
        time_abs: false,
        utc: false,
    };
    crate::sink::Table::new(crate::sink::Output::memory(), opts, extra)
}
