//! Replays the committed, minimized fuzz corpus (`fuzz/corpus/<target>/`) and the fuzz seeds
//! through the same invariant checks the fuzz targets run (`busnoop::selfcheck`), so CI keeps
//! every input the fuzzers found interesting without running a fuzzer.
//!
//! Not in the published crate (Cargo.toml `exclude`): it reads `fuzz/`, which stays in the
//! repository.

use std::path::PathBuf;

fn inputs(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut out = Vec::new();
    for dir in ["corpus", "seeds"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir).join(target)) else {
            continue;
        };
        for e in entries.flatten() {
            out.push((e.path(), std::fs::read(e.path()).unwrap()));
        }
    }
    assert!(!out.is_empty(), "no corpus for fuzz target {target}");
    out
}

fn replay(target: &str, check: fn(&[u8])) {
    for (path, data) in inputs(target) {
        let r = std::panic::catch_unwind(|| check(&data));
        assert!(
            r.is_ok(),
            "{target}: invariant violated by {}",
            path.display()
        );
    }
}

#[test]
fn sport_corpus() {
    replay("sport", busnoop::selfcheck::sport);
}

#[test]
fn edgetx_log_corpus() {
    replay("edgetx_log", busnoop::selfcheck::edgetx_log);
}

#[test]
fn recording_corpus() {
    replay("recording", busnoop::selfcheck::recording);
}

#[test]
fn sbus_serial_corpus() {
    replay("sbus_serial", busnoop::selfcheck::sbus_serial);
}

#[test]
fn sbus_ether_corpus() {
    replay("sbus_ether", busnoop::selfcheck::sbus_ether);
}

#[test]
fn sab_corpus() {
    replay("sab", busnoop::selfcheck::sab);
}

#[test]
fn crsf_corpus() {
    replay("crsf", busnoop::selfcheck::crsf);
}

#[test]
fn ghst_corpus() {
    replay("ghst", busnoop::selfcheck::ghst);
}

#[test]
fn futaba_corpus() {
    replay("futaba", busnoop::selfcheck::futaba);
}

#[test]
fn logs_corpus() {
    replay("logs", busnoop::selfcheck::logs);
}

#[test]
fn ibus_corpus() {
    replay("ibus", busnoop::selfcheck::ibus);
}

#[test]
fn fport_corpus() {
    replay("fport", busnoop::fport::selfcheck::check);
}

#[test]
fn modbus_corpus() {
    replay("modbus", busnoop::selfcheck::modbus);
}

#[test]
fn logic_trace_corpus() {
    replay("logic_trace", busnoop::selfcheck::logic_trace);
}
