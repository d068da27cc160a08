//! Tests of the S-Bus row mapping (moved from map.rs).

use super::*;
use crate::row::Collected;

/// The response time and the sequence number as the general writers give them.
#[test]
fn response_time_and_sequence_texts() {
    let mut us: Vec<u64> = (0..3000).collect();
    us.extend([
        9_999_949,
        9_999_950,
        429_496_729_549,
        429_496_729_550,
        429_496_729_650,
        i64::MAX as u64 - 50,
        i64::MAX as u64 - 49,
        i64::MAX as u64,
        i64::MAX as u64 + 1,
        u64::MAX - 50,
        u64::MAX,
    ]);
    us.extend((0..64).map(|b| 1u64 << b));
    for u in us {
        let mut sc = Scratch::default();
        sc.resp_time(u);
        let mut want = String::new();
        push_fixed(&mut want, (u as i64).wrapping_add(50) / 100, 1);
        assert_eq!(sc.resp_text(&mut [0; 16]), want, "{u}");
    }
    for seq in [0u16, 1, 9, 10, 99, 100, 999, 1000, 9999, 10000, 65535] {
        let mut sc = Scratch::default();
        sc.seq(seq);
        assert_eq!(sc.seq_text(&mut [0; 16]), seq.to_string());
    }
}

fn read_request(station: u8) -> Outstanding {
    let text = telegram::describe_request(
        station,
        0x06,
        &[0, 0, 5],
        &mut String::new(),
        &mut String::new(),
    );
    Outstanding::new(text.info, 1_000, true, Some(7))
}

#[test]
fn a_timeout_row_leaves_the_row_being_built_alone() {
    let mut m = Mapper::new(true);
    let mut st = StationStats::default();
    let mut class = Class::Plain;
    m.sc.clear();
    m.request(3, 0x06, &[0, 0, 5], &mut st, &mut class);
    let mut out = Collected::default();
    let p = read_request(4);
    m.timeout(
        &p,
        TimeoutWhy::NextRequest,
        2_000,
        250_000,
        "PCD",
        None,
        &mut out,
    )
    .unwrap();
    put_row(
        &mut out,
        &mut m.sc,
        2_000,
        Some(3),
        "PCD",
        "Request",
        class,
        "x",
        &[],
    )
    .unwrap();
    let [timeout, request] = &out.rows[..] else {
        panic!("{:?}", out.rows)
    };
    assert_eq!(timeout.kind, "Timeout");
    assert_eq!(
        timeout.extra,
        ["", "7", "no answer before the next request"]
    );
    assert_eq!(request.extra, ["", "", ""]);
    assert_eq!(
        (request.sensor_no.as_str(), request.data.as_str()),
        ("R5", "R5")
    );
    assert_eq!((m.totals.timeouts, st.requests), (1, 1));
}

#[test]
fn answers_count_in_the_paired_requests_station() {
    let mut m = Mapper::new(true);
    let mut st = StationStats::default();
    let req = read_request(3);
    let mut class = Class::Plain;
    let answer = Answer::Paired {
        req,
        elapsed: 300_000,
        late: true,
    };
    let info = m.answer(&answer, true, 250_000, |_| &mut st, &mut class);
    assert_eq!(class, Class::Warning);
    assert_eq!(m.sc.note, "late: after the 250 ms timeout");
    assert_eq!(m.sc.resp_text(&mut [0; 16]), "300.0");
    let kind = m.ack_nak(0, None, info.as_ref().map(|i| (i, &mut st)), &mut class);
    assert_eq!(kind, "ACK");
    assert!(m.sc.note.ends_with("; ACK to a request that expects data"));
    assert_eq!((st.late, st.acks, st.times.count), (1, 1, 1));

    let mut m = Mapper::new(false);
    let mut class = Class::Plain;
    assert_eq!(m.ack_nak(2, None, None, &mut class), "NAK");
    assert_eq!(
        (m.sc.note.as_str(), class, m.totals.naks),
        ("", Class::Warning, 1)
    );
    assert_eq!(
        m.sc.data,
        "NAK password (0x0002)".replace("NAK password", commands::ack_nak_name(2))
    );
}
