use std::path::Path;

use super::*;
use crate::row::Part;
use crate::row::line;
use crate::row::pretty::{PRETTY_GROW_MAX, RESET};

fn sample_row() -> Row<'static> {
    Row {
        stamp: 0,
        micros: Some(4_280_999),
        id: Some(0),
        device: "Vario",
        kind: "Data",
        class: Class::Plain,
        sensor_no: "100",
        sensor: "Alt",
        data: "65.43",
        extra: &["m", "a \"quoted\", note"],
        parts: crate::row::Parts::List(&[Part {
            name: "Alt",
            unit: "m",
            text: "65.43",
            value: 65.43,
        }]),
        raw: &[0x7E, 0x00],
    }
}

fn render(format: Format, raw: bool) -> String {
    let opts = TableOptions {
        format,
        color: false,
        raw,
        time_abs: false,
        utc: false,
    };
    let mut t = Table::new(Output::memory(), opts, &["Unit", "Note"]);
    t.write(&sample_row()).unwrap();
    t.flush().unwrap();
    String::from_utf8(t.output().memory_contents().to_vec()).unwrap()
}

#[test]
fn tsv_has_header_and_fields() {
    let s = render(Format::Tsv, true);
    let lines: Vec<&str> = s.lines().collect();
    assert_eq!(
        lines[0],
        "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote\tRaw"
    );
    assert_eq!(
        lines[1],
        "1\t4280\t0\tVario\tData\t100\tAlt\t65.43\t65.43\tm\ta \"quoted\", note\t7E 00"
    );
}

#[test]
fn csv_quotes() {
    let s = render(Format::Csv, false);
    let mut r = csv::Reader::from_reader(s.as_bytes());
    let headers = r.headers().unwrap().clone();
    assert_eq!(&headers[5], "Sensor #");
    let rec = r.records().next().unwrap().unwrap();
    assert_eq!(&headers[8], "Value");
    assert_eq!(&rec[10], "a \"quoted\", note");
    assert_eq!(&rec[7], "65.43");
    assert_eq!(&rec[8], "65.43");
}

#[test]
fn jsonl_escapes() {
    let s = render(Format::Jsonl, true);
    assert_eq!(
        s.trim_end(),
        r#"{"counter":1,"millis":4280,"id":0,"device":"Vario","type":"Data","sensor_no":"100","sensor":"Alt","data":"65.43","value":65.43,"unit":"m","note":"a \"quoted\", note","parts":{"Alt":65.43},"raw":"7E 00"}"#
    );
}

#[test]
fn pretty_aligns() {
    let s = render(Format::Pretty, false);
    let lines: Vec<&str> = s.lines().collect();
    assert!(lines[0].starts_with("Counter    Millis   ID  Device"));
    assert!(lines[1].starts_with("      1      4280    0  Vario"));
}

/// Where each column of a pretty line starts (after a run of two spaces).
fn starts(line: &str) -> Vec<usize> {
    let b = line.as_bytes();
    (1..b.len())
        .filter(|&i| b[i] != b' ' && i >= 2 && b[i - 1] == b' ' && b[i - 2] == b' ')
        .collect()
}

#[test]
fn pretty_columns_come_from_the_protocol_and_grow_for_long_values() {
    let opts = TableOptions {
        format: Format::Pretty,
        color: false,
        raw: false,
        time_abs: false,
        utc: false,
    };
    let mut t = Table::new(Output::memory(), opts, &["Resp ms", "Note"]);
    t.set_pretty_widths(&[7, 8, 3, 15, 9, 9, 12, 10, 3, 0]);
    t.header().unwrap();
    let row = |device: &'static str, data: &'static str| Row {
        stamp: 0,
        micros: Some(1000),
        id: Some(10),
        device,
        kind: "Request",
        class: Class::Plain,
        sensor_no: "R0",
        sensor: "Read",
        data,
        extra: &["1.5", "note"],
        parts: crate::row::Parts::NONE,
        raw: &[],
    };
    t.write(&row("10.0.0.1:5050", "R0=1")).unwrap();
    // Longer than its column: the column grows, here and for every later row.
    t.write(&row("192.168.100.200:5050", "R0=1")).unwrap();
    t.write(&row("10.0.0.1:5050", "R0=12345678 R1=2")).unwrap();
    t.write(&row("10.0.0.1:5050", "R0=1")).unwrap();
    // Beyond the limit: this row overflows, the column keeps its width.
    let huge: &'static str = Box::leak("x".repeat(PRETTY_GROW_MAX + 1).into_boxed_str());
    t.write(&row("10.0.0.1:5050", huge)).unwrap();
    t.write(&row("10.0.0.1:5050", "R0=1")).unwrap();
    t.flush().unwrap();
    let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // The protocol's widths ("Resp ms" is wider than its 3).
    assert_eq!(
        lines[0],
        "Counter    Millis   ID  Device           Type       Sensor #   Sensor        Data        Resp ms  Note"
    );
    // The starts of the seven left-aligned columns (Device to Note).
    let left = |l: &str| {
        let s = starts(l);
        s[s.len() - 7..].to_vec()
    };
    assert_eq!(left(lines[1]), left(lines[0]), "the header's widths");
    let grown = left(lines[2]);
    assert_eq!(grown[0], left(lines[1])[0], "Device starts where it did");
    assert_eq!(
        grown[1],
        left(lines[1])[1] + "192.168.100.200:5050".len() - 15,
        "Type moves by what Device grew"
    );
    let data_grown = left(lines[3]);
    assert_eq!(data_grown[..5], grown[..5]);
    assert_eq!(data_grown[5], grown[5] + "R0=12345678 R1=2".len() - 10);
    assert_eq!(
        left(lines[4]),
        data_grown,
        "later rows keep the grown widths"
    );
    assert_eq!(
        left(lines[6]),
        data_grown,
        "an overflow does not widen the column"
    );
}

#[test]
fn csv_fields_are_quoted_as_the_csv_crate_quotes_them() {
    let fields = [
        "",
        "plain",
        "a,b",
        "say \"hi\"",
        "\"",
        "\"\"",
        "line\nbreak",
        "cr\r",
        "tab\there",
        " spaced ",
        "#hash",
        "é ü ✓",
        ",",
        "a\"b,c\"\r\nd",
    ];
    for f in fields {
        let mut ours = vec![0; 16];
        let len = line::write_line(&mut ours, 0, |w| {
            w.csv(b"x");
            w.byte(b',');
            w.csv(f.as_bytes());
            w.put(b"\r\n");
        });
        ours.truncate(len);
        let mut w = csv::WriterBuilder::new()
            .terminator(csv::Terminator::CRLF)
            .from_writer(Vec::new());
        w.write_record(["x", f]).unwrap();
        assert_eq!(
            String::from_utf8(ours).unwrap(),
            String::from_utf8(w.into_inner().unwrap()).unwrap(),
            "{f:?}"
        );
    }
}

#[test]
fn colour_codes_are_what_owo_colors_writes() {
    use owo_colors::{OwoColorize, Style};
    let s = |b: &[u8]| String::from_utf8(b.to_vec()).unwrap();
    let reset = s(RESET);
    assert_eq!(format!("{}", "x".bold()), format!("{}x{reset}", s(BOLD)));
    for (style, code) in [
        (Style::new().dimmed(), DIMMED),
        (Style::new().yellow(), YELLOW),
        (Style::new().red(), RED),
        (Style::new().cyan(), CYAN),
    ] {
        assert_eq!(
            format!("{}", "x".style(style)),
            format!("{}x{reset}", s(code))
        );
    }
}

#[test]
fn pretty_cells_replace_control_characters_and_count_chars() {
    let opts = TableOptions {
        format: Format::Pretty,
        color: true,
        raw: false,
        time_abs: false,
        utc: false,
    };
    let mut t = Table::new(Output::memory(), opts, &["Note"]);
    t.set_pretty_widths(&[7, 8, 3, 6, 4, 8, 6, 4, 4]);
    let row = Row {
        stamp: 0,
        micros: None,
        id: None,
        device: "é\tü",
        kind: "Data",
        class: Class::Error,
        sensor_no: "",
        sensor: "a\u{85}b",
        data: "",
        extra: &[""],
        parts: crate::row::Parts::NONE,
        raw: &[],
    };
    t.write(&row).unwrap();
    t.flush().unwrap();
    let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
    let line = text.lines().nth(1).unwrap();
    // Trailing blanks trimmed inside the colour; a control character is one blank.
    assert_eq!(
        line,
        "\x1b[31m      1                 é ü     Data            a b\x1b[0m"
    );
}

#[test]
fn json_numbers() {
    for ok in ["0", "12", "-1.50", "0.005", "18446744073709551615"] {
        assert!(is_json_number(ok.as_bytes()), "{ok}");
    }
    for bad in ["", "-", "01", ".5", "1.", "1e3", "0x10", "1 2", "NaN"] {
        assert!(!is_json_number(bad.as_bytes()), "{bad}");
    }
}

#[test]
fn format_from_extension() {
    assert_eq!(Format::from_path(Path::new("a.CSV")), Some(Format::Csv));
    assert_eq!(Format::from_path(Path::new("a.jsonl")), Some(Format::Jsonl));
    assert_eq!(Format::from_path(Path::new("a.bin")), None);
}

/// A sink and a tap that write down what reaches them, in order.
#[derive(Default)]
struct Log(Vec<String>);

struct LogSink<'a>(&'a std::cell::RefCell<Log>);
impl RowOut for LogSink<'_> {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        self.0.borrow_mut().0.push(format!("sink row {}", row.data));
        Ok(())
    }
    fn row_unframed(&mut self, row: &Row<'_>, _frame: &crate::row::Unframed<'_>) -> RowResult {
        self.0
            .borrow_mut()
            .0
            .push(format!("sink row {} framed", row.data));
        Ok(())
    }
}
impl Sink for LogSink<'_> {
    fn flush(&mut self) -> Result<(), OutputError> {
        self.0.borrow_mut().0.push("sink flush".into());
        Ok(())
    }
    fn close(&mut self) -> Result<(), OutputError> {
        self.0.borrow_mut().0.push("sink close".into());
        Ok(())
    }
    fn set_anchor(&mut self, anchor: Option<Anchor>) {
        self.0
            .borrow_mut()
            .0
            .push(format!("sink anchor {}", anchor.is_some()));
    }
    fn quit(&self) -> bool {
        true
    }
    fn skip(&mut self) {
        self.0.borrow_mut().0.push("sink skip".into());
    }
}

struct LogTap<'a> {
    log: &'a std::cell::RefCell<Log>,
    fail_on: Option<&'static str>,
}
impl Tap for LogTap<'_> {
    fn before_row<S: Sink + ?Sized>(
        &mut self,
        row: &Row<'_>,
        frame: Option<&crate::row::Unframed<'_>>,
        inner: &mut S,
    ) -> RowResult {
        let framed = if frame.is_some() { " framed" } else { "" };
        self.log
            .borrow_mut()
            .0
            .push(format!("tap row {}{framed}", row.data));
        if self.fail_on == Some(row.data) {
            return Err(OutputError {
                path: None,
                error: std::io::Error::from(std::io::ErrorKind::StorageFull),
            });
        }
        inner.flush()
    }
    fn flush(&mut self) -> Result<(), OutputError> {
        self.log.borrow_mut().0.push("tap flush".into());
        Ok(())
    }
    fn set_anchor(&mut self, anchor: Option<Anchor>) {
        self.log
            .borrow_mut()
            .0
            .push(format!("tap anchor {}", anchor.is_some()));
    }
}

#[test]
fn a_tap_sees_everything_first_and_the_sink_gets_the_rest() {
    let log = std::cell::RefCell::new(Log::default());
    let mut sink = LogSink(&log);
    let mut t = Tapped {
        inner: &mut sink,
        tap: LogTap {
            log: &log,
            fail_on: Some("bad"),
        },
    };
    t.set_anchor(Some(Anchor::Instant(chrono::DateTime::UNIX_EPOCH)));
    t.row(&sample_row()).unwrap();
    let frame = crate::row::Unframed {
        bytes: &[0, 10, 6],
        bad_check: None,
    };
    t.row_unframed(&sample_row(), &frame).unwrap();
    t.skip();
    let bad = Row {
        stamp: 0,
        data: "bad",
        ..sample_row()
    };
    assert!(t.row(&bad).is_err(), "the tap's error comes back");
    assert!(t.quit(), "quit is the sink's");
    t.flush().unwrap();
    t.close().unwrap();
    assert_eq!(
        log.into_inner().0,
        [
            "tap anchor true",
            "sink anchor true",
            "tap row 65.43",
            "sink flush",
            "sink row 65.43",
            "tap row 65.43 framed",
            "sink flush",
            "sink row 65.43 framed",
            "sink skip",
            "tap row bad",
            "tap flush",
            "sink flush",
            "tap flush",
            "sink close",
        ]
    );
}

/// Blanks are held back until text follows; a line's end is trimmed as `str::trim_end` trims
/// it, also when the last text itself ends in whitespace (ASCII, Unicode, or a control
/// character shown as a blank), with or without colour.
#[test]
fn pretty_lines_end_as_trim_end_leaves_them() {
    for color in [false, true] {
        for (data, note, end) in [
            ("abc", "", "abc"),
            ("abc  ", "", "abc"),
            ("abc", "n\u{a0}", "n"),
            ("abc", "n\u{2003} \t", "n"),
            ("abc", "x\u{85}", "x"),
            ("", "", "Data"),
            ("ü ", "", "ü"),
        ] {
            let opts = TableOptions {
                format: Format::Pretty,
                color,
                raw: false,
                time_abs: false,
                utc: false,
            };
            let mut t = Table::new(Output::memory(), opts, &["Unit", "Note"]);
            let extra = ["", note];
            let row = Row {
                stamp: 0,
                micros: Some(1000),
                id: Some(1),
                device: "Dev",
                kind: "Data",
                class: Class::Warning,
                sensor_no: "",
                sensor: "",
                data,
                extra: &extra,
                parts: crate::row::Parts::NONE,
                raw: &[],
            };
            t.write(&row).unwrap();
            t.flush().unwrap();
            let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
            let line = text.lines().nth(1).unwrap();
            let line = if color {
                line.strip_prefix("\x1b[33m")
                    .and_then(|l| l.strip_suffix("\x1b[0m"))
                    .unwrap()
            } else {
                line
            };
            assert!(line.ends_with(end), "{data:?} {note:?}: {line:?}");
            assert_eq!(line, line.trim_end(), "{data:?} {note:?}");
        }
    }
}

/// A row longer than the output buffer's room is written whole, in every format.
#[test]
fn rows_longer_than_the_room_are_whole() {
    let long = "x".repeat(300_000);
    for format in [Format::Tsv, Format::Csv, Format::Jsonl, Format::Pretty] {
        let opts = TableOptions {
            format,
            color: false,
            raw: false,
            time_abs: false,
            utc: false,
        };
        let mut t = Table::new(Output::memory(), opts, &["Note"]);
        let extra = [long.as_str()];
        let mut row = sample_row();
        row.extra = &extra;
        for _ in 0..3 {
            t.write(&row).unwrap();
        }
        t.flush().unwrap();
        let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
        let rows: Vec<&str> = text.lines().filter(|l| l.contains(&long)).collect();
        assert_eq!(rows.len(), 3, "{format:?}");
    }
}

/// Rows for the stamp tests: stamps repeat, with cells that need escaping, empty cells, a
/// missing Millis, a cell that widens a pretty column between two rows of one stamp, and a
/// span too long to keep.
fn stamped_rows() -> Vec<Row<'static>> {
    let base = sample_row();
    let long: &'static str = "a sensor name long enough that the span of its cells, ID to Sensor, is \
                               longer than a slot of the cache can hold, in every format";
    let mut rows = vec![
        Row { stamp: 1, ..base },
        Row {
            stamp: 2,
            id: Some(27),
            device: "Dev\tice, \"q\"",
            kind: "Bad\u{7}",
            sensor_no: "",
            sensor: "Höhe",
            data: "1,5",
            ..base
        },
        Row {
            stamp: 3,
            id: None,
            device: "",
            kind: "",
            sensor_no: "",
            sensor: "",
            ..base
        },
        Row {
            stamp: 4,
            micros: None,
            ..base
        },
        Row {
            stamp: 5,
            sensor: long,
            ..base
        },
    ];
    // Every stamp again, then a row that widens the Device column, then every stamp again.
    let again = rows.clone();
    rows.extend(again.iter().copied());
    rows.push(Row {
        stamp: 6,
        device: "A device name that widens its column",
        ..base
    });
    rows.extend(again.iter().map(|r| Row {
        micros: r.micros.map(|us| us + 1_000_000),
        ..*r
    }));
    rows.push(Row {
        stamp: 4,
        micros: Some(5),
        ..base
    });
    rows
}

fn render_rows(format: Format, color: bool, rows: &[Row<'_>]) -> (String, Table) {
    let mut t = crate::testing::memory_table(format, color, &["Unit", "Note"]);
    for r in rows {
        t.write(r).unwrap();
    }
    t.flush().unwrap();
    let s = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
    (s, t)
}

#[test]
fn stamped_rows_are_written_as_unstamped_ones() {
    let stamped = stamped_rows();
    let plain: Vec<Row<'_>> = stamped.iter().map(|r| Row { stamp: 0, ..*r }).collect();
    for (format, color) in [
        (Format::Tsv, false),
        (Format::Csv, false),
        (Format::Jsonl, false),
        (Format::Pretty, false),
        (Format::Pretty, true),
    ] {
        let (with, t) = render_rows(format, color, &stamped);
        let (without, _) = render_rows(format, color, &plain);
        assert_eq!(with, without, "{format:?}, colour {color}");
        // The spans were kept (and so copied for the rows after): stamp 1 in every format,
        // never the span too long for a slot.
        let widths = t.text.widths[2..7].iter().sum::<usize>() as u32;
        let widths = if format == Format::Pretty { widths } else { 0 };
        assert!(t.text.spans.get(1, widths).is_some(), "{format:?}");
        assert!(t.text.spans.get(5, widths).is_none(), "{format:?}");
    }
}

#[cfg(debug_assertions)]
#[test]
#[should_panic(expected = "differ in the cells ID to Sensor")]
fn a_stamp_on_rows_that_differ_fails_in_debug_builds() {
    let base = sample_row();
    let rows = [
        Row { stamp: 9, ..base },
        Row {
            stamp: 9,
            sensor: "Other",
            ..base
        },
    ];
    render_rows(Format::Tsv, false, &rows);
}
