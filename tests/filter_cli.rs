//! Filters, names, the project file and `--stats-format json` from the command line, on each
//! protocol's fixtures. A filtered run must print exactly the rows of the unfiltered run that
//! the filter describes, with the same Counter.

mod common;

use std::path::Path;
use std::process::Command;

use assert_cmd::cargo::CommandCargoExt;
use common::fixture;

const SPORT: &str = "edgetx-MODELE24-2014-07-11-sport.log";
const SPORT_BIN: &str = "sport-sample.bin";
const ETHER: &str = "sbus-digimat.pcap";
const SAB: &str = "sab2-session.bin";

/// busnoop in an empty directory (no busnoop.toml around).
fn busnoop(dir: &Path) -> Command {
    let mut c = Command::cargo_bin("busnoop").unwrap();
    c.current_dir(dir);
    c
}

struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

fn run_in(dir: &Path, args: &[&str]) -> Run {
    let out = busnoop(dir).args(args).output().unwrap();
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8(out.stdout).unwrap(),
        stderr: String::from_utf8(out.stderr).unwrap(),
    }
}

fn run(args: &[&str]) -> Run {
    let dir = tempfile::tempdir().unwrap();
    run_in(dir.path(), args)
}

/// The TSV rows (header dropped) of `protocol file extra…`.
fn rows(protocol: &str, file: &str, extra: &[&str]) -> Vec<Vec<String>> {
    let path = fixture(file);
    let mut args = vec![protocol, path.to_str().unwrap(), "-f", "tsv"];
    args.extend_from_slice(extra);
    let r = run(&args);
    assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
    r.stdout
        .lines()
        .skip(1)
        .map(|l| l.split('\t').map(str::to_owned).collect())
        .collect()
}

/// Column indexes of the base columns.
const ID: usize = 2;
const DEVICE: usize = 3;
const TYPE: usize = 4;
const SENSOR_NO: usize = 5;
const SENSOR: usize = 6;

/// The filtered run equals the unfiltered rows that `keep` selects, Counters included, and
/// selects some rows but not all.
fn check(protocol: &str, file: &str, filter: &[&str], keep: impl Fn(&[String]) -> bool) {
    let all = rows(protocol, file, &[]);
    let want: Vec<Vec<String>> = all.iter().filter(|r| keep(r)).cloned().collect();
    let got = rows(protocol, file, filter);
    assert!(!want.is_empty(), "{filter:?} selects nothing");
    assert!(want.len() < all.len(), "{filter:?} selects everything");
    assert_eq!(got, want, "{protocol} {file} {filter:?}");
}

fn id(r: &[String]) -> Option<u32> {
    r[ID].parse().ok()
}

#[test]
fn sport_each_filter() {
    check("sport", SPORT, &["--id", "24"], |r| id(r) == Some(24));
    check("sport", SPORT, &["--id", "0-1,0x18"], |r| {
        matches!(id(r), Some(0 | 1 | 24))
    });
    check("sport", SPORT, &["--id", "1", "--id", "8"], |r| {
        matches!(id(r), Some(1 | 8))
    });
    check("sport", SPORT, &["--not-id", "0-23"], |r| {
        id(r).is_none_or(|i| i > 23)
    });
    check("sport", SPORT, &["--type", "data"], |r| r[TYPE] == "Data");
    check("sport", SPORT, &["--type", "Poll"], |r| r[TYPE].is_empty());
    check("sport", SPORT, &["--hide-polls"], |r| !r[TYPE].is_empty());
    check("sport", SPORT_BIN, &["--hide-null"], |r| r[TYPE] != "Null");
    check("sport", SPORT_BIN, &["--not-type", "Null,Poll"], |r| {
        r[TYPE] != "Null" && !r[TYPE].is_empty()
    });
    check("sport", SPORT, &["--sensor", "cels,RxBt"], |r| {
        r[SENSOR] == "Cels" || r[SENSOR] == "RxBt"
    });
    // Sensor # is `0x0300`; the old notation (`300`, as the S-Port_Snoop sample writes it), the
    // zero-padded one and the new one all select it.
    for v in ["0300", "300", "0x0300", "0X300"] {
        check("sport", SPORT, &["--sensor", v], |r| {
            r[SENSOR_NO] == "0x0300"
        });
    }
    check("sport", SPORT, &["--device", "receiver"], |r| {
        r[DEVICE] == "Receiver"
    });
}

#[test]
fn sport_errors_only_and_combinations() {
    // A capture with a broken frame: the sample with one CRC byte changed.
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(fixture(SPORT_BIN)).unwrap();
    let pos = bytes.windows(2).position(|w| w == [0x7E, 0x00]).unwrap();
    bytes[pos + 9] ^= 0x01;
    let bad = dir.path().join("bad.bin");
    std::fs::write(&bad, &bytes).unwrap();
    let bad = bad.to_str().unwrap();
    let all = rows("sport", bad, &[]);
    assert!(all.iter().any(|r| r[TYPE] == "BadCRC"));
    check("sport", bad, &["--errors"], |r| r[TYPE] == "BadCRC");
    // AND across filters, OR within one.
    check(
        "sport",
        SPORT,
        &["--id", "24", "--type", "Data", "--sensor", "RSSI,SWR"],
        |r| id(r) == Some(24) && r[TYPE] == "Data" && (r[SENSOR] == "RSSI" || r[SENSOR] == "SWR"),
    );
    check("sport", SPORT, &["--hide-polls", "--not-id", "24"], |r| {
        !r[TYPE].is_empty() && id(r) != Some(24)
    });
}

#[test]
fn names_on_sport_are_shown_and_filterable() {
    let named = rows(
        "sport",
        SPORT,
        &["--name", "Pack=1", "--name", "Pack2=0x08"],
    );
    let plain = rows("sport", SPORT, &[]);
    assert_eq!(named.len(), plain.len());
    for (n, p) in named.iter().zip(&plain) {
        match id(p) {
            Some(1) => assert_eq!(n[DEVICE], "Pack"),
            Some(8) => assert_eq!(n[DEVICE], "Pack2"),
            _ => assert_eq!(n, p),
        }
    }
    let got = rows(
        "sport",
        SPORT,
        &[
            "--name",
            "Pack=1",
            "--device",
            "pack,pack2",
            "--name",
            "Pack2=8",
        ],
    );
    let want: Vec<_> = named
        .into_iter()
        .filter(|r| matches!(id(r), Some(1 | 8)))
        .collect();
    assert_eq!(got, want);
}

#[test]
fn ether_sbus_filters_and_names() {
    check("sbus", ETHER, &["--type", "NAK,ack"], |r| {
        r[TYPE] == "NAK" || r[TYPE] == "ACK"
    });
    check("sbus", ETHER, &["--errors"], |r| r[TYPE] == "NAK");
    check("sbus", ETHER, &["--sensor", "read dbx"], |r| {
        r[SENSOR] == "Read DBX"
    });
    check("sbus", ETHER, &["--not-type", "Request"], |r| {
        r[TYPE] != "Request"
    });
    // Names work on Ether-S-Bus (they replace the PLC address of the station's rows), with
    // --name and with the old --station.
    for opt in ["--name", "--station"] {
        let named = rows("sbus", ETHER, &[opt, "Boiler=10"]);
        assert!(
            named
                .iter()
                .all(|r| id(r) != Some(10) || r[DEVICE] == "Boiler")
        );
        assert!(named.iter().any(|r| r[DEVICE] == "Boiler"));
    }
    let got = rows(
        "sbus",
        ETHER,
        &["--name", "Boiler=10", "--device", "boiler", "--type", "NAK"],
    );
    assert_eq!(got.len(), 1);
    assert_eq!(got[0][DEVICE], "Boiler");
    // The station filter on a capture that has only station 10.
    let all = rows("sbus", ETHER, &[]);
    let ten = rows("sbus", ETHER, &["--id", "10"]);
    assert_eq!(
        ten,
        all.iter()
            .filter(|r| id(r) == Some(10))
            .cloned()
            .collect::<Vec<_>>()
    );
    assert!(rows("sbus", ETHER, &["--id", "11"]).is_empty());
}

#[test]
fn sab_filters_names_and_the_device_rule() {
    check("sab2", SAB, &["--id", "5"], |r| id(r) == Some(5));
    check("sab2", SAB, &["--type", "ack,NACK"], |r| {
        r[TYPE] == "ACK" || r[TYPE] == "NACK"
    });
    check("sab2", SAB, &["--errors"], |r| {
        !matches!(r[TYPE].as_str(), "Request" | "ACK")
    });
    check("sab2", SAB, &["--sensor", "0x10"], |r| {
        r[SENSOR_NO] == "0x10"
    });
    // `--device NAME=ADDR` names (the old SAB option), `--device NAME` filters.
    let all = rows("sab2", SAB, &["--device", "sonar=5"]);
    assert!(all.iter().any(|r| r[DEVICE] == "sonar"));
    let got = rows("sab2", SAB, &["--device", "sonar=5", "--device", "SONAR"]);
    assert_eq!(
        got,
        all.iter()
            .filter(|r| r[DEVICE] == "sonar")
            .cloned()
            .collect::<Vec<_>>()
    );
    assert_eq!(rows("sab2", SAB, &["--name", "sonar=5"]), all);
    let got = rows(
        "sab2",
        SAB,
        &["--command", "distance=0x10", "--sensor", "Distance"],
    );
    assert!(!got.is_empty() && got.iter().all(|r| r[SENSOR] == "distance"));
}

#[test]
fn usage_errors_name_the_valid_values() {
    let sport = fixture(SPORT);
    let sport = sport.to_str().unwrap();
    let ether = fixture(ETHER);
    let ether = ether.to_str().unwrap();
    let sab = fixture(SAB);
    let sab = sab.to_str().unwrap();
    for (args, want) in [
        (vec!["sport", sport, "--id", "40"], "0-31 (0x00-0x1F)"),
        (
            vec!["sport", sport, "--id", "0xA1"],
            "poll byte of physical ID 1",
        ),
        (
            vec!["sbus", ether, "--id", "256"],
            "outside the station range 0-255",
        ),
        (
            vec!["sab2", sab, "--not-id", "64"],
            "outside the address range 0-63",
        ),
        (
            vec!["sport", sport, "--id", "two"],
            "expected IDs like 2, 0x1B or 0-9",
        ),
        (
            vec!["sport", sport, "--sensor", "VFAZ"],
            "did you mean VFAS?",
        ),
        (vec!["sport", sport, "--type", "Dta"], "types: Data, Null"),
        (
            vec!["sbus", ether, "--type", "Poll"],
            "types: Request, Response",
        ),
        (vec!["sbus", ether, "--hide-polls"], "S-Bus has no polls"),
        (
            vec!["sab2", sab, "--hide-null"],
            "SAB has no keep-alive rows",
        ),
        (
            vec!["sport", sport, "--device", "Boiler"],
            "the Device column shows ASS-70",
        ),
        (
            vec!["sab2", sab, "--device", "sonar"],
            "until devices are named",
        ),
        (
            vec!["sab2", sab, "--sensor", "speed"],
            "--command NAME=CODE",
        ),
        (vec!["sbus", ether, "--sensor", "Q7"], "R100, F5"),
        (vec!["sport", sport, "--name", "Pack"], "expected NAME=ID"),
        (vec!["sport", sport, "--name", "Pack=32"], "0-31"),
    ] {
        let r = run(&args);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stderr);
        assert!(r.stderr.contains(want), "{args:?}: {}", r.stderr);
        assert_eq!(r.stderr.lines().count(), 1, "one line: {}", r.stderr);
        assert!(r.stderr.len() < 400, "short: {}", r.stderr);
        assert!(r.stdout.is_empty(), "{args:?}");
    }
}

#[test]
fn project_file_names_filters_and_defaults() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("busnoop.toml"),
        r#"# the test bench
[sport]
format = "csv"
stats = true

[sport.names]
Pack = 1

[sport.filter]
hide-polls = true
id = [1, "24"]

[sbus.names]
Boiler = 10

[sab2]
timeout-ms = 10
[sab2.commands]
distance = 0x10
"#,
    )
    .unwrap();
    let sport = fixture(SPORT);
    let sport = sport.to_str().unwrap();
    let r = run_in(dir.path(), &["sport", sport]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let mut lines = r.stdout.lines();
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("Counter,Millis,ID,Device"),
        "csv from the file"
    );
    let body: Vec<&str> = lines.collect();
    assert!(!body.is_empty());
    for l in &body {
        let f: Vec<&str> = l.split(',').collect();
        assert!(f[2] == "1" || f[2] == "24", "{l}");
        assert!(!f[4].is_empty(), "no polls: {l}");
        if f[2] == "1" {
            assert_eq!(f[3], "Pack");
        }
    }
    assert!(
        r.stderr.contains("S.Port statistics (592 rows"),
        "{}",
        r.stderr
    );
    // The command line wins: a list replaces the file's, -f replaces the format.
    let r = run_in(dir.path(), &["sport", sport, "--id", "8", "-f", "tsv"]);
    let body: Vec<&str> = r.stdout.lines().skip(1).collect();
    assert!(!body.is_empty() && body.iter().all(|l| l.split('\t').nth(2) == Some("8")));
    // --no-config ignores it.
    let r = run_in(dir.path(), &["sport", sport, "--no-config", "-f", "tsv"]);
    assert_eq!(r.stdout.lines().count(), 593);
    // Other protocols read their own tables.
    let ether = fixture(ETHER);
    let r = run_in(dir.path(), &["sbus", ether.to_str().unwrap(), "-f", "tsv"]);
    assert!(r.stdout.contains("\tBoiler\t"), "{}", r.stdout);
    let sab = fixture(SAB);
    let r = run_in(
        dir.path(),
        &[
            "sab",
            sab.to_str().unwrap(),
            "-f",
            "tsv",
            "--sensor",
            "distance",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("\tdistance\t"));
    // The file's sensor filter in the old and the new hex notation (a bare `300` is read as
    // the hex digits it shows, as before).
    for sensor in ["\"300\"", "300", "\"0x0300\"", "[\"0X300\"]"] {
        let cfg = tempfile::tempdir().unwrap();
        std::fs::write(
            cfg.path().join("busnoop.toml"),
            format!("[sport.filter]\nsensor = {sensor}\n"),
        )
        .unwrap();
        let r = run_in(cfg.path(), &["sport", sport, "-f", "tsv"]);
        assert_eq!(r.code, 0, "{sensor}: {}", r.stderr);
        let body: Vec<&str> = r.stdout.lines().skip(1).collect();
        assert!(!body.is_empty(), "{sensor}");
        assert!(
            body.iter().all(|l| l.split('\t').nth(5) == Some("0x0300")),
            "{sensor}: {body:?}"
        );
    }
    // A bare `0x0300` is the TOML integer 768: refused, with the fix.
    let cfg = tempfile::tempdir().unwrap();
    std::fs::write(
        cfg.path().join("busnoop.toml"),
        "[sport.filter]\nsensor = [\"Cels\", 0x0300] # hex\n",
    )
    .unwrap();
    let r = run_in(cfg.path(), &["sport", sport, "-f", "tsv"]);
    assert_eq!(r.code, 12, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("busnoop.toml:2: [sport.filter] sensor 0x0300 is a TOML integer")
            && r.stderr.contains("sensor = \"0x0300\""),
        "{}",
        r.stderr
    );
    // --config FILE from elsewhere.
    let other = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("busnoop.toml");
    let r = run_in(
        other.path(),
        &["sport", sport, "--config", cfg.to_str().unwrap()],
    );
    assert!(r.stdout.starts_with("Counter,Millis"), "{}", r.stdout);
}

#[test]
fn a_bad_project_file_is_refused_with_its_line() {
    let sport = fixture(SPORT);
    let sport = sport.to_str().unwrap();
    for (text, code, want) in [
        (
            "[sport]\nbaud = 57600\nbuad = 1\n",
            12,
            "busnoop.toml:3: unknown field `buad`",
        ),
        (
            "[sport.filter]\n\nhide_polls = true\n",
            12,
            "busnoop.toml:3: unknown field `hide_polls`",
        ),
        ("[sport]\nformat = \"xml\"\n", 12, "busnoop.toml:2:"),
        (
            "[sport]\ntimeout-ms = 5\n",
            12,
            "busnoop.toml:2: [sport] has no key `timeout-ms`",
        ),
        (
            "[sport.filter]\nid = 99\n",
            12,
            "busnoop.toml: [sport.filter] id 99: outside the physical ID range",
        ),
        (
            "[sport.names]\nX = 99\n",
            12,
            "busnoop.toml: [sport] names X=99: outside",
        ),
        ("[sport\n", 12, "busnoop.toml:1:"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("busnoop.toml"), text).unwrap();
        let r = run_in(dir.path(), &["sport", sport]);
        assert_eq!(r.code, code, "{text}: {}", r.stderr);
        assert!(r.stderr.contains(want), "{text}: {}", r.stderr);
        assert!(r.stdout.is_empty());
    }
    let r = run(&["sport", sport, "--config", "/nonexistent/busnoop.toml"]);
    assert_eq!(r.code, 3, "{}", r.stderr);
}

#[test]
fn stats_as_json_count_hidden_rows() {
    let sport = fixture(SPORT);
    let r = run(&[
        "sport",
        sport.to_str().unwrap(),
        "-f",
        "tsv",
        "--hide-polls",
        "--stats-format",
        "json",
    ]);
    assert_eq!(r.code, 0);
    let last = r.stderr.lines().last().unwrap();
    let v: serde_json::Value = serde_json::from_str(last).unwrap();
    assert_eq!(v["protocol"], "S.Port");
    assert_eq!(v["rows"], 592);
    assert_eq!(v["hidden"], 461);
    assert_eq!(v["shown"], 131);
    assert_eq!(r.stdout.lines().count(), 132);
    let receiver = v["table"]
        .as_array()
        .unwrap()
        .iter()
        .find(|row| row["id"] == 24)
        .unwrap();
    assert_eq!(receiver["device"], "Receiver");
    assert_eq!(receiver["answers"], 47);
    assert!(receiver["mean_ms"].is_f64());
    assert!(v["head"][0].as_str().unwrap().contains("poll interval"));
    // The text form says how many rows the filters hid.
    let r = run(&[
        "sport",
        sport.to_str().unwrap(),
        "-f",
        "tsv",
        "--hide-polls",
        "--stats",
    ]);
    assert!(
        r.stderr
            .contains("S.Port statistics (592 rows, 131 shown, 461 hidden by filters)"),
        "{}",
        r.stderr
    );
}

/// A project file is a few lines of TOML: `--config /dev/zero` (or a huge file, or
/// `./busnoop.toml` a link to one) is refused after its first MiB, exit 12. It used to be read
/// whole into memory: /dev/zero grew by 600 MB a second until the machine ran out. The run is
/// limited to 1 GiB of address space here, so that the old behaviour fails instead of
/// swapping.
#[test]
fn an_endless_project_file_is_refused_without_reading_it_all() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().unwrap();
    let sport = fixture(SPORT_BIN);
    let mut cmd = busnoop(dir.path());
    cmd.arg("sport").arg(&sport).args(["--config", "/dev/zero"]);
    // SAFETY: only setrlimit in the child before exec.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: 1 << 30,
                rlim_max: 1 << 30,
            };
            libc::setrlimit(libc::RLIMIT_AS, &lim);
            Ok(())
        });
    }
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(12), "{err}");
    assert!(err.contains("/dev/zero") && err.contains("1 MiB"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(out.stdout.is_empty());
}
