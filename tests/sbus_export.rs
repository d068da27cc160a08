//! Serial S-Bus `--export` (docs/wireshark.md, "Serial S-Bus as Ether-S-Bus"): generated
//! sessions in data, secure, break and parity mode, with bad CRCs, NAKs, retries, missing
//! answers, DLE-escaped values and garbage. The export must decode, frame for frame, to the
//! table's stations, commands, addresses, values and CRC status: in tshark's own `sbus`
//! dissector when tshark is installed (skipped with a message otherwise), and always in
//! busnoop's Ether-S-Bus decoder.

mod common;
use common::{busnoop, ok};

use std::collections::HashMap;
use std::process::Command;

use busnoop::sbus::telegram::{
    CrcBasis, encode_break_request, encode_break_response, encode_data, encode_secure,
};

/// A small deterministic generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Data,
    Secure,
    Break,
    Parity,
}

/// One telegram of the session: attribute and payload (request `station cmd body`, response
/// data, ACK/NAK code), and whether its CRC is spoiled.
type Tele = (u8, Vec<u8>, bool);

/// Exchanges of a master polling stations 1-9: register reads (values with B5/C5 bytes in a
/// quarter of them), register writes (ACK), flag reads; NAKs, missing answers, retries and
/// bad CRCs on either side.
fn session(seed: u64, n: usize) -> Vec<Vec<Tele>> {
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    for i in 0..n {
        let station = 1 + rng.below(9) as u8;
        let addr = (rng.below(1000) as u16).to_be_bytes();
        let (req, answer): (Vec<u8>, Option<Vec<u8>>) = match rng.below(10) {
            0..=5 => {
                let count = 1 + rng.below(4) as u8;
                let mut data = Vec::new();
                for _ in 0..count {
                    let mut v = rng.next() as u32;
                    if rng.below(4) == 0 {
                        v = (v & 0xFFFF_0000) | 0xB5C5;
                    }
                    data.extend_from_slice(&v.to_be_bytes());
                }
                (vec![station, 0x06, count - 1, addr[0], addr[1]], Some(data))
            }
            6..=7 => {
                let mut req = vec![station, 0x0E, 5, addr[0], addr[1]];
                req.extend_from_slice(&(rng.next() as u32).to_be_bytes());
                (req, None)
            }
            _ => (
                vec![station, 0x02, 7, addr[0], addr[1]],
                Some(vec![rng.next() as u8]),
            ),
        };
        let fate = rng.below(20);
        let mut ex = vec![(0u8, req.clone(), fate == 1)];
        match (fate, answer) {
            // No answer, then the master's retry (answered).
            (0, a) => {
                ex.push((0, req, false));
                ex.push(match a {
                    Some(d) => (1, d, false),
                    None => (2, vec![0, 0], false),
                });
            }
            (2, _) => ex.push((2, vec![0, 1], false)),
            (3, Some(d)) => ex.push((1, d, true)),
            (_, Some(d)) => ex.push((1, d, false)),
            (_, None) => ex.push((2, vec![0, 0], false)),
        }
        // The first exchanges are clean, so that auto detection has no doubt.
        if i < 8 {
            for t in &mut ex {
                t.2 = false;
            }
        }
        out.push(ex);
    }
    out
}

/// The session's bytes on the wire, with a garbage run in the middle.
fn wire(mode: Mode, exchanges: &[Vec<Tele>]) -> Vec<u8> {
    let mut out = Vec::new();
    for (i, ex) in exchanges.iter().enumerate() {
        if i == exchanges.len() / 2 && matches!(mode, Mode::Data | Mode::Secure) {
            out.extend_from_slice(&[0x11, 0x22, 0x33]);
        }
        for (at, payload, bad) in ex {
            let start = out.len();
            match mode {
                Mode::Data => encode_data(&mut out, *at, payload, CrcBasis::Escaped),
                Mode::Secure => {
                    let outer = if *at == 0 { 0x10 } else { 0x11 };
                    encode_secure(&mut out, outer, i as u8, *at, payload, CrcBasis::Escaped)
                }
                Mode::Break | Mode::Parity => match at {
                    0 => {
                        if mode == Mode::Break {
                            out.push(0x00);
                        }
                        encode_break_request(&mut out, payload[0], payload[1], &payload[2..])
                    }
                    1 => encode_break_response(&mut out, payload),
                    _ => out.push(if payload[1] == 0 { 0x06 } else { 0x15 }),
                },
            }
            if *bad {
                // Spoil the CRC's last byte (never into a framing byte).
                let last = out.len() - 1;
                let framed = matches!(mode, Mode::Data | Mode::Secure);
                out[last] = match out[last] {
                    // The second byte of a DLE pair: the other pair.
                    b @ (0x00 | 0x01) if framed && out[last - 1] == 0xC5 => b ^ 1,
                    b if framed && matches!(b ^ 0x11, 0xB5 | 0xC5) => b ^ 0x22,
                    b => b ^ 0x11,
                };
                assert!(out.len() > start);
            }
        }
    }
    out
}

/// Table rows (TSV with `--raw`) by column name.
fn table(tsv: &str) -> Vec<HashMap<String, String>> {
    let mut lines = tsv.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split('\t'))
                .map(|(h, f)| (h.to_string(), f.to_string()))
                .collect()
        })
        .collect()
}

/// The rows that carry a frame's bytes, one per frame.
fn frame_rows(rows: &[HashMap<String, String>]) -> Vec<&HashMap<String, String>> {
    rows.iter().filter(|r| !r["Raw"].is_empty()).collect()
}

/// The values a Data cell lists (`R100=355 R101=187`): (medium letter, value) in order.
fn values(data: &str) -> Vec<(char, i64)> {
    data.split(' ')
        .filter_map(|t| {
            let (name, v) = t.split_once('=')?;
            Some((name.chars().next()?, v.parse().ok()?))
        })
        .collect()
}

fn tshark() -> Option<Command> {
    let ok = Command::new("tshark")
        .arg("-v")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!(
            "tshark is not installed: skipping the comparison with Wireshark's sbus dissector"
        );
        return None;
    }
    let mut c = Command::new("tshark");
    c.env(
        "WIRESHARK_CONFIG_DIR",
        std::env::temp_dir().join("busnoop-no-wireshark-profile"),
    );
    Some(c)
}

const FIELDS: [&str; 14] = [
    "ip.src",
    "ip.dst",
    "sbus.seq",
    "sbus.att",
    "sbus.destination",
    "sbus.cmd",
    "sbus.addr_RTC",
    "sbus.addr_IOF",
    "sbus.data_rtc",
    "sbus.data_iof",
    "sbus.nakcode",
    "sbus.crc.status",
    "frame.comment",
    "_ws.col.Info",
];

/// Exports the session of `mode` and checks the export against the table; returns the
/// counts of (requests, responses, ACK/NAKs, bad CRCs, non-telegrams) checked by tshark.
fn export_matches(mode: Mode, name: &str, args: &[&str]) -> Option<[usize; 5]> {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join(format!("{name}.bin"));
    std::fs::write(&input, wire(mode, &session(0x9E37_79B9_7F4A_7C15, 60))).unwrap();
    let export = dir.path().join("export.pcapng");
    let tsv = ok(&busnoop()
        .arg("sbus")
        .arg(&input)
        .args(args)
        .args(["-f", "tsv", "--raw", "--stats", "--export"])
        .arg(&export)
        .output()
        .unwrap());
    let rows = table(&tsv);
    let frames = frame_rows(&rows);
    let kinds = |k: &str| frames.iter().filter(|r| r["Type"] == k).count();
    assert!(
        kinds("Request") > 40 && kinds("Response") > 20 && kinds("Retry") > 0,
        "{name}: {tsv}"
    );
    assert!(kinds("BadCRC") >= 2 && kinds("NAK") > 0, "{name}: {tsv}");

    // busnoop reads the export as Ether-S-Bus: the same telegrams.
    let back = table(&ok(&busnoop()
        .arg("sbus")
        .arg(&export)
        .args(["-f", "tsv", "--raw"])
        .output()
        .unwrap()));
    let telegrams = |rows: &[&HashMap<String, String>]| -> Vec<Vec<String>> {
        rows.iter()
            .filter(|r| {
                ["Request", "Retry", "Response", "ACK", "NAK"].contains(&r["Type"].as_str())
            })
            .map(|r| {
                // A break-mode ACK character has no code of its own: compare the Type only.
                let data = if r["Type"].len() == 3 { "" } else { &r["Data"] };
                ["ID", "Type", "Sensor #", "Sensor"]
                    .map(|c| r[c].clone())
                    .into_iter()
                    .chain([data.to_string()])
                    .collect::<Vec<_>>()
            })
            .collect()
    };
    let back = frame_rows(&back);
    assert_eq!(back.len(), frames.len(), "{name}");
    for (i, (w, g)) in frames.iter().zip(&back).enumerate() {
        let what = format!("{name}: frame {i} of the export read back as Ether-S-Bus");
        let telegram =
            |t: &str| ["Request", "Retry", "Response", "ACK", "NAK", "BadCRC"].contains(&t);
        // (Bytes that are no telegram have names of their own in either decoder.)
        if telegram(&w["Type"]) || telegram(&g["Type"]) {
            assert_eq!(g["Type"], w["Type"], "{what}");
        }
        // The serial decoder pairs an answer with a request whose CRC failed (the station
        // may have read it right); the Ether-S-Bus decoder does not.
        if i == 0 || frames[i - 1]["Type"] != "BadCRC" {
            assert_eq!(telegrams(&[*g]), telegrams(&[*w]), "{what}");
        }
    }

    let mut tshark = tshark()?;
    let mut cmd = tshark.args(["-2", "-r"]).arg(&export).args([
        "-T",
        "fields",
        "-E",
        "occurrence=a",
        "-E",
        "aggregator=,",
    ]);
    for f in FIELDS {
        cmd = cmd.args(["-e", f]);
    }
    let out = ok(&cmd.output().unwrap());
    let packets: Vec<HashMap<&str, &str>> = out
        .lines()
        .map(|l| FIELDS.iter().copied().zip(l.split('\t')).collect())
        .collect();
    assert_eq!(packets.len(), frames.len(), "{name}: {out}");
    let mut counts = [0usize; 5];
    let mut last_seq = None;
    let mut seqs = HashMap::new();
    for (row, p) in frames.iter().zip(&packets) {
        let what = format!("{name}: {row:?}\nagainst {p:?}");
        let station = match row["ID"].as_str() {
            "" => "0.0.0.0".to_string(),
            id => format!("10.0.0.{id}"),
        };
        let kind = row["Type"].as_str();
        let note = &row["Note"];
        let bad = kind == "BadCRC";
        // What the telegram is: its Type, or for a bad CRC the decoder's note.
        let at = match kind {
            "Request" | "Retry" => "0x00",
            "Response" => "0x01",
            "ACK" | "NAK" => "0x02",
            "BadCRC" if note.ends_with("response") => "0x01",
            "BadCRC" if note.ends_with("ACK/NAK") => "0x02",
            "BadCRC" => "0x00",
            _ => "",
        };
        assert_eq!(p["sbus.att"], at, "{what}");
        if at.is_empty() {
            // Bytes that are no telegram: as they were, with busnoop's verdict.
            counts[4] += 1;
            assert_eq!(p["ip.src"], "0.0.0.0", "{what}");
            assert!(
                p["frame.comment"].starts_with(&format!("busnoop: {kind}")),
                "{what}"
            );
            continue;
        }
        assert_eq!(p["sbus.crc.status"], if bad { "0" } else { "1" }, "{what}");
        if bad {
            counts[3] += 1;
            assert!(p["frame.comment"].starts_with("busnoop: BadCRC"), "{what}");
        } else {
            assert_eq!(p["frame.comment"], "", "{what}");
        }
        let seq: u16 = p["sbus.seq"].parse().unwrap();
        let sensor_no = &row["Sensor #"];
        let (medium, addr) = sensor_no.split_at(sensor_no.len().min(1));
        let addr_field = match medium {
            "R" | "T" | "C" => "sbus.addr_RTC",
            _ => "sbus.addr_IOF",
        };
        match at {
            "0x00" => {
                counts[0] += 1;
                // A new sequence number per request to the station; a retry keeps its
                // request's.
                let last = seqs.get(&station).copied();
                match (kind, last) {
                    ("Retry", Some(s)) => assert_eq!(seq, s, "{what}"),
                    (_, Some(s)) => assert_eq!(seq, s + 1, "{what}"),
                    (_, None) => assert_eq!(seq, 0x100, "{what}"),
                }
                seqs.insert(station.clone(), seq);
                last_seq = Some(seq);
                assert_eq!(p["ip.src"], "10.0.1.254", "{what}");
                assert_eq!(p["ip.dst"], station, "{what}");
                assert_eq!(p["sbus.destination"], row["ID"], "{what}");
                let info = format!("Request: {}", row["Sensor"]);
                assert!(p["_ws.col.Info"].starts_with(&info), "{what}");
                assert_eq!(
                    p["_ws.col.Info"].ends_with("(Retry)"),
                    kind == "Retry",
                    "{what}"
                );
                assert_eq!(p[addr_field], addr, "{what}");
                if !bad && row["Sensor"].starts_with("Write") {
                    let want: Vec<String> = values(&row["Data"])
                        .iter()
                        .map(|v| (v.1 as i32 as u32).to_string())
                        .collect();
                    assert_eq!(p["sbus.data_rtc"], want.join(","), "{what}");
                }
            }
            _ => {
                let asked = seqs.get(&station).copied().or(last_seq);
                assert_eq!(Some(seq), asked, "an answer repeats its request's: {what}");
                assert_eq!(p["ip.src"], station, "{what}");
                assert_eq!(p["ip.dst"], "10.0.1.254", "{what}");
                if at == "0x02" {
                    counts[2] += 1;
                    let code = if kind == "ACK" { "0x0000" } else { "0x0001" };
                    assert_eq!(p["sbus.nakcode"], code, "{what}");
                    continue;
                }
                counts[1] += 1;
                // (An answer to a request that failed its CRC is not paired: its registers
                // are not known, the table shows its bytes.)
                if bad || note.contains("not paired") {
                    continue;
                }
                let vals = values(&row["Data"]);
                assert!(!vals.is_empty(), "{what}");
                if vals[0].0 == 'F' {
                    // One byte of flags, bit 0 first: tshark prints it in binary digits.
                    let byte = vals
                        .iter()
                        .enumerate()
                        .fold(0u8, |b, (i, v)| b | ((v.1 as u8) << i));
                    assert_eq!(p["sbus.data_iof"], format!("{byte:b}"), "{what}");
                } else {
                    let want: Vec<String> = vals
                        .iter()
                        .map(|v| (v.1 as i32 as u32).to_string())
                        .collect();
                    assert_eq!(p["sbus.data_rtc"], want.join(","), "{what}");
                }
            }
        }
    }
    Some(counts)
}

#[test]
fn data_mode_export_decodes_in_wiresharks_sbus_dissector_like_the_table() {
    if let Some(c) = export_matches(Mode::Data, "data", &[]) {
        assert!(
            c[0] > 40 && c[1] > 20 && c[2] > 5 && c[3] >= 2 && c[4] == 1,
            "{c:?}"
        );
    }
}

#[test]
fn secure_mode_export_decodes_like_the_table() {
    if let Some(c) = export_matches(Mode::Secure, "secure", &["--mode", "secure"]) {
        assert!(c[0] > 40 && c[3] >= 2 && c[4] == 1, "{c:?}");
    }
}

#[test]
fn break_mode_export_decodes_like_the_table() {
    if let Some(c) = export_matches(Mode::Break, "break", &["--mode", "break"]) {
        assert!(c[0] > 40 && c[1] > 20 && c[2] > 5 && c[3] >= 2, "{c:?}");
    }
}

#[test]
fn parity_mode_export_decodes_like_the_table() {
    if let Some(c) = export_matches(Mode::Parity, "parity", &["--mode", "parity"]) {
        assert!(c[0] > 40 && c[3] >= 2, "{c:?}");
    }
}

#[test]
fn export_of_the_fixture_vectors() {
    // The serial data-mode vectors of fixtures/sbus.tsv, one after the other: every valid one
    // is a datagram with a good CRC, the ones printed with a wrong CRC show it bad.
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = Vec::new();
    for v in common::read_tsv("sbus.tsv") {
        if v["mode"] == "data" {
            bytes.extend(busnoop::fmt::parse_hex(&v["hex_on_wire"]).unwrap());
        }
    }
    let input = dir.path().join("vectors.bin");
    std::fs::write(&input, &bytes).unwrap();
    let export = dir.path().join("v.pcapng");
    let tsv = ok(&busnoop()
        .arg("sbus")
        .arg(&input)
        .args(["--mode", "data", "-f", "tsv", "--raw", "--export"])
        .arg(&export)
        .output()
        .unwrap());
    let rows = table(&tsv);
    let n = frame_rows(&rows).len();
    let mut s = busnoop::pcap::PcapStream::default();
    let mut packets = Vec::new();
    s.push(&std::fs::read(&export).unwrap(), &mut |p| {
        packets.push((p.link_type, p.data.to_vec()))
    })
    .unwrap();
    assert_eq!(packets.len(), n, "{tsv}");
    assert!(packets.iter().all(|p| p.0 == busnoop::pcap::linktype::RAW));
    // The first: RACOM's read of 4 registers at station 1, as Ether-S-Bus from the master.
    let first = &packets[0].1;
    assert_eq!(&first[12..20], &[10, 0, 1, 254, 10, 0, 0, 1]);
    let mut want = Vec::new();
    busnoop::sbus::telegram::encode_ether(&mut want, 0x100, 0, &[1, 6, 3, 0, 0]);
    assert_eq!(&first[28..], &want[..]);
}

#[test]
fn filters_and_pacing_hand_the_telegrams_on() {
    // `--id` (the filter) and `--speed` (the pacer) sit between the decoder and the export:
    // the telegrams still arrive re-read, as Ether-S-Bus datagrams of the kept station only.
    use busnoop::sbus::ether::{Extract, extract, parse};
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("data.bin");
    std::fs::write(&input, wire(Mode::Data, &session(7, 40))).unwrap();
    let export = dir.path().join("e.pcapng");
    let tsv = ok(&busnoop()
        .arg("sbus")
        .arg(&input)
        .args([
            "--id", "4", "--speed", "1000", "-f", "tsv", "--raw", "--export",
        ])
        .arg(&export)
        .output()
        .unwrap());
    let rows = table(&tsv);
    let frames = frame_rows(&rows);
    assert!(
        frames.len() > 6 && frames.iter().all(|r| r["ID"] == "4"),
        "{tsv}"
    );
    let mut s = busnoop::pcap::PcapStream::default();
    let mut n = 0;
    s.push(&std::fs::read(&export).unwrap(), &mut |p| {
        let Extract::Udp(u) = extract(p.link_type, p.data) else {
            panic!("not UDP: {:?}", p.data)
        };
        let t = parse(u.payload).expect("an Ether-S-Bus datagram");
        let station = if t.at == 0 { u.dst } else { u.src };
        assert_eq!(station.ip().to_string(), "10.0.0.4");
        n += 1;
    })
    .unwrap();
    assert_eq!(n, frames.len());
}
