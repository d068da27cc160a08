//! The F.Port sessions written by `tools/fport-gen/gen.py` (an independent generator, in
//! Python, from the protocol facts) decode row for row as its `fixtures/fport-sessions.tsv`
//! says: the Type, where each row's bytes lie, the physical ID, the app ID and the Value.

mod common;

use busnoop::fport::{self, Framing, Options, Reason, Variant};
use busnoop::protocol::Decoder;
use busnoop::row::{Collected, OwnedRow};
use common::{fixture, read_tsv};

fn decode(variant: Variant, bytes: &[u8]) -> (Vec<OwnedRow>, Option<(Framing, Reason)>) {
    let mut d = fport::FportDecoder::new(Options {
        variant,
        baud: None,
    });
    let mut out = Collected::default();
    d.push(bytes, None, &mut out).unwrap();
    d.finish(&mut out).unwrap();
    (out.rows, d.chosen())
}

fn check(file: &str, variant: Variant, framing: Framing) {
    let bytes = std::fs::read(fixture(file)).unwrap();
    let want: Vec<_> = read_tsv("fport-sessions.tsv")
        .into_iter()
        .filter(|r| r["file"] == file)
        .collect();
    assert!(want.len() > 100, "{file}: {} rows expected", want.len());
    for v in [variant, Variant::Auto] {
        let (rows, chosen) = decode(v, &bytes);
        assert_eq!(chosen.map(|c| c.0), Some(framing), "{file} {v:?}");
        assert_eq!(rows.len(), want.len(), "{file} {v:?}");
        let mut offset = 0;
        for (r, w) in rows.iter().zip(&want) {
            let kind = if r.kind.is_empty() { "Poll" } else { &r.kind };
            let id = r.id.map(|i| i.to_string()).unwrap_or_default();
            assert_eq!(
                (
                    kind,
                    offset.to_string(),
                    r.raw.len().to_string(),
                    id,
                    r.sensor_no.as_str(),
                    r.value()
                ),
                (
                    w["type"].as_str(),
                    w["offset"].clone(),
                    w["length"].clone(),
                    w["id"].clone(),
                    w["sensor_no"].as_str(),
                    w["value"].as_str()
                ),
                "{file} {v:?}: {r:?}"
            );
            assert_eq!(&bytes[offset..offset + r.raw.len()], &r.raw[..]);
            offset += r.raw.len();
        }
        assert_eq!(offset, bytes.len());
    }
}

#[test]
fn the_f_port_v1_session_decodes_as_generated() {
    check("fport-v1-session.bin", Variant::V1, Framing::V1);
}

#[test]
fn the_f_port_2_session_decodes_as_generated() {
    check("fport2-session.bin", Variant::V2, Framing::V2);
}

/// The sessions hold every kind of row the generator writes.
#[test]
fn the_sessions_cover_the_kinds() {
    let kinds: std::collections::BTreeSet<String> = read_tsv("fport-sessions.tsv")
        .into_iter()
        .map(|r| r["type"].clone())
        .collect();
    for k in [
        "Control",
        "Poll",
        "Data",
        "Null",
        "Read",
        "Reply",
        "OtaStart",
        "OtaData",
        "OtaStop",
        "BadCRC",
        "Truncated",
        "Garbage",
    ] {
        assert!(kinds.contains(k), "{k} missing from {kinds:?}");
    }
}
