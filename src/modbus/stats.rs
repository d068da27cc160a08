//! Modbus counters per slave and function and for the whole input, the `--stats` report and
//! the problems line.

use super::function;
use crate::fmt::push_fixed;
use crate::stats::{Column, Problems, Report};
use crate::summary::Times;

/// (slave, function) pairs with their own `--stats` row; more share one row.
pub const MAX_ROWS: usize = 512;

/// Counters of one slave and function.
#[derive(Clone, Debug, Default)]
pub struct FunctionStats {
    pub requests: u64,
    pub broadcasts: u64,
    pub responses: u64,
    /// By exception code (index 0: codes above 15).
    pub exceptions: [u64; 16],
    pub retries: u64,
    pub timeouts: u64,
    pub crc_errors: u64,
    pub late: u64,
    /// Response times in µs (bounded: exact up to a cap, then a histogram).
    pub times: Times,
}

impl FunctionStats {
    pub fn exception_total(&self) -> u64 {
        self.exceptions.iter().sum()
    }

    fn valid(&self) -> bool {
        self.requests + self.responses + self.exception_total() > 0
    }
}

/// Counters of the whole input.
#[derive(Clone, Debug, Default)]
pub struct Totals {
    pub valid: u64,
    pub requests: u64,
    pub responses: u64,
    pub exceptions: u64,
    pub crc_errors: u64,
    pub truncated: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    pub timeouts: u64,
    pub retries: u64,
    pub late: u64,
    /// Responses without a waiting request (or for another slave or function).
    pub unpaired: u64,
    /// Frames whose two readings had the same length, told apart by the pairing.
    pub ambiguous: u64,
    /// Requests still waiting for an answer when the input ended.
    pub unanswered_at_end: u64,
    /// CRC errors and cut frames of slave/function pairs never seen in a valid frame (noise
    /// reads as any header).
    pub unattributed: u64,
    /// Pairs beyond `MAX_ROWS` counted in one row.
    pub merged: u64,
}

/// The counters by (slave, function), bounded.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// Each pair's place in `rows` plus one (0: none), by [`slot`]; allocated at the first
    /// pair.
    index: Vec<u16>,
    /// The pairs in the order they were first seen.
    rows: Vec<((u8, u8), FunctionStats)>,
    other: FunctionStats,
}

/// A pair's place in [`Table::index`] (function codes without the exception bit).
fn slot(slave: u8, function: u8) -> usize {
    (slave as usize) << 7 | (function & 0x7F) as usize
}

impl Table {
    /// The counters of a pair seen in a valid frame (created on first use; beyond
    /// [`MAX_ROWS`] pairs, the shared row).
    pub fn valid(&mut self, slave: u8, function: u8, totals: &mut Totals) -> &mut FunctionStats {
        if self.index.is_empty() {
            self.index = vec![0; 256 << 7];
        }
        let at = slot(slave, function);
        match self.index[at] as usize {
            0 if self.rows.len() >= MAX_ROWS => {
                totals.merged += 1;
                &mut self.other
            }
            0 => {
                self.rows
                    .push(((slave, function & 0x7F), FunctionStats::default()));
                self.index[at] = self.rows.len() as u16;
                &mut self.rows.last_mut().expect("just pushed").1
            }
            i => &mut self.rows[i - 1].1,
        }
    }

    fn place(&self, slave: u8, function: u8) -> Option<usize> {
        match self.index.get(slot(slave, function)) {
            Some(&i) if i > 0 => Some(i as usize - 1),
            _ => None,
        }
    }

    /// The counters of a pair if it was seen in a valid frame.
    pub fn seen(&mut self, slave: u8, function: u8) -> Option<&mut FunctionStats> {
        let i = self.place(slave, function)?;
        Some(&mut self.rows[i].1)
    }

    pub fn get(&self, slave: u8, function: u8) -> Option<&FunctionStats> {
        let i = self.place(slave, function)?;
        Some(&self.rows[i].1)
    }
}

fn ms_text(us: u64) -> String {
    let mut s = String::new();
    push_fixed(&mut s, (us.min(i64::MAX as u64 - 50) as i64 + 50) / 100, 1);
    s
}

/// The `--stats` report: `head`, a row per slave and function (`name` gives the Device column),
/// the totals.
pub fn report(head: String, table: &Table, t: &Totals, name: impl Fn(u8) -> String) -> Report {
    let columns = [
        Column::right("ID", 3),
        Column::left("Device", 14).gap(2),
        Column::left("Function", 35).gap(2),
        Column::right("Requests", 8),
        Column::right("Response", 8),
        Column::right("Except", 6),
        Column::right("Retry", 6),
        Column::right("Timeout", 7),
        Column::right("BadCRC", 6),
        Column::right("Late", 5),
        Column::right("Min ms", 8),
        Column::right("Med ms", 8),
        Column::right("Max ms", 8),
    ];
    let mut r = Report::new(&columns);
    r.head.push(head);
    r.head.push(
        "Min/Med/Max ms: response time, request to answer; Late: answers after the timeout; \
         CRC errors counted where the pair was seen in a valid frame"
            .into(),
    );
    let mut sorted: Vec<_> = table.rows.iter().collect();
    sorted.sort_by_key(|(key, _)| *key);
    let rows = sorted
        .into_iter()
        .filter(|(_, st)| st.valid())
        .map(|(key, st)| {
            let (s, f) = *key;
            let mut fun = String::new();
            fun.push_str(crate::fmt::hex_0x(f));
            fun.push(' ');
            fun.push_str(function::name(f));
            (s.to_string(), name(s), fun, st)
        });
    let other = (table.other.valid() || table.other.crc_errors > 0).then(|| {
        (
            "*".to_owned(),
            String::new(),
            format!("other pairs ({})", t.merged),
            &table.other,
        )
    });
    for (id, device, fun, st) in rows.chain(other) {
        let mut cells = vec![id, device, fun];
        cells.extend(
            [
                st.requests,
                st.responses,
                st.exception_total(),
                st.retries,
                st.timeouts,
                st.crc_errors,
                st.late,
            ]
            .map(|n| n.to_string()),
        );
        match st.times.median_upper() {
            Some((m, exact)) => {
                let m = if exact {
                    ms_text(m)
                } else {
                    format!("~{}", ms_text(m))
                };
                cells.extend([ms_text(st.times.min), m, ms_text(st.times.max)]);
            }
            None => cells.extend(["-", "-", "-"].map(String::from)),
        }
        r.row(cells);
        if st.exception_total() > 0 {
            let mut parts = Vec::new();
            for (code, &n) in st.exceptions.iter().enumerate() {
                if n > 0 {
                    let name = match function::exception_name(code as u8) {
                        "" if code == 0 => "other codes".to_owned(),
                        "" => format!("code {code}"),
                        n => format!("{code} {n}"),
                    };
                    parts.push(format!("{name} ×{n}"));
                }
            }
            r.detail(format!("exceptions: {}", parts.join(", ")));
        }
        if st.broadcasts > 0 {
            r.detail(format!("broadcasts {}", st.broadcasts));
        }
    }
    r.totals.push(format!(
        "valid frames {} (requests {}, responses {}, exceptions {}), CRC errors {}, truncated {}, \
         garbage {} bytes in {} runs",
        t.valid,
        t.requests,
        t.responses,
        t.exceptions,
        t.crc_errors,
        t.truncated,
        t.garbage_bytes,
        t.garbage_runs,
    ));
    r.totals.push(format!(
        "retries {}, timeouts {}, late {}, responses without a request {}, told apart by pairing {}, \
         unanswered at the end {}, bad frames of pairs never seen valid {}",
        t.retries,
        t.timeouts,
        t.late,
        t.unpaired,
        t.ambiguous,
        t.unanswered_at_end,
        t.unattributed,
    ));
    r
}

/// What went wrong, for the one-line summary.
pub fn problems(t: &Totals) -> Problems {
    let mut p = Problems::new("Modbus");
    p.count("crc_errors", t.crc_errors, "CRC error", "CRC errors")
        .count("truncated", t.truncated, "cut frame", "cut frames")
        .garbage(t.garbage_bytes, t.garbage_runs)
        .count("timeouts", t.timeouts, "timeout", "timeouts")
        .count("retries", t.retries, "retry", "retries")
        .count("exceptions", t.exceptions, "exception", "exceptions")
        .count(
            "unpaired",
            t.unpaired,
            "response without a request",
            "responses without a request",
        );
    p.in_valid(t.valid, "valid frame", "valid frames");
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_and_problems() {
        let mut t = Totals::default();
        let mut table = Table::default();
        let st = table.valid(1, 3, &mut t);
        st.requests = 3;
        st.responses = 2;
        st.exceptions[2] = 1;
        st.times.add(12_340);
        table.valid(0, 6, &mut t).broadcasts = 1;
        table.valid(0, 6, &mut t).requests = 1;
        table.valid(9, 4, &mut t).crc_errors = 1;
        t.valid = 7;
        let text = report("19200 8E1".into(), &table, &t, |s| {
            if s == 1 {
                "Boiler".into()
            } else {
                String::new()
            }
        })
        .to_string();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "19200 8E1");
        assert!(
            lines[2].starts_with(" ID  Device          Function"),
            "{}",
            lines[2]
        );
        assert!(
            lines[3].starts_with("  0                  0x06 Write Single Register"),
            "{text}"
        );
        assert_eq!(lines[4], "     broadcasts 1");
        assert!(
            lines[5].starts_with("  1  Boiler          0x03 Read Holding Registers"),
            "{text}"
        );
        assert!(lines[5].ends_with("12.3     12.3     12.3"), "{text}");
        assert_eq!(lines[6], "     exceptions: 2 Illegal Data Address ×1");
        assert!(
            !text.contains("0x04"),
            "a pair with only a bad frame has no row"
        );
        assert!(lines[7].starts_with("valid frames 7"));
        assert_eq!(problems(&t).line(), None);
        t.crc_errors = 2;
        t.exceptions = 1;
        assert_eq!(
            problems(&t).line().unwrap(),
            "Modbus: 2 CRC errors, 1 exception in 7 valid frames"
        );
    }

    #[test]
    fn rows_are_bounded() {
        let mut t = Totals::default();
        let mut table = Table::default();
        for s in 0..=247u8 {
            for f in [1u8, 2, 3] {
                table.valid(s, f, &mut t).requests += 1;
            }
        }
        assert_eq!(table.rows.len(), MAX_ROWS);
        assert_eq!(t.merged, 248 * 3 - MAX_ROWS as u64);
        assert!(
            report(String::new(), &table, &t, |_| String::new())
                .to_string()
                .contains("other pairs")
        );
    }
}
