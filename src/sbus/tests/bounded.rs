//! Bounded memory: the S-Bus tables stay under their caps whatever the input (serial response
//! times, Ether-S-Bus conversations, waiting requests, retries).

use super::*;

// ---------------------------------------------------------------------------------------------
// Bounded memory: tables stay under their caps whatever the input
// ---------------------------------------------------------------------------------------------

#[test]
fn serial_response_times_stay_bounded() {
    let mut segs = Vec::new();
    let mut t = 0u64;
    for i in 0..20_000u64 {
        let mut v = Vec::new();
        encode_data(&mut v, 0, &[3, 6, 0, 0, 5], CrcBasis::Both);
        segs.push((v, Some(t)));
        let mut a = Vec::new();
        encode_data(&mut a, 1, &[0, 0, 0, 7], CrcBasis::Both);
        segs.push((a, Some(t + 10_000 + i % 1_000)));
        t += 100_000;
    }
    let mut d = decoder(SMode::Data);
    let mut out = Collected::default();
    for (b, t) in &segs {
        d.push(b, *t, &mut out).unwrap();
        out.rows.clear();
    }
    d.finish(&mut out).unwrap();
    let times = &d.station_stats(3).times;
    assert_eq!(times.count, 20_000);
    assert!(
        times.heap_bytes() <= crate::summary::MAX_HEAP_BYTES,
        "{}",
        times.heap_bytes()
    );
    // the median comes from the histogram now (three significant digits), marked with ~
    let stats = d.stats().to_string();
    assert!(
        stats.contains(" ~10.5 ") || stats.contains(" ~10.4 "),
        "{stats}"
    );
}

/// Ether-S-Bus captures for the bound tests.
struct EtherCapture {
    bytes: Vec<u8>,
    frame: Vec<u8>,
    payload: Vec<u8>,
}

impl EtherCapture {
    fn new() -> Self {
        let mut bytes = Vec::new();
        crate::pcap::write::header(&mut bytes, crate::pcap::linktype::ETHERNET);
        EtherCapture {
            bytes,
            frame: Vec::new(),
            payload: Vec::new(),
        }
    }

    /// A request (`at` 0) from `client` to `plc`, or an answer (`at` 1/2) back.
    fn packet(&mut self, ts: i64, client: ([u8; 4], u16), plc: ([u8; 4], u16), seq: u16, at: u8) {
        self.payload.clear();
        self.frame.clear();
        if at == telegram::AT_REQUEST {
            telegram::encode_ether(&mut self.payload, seq, at, &[1, 6, 0, 0, 5]);
            crate::pcap::write::udp4_frame(&mut self.frame, client, plc, &self.payload);
        } else {
            telegram::encode_ether(&mut self.payload, seq, at, &[0, 0, 0, 7]);
            crate::pcap::write::udp4_frame(&mut self.frame, plc, client, &self.payload);
        }
        crate::pcap::write::record(&mut self.bytes, ts, &self.frame);
    }

    /// Decodes in 64 KiB chunks; returns (kind, device) of every row and the decoder.
    fn decode(&self) -> (Vec<(String, String)>, EtherDecoder) {
        let mut e = PcapBytes::new(EtherDecoder::new(&Options::default()));
        let mut out = Collected::default();
        let mut rows = Vec::new();
        for c in self.bytes.chunks(65_536) {
            e.push(c, None, &mut out).unwrap();
            rows.extend(out.rows.drain(..).map(|r| (r.kind, r.device)));
            let s = e.decoder.table_sizes();
            assert!(s.conversations <= pairing::MAX_CONVERSATIONS, "{s:?}");
            assert!(s.outstanding <= pairing::MAX_OUTSTANDING, "{s:?}");
            assert!(s.deadlines <= 2 * s.outstanding + 1_100, "{s:?}");
            assert!(s.plcs <= MAX_PLCS + 1, "{s:?}");
        }
        e.finish(&mut out).unwrap();
        rows.extend(out.rows.drain(..).map(|r| (r.kind, r.device)));
        (rows, e.decoder)
    }
}

const PLC: ([u8; 4], u16) = ([10, 0, 0, 5], 5050);
const T0: i64 = 1_750_000_000_000_000;

fn count(rows: &[(String, String)], kind: &str) -> usize {
    rows.iter().filter(|r| r.0 == kind).count()
}

#[test]
fn ether_many_conversations_are_capped_and_their_requests_time_out() {
    // A port scan with constant timestamps: every source port sends one request, no answers.
    let extra = 1_000;
    let n = pairing::MAX_CONVERSATIONS + extra;
    let mut cap = EtherCapture::new();
    for i in 0..n {
        let ip = [10, 1, (i >> 16) as u8, (i >> 8) as u8];
        cap.packet(T0, (ip, i as u16), PLC, 7, 0);
    }
    let (rows, e) = cap.decode();
    assert_eq!(count(&rows, "Request"), n);
    // the conversations dropped at the cap: their open requests became Timeout rows
    assert_eq!(count(&rows, "Timeout"), extra);
    let t = e.totals();
    assert_eq!(t.conversations_dropped, extra as u64);
    assert_eq!(t.timeouts, extra as u64);
    assert_eq!(t.unanswered_at_end, pairing::MAX_CONVERSATIONS as u64);
    let problems = e.problems().line().unwrap();
    assert!(problems.contains("1000 timeouts"), "{problems}");
    assert!(
        problems.contains("1000 conversations dropped (more than 4096 at once)"),
        "{problems}"
    );
    assert!(
        e.stats().to_string().contains("conversations 5096"),
        "{}",
        e.stats().to_string()
    );
}

#[test]
fn ether_idle_conversations_expire() {
    // 2000 clients, one poll each, 100 ms apart: a conversation idle for a minute is forgotten.
    let mut cap = EtherCapture::new();
    for i in 0..2_000u32 {
        let ts = T0 + i as i64 * 100_000;
        let client = ([10, 2, (i >> 8) as u8, i as u8], 40_000);
        cap.packet(ts, client, PLC, 1, 0);
        cap.packet(ts + 5_000, client, PLC, 1, 1);
    }
    let (rows, e) = cap.decode();
    assert_eq!(count(&rows, "Response"), 2_000);
    assert_eq!(count(&rows, "Timeout"), 0);
    let s = e.table_sizes();
    // idle for 60 s, found by a sweep every 7.5 s of capture time
    assert!(s.conversations <= 676, "{s:?}");
    let t = e.totals();
    assert!(t.conversations_expired >= 1_300, "{t:?}");
    assert_eq!(t.conversations_dropped, 0);
    assert_eq!(e.problems().line(), None, "idle expiry is not a problem");
}

#[test]
fn ether_many_plcs_are_counted_together_beyond_the_cap() {
    let n = MAX_PLCS + 10;
    let mut cap = EtherCapture::new();
    for i in 0..n {
        let plc = ([10, 3, (i >> 8) as u8, i as u8], 5050);
        cap.packet(T0 + i as i64 * 1000, ([10, 0, 0, 1], 40_000), plc, 1, 0);
        cap.packet(
            T0 + i as i64 * 1000 + 500,
            ([10, 0, 0, 1], 40_000),
            plc,
            1,
            1,
        );
    }
    let (rows, e) = cap.decode();
    // rows name every PLC
    let last = format!("10.3.{}.{}:5050", (n - 1) >> 8, (n - 1) as u8);
    assert_eq!(rows.last().unwrap().1, last);
    let plcs: Vec<(&str, &StationStats)> = e.plc_stats().collect();
    assert_eq!(plcs.len(), MAX_PLCS + 1);
    let (name, other) = plcs[MAX_PLCS];
    assert_eq!(name, "other PLCs (10)");
    assert_eq!((other.requests, other.responses), (10, 10));
    assert_eq!(e.totals().plcs_merged, 10);
    assert!(
        e.stats().to_string().contains("other PLCs (10)"),
        "{}",
        e.stats().to_string()
    );
}

#[test]
fn ether_constant_timestamps_keep_the_deadline_queue_small() {
    // Answered polls, all at the same instant (or a capture without real times).
    let mut cap = EtherCapture::new();
    for i in 0..100_000u32 {
        let seq = i as u16;
        cap.packet(T0, ([10, 0, 0, 1], 40_000), PLC, seq, 0);
        cap.packet(T0, ([10, 0, 0, 1], 40_000), PLC, seq, 1);
    }
    let (rows, e) = cap.decode();
    assert_eq!(count(&rows, "Response"), 100_000);
    let s = e.table_sizes();
    assert!(s.deadlines <= 1_100, "{s:?}");
    assert_eq!(s.outstanding, 0);
}

#[test]
fn ether_a_long_run_of_retries_stays_small() {
    let mut cap = EtherCapture::new();
    for i in 0..100_000i64 {
        cap.packet(T0 + i, ([10, 0, 0, 1], 40_000), PLC, 9, 0);
    }
    let (rows, e) = cap.decode();
    assert_eq!(count(&rows, "Retry"), 99_999);
    let s = e.table_sizes();
    assert!(s.deadlines <= 1_100, "{s:?}");
    assert_eq!(e.totals().unanswered_at_end, 1);
}

#[test]
fn ether_more_than_65536_waiting_requests_become_timeouts() {
    // 70 000 requests on four conversations, no answers, constant timestamps.
    let n = 70_000usize;
    let mut cap = EtherCapture::new();
    for i in 0..n {
        let client = ([10, 0, 0, 1], 40_000 + (i % 4) as u16);
        cap.packet(T0, client, PLC, (i / 4) as u16, 0);
    }
    let (rows, e) = cap.decode();
    let dropped = n - pairing::MAX_OUTSTANDING;
    assert_eq!(count(&rows, "Timeout"), dropped);
    let t = e.totals();
    assert_eq!(t.requests_dropped, dropped as u64);
    assert_eq!(t.timeouts, dropped as u64);
    assert_eq!(t.unanswered_at_end, pairing::MAX_OUTSTANDING as u64);
    let problems = e.problems().line().unwrap();
    assert!(
        problems.contains("4464 requests given up (more than 65536 waiting)"),
        "{problems}"
    );
}

#[test]
fn ether_timeout_rows_at_the_caps_leave_the_next_row_alone() {
    // One conversation more than the cap: the dropped conversation's Timeout row comes just
    // before the new request's row, which must still show its own sequence, data and notes.
    let n = pairing::MAX_CONVERSATIONS + 1;
    let mut cap = EtherCapture::new();
    for i in 0..n {
        let ip = [10, 1, (i >> 16) as u8, (i >> 8) as u8];
        cap.packet(T0, (ip, i as u16), PLC, 7, 0);
    }
    let mut e = PcapBytes::new(EtherDecoder::new(&Options::default()));
    let mut out = Collected::default();
    e.push(&cap.bytes, None, &mut out).unwrap();
    let rows = &out.rows;
    let at = rows.iter().position(|r| r.kind == "Timeout").unwrap();
    assert!(rows[at].extra[2].starts_with("given up"), "{:?}", rows[at]);
    let next = &rows[at + 1];
    assert_eq!(next.kind, "Request");
    assert_eq!(
        (next.data.as_str(), next.extra[1].as_str()),
        (rows[0].data.as_str(), "7")
    );
    assert_eq!(next.extra[2], rows[0].extra[2], "{next:?}");
}
