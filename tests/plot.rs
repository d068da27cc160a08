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
