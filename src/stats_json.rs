//! `--stats-format json`: the statistics ([`crate::stats::Report`]) as one JSON object.
//!
//! ```json
//! {"protocol":"S.Port","rows":592,"shown":131,"hidden":461,"valid_frames":131,
//!  "head":[],"columns":["ID","Device","Polls",...],
//!  "table":[{"ID":1,"Device":"FLVSS","Polls":35,...,"details":["..."]}],
//!  "totals":["valid frames 131, ..."],"problems":null}
//! ```
//!
//! Table cells keep the text's column names as keys; a cell that reads as a number becomes a
//! JSON number, an empty cell or `-` becomes `null`. Detail lines under a row are its
//! `details`. `problems` is the one problems line, or `null`.

use serde_json::{Map, Value, json};

use crate::stats::{Report, ReportRow};

/// A cell as a JSON value.
fn cell(text: &str) -> Value {
    let t = text.trim();
    if t.is_empty() || t == "-" {
        return Value::Null;
    }
    if let Ok(i) = t.parse::<i64>() {
        return Value::from(i);
    }
    if t.bytes()
        .all(|b| b.is_ascii_digit() || b == b'.' || b == b'-')
        && let Ok(f) = t.parse::<f64>()
        && f.is_finite()
    {
        return Value::from(f);
    }
    Value::String(text.to_owned())
}

/// The report and the run's counts as one line of JSON.
pub fn to_json(
    report: &Report,
    protocol: &str,
    rows: u64,
    hidden: u64,
    valid_frames: u64,
    problems: Option<&str>,
) -> String {
    let mut table: Vec<Value> = Vec::new();
    for line in &report.rows {
        match line {
            ReportRow::Cells(cells) => {
                let mut obj = Map::new();
                for (c, col) in cells.iter().zip(&report.columns) {
                    obj.insert(col.name.to_owned(), cell(c));
                }
                table.push(Value::Object(obj));
            }
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
    let columns: Vec<&str> = report.columns.iter().map(|c| c.name).collect();
    json!({
        "protocol": protocol,
        "rows": rows,
        "shown": rows - hidden.min(rows),
        "hidden": hidden,
        "valid_frames": valid_frames,
        "head": report.head,
        "columns": columns,
        "table": table,
        "totals": report.totals,
        "problems": problems,
    })
    .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::Column;

    #[test]
    fn cells_become_numbers_nulls_and_details() {
        let mut r = Report::new(&[
            Column::right("ID", 3),
            Column::left("Device", 10),
            Column::right("Mean ms", 8),
        ]);
        r.row(vec!["1".into(), "FLVSS".into(), "12.5".into()]);
        r.detail("late 2".into());
        r.row(vec!["all".into(), String::new(), "-".into()]);
        r.totals.push("valid frames 3".into());
        let v: Value = serde_json::from_str(&to_json(&r, "S.Port", 10, 4, 3, None)).unwrap();
        assert_eq!(v["shown"], 6);
        assert_eq!(v["table"][0]["ID"], 1);
        assert_eq!(v["table"][0]["Mean ms"], 12.5);
        assert_eq!(v["table"][0]["details"][0], "late 2");
        assert_eq!(v["table"][1]["ID"], "all");
        assert!(v["table"][1]["Device"].is_null() && v["table"][1]["Mean ms"].is_null());
        assert!(v["problems"].is_null());
        assert_eq!(v["columns"][2], "Mean ms");
    }
}
