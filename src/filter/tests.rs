use super::*;
use crate::row::{Part, Parts};

fn no_hint(_: u32) -> Option<String> {
    None
}

fn sensors() -> Vec<Sensor> {
    vec![
        Sensor::named("Alt"),
        Sensor {
            column: "Cels".into(),
            parts: (1..=6).map(|i| format!("Cell{i}")).collect(),
        },
        Sensor::named("RxBt"),
        Sensor {
            column: "Volts".into(),
            parts: vec!["VFAS".into()],
        },
    ]
}

fn hex_no(s: &str) -> bool {
    parse_hex(s).is_some_and(|n| n <= 0xFFFF)
}

fn device(id: u32) -> &'static str {
    ["Vario", "FLVSS", ""][id as usize % 3]
}

const VOCAB: Vocab = Vocab {
    ids: Some(0..=31),
    id_name: "physical ID",
    id_hint: no_hint,
    types: &["Data", "Null", "BadCRC", "Garbage"],
    polls: true,
    keepalives: true,
    sensors,
    sensor_no_text: "app IDs in hex",
    sensor_no: hex_no,
    sensor_no_hex: true,
    devices: Some(device),
};

fn spec(f: impl FnOnce(&mut Spec)) -> Spec {
    let mut s = Spec::default();
    f(&mut s);
    s
}

fn filter(s: &Spec) -> Result<Filter, Error> {
    let names = Names::parse(&s.names, "--name", &VOCAB)?;
    Filter::new(s, &VOCAB, &names, &[], "S.Port")
}

fn row(id: Option<u32>, kind: &'static str, class: Class) -> Row<'static> {
    Row {
        stamp: 0,
        id,
        kind,
        class,
        device: "FLVSS",
        sensor_no: "0x0210",
        sensor: "Cels",
        ..Row::empty(Some(0))
    }
}

/// The live view's `f` filter: the command line's options as words, checked as there; a
/// bare number is an ID (it used to be a substring: `1` also kept ID 24).
#[test]
fn words_are_the_command_lines_filters() {
    let words = |t: &str| Filter::from_words(t, &VOCAB, &Names::default(), &[], "S.Port");
    let at = |id: u32| Row {
        id: Some(id),
        ..row(None, "Data", Class::Plain)
    };
    for text in ["id=1", "1", "--id 1", "--id=1", "ID:1"] {
        let f = words(text).unwrap();
        assert!(f.keep(&at(1)), "{text}");
        assert!(!f.keep(&at(24)) && !f.keep(&at(11)), "{text}");
    }
    let f = words("sensor=VFAS not-id=2 type=Data").unwrap();
    let volts = Row {
        sensor: "Volts",
        ..at(1)
    };
    assert!(
        f.keep(&volts)
            && !f.keep(&at(1))
            && !f.keep(&Row {
                id: Some(2),
                ..volts
            })
    );
    // A bare word: a sensor by either name, else a device.
    assert!(words("volts").unwrap().keep(&volts));
    let f = words("vario").unwrap();
    assert!(
        f.keep(&Row {
            device: "Vario",
            ..at(0)
        }) && !f.keep(&at(0))
    );
    assert!(
        words("errors")
            .unwrap()
            .keep(&row(Some(1), "BadCRC", Class::Error))
    );
    assert!(!words("errors").unwrap().keep(&at(1)));
    // Refused with the reason, as on the command line.
    assert!(words("id=40").unwrap_err().contains("outside"));
    assert!(words("type=Pol").unwrap_err().contains("types:"));
    assert!(words("colour=red").unwrap_err().contains("not a filter"));
    assert!(
        words("nosuchthing")
            .unwrap_err()
            .contains("no S.Port sensor or device")
    );
    assert!(words("id").unwrap_err().contains("give a value"));
}

#[test]
fn no_rule_keeps_everything() {
    let f = filter(&Spec::default()).unwrap();
    assert!(!f.is_active());
    assert!(f.keep(&row(None, "Garbage", Class::Error)));
}

#[test]
fn ids_lists_ranges_and_hex() {
    let f = filter(&spec(|s| {
        s.id = vec!["2,8".into(), "0x1B".into(), "10-12".into()]
    }))
    .unwrap();
    for (id, keep) in [
        (2, true),
        (8, true),
        (27, true),
        (11, true),
        (3, false),
        (13, false),
    ] {
        assert_eq!(f.keep(&row(Some(id), "Data", Class::Plain)), keep, "{id}");
    }
    assert!(
        !f.keep(&row(None, "Garbage", Class::Error)),
        "no ID, no match"
    );
    let f = filter(&spec(|s| s.not_id = vec!["0-9".into()])).unwrap();
    assert!(!f.keep(&row(Some(3), "Data", Class::Plain)));
    assert!(f.keep(&row(Some(10), "Data", Class::Plain)));
    assert!(
        f.keep(&row(None, "Garbage", Class::Error)),
        "no ID is not excluded"
    );
}

#[test]
fn id_errors_name_the_range() {
    let e = filter(&spec(|s| s.id = vec!["40".into()])).unwrap_err();
    assert!(e.contains("0-31 (0x00-0x1F)"), "{e}");
    let e = filter(&spec(|s| s.id = vec!["x".into()])).unwrap_err();
    assert!(e.contains("expected IDs like"), "{e}");
    let e = filter(&spec(|s| s.id = vec!["9-2".into()])).unwrap_err();
    assert!(e.contains("empty"), "{e}");
}

#[test]
fn types_are_case_insensitive_and_checked() {
    let f = filter(&spec(|s| s.types = vec!["data,badcrc".into()])).unwrap();
    assert!(f.keep(&row(Some(1), "Data", Class::Plain)));
    assert!(f.keep(&row(Some(1), "BadCRC", Class::Error)));
    assert!(!f.keep(&row(Some(1), "Null", Class::Quiet)));
    assert!(
        !f.keep(&row(Some(1), "", Class::Plain)),
        "a poll is not Data"
    );
    let f = filter(&spec(|s| s.types = vec!["poll".into()])).unwrap();
    assert!(f.keep(&row(Some(1), "", Class::Plain)));
    assert!(!f.keep(&row(Some(1), "Data", Class::Plain)));
    let e = filter(&spec(|s| s.types = vec!["Dta".into()])).unwrap_err();
    assert!(
        e.contains("types: Data, Null, BadCRC, Garbage, Poll"),
        "{e}"
    );
    let f = filter(&spec(|s| s.not_types = vec!["Null".into()])).unwrap();
    assert!(!f.keep(&row(Some(1), "Null", Class::Quiet)));
}

#[test]
fn shortcuts() {
    let f = filter(&spec(|s| s.hide_polls = true)).unwrap();
    assert!(!f.keep(&row(Some(1), "", Class::Plain)));
    assert!(f.keep(&row(Some(1), "Data", Class::Plain)));
    let f = filter(&spec(|s| s.hide_null = true)).unwrap();
    assert!(!f.keep(&row(Some(1), "Null", Class::Quiet)));
    let f = filter(&spec(|s| s.errors = true)).unwrap();
    assert!(f.keep(&row(Some(1), "BadCRC", Class::Error)));
    assert!(f.keep(&row(Some(1), "Data", Class::Warning)));
    assert!(
        f.keep(&row(None, "LinkDown", Class::Info)),
        "gaps stay visible"
    );
    assert!(!f.keep(&row(Some(1), "Data", Class::Plain)));
    let no_polls = Vocab {
        polls: false,
        keepalives: false,
        ..VOCAB
    };
    let names = Names::default();
    let e = Filter::new(
        &spec(|s| s.hide_polls = true),
        &no_polls,
        &names,
        &[],
        "S-Bus",
    )
    .unwrap_err();
    assert!(e.contains("S-Bus has no polls"), "{e}");
    // A stream of frames is not told about requests and answers.
    let stream = Vocab {
        types: &["GPS", "RC", "Link"],
        polls: false,
        ..VOCAB
    };
    let e = Filter::new(&spec(|s| s.hide_polls = true), &stream, &names, &[], "CRSF").unwrap_err();
    assert!(
        e.contains("frames come unasked") && e.contains("--not-type RC") && !e.contains("request"),
        "{e}"
    );
    let e = Filter::new(
        &spec(|s| s.hide_null = true),
        &no_polls,
        &names,
        &[],
        "S-Bus",
    )
    .unwrap_err();
    assert!(e.contains("no keep-alive"), "{e}");
}

#[test]
fn sensors_by_name_or_number() {
    let f = filter(&spec(|s| s.sensor = vec!["cels".into()])).unwrap();
    assert!(f.keep(&row(Some(1), "Data", Class::Plain)));
    // The new notation and the S-Port_Snoop sample's (`210`) select the same rows.
    for v in ["0x0210", "0X0210", "0210", "210", "0x210"] {
        let f = filter(&spec(|s| s.sensor = vec![v.into()])).unwrap();
        assert!(f.keep(&row(Some(1), "Data", Class::Plain)), "{v}");
    }
    let f = filter(&spec(|s| s.sensor = vec!["Alt".into()])).unwrap();
    assert!(!f.keep(&row(Some(1), "Data", Class::Plain)));
    let e = filter(&spec(|s| s.sensor = vec!["VFAZ".into()])).unwrap_err();
    assert!(e.contains("did you mean VFAS?"), "{e}");
    assert!(e.contains("Sensor column: Alt, Cels, RxBt, Volts;"), "{e}");
    // Either name of a sensor selects its rows: the table's and the radio's.
    for v in ["Cels", "cell3", "CELL1"] {
        let f = filter(&spec(|s| s.sensor = vec![v.into()])).unwrap();
        assert!(f.keep(&row(Some(1), "Data", Class::Plain)), "{v}");
    }
    let f = filter(&spec(|s| s.sensor = vec!["VFAS".into()])).unwrap();
    assert!(!f.keep(&row(Some(1), "Data", Class::Plain)));
    // A number's name selects the rows that carry it and its sensor's column, not the rows
    // of other sensors that share an entry's other names.
    let parts = [Part {
        name: "Cell2",
        unit: "V",
        text: "4.1",
        value: 4.1,
    }];
    let other = Row {
        sensor: "Other",
        parts: Parts::List(&parts),
        ..row(Some(1), "Data", Class::Plain)
    };
    let f = filter(&spec(|s| s.sensor = vec!["Cell2".into()])).unwrap();
    assert!(f.keep(&other), "carries Cell2");
    let f = filter(&spec(|s| s.sensor = vec!["Cell3".into()])).unwrap();
    assert!(!f.keep(&other), "Cell3 is Cels' name, not this row's");
    assert!(f.keep(&row(Some(1), "Data", Class::Plain)), "a Cels row");
    let f = Filter::new(
        &spec(|s| s.sensor = vec!["speed".into()]),
        &VOCAB,
        &Names::default(),
        &["speed".into()],
        "SAB",
    );
    assert!(f.is_ok(), "names from options count");
}

#[test]
fn devices_and_names() {
    let s = spec(|s| {
        s.names = vec!["Pack=1".into()];
        s.device = vec!["pack".into()];
    });
    let f = filter(&s).unwrap();
    let names = Names::parse(&s.names, "--name", &VOCAB).unwrap();
    assert_eq!(names.get(1), Some("Pack"));
    let mut t = memory_table();
    let sel = Selection {
        filter: f,
        names,
        sensors: Vec::new(),
    };
    let mut out = Select {
        table: &mut t,
        selection: &sel,
    };
    out.row(&row(Some(0), "Data", Class::Plain)).unwrap();
    out.row(&row(Some(1), "Data", Class::Plain)).unwrap();
    t.flush().unwrap();
    let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "{text}");
    assert!(lines[1].starts_with("2\t0\t1\tPack\tData"), "{text}");
    assert_eq!(t.rows(), 2);
    let e = filter(&spec(|s| s.device = vec!["Boiler".into()])).unwrap_err();
    assert!(e.contains("shows FLVSS, Vario"), "{e}");
    assert!(filter(&spec(|s| s.device = vec!["vario".into()])).is_ok());
}

/// A TSV table in memory, for comparing what reaches it.
fn memory_table() -> crate::sink::Table {
    crate::sink::Table::new(
        crate::sink::Output::memory(),
        crate::sink::TableOptions {
            format: crate::sink::Format::Tsv,
            color: false,
            raw: false,
            time_abs: false,
            utc: false,
        },
        &[],
    )
}

/// The table's text and row count after `rows` went in through `send`.
fn through(
    rows: &[Row<'_>],
    mut send: impl FnMut(&mut crate::sink::Table, &Row<'_>),
) -> (String, u64) {
    let mut t = memory_table();
    for r in rows {
        send(&mut t, r);
    }
    t.flush().unwrap();
    let text = String::from_utf8(t.output().memory_contents().to_vec()).unwrap();
    (text, t.rows())
}

/// `Select::out` hands rows straight to the table only when the `Select` layer would pass
/// every row unchanged: the table gets the same rows either way, for selections with and
/// without names and filters.
#[test]
fn out_skips_the_layer_only_when_it_changes_nothing() {
    let mut rows = Vec::new();
    for id in [None, Some(0), Some(1), Some(2), Some(27), Some(31)] {
        for (kind, class) in [
            ("Data", Class::Plain),
            ("", Class::Quiet),
            ("Null", Class::Quiet),
            ("BadCRC", Class::Error),
            ("Garbage", Class::Error),
            ("LinkDown", Class::Info),
        ] {
            rows.push(row(id, kind, class));
        }
    }
    let specs = [
        Spec::default(),
        spec(|s| s.names = vec!["Pack=1".into()]),
        spec(|s| s.id = vec!["1-2".into()]),
        spec(|s| s.types = vec!["Data".into()]),
    ];
    for (i, s) in specs.iter().enumerate() {
        let sel = Selection {
            filter: filter(s).unwrap(),
            names: Names::parse(&s.names, "--name", &VOCAB).unwrap(),
            sensors: Vec::new(),
        };
        assert_eq!(sel.passes_all(), i == 0, "spec {i}");
        let direct = through(&rows, |table, r| {
            Select {
                table,
                selection: &sel,
            }
            .out()
            .row(r)
            .unwrap()
        });
        let layered = through(&rows, |table, r| {
            Select {
                table,
                selection: &sel,
            }
            .row(r)
            .unwrap()
        });
        assert_eq!(direct, layered, "spec {i}");
    }
}

#[test]
fn name_errors() {
    let e = Names::parse(&["Boiler".into()], "--name", &VOCAB).unwrap_err();
    assert!(e.contains("expected NAME=ID"), "{e}");
    let e = Names::parse(&["=3".into()], "--name", &VOCAB).unwrap_err();
    assert!(e.contains("empty"), "{e}");
    let e = Names::parse(&["a=99".into()], "--name", &VOCAB).unwrap_err();
    assert!(e.contains("0-31"), "{e}");
    let n = Names::parse(&["a=1".into(), "b=0x1".into()], "--name", &VOCAB).unwrap();
    assert_eq!(n.get(1), Some("b"), "the later name wins");
    assert_eq!(n.pairs().count(), 1);
}
