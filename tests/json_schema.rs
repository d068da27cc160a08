//! The JSON Lines rows follow their documented schema (docs/jsonl-rows.v1.schema.json) on every
//! fixture, with and without --raw and --time abs.
//!
//! The checker below knows the keywords the schema uses (type, required, properties,
//! additionalProperties, minimum) and fails on any other, so the schema cannot promise more than
//! is checked.

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
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/jsonl-rows.v1.schema.json");
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
