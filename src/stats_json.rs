//! The statistics as one JSON object (`--stats-format json`, `--stats-json FILE`), following
//! the versioned schema `docs/stats.v1.schema.json`:
//!
//! ```json
//! {"schema":"busnoop-stats.v1","protocol":"S.Port","rows":592,"shown":131,"hidden":461,
//!  "valid_frames":131,"head":["…"],
//!  "columns":[{"key":"id","name":"ID","type":"number"},{"key":"device","name":"Device","type":"string"},…],
//!  "table":[{"id":1,"device":"FLVSS","polls":53,"answers":51,…,"mean_ms":135.8}],
//!  "all":{"polls":592,…},
//!  "totals":{"valid_frames":131,"garbage_bytes":0,…},
//!  "problems":{"crc_errors":0,"truncated_frames":0,…},"notes":[],"summary":"",
//!  "exit":{"code":0,"message":""}}
//! ```
//!
//! Keys are snake case; a key has one type: a table cell of a numeric column is a number (an
//! empty cell or `-` leaves the key out), of a text column a string; `totals` and `problems` are
//! objects of counts. The object is written when the run ends, whatever the end: after the
//! failure's message, so that it is the last line on stderr also on exit 10 or a failed write
//! ([`finish`]); a run that fails before decoding writes it with zero counts.

use std::io::Write;
use std::path::PathBuf;
use std::sync::Mutex;

use serde_json::{Map, Value, json};

use crate::stats::{Problems, Report, ReportRow};

/// The schema's name and version (the file `docs/stats.v1.schema.json`).
pub const SCHEMA: &str = "busnoop-stats.v1";

/// Where the object goes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Destinations {
    /// The last line on stderr (`--stats-format json`).
    pub stderr: bool,
    /// A file (`--stats-json FILE`).
    pub file: Option<PathBuf>,
}

impl Destinations {
    pub fn any(&self) -> bool {
        self.stderr || self.file.is_some()
    }
}

struct Pending {
    to: Destinations,
    object: Map<String, Value>,
}

/// The object of this run, written by [`finish`].
static PENDING: Mutex<Option<Pending>> = Mutex::new(None);

fn pending() -> std::sync::MutexGuard<'static, Option<Pending>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// The run of `protocol` writes its statistics as JSON to `to`: until the decoder's report
/// comes ([`record`]), an object with zero counts stands for it (a run that fails before
/// decoding still writes one).
pub fn expect(to: Destinations, protocol: &str) {
    if !to.any() {
        return;
    }
    let object = object(&Report::default(), protocol, 0, 0, 0, &Problems::new(""));
    *pending() = Some(Pending { to, object });
}

/// The decoder's report and the run's counts, for [`finish`].
pub fn record(
    report: &Report,
    protocol: &str,
    rows: u64,
    hidden: u64,
    valid_frames: u64,
    problems: &Problems,
) {
    if let Some(p) = pending().as_mut() {
        p.object = object(report, protocol, rows, hidden, valid_frames, problems);
    }
}

/// Writes the object, after every other message, with the run's exit code and failure
/// message (empty on success); returns the exit code, which becomes that of a failed write
/// (8) when the statistics file cannot be written after a run that went well.
/// What one port of a run with several sources reports (`record_ports`).
pub struct PortReport<'a> {
    pub port: &'a str,
    pub report: Report,
    pub rows: u64,
    pub hidden: u64,
    pub valid_frames: u64,
    pub problems: Problems,
}

/// The statistics of a run with several sources: the whole run's counts (rows, valid frames,
/// problems and totals summed over the ports) with each port's own object under `ports`
/// (docs/stats.v1.schema.json).
pub fn record_ports(protocol: &str, ports: &[PortReport<'_>]) {
    let mut guard = pending();
    let Some(p) = guard.as_mut() else {
        return;
    };
    let rows: u64 = ports.iter().map(|p| p.rows).sum();
    let hidden: u64 = ports.iter().map(|p| p.hidden).sum();
    let valid: u64 = ports.iter().map(|p| p.valid_frames).sum();
    let mut whole = object(
        &Report::default(),
        protocol,
        rows,
        hidden,
        valid,
        &Problems::new(""),
    );
    let mut problems: Vec<(&'static str, u64)> = Vec::new();
    let mut totals: Vec<(&'static str, u64)> = Vec::new();
    let mut list = Vec::new();
    for port in ports {
        for &(k, n) in port.problems.counts() {
            add(&mut problems, k, n);
        }
        for &(k, n) in &port.report.counts {
            add(&mut totals, k, n);
        }
        let mut o = object(
            &port.report,
            protocol,
            port.rows,
            port.hidden,
            port.valid_frames,
            &port.problems,
        );
        o.remove("schema");
        o.insert("port".into(), Value::String(port.port.to_owned()));
        list.push(Value::Object(o));
    }
    whole.insert("problems".into(), counts(&problems));
    whole.insert("totals".into(), counts(&totals));
    let summary: Vec<String> = ports
        .iter()
        .filter_map(|p| Some(format!("{}: {}", p.port, p.problems.line()?)))
        .collect();
    whole.insert("summary".into(), Value::String(summary.join("; ")));
    whole.insert("ports".into(), Value::Array(list));
    p.object = whole;
}

fn add(list: &mut Vec<(&'static str, u64)>, key: &'static str, n: u64) {
    match list.iter_mut().find(|(k, _)| *k == key) {
        Some(c) => c.1 += n,
        None => list.push((key, n)),
    }
}

pub fn finish(code: u8, message: &str) -> u8 {
    let Some(Pending { to, mut object }) = pending().take() else {
        return code;
    };
    let line = |object: &mut Map<String, Value>, code: u8, message: &str| {
        object.insert("exit".into(), json!({ "code": code, "message": message }));
        Value::Object(object.clone()).to_string()
    };
    let (mut code, mut message) = (code, message.to_owned());
    if let Some(path) = &to.file {
        let text = line(&mut object, code, &message);
        let written = std::fs::File::create(path).and_then(|mut f| {
            f.write_all(text.as_bytes())?;
            f.write_all(b"\n")
        });
        if let Err(e) = written {
            let failed = format!("cannot write the statistics to {}: {e}", path.display());
            eprintln!("busnoop: {failed}");
            if code == crate::exit::code::OK {
                (code, message) = (crate::exit::code::OUTPUT, failed);
            }
        }
    }
    if to.stderr {
        eprintln!("{}", line(&mut object, code, &message));
    }
    code
}

/// Whether this run writes its statistics as JSON.
pub fn wanted() -> bool {
    pending().is_some()
}

/// A cell of a numeric column: its number (`12`, `12.5`, `0xC8`; `~12.5` is an estimate), or nothing
/// for an empty cell or `-`.
fn number(text: &str) -> Option<(Value, bool)> {
    let t = text.trim();
    let (t, estimated) = match t.strip_prefix('~') {
        Some(rest) => (rest, true),
        None => (t, false),
    };
    if t.is_empty() || t == "-" {
        return None;
    }
    if let Ok(i) = t.parse::<i64>() {
        return Some((Value::from(i), estimated));
    }
    // An ID or code shown in hex (`0xC8`) is the same number.
    if let Some(h) = t.strip_prefix("0x")
        && let Ok(i) = i64::from_str_radix(h, 16)
    {
        return Some((Value::from(i), estimated));
    }
    t.parse::<f64>()
        .ok()
        .filter(|f| f.is_finite())
        .map(|f| (Value::from(f), estimated))
}

/// A table row as an object keyed by the columns' JSON keys; `skip`: the leading cells left
/// out (the `all` row's ID and Device).
fn row_object(report: &Report, cells: &[String], skip: usize) -> Map<String, Value> {
    let mut obj = Map::new();
    let mut estimated = Vec::new();
    for (c, col) in cells.iter().zip(&report.columns).skip(skip) {
        let key = col.json_key();
        if col.numeric() {
            match number(c) {
                Some((v, est)) => {
                    if est {
                        estimated.push(Value::String(key.clone()));
                    }
                    obj.insert(key, v);
                }
                None => debug_assert!(
                    c.trim().is_empty() || c.trim() == "-",
                    "column {} holds {c:?}, not a number",
                    col.name
                ),
            }
        } else if !c.trim().is_empty() {
            obj.insert(key, Value::String(c.clone()));
        }
    }
    if !estimated.is_empty() {
        obj.insert("estimated".into(), Value::Array(estimated));
    }
    obj
}

fn counts(list: &[(&'static str, u64)]) -> Value {
    let mut obj = Map::new();
    for &(k, n) in list {
        // A counter asked about twice keeps its sum (never happens with the protocols' keys).
        let sum = obj.get(k).and_then(Value::as_u64).unwrap_or(0) + n;
        obj.insert(k.to_owned(), Value::from(sum));
    }
    Value::Object(obj)
}

/// The report and the run's counts as the schema's object (without `exit`).
fn object(
    report: &Report,
    protocol: &str,
    rows: u64,
    hidden: u64,
    valid_frames: u64,
    problems: &Problems,
) -> Map<String, Value> {
    let mut table: Vec<Value> = Vec::new();
    let mut all = Map::new();
    for line in &report.rows {
        match line {
            ReportRow::Cells(cells) => table.push(Value::Object(row_object(report, cells, 0))),
            ReportRow::Total(cells) => all = row_object(report, cells, 2),
            ReportRow::Detail(text) => {
                if let Some(Value::Object(last)) = table.last_mut() {
                    let details = last
                        .entry("details")
                        .or_insert_with(|| Value::Array(Vec::new()));
                    if let Value::Array(a) = details {
                        a.push(Value::String(text.clone()));
                    }
                }
            }
        }
    }
    let columns: Vec<Value> = report
        .columns
        .iter()
        .map(|c| {
            json!({
                "key": c.json_key(),
                "name": c.name,
                "type": if c.numeric() { "number" } else { "string" },
            })
        })
        .collect();
    let obj = json!({
        "schema": SCHEMA,
        "protocol": protocol,
        "rows": rows,
        "shown": rows - hidden.min(rows),
        "hidden": hidden,
        "valid_frames": valid_frames,
        "head": report.head,
        "columns": columns,
        "table": table,
        "all": all,
        "totals": counts(&report.counts),
        "problems": counts(problems.counts()),
        "notes": problems.notes(),
        "summary": problems.line().unwrap_or_default(),
    });
    match obj {
        Value::Object(m) => m,
        _ => Map::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::Column;

    #[test]
    fn cells_become_numbers_keys_snake_case_and_the_total_apart() {
        let mut r = Report::new(&[
            Column::right("ID", 3),
            Column::left("Device", 10),
            Column::right("Mean ms", 8),
            Column::left("NACK codes", 0),
        ]);
        r.row(vec![
            "1".into(),
            "FLVSS".into(),
            "12.5".into(),
            "x 1".into(),
        ]);
        r.detail("late 2".into());
        r.row(vec!["2".into(), String::new(), "~3.5".into()]);
        r.row(vec!["3".into(), String::new(), "-".into()]);
        r.total_row(vec!["all".into(), String::new(), "7".into()]);
        r.totals.push("valid frames 3".into());
        r.counts(&[("valid_frames", 3)]);
        let mut p = Problems::new("X");
        p.count("crc_errors", 0, "CRC error", "CRC errors")
            .count("timeouts", 2, "timeout", "timeouts")
            .item("no valid frame");
        let v = Value::Object(object(&r, "S.Port", 10, 4, 3, &p));
        assert_eq!(v["schema"], SCHEMA);
        assert_eq!(v["shown"], 6);
        assert_eq!(v["table"][0]["id"], 1);
        assert_eq!(v["table"][0]["mean_ms"], 12.5);
        assert_eq!(v["table"][0]["nack_codes"], "x 1");
        assert_eq!(v["table"][0]["details"][0], "late 2");
        assert_eq!(v["table"][1]["mean_ms"], 3.5);
        assert_eq!(v["table"][1]["estimated"][0], "mean_ms");
        assert!(v["table"][1].get("device").is_none());
        assert!(v["table"][2].get("mean_ms").is_none());
        assert_eq!(v["table"].as_array().unwrap().len(), 3);
        assert_eq!(v["all"], json!({"mean_ms": 7}));
        assert_eq!(v["totals"], json!({"valid_frames": 3}));
        assert_eq!(v["problems"], json!({"crc_errors": 0, "timeouts": 2}));
        assert_eq!(v["notes"], json!(["no valid frame"]));
        assert_eq!(v["summary"], "X: 2 timeouts, no valid frame");
        assert_eq!(
            v["columns"][2],
            json!({"key": "mean_ms", "name": "Mean ms", "type": "number"})
        );
    }
}
