//! Several sources at once (`busnoop PROTO SRC1 SRC2`): one table merged by time with a Port
//! column, on two pseudo-terminals (live, Ctrl-C) and on files; recordings keep the ports apart
//! and replay to them; a missing source fails before anything is written; one source stays as it
//! was (no Port column).

mod common;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use busnoop::sport::wire;
use common::pty::{bin, bus, lock, wait_exit};
use common::{busnoop, fixture, ok, text};

/// One S.Port poll slot: a poll of `phys` and, unless it is 2, its answer carrying `value`.
fn slot(phys: u8, value: u32) -> Vec<u8> {
    let mut b = Vec::new();
    if phys == 2 {
        wire::encode_poll(&mut b, wire::header_for(phys));
    } else {
        wire::encode_frame(&mut b, wire::header_for(phys), 0x10, 0x0100, value);
    }
    b
}

/// The rows of a TSV table as maps of column name → cell.
fn rows(tsv: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = tsv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split('\t').collect();
    lines
        .map(|l| {
            header
                .iter()
                .map(|h| (*h).to_owned())
                .zip(l.split('\t').map(str::to_owned))
                .collect()
        })
        .collect()
}

/// A busnoop recording of one line (classic pcap, link type USER0: each packet is the line's
/// bytes), `(µs since the Unix epoch, bytes)` per packet.
fn timed_recording(path: &Path, packets: &[(i64, Vec<u8>)]) {
    let mut out = Vec::new();
    busnoop::pcap::write::header(&mut out, busnoop::pcap::linktype::USER0);
    for (ts, bytes) in packets {
        busnoop::pcap::write::record(&mut out, *ts, bytes);
    }
    std::fs::write(path, out).unwrap();
}

const T0: i64 = 1_700_000_000_000_000;

/// Two recordings of one conversation: slot `i` at `T0 + 12 ms · i`, the even slots on one
/// wire (physical IDs 0 and 2 in turn), the odd ones on the other (ID 1); the second file
/// starts 12 ms after the first.
fn two_wires(dir: &Path, slots: usize) -> (PathBuf, PathBuf) {
    let (mut even, mut odd) = (Vec::new(), Vec::new());
    for i in 0..slots {
        let t = T0 + 12_000 * i as i64;
        if i % 2 == 0 {
            even.push((t, slot(if i % 4 == 0 { 0 } else { 2 }, 100 + i as u32)));
        } else {
            odd.push((t, slot(1, 100 + i as u32)));
        }
    }
    let (a, b) = (dir.join("even.pcap"), dir.join("odd.pcap"));
    timed_recording(&a, &even);
    timed_recording(&b, &odd);
    (a, b)
}

#[test]
fn two_files_merge_by_time_with_a_port_column() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_wires(dir.path(), 40);
    let out = busnoop()
        .args(["sport", "-f", "tsv"])
        .args([&b, &a])
        .output()
        .unwrap();
    let table = ok(&out);
    let header = table.lines().next().unwrap();
    assert!(
        header.starts_with(
            "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tPort\t"
        ),
        "{header}"
    );
    let got = rows(&table);
    assert_eq!(got.len(), 40, "{table}");
    for (i, r) in got.iter().enumerate() {
        assert_eq!(r["Counter"], (i + 1).to_string());
        // One clock: the odd file's start is 12 ms after the even one's.
        assert_eq!(r["Millis"], (12 * i).to_string(), "row {i}: {table}");
        let (port, id) = if i % 2 == 0 {
            (&a, if i % 4 == 0 { "0" } else { "2" })
        } else {
            (&b, "1")
        };
        assert_eq!(r["Port"], port.display().to_string(), "row {i}");
        assert_eq!(r["ID"], id, "row {i}");
        if id != "2" {
            // Alt in centimetres on the wire.
            let want = format!("{}.{:02}", (100 + i) / 100, (100 + i) % 100);
            assert_eq!(r["Value"], want, "{r:?}");
        }
    }
    // Each port's rows are exactly what the file gives alone (Counter and Port aside).
    for (file, parity) in [(&a, 0), (&b, 1)] {
        let alone = rows(&ok(&busnoop()
            .args(["sport", "-f", "tsv"])
            .arg(file)
            .output()
            .unwrap()));
        let merged: Vec<_> = got.iter().skip(parity).step_by(2).collect();
        assert_eq!(alone.len(), merged.len());
        for (x, y) in alone.iter().zip(merged) {
            for col in [
                "ID", "Device", "Type", "Sensor #", "Sensor", "Data", "Value",
            ] {
                assert_eq!(x[col], y[col], "{col}");
            }
            let shift = if parity == 1 { 12 } else { 0 };
            let ms = |r: &std::collections::HashMap<String, String>| -> u64 {
                r["Millis"].parse().unwrap()
            };
            assert_eq!(ms(x) + shift, ms(y));
        }
    }
}

#[test]
fn json_rows_carry_the_port_and_one_source_has_none() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_wires(dir.path(), 8);
    let out = busnoop()
        .args(["sport", "-f", "jsonl"])
        .args([&a, &b])
        .output()
        .unwrap();
    let lines: Vec<serde_json::Value> = ok(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 8);
    for (i, v) in lines.iter().enumerate() {
        let want = if i % 2 == 0 { &a } else { &b };
        assert_eq!(v["port"], want.display().to_string(), "{v}");
    }
    let one = busnoop()
        .args(["sport", "-f", "jsonl"])
        .arg(&a)
        .output()
        .unwrap();
    assert!(!ok(&one).contains("\"port\""));
    let tsv = busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(fixture("sport-sample.bin"))
        .output()
        .unwrap();
    assert!(!ok(&tsv).lines().next().unwrap().contains("Port"));
}

/// One source is written exactly as before the merge existed: the S-Port_Snoop sample's table
/// is the same whether or not a Port column could have been.
#[test]
fn one_source_is_byte_identical_to_its_merge_free_table() {
    let sample = fixture("sport-sample.bin");
    let alone = ok(&busnoop()
        .args(["sport", "-f", "tsv", "--stats"])
        .arg(&sample)
        .output()
        .unwrap());
    // The same bytes merged with an empty second source: the same rows, plus the Port cell.
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let merged = busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(&sample)
        .arg(&empty)
        .output()
        .unwrap();
    let merged = ok(&merged);
    let strip = |line: &str| {
        let mut cells: Vec<&str> = line.split('\t').collect();
        cells.remove(9);
        cells.join("\t")
    };
    let merged: Vec<String> = merged.lines().map(strip).collect();
    let alone: Vec<&str> = alone.lines().collect();
    assert_eq!(merged, alone);
}

#[test]
fn a_recording_of_two_ports_replays_with_the_same_ports() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_wires(dir.path(), 24);
    let rec = dir.path().join("both.pcapng");
    let merged = ok(&busnoop()
        .args(["sport", "-f", "tsv", "--record"])
        .arg(&rec)
        .args([&a, &b])
        .output()
        .unwrap());
    // One interface per port, named by its source.
    let bytes = std::fs::read(&rec).unwrap();
    let found = busnoop::pcap::pcapng_interfaces(&bytes);
    let names: Vec<Option<String>> = found.iter().map(|i| i.name.clone()).collect();
    assert_eq!(
        names,
        [Some(a.display().to_string()), Some(b.display().to_string())]
    );
    let replay = ok(&busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(&rec)
        .output()
        .unwrap());
    assert_eq!(replay, merged);
    // Recorded again, the ports keep their names.
    let again = dir.path().join("again.pcapng");
    let re = ok(&busnoop()
        .args(["sport", "-f", "tsv", "--record"])
        .arg(&again)
        .arg(&rec)
        .output()
        .unwrap());
    assert_eq!(re, merged);
    let replay = ok(&busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(&again)
        .output()
        .unwrap());
    assert_eq!(replay, merged);
    // A recording of several ports on a pipe is read as one line, with a warning.
    let piped = busnoop()
        .args(["sport", "-f", "tsv", "-"])
        .stdin(std::fs::File::open(&rec).unwrap())
        .output()
        .unwrap();
    assert!(
        text(&piped.stderr).contains("a recording of several ports"),
        "{}",
        text(&piped.stderr)
    );
    // Classic pcap cannot keep ports apart: refused before anything is written.
    let pcap = dir.path().join("both.pcap");
    let out = busnoop()
        .args(["sport", "--record"])
        .arg(&pcap)
        .args([&a, &b])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("FILE.pcapng"));
    assert!(!pcap.exists());
}

#[test]
fn a_missing_second_source_fails_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("out.tsv");
    let rec = dir.path().join("rec.pcapng");
    let missing = dir.path().join("missing.bin");
    let out = busnoop()
        .args(["sport", "-o"])
        .arg(&table)
        .arg("--record")
        .arg(&rec)
        .arg(fixture("sport-sample.bin"))
        .arg(&missing)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(
        err.contains("missing.bin") && err.contains("no such file"),
        "{err}"
    );
    assert!(!table.exists() && !rec.exists());
    // The same source twice, and a device with a file, are usage errors.
    let sample = fixture("sport-sample.bin");
    let out = busnoop()
        .args(["sport"])
        .args([&sample, &sample])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("given twice"));
}

/// A port whose bytes are not the protocol is told; nothing decoded anywhere is exit 10.
#[test]
fn nothing_decoded_is_per_port_and_exit_10_only_when_no_port_decoded() {
    let dir = tempfile::tempdir().unwrap();
    let noise = dir.path().join("noise.bin");
    std::fs::write(&noise, common::noise(2000, 7)).unwrap();
    let out = busnoop()
        .args(["sport", "-f", "tsv"])
        .arg(fixture("sport-sample.bin"))
        .arg(&noise)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(err.contains("no S.Port frame in"), "{err}");
    let noise2 = dir.path().join("noise2.bin");
    std::fs::write(&noise2, common::noise(2000, 9)).unwrap();
    let out = busnoop()
        .args(["sport", "-f", "tsv"])
        .args([&noise, &noise2])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(10), "{}", text(&out.stderr));
}

#[test]
fn stats_per_port_in_text_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_wires(dir.path(), 10);
    let out = busnoop()
        .args(["sport", "-f", "tsv", "--stats"])
        .args([&a, &b])
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(
        err.contains(&format!("S.Port statistics, port {} (5 rows)", a.display())),
        "{err}"
    );
    assert!(err.contains(&format!("S.Port statistics, port {} (5 rows)", b.display())));
    let out = busnoop()
        .args(["sport", "-f", "tsv", "--stats-format", "json"])
        .args([&a, &b])
        .output()
        .unwrap();
    // One object for the run (its counts summed), each port's own under `ports`.
    let last = text(&out.stderr).lines().last().unwrap().to_owned();
    let v: serde_json::Value = serde_json::from_str(&last).unwrap();
    assert_eq!(v["rows"], 10, "{v}");
    let ports = v["ports"].as_array().unwrap();
    assert_eq!(ports.len(), 2);
    assert_eq!(ports[1]["port"], b.display().to_string());
    assert_eq!(ports[1]["rows"], 5);
}

/// `--wide` keeps each port's numbers apart: a name both ports send carries the port.
#[test]
fn wide_names_a_shared_number_by_its_port() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_wires(dir.path(), 12);
    let out = busnoop()
        .args(["sport", "-f", "csv", "--wide", "--every", "24"])
        .args([&a, &b])
        .output()
        .unwrap();
    let table = ok(&out);
    let header = table.lines().next().unwrap();
    let want = |p: &Path| format!("Alt@{}(m)", p.display());
    assert!(
        header.contains(&want(&a)) && header.contains(&want(&b)),
        "{header}"
    );
}

/// Spawns `busnoop ARGS` and collects its stdout lines.
fn spawn(args: &[&std::ffi::OsStr]) -> (std::process::Child, std::sync::mpsc::Receiver<String>) {
    let mut child = Command::new(bin())
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        use std::io::BufRead;
        for line in std::io::BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    (child, rx)
}

/// Two adapters on the two wires: two ptys fed two halves of a conversation give one table in
/// time order with the Port column; Ctrl-C writes every row; the recording replays to the same
/// rows and ports.
#[test]
fn two_ptys_merge_live_in_time_order_and_ctrl_c_writes_every_row() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("live.pcapng");
    let (mut even, mut odd) = (bus(), bus());
    let (mut child, rx) = spawn(&[
        "sport".as_ref(),
        "-f".as_ref(),
        "tsv".as_ref(),
        "--record".as_ref(),
        rec.as_os_str(),
        even.path.as_os_str(),
        odd.path.as_os_str(),
    ]);
    let header = rx.recv_timeout(Duration::from_secs(10)).unwrap();
    assert!(header.contains("\tValue\tPort\t"), "{header}");
    let n = 30;
    let mut live = vec![header];
    for i in 0..n {
        let (side, phys) = if i % 2 == 0 {
            (&mut even.master, if i % 4 == 0 { 0 } else { 2 })
        } else {
            (&mut odd.master, 1)
        };
        side.write_all(&slot(phys, 100 + i as u32)).unwrap();
        side.flush().unwrap();
        std::thread::sleep(Duration::from_millis(15));
    }
    // Every row is out before the signal (a row is written when its frame is whole).
    let deadline = Instant::now() + Duration::from_secs(10);
    while live.len() < n + 1 {
        assert!(Instant::now() < deadline, "rows so far: {live:?}");
        if let Ok(l) = rx.recv_timeout(Duration::from_millis(100)) {
            live.push(l);
        }
    }
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(130));
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert!(
        err.contains(&format!(
            "interrupted after {n} rows; all decoded rows were written"
        )),
        "{err}"
    );
    while let Ok(l) = rx.recv_timeout(Duration::from_secs(1)) {
        live.push(l);
    }
    assert_eq!(live.len(), n + 1, "{live:?}");
    let table = live.join("\n") + "\n";
    let got = rows(&table);
    let mut last = 0;
    for (i, r) in got.iter().enumerate() {
        let (port, id) = if i % 2 == 0 {
            (&even.path, if i % 4 == 0 { "0" } else { "2" })
        } else {
            (&odd.path, "1")
        };
        assert_eq!(r["Port"], port.display().to_string(), "row {i}: {table}");
        assert_eq!(r["ID"], id, "row {i}");
        let ms: u64 = r["Millis"].parse().unwrap();
        assert!(ms >= last, "row {i}: {table}");
        last = ms;
    }
    // One clock: 30 slots 15 ms apart span about 435 ms.
    assert!(last >= 29 * 12, "{table}");
    let replay = Command::new(bin())
        .args(["sport", "-f", "tsv"])
        .arg(&rec)
        .output()
        .unwrap();
    assert_eq!(text(&replay.stdout), table, "{}", text(&replay.stderr));
    drop((even.slave, odd.slave));
}

/// An unplugged adapter ends the run (exit 7) with every row of both ports written.
#[test]
fn one_unplugged_port_ends_the_run_with_every_row_written() {
    let _g = lock();
    let (mut a, b) = (bus(), bus());
    let (mut child, rx) = spawn(&[
        "sport".as_ref(),
        "-f".as_ref(),
        "tsv".as_ref(),
        a.path.as_os_str(),
        b.path.as_os_str(),
    ]);
    rx.recv_timeout(Duration::from_secs(10)).unwrap();
    for i in 0..4 {
        a.master.write_all(&slot(0, i)).unwrap();
        a.master.flush().unwrap();
        std::thread::sleep(Duration::from_millis(15));
    }
    std::thread::sleep(Duration::from_millis(200));
    drop(a.master);
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(7));
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert!(err.contains("adapter disconnected after 4 frames"), "{err}");
    let mut lines = Vec::new();
    while let Ok(l) = rx.recv_timeout(Duration::from_secs(1)) {
        lines.push(l);
    }
    assert_eq!(lines.len(), 4, "{lines:?}");
    drop(b);
}

/// Filters apply to every port; the Counter stays the row's number in the merged table.
#[test]
fn filters_apply_to_every_port_and_keep_the_merged_counter() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_wires(dir.path(), 16);
    let out = busnoop()
        .args(["sport", "-f", "tsv", "--id", "1,2", "--stats"])
        .args([&a, &b])
        .output()
        .unwrap();
    let got = rows(&ok(&out));
    // Slots 1, 3, 5 … (ID 1, odd wire) and 2, 6, 10 … (ID 2, even wire).
    let counters: Vec<&str> = got.iter().map(|r| r["Counter"].as_str()).collect();
    assert_eq!(
        counters,
        [
            "2", "3", "4", "6", "7", "8", "10", "11", "12", "14", "15", "16"
        ]
    );
    let err = text(&out.stderr);
    assert!(
        err.contains("(8 rows, 4 shown, 4 hidden by filters)"),
        "{err}"
    );
}

/// `busnoop plot` of a recording of two ports: one series per port, a shared name carries it.
#[test]
fn plot_draws_a_series_per_port() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_wires(dir.path(), 16);
    let rec = dir.path().join("both.pcapng");
    ok(&busnoop()
        .args(["sport", "-f", "tsv", "-o"])
        .arg(dir.path().join("t.tsv"))
        .arg("--record")
        .arg(&rec)
        .args([&a, &b])
        .output()
        .unwrap());
    let svg = dir.path().join("p.svg");
    let out = busnoop()
        .args(["plot", "--protocol", "sport", "-o"])
        .arg(&svg)
        .arg(&rec)
        .output()
        .unwrap();
    ok(&out);
    let drawn = std::fs::read_to_string(&svg).unwrap();
    for p in [&a, &b] {
        // The legend names the port by its file name.
        let file = p.file_name().unwrap().to_str().unwrap();
        assert!(drawn.contains(&format!("Alt@{file} (m)")), "{p:?}: {drawn}");
    }
    // By the name with its port, one series.
    let out = busnoop()
        .args(["plot", "--protocol", "sport", "--sensor"])
        .arg(format!("Alt@{}", b.display()))
        .arg("-o")
        .arg(&svg)
        .arg(&rec)
        .output()
        .unwrap();
    ok(&out);
    let drawn = std::fs::read_to_string(&svg).unwrap();
    assert!(!drawn.contains(&format!("Alt@{}", a.display())));
}

/// With --reconnect only the unplugged port waits: the other one goes on, and the unplugged one
/// comes back on its own row.
#[test]
fn with_reconnect_only_the_unplugged_port_waits() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("adapter");
    let a = bus();
    std::os::unix::fs::symlink(&a.path, &link).unwrap();
    let mut other = bus();
    let (mut child, rx) = spawn(&[
        "sport".as_ref(),
        "-f".as_ref(),
        "tsv".as_ref(),
        "--reconnect".as_ref(),
        link.as_os_str(),
        other.path.as_os_str(),
    ]);
    rx.recv_timeout(Duration::from_secs(10)).unwrap();
    let common::pty::Bus {
        mut master, slave, ..
    } = a;
    master.write_all(&slot(0, 1)).unwrap();
    master.flush().unwrap();
    let first = rx.recv_timeout(Duration::from_secs(10)).unwrap();
    assert!(first.contains(&link.display().to_string()), "{first}");
    drop(master);
    drop(slave);
    let down = rx.recv_timeout(Duration::from_secs(10)).unwrap();
    assert!(down.contains("\tLinkDown\t"), "{down}");
    assert!(down.contains(&link.display().to_string()), "{down}");
    // The other port goes on while the first waits.
    for i in 0..5 {
        other.master.write_all(&slot(1, 10 + i)).unwrap();
        other.master.flush().unwrap();
        let row = rx.recv_timeout(Duration::from_secs(10)).unwrap();
        assert!(row.contains(&other.path.display().to_string()), "{row}");
        assert!(row.contains("\tData\t"), "{row}");
    }
    // Plugged in again: the stable name points to a new device node.
    let mut back = bus();
    let tmp = dir.path().join("adapter.new");
    std::os::unix::fs::symlink(&back.path, &tmp).unwrap();
    std::fs::rename(&tmp, &link).unwrap();
    let up = rx.recv_timeout(Duration::from_secs(10)).unwrap();
    assert!(up.contains("\tLinkUp\t"), "{up}");
    back.master.write_all(&slot(0, 2)).unwrap();
    back.master.flush().unwrap();
    let row = rx.recv_timeout(Duration::from_secs(10)).unwrap();
    assert!(
        row.contains(&link.display().to_string()) && row.contains("\tData\t"),
        "{row}"
    );
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert_eq!(wait_exit(&mut child).code(), Some(130));
    drop((other.slave, back.slave));
}

/// A reader that goes away (`| head -1`) ends a run of several sources quietly with 141, a full
/// disk with the output's exit code 8: the sink's failure stops every port.
#[test]
fn a_closed_pipe_and_a_full_disk_end_several_sources() {
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let big = common::big_sport(dir.path(), 100_000, 0x0100);
    let copy = dir.path().join("copy.bin");
    std::fs::copy(&big, &copy).unwrap();
    let mut child = busnoop()
        .args(["sport", "-f", "tsv"])
        .args([&big, &copy])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("Counter\t"));
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(141));
    assert!(
        !text(&out.stderr).contains("busnoop: cannot"),
        "{}",
        text(&out.stderr)
    );
    let out = busnoop()
        .args(["sport", "-f", "tsv", "-o", "/dev/full"])
        .args([&big, &copy])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(8));
    assert!(text(&out.stderr).contains("cannot write to /dev/full"));
}
