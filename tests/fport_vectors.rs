//! The real S.Port payloads of fixtures/sport-vectors.tsv, wrapped in F.Port v1 and F.Port 2
//! telemetry frames with the F.Port checksums: every F.Port row shows the same Sensor #,
//! Sensor, Data, Value, Unit and parts as `busnoop sport` does for the same 8 bytes (the
//! S.Port decoder run on the S.Port frame), and the same Type for the answers.

mod common;

use busnoop::fmt::parse_hex;
use busnoop::fport::{self, Options, Variant, wire};
use busnoop::row::OwnedRow;
use busnoop::sport::wire as sport_wire;
use common::{decode, read_tsv, sport_rows};

/// The unstuffed header and body (type..crc) of an S.Port frame on the wire.
fn unstuff(wire_bytes: &[u8]) -> (u8, [u8; 8]) {
    let mut out = Vec::new();
    let mut esc = false;
    for &b in &wire_bytes[1..] {
        if esc {
            out.push(b ^ 0x20);
            esc = false;
        } else if b == sport_wire::ESCAPE {
            esc = true;
        } else {
            out.push(b);
        }
    }
    (out[0], out[1..9].try_into().unwrap())
}

/// The S.Port table's row for `body` from `header`.
fn sport_row(header: u8, body: &[u8; 8]) -> OwnedRow {
    let mut bytes = Vec::new();
    sport_wire::encode_raw(&mut bytes, header, body);
    let rows = sport_rows(&bytes);
    assert_eq!(rows.len(), 1);
    rows.into_iter().next().unwrap()
}

fn fport_rows(variant: Variant, bytes: &[u8]) -> Vec<OwnedRow> {
    let mut d = fport::decoder(Options {
        variant,
        baud: None,
    });
    decode(d.as_mut(), [(bytes, None)])
}

/// Sensor #, Sensor, Data, Value, Unit and the parts (name, unit, text).
type Cells<'a> = (
    &'a str,
    &'a str,
    &'a str,
    &'a str,
    &'a str,
    &'a [(String, String, String)],
);

/// The cells the output contract names, and Data.
fn cells(r: &OwnedRow) -> Cells<'_> {
    (
        &r.sensor_no,
        &r.sensor,
        &r.data,
        r.value(),
        &r.extra[0],
        &r.parts,
    )
}

/// Every vector with a body: (source, header, body).
fn vectors() -> Vec<(String, u8, [u8; 8])> {
    let out: Vec<_> = read_tsv("sport-vectors.tsv")
        .into_iter()
        .filter(|v| v["expected_frame_type"] != "poll")
        .map(|v| {
            let bytes = parse_hex(&v["hex_bytes_on_wire"]).unwrap();
            let (header, body) = unstuff(&bytes);
            assert!(sport_wire::crc_ok(&body), "{v:?}");
            (v["hex_bytes_on_wire"].clone(), header, body)
        })
        .collect();
    assert!(out.len() >= 60, "{} vectors", out.len());
    out
}

#[test]
fn f_port_2_telemetry_rows_are_the_s_port_rows() {
    for (src, header, body) in vectors() {
        let payload: [u8; 7] = body[..7].try_into().unwrap();
        let mut bytes = Vec::new();
        wire::encode_v2_control(&mut bytes, &[992; 16], 0, 100);
        wire::encode_v2_telemetry(&mut bytes, header, &payload);
        wire::encode_v2_telemetry(&mut bytes, header, &payload);
        let rows = fport_rows(Variant::V2, &bytes);
        assert_eq!(rows.len(), 3, "{src}: {rows:?}");
        let want = sport_row(header, &body);
        let (down, up) = (&rows[1], &rows[2]);
        assert_eq!(
            (down.extra[1].as_str(), up.extra[1].as_str()),
            ("Downlink", "Uplink")
        );
        for r in [down, up] {
            assert_eq!(cells(r), cells(&want), "{src}");
            assert_eq!(r.id, want.id, "{src}");
            assert_eq!(r.device, want.device, "{src}");
            // The S.Port note (MSP/MAVlite named, config fields) comes first; the check bits
            // of a physical ID byte are named in words of their own.
            let sport_note = want.extra[1].split("non-standard").next().unwrap();
            let sport_note = sport_note.trim_end_matches("; ");
            assert!(r.extra[2].starts_with(sport_note), "{src}: {r:?}");
            assert_eq!(
                r.extra[2].contains("non-standard check bits"),
                want.extra[1].contains("non-standard check bits"),
                "{src}"
            );
        }
        assert_eq!(up.kind, want.kind, "{src}");
        if body[0] == 0x00 {
            assert_eq!(down.kind, "", "{src}: a downlink null frame is a poll");
        } else {
            assert_eq!(down.kind, want.kind, "{src}");
        }
    }
}

/// F.Port v1 carries no physical ID: answers are the flight controller's (27), read and write
/// requests the uplink ID's (13), and the S.Port table reads them from there.
#[test]
fn f_port_v1_telemetry_rows_are_the_s_port_rows() {
    for (src, _, body) in vectors() {
        let payload: [u8; 7] = body[..7].try_into().unwrap();
        let mut bytes = Vec::new();
        wire::encode_v1_telemetry(&mut bytes, wire::V1_DOWNLINK, &payload);
        wire::encode_v1_telemetry(&mut bytes, wire::V1_UPLINK, &payload);
        let rows = fport_rows(Variant::V1, &bytes);
        assert_eq!(rows.len(), 2, "{src}: {rows:?}");
        let request = matches!(body[0], 0x30 | 0x31);
        let down_phys = if request { 13 } else { 27 };
        let want_down = sport_row(sport_wire::header_for(down_phys), &body);
        let want_up = sport_row(sport_wire::header_for(27), &body);
        assert_eq!(cells(&rows[0]), cells(&want_down), "{src}");
        assert_eq!(rows[0].id, Some(down_phys as u32));
        assert_eq!(cells(&rows[1]), cells(&want_up), "{src}");
        assert_eq!(
            (rows[1].kind.as_str(), rows[1].id),
            (want_up.kind.as_str(), Some(27))
        );
        assert_eq!(rows[0].extra[2], want_down.extra[1], "{src}");
        assert_eq!(rows[1].extra[2], want_up.extra[1], "{src}");
    }
}

/// MSP over S.Port is named as the S.Port table names it, in both framings.
#[test]
fn msp_requests_and_replies_are_named() {
    let request = wire::payload(0x30, 0x0730, 0x0000_6401);
    let reply = wire::payload(0x32, 0x0730, 0x0000_0064);
    let mut v1 = Vec::new();
    wire::encode_v1_telemetry(&mut v1, wire::V1_DOWNLINK, &request);
    wire::encode_v1_telemetry(&mut v1, wire::V1_UPLINK, &reply);
    let mut v2 = Vec::new();
    wire::encode_v2_control(&mut v2, &[992; 16], 0, 100);
    wire::encode_v2_telemetry(&mut v2, 0x0D, &request);
    wire::encode_v2_telemetry(&mut v2, 0x1B, &reply);
    for (variant, bytes, at) in [(Variant::V1, v1, 0), (Variant::V2, v2, 1)] {
        let rows = fport_rows(variant, &bytes);
        assert_eq!(rows[at].kind, "Read");
        assert_eq!(rows[at].id, Some(13));
        assert!(rows[at].extra[2].contains("MSP"), "{:?}", rows[at]);
        assert_eq!(rows[at + 1].kind, "Reply");
        assert!(rows[at + 1].extra[2].contains("MSP"), "{:?}", rows[at + 1]);
    }
}
