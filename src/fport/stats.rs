//! F.Port statistics: frames per kind, errors, resynchronisations and the telemetry of every
//! physical ID, as a [`Report`] and [`Problems`].

use crate::stats::{Column, Problems, Report};

/// Telemetry counts of one physical ID.
#[derive(Clone, Copy, Debug, Default)]
pub struct PhysStats {
    /// Downlink null frames (polls).
    pub polls: u64,
    /// Downlink frames with a payload (MSP requests, forwarded frames).
    pub requests: u64,
    /// Uplink frames.
    pub answers: u64,
    /// Uplink data frames.
    pub data: u64,
    /// Uplink null frames (nothing to send).
    pub null: u64,
    /// Uplink frames of other types (replies, OTA answers).
    pub other: u64,
}

/// Counters kept while decoding (`--stats`).
#[derive(Clone, Debug, Default)]
pub struct Stats {
    pub per: [PhysStats; 32],
    /// Control frames with channels, by channel count 8, 16, 24.
    pub control: [u64; 3],
    pub frame_lost: u64,
    pub failsafe: u64,
    pub rssi_min: Option<u8>,
    pub rssi_max: Option<u8>,
    /// OTA firmware-update frames (control, downlink and uplink).
    pub ota: u64,
    /// Frames of an unknown type or length (checksum passed).
    pub unknown: u64,
    pub valid_frames: u64,
    pub crc_errors: u64,
    pub truncated: u64,
    pub garbage_bytes: u64,
    pub garbage_runs: u64,
    /// Valid frames that followed broken bytes (a bad, cut or garbage run before them).
    pub resyncs: u64,
    /// F.Port 2 telemetry frames whose direction was guessed.
    pub guessed: u64,
    pub unusual_escapes: u64,
    /// F.Port 2 telemetry frames whose physical ID byte has wrong check bits.
    pub check_bits: u64,
    /// Something broken came since the last valid frame.
    pub(crate) broken: bool,
}

impl Stats {
    /// A frame passed its checksum.
    pub(crate) fn valid(&mut self) {
        self.valid_frames += 1;
        if self.broken {
            self.resyncs += 1;
            self.broken = false;
        }
    }

    pub(crate) fn rssi(&mut self, v: u8) {
        self.rssi_min = Some(self.rssi_min.map_or(v, |m| m.min(v)));
        self.rssi_max = Some(self.rssi_max.map_or(v, |m| m.max(v)));
    }

    /// The `--stats` report; `head` says which variant was decoded and why.
    pub fn report(&self, head: String) -> Report {
        let mut r = Report::new(&[
            Column::right("ID", 3),
            Column::left("Device", 10).gap(2),
            Column::right("Polls", 8),
            Column::right("Requests", 9),
            Column::right("Answers", 8),
            Column::right("Data", 8),
            Column::right("Null", 8),
            Column::right("Other", 6),
        ]);
        r.head.push(head);
        r.head.push(
            "Polls: downlink null frames to the ID; Requests: other downlink frames; Answers: \
             uplink frames from it (Data, Null, Other)"
                .into(),
        );
        let cells = |p: &PhysStats| {
            [p.polls, p.requests, p.answers, p.data, p.null, p.other].map(|n| n.to_string())
        };
        let mut total = PhysStats::default();
        for (phys, p) in self.per.iter().enumerate() {
            if p.polls + p.requests + p.answers == 0 {
                continue;
            }
            total.polls += p.polls;
            total.requests += p.requests;
            total.answers += p.answers;
            total.data += p.data;
            total.null += p.null;
            total.other += p.other;
            let mut row = vec![
                phys.to_string(),
                crate::sport::names::device(phys as u8).to_owned(),
            ];
            row.extend(cells(p));
            r.row(row);
        }
        let mut row = vec!["all".to_owned(), String::new()];
        row.extend(cells(&total));
        r.total_row(row);
        let [c8, c16, c24] = self.control;
        let rssi = match (self.rssi_min, self.rssi_max) {
            (Some(a), Some(b)) => format!(", RSSI {a}-{b}"),
            _ => String::new(),
        };
        r.totals.push(format!(
            "control frames {} (8 channels {c8}, 16 channels {c16}, 24 channels {c24}), frame \
             lost {}, failsafe {}{rssi}, OTA frames {}, unknown frames {}",
            c8 + c16 + c24,
            self.frame_lost,
            self.failsafe,
            self.ota,
            self.unknown
        ));
        r.totals.push(format!(
            "valid frames {}, CRC errors {}, truncated {}, garbage {}, \
             resyncs {}, guessed directions {}, unusual escapes {}, non-standard check bits {}",
            self.valid_frames,
            self.crc_errors,
            self.truncated,
            crate::stats::garbage(self.garbage_bytes, self.garbage_runs),
            self.resyncs,
            self.guessed,
            self.unusual_escapes,
            self.check_bits
        ));
        r
    }

    /// The one problems line, `subject` naming the variant.
    pub fn problems(&self, subject: &'static str) -> Problems {
        let mut p = Problems::new(subject);
        p.count("crc_errors", self.crc_errors, "CRC error", "CRC errors")
            .count(
                "truncated_frames",
                self.truncated,
                "truncated frame",
                "truncated frames",
            )
            .garbage(self.garbage_bytes, self.garbage_runs)
            .count(
                "unusual_escapes",
                self.unusual_escapes,
                "unusual escape",
                "unusual escapes",
            )
            .in_valid(self.valid_frames, "valid frame", "valid frames");
        p
    }
}
