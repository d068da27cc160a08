//! `busnoop plot` (issue 13): the SVG's lines are the capture's values.

mod common;

use assert_cmd::Command;
use common::fixture;

/// The `points` of every `<polyline>` drawn with `stroke-width="2"` (the series; axes, grid
/// and error marks are thinner).
fn series_lines(svg: &str) -> Vec<Vec<(f64, f64)>> {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p.split('>').next().unwrap().contains("stroke-width=\"2\""))
        .map(|p| {
            let pts = p
                .split("points=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap();
            pts.split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

/// (seconds, value) of every row of the long table whose Sensor is `sensor`.
fn values(file: &str, sensor: &str) -> Vec<(f64, f64)> {
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .args(["sport", fixture(file).to_str().unwrap(), "-f", "csv"])
        .output()
        .unwrap();
    let mut r = csv::Reader::from_reader(out.stdout.as_slice());
    r.records()
        .map(Result::unwrap)
        .filter(|r| &r[6] == sensor && !r[8].is_empty())
        .map(|r| (r[1].parse::<f64>().unwrap() / 1000.0, r[8].parse().unwrap()))
        .collect()
}

/// Every point's pixel is a linear map of (time, value): fitted on two points, every other
/// point within a pixel of it (plotters rounds to whole pixels).
fn assert_linear(pixels: &[(f64, f64)], data: &[(f64, f64)]) {
    assert_eq!(pixels.len(), data.len(), "one point per value");
    let fit = |px: &dyn Fn(usize) -> f64, dv: &dyn Fn(usize) -> f64| {
        let (i, j) = (0..data.len())
            .flat_map(|i| (0..data.len()).map(move |j| (i, j)))
            .max_by(|a, b| {
                (dv(a.0) - dv(a.1))
                    .abs()
                    .partial_cmp(&(dv(b.0) - dv(b.1)).abs())
                    .unwrap()
            })
            .unwrap();
        if dv(j) == dv(i) {
            // A constant: one flat line.
            assert!((0..data.len()).all(|k| px(k) == px(0)), "a flat line");
            return None;
        }
        let b = (px(j) - px(i)) / (dv(j) - dv(i));
        let a = px(i) - b * dv(i);
        for k in 0..data.len() {
            let want = a + b * dv(k);
            assert!(
                (want - px(k)).abs() <= 1.01,
                "point {k}: pixel {} for {}, expected {want}",
                px(k),
                dv(k)
            );
        }
        Some(b)
    };
    let bx = fit(&|k| pixels[k].0, &|k| data[k].0);
    let by = fit(&|k| pixels[k].1, &|k| data[k].1);
    assert!(bx.unwrap() > 0.0, "time runs right");
    assert!(by.is_none_or(|b| b < 0.0), "values rise upwards");
}

#[test]
fn svg_lines_are_the_values() {
    let dir = tempfile::tempdir().unwrap();
    let svg_path = dir.path().join("flight.svg");
    Command::cargo_bin("busnoop")
        .unwrap()
        .args(["plot"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .args(["--sensor", "RSSI,RxBt", "-o"])
        .arg(&svg_path)
        .assert()
        .success();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    let lines = series_lines(&svg);
    assert_eq!(lines.len(), 2, "one line per sensor");
    // One panel per unit, each with its axis title.
    assert!(svg.contains("(dB)") && svg.contains("(V)"));
    assert!(svg.contains("time since the capture"));
    let file = "edgetx-MODELE24-2014-07-11-sport.log";
    let rssi = values(file, "RSSI");
    let rxbt = values(file, "RxBt");
    assert!(rssi.len() > 10 && rxbt.len() > 10);
    assert!(rssi.iter().any(|r| r.1 != rssi[0].1), "RSSI varies");
    assert_linear(&lines[0], &rssi);
    assert_linear(&lines[1], &rxbt);
}

#[test]
fn png_is_written_and_unknown_names_are_listed() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("flight.png");
    Command::cargo_bin("busnoop")
        .unwrap()
        .args(["plot"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .args(["--sensor", "Cell1", "-o"])
        .arg(&png)
        .assert()
        .success();
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .args(["plot"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .args(["--sensor", "Alt", "-o"])
        .arg(dir.path().join("x.svg"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no number named Alt") && err.contains("RSSI"),
        "{err}"
    );
    let out = Command::cargo_bin("busnoop")
        .unwrap()
        .args(["plot"])
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .args(["-o"])
        .arg(dir.path().join("x.pdf"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".svg or .png"));
}

/// Nothing to plot is not a failed write: a sensor name the capture does not have is a usage
/// error (exit 2), a capture without any number has nothing to draw (exit 10), each in one line
/// without "cannot write to". Both used to be `cannot write to IMAGE: …`, exit 8, the code of a
/// full disk.
#[test]
fn nothing_to_plot_is_not_a_write_error() {
    let dir = tempfile::tempdir().unwrap();
    let polls = dir.path().join("polls.bin");
    std::fs::write(&polls, [0x7E, 0xA1].repeat(100)).unwrap();
    let log = fixture("edgetx-MODELE24-2014-07-11-sport.log");
    for (source, extra, code, want) in [
        (
            log.as_path(),
            &["--sensor", "Alt"][..],
            2,
            "no number named Alt",
        ),
        (
            polls.as_path(),
            &["--protocol", "sport"][..],
            10,
            "carries a number",
        ),
    ] {
        let out = Command::cargo_bin("busnoop")
            .unwrap()
            .arg("plot")
            .arg(source)
            .args(extra)
            .arg("-o")
            .arg(dir.path().join("x.svg"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{err}");
        let last = err.lines().last().unwrap();
        assert!(
            last.contains(want) && !last.contains("cannot write"),
            "{err}"
        );
        assert!(!dir.path().join("x.svg").exists());
    }
}

/// `busnoop plot -` (or a FIFO) without `--protocol`: a pipe can be read only once, so its
/// protocol cannot be detected before it is plotted. It is refused at once, naming the option.
/// It used to be detected on the pipe's bytes, which the plot then did not get: `empty input:
/// standard input holds no bytes` (exit 10), and a FIFO was waited on for a second writer for
/// ever.
#[test]
fn a_pipe_needs_the_protocol_named() {
    use std::io::Write;
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let log = std::fs::read(fixture("edgetx-MODELE24-2014-07-11-sport.log")).unwrap();
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .args(["plot", "-", "-o"])
        .arg(dir.path().join("x.svg"))
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pipe = child.stdin.take().unwrap();
    // busnoop may refuse before reading: a broken pipe is fine.
    let _ = pipe.write_all(&log);
    drop(pipe);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--protocol"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    // A FIFO no one writes to: refused without waiting.
    let fifo = dir.path().join("fifo");
    common::mkfifo(&fifo);
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .arg("plot")
        .arg(&fifo)
        .arg("-o")
        .arg(dir.path().join("y.svg"))
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            panic!("busnoop plot FIFO waited");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
