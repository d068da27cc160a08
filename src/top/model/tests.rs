use super::*;
use crate::row::{Part, Parts};

fn data<'a>(id: u32, no: &'a str, name: &'a str, value: &'a str, extra: &'a [&'a str]) -> Row<'a> {
    Row {
        stamp: 0,
        id: Some(id),
        device: "FAS-40S",
        kind: "Data",
        sensor_no: no,
        sensor: name,
        data: value,
        extra,
        raw: &[0x10, 0, 0, 0, 0, 0, 0, 0],
        ..Row::empty(None)
    }
}

/// A row with one number named as its sensor.
fn num<'a>(row: Row<'a>, part: &'a [Part<'a>]) -> Row<'a> {
    Row {
        parts: Parts::List(part),
        ..row
    }
}

fn part<'a>(name: &'a str, unit: &'a str, text: &'a str) -> Part<'a> {
    Part {
        name,
        unit,
        text,
        value: text.parse().unwrap(),
    }
}

#[test]
fn one_line_per_number_with_value_unit_min_max_and_rate() {
    let mut m = Model::new(&["Unit", "Note"]);
    let unit = ["V", ""];
    for (i, v) in ["12.1", "12.30", "11.9", "11.9"].iter().enumerate() {
        let p = [part("VFAS", "V", v)];
        m.row(
            &num(data(2, "210", "Volts", v, &unit), &p),
            i as u64 * 250_000,
        );
    }
    let p = [part("Curr", "A", "1.5")];
    m.row(&num(data(2, "200", "Amps", "1.5", &["A", ""]), &p), 100_000);
    assert_eq!(m.lines().len(), 2);
    let l = &m.lines()[0];
    assert_eq!((l.value.as_str(), l.unit.as_str()), ("11.9", "V"));
    assert_eq!(l.part_label(), "VFAS");
    // The texts as the rows wrote them (the wire's precision), not reformatted.
    let (min, max) = (l.min.as_ref().unwrap(), l.max.as_ref().unwrap());
    assert_eq!((min.text.as_str(), max.text.as_str()), ("11.9", "12.30"));
    assert_eq!(l.frames, 4);
    // Changed at 500 ms (12.30 -> 11.9), not at 750 ms (same value).
    assert_eq!(l.changed_at, Some(500_000));
    assert!(l.changed(1_000_000) && !l.changed(1_600_000));
    // 4 frames in the 1 s since the line appeared.
    assert_eq!(l.rate(1_000_000), Some(4.0));
    assert_eq!(l.rate(200_000), None, "too young");
    assert_eq!(l.age(1_000_000), 250_000);
    assert!(!l.stale(3_000_000) && l.stale(3_800_000));
    assert_eq!(m.bytes, 40);
}

/// An FLVSS frame carries the cell count and two cells (`count=3 cell1=4.138
/// cell2=4.137`), the next frame the third cell: each cell gets a line of its own, with its
/// own last value, minimum and maximum, from the row's typed numbers. The view used to read
/// the first number of the Data text, the cell count: Min 3 / Max 3, on one line whose
/// value swapped between the two half-frames.
#[test]
fn every_cell_has_a_line_with_its_own_min_and_max() {
    let mut m = Model::new(&["Unit", "Note"]);
    let frames: [(&str, &[Part<'_>]); 4] = [
        (
            "count=3 cell1=4.138 cell2=4.137",
            &[part("Cell1", "V", "4.138"), part("Cell2", "V", "4.137")],
        ),
        ("count=3 cell3=4.120", &[part("Cell3", "V", "4.120")]),
        (
            "count=3 cell1=3.902 cell2=3.950",
            &[part("Cell1", "V", "3.902"), part("Cell2", "V", "3.950")],
        ),
        ("count=3 cell3=3.611", &[part("Cell3", "V", "3.611")]),
    ];
    for (t, (text, parts)) in frames.iter().enumerate() {
        let row = Row {
            parts: Parts::List(parts),
            ..data(1, "0x0300", "Cels", text, &["V", ""])
        };
        m.row(&row, t as u64 * 100_000);
    }
    let got: Vec<(&str, &str, &str, &str)> = m
        .order(Sort::Id, None, 1_000_000)
        .into_iter()
        .map(|i| {
            let l = &m.lines()[i];
            (
                l.key.part.as_str(),
                l.value.as_str(),
                l.min.as_ref().unwrap().text.as_str(),
                l.max.as_ref().unwrap().text.as_str(),
            )
        })
        .collect();
    assert_eq!(
        got,
        [
            ("Cell1", "3.902", "3.902", "4.138"),
            ("Cell2", "3.950", "3.950", "4.137"),
            ("Cell3", "3.611", "3.611", "4.120"),
        ]
    );
    assert!(m.lines().iter().all(|l| l.numeric && l.frames == 2));
}

/// A read's request (`R0..R3`) shows until the answer brings the registers, which then get
/// a line each; a write's `ACK (0x0000)` does not hide the value written.
#[test]
fn requests_show_until_an_answer_brings_numbers() {
    let mut m = Model::new(&[]);
    let req = Row {
        stamp: 0,
        kind: "Request",
        data: "R0..R1",
        ..data(10, "R0", "Read register(s)", "", &[])
    };
    m.row(&req, 0);
    assert_eq!(m.order(Sort::Id, None, 0).len(), 1);
    assert_eq!(m.lines()[0].value, "R0..R1");
    let regs = [part("R0", "", "42"), part("R1", "", "1")];
    let resp = Row {
        stamp: 0,
        kind: "Response",
        data: "R0=42 R1=1",
        parts: Parts::List(&regs),
        ..req
    };
    m.row(&resp, 1000);
    m.row(&req, 2000);
    let shown: Vec<(&str, &str)> = m
        .order(Sort::Id, None, 3000)
        .into_iter()
        .map(|i| (m.lines()[i].key.part.as_str(), m.lines()[i].value.as_str()))
        .collect();
    assert_eq!(shown, [("R0", "42"), ("R1", "1")]);
    let written = [part("R1", "", "181")];
    let write = Row {
        stamp: 0,
        kind: "Request",
        data: "R1=181",
        parts: Parts::List(&written),
        ..data(10, "R1", "Write register(s)", "", &[])
    };
    let ack = Row {
        stamp: 0,
        kind: "ACK",
        data: "ACK (0x0000)",
        ..write
    };
    m.row(&write, 4000);
    m.row(&ack, 5000);
    let i = m.order(Sort::Id, None, 6000)[2];
    assert_eq!(
        (
            m.lines()[i].key.sensor.as_str(),
            m.lines()[i].value.as_str()
        ),
        ("Write register(s)", "181")
    );
    assert_eq!(m.order(Sort::Id, None, 6000).len(), 3);
}

/// Protocols without IDs (rows with `id: None`) have their lines too.
#[test]
fn rows_without_an_id_have_lines() {
    let mut m = Model::new(&[]);
    let p = [part("distance", "m", "1.25")];
    let row = Row {
        id: None,
        ..num(data(0, "0x10", "distance", "1.25", &[]), &p)
    };
    m.row(&row, 0);
    m.row(&row, 1000);
    assert_eq!(m.lines().len(), 1);
    assert_eq!(m.lines()[0].key.id, None);
    assert_eq!(m.lines()[0].frames, 2);
}

#[test]
fn errors_count_on_their_line_and_become_events() {
    let mut m = Model::new(&[]);
    m.row(&data(5, "0x10", "", "01", &[]), 0);
    let bad = Row {
        stamp: 0,
        kind: kind::BAD_CRC,
        class: Class::Error,
        ..data(5, "0x10", "", "01", &[])
    };
    m.row(&bad, 10);
    // A bad frame of an unknown key opens no line but counts on its ID's line.
    m.row(
        &Row {
            stamp: 0,
            sensor_no: "0x99",
            ..bad
        },
        20,
    );
    let nak = Row {
        stamp: 0,
        kind: "NACK",
        ..data(5, "0x10", "", "02 (2)", &[])
    };
    m.row(&nak, 30);
    let timeout = Row {
        stamp: 0,
        kind: kind::TIMEOUT,
        class: Class::Warning,
        ..data(7, "0x11", "", "", &[])
    };
    m.row(&timeout, 40);
    assert_eq!(m.lines().len(), 1);
    let l = &m.lines()[0];
    assert_eq!((l.crc_errors, l.timeouts, l.value.as_str()), (2, 1, "01"));
    assert_eq!((m.crc_errors, m.timeouts, m.error_rows), (2, 2, 2));
    assert_eq!(m.events.len(), 4);
    assert_eq!(m.events[0].kind, "BadCRC");
    assert_eq!(m.valid_percent(), Some(60.0));
}

#[test]
fn rows_without_a_sensor_open_no_line() {
    let mut m = Model::new(&[]);
    m.row(
        &Row {
            stamp: 0,
            kind: "",
            ..data(26, "", "", "", &[])
        },
        0,
    );
    m.row(
        &Row {
            stamp: 0,
            kind: "Null",
            class: Class::Quiet,
            ..data(0, "", "", "", &[])
        },
        0,
    );
    assert!(m.lines().is_empty());
    assert_eq!(m.frame_rows, 2);
}

#[test]
fn lines_are_capped_and_the_rest_counted() {
    let mut m = Model::new(&[]);
    for i in 0..MAX_LINES as u32 + 10 {
        let no = i.to_string();
        m.row(&data(i, &no, "x", "1", &[]), 0);
    }
    assert_eq!(m.lines().len(), MAX_LINES);
    assert_eq!(m.overflow_rows, 10);
}

#[test]
fn memory_per_line_is_bounded() {
    let mut m = Model::new(&[]);
    let long = "9".repeat(10_000);
    for t in 0..10_000u64 {
        m.row(&data(1, "1", "x", &long, &[]), t * 1000);
    }
    let l = &m.lines()[0];
    assert!(l.times.len() <= RATE_TIMES);
    assert!(l.value.chars().count() <= TEXT_MAX + 1);
    // 1000 frames/s, more than the kept times cover.
    let r = l.rate(9_999_000).unwrap();
    assert!((r - 1000.0).abs() < 10.0, "{r}");
    assert!(m.byte_times.len() <= 51);
}

#[test]
fn sort_filter_and_marks() {
    let mut m = Model::new(&[]);
    let (alt, volts, lat) = (
        [part("Alt", "m", "1")],
        [part("VFAS", "V", "1")],
        [part("Lat", "deg", "1")],
    );
    m.row(
        &Row {
            stamp: 0,
            device: "Vario",
            ..num(data(0, "0x0100", "Alt", "1", &[]), &alt)
        },
        0,
    );
    for t in 0..10 {
        m.row(
            &Row {
                stamp: 0,
                device: "FAS-40S",
                ..num(data(2, "0x0210", "Volts", "1", &[]), &volts)
            },
            t * 100_000,
        );
    }
    m.row(
        &Row {
            stamp: 0,
            device: "GPS",
            ..num(data(24, "0x0800", "GPS", "1", &[]), &lat)
        },
        900_000,
    );
    let now = 1_000_000;
    assert_eq!(m.order(Sort::Id, None, now), [0, 1, 2]);
    assert_eq!(m.order(Sort::Rate, None, now)[0], 1);
    assert_eq!(
        m.order(Sort::Age, None, now),
        [1, 2, 0],
        "equal ages by key"
    );
    assert_eq!(m.order(Sort::Name, None, now), [1, 2, 0]);
    let vocab = crate::sport::PROTOCOL.vocab;
    let f = |t: &str| Filter::from_words(t, vocab, &Default::default(), &[], "S.Port").unwrap();
    assert_eq!(m.order(Sort::Id, Some(&f("sensor=VFAS")), now), [1]);
    assert_eq!(m.order(Sort::Id, Some(&f("volts")), now), [1]);
    // An ID is an ID, not a substring: `2` is not also 24.
    assert_eq!(m.order(Sort::Id, Some(&f("2")), now), [1]);
    assert_eq!(m.order(Sort::Id, Some(&f("id=24")), now), [2]);
    assert_eq!(m.order(Sort::Id, Some(&f("not-id=0-9")), now), [2]);
    assert_eq!(m.order(Sort::Id, Some(&f("device=Vario")), now), [0]);
    assert_eq!(m.order(Sort::Id, Some(&f("type=Data")), now), [0, 1, 2]);
    m.toggle_mark(2);
    assert_eq!(m.order(Sort::Id, None, now), [2, 0, 1]);
}
