//! The Value column and typed JSON Lines (issue 13): what a spreadsheet and a script read.

mod common;

use assert_cmd::Command;
use common::fixture;

fn run(args: &[&str]) -> Vec<u8> {
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

const CAPTURES: [(&str, &str); 5] = [
    ("sport", "edgetx-MODELE24-2014-07-11-sport.log"),
    ("sport", "sport-sample.bin"),
    ("sbus", "sbus-digimat.pcap"),
    ("sab2", "sab1-session.bin"),
    ("sab2", "sab2-session.bin"),
];

/// SAB with declared types (`--value`): scaled integers and floats are numbers too.
const SAB_DECLARED: [&str; 8] = [
    "--command",
    "distance=0x10",
    "--value",
    "distance=u16*0.01:m",
    "--value",
    "0x34=f32*0.5:deg",
    "--value",
    "2=i8*-0.1",
];

/// The spreadsheet check: every non-empty Value cell of every fixture parses as a number, and
/// the Value column sits right after Data.
#[test]
fn every_value_cell_is_a_number() {
    let mut numbers = 0;
    let declared = CAPTURES[3..].iter().map(|c| (c, &SAB_DECLARED[..]));
    let runs = CAPTURES.iter().map(|c| (c, &[][..])).chain(declared);
    for (&(protocol, file), options) in runs {
        let path = fixture(file);
        let mut args = vec![protocol, path.to_str().unwrap(), "-f", "csv"];
        args.extend_from_slice(options);
        let csv = run(&args);
        let mut r = csv::Reader::from_reader(csv.as_slice());
        let headers = r.headers().unwrap().clone();
        assert_eq!(&headers[7], "Data");
        assert_eq!(&headers[8], "Value");
        for rec in r.records() {
            let rec = rec.unwrap();
            let v = &rec[8];
            if v.is_empty() {
                continue;
            }
            let n: f64 = v
                .parse()
                .unwrap_or_else(|_| panic!("{file}: Value {v:?} is not a number: {rec:?}"));
            assert!(n.is_finite());
            numbers += 1;
        }
    }
    // The EdgeTX capture alone has 131 data frames, all with a number.
    assert!(numbers >= 131, "{numbers}");
}

#[test]
fn edgetx_capture_values_have_full_precision() {
    let path = fixture("edgetx-MODELE24-2014-07-11-sport.log");
    let tsv = String::from_utf8(run(&["sport", path.to_str().unwrap(), "-f", "tsv"])).unwrap();
    let rows: Vec<Vec<&str>> = tsv
        .lines()
        .skip(1)
        .map(|l| l.split('\t').collect())
        .collect();
    let data: Vec<&Vec<&str>> = rows.iter().filter(|r| r[4] == "Data").collect();
    assert_eq!(data.len(), 131);
    assert!(
        data.iter().all(|r| !r[8].is_empty()),
        "every data frame has a Value"
    );
    // The first FLVSS frame of physical ID 1: cells 0x80D and 0x818 in 2 mV units.
    let cels = data
        .iter()
        .find(|r| r[2] == "1" && r[6] == "Cels" && r[7].contains("cell1"))
        .unwrap();
    assert_eq!(cels[7], "count=3 cell1=4.122 cell2=4.144");
    assert_eq!((cels[8], cels[9]), ("4.122", "V"));
    let rssi = data.iter().find(|r| r[6] == "RSSI").unwrap();
    assert_eq!(rssi[9], "dB");
    // Polls carry no number.
    assert!(
        rows.iter()
            .filter(|r| r[4].is_empty())
            .all(|r| r[8].is_empty())
    );
}

#[test]
fn json_lines_are_typed() {
    let path = fixture("edgetx-MODELE24-2014-07-11-sport.log");
    let out = String::from_utf8(run(&["sport", path.to_str().unwrap(), "-f", "jsonl"])).unwrap();
    let mut cells = 0;
    for line in out.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let o = v.as_object().unwrap();
        assert!(o["counter"].is_u64() && o["millis"].is_u64());
        // Empty cells are null, never "".
        for (k, x) in o {
            assert_ne!(x.as_str(), Some(""), "{k} in {line}");
        }
        match o["type"].as_str() {
            Some("Data") => {
                assert!(o["value"].is_number(), "{line}");
                let parts = o["parts"].as_object().unwrap();
                assert!(parts.values().all(serde_json::Value::is_number), "{line}");
                // The Value is the first part.
                assert_eq!(parts.values().next().unwrap(), &o["value"], "{line}");
                if o["sensor"] == "Cels" && parts.len() == 2 && o["id"] == 1 {
                    assert_eq!(line.matches("\"Cell1\":4.122,\"Cell2\":4.144").count(), 1);
                    cells += 1;
                }
            }
            _ => {
                assert!(o["value"].is_null(), "{line}");
                assert!(!o.contains_key("parts"), "{line}");
            }
        }
    }
    assert!(cells > 0);
    // S-Bus: the response time and sequence are numbers.
    let path = fixture("sbus-digimat.pcap");
    let out = String::from_utf8(run(&["sbus", path.to_str().unwrap(), "-f", "jsonl"])).unwrap();
    let second: serde_json::Value = serde_json::from_str(out.lines().nth(1).unwrap()).unwrap();
    assert_eq!(second["resp_ms"], 71.5);
    assert_eq!(second["seq"], 1);
}
