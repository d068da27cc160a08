//! Decoder tests: every function's rows, the register map, pairing and timeouts, statistics,
//! chunking.

use super::wire::push_crc;
use super::*;
use crate::row::{Class, Collected, OwnedRow};

/// A frame from its bytes without the CRC.
pub(crate) fn f(bytes: &[u8]) -> Vec<u8> {
    let mut v = bytes.to_vec();
    push_crc(&mut v);
    v
}

/// One request and its response for every public function (MODBUS Application Protocol
/// V1.1b3's examples where it has them), and an exception.
pub(crate) fn exchanges() -> Vec<(Vec<u8>, Vec<u8>)> {
    let mut dev = vec![0x01, 0x2B, 0x0E, 0x01, 0x01, 0x00, 0x00, 0x03];
    for (id, text) in [(0u8, &b"Company"[..]), (1, b"PROD1"), (2, b"V2.11")] {
        dev.extend_from_slice(&[id, text.len() as u8]);
        dev.extend_from_slice(text);
    }
    let pairs: Vec<(Vec<u8>, Vec<u8>)> = vec![
        (vec![1, 1, 0, 0x13, 0, 0x0A], vec![1, 1, 2, 0xCD, 0x01]),
        (
            vec![1, 2, 0, 0xC4, 0, 0x16],
            vec![1, 2, 3, 0xAC, 0xDB, 0x35],
        ),
        (
            vec![1, 3, 0, 0x6B, 0, 3],
            vec![1, 3, 6, 0x02, 0x2B, 0, 0, 0, 0x64],
        ),
        (vec![1, 4, 0, 8, 0, 1], vec![1, 4, 2, 0, 0x0A]),
        (vec![1, 5, 0, 0xAC, 0xFF, 0], vec![1, 5, 0, 0xAC, 0xFF, 0]),
        (vec![1, 6, 0, 1, 0, 3], vec![1, 6, 0, 1, 0, 3]),
        (vec![1, 7], vec![1, 7, 0x6D]),
        (vec![1, 8, 0, 0, 0xA5, 0x37], vec![1, 8, 0, 0, 0xA5, 0x37]),
        (vec![1, 0x0B], vec![1, 0x0B, 0xFF, 0xFF, 0x01, 0x08]),
        (
            vec![1, 0x0C],
            vec![1, 0x0C, 8, 0, 0, 1, 8, 1, 0x21, 0x20, 0],
        ),
        (
            vec![1, 0x0F, 0, 0x13, 0, 0x0A, 2, 0xCD, 0x01],
            vec![1, 0x0F, 0, 0x13, 0, 0x0A],
        ),
        (
            vec![1, 0x10, 0, 1, 0, 2, 4, 0, 0x0A, 1, 2],
            vec![1, 0x10, 0, 1, 0, 2],
        ),
        (vec![1, 0x11], vec![1, 0x11, 3, 0x42, 0xFF, 0x07]),
        (
            vec![1, 0x14, 0x0E, 6, 0, 4, 0, 1, 0, 2, 6, 0, 3, 0, 9, 0, 2],
            vec![
                1, 0x14, 0x0C, 5, 6, 0x0D, 0xFE, 0, 0x20, 5, 6, 0x33, 0xCD, 0, 0x40,
            ],
        ),
        (
            vec![
                1, 0x15, 0x0D, 6, 0, 4, 0, 7, 0, 3, 0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D,
            ],
            vec![
                1, 0x15, 0x0D, 6, 0, 4, 0, 7, 0, 3, 0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D,
            ],
        ),
        (
            vec![1, 0x16, 0, 4, 0, 0xF2, 0, 0x25],
            vec![1, 0x16, 0, 4, 0, 0xF2, 0, 0x25],
        ),
        (
            vec![
                1, 0x17, 0, 3, 0, 6, 0, 0x0E, 0, 3, 6, 0, 0xFF, 0, 0xFF, 0, 0xFF,
            ],
            vec![
                1, 0x17, 0x0C, 0, 0xFE, 0x0A, 0xCD, 0, 1, 0, 3, 0, 0x0D, 0, 0xFF,
            ],
        ),
        (
            vec![1, 0x18, 0x04, 0xDE],
            vec![1, 0x18, 0, 6, 0, 2, 0x01, 0xB8, 0x12, 0x84],
        ),
        (vec![1, 0x2B, 0x0E, 1, 0], dev),
        (vec![1, 3, 0, 0, 0, 0x7F], vec![1, 0x83, 3]),
    ];
    pairs.into_iter().map(|(a, b)| (f(&a), f(&b))).collect()
}

/// Decodes `segments` (bytes, time) with `opts`; checks that byte-by-byte feeding gives the
/// same rows.
pub(crate) fn decode(opts: &Options, segments: &[(Vec<u8>, Option<u64>)]) -> Vec<OwnedRow> {
    let run = |segs: &mut dyn Iterator<Item = (&[u8], Option<u64>)>| {
        let mut d = ModbusDecoder::new(opts.clone());
        let mut out = Collected::default();
        for (b, t) in segs {
            d.push(b, t, &mut out).unwrap();
        }
        d.finish(&mut out).unwrap();
        out.rows
    };
    let whole = run(&mut segments.iter().map(|(b, t)| (&b[..], *t)));
    let bytes = run(&mut segments
        .iter()
        .flat_map(|(b, t)| b.chunks(1).map(move |c| (c, *t))));
    assert_eq!(whole, bytes, "byte by byte");
    whole
}

fn untimed(bytes: &[u8]) -> Vec<OwnedRow> {
    decode(&Options::default(), &[(bytes.to_vec(), None)])
}

fn part<'a>(r: &'a OwnedRow, name: &str) -> Option<&'a str> {
    r.parts.iter().find(|p| p.0 == name).map(|p| p.2.as_str())
}

fn names(r: &OwnedRow) -> Vec<&str> {
    r.parts.iter().map(|p| p.0.as_str()).collect()
}

#[test]
fn every_function_request_and_response_rows() {
    for (req, resp) in exchanges() {
        let rows = untimed(&[req.clone(), resp.clone()].concat());
        assert_eq!(rows.len(), 2, "{rows:?}");
        let fc = req[1];
        let (q, a) = (&rows[0], &rows[1]);
        assert_eq!(q.kind, "Request");
        assert_eq!(q.id, Some(1));
        assert_eq!(q.sensor_no, format!("0x{fc:02X}"));
        assert_eq!(q.sensor, function::name(fc));
        assert_eq!(q.raw, req);
        assert_eq!(
            a.kind,
            if resp[1] & 0x80 != 0 {
                "Exception"
            } else {
                "Response"
            }
        );
        assert_eq!(
            a.sensor_no, q.sensor_no,
            "an exception names the function it answers"
        );
        assert_eq!(a.raw, resp);
        assert!(!a.extra[2].contains("no request"), "{a:?}");
    }
}

#[test]
fn parts_follow_the_output_contract() {
    let ex = exchanges();
    let rows = |i: usize| untimed(&[ex[i].0.clone(), ex[i].1.clone()].concat());
    // FC 1: 10 coils from 0x13
    let r = rows(0);
    assert_eq!(
        (part(&r[0], "start"), part(&r[0], "count")),
        (Some("19"), Some("10"))
    );
    assert_eq!(
        names(&r[1]),
        [
            "C19", "C20", "C21", "C22", "C23", "C24", "C25", "C26", "C27", "C28"
        ]
    );
    // 0xCD = 1100 1101, first coil in bit 0
    let bits: Vec<&str> = r[1].parts.iter().map(|p| p.2.as_str()).collect();
    assert_eq!(bits, ["1", "0", "1", "1", "0", "0", "1", "1", "1", "0"]);
    // FC 3: three registers from 107
    let r = rows(2);
    assert_eq!(names(&r[1]), ["R107", "R108", "R109"]);
    assert_eq!(r[1].value(), "555");
    assert_eq!(r[1].data, "R107=555 R108=0 R109=100");
    assert_eq!(r[0].data, "start=107 count=3");
    // FC 5 and 6: the echo carries the value
    let r = rows(4);
    assert_eq!(names(&r[0]), ["start", "count", "C172"]);
    assert_eq!(names(&r[1]), ["C172"]);
    assert_eq!(part(&r[1], "C172"), Some("1"));
    let r = rows(5);
    assert_eq!(part(&r[0], "R1"), Some("3"));
    assert_eq!(names(&r[1]), ["R1"]);
    // FC 16: the written values, then the response's start and count
    let r = rows(11);
    assert_eq!(names(&r[0]), ["start", "count", "R1", "R2"]);
    assert_eq!(r[0].data, "start=1 count=2 R1=10 R2=258");
    assert_eq!(names(&r[1]), ["start", "count"]);
    // FC 23: the read's start and count; the answer's registers at the read's addresses
    let r = rows(16);
    assert_eq!(part(&r[0], "start"), Some("3"));
    assert_eq!(part(&r[0], "write_start"), Some("14"));
    assert_eq!(names(&r[1])[..2], ["R3", "R4"]);
    // FC 43/14: the objects in the Data cell
    let r = rows(18);
    assert_eq!(
        r[1].data,
        "VendorName=\"Company\" ProductCode=\"PROD1\" MajorMinorRevision=\"V2.11\""
    );
    // the exception: its code
    let r = rows(19);
    assert_eq!(r[1].kind, "Exception");
    assert_eq!(names(&r[1]), ["code"]);
    assert_eq!(part(&r[1], "code"), Some("3"));
    assert_eq!(r[1].data, "Illegal Data Value (3)");
    assert_eq!(r[1].class, Class::Warning);
}

#[test]
fn unpaired_responses_count_from_their_first_value() {
    let ex = exchanges();
    let rows = untimed(&ex[2].1);
    assert_eq!(rows[0].kind, "Response");
    assert_eq!(names(&rows[0]), ["R+0", "R+1", "R+2"]);
    assert!(rows[0].extra[2].contains("no request seen"));
}
