//! Every serial S-Bus telegram of `fixtures/sbus.tsv` (the shared wire reference's vectors)
//! decodes as listed, through the binary; the misprinted seeds are flagged `BadCRC`.

use std::path::PathBuf;

use assert_cmd::Command;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// The wire bytes of every row of `sbus.tsv`, in file order.
fn vectors() -> Vec<(String, Vec<u8>, String)> {
    let text = std::fs::read_to_string(fixture("sbus.tsv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            let bytes = busnoop::fmt::parse_hex(c[2]).unwrap();
            (c[1].to_owned(), bytes, c[4].to_owned())
        })
        .collect()
}

#[derive(Debug)]
struct Row {
    millis: String,
    id: String,
    kind: String,
    sensor_no: String,
    sensor: String,
    data: String,
    seq: String,
    note: String,
}

fn decode(bytes: &[u8], args: &[&str]) -> Vec<Row> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("in.bin");
    std::fs::write(&path, bytes).unwrap();
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .arg("sbus")
        .arg(&path)
        .args(["-f", "tsv"])
        // A vector of one broken telegram is a poor run (exit 13): its rows are what is read.
        .arg("--lenient")
        .args(args)
        .output()
        .unwrap();
    // A vector that is only a bad telegram decodes nothing: exit 10, said on stderr.
    let nothing = out.status.code() == Some(10)
        && String::from_utf8_lossy(&out.stderr).contains("busnoop: no S-Bus frame in ");
    assert!(out.status.success() || nothing, "{out:?}");
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tResp ms\tSeq\tNote"
    );
    lines
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            Row {
                millis: c[1].into(),
                id: c[2].into(),
                kind: c[4].into(),
                sensor_no: c[5].into(),
                sensor: c[6].into(),
                data: c[7].into(),
                seq: c[10].into(),
                note: c[11].into(),
            }
        })
        .collect()
}

fn join(v: &[(String, Vec<u8>, String)], idx: &[usize]) -> Vec<u8> {
    idx.iter().flat_map(|&i| v[i].1.clone()).collect()
}

#[test]
fn vector_file_is_the_expected_one() {
    let v = vectors();
    assert_eq!(v.len(), 22);
    let misprinted: Vec<usize> = (0..v.len()).filter(|&i| v[i].2 == "no").collect();
    assert_eq!(misprinted, [0, 13, 17]);
}

#[test]
fn secure_seed_telegrams() {
    let v = vectors();
    for mode in ["data", "secure", "auto"] {
        // as printed: CRC F8 1D is a misprint of 8F 1D (alone, auto mode has no valid
        // telegram to recognise the data mode by)
        let r = decode(
            &v[0].1,
            &["--mode", if mode == "auto" { "data" } else { mode }],
        );
        assert_eq!(r[0].kind, "BadCRC");
        assert_eq!((r[0].id.as_str(), r[0].sensor_no.as_str()), ("5", "R0"));
        assert_eq!(r[0].seq, "2");
        assert!(r[0].note.contains("CRC 0xF81D, expected 0x8F1D"), "{r:?}");
        // corrected request + response
        let r = decode(&join(&v, &[1, 2]), &["--mode", mode]);
        assert_eq!(r.len(), 2, "{r:?}");
        assert_eq!(
            (
                r[0].kind.as_str(),
                r[0].id.as_str(),
                r[0].sensor_no.as_str()
            ),
            ("Request", "5", "R0")
        );
        assert_eq!(r[0].sensor, "Read register(s)");
        assert_eq!((r[1].kind.as_str(), r[1].id.as_str()), ("Response", "5"));
        assert_eq!(r[1].data, "R0=305419896");
        assert_eq!((r[0].seq.as_str(), r[1].seq.as_str()), ("2", "2"));
        // R181 = 0xB5 sent as C5 00: the CRC matches over the escaped bytes only
        let r = decode(&join(&v, &[3, 4]), &["--mode", mode]);
        assert_eq!(r[0].kind, "Request");
        assert_eq!(r[0].sensor_no, "R181");
        assert_eq!(r[0].note, "CRC over the escaped bytes");
        assert_eq!(r[1].data, "R181=0");
        assert_eq!(r[1].seq, "3");
        // a standard response to a secure request pairs (FAQ 100713)
        let mut std_resp = Vec::new();
        busnoop::sbus::telegram::encode_data(
            &mut std_resp,
            1,
            &[0x12, 0x34, 0x56, 0x78],
            busnoop::sbus::telegram::CrcBasis::Both,
        );
        assert_eq!(
            busnoop::fmt::hex(&std_resp),
            "B5 01 12 34 56 78 A6 D0",
            "the FAQ's standard-mode answer"
        );
        let mut s = v[1].1.clone();
        s.extend_from_slice(&std_resp);
        let r = decode(&s, &["--mode", mode]);
        assert_eq!(
            (r[1].kind.as_str(), r[1].data.as_str()),
            ("Response", "R0=305419896")
        );
        assert_eq!(r[1].note, "");
    }
}

#[test]
fn racom_data_mode_seed_telegrams() {
    let v = vectors();
    for mode in ["data", "auto"] {
        // read 4 registers + the reassembled 4-register answer
        let r = decode(&join(&v, &[7, 14]), &["--mode", mode]);
        assert_eq!(r.len(), 2, "{r:?}");
        assert_eq!(
            (r[0].kind.as_str(), r[0].id.as_str(), r[0].data.as_str()),
            ("Request", "1", "R0..R3")
        );
        assert_eq!((r[1].kind.as_str(), r[1].id.as_str()), ("Response", "1"));
        assert_eq!(r[1].sensor_no, "R0");
        assert_eq!(r[1].sensor, "Read register(s)");
        assert_eq!(
            r[1].data, "R0=2717 R1=2717 R2=-2081223699 R3=503725518",
            "0x00000A9D, 0x00000A9D, 0x83F30BED, 0x1E063DCE"
        );
        assert_eq!(r[1].note, "");
        // the truncated telegram as printed: BadCRC
        let r = decode(&join(&v, &[7, 13]), &["--mode", mode]);
        assert_eq!(r[1].kind, "BadCRC");
        assert_eq!(r[1].id, "1");
        assert!(r[1].note.contains("CRC 0x83F3"), "{r:?}");
        // write outputs O16-O19 = 1, ACK
        let r = decode(&join(&v, &[10, 8]), &["--mode", mode]);
        assert_eq!(r[0].data, "O16=1 O17=1 O18=1 O19=1");
        assert_eq!(r[0].sensor, "Write output(s)");
        assert_eq!((r[1].kind.as_str(), r[1].id.as_str()), ("ACK", "2"));
        assert_eq!(r[1].data, "ACK (0x0000)");
        // read R100, R101 → 355, 187
        let r = decode(&join(&v, &[11, 12]), &["--mode", mode]);
        assert_eq!(r[0].data, "R100..R101");
        assert_eq!(r[1].data, "R100=355 R101=187");
        assert_eq!(r[1].millis, "9", "9 bytes at 9600 baud, 10 bits each");
        // NAK code 1 for the read
        let r = decode(&join(&v, &[11, 9]), &["--mode", mode]);
        assert_eq!(r[1].kind, "NAK");
        assert_eq!(r[1].data, "NAK, no reason specified (0x0001)");
        assert_eq!(r[1].sensor_no, "R100");
    }
    // ACK and NAK alone: no request
    let r = decode(&v[8].1, &["--mode", "data"]);
    assert_eq!(
        (r[0].kind.as_str(), r[0].note.as_str()),
        ("ACK", "no request")
    );
}

#[test]
fn break_mode_seed_telegrams() {
    let v = vectors();
    for mode in ["break", "auto"] {
        // write O10 = 1, ACK character
        let r = decode(&join(&v, &[15, 19]), &["--mode", mode]);
        assert_eq!(r.len(), 2, "{r:?}");
        assert_eq!(
            (r[0].kind.as_str(), r[0].id.as_str(), r[0].data.as_str()),
            ("Request", "2", "O10=1")
        );
        assert_eq!(
            (r[1].kind.as_str(), r[1].sensor_no.as_str()),
            ("ACK", "O10")
        );
        // read R10; the answer as printed has a stray 06: BadCRC
        let r = decode(&join(&v, &[16, 17]), &["--mode", mode]);
        assert_eq!(r[0].data, "R10");
        assert_eq!((r[1].kind.as_str(), r[1].id.as_str()), ("BadCRC", "2"));
        assert!(r[1].note.contains("CRC 0x87AC"), "{r:?}");
        // corrected: R10 = 526
        let r = decode(&join(&v, &[16, 18]), &["--mode", mode]);
        assert_eq!(
            (r[1].kind.as_str(), r[1].data.as_str()),
            ("Response", "R10=526")
        );
        // NAK character
        let r = decode(&join(&v, &[16, 20]), &["--mode", mode]);
        assert_eq!((r[1].kind.as_str(), r[1].data.as_str()), ("NAK", "NAK"));
        assert_eq!(r[1].sensor_no, "R10");
    }
    for mode in ["break", "parity"] {
        // the manual's example with its computed CRC
        let r = decode(&v[21].1, &["--mode", mode]);
        assert_eq!(
            (r[0].kind.as_str(), r[0].id.as_str(), r[0].data.as_str()),
            ("Request", "10", "R100=12345")
        );
        assert_eq!(r[0].sensor, "Write register(s)");
        let r = decode(&v[19].1, &["--mode", mode]);
        assert_eq!(
            (r[0].kind.as_str(), r[0].note.as_str()),
            ("ACK", "no request")
        );
        let r = decode(&v[20].1, &["--mode", mode]);
        assert_eq!(r[0].kind, "NAK");
    }
    // parity mode uses 11 bits per character: the answer starts at 7 × 11 / 9600 s
    let r = decode(&join(&v, &[16, 18]), &["--mode", "parity"]);
    assert_eq!(r[1].millis, "8");
    let r = decode(
        &join(&v, &[16, 18]),
        &["--mode", "break", "--baud", "19200"],
    );
    assert_eq!(r[1].millis, "3");
}

#[test]
fn ether_seed_telegrams() {
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .args(["sbus", "-f", "tsv"])
        .arg(fixture("sbus_seeds_ether.pcap"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split('\t').collect())
        .collect();
    assert_eq!(rows.len(), 2);
    assert_eq!(
        rows[0][..11],
        [
            "1",
            "0",
            "75",
            "127.0.0.2:5050",
            "Request",
            "R0",
            "Read register(s)",
            "R0",
            "",
            "",
            "182"
        ]
    );
    assert_eq!(
        rows[1][..11],
        [
            "2",
            "0",
            "75",
            "127.0.0.2:5050",
            "Response",
            "R0",
            "Read register(s)",
            "R0=305419896",
            // Value: the register as a number (issue 13).
            "305419896",
            "0.0",
            "182"
        ]
    );
    // the same as Wireshark's decode in sbus_seeds_ether_tshark.txt
    let ws = std::fs::read_to_string(fixture("sbus_seeds_ether_tshark.txt")).unwrap();
    assert!(ws.contains("Destination: 75"));
    assert!(ws.contains("Sequence: 182"));
    assert!(ws.contains("S-Bus 32-bit data: 305419896"));
}
