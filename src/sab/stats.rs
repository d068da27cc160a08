//! Counters for `--stats` and the one-line problem summary.

use std::fmt::Write as _;

use super::detect::Reason;
use super::frame::Framing;
use super::header::{ADDRESSES, NackCode};
use crate::stats::{Column, Problems, Report};

pub use crate::summary::Times;

/// Framing choices listed at most: the first ones and the latest; the others are counted.
pub const MAX_FRAMINGS: usize = 16;

/// Counters of one address.
#[derive(Clone, Debug, Default)]
pub struct AddrStats {
    pub requests: u64,
    pub reserved: u64,
    pub acks: u64,
    pub nacks: u64,
    /// `(code, count)`, sorted by code.
    pub nack_codes: Vec<(u8, u64)>,
    pub timeouts: u64,
    pub late: u64,
    pub unpaired: u64,
    pub repeats: u64,
    pub bad_crc: u64,
    pub times: Times,
}

impl AddrStats {
    fn used(&self) -> bool {
        self.requests + self.reserved + self.acks + self.nacks + self.timeouts + self.bad_crc > 0
    }

    pub fn nack(&mut self, code: u8) {
        self.nacks += 1;
        match self.nack_codes.binary_search_by_key(&code, |e| e.0) {
            Ok(i) => self.nack_codes[i].1 += 1,
            Err(i) => self.nack_codes.insert(i, (code, 1)),
        }
    }
}

/// Everything `--stats` reports.
#[derive(Clone, Debug)]
pub struct Stats {
    pub per: Vec<AddrStats>,
    pub bytes: u64,
    pub valid_frames: u64,
    pub bad_crc: u64,
    pub truncated: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    pub false_syncs: u64,
    pub bad_lengths: u64,
    pub runts: u64,
    pub aborts: u64,
    pub overlong: u64,
    pub odd_escapes: u64,
    pub timeouts: u64,
    pub late: u64,
    pub unpaired: u64,
    pub repeats: u64,
    pub nacks: u64,
    /// The framings chosen, in order (more than one after a switch): at most
    /// [`MAX_FRAMINGS`], the first ones and the latest.
    pub framings: Vec<(Framing, Reason)>,
    /// Choices left out of `framings` (a stream switching back and forth).
    pub framings_omitted: u64,
}

impl Default for Stats {
    fn default() -> Self {
        Stats {
            per: vec![AddrStats::default(); ADDRESSES],
            bytes: 0,
            valid_frames: 0,
            bad_crc: 0,
            truncated: 0,
            garbage_bytes: 0,
            garbage_runs: 0,
            false_syncs: 0,
            bad_lengths: 0,
            runts: 0,
            aborts: 0,
            overlong: 0,
            odd_escapes: 0,
            timeouts: 0,
            late: 0,
            unpaired: 0,
            repeats: 0,
            nacks: 0,
            framings: Vec::new(),
            framings_omitted: 0,
        }
    }
}

impl Stats {
    /// Records a framing choice (the list stays bounded).
    pub fn chose(&mut self, framing: Framing, reason: Reason) {
        if self.framings.len() >= MAX_FRAMINGS {
            self.framings.pop();
            self.framings_omitted += 1;
        }
        self.framings.push((framing, reason));
    }
}

fn ms(micros: u64) -> String {
    let mut s = String::new();
    crate::fmt::push_fixed(&mut s, micros.min(i64::MAX as u64) as i64, 3);
    s
}

impl Stats {
    /// The `--stats` report. `device` names an address (may be empty).
    pub fn report(&self, device: impl Fn(u8) -> String) -> Report {
        let mut r = Report::new(&[
            Column::right("Addr", 4),
            Column::left("Device", 12).gap(2),
            Column::right("Requests", 8),
            Column::right("ACK", 8),
            Column::right("NACK", 6),
            Column::right("Timeouts", 8),
            Column::right("Late", 5),
            Column::right("BadCRC", 6),
            Column::right("Resp min", 9).key("resp_min_ms"),
            Column::right("median", 9).key("resp_median_ms"),
            Column::right("max ms", 9).key("resp_max_ms"),
            Column::left("NACK codes", 0).gap(2),
        ]);
        if self.framings.is_empty() {
            r.head.push("framing: not decided (no input)".into());
        }
        for (i, (framing, reason)) in self.framings.iter().enumerate() {
            if self.framings_omitted > 0 && i + 1 == self.framings.len() {
                r.head
                    .push(format!("… {} more framing switches", self.framings_omitted));
            }
            let mut line = String::new();
            reason.describe(*framing, &mut line);
            r.head.push(line);
        }
        r.head.push(
            "Resp min/median/max ms: response time, request to response; Late: responses after \
             the timeout"
                .into(),
        );
        let counts = |a: &AddrStats| {
            [
                a.requests + a.reserved,
                a.acks,
                a.nacks,
                a.timeouts,
                a.late,
                a.bad_crc,
            ]
            .map(|n| n.to_string())
        };
        let mut total = AddrStats::default();
        for (addr, a) in self.per.iter().enumerate() {
            if !a.used() {
                continue;
            }
            total.requests += a.requests + a.reserved;
            total.acks += a.acks;
            total.nacks += a.nacks;
            total.timeouts += a.timeouts;
            total.late += a.late;
            total.bad_crc += a.bad_crc;
            let (min, median, max) = if a.times.count > 0 {
                (
                    ms(a.times.min),
                    a.times.median().map_or("-".into(), |(m, exact)| {
                        if exact { ms(m) } else { format!("~{}", ms(m)) }
                    }),
                    ms(a.times.max),
                )
            } else {
                ("-".into(), "-".into(), "-".into())
            };
            let mut codes = String::new();
            for &(code, n) in &a.nack_codes {
                if !codes.is_empty() {
                    codes.push_str(", ");
                }
                NackCode::of(code).push_name(&mut codes);
                let _ = write!(codes, " {n}");
            }
            let mut cells = vec![addr.to_string(), device(addr as u8)];
            cells.extend(counts(a));
            cells.extend([min, median, max, codes]);
            r.row(cells);
        }
        let mut cells = vec!["all".to_owned(), String::new()];
        cells.extend(counts(&total));
        r.total_row(cells);
        r.totals.push(format!(
            "bytes {}, valid frames {}, bad CRC {}, truncated {}, garbage {}",
            self.bytes,
            self.valid_frames,
            self.bad_crc,
            self.truncated,
            crate::stats::garbage(self.garbage_bytes, self.garbage_runs)
        ));
        r.totals.push(format!(
            "SAB v1 resync: false 0x54 rescanned {}, 0x54 with LENGTH > 32 {}",
            self.false_syncs, self.bad_lengths
        ));
        r.totals.push(format!(
            "SAB2: runts {}, aborts {}, overlong {}, unusual escapes {}",
            self.runts, self.aborts, self.overlong, self.odd_escapes
        ));
        r.totals.push(format!(
            "pairing: timeouts {}, late responses {}, responses without request {}, repeated responses {}",
            self.timeouts, self.late, self.unpaired, self.repeats
        ));
        r.counts(&[
            ("bytes", self.bytes),
            ("valid_frames", self.valid_frames),
            ("bad_crc", self.bad_crc),
            ("truncated", self.truncated),
            ("garbage_bytes", self.garbage_bytes),
            ("garbage_runs", self.garbage_runs),
            ("false_syncs_rescanned", self.false_syncs),
            ("sync_with_long_length", self.bad_lengths),
            ("runts", self.runts),
            ("aborts", self.aborts),
            ("overlong", self.overlong),
            ("unusual_escapes", self.odd_escapes),
            ("timeouts", self.timeouts),
            ("late_responses", self.late),
            ("responses_without_request", self.unpaired),
            ("repeated_responses", self.repeats),
        ]);
        r
    }

    /// What went wrong (empty when everything decoded cleanly).
    pub fn problems(&self) -> Problems {
        let mut p = Problems::new("SAB");
        if self.valid_frames == 0 && self.bytes > 0 {
            p.item("no valid frame");
        }
        p.count("crc_errors", self.bad_crc, "CRC error", "CRC errors")
            .count(
                "truncated_frames",
                self.truncated,
                "truncated frame",
                "truncated frames",
            )
            .count("timeouts", self.timeouts, "timeout", "timeouts")
            .count(
                "late_responses",
                self.late,
                "late response",
                "late responses",
            )
            .count(
                "responses_without_request",
                self.unpaired,
                "response without request",
                "responses without request",
            )
            .count(
                "repeated_responses",
                self.repeats,
                "repeated response",
                "repeated responses",
            )
            .count("nacks", self.nacks, "NACK", "NACKs")
            .count("runts", self.runts, "runt", "runts")
            .count(
                "aborted_frames",
                self.aborts,
                "aborted frame",
                "aborted frames",
            )
            .count(
                "overlong_frames",
                self.overlong,
                "overlong frame",
                "overlong frames",
            )
            .garbage(self.garbage_bytes, self.garbage_runs)
            .in_valid(self.valid_frames, "valid frame", "valid frames");
        let framing = self
            .framings
            .last()
            .map_or("no framing", |(f, _)| f.protocol());
        p.tail(&format!(" ({framing})"));
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nack_codes_sorted() {
        let mut a = AddrStats::default();
        for c in [3, 1, 3, 0x21] {
            a.nack(c);
        }
        assert_eq!(a.nack_codes, [(1, 1), (3, 2), (0x21, 1)]);
        assert_eq!(a.nacks, 4);
    }

    #[test]
    fn problems_line() {
        let mut s = Stats::default();
        assert_eq!(s.problems().line(), None);
        s.valid_frames = 10;
        s.bytes = 100;
        s.timeouts = 1;
        s.bad_crc = 2;
        s.framings.push((Framing::Hdlc, Reason::Forced));
        assert_eq!(
            s.problems().line().unwrap(),
            "SAB: 2 CRC errors, 1 timeout in 10 valid frames (SAB2)"
        );
    }
}
