//! The JSON Lines rows follow their documented schema (docs/jsonl-rows.v1.schema.json) on every
//! fixture, with and without --raw and --time abs; the JSON statistics theirs
//! (docs/stats.v1.schema.json), on every fixture and on failing runs.
//!
//! The checker below knows the keywords the schemas use (type, required, properties,
//! additionalProperties, items, minimum) and fails on any other, so a schema cannot promise more
//! than is checked.

mod common;

use assert_cmd::Command;
use common::fixture;
use serde_json::Value;

fn type_ok(t: &str, v: &Value) -> bool {
    match t {
        "object" => v.is_object(),
        "string" => v.is_string(),
        "integer" => v.is_i64() || v.is_u64(),
        "number" => v.is_number(),
        "null" => v.is_null(),
        "array" => v.is_array(),
        "boolean" => v.is_boolean(),
        other => panic!("unknown type {other}"),
    }
}

fn check(schema: &Value, v: &Value, at: &str) -> Result<(), String> {
    let s = schema.as_object().expect("a schema is an object");
    for key in s.keys() {
        assert!(
            [
                "$schema",
                "$id",
                "title",
                "description",
                "type",
                "required",
                "properties",
                "additionalProperties",
                "items",
                "minimum"
            ]
            .contains(&key.as_str()),
            "the checker does not know the keyword {key}"
        );
    }
    if let Some(t) = s.get("type") {
        let ok = match t {
            Value::String(t) => type_ok(t, v),
            Value::Array(ts) => ts.iter().any(|t| type_ok(t.as_str().unwrap(), v)),
            _ => panic!("bad type"),
        };
        if !ok {
            return Err(format!("{at}: {v} is not of type {t}"));
        }
    }
    if let (Some(min), Some(n)) = (s.get("minimum"), v.as_f64())
        && n < min.as_f64().unwrap()
    {
        return Err(format!("{at}: {n} below {min}"));
    }
    if let (Some(items), Some(a)) = (s.get("items"), v.as_array()) {
        for (i, x) in a.iter().enumerate() {
            check(items, x, &format!("{at}[{i}]"))?;
        }
    }
    if let Some(obj) = v.as_object() {
        for r in s
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            let r = r.as_str().unwrap();
            if !obj.contains_key(r) {
                return Err(format!("{at}: missing {r}"));
            }
        }
        let props = s.get("properties").and_then(Value::as_object);
        for (k, x) in obj {
            match props.and_then(|p| p.get(k)) {
                Some(sub) => check(sub, x, &format!("{at}.{k}"))?,
                None => match s.get("additionalProperties") {
                    Some(Value::Bool(false)) => return Err(format!("{at}: unexpected key {k}")),
                    Some(sub @ Value::Object(_)) => check(sub, x, &format!("{at}.{k}"))?,
                    _ => {}
                },
            }
        }
    }
    Ok(())
}

fn schema() -> Value {
    schema_file("docs/jsonl-rows.v1.schema.json")
}

fn schema_file(name: &str) -> Value {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn every_fixture_follows_the_schema() {
    let schema = schema();
    let captures = [
        ("sport", "edgetx-MODELE24-2014-07-11-sport.log"),
        ("sport", "sport-sample.bin"),
        ("sbus", "sbus-digimat.pcap"),
        ("sbus", "sbus_seeds_ether.pcap"),
        ("sab2", "sab1-session.bin"),
        ("sab2", "sab2-session.bin"),
        ("futaba", "futaba-session.bin"),
        ("ibus", "ibus-sensors.bin"),
        ("ibus", "ibus-rc.bin"),
        ("fport", "fport-v1-session.bin"),
        ("fport", "fport2-session.bin"),
    ];
    let mut rows = 0;
    let mut with_parts = 0;
    for (protocol, file) in captures {
        // SAB with declared types too: units, scaled numbers and floats in `value` and `parts`.
        let declared = &["--value", "0x10=u16*0.01:m", "--value", "0x34=f32:deg"][..];
        let sab = protocol == "sab2";
        for extra in [&[][..], &["--raw", "--time", "abs"][..], declared] {
            if extra == declared && !sab {
                continue;
            }
            let out = Command::cargo_bin("busnoop")
                .unwrap()
                .args([protocol, fixture(file).to_str().unwrap(), "-f", "jsonl"])
                .args(extra)
                .output()
                .unwrap();
            for line in String::from_utf8(out.stdout).unwrap().lines() {
                let v: Value = serde_json::from_str(line).unwrap();
                if let Err(e) = check(&schema, &v, file) {
                    panic!("{e}\n{line}");
                }
                rows += 1;
                with_parts += usize::from(v.get("parts").is_some());
            }
        }
    }
    assert!(
        rows > 1000 && with_parts > 200,
        "{rows} rows, {with_parts} with parts"
    );
}

/// Rows of several sources carry `port`, a string the schema knows.
#[test]
fn rows_of_several_sources_follow_the_schema() {
    let schema = schema();
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .arg("sport")
        .arg(fixture("sport-sample.bin"))
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .args(["-f", "jsonl", "--raw"])
        .output()
        .unwrap();
    let mut ports = std::collections::BTreeSet::new();
    for line in String::from_utf8(out.stdout).unwrap().lines() {
        let v: Value = serde_json::from_str(line).unwrap();
        if let Err(e) = check(&schema, &v, "merged") {
            panic!("{e}\n{line}");
        }
        ports.insert(v["port"].as_str().expect("a port").to_owned());
    }
    assert_eq!(ports.len(), 2, "{ports:?}");
    let mut v: Value = serde_json::from_str(r#"{"counter":1,"millis":0,"id":1,"device":null,"type":null,"sensor_no":null,"sensor":null,"data":null,"value":null,"port":7}"#).unwrap();
    assert!(check(&schema, &v, "bad").is_err(), "a port is a string");
    v["port"] = Value::from("/dev/ttyUSB1");
    check(&schema, &v, "good").unwrap();
}

/// The checker is not a yes-machine: rows that break the schema are caught.
#[test]
fn the_checker_catches_wrong_rows() {
    let schema = schema();
    let good: Value = serde_json::from_str(
        r#"{"counter":1,"millis":0,"id":1,"device":"FLVSS","type":"Data","sensor_no":"300","sensor":"Cels","data":"x","value":4.122,"unit":"V","note":null,"parts":{"Cell1":4.122}}"#,
    )
    .unwrap();
    check(&schema, &good, "good").unwrap();
    for (key, bad) in [
        ("value", Value::String("4.122".into())),
        ("sensor_no", Value::from(300)),
        ("millis", Value::from(-1)),
        ("parts", serde_json::json!({"Cell1": "4.1"})),
        ("surprise", Value::from(1)),
    ] {
        let mut v = good.clone();
        v[key] = bad;
        assert!(check(&schema, &v, "bad").is_err(), "{key}");
    }
    let mut v = good.clone();
    v.as_object_mut().unwrap().remove("value");
    assert!(check(&schema, &v, "bad").is_err());
}

/// The JSON statistics of every fixture with every subcommand that reads it, and of runs that
/// fail (nothing decoded, exit 10; no input, exit 3; a full disk, exit 8), follow
/// docs/stats.v1.schema.json: the last line on stderr, and the same object in the file of
/// `--stats-json`. Each key has one type in every run (a table column's cells are all numbers
/// or all strings, as `columns` says). The object used to have keys with spaces (`"Max ms"`),
/// `ID` a number, `"all"` or null, `totals` a list of prose lines, `problems` a string or null,
/// and on exit 10 it was no longer the last line on stderr.
#[test]
fn the_statistics_follow_their_schema_on_every_fixture_and_on_failures() {
    let schema = schema_file("docs/stats.v1.schema.json");
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let noise = dir.path().join("noise.bin");
    std::fs::write(&noise, [0x55u8; 300]).unwrap();
    let missing = dir.path().join("missing.bin");
    let sport = fixture("sport-sample.bin");
    let mut runs: Vec<(Vec<String>, i32)> = Vec::new();
    for (protocol, file) in [
        ("sport", "edgetx-MODELE24-2014-07-11-sport.log"),
        ("sport", "sport-sample.bin"),
        ("sbus", "sbus-digimat.pcap"),
        ("sbus", "sbus_seeds_ether.pcap"),
        ("sab2", "sab1-session.bin"),
        ("sab2", "sab2-session.bin"),
    ] {
        let f = fixture(file).to_str().unwrap().to_owned();
        runs.push((
            vec![protocol.into(), f.clone(), "-o".into(), "/dev/null".into()],
            0,
        ));
        runs.push((
            vec![
                protocol.into(),
                f,
                "-o".into(),
                "/dev/null".into(),
                "--errors".into(),
            ],
            0,
        ));
    }
    // Every protocol's own captures (named after its command), whatever their exit code.
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(fixture("."))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "bin" || x == "pcap"))
        .collect();
    files.sort();
    for p in busnoop::protocols::PROTOCOLS {
        let stem = p.command.trim_end_matches('2');
        for f in files.iter().filter(|f| {
            f.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(stem))
        }) {
            let f = f.to_str().unwrap().to_owned();
            runs.push((
                vec![p.command.into(), f, "-o".into(), "/dev/null".into()],
                -1,
            ));
        }
    }
    for extra in [["--mode", "data"], ["--mode", "break"]] {
        let f = fixture("sbus.tsv").to_str().unwrap().to_owned();
        let mut a = vec!["sbus".to_owned(), f, "-o".into(), "/dev/null".into()];
        a.extend(extra.iter().map(|s| s.to_string()));
        // A text file read as serial S-Bus: garbage, or nothing decoded.
        runs.push((a, -1));
    }
    let path = |p: &std::path::Path| p.to_str().unwrap().to_owned();
    runs.push((
        vec![
            "sport".into(),
            path(&empty),
            "-o".into(),
            "/dev/null".into(),
        ],
        10,
    ));
    runs.push((
        vec!["sab2".into(), path(&noise), "-o".into(), "/dev/null".into()],
        10,
    ));
    runs.push((vec!["sport".into(), path(&missing)], 3));
    runs.push((
        vec![
            "sport".into(),
            path(&sport),
            "-o".into(),
            "/dev/full".into(),
        ],
        8,
    ));
    let mut types: std::collections::HashMap<String, &'static str> = Default::default();
    let mut failures = 0;
    for (args, code) in &runs {
        let file = dir.path().join("stats.json");
        let _ = std::fs::remove_file(&file);
        let out = Command::cargo_bin("busnoop")
            .unwrap()
            .args(args)
            .args(["--stats-format", "json", "--stats-json"])
            .arg(&file)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        let got = out.status.code().unwrap();
        if *code >= 0 {
            assert_eq!(got, *code, "{args:?}: {err}");
        }
        failures += usize::from(got != 0);
        let last = err.lines().last().unwrap_or("");
        let v: Value = serde_json::from_str(last)
            .unwrap_or_else(|e| panic!("{args:?}: the last line is no JSON ({e}): {err}"));
        if let Err(e) = check(&schema, &v, "stats") {
            panic!("{args:?}: {e}\n{last}");
        }
        assert_eq!(v["exit"]["code"], got, "{args:?}");
        assert_eq!(v["exit"]["message"] == "", got == 0, "{args:?}: {last}");
        let in_file: Value =
            serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        assert_eq!(in_file, v, "{args:?}: the file holds the same object");
        // One type per key: a column's cells, the same key in every run.
        let declared: std::collections::HashMap<&str, &str> = v["columns"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| (c["key"].as_str().unwrap(), c["type"].as_str().unwrap()))
            .collect();
        for row in v["table"].as_array().unwrap().iter().chain([&v["all"]]) {
            for (k, x) in row.as_object().unwrap() {
                if k == "details" || k == "estimated" {
                    continue;
                }
                let t = if x.is_number() { "number" } else { "string" };
                assert_eq!(declared.get(k.as_str()), Some(&t), "{args:?}: {k} = {x}");
                let seen = types.entry(format!("{}.{k}", v["protocol"])).or_insert(t);
                assert_eq!(*seen, t, "{args:?}: {k} = {x}");
            }
        }
    }
    assert!(failures >= 4, "{failures} failing runs");
}
