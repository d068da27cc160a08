//! Wireshark interop (docs/wireshark.md): pcapng recordings, the per-frame export, the Lua
//! dissectors (checked with tshark when it is installed) and the extcap interface.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::fixture;

fn busnoop() -> Command {
    let mut c = Command::new(assert_cmd::cargo::cargo_bin("busnoop"));
    c.env_remove("NO_COLOR").env_remove("RUST_LOG");
    c
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn ok(out: &Output) -> String {
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    text(&out.stdout)
}

/// The rows (TSV) of `protocol` on `source`.
fn rows(protocol: &str, source: &Path) -> String {
    ok(&busnoop()
        .arg(protocol)
        .arg(source)
        .args(["-f", "tsv"])
        .output()
        .unwrap())
}

#[test]
fn pcap_and_pcapng_recordings_replay_to_the_same_rows_as_the_run() {
    let dir = tempfile::tempdir().unwrap();
    for (protocol, source) in [
        ("sport", fixture("edgetx-MODELE24-2014-07-11-sport.log")),
        ("sport", fixture("sport-sample.bin")),
        ("sab", fixture("sab2-session.bin")),
    ] {
        let pcap = dir.path().join("r.pcap");
        let pcapng = dir.path().join("r.pcapng");
        let run = ok(&busnoop()
            .arg(protocol)
            .arg(&source)
            .args(["-f", "tsv", "--record"])
            .arg(&pcap)
            .output()
            .unwrap());
        let run_ng = ok(&busnoop()
            .arg(protocol)
            .arg(&source)
            .args(["-f", "tsv", "--record"])
            .arg(&pcapng)
            .output()
            .unwrap());
        assert_eq!(run, run_ng);
        assert!(run.lines().count() > 10, "{run}");
        assert_eq!(rows(protocol, &pcap), run, "{}", source.display());
        assert_eq!(rows(protocol, &pcapng), run, "{}", source.display());
        let bytes = std::fs::read(&pcapng).unwrap();
        assert_eq!(&bytes[..4], b"\x0A\x0D\x0D\x0A");
        let name = text(&bytes);
        assert!(name.contains(&*source.to_string_lossy()), "if_name");
        assert!(name.contains(" baud "), "if_description");
    }
}

#[test]
fn an_unknown_recording_extension_is_refused_with_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["r.txt", "r.pcap.gz", "recording"] {
        let target = dir.path().join(name);
        let out = busnoop()
            .arg("sport")
            .arg(fixture("sport-sample.bin"))
            .arg("--record")
            .arg(&target)
            .output()
            .unwrap();
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(".pcapng") && err.contains(".raw"), "{err}");
        assert!(out.stdout.is_empty());
        assert!(!target.exists(), "{name} was created");
    }
    // The raw names keep the bytes as received.
    for name in ["r.bin", "r.RAW"] {
        let target = dir.path().join(name);
        ok(&busnoop()
            .arg("sport")
            .arg(fixture("sport-sample.bin"))
            .arg("--record")
            .arg(&target)
            .output()
            .unwrap());
        assert_eq!(
            std::fs::read(&target).unwrap(),
            std::fs::read(fixture("sport-sample.bin")).unwrap()
        );
    }
}
