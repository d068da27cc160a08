//! `--record` of a network capture (Ether-S-Bus in pcap or pcapng): the recording holds the
//! packets themselves (the input's link type, each packet's time, bytes and original length),
//! so that it replays to the same rows and Wireshark opens it; raw names are refused up front;
//! the recording never lands on its own input.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};

use busnoop::pcap::PcapStream;
use common::{busnoop, fixture, ok, text};

/// The Ether-S-Bus captures of `fixtures/`: classic little-endian microsecond pcaps with
/// tcpdump's header (snap length 262144, Ethernet).
const CAPTURES: [&str; 2] = ["sbus-digimat.pcap", "sbus_seeds_ether.pcap"];

/// The TSV of `busnoop sbus SOURCE ARGS`, which must succeed.
fn rows(source: &Path, args: &[&str]) -> String {
    ok(&busnoop()
        .arg("sbus")
        .arg(source)
        .args(["-f", "tsv"])
        .args(args)
        .output()
        .unwrap())
}

/// The TSV of `busnoop sbus SOURCE --record RECORDING`, which must succeed.
fn rows_recording(source: &Path, recording: &Path) -> String {
    ok(&busnoop()
        .arg("sbus")
        .arg(source)
        .args(["-f", "tsv", "--record"])
        .arg(recording)
        .output()
        .unwrap())
}

/// Every packet of a capture: time (µs), link type, bytes, original length.
fn packets(capture: &[u8]) -> Vec<(i64, u32, Vec<u8>, u32)> {
    let mut got = Vec::new();
    let mut s = PcapStream::new();
    s.push(capture, &mut |p| {
        got.push((p.ts_micros, p.link_type, p.data.to_vec(), p.orig_len))
    })
    .unwrap();
    s.finish().unwrap();
    got
}

/// The TSV of the run that recorded, of the input and of the recording are the same, and the
/// recording holds the input's packets.
fn same_rows_and_packets(input: &Path, recording: &Path) -> String {
    let want = rows(input, &[]);
    assert!(want.lines().count() > 2, "{want}");
    assert_eq!(
        rows_recording(input, recording),
        want,
        "{}",
        input.display()
    );
    assert_eq!(rows(recording, &[]), want, "{}", recording.display());
    assert_eq!(
        packets(&std::fs::read(recording).unwrap()),
        packets(&std::fs::read(input).unwrap()),
        "{}",
        recording.display()
    );
    want
}

#[test]
fn a_recorded_capture_replays_to_the_same_rows_and_packets() {
    let dir = tempfile::tempdir().unwrap();
    for name in CAPTURES {
        let input = fixture(name);
        let pcap = dir.path().join("copy.pcap");
        same_rows_and_packets(&input, &pcap);
        // tcpdump's own format, written back field for field.
        assert_eq!(
            std::fs::read(&pcap).unwrap(),
            std::fs::read(&input).unwrap()
        );

        let pcapng = dir.path().join("copy.pcapng");
        same_rows_and_packets(&input, &pcapng);
        let bytes = std::fs::read(&pcapng).unwrap();
        assert_eq!(busnoop::pcap::pcapng_link_type(&bytes), Some(1), "Ethernet");
        assert!(text(&bytes).contains("busnoop "), "shb_userappl");

        // A pcapng input, recorded as pcap again: the original capture.
        let again = dir.path().join("again.pcap");
        same_rows_and_packets(&pcapng, &again);
        assert_eq!(
            std::fs::read(&again).unwrap(),
            std::fs::read(&input).unwrap()
        );
    }
}

#[test]
fn a_piped_capture_is_recorded_as_its_packets() {
    // `tcpdump -w - | busnoop sbus - --record copy.pcap`
    let dir = tempfile::tempdir().unwrap();
    let input = fixture("sbus-digimat.pcap");
    let copy = dir.path().join("copy.pcap");
    let run = ok(&busnoop()
        .args(["sbus", "-", "-f", "tsv", "--record"])
        .arg(&copy)
        .stdin(std::fs::File::open(&input).unwrap())
        .output()
        .unwrap());
    assert_eq!(run, rows(&input, &[]));
    assert_eq!(
        std::fs::read(&copy).unwrap(),
        std::fs::read(&input).unwrap()
    );
}

/// `capture` (a classic little-endian microsecond pcap) with nanosecond time stamps: each
/// record's fraction in ns, plus `extra(i)` ns for the `i`th record.
fn in_nanoseconds(capture: &[u8], extra: impl Fn(u32) -> u32) -> Vec<u8> {
    let mut out = capture.to_vec();
    out[..4].copy_from_slice(&0xA1B2_3C4Du32.to_le_bytes());
    let (mut at, mut i) = (24, 0);
    while at + 16 <= out.len() {
        let word = |b: &[u8], o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
        let ns = word(&out, at + 4) * 1000 + extra(i);
        out[at + 4..at + 8].copy_from_slice(&ns.to_le_bytes());
        at += 16 + word(&out, at + 8) as usize;
        i += 1;
    }
    out
}

#[test]
fn nanosecond_captures_keep_their_precision() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("ns.pcap");
    let bytes = in_nanoseconds(&std::fs::read(fixture("sbus-digimat.pcap")).unwrap(), |i| {
        i * 7 % 1000
    });
    std::fs::write(&input, &bytes).unwrap();
    let want = rows(&fixture("sbus-digimat.pcap"), &[]);

    let pcap = dir.path().join("copy.pcap");
    assert_eq!(same_rows_and_packets(&input, &pcap), want);
    assert_eq!(std::fs::read(&pcap).unwrap(), bytes, "nanoseconds kept");

    // pcapng keeps them too: recorded as pcap again, it is the nanosecond input.
    let pcapng = dir.path().join("copy.pcapng");
    same_rows_and_packets(&input, &pcapng);
    let again = dir.path().join("again.pcap");
    same_rows_and_packets(&pcapng, &again);
    assert_eq!(std::fs::read(&again).unwrap(), bytes, "nanoseconds kept");
}

#[test]
fn a_capture_without_packets_is_recorded_as_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("empty.pcap");
    let header = std::fs::read(fixture("sbus-digimat.pcap")).unwrap()[..24].to_vec();
    std::fs::write(&input, &header).unwrap();
    let copy = dir.path().join("copy.pcap");
    let out = busnoop()
        .arg("sbus")
        .arg(&input)
        .arg("--record")
        .arg(&copy)
        .output()
        .unwrap();
    assert!(!text(&out.stderr).contains("panicked"));
    assert_eq!(std::fs::read(&copy).unwrap(), header);
}

#[test]
fn a_broken_capture_is_recorded_up_to_its_last_whole_packet() {
    let dir = tempfile::tempdir().unwrap();
    let whole = std::fs::read(fixture("sbus-digimat.pcap")).unwrap();
    let input = dir.path().join("cut.pcap");
    std::fs::write(&input, &whole[..whole.len() - 5]).unwrap();
    let copy = dir.path().join("copy.pcap");
    let run = rows_recording(&input, &copy);
    assert!(run.contains("ends inside the record"), "{run}");
    let recorded = std::fs::read(&copy).unwrap();
    let got = packets(&recorded);
    assert_eq!(got, packets(&whole)[..got.len()]);
    assert_eq!(got.len(), 49);
    assert!(whole.starts_with(&recorded));
}

/// `--record -`, and a FIFO named without an extension (`--record >(tshark -r -)`; here the
/// pipe of standard output as /dev/stdout): classic pcap.
#[test]
fn record_to_standard_output_writes_the_packets_as_pcap() {
    let dir = tempfile::tempdir().unwrap();
    let input = fixture("sbus-digimat.pcap");
    let table = dir.path().join("t.tsv");
    for target in ["-", "/dev/stdout"] {
        let out = busnoop()
            .arg("sbus")
            .arg(&input)
            .args(["--record", target, "-o"])
            .arg(&table)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        assert_eq!(out.stdout, std::fs::read(&input).unwrap(), "{target}");
    }
}

/// The run was refused with a one-line usage error containing every one of `words`, wrote
/// nothing on standard output, and `target` does not exist.
fn refused(out: &Output, words: &[&str], target: &Path) {
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for w in words {
        assert!(err.contains(w), "{w}: {err}");
    }
    assert!(out.stdout.is_empty());
    assert!(!target.exists(), "{} was created", target.display());
}

#[test]
fn raw_recordings_of_packets_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["copy.bin", "copy.RAW"] {
        let target = dir.path().join(name);
        let table = dir.path().join("t.tsv");
        let out = busnoop()
            .arg("sbus")
            .arg(fixture("sbus-digimat.pcap"))
            .arg("--record")
            .arg(&target)
            .arg("-o")
            .arg(&table)
            .output()
            .unwrap();
        refused(&out, &["--record", ".pcap", ".pcapng"], &target);
        assert!(!table.exists(), "the table was created");
    }
    // From standard input too.
    let target = dir.path().join("copy.bin");
    let out = busnoop()
        .args(["sbus", "-", "--record"])
        .arg(&target)
        .stdin(std::fs::File::open(fixture("sbus-digimat.pcap")).unwrap())
        .output()
        .unwrap();
    refused(&out, &[".pcap", ".pcapng"], &target);
}

/// A copy of the digimat capture in `dir` under `name`.
fn capture(dir: &Path, name: &str) -> (PathBuf, Vec<u8>) {
    let bytes = std::fs::read(fixture("sbus-digimat.pcap")).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, &bytes).unwrap();
    (p, bytes)
}

#[test]
fn a_recording_onto_its_own_capture_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap.pcap");
    let sym = dir.path().join("sym.pcap");
    std::os::unix::fs::symlink(&cap, &sym).unwrap();
    let hard = dir.path().join("hard.pcapng");
    std::fs::hard_link(&cap, &hard).unwrap();
    for target in [&cap, &sym, &hard] {
        let out = busnoop()
            .arg("sbus")
            .arg(&cap)
            .arg("--record")
            .arg(target)
            .stdout(Stdio::null())
            .output()
            .unwrap();
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("same file"), "{err}");
        assert_eq!(std::fs::read(&cap).unwrap(), bytes, "{}", target.display());
    }
    // Standard input is the file: `busnoop sbus - --record cap.pcap < cap.pcap`.
    let out = busnoop()
        .args(["sbus", "-", "--record"])
        .arg(&cap)
        .stdin(std::fs::File::open(&cap).unwrap())
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert_eq!(std::fs::read(&cap).unwrap(), bytes);
}
