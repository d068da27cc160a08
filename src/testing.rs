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

/// A boxed decoder as a [`crate::protocol::Decoder`] value (to wrap it in
/// [`crate::protocol::PcapBytes`]).
pub(crate) struct Boxed(pub Box<dyn crate::protocol::Decoder>);

impl crate::protocol::Decoder for Boxed {
    fn columns(&self) -> &'static [&'static str] {
        self.0.columns()
    }
    fn push(
        &mut self,
        data: &[u8],
        time: Option<u64>,
        out: &mut dyn crate::row::RowOut,
    ) -> crate::row::RowResult {
        self.0.push(data, time, out)
    }
    fn packet(
        &mut self,
        p: &crate::pcap::Packet<'_>,
        out: &mut dyn crate::row::RowOut,
    ) -> crate::row::RowResult {
        self.0.packet(p, out)
    }
    fn capture_error(
        &mut self,
        e: &crate::pcap::PcapError,
        out: &mut dyn crate::row::RowOut,
    ) -> crate::row::RowResult {
        self.0.capture_error(e, out)
    }
    fn idle(&mut self, now: u64, out: &mut dyn crate::row::RowOut) -> crate::row::RowResult {
        self.0.idle(now, out)
    }
    fn finish(&mut self, out: &mut dyn crate::row::RowOut) -> crate::row::RowResult {
        self.0.finish(out)
    }
    fn valid_frames(&self) -> u64 {
        self.0.valid_frames()
    }
    fn stats(&self) -> crate::stats::Report {
        self.0.stats()
    }
    fn problems(&self) -> crate::stats::Problems {
        self.0.problems()
    }
}

/// The tables [`assert_direct_rows_match`] compares: (format, colour, `--raw`).
const TABLES: [(crate::sink::Format, bool, bool); 10] = {
    use crate::sink::Format::{Csv, Jsonl, Pretty, Tsv};
    [
        (Tsv, false, false),
        (Tsv, false, true),
        (Csv, false, false),
        (Csv, false, true),
        (Jsonl, false, false),
        (Jsonl, false, true),
        (Pretty, false, false),
        (Pretty, false, true),
        (Pretty, true, false),
        (Pretty, true, true),
    ]
};

/// How many decoders [`assert_direct_rows_match`] takes from `make`: one for the columns, one
/// for the rows as `Row`s, one for each table written straight.
pub(crate) const DECODERS_PER_MATCH: usize = 2 + TABLES.len();

/// Decodes `chunks` (bytes with their times) with a decoder from `make` into a table of every
/// format, with and without `--raw`, twice: once as the driver does (the decoder writes the
/// rows it can straight into the table, [`crate::row::Direct`]), once through a stage that
/// lends no `Direct` (every row a [`crate::row::Row`], as behind a filter), and asserts that
/// both tables are byte for byte the same, and so are the decoders' statistics. Returns how
/// many rows went straight into a table (over all of them). The rows as `Row`s are decoded
/// once for all the tables (the decoder's rows do not depend on the table behind a stage that
/// lends no `Direct`); the rows written straight once per table.
pub(crate) fn assert_direct_rows_match(
    make: &dyn Fn() -> Box<dyn crate::protocol::Decoder>,
    chunks: &[(&[u8], Option<u64>)],
    what: &str,
) -> u64 {
    use crate::row::{Direct, Row, RowOut, RowResult};
    use crate::sink::{Format, Table};

    /// Every row as a `Row`, into every table.
    struct RowsOnly<'a>(&'a mut [Table]);
    impl RowOut for RowsOnly<'_> {
        fn row(&mut self, row: &Row<'_>) -> RowResult {
            for t in self.0.iter_mut() {
                t.write(row)?;
            }
            Ok(())
        }
    }
    /// The table itself, counting the rows that come as `Row`s.
    struct Counting<'a>(&'a mut Table, u64);
    impl RowOut for Counting<'_> {
        fn row(&mut self, row: &Row<'_>) -> RowResult {
            self.1 += 1;
            self.0.write(row)
        }
        fn direct(&mut self, columns: &'static [&'static str]) -> Option<Direct<'_>> {
            self.0.direct(columns)
        }
    }
    let decode = |out: &mut dyn RowOut| {
        let mut d = make();
        for &(chunk, time) in chunks {
            d.push(chunk, time, out).unwrap();
        }
        d.finish(out).unwrap();
        (d.stats().to_string(), d.problems().line())
    };
    let columns = make().columns();
    let table = |&(format, color, raw): &(Format, bool, bool)| {
        let opts = crate::sink::TableOptions {
            format,
            color,
            raw,
            time_abs: false,
            utc: false,
        };
        let mut t = Table::new(crate::sink::Output::memory(), opts, columns);
        t.header().unwrap();
        t
    };
    let mut as_rows: Vec<Table> = TABLES.iter().map(table).collect();
    let stats_a = decode(&mut RowsOnly(&mut as_rows));
    let mut direct_rows = 0;
    for (config, a) in TABLES.iter().zip(&mut as_rows) {
        let &(format, color, raw) = config;
        let mut b = table(config);
        let mut counting = Counting(&mut b, 0);
        let stats_b = decode(&mut counting);
        let rows_as_rows = counting.1;
        a.flush().unwrap();
        b.flush().unwrap();
        let (ta, tb) = (a.output().memory_contents(), b.output().memory_contents());
        if ta != tb {
            let (la, lb) = (ta.split(|&c| c == b'\n'), tb.split(|&c| c == b'\n'));
            for (n, (x, y)) in la.zip(lb).enumerate() {
                assert_eq!(
                    String::from_utf8_lossy(x),
                    String::from_utf8_lossy(y),
                    "{what}: {format:?} colour {color} raw {raw}: line {} differs \
                     (left: every row as a Row, right: rows written straight)",
                    n + 1
                );
            }
            assert_eq!(ta.len(), tb.len(), "{what}: {format:?}: lengths differ");
        }
        assert_eq!(stats_a, stats_b, "{what}: the statistics differ");
        assert_eq!(a.rows(), b.rows(), "{what}: row counts");
        assert_eq!(a.frames(), b.frames(), "{what}: frame counts");
        direct_rows += b.rows() - rows_as_rows;
    }
    direct_rows
}
