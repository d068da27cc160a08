//! Invariant checks on arbitrary input for the fuzz target `fport` and the corpus test: each
//! variant gives the same rows however the input is split, every byte is in exactly one row,
//! rows come in time order, and every frame shown as valid passes its checksum when re-read
//! from its wire bytes.

use super::{Options, Variant, wire};
use crate::row::Class;
use crate::selfcheck::same_rows_however_chunked;

/// Panics when an invariant does not hold for `data`.
pub fn check(data: &[u8]) {
    for variant in [Variant::Auto, Variant::V1, Variant::V2, Variant::Fbus] {
        let opts = Options {
            variant,
            baud: None,
        };
        let rows = same_rows_however_chunked(&|| super::decoder(opts), data);
        let total: usize = rows.iter().map(|r| r.raw.len()).sum();
        assert_eq!(total, data.len(), "{variant:?}: bytes lost or duplicated");
        let mut last = 0;
        for r in &rows {
            let micros = r.micros.expect("every F.Port row has a time");
            assert!(micros >= last, "{variant:?}: rows out of time order: {r:?}");
            last = micros;
            if !matches!(r.class, Class::Error) {
                assert!(
                    rechecks(variant, &r.raw),
                    "{variant:?}: a row without a valid frame: {r:?}"
                );
            }
        }
    }
}

/// Whether the wire bytes of a row not flagged as an error hold a frame passing its checksum:
/// F.Port 2 as they are, F.Port v1 unstuffed between the delimiters (and a pad byte).
fn rechecks(variant: Variant, raw: &[u8]) -> bool {
    match variant {
        Variant::V1 => v1_ok(raw),
        Variant::V2 | Variant::Fbus => v2_ok(raw),
        Variant::Auto => v1_ok(raw) || v2_ok(raw),
    }
}

fn v1_ok(raw: &[u8]) -> bool {
    let mut body = Vec::new();
    let mut esc = false;
    for &b in raw {
        match b {
            wire::START | 0xFF if body.is_empty() => {}
            wire::START => break,
            wire::ESCAPE => esc = true,
            b if esc => {
                body.push(b ^ 0x20);
                esc = false;
            }
            b => body.push(b),
        }
    }
    body.len() >= 3 && body[0] as usize + 2 == body.len() && wire::check_ok(&body)
}

fn v2_ok(raw: &[u8]) -> bool {
    raw.len() >= 3 && wire::check_ok(&raw[1..])
}
