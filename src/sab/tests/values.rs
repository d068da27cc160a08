//! The Value column of SAB rows: defaults of requests and acks, declared (typed, scaled) values.

use super::*;

/// The Value of every row of the demo session: (Type, part name, Value, Unit).
fn values_of(rows: &[OwnedRow]) -> Vec<(String, String, String, String)> {
    rows.iter()
        .map(|r| {
            let (name, text) = r.parts.first().map_or((String::new(), String::new()), |p| {
                (p.0.clone(), p.2.clone())
            });
            (r.kind.clone(), name, text, col(r, "Unit").to_owned())
        })
        .collect()
}

#[test]
fn default_values_of_requests_and_acks() {
    for framing in [Framing::Sync, Framing::Hdlc] {
        let o = Options {
            commands: vec![("distance".into(), 0x10)],
            ..opts(choice(framing))
        };
        let (rows, _) = decode(&o, &sample::session(framing));
        let v = values_of(&rows);
        let s =
            |a: &str, b: &str, c: &str| (a.to_owned(), b.to_owned(), c.to_owned(), String::new());
        // A write's payload: the request's number, named `.req`.
        assert_eq!(v[0], s("Request", "0x02.req", "85"));
        assert_eq!(v[1], s("ACK", "", ""));
        // A read: the ACK's number, named by --command.
        assert_eq!(v[3], s("ACK", "distance", "291"));
        // An argument and an answer: two quantities, two names; unsigned.
        assert_eq!(v[4], s("Request", "0x34.req", "3735928559"));
        assert_eq!(v[5], s("ACK", "0x34", "305419896"));
        // A NACK's payload is an error code, not a number.
        assert_eq!(v[7], s("NACK", "", ""));
        assert_eq!(v[8], s("Request", "distance.req", "1"));
        assert_eq!(v[9], s("NACK", "", ""));
        assert_eq!(v[13], s("ACK", "0x02", "125"));
        // A frame whose check failed carries no number.
        let bad = rows.iter().find(|r| r.kind == "BadCRC").unwrap();
        assert!(bad.parts.is_empty(), "{bad:?}");
        assert!(bad.data.ends_with("(6)"));
        for r in &rows {
            assert!(r.parts.len() <= 1);
            if let Some(p) = r.parts.first() {
                assert!(matches!(r.kind.as_str(), "Request" | "ACK"), "{r:?}");
                p.2.parse::<f64>().unwrap();
            }
        }
    }
}

#[test]
fn declared_values_are_typed_scaled_and_have_units() {
    let mut w = Vec::new();
    let f = Framing::Hdlc;
    sample::frame(&mut w, f, Flags::Request, 5, 0x10, &[]);
    sample::frame(&mut w, f, Flags::Ack, 5, 0x10, &291u16.to_le_bytes());
    sample::frame(&mut w, f, Flags::Request, 0x12, 0x34, &[2]);
    sample::frame(&mut w, f, Flags::Ack, 0x12, 0x34, &(-12.5f32).to_le_bytes());
    // Not an f32: the declared size does not fit.
    sample::frame(&mut w, f, Flags::Request, 0x12, 0x34, &[2]);
    sample::frame(&mut w, f, Flags::Ack, 0x12, 0x34, &[1, 2]);
    sample::frame(&mut w, f, Flags::Request, 0x12, 0x34, &[2]);
    sample::frame(&mut w, f, Flags::Ack, 0x12, 0x34, &f32::NAN.to_le_bytes());
    // A write with a signed value.
    sample::frame(&mut w, f, Flags::Request, 1, 0x02, &(-300i16).to_le_bytes());
    sample::frame(&mut w, f, Flags::Ack, 1, 0x02, &[]);
    let d = |command, direction, ty, scale, unit: &str| Declared {
        command,
        direction,
        ty,
        scale,
        unit: unit.into(),
    };
    let o = Options {
        commands: vec![("distance".into(), 0x10)],
        values: vec![
            d(
                0x10,
                Direction::Both,
                ValueType::U16,
                Scale {
                    mantissa: 1,
                    decimals: 2,
                },
                "m",
            ),
            d(0x34, Direction::Ack, ValueType::F32, Scale::ONE, "deg"),
            d(
                0x02,
                Direction::Both,
                ValueType::I16,
                Scale {
                    mantissa: 1,
                    decimals: 1,
                },
                "mm/s",
            ),
        ],
        ..opts(FramingChoice::Hdlc)
    };
    let (rows, _) = decode(&o, &w);
    let v = values_of(&rows);
    let s = |a: &str, b: &str, c: &str, u: &str| (a.into(), b.into(), c.into(), u.into());
    // A query's empty payload is no mistake.
    assert_eq!(v[0], s("Request", "", "", ""));
    assert!(!col(&rows[0], "Note").contains("--value"));
    assert_eq!(v[1], s("ACK", "distance", "2.91", "m"));
    assert_eq!(rows[1].data, "23 01 (2.91 m)");
    // The request direction of 0x34 is not declared: the default rule.
    assert_eq!(v[2], s("Request", "0x34.req", "2", ""));
    assert_eq!(v[3], s("ACK", "0x34", "-12.5", "deg"));
    assert_eq!(rows[3].data, "00 00 48 C1 (-12.5 deg)");
    assert_eq!(v[5], s("ACK", "", "", ""));
    assert_eq!(rows[5].data, "01 02 (513)");
    assert_eq!(
        col(&rows[5], "Note"),
        "2 payload bytes, --value declares f32 (4): no value"
    );
    assert_eq!(v[7], s("ACK", "", "", ""));
    assert_eq!(col(&rows[7], "Note"), "f32 NaN or infinite: no value");
    assert_eq!(v[8], s("Request", "0x02.req", "-30.0", "mm/s"));
    assert_eq!(rows[8].data, "D4 FE (-30.0 mm/s)");
}
