//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

pub mod pty;

use busnoop::decoder::{Collected, Decoder, OwnedRow};

/// Path of a file in `fixtures/`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// Reads a tab-separated fixture with a header line into maps of column name → value.
pub fn read_tsv(name: &str) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(fixture(name)).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut fields: Vec<&str> = l.split('\t').collect();
            fields.resize(header.len(), "");
            header
                .iter()
                .zip(fields)
                .map(|(h, f)| (h.to_string(), f.to_string()))
                .collect()
        })
        .collect()
}

/// Feeds `(bytes, time)` segments through a decoder and returns every row.
pub fn decode<'a>(
    decoder: &mut dyn Decoder,
    segments: impl IntoIterator<Item = (&'a [u8], Option<u64>)>,
) -> Vec<OwnedRow> {
    let mut out = Collected::default();
    for (bytes, time) in segments {
        decoder.push(bytes, time, &mut out).unwrap();
    }
    decoder.finish(&mut out).unwrap();
    out.rows
}

/// Decodes untimed bytes in one piece with a fresh S.Port decoder.
pub fn sport_rows(bytes: &[u8]) -> Vec<OwnedRow> {
    let mut d = busnoop::sport::SportDecoder::new();
    decode(&mut d, [(bytes, None)])
}
