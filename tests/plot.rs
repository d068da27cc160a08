//! `busnoop plot` (issue 13): the SVG's lines are the capture's values.

mod common;

use assert_cmd::Command;
use common::fixture;

/// Where the legend starts: the data are left of it (src/plot/mod.rs, `WIDTH - LEGEND`).
const LEGEND_X: f64 = 960.0;

/// The value of attribute `name` in the tag `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    Some(&tag[at..at + tag[at..].find('"')?])
}

/// Every `<polyline>` drawn with `stroke-width="2"` in the data area (the series' steps; axes,
/// grid and error marks are thinner, the legend's samples right of [`LEGEND_X`]): its colour and
/// points.
fn series_lines(svg: &str) -> Vec<(String, Vec<(f64, f64)>)> {
    svg.split("<polyline")
        .skip(1)
        .map(|p| p.split('>').next().unwrap())
        .filter(|tag| attr(tag, "stroke-width") == Some("2"))
        .map(|tag| {
            let pts = attr(tag, "points")
                .unwrap()
                .split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect::<Vec<(f64, f64)>>();
            (attr(tag, "stroke").unwrap().to_owned(), pts)
        })
        .filter(|(_, pts)| pts.iter().all(|p| p.0 < LEGEND_X))
        .collect()
}

/// The markers of a series' line: the circles of its colour on its points (each panel's
/// colours start again), in drawing order.
fn markers_on(svg: &str, line: &(String, Vec<(f64, f64)>)) -> Vec<(f64, f64)> {
    markers(svg, &line.0)
        .into_iter()
        .filter(|m| line.1.contains(m))
        .collect()
}

/// The markers (`<circle>`) of colour `color` in the data area, in drawing order.
fn markers(svg: &str, color: &str) -> Vec<(f64, f64)> {
    svg.split("<circle")
        .skip(1)
        .map(|p| p.split('>').next().unwrap())
        .filter(|tag| attr(tag, "fill") == Some(color))
        .map(|tag| {
            (
                attr(tag, "cx").unwrap().parse().unwrap(),
                attr(tag, "cy").unwrap().parse().unwrap(),
            )
        })
        .filter(|p: &(f64, f64)| p.0 < LEGEND_X)
        .collect()
}

/// The labels of the legend (texts right of [`LEGEND_X`]).
fn legend(svg: &str) -> Vec<String> {
    texts(svg)
        .into_iter()
        .filter(|t| t.x >= LEGEND_X)
        .map(|t| t.text)
        .collect()
}

/// A `<text>`: where it is anchored, how, its size and its text.
#[derive(Debug)]
struct Text {
    x: f64,
    y: f64,
    anchor: String,
    dy: String,
    size: f64,
    rotated: bool,
    text: String,
}

fn texts(svg: &str) -> Vec<Text> {
    svg.split("<text")
        .skip(1)
        .map(|p| {
            let (tag, rest) = p.split_once('>').unwrap();
            let text = rest.split("</text>").next().unwrap().trim().to_owned();
            Text {
                x: attr(tag, "x").unwrap().parse().unwrap(),
                y: attr(tag, "y").unwrap().parse().unwrap(),
                anchor: attr(tag, "text-anchor").unwrap_or("start").to_owned(),
                dy: attr(tag, "dy").unwrap_or("").to_owned(),
                size: attr(tag, "font-size").unwrap().parse().unwrap(),
                rotated: attr(tag, "transform").is_some(),
                text,
            }
        })
        .collect()
}

/// The image's width and height.
fn size(svg: &str) -> (f64, f64) {
    let tag = svg.split("<svg").nth(1).unwrap().split('>').next().unwrap();
    (
        attr(tag, "width").unwrap().parse().unwrap(),
        attr(tag, "height").unwrap().parse().unwrap(),
    )
}

/// Every text lies inside the image (its width taken as 0.62 of the font size per character,
/// DejaVu Sans' widest digits and most letters).
fn assert_labels_inside(svg: &str, what: &str) {
    let (w, h) = size(svg);
    for t in texts(svg) {
        let len = t.text.chars().count() as f64 * t.size * 0.62;
        let (along, across, limit_along, limit_across) = if t.rotated {
            (t.y, t.x, h, w)
        } else {
            (t.x, t.y, w, h)
        };
        // Across the text: from its top to its baseline, as `dy` places it.
        let (top, bottom) = match t.dy.as_str() {
            d if d.starts_with('-') => (across - t.size, across),
            "0.76em" => (across, across + t.size),
            _ => (across - t.size / 2.0, across + t.size / 2.0),
        };
        let (a, b) = match t.anchor.as_str() {
            "middle" => (along - len / 2.0, along + len / 2.0),
            "end" => (along - len, along),
            _ => (along, along + len),
        };
        assert!(
            a >= 0.0 && b <= limit_along && top >= -1.0 && bottom <= limit_across + 1.0,
            "{what}: {t:?} is not inside the image of {w}x{h}"
        );
    }
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
    let file = "edgetx-MODELE24-2014-07-11-sport.log";
    let rssi = values(file, "RSSI");
    let rxbt = values(file, "RxBt");
    assert!(rssi.len() > 10 && rxbt.len() > 10);
    assert!(rssi.iter().any(|r| r.1 != rssi[0].1), "RSSI varies");
    // A marker at every sample, at a linear map of (time, value).
    assert_linear(&markers_on(&svg, &lines[0]), &rssi);
    assert_linear(&markers_on(&svg, &lines[1]), &rxbt);
    // Between samples the value is held: the line is a staircase through the markers, each
    // step level until the next sample (never a ramp that did not happen).
    for line in &lines {
        let (pts, m) = (&line.1, markers_on(&svg, line));
        assert_eq!(pts.len(), 2 * m.len() - 1, "two points per step");
        for (k, w) in m.windows(2).enumerate() {
            assert_eq!(pts[2 * k], w[0]);
            assert_eq!(
                pts[2 * k + 1],
                (w[1].0, w[0].1),
                "held until the next sample"
            );
            assert_eq!(pts[2 * k + 2], w[1]);
        }
    }
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
    let deadline = std::time::Instant::now() + common::PATIENCE;
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

/// The default plot of every fixture, by every subcommand that reads it: every series has its
/// points (a marker for each sample: a series of one sample is visible), every text lies inside
/// the image (title, axis labels, legend), and the legend lists every number of the capture,
/// beside the data and not on it. The README's own example drew two empty panels (a series of
/// one sample had no marker), S-Bus and SAB put every unitless series in one panel with the y
/// labels cut (`00000000.0`) and a legend running off the image.
#[test]
fn every_fixtures_default_plot_has_every_series_and_every_label_inside() {
    let dir = tempfile::tempdir().unwrap();
    let mut seen = 0;
    for (protocol, file, extra) in [
        ("sport", "sport-sample.bin", &["--sensor", "Alt,VFAS"][..]),
        ("sport", "sport-sample.bin", &[][..]),
        ("sport", "edgetx-MODELE24-2014-07-11-sport.log", &[][..]),
        ("sbus", "sbus-digimat.pcap", &[][..]),
        ("sbus", "sbus_seeds_ether.pcap", &[][..]),
        ("sab2", "sab1-session.bin", &[][..]),
        ("sab2", "sab2-session.bin", &[][..]),
    ] {
        let svg_path = dir.path().join("p.svg");
        let out = Command::cargo_bin("busnoop")
            .unwrap()
            .args(["plot", "--protocol", protocol])
            .arg(fixture(file))
            .args(extra)
            .arg("-o")
            .arg(&svg_path)
            .output()
            .unwrap();
        let what = format!("{file} {extra:?}");
        if out.status.code() == Some(10) {
            // No number at all (S-Bus seeds): nothing to draw.
            assert!(String::from_utf8_lossy(&out.stderr).contains("carries a number"));
            continue;
        }
        assert!(
            out.status.success(),
            "{what}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        let lines = series_lines(&svg);
        let names = legend(&svg);
        // The numbers of the capture (JSON Lines parts), by ID and name.
        let rows = Command::cargo_bin("busnoop")
            .unwrap()
            .arg(protocol)
            .arg(fixture(file))
            .args(["-f", "jsonl"])
            .output()
            .unwrap();
        let mut numbers = std::collections::BTreeSet::new();
        for l in String::from_utf8_lossy(&rows.stdout).lines() {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            if let Some(p) = v["parts"].as_object() {
                for k in p.keys() {
                    numbers.insert((v["id"].to_string(), k.clone()));
                }
            }
        }
        let wanted = if extra.is_empty() { numbers.len() } else { 2 };
        let series: Vec<&String> = names.iter().filter(|n| *n != "broken frame").collect();
        assert_eq!(series.len(), wanted, "{what}: legend {names:?}");
        assert_eq!(lines.len(), wanted, "{what}: one line per series");
        for line in &lines {
            assert!(!line.1.is_empty(), "{what}: a series without points");
            assert!(
                !markers_on(&svg, line).is_empty(),
                "{what}: no marker on {line:?}"
            );
        }
        assert_labels_inside(&svg, &what);
        seen += 1;
    }
    assert!(seen >= 6);
}

/// Panels by size: S-Bus flags (0/1) and counters are not drawn in the panel of a register of
/// 305419896, where they were a flat line at zero; no panel has more than six series.
#[test]
fn flags_and_large_values_get_panels_of_their_own() {
    let dir = tempfile::tempdir().unwrap();
    let svg_path = dir.path().join("p.svg");
    Command::cargo_bin("busnoop")
        .unwrap()
        .args(["plot", "--protocol", "sbus"])
        .arg(fixture("sbus-digimat.pcap"))
        .arg("-o")
        .arg(&svg_path)
        .assert()
        .success();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    // The legend's entries by panel: a panel's entries are 22 pixels apart, panels further.
    let mut entries: Vec<(f64, String)> = texts(&svg)
        .into_iter()
        .filter(|t| t.x >= LEGEND_X)
        .map(|t| (t.y, t.text))
        .collect();
    entries.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut panels: Vec<Vec<String>> = Vec::new();
    let mut last = f64::NEG_INFINITY;
    for (y, name) in entries {
        if y - last > 30.0 {
            panels.push(Vec::new());
        }
        last = y;
        panels.last_mut().unwrap().push(name);
    }
    assert!(panels.len() >= 3, "{panels:?}");
    for p in &panels {
        assert!(p.len() <= 6, "{p:?}");
        if p.iter().any(|n| n == "R0") {
            assert!(
                !p.iter().any(|n| n.starts_with('F') || n == "C5"),
                "flags and counters with R0: {p:?}"
            );
        }
    }
}

/// Where the source has wall-clock time (an EdgeTX log), the x axis shows the time of day.
#[test]
fn the_x_axis_shows_the_time_of_day_when_the_source_has_it() {
    let dir = tempfile::tempdir().unwrap();
    let svg_path = dir.path().join("p.svg");
    Command::cargo_bin("busnoop")
        .unwrap()
        .arg("plot")
        .arg(fixture("edgetx-MODELE24-2014-07-11-sport.log"))
        .args(["--sensor", "RSSI", "-o"])
        .arg(&svg_path)
        .assert()
        .success();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.contains("time of day (2014-07-11)"), "x axis title");
    assert!(
        texts(&svg).iter().any(|t| t.text.starts_with("22:41:0")),
        "times of day on the x axis"
    );
    // A raw file has no wall-clock time: seconds since the start.
    Command::cargo_bin("busnoop")
        .unwrap()
        .arg("plot")
        .arg(fixture("sport-sample.bin"))
        .args(["--sensor", "Alt", "-o"])
        .arg(&svg_path)
        .assert()
        .success();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.contains("time since the capture"));
}

/// `plot` takes the table's selection (--id, --type, --device …), the project file switches,
/// the protocol's own options after `--`, and a time range (--from/--to).
#[test]
fn plot_takes_the_tables_options_the_protocols_and_a_time_range() {
    let dir = tempfile::tempdir().unwrap();
    let svg_path = dir.path().join("p.svg");
    let log = fixture("edgetx-MODELE24-2014-07-11-sport.log");
    let plot = |args: &[&str]| {
        let out = Command::cargo_bin("busnoop")
            .unwrap()
            .current_dir(dir.path())
            .arg("plot")
            .arg("-o")
            .arg(&svg_path)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        let svg = std::fs::read_to_string(&svg_path).unwrap_or_default();
        let _ = std::fs::remove_file(&svg_path);
        (out.status.code(), legend(&svg), err)
    };
    let l = log.to_str().unwrap();
    // --id: only ID 8's numbers (named without @, no other ID has them now).
    let (code, names, err) = plot(&[l, "--id", "8"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(names, ["Cell1 (V)", "Cell2 (V)", "Cell3 (V)"], "{err}");
    // --device by name, --name naming an ID.
    let (_, names, _) = plot(&[
        l, "--name", "Pack=8", "--device", "Pack", "--sensor", "Cell1",
    ]);
    assert_eq!(names, ["Cell1 (V)"]);
    // --type, and a filter the protocol cannot match is refused as by the table.
    let (code, _, err) = plot(&[l, "--type", "Nope"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("types:"), "{err}");
    // The project file: read from ./busnoop.toml, ignored with --no-config.
    std::fs::write(dir.path().join("busnoop.toml"), "[sport.filter]\nid = 24\n").unwrap();
    let (_, names, _) = plot(&[l]);
    assert_eq!(names, ["SWR", "RSSI (dB)", "RxBt (V)"]);
    let (_, names, _) = plot(&[l, "--no-config"]);
    assert!(names.len() > 3, "{names:?}");
    std::fs::remove_file(dir.path().join("busnoop.toml")).unwrap();
    // The protocol's options after --: SAB's declared types.
    let sab = fixture("sab2-session.bin");
    let (code, names, err) = plot(&[
        sab.to_str().unwrap(),
        "--protocol",
        "sab2",
        "--sensor",
        "0x10",
        "--",
        "--value",
        "0x10=u16*0.01:m",
    ]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(names, ["0x10 (m)", "broken frame"], "{err}");
    let (code, _, err) = plot(&[l, "--", "--no-such-option"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("after --"), "{err}");
    // A time range: seconds since the start, or a time of day.
    for range in [
        ["--from", "3", "--to", "5"],
        ["--from", "22:41:04", "--to", "22:41:06"],
    ] {
        let mut args = vec![l, "--sensor", "RSSI"];
        args.extend(range);
        let out = Command::cargo_bin("busnoop")
            .unwrap()
            .arg("plot")
            .args(&args)
            .arg("-o")
            .arg(&svg_path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        let lines = series_lines(&svg);
        let m = markers_on(&svg, &lines[0]);
        let all = values("edgetx-MODELE24-2014-07-11-sport.log", "RSSI");
        assert!(
            m.len() < all.len() / 2 && m.len() >= 3,
            "{range:?}: {} of {}",
            m.len(),
            all.len()
        );
    }
    let (code, _, err) = plot(&[l, "--from", "soon"]);
    assert_eq!(code, Some(2), "{err}");
}

/// Kills the child if the test fails before it exited.
struct Guard(std::process::Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Waits for the child's exit, failing after [`common::PATIENCE`].
fn exit_within(child: &mut std::process::Child) -> std::process::ExitStatus {
    let deadline = std::time::Instant::now() + common::PATIENCE;
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        assert!(std::time::Instant::now() < deadline, "busnoop did not exit");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// M4 (issue 32): `plot -o out.svg` where out.svg is a FIFO without a reader blocked in
/// `open()` and ignored SIGINT/SIGTERM. Now a signal ends the wait (130/143), and a reader that
/// comes gets the image.
#[test]
fn a_fifo_image_without_a_reader_ends_on_a_signal() {
    for (sig, code) in [(libc::SIGINT, 130), (libc::SIGTERM, 143)] {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("p.svg");
        common::mkfifo(&fifo);
        let child = common::busnoop()
            .args(["plot", "--protocol", "sport"])
            .arg(fixture("sport-sample.bin"))
            .arg("-o")
            .arg(&fifo)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut g = Guard(child);
        common::wait_for_handlers(&g.0);
        unsafe { libc::kill(g.0.id() as i32, sig) };
        let status = exit_within(&mut g.0);
        assert_eq!(status.code(), Some(code));
    }
    // A reader that comes gets the whole image.
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("p.svg");
    common::mkfifo(&fifo);
    let child = common::busnoop()
        .args(["plot", "--protocol", "sport"])
        .arg(fixture("sport-sample.bin"))
        .arg("-o")
        .arg(&fifo)
        .spawn()
        .unwrap();
    let mut g = Guard(child);
    let svg = std::fs::read_to_string(&fifo).unwrap();
    assert_eq!(exit_within(&mut g.0).code(), Some(0));
    assert!(
        svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
        "{svg}"
    );
}

/// L4 (issue 32): a full disk replaced the old image with a cut one (the image was written in
/// place); now it is written to a temporary name and renamed, so the old image stays whole. L15:
/// the message is a sentence, not Rust debug text (`ImageError(IoError(Custom { … }))`).
#[test]
fn a_full_disk_keeps_the_old_image_and_says_so_plainly() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["p.svg", "p.png"] {
        let image = dir.path().join(name);
        let log = fixture("edgetx-MODELE24-2014-07-11-sport.log");
        let out = common::busnoop()
            .arg("plot")
            .arg(&log)
            .arg("-o")
            .arg(&image)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", common::text(&out.stderr));
        let old = std::fs::read(&image).unwrap();
        assert!(old.len() > 20_000, "{}", old.len());
        let mut cmd = common::busnoop();
        cmd.arg("plot").arg(&log).arg("-o").arg(&image);
        common::limit_file_size(&mut cmd, 10_000);
        let out = cmd.output().unwrap();
        let err = common::text(&out.stderr);
        assert_eq!(out.status.code(), Some(8), "{err}");
        assert!(
            std::fs::read(&image).unwrap() == old,
            "{name}: the old image is whole"
        );
        assert!(
            err.starts_with(&format!(
                "busnoop: cannot write {}: File too large",
                image.display()
            )),
            "{err}"
        );
        assert!(
            !err.contains("Error(") && !err.contains("Custom {"),
            "{err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
        // No temporary file left behind.
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), if name == "p.svg" { 1 } else { 2 }, "{left:?}");
    }
}

/// L4 (issue 32): an unwritable folder was found only after the whole input was decoded. Now
/// it is refused first: a FIFO input that no one writes is never waited for.
#[test]
fn an_unwritable_image_folder_is_refused_before_the_input_is_read() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    let feed = dir.path().join("feed");
    common::mkfifo(&feed);
    std::fs::set_permissions(&feed, std::fs::Permissions::from_mode(0o666)).unwrap();
    let (_keep, mut cmd) = common::unprivileged_busnoop();
    let child = cmd
        .args(["plot", "--protocol", "sport"])
        .arg(&feed)
        .arg("-o")
        .arg(locked.join("p.svg"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut g = Guard(child);
    let status = exit_within(&mut g.0);
    let mut err = String::new();
    std::io::Read::read_to_string(g.0.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(8), "{err}");
    assert!(
        err.contains("cannot create") && err.contains("ermission denied"),
        "{err}"
    );
}

/// M2 (issue 32): plot had no cap on series, found a row's series by a linear search and
/// labelled them quadratically: a crafted 3 MB capture took 60 s. Now at most 64 series, the
/// rest counted in a note.
#[test]
fn many_series_are_capped_with_a_note() {
    use busnoop::sport::wire;
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = Vec::new();
    for i in 0..30_000u32 {
        // 28 IDs × 400 app IDs: 11 200 series.
        let k = i % 11_200;
        wire::encode_frame(
            &mut bytes,
            wire::header_for((k % 28) as u8),
            0x10,
            0x5100 + (k / 28) as u16 * 16,
            i,
        );
    }
    let input = dir.path().join("series.bin");
    std::fs::write(&input, bytes).unwrap();
    let image = dir.path().join("p.svg");
    let t = std::time::Instant::now();
    let out = common::busnoop()
        .args(["plot", "--protocol", "sport"])
        .arg(&input)
        .arg("-o")
        .arg(&image)
        .output()
        .unwrap();
    let err = common::text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        t.elapsed() < std::time::Duration::from_secs(60),
        "{:?}",
        t.elapsed()
    );
    assert!(
        err.contains("plot: the first 64 series are drawn") && err.contains("--sensor"),
        "{err}"
    );
    let svg = std::fs::read_to_string(&image).unwrap();
    assert_eq!(series_lines(&svg).len(), 64);
}
