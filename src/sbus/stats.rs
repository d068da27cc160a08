//! S-Bus counters (per station or PLC, and for the whole input), the `--stats` report and the
//! problems line.

use super::pairing::{CONVERSATION_IDLE, MAX_CONVERSATIONS, MAX_OUTSTANDING};
use crate::fmt::push_fixed;
use crate::stats::{Column, Problems, Report};

/// Ether-S-Bus PLCs with their own `--stats` row; the rest share one row (`other PLCs (N)`).
pub const MAX_PLCS: usize = 256;

/// NAK reasons counted separately: codes 1-4, the single NAK character, other codes.
const NAK_SLOTS: usize = 6;

pub(super) fn nak_slot(code: u16, short: bool) -> usize {
    if short {
        return 4;
    }
    match code {
        1..=4 => code as usize - 1,
        _ => 5,
    }
}

const NAK_LABELS: [&str; NAK_SLOTS] = [
    "0x0001 no reason",
    "0x0002 password",
    "0x0003 PGU port reduced",
    "0x0004 PGU port used",
    "NAK character",
    "other code",
];

/// Counters per station (serial) or per PLC (Ether-S-Bus).
#[derive(Clone, Debug, Default)]
pub struct StationStats {
    pub requests: u64,
    pub broadcasts: u64,
    pub responses: u64,
    pub acks: u64,
    pub naks: [u64; NAK_SLOTS],
    pub retries: u64,
    pub timeouts: u64,
    pub crc_errors: u64,
    pub late: u64,
    pub mismatched: u64,
    pub seq_gaps: u64,
    pub seq_missing: u64,
    /// Response times in µs (bounded: exact up to a cap, then a histogram).
    pub times: crate::summary::Times,
}

impl StationStats {
    pub(super) fn seen(&self) -> bool {
        self.requests + self.responses + self.acks + self.nak_total() + self.crc_errors > 0
    }

    pub fn nak_total(&self) -> u64 {
        self.naks.iter().sum()
    }

    /// (min, median, max) response time in µs; the median is the upper one for an even count
    /// and `false` when it comes from the histogram (three significant digits).
    pub fn response_times(&self) -> Option<(u64, (u64, bool), u64)> {
        let median = self.times.median_upper()?;
        Some((self.times.min, median, self.times.max))
    }
}

/// Counters for the whole capture.
#[derive(Clone, Debug, Default)]
pub struct Totals {
    pub valid: u64,
    pub crc_errors: u64,
    pub broken: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    pub timeouts: u64,
    pub retries: u64,
    pub naks: u64,
    pub no_request: u64,
    pub mismatched: u64,
    pub late: u64,
    /// CRC basis counts for data-mode telegrams: escaped, unescaped, both.
    pub basis: [u64; 3],
    /// Ether-S-Bus: packets read, UDP datagrams on the port, fragments skipped, packets that
    /// did not parse, other link types.
    pub packets: u64,
    pub datagrams: u64,
    pub fragments: u64,
    pub malformed: u64,
    pub not_sbus: u64,
    pub other_links: u64,
    pub seq_gaps: u64,
    /// Requests still waiting for an answer when the input ended.
    pub unanswered_at_end: u64,
    /// Ether-S-Bus conversations seen, forgotten after a minute without a packet, dropped at
    /// the cap (`MAX_CONVERSATIONS`); requests given up at `MAX_OUTSTANDING`; PLCs beyond
    /// [`MAX_PLCS`] counted in one row.
    pub conversations: u64,
    pub conversations_expired: u64,
    pub conversations_dropped: u64,
    pub requests_dropped: u64,
    pub plcs_merged: u64,
    /// The capture container itself is broken (message).
    pub pcap_error: Option<String>,
}

fn ms_text(us: u64) -> String {
    let mut s = String::new();
    push_fixed(&mut s, (us.min(i64::MAX as u64 - 50) as i64 + 50) / 100, 1);
    s
}

/// The `--stats` report: `head` (mode and timeout), a row per station or PLC (`(ID, Device,
/// counters)`), the totals. `ether` adds the sequence columns and lines of Ether-S-Bus.
pub(super) fn report<'a>(
    head: String,
    rows: impl Iterator<Item = (String, &'a str, &'a StationStats)>,
    t: &Totals,
    ether: bool,
) -> Report {
    let mut columns = vec![
        Column::right("ID", 4),
        Column::left("Device", 22).gap(2),
        Column::right("Requests", 8),
        Column::right("Response", 8),
        Column::right("ACK", 6),
        Column::right("NAK", 6),
        Column::right("Retry", 6),
        Column::right("Timeout", 7),
        Column::right("BadCRC", 6),
        Column::right("Late", 5),
    ];
    if ether {
        columns.push(Column::right("SeqGap", 6));
    }
    columns.extend([
        Column::right("Min ms", 8),
        Column::right("Med ms", 8),
        Column::right("Max ms", 8),
    ]);
    let mut r = Report::new(&columns);
    r.head.push(head);
    r.head.push(
        "Min/Med/Max ms: response time, request to answer; Late: answers after the timeout".into(),
    );
    for (id, name, st) in rows {
        let mut cells = vec![id, name.to_owned()];
        cells.extend(
            [
                st.requests,
                st.responses,
                st.acks,
                st.nak_total(),
                st.retries,
                st.timeouts,
                st.crc_errors,
                st.late,
            ]
            .map(|n| n.to_string()),
        );
        if ether {
            cells.push(st.seq_gaps.to_string());
        }
        match st.response_times() {
            Some((a, (m, exact), b)) => {
                let m = if exact {
                    ms_text(m)
                } else {
                    format!("~{}", ms_text(m))
                };
                cells.extend([ms_text(a), m, ms_text(b)]);
            }
            None => cells.extend(["-", "-", "-"].map(String::from)),
        }
        r.row(cells);
        if st.nak_total() > 0 {
            let mut parts = Vec::new();
            for (i, &n) in st.naks.iter().enumerate() {
                if n > 0 {
                    parts.push(format!("{} ×{n}", NAK_LABELS[i]));
                }
            }
            r.detail(format!("NAK reasons: {}", parts.join(", ")));
        }
        if st.mismatched > 0 || st.broadcasts > 0 || st.seq_missing > 0 {
            r.detail(format!(
                "length mismatches {}, broadcasts {}, sequence numbers skipped {}",
                st.mismatched, st.broadcasts, st.seq_missing
            ));
        }
    }
    r.totals.push(format!(
        "valid telegrams {}, CRC errors {}, cut/broken {}, garbage {}, \
         retries {}, timeouts {}, NAKs {}, answers without request {}, length mismatches {}, late {}, \
         unanswered at the end {}",
        t.valid,
        t.crc_errors,
        t.broken,
        crate::stats::garbage(t.garbage_bytes, t.garbage_runs),
        t.retries,
        t.timeouts,
        t.naks,
        t.no_request,
        t.mismatched,
        t.late,
        t.unanswered_at_end
    ));
    r.counts(&[
        ("valid_telegrams", t.valid),
        ("crc_errors", t.crc_errors),
        ("cut_telegrams", t.broken),
        ("garbage_bytes", t.garbage_bytes),
        ("garbage_runs", t.garbage_runs),
        ("retries", t.retries),
        ("timeouts", t.timeouts),
        ("naks", t.naks),
        ("answers_without_request", t.no_request),
        ("length_mismatches", t.mismatched),
        ("late", t.late),
        ("unanswered_at_end", t.unanswered_at_end),
    ]);
    if ether {
        r.totals.push(format!(
            "packets {}, S-Bus datagrams {}, not S-Bus on the port {}, IP fragments skipped {}, \
             unparsable packets {}, other link types {}, sequence gaps {}",
            t.packets, t.datagrams, t.not_sbus, t.fragments, t.malformed, t.other_links, t.seq_gaps
        ));
        r.counts(&[
            ("packets", t.packets),
            ("sbus_datagrams", t.datagrams),
            ("not_sbus_datagrams", t.not_sbus),
            ("ip_fragments_skipped", t.fragments),
            ("unparsable_packets", t.malformed),
            ("other_link_types", t.other_links),
            ("sequence_gaps", t.seq_gaps),
        ]);
        r.totals.push(format!(
            "conversations {}, forgotten after {} s idle {}, dropped at the cap of {} {}, \
             requests given up at the cap of {} {}, PLCs beyond {} counted together {}",
            t.conversations,
            CONVERSATION_IDLE / 1_000_000,
            t.conversations_expired,
            MAX_CONVERSATIONS,
            t.conversations_dropped,
            MAX_OUTSTANDING,
            t.requests_dropped,
            MAX_PLCS,
            t.plcs_merged
        ));
        r.counts(&[
            ("conversations", t.conversations),
            ("conversations_expired", t.conversations_expired),
            ("conversations_dropped", t.conversations_dropped),
            ("requests_given_up", t.requests_dropped),
            ("plcs_merged", t.plcs_merged),
        ]);
    } else {
        r.totals.push(format!(
            "CRC basis of data-mode telegrams: escaped {}, unescaped {}, both (no DLE pair) {}",
            t.basis[0], t.basis[1], t.basis[2]
        ));
        r.counts(&[
            ("crc_basis_escaped", t.basis[0]),
            ("crc_basis_unescaped", t.basis[1]),
            ("crc_basis_both", t.basis[2]),
        ]);
    }
    if let Some(e) = &t.pcap_error {
        r.totals.push(format!("capture error: {e}"));
    }
    r
}

/// What went wrong, for the one-line summary.
pub(super) fn problems(t: &Totals) -> Problems {
    let mut p = Problems::new("S-Bus");
    p.count("crc_errors", t.crc_errors, "CRC error", "CRC errors")
        .count("cut_telegrams", t.broken, "cut telegram", "cut telegrams")
        .garbage(t.garbage_bytes, t.garbage_runs)
        .count("timeouts", t.timeouts, "timeout", "timeouts")
        .count("retries", t.retries, "retry", "retries")
        .count("naks", t.naks, "NAK", "NAKs")
        .count_then(
            "conversations_dropped",
            t.conversations_dropped,
            "conversation",
            "conversations",
            &format!(" dropped (more than {MAX_CONVERSATIONS} at once)"),
        )
        .count_then(
            "requests_given_up",
            t.requests_dropped,
            "request",
            "requests",
            &format!(" given up (more than {MAX_OUTSTANDING} waiting)"),
        )
        .count(
            "not_sbus_datagrams",
            t.not_sbus,
            "datagram on the port that is not S-Bus",
            "datagrams on the port that are not S-Bus",
        )
        .count(
            "ip_fragments_skipped",
            t.fragments,
            "IP fragment skipped",
            "IP fragments skipped",
        )
        .count(
            "unparsable_packets",
            t.malformed,
            "unparsable packet",
            "unparsable packets",
        )
        .count(
            "other_link_types_skipped",
            t.other_links,
            "packet of a link type that is not network traffic skipped",
            "packets of a link type that is not network traffic skipped",
        );
    if let Some(e) = &t.pcap_error {
        p.item(format!("capture error: {e}"));
    }
    p.in_valid(t.valid, "valid telegram", "valid telegrams");
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_lines() {
        let mut st = StationStats {
            requests: 3,
            responses: 2,
            broadcasts: 1,
            ..StationStats::default()
        };
        st.naks[nak_slot(2, false)] = 1;
        st.times.add(12_340);
        let t = Totals {
            valid: 6,
            ..Totals::default()
        };
        let r = report(
            "data mode".into(),
            [("5".into(), "PCD", &st)].into_iter(),
            &t,
            false,
        );
        let text = r.to_string();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "data mode");
        assert!(lines[1].starts_with("Min/Med/Max ms: response time"));
        assert_eq!(
            lines[2],
            "  ID  Device                 Requests Response    ACK    NAK  Retry Timeout BadCRC  Late   Min ms   Med ms   Max ms"
        );
        assert_eq!(
            lines[3],
            "   5  PCD                           3        2      0      1      0       0      0     0     12.3     12.3     12.3"
        );
        assert_eq!(lines[4], "      NAK reasons: 0x0002 password ×1");
        assert_eq!(
            lines[5],
            "      length mismatches 0, broadcasts 1, sequence numbers skipped 0"
        );
        assert!(lines[6].starts_with("valid telegrams 6, "));
        assert!(lines[7].starts_with("CRC basis of data-mode telegrams"));
        assert_eq!(lines.len(), 8);
        assert!(
            report("e".into(), std::iter::empty(), &t, true)
                .to_string()
                .contains(" SeqGap ")
        );
    }

    #[test]
    fn problems_line() {
        let mut t = Totals {
            valid: 1,
            ..Totals::default()
        };
        assert_eq!(problems(&t).line(), None);
        t.crc_errors = 1;
        t.requests_dropped = 2;
        t.pcap_error = Some("cut".into());
        assert_eq!(
            problems(&t).line().unwrap(),
            "S-Bus: 1 CRC error, 2 requests given up (more than 65536 waiting), capture error: cut \
             in 1 valid telegram"
        );
    }
}
