//! Wireshark interop (docs/wireshark.md): pcapng recordings, the per-frame export, the Lua
//! dissectors (checked with tshark when it is installed) and the extcap interface.

mod common;

use std::path::Path;
use std::process::Command;

use common::fixture;
use common::{busnoop, ok, text};

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

/// tshark, when it is installed (CI installs it); `None` with a message otherwise.
fn tshark() -> Option<Command> {
    let ok = Command::new("tshark")
        .arg("-v")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!("tshark is not installed: skipping the Wireshark comparison");
        return None;
    }
    let mut c = Command::new("tshark");
    // A clean profile: no user preferences or plugins change what it decodes.
    c.env(
        "WIRESHARK_CONFIG_DIR",
        std::env::temp_dir().join("busnoop-no-wireshark-profile"),
    );
    Some(c)
}

/// The table's rows that carry frame bytes, one per frame (TSV with --raw), by column name.
fn frame_rows(tsv: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = tsv.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let mut rows: Vec<std::collections::HashMap<String, String>> = Vec::new();
    for l in lines {
        let row: std::collections::HashMap<String, String> = header
            .iter()
            .zip(l.split('\t'))
            .map(|(h, f)| (h.to_string(), f.to_string()))
            .collect();
        if row["Raw"].is_empty() {
            continue;
        }
        if rows
            .last()
            .is_some_and(|p| p["Raw"] == row["Raw"] && p["Millis"] == row["Millis"])
        {
            continue;
        }
        rows.push(row);
    }
    rows
}

/// The numbers of every row (JSON Lines `parts`, in order) by Counter.
fn parts_by_counter(protocol: &str, input: &Path, extra: &[&str]) -> Vec<Vec<(String, f64)>> {
    let json = ok(&busnoop()
        .arg(protocol)
        .arg(input)
        .args(["-f", "jsonl"])
        .args(extra)
        .output()
        .unwrap());
    let mut by = vec![Vec::new()];
    for l in json.lines() {
        let v: serde_json::Value = serde_json::from_str(l).unwrap();
        let parts = v["parts"]
            .as_object()
            .map(|p| {
                p.iter()
                    .map(|(k, x)| (k.clone(), x.as_f64().unwrap()))
                    .collect()
            })
            .unwrap_or_default();
        by.push(parts);
    }
    by
}

/// The dissector's numbers of a packet: `part` and `value` fields (comma-separated).
fn dissected(names: &str, values: &str) -> Vec<(String, f64)> {
    if names.is_empty() {
        return Vec::new();
    }
    names
        .split(',')
        .zip(values.split(','))
        .map(|(n, v)| (n.to_owned(), v.parse().unwrap()))
        .collect()
}

/// The same numbers, as numbers (tshark prints a double in its shortest form: `0` for 0.00).
fn same_numbers(a: &[(String, f64)], b: &[(String, f64)]) -> bool {
    let mut a = a.to_vec();
    let mut b = b.to_vec();
    a.sort_by(|x, y| x.0.cmp(&y.0));
    b.sort_by(|x, y| x.0.cmp(&y.0));
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| x.0 == y.0 && (x.1 - y.1).abs() <= 1e-9 * x.1.abs().max(1.0))
}

/// The S.Port export of `input`, decoded by tshark with busnoop-sport.lua, against the table:
/// frame for frame the same physical IDs, app IDs, CRC status, and every number of every data
/// frame by name and value (`sport.part`, `sport.value`, a number); `sport.value > 4` filters.
fn sport_export_matches(input: &Path, expect_bad: bool) {
    let Some(mut tshark) = tshark() else { return };
    let dir = tempfile::tempdir().unwrap();
    let export = dir.path().join("export.pcapng");
    let table = ok(&busnoop()
        .arg("sport")
        .arg(input)
        .args(["-f", "tsv", "--raw", "--export"])
        .arg(&export)
        .output()
        .unwrap());
    let rows = frame_rows(&table);
    let parts = parts_by_counter("sport", input, &[]);
    let lua = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/contrib/wireshark/busnoop-sport.lua"
    );
    let out = tshark
        .arg("-X")
        .arg(format!("lua_script:{lua}"))
        .arg("-r")
        .arg(&export)
        .args(["-T", "fields", "-E", "occurrence=a"])
        .args(["-e", "sport.phys_id", "-e", "sport.app_id"])
        .args(["-e", "sport.part", "-e", "sport.value"])
        .args(["-e", "sport.crc_status", "-e", "_ws.expert.message"])
        .output()
        .unwrap();
    let fields = ok(&out);
    let packets: Vec<Vec<&str>> = fields.lines().map(|l| l.split('\t').collect()).collect();
    assert_eq!(packets.len(), rows.len(), "{fields}");
    assert!(rows.len() > 20);
    let (mut bad, mut numbers, mut above_4) = (0, 0, 0);
    for (row, pkt) in rows.iter().zip(&packets) {
        let what = format!("{row:?} against {pkt:?}");
        assert_eq!(row["ID"], pkt[0], "{what}");
        let crc_bad = row["Type"] == "BadCRC";
        if row["Type"].is_empty() {
            assert_eq!(pkt[4], "", "a poll has no CRC: {what}");
            continue;
        }
        assert_eq!(pkt[4], if crc_bad { "bad" } else { "good" }, "{what}");
        if crc_bad {
            bad += 1;
            assert!(pkt[5].split(',').any(|m| m == "Bad CRC"), "{what}");
            continue;
        }
        if !row["Sensor #"].is_empty() {
            let app = u16::from_str_radix(row["Sensor #"].trim_start_matches("0x"), 16).unwrap();
            assert_eq!(pkt[1], format!("0x{app:04x}"), "{what}");
        }
        let want = &parts[row["Counter"].parse::<usize>().unwrap()];
        let got = dissected(pkt[2], pkt[3]);
        assert!(same_numbers(want, &got), "{what}: {want:?} against {got:?}");
        numbers += want.len();
        above_4 += usize::from(want.iter().any(|p| p.1 > 4.0));
    }
    assert!(numbers > 0);
    assert_eq!(bad > 0, expect_bad, "the input's bad CRCs");
    // `sport.value` is a number: a display filter compares it.
    let Some(mut tshark) = self::tshark() else {
        return;
    };
    let filtered = ok(&tshark
        .arg("-X")
        .arg(format!("lua_script:{lua}"))
        .arg("-r")
        .arg(&export)
        .args([
            "-Y",
            "sport.value > 4",
            "-T",
            "fields",
            "-e",
            "sport.phys_id",
        ])
        .output()
        .unwrap());
    assert_eq!(filtered.lines().count(), above_4, "sport.value > 4");
}

#[test]
fn tshark_decodes_the_sport_export_like_the_table() {
    // The sample with one frame's CRC spoiled (a Volts frame: 7E 22 10 10 02 .. DD).
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let at = bytes
        .windows(10)
        .position(|w| w == [0x7E, 0x22, 0x10, 0x10, 0x02, 0, 0, 0, 0, 0xDD])
        .unwrap();
    bytes[at + 9] = 0xDC;
    let input = dir.path().join("sample.bin");
    std::fs::write(&input, bytes).unwrap();
    sport_export_matches(&input, true);
    // Every sensor of the EdgeTX capture (cells, RSSI, RxBt, SWR), typed.
    sport_export_matches(&fixture("edgetx-MODELE24-2014-07-11-sport.log"), false);
}

#[test]
fn export_names_and_protocols_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    for (protocol, input, name, says) in [
        ("sport", "sport-sample.bin", "e.pcap", "FILE.pcapng"),
        // An Ether-S-Bus capture is Wireshark's already.
        (
            "sbus",
            "sbus_seeds_ether.pcap",
            "e.pcapng",
            "is a network capture, which Wireshark opens as it is",
        ),
    ] {
        let target = dir.path().join(name);
        let out = busnoop()
            .arg(protocol)
            .arg(fixture(input))
            .arg("--export")
            .arg(&target)
            .output()
            .unwrap();
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(says), "{err}");
        assert!(!target.exists());
    }
}

#[test]
fn tshark_decodes_the_sab_export_like_the_table() {
    for session in ["sab1-session.bin", "sab2-session.bin"] {
        let Some(mut tshark) = tshark() else { return };
        let dir = tempfile::tempdir().unwrap();
        let export = dir.path().join("export.pcapng");
        let table = ok(&busnoop()
            .arg("sab2")
            .arg(fixture(session))
            .args(["-f", "tsv", "--raw", "--export"])
            .arg(&export)
            .output()
            .unwrap());
        let rows = frame_rows(&table);
        let lua = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/contrib/wireshark/busnoop-sab.lua"
        );
        let fields = ok(&tshark
            .arg("-X")
            .arg(format!("lua_script:{lua}"))
            .arg("-r")
            .arg(&export)
            .args(["-T", "fields", "-E", "occurrence=a"])
            .args(["-e", "sab.address", "-e", "sab.type", "-e", "sab.command"])
            .args(["-e", "sab.crc_status", "-e", "_ws.expert.message"])
            .args(["-e", "sab.value_name", "-e", "sab.value"])
            .output()
            .unwrap());
        let packets: Vec<Vec<&str>> = fields.lines().map(|l| l.split('\t').collect()).collect();
        assert_eq!(packets.len(), rows.len(), "{session}: {fields}");
        // Every number of the table, typed, by name.
        let parts = parts_by_counter("sab2", &fixture(session), &[]);
        let mut numbers = 0;
        for (row, pkt) in rows.iter().zip(&packets) {
            let want = &parts[row["Counter"].parse::<usize>().unwrap()];
            let got = dissected(pkt[5], pkt[6]);
            assert!(
                same_numbers(want, &got),
                "{session}: {row:?}: {want:?} against {got:?}"
            );
            numbers += want.len();
        }
        assert!(numbers >= 5, "{session}: {numbers} numbers");
        let (mut frames, mut bad) = (0, 0);
        for (row, pkt) in rows.iter().zip(&packets) {
            let what = format!("{session}: {row:?} against {pkt:?}");
            match row["Type"].as_str() {
                "Request" | "ACK" | "NACK" => {
                    frames += 1;
                    assert_eq!(row["ID"], pkt[0], "{what}");
                    assert_eq!(row["Type"], pkt[1], "{what}");
                    assert_eq!(row["Sensor #"], pkt[2], "{what}");
                    assert_eq!(pkt[3], "good", "{what}");
                }
                "BadCRC" => {
                    bad += 1;
                    assert_eq!(pkt[3], "bad", "{what}");
                    assert!(pkt[4].split(',').any(|m| m == "Bad CRC"), "{what}");
                }
                // Garbage, runts: bytes that are no frame.
                _ => assert_eq!(pkt[3], "", "{what}"),
            }
        }
        assert!(
            frames >= 19 && bad == 1,
            "{session}: {frames} frames, {bad} bad"
        );
    }
}

/// Two frames with the same bytes that arrive in one read (so with one time) are two frames:
/// the table shows both, and the export had only one packet for them. A live adapter hands
/// over several frames per read, and RC buses repeat the same frame while the sticks rest.
#[test]
fn identical_frames_with_one_time_are_two_packets() {
    let dir = tempfile::tempdir().unwrap();
    let export = dir.path().join("e.pcapng");
    // The table's rows with bytes (the last column, `--raw`) and the export's packets, of one
    // run.
    let framed_and_packets = |protocol: &str, input: &Path| {
        let table = ok(&busnoop()
            .args([protocol, "--no-config", "--raw", "-f", "tsv", "--export"])
            .arg(&export)
            .arg(input)
            .output()
            .unwrap());
        let framed: Vec<String> = table
            .lines()
            .skip(1)
            .filter_map(|l| l.rsplit('\t').next().filter(|raw| !raw.is_empty()))
            .map(String::from)
            .collect();
        (framed, packets_of(&std::fs::read(&export).unwrap()))
    };
    // EdgeTX debug log lines: the second holds two polls of ID 1, read at one time.
    let log = dir.path().join("two.log");
    std::fs::write(
        &log,
        "2014-07-11,22:41:01.340: 7E 00\n\
         2014-07-11,22:41:01.350: 7E A1 7E A1\n\
         2014-07-11,22:41:01.360: 7E 22\n",
    )
    .unwrap();
    let (framed, packets) = framed_and_packets("sport", &log);
    assert_eq!(framed, ["7E 00", "7E A1", "7E A1", "7E 22"]);
    let frames: Vec<&[u8]> = packets.iter().map(|(_, b)| &b[..]).collect();
    assert_eq!(
        frames,
        [
            &[0x7E, 0x00][..],
            &[0x7E, 0xA1],
            &[0x7E, 0xA1],
            &[0x7E, 0x22]
        ]
    );
    // A real capture: Modbus echoes a write request in its response, and in this pcap both
    // have one time; eleven responses were missing from the export.
    let (framed, packets) = framed_and_packets("modbus", &fixture("modbus-gen.pcap"));
    assert_eq!((packets.len(), framed.len()), (158, 158));
}

/// The packets (link type, bytes) of a pcapng file.
fn packets_of(bytes: &[u8]) -> Vec<(u32, Vec<u8>)> {
    let mut got = Vec::new();
    let mut s = busnoop::pcap::PcapStream::default();
    s.push(bytes, &mut |p| got.push((p.link_type, p.data.to_vec())))
        .unwrap();
    got
}

#[test]
fn extcap_lists_its_interfaces_as_wireshark_asks() {
    // Wireshark runs the extcap (a symlink to busnoop) with its own options first.
    let list = ok(&busnoop()
        .args(["--extcap-interfaces", "--extcap-version=4.0"])
        .output()
        .unwrap());
    assert!(list.starts_with("extcap {version="), "{list}");
    assert!(list.contains("interface {value=busnoop-sport}{display=FrSky S.Port (busnoop)}"));
    assert!(list.contains("interface {value=busnoop-sab2}"));
    let dlts = ok(&busnoop()
        .args(["--extcap-dlts", "--extcap-interface", "busnoop-sport"])
        .output()
        .unwrap());
    assert_eq!(
        dlts,
        "dlt {number=147}{name=USER0}{display=FrSky S.Port (busnoop) frames}\n"
    );
    let config = ok(&busnoop()
        .args([
            "extcap",
            "--extcap-config",
            "--extcap-interface",
            "busnoop-sab2",
        ])
        .output()
        .unwrap());
    assert!(
        config.contains("{call=--port}") && config.contains("{type=selector}"),
        "{config}"
    );
    assert!(config.contains("{default=115200}"), "{config}");
    let out = busnoop()
        .args(["--extcap-dlts", "--extcap-interface", "eth0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("unknown interface eth0"));
}

#[test]
fn extcap_captures_a_serial_bus_into_wiresharks_fifo() {
    use common::pty::{bus, lock, wait_exit};
    use std::io::{Read, Write};
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("wireshark-fifo");
    nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::S_IRWXU).unwrap();
    let mut b = bus();
    let mut child = busnoop()
        .args(["--capture", "--extcap-interface", "busnoop-sport", "--fifo"])
        .arg(&fifo)
        .arg("--port")
        .arg(&b.path)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wireshark's side: read the FIFO as it comes.
    let (tx, rx) = std::sync::mpsc::channel();
    let reader_path = fifo.clone();
    std::thread::spawn(move || {
        let mut f = std::fs::File::open(reader_path).unwrap();
        let mut s = busnoop::pcap::PcapStream::default();
        let mut buf = [0u8; 4096];
        loop {
            let n = f.read(&mut buf).unwrap_or(0);
            if n == 0 {
                break;
            }
            let _ = s.push(&buf[..n], &mut |p| {
                let _ = tx.send((p.link_type, p.data.to_vec()));
            });
        }
    });
    let traffic = std::fs::read(fixture("sport-sample.bin")).unwrap();
    b.master.write_all(&traffic).unwrap();
    b.master.flush().unwrap();
    // Wireshark sees frames while the capture runs.
    let want = packets_of(&{
        let dir2 = tempfile::tempdir().unwrap();
        let e = dir2.path().join("e.pcapng");
        ok(&busnoop()
            .arg("sport")
            .arg(fixture("sport-sample.bin"))
            .arg("--export")
            .arg(&e)
            .args(["-o", "/dev/null"])
            .output()
            .unwrap());
        std::fs::read(&e).unwrap()
    });
    let mut live = Vec::new();
    while live.len() < 20 {
        let p = rx
            .recv_timeout(common::PATIENCE)
            .expect("no frame reached the FIFO for 10 s");
        live.push(p);
    }
    // Wireshark stops an extcap with SIGTERM.
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGTERM,
    )
    .unwrap();
    let status = wait_exit(&mut child);
    drop(b);
    // SIGTERM is how every capture ends: exit code 0, and nothing on stderr, which Wireshark
    // would show as an error.
    let err = common::pty::stderr_of(&mut child);
    assert_eq!((status.code(), err.as_str()), (Some(0), ""));
    assert!(live.iter().all(|p| p.0 == busnoop::pcap::linktype::USER0));
    assert_eq!(live[..], want[..20]);
}
