use super::thin::MAX_POINTS;
use super::*;

#[test]
fn legend_names_keep_their_start_and_end() {
    assert_eq!(
        short_port("Alt@/dev/serial/by-id/usb-FTDI-if00 (m)"),
        "Alt@usb-FTDI-if00 (m)"
    );
    assert_eq!(short_port("Cell1@8 (V)"), "Cell1@8 (V)");
    let cut = fit("Cell1@/a/very/long/path/to/rx.pcap", 100, 10);
    assert!(
        cut.starts_with("Cell1@") && cut.ends_with("rx.pcap") && cut.contains('…'),
        "{cut}"
    );
}
use crate::row::Part;

fn row(us: u64, class: Class, parts: &'static [Part<'static>]) -> Row<'static> {
    Row {
        stamp: 0,
        micros: Some(us),
        id: Some(0),
        device: "",
        kind: "",
        class,
        sensor_no: "",
        sensor: "",
        data: "",
        extra: &[],
        parts: parts.into(),
        raw: &[],
    }
}

const ALT1: &[Part<'static>] = &[Part {
    name: "Alt",
    unit: "m",
    text: "10",
    value: 10.0,
}];
const ALT2: &[Part<'static>] = &[Part {
    name: "Alt",
    unit: "m",
    text: "20",
    value: 20.0,
}];

/// A long or noisy capture: the points of a series and the broken frames' marks are thinned
/// to at most [`MAX_POINTS`] each (the image is 1000 pixels wide). They used to be kept
/// all: memory grew with the capture, and `busnoop plot /dev/urandom` drew an SVG of
/// gigabytes, a red line per broken frame.
#[test]
fn long_captures_are_thinned_to_a_bounded_plot() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.svg");
    let mut p = Plot::new(PlotSpec {
        path: path.clone(),
        title: "t".into(),
        ..PlotSpec::default()
    });
    let n = 300_000u64;
    for i in 0..n {
        p.row(&row(i * 10_000, Class::Plain, ALT1));
        p.row(&row(i * 10_000 + 5_000, Class::Error, &[]));
    }
    let points = &p.series[0].points.kept;
    assert!(points.len() <= MAX_POINTS && points.len() > MAX_POINTS / 8);
    assert!(p.errors.kept.len() <= MAX_POINTS && p.errors.kept.len() > MAX_POINTS / 8);
    // Spread over the whole capture, in time order.
    assert_eq!(points[0].0, 0.0);
    assert!(points.last().unwrap().0 > (n - 100) as f64 * 0.01);
    assert!(points.windows(2).all(|w| w[0].0 < w[1].0));
    p.draw().unwrap();
    let size = std::fs::metadata(&path).unwrap().len();
    assert!(size < 8_000_000, "{size} bytes");
}

/// Thinning keeps what the eye looks for: a one-sample spike and dip in a long flat series,
/// and a lone broken frame after a burst of them (every other point dropped would lose each
/// of them half the time, or more).
#[test]
fn thinning_keeps_spikes_dips_and_lone_marks() {
    let mut s = Thinned::default();
    let mut marks = Thinned::default();
    let n = 1_000_000u64;
    let (spike, dip) = (123_457, 876_543);
    for i in 0..n {
        let t = i as f64 * 0.01;
        let v = match i {
            _ if i == spike => 100.0,
            _ if i == dip => -50.0,
            _ => (i % 7) as f64,
        };
        s.push(t, v);
        if i < n / 2 || i == n - 3 {
            marks.push(t, 0.0);
        }
    }
    assert!(s.kept.len() <= MAX_POINTS);
    assert!(s.kept.contains(&(spike as f64 * 0.01, 100.0)), "spike lost");
    assert!(s.kept.contains(&(dip as f64 * 0.01, -50.0)), "dip lost");
    // The envelope of the rest: its lowest and highest values are still there.
    assert!(s.kept.iter().any(|p| p.1 == 0.0) && s.kept.iter().any(|p| p.1 == 6.0));
    assert!(marks.kept.len() <= MAX_POINTS);
    assert!(
        marks.kept.contains(&((n - 3) as f64 * 0.01, 0.0)),
        "the lone mark was lost"
    );
}

/// Times out of order (a capture whose clock jumps back and forth) cannot be merged by cell,
/// and the bound still holds.
#[test]
fn thinning_is_bounded_whatever_the_order_of_times() {
    let mut s = Thinned::default();
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    for _ in 0..200_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        s.push((x % 1_000_000) as f64, (x >> 40) as f64);
        assert!(s.kept.len() <= MAX_POINTS);
    }
    assert!(s.kept.len() > MAX_POINTS / 8);
}

/// M2 (issue 32): at most MAX_SERIES series, found through a map; the numbers of the rest
/// are counted; labels still carry the ID when a name is shared.
#[test]
fn series_are_capped_and_counted() {
    let mut p = Plot::new(PlotSpec::default());
    let names: Vec<&'static [Part<'static>]> = (0..200)
        .map(|i| {
            let name: &'static str = format!("N{}", i % 100).leak();
            &*vec![Part {
                name,
                unit: "V",
                text: "1",
                value: 1.0,
            }]
            .leak()
        })
        .collect();
    for round in 0..3u64 {
        for (i, parts) in names.iter().enumerate() {
            let mut r = row(round * 1000 + i as u64, Class::Plain, parts);
            r.id = Some((i / 100) as u32);
            p.row(&r);
        }
    }
    assert_eq!(p.series.len(), MAX_SERIES);
    assert_eq!(p.left_out(), 3 * (200 - MAX_SERIES as u64));
    assert!(p.series.iter().all(|s| s.points.kept.len() == 3));
    assert_eq!(p.label(&p.series[0]), "N0");
    // An error row carries no number into the plot.
    let mut bad = row(5000, Class::Error, ALT1);
    bad.id = Some(0);
    p.row(&bad);
    assert!(!p.series.iter().any(|s| s.name == "Alt"));
}

/// A signal while drawing gives the drawing up: no image, the signal's failure.
#[test]
fn a_signal_while_drawing_leaves_no_image() {
    let dir = tempfile::tempdir().unwrap();
    for (k, name) in ["p.svg", "p.png"].into_iter().enumerate() {
        let path = dir.path().join(name);
        let mut p = Plot::new(PlotSpec {
            path: path.clone(),
            title: "t".into(),
            ..PlotSpec::default()
        });
        p.row(&row(0, Class::Plain, ALT1));
        p.row(&row(1_000_000, Class::Plain, ALT2));
        let r = p.draw_until(&|| Some(libc::SIGTERM));
        assert!(matches!(r, Err(Failure::Signal(ref i)) if i.signal == libc::SIGTERM));
        assert!(!path.exists());
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            k,
            "no temporary file"
        );
        p.draw_until(&|| None).unwrap();
        assert!(path.exists());
    }
}

/// A broken frame's moment is a red vertical line across the panel.
#[test]
fn broken_frames_are_marked() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.svg");
    let mut p = Plot::new(PlotSpec {
        sensors: vec!["Alt".into()],
        wanted: vec!["Alt".into()],
        path: path.clone(),
        title: "t".into(),
        ..PlotSpec::default()
    });
    p.row(&row(0, Class::Plain, ALT1));
    p.row(&row(1_000_000, Class::Error, &[]));
    p.row(&row(2_000_000, Class::Plain, ALT2));
    p.draw().unwrap();
    let svg = std::fs::read_to_string(path).unwrap();
    // The series' line (the legend's sample is right of the data).
    let series: Vec<&str> = svg
        .split("<polyline")
        .filter(|l| l.contains("stroke-width=\"2\"") && !l.contains("points=\"968,"))
        .collect();
    assert_eq!(series.len(), 1);
    let xs: Vec<f64> = series[0]
        .split("points=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap()
        .split_whitespace()
        .map(|xy| xy.split(',').next().unwrap().parse().unwrap())
        .collect();
    // A step: (0, 10), (2, 10), (2, 20).
    assert_eq!(xs.len(), 3);
    let mid = (xs[0] + xs[2]) / 2.0;
    let red: Vec<&str> = svg
        .split("<polyline")
        .filter(|l| l.contains("stroke=\"#FF0000\""))
        .collect();
    assert!(
        red.iter().any(|l| {
            let pts = l
                .split("points=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap();
            let x: Vec<f64> = pts
                .split_whitespace()
                .map(|xy| xy.split(',').next().unwrap().parse().unwrap())
                .collect();
            x.len() == 2 && x[0] == x[1] && (x[0] - mid).abs() <= 1.0
        }),
        "a red vertical line at t = 1 s: {red:?}"
    );
}

fn series(name: &str, unit: &str, values: &[f64]) -> Series {
    let mut points = Thinned::default();
    for (i, &v) in values.iter().enumerate() {
        points.push(i as f64, v);
    }
    Series {
        id: Some(1),
        port: String::new(),
        name: name.into(),
        unit: unit.into(),
        points,
    }
}

/// Panels by unit, then flags apart, then by size, at most six to a panel: a flag next to
/// 3.7e9 was a flat line at zero, and twenty series in one panel an unreadable legend.
#[test]
fn panels_by_unit_flags_size_and_at_most_six() {
    let mut all = vec![
        series("big", "", &[3.7e9, 1.0]),
        series("flag", "", &[0.0, 1.0, 1.0]),
        series("count", "", &[3.0, 99.0]),
        series("volts", "V", &[4.1, 4.2]),
        series("small", "", &[0.5, 2.0]),
    ];
    for i in 0..8 {
        all.push(series(&format!("F{i}"), "", &[1.0, 0.0]));
    }
    let chosen: Vec<(String, &Series)> = all.iter().map(|s| (s.name.clone(), s)).collect();
    let got: Vec<(String, Vec<&str>)> = panels(&chosen)
        .iter()
        .map(|p| {
            (
                p.unit.clone(),
                p.members.iter().map(|m| m.0.as_str()).collect(),
            )
        })
        .collect();
    let want: Vec<(String, Vec<&str>)> = vec![
        ("".into(), vec!["flag", "F0", "F1", "F2", "F3", "F4"]),
        ("".into(), vec!["F5", "F6", "F7"]),
        ("".into(), vec!["count", "small"]),
        ("".into(), vec!["big"]),
        ("V".into(), vec!["volts"]),
    ];
    assert_eq!(got, want);
}

/// A series of one sample is a marker; labels of large values are written whole.
#[test]
fn one_sample_is_a_marker_and_labels_are_whole() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.svg");
    let mut p = Plot::new(PlotSpec {
        path: path.clone(),
        title: "t".into(),
        ..PlotSpec::default()
    });
    p.row(&row(500_000, Class::Plain, ALT1));
    p.draw().unwrap();
    let svg = std::fs::read_to_string(&path).unwrap();
    assert!(svg.contains("<circle"), "a marker");
    assert_eq!(number(3_735_928_559.0, 5e8), "3735928559");
    assert_eq!(number(4.1234, 0.05), "4.12");
    assert_eq!(number(-0.0001, 0.5), "0.0");
}
