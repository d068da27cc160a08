//! Data safety on the command line: an output, a recording, an export or a plot is never the
//! input (file, link, pipe, serial port) nor another output, and is checked before anything is
//! written (docs/robustness.md, "Paths and options"). Special outputs and options: tests/outputs.rs.

mod common;

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};

use common::fixture;
use common::{busnoop, capture, no_panic, output_within, text};

/// The run was refused with a usage error naming the clash, and `path` still holds `bytes`.
fn refused(out: &Output, path: &Path, bytes: &[u8]) {
    no_panic(out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("same file"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        std::fs::read(path).unwrap() == bytes,
        "{} was changed",
        path.display()
    );
}

#[test]
fn output_onto_the_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap");

    // -o onto the input, directly, through a symlink either way, through a hard link.
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&cap)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    let sym = dir.path().join("sym");
    std::os::unix::fs::symlink(&cap, &sym).unwrap();
    for (src, dst) in [(&cap, &sym), (&sym, &cap)] {
        let out = busnoop()
            .arg("sport")
            .arg(src)
            .arg("-o")
            .arg(dst)
            .output()
            .unwrap();
        refused(&out, &cap, &bytes);
    }
    let hard = dir.path().join("hard");
    std::fs::hard_link(&cap, &hard).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&hard)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);

    // A capture's own name (`-o a.bin` onto a.bin): the clash is named, not the hint to use
    // --record a.bin, which would point at the input again.
    let (bin, bin_bytes) = capture(dir.path(), "a.bin");
    let out = busnoop()
        .arg("sport")
        .arg(&bin)
        .arg("-o")
        .arg(&bin)
        .output()
        .unwrap();
    refused(&out, &bin, &bin_bytes);

    // Standard input is the file: `busnoop sport - -o cap < cap`.
    let out = busnoop()
        .args(["sport", "-", "-o"])
        .arg(&cap)
        .stdin(std::fs::File::open(&cap).unwrap())
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);

    // --record onto the input.
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&hard)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);

    // Standard output appends to the input: `busnoop sport - < cap >> cap`.
    let out = busnoop()
        .args(["sport", "-"])
        .stdin(std::fs::File::open(&cap).unwrap())
        .stdout(std::fs::OpenOptions::new().append(true).open(&cap).unwrap())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
}

#[test]
fn a_plot_onto_its_input_is_refused() {
    // `busnoop plot` writes .svg or .png: a capture under such a name (or a link of that name
    // to the capture) must not become the image.
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap.svg");
    let out = busnoop()
        .args(["plot", "--protocol", "sport"])
        .arg(&cap)
        .arg("-o")
        .arg(&cap)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    let png = dir.path().join("link.png");
    std::os::unix::fs::symlink(&cap, &png).unwrap();
    let out = busnoop()
        .args(["plot", "--protocol", "sport"])
        .arg(&cap)
        .arg("-o")
        .arg(&png)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
}

#[test]
fn a_recording_replayed_onto_itself_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let rec = dir.path().join("rec.pcap");
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&rec)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let bytes = std::fs::read(&rec).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&rec)
        .arg("--record")
        .arg(&rec)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    refused(&out, &rec, &bytes);
}

#[test]
fn record_and_output_onto_one_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap");
    // X does not exist yet: the names are compared.
    let x = dir.path().join("x.txt");
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("-o")
        .arg(dir.path().join(".").join("x.txt"))
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    assert!(!x.exists(), "nothing is created");
    // X exists: the files are compared.
    std::fs::write(&x, b"keep").unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("-o")
        .arg(&x)
        .output()
        .unwrap();
    refused(&out, &x, b"keep");
}

/// A refused run: exit code 2 and one line naming the clash and what writing would do.
fn refused_saying(out: &Output, consequence: &str) {
    no_panic(out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("same file"), "{err}");
    assert!(err.contains(consequence), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
}

#[test]
fn output_into_the_input_pipe_is_refused() {
    // `… | busnoop sport - -o /dev/stdin`: the output would be the pipe busnoop reads, which
    // then never ends (busnoop holds its write end) and carries busnoop's own rows back in.
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    for args in [
        ["sport", "-", "-o", "/dev/stdin"],
        ["sport", "-", "--record", "/dev/stdin"],
    ] {
        let out = output_within(busnoop().args(args), Some(sample.clone()), Stdio::piped());
        refused_saying(&out, "its own output");
    }

    // A named pipe given as the input and as the output.
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    common::mkfifo(&fifo);
    let out = output_within(
        busnoop().arg("sport").arg(&fifo).arg("-o").arg(&fifo),
        None,
        Stdio::piped(),
    );
    refused_saying(&out, "its own output");
}

#[test]
fn output_onto_the_serial_port_is_refused() {
    // `busnoop sport /dev/ttyUSB0 -o /dev/ttyUSB0` (or `> /dev/ttyUSB0`, or `--record` there)
    // would transmit the table on the bus: a passive sniffer never sends a byte.
    let _lock = common::pty::lock();
    let mut bus = common::pty::bus();
    let dev = bus.path.clone();
    for opt in ["-o", "--record"] {
        let out = output_within(
            busnoop().arg("sport").arg(&dev).arg(opt).arg(&dev),
            None,
            Stdio::piped(),
        );
        refused_saying(&out, "transmit");
    }
    let tty = std::fs::OpenOptions::new().write(true).open(&dev).unwrap();
    let out = output_within(busnoop().arg("sport").arg(&dev), None, tty.into());
    no_panic(&out);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("transmit"),
        "{}",
        text(&out.stderr)
    );
    // Nothing reached the bus side.
    serialport::SerialPort::set_timeout(&mut bus.master, std::time::Duration::from_millis(200))
        .unwrap();
    let mut buf = [0u8; 64];
    let got = std::io::Read::read(&mut bus.master, &mut buf);
    assert!(
        !matches!(got, Ok(n) if n > 0),
        "busnoop wrote to the bus: {got:?} {:?}",
        &buf[..*got.as_ref().unwrap_or(&0)]
    );
}

/// `--export` is an output like `-o` and `--record`: compared with them as files, not as
/// names (`--record x.pcapng --export ./x.pcapng` used to write both into one file, the
/// recording's blocks and the export's interleaved), and the message names `--export`.
#[test]
fn export_onto_the_recording_or_the_table_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let x = dir.path().join("x.pcapng");
    // X does not exist yet: two spellings of one name (`Path`'s `==` would see through a
    // `.`, not through `sub/..`).
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("--export")
        .arg(dir.path().join("sub/../x.pcapng"))
        .args(["-o", "/dev/null"])
        .output()
        .unwrap();
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--export") && err.contains("same file"),
        "{err}"
    );
    assert!(!x.exists(), "nothing is created");
    // X exists, named through a symbolic link.
    std::fs::write(&x, b"keep").unwrap();
    let link = dir.path().join("link.pcapng");
    std::os::unix::fs::symlink(&x, &link).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--record")
        .arg(&x)
        .arg("--export")
        .arg(&link)
        .args(["-o", "/dev/null"])
        .output()
        .unwrap();
    refused(&out, &x, b"keep");
    assert!(text(&out.stderr).contains("--export"));
    // Standard output appended to the export: the message names --export, not --record.
    let stdout = std::fs::OpenOptions::new().append(true).open(&x).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("--export")
        .arg(&x)
        .stdout(stdout)
        .output()
        .unwrap();
    refused(&out, &x, b"keep");
    let err = text(&out.stderr);
    assert!(err.contains("standard output and --export"), "{err}");
}

/// An output named through a symbolic link whose target does not exist yet is created at the
/// target: `-o out.csv --record r.pcap` with `out.csv -> r.pcap` used to pass the check (a
/// dangling link had no name to compare) and wrote the table into the recording.
#[test]
fn outputs_meeting_through_a_dangling_link_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, bytes) = capture(dir.path(), "cap");
    let rec = dir.path().join("r.pcap");
    let link = dir.path().join("out.csv");
    std::os::unix::fs::symlink("r.pcap", &link).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&link)
        .arg("--record")
        .arg(&rec)
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    assert!(!rec.exists(), "nothing is created");
    // A chain of links, the last one dangling, to the export.
    let hop = dir.path().join("hop.pcapng");
    std::os::unix::fs::symlink("e.pcapng", &hop).unwrap();
    let first = dir.path().join("first.csv");
    std::os::unix::fs::symlink(&hop, &first).unwrap();
    let out = busnoop()
        .arg("sport")
        .arg(&cap)
        .arg("-o")
        .arg(&first)
        .arg("--export")
        .arg(dir.path().join("e.pcapng"))
        .output()
        .unwrap();
    refused(&out, &cap, &bytes);
    assert!(!dir.path().join("e.pcapng").exists(), "nothing is created");
}

/// `busnoop plot`'s image name and folder are checked before the capture is read: they used
/// to be checked only when the image was drawn, after the whole input (a pipe, a FIFO, a long
/// capture) had been decoded, and a wrong extension was exit code 8. Here the input is a FIFO
/// no one writes to: reading it would wait for ever.
#[test]
fn a_plot_checks_its_image_name_before_reading_the_capture() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    common::mkfifo(&fifo);
    let plot = |image: PathBuf| {
        output_within(
            busnoop()
                .arg("plot")
                .arg(&fifo)
                .args(["--protocol", "sport", "-o"])
                .arg(image),
            None,
            Stdio::piped(),
        )
    };
    let out = plot(dir.path().join("flight.txt"));
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(".svg or .png"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    let out = plot(dir.path().join("no-such-folder").join("flight.svg"));
    no_panic(&out);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(8), "{err}");
    assert!(
        err.contains("no-such-folder") && err.contains("No such file or directory"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

/// An output into a folder that does not exist is refused before any output is created: a
/// typo in `-o` used to fail only after the recording and the export had been created (and an
/// existing recording of that name emptied), a typo in `--record` after the table had.
#[test]
fn an_output_into_a_missing_folder_creates_no_other_output() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let missing = dir.path().join("no-such-folder");
    let rec = dir.path().join("r.pcap");
    std::fs::write(&rec, b"keep").unwrap();
    let export = dir.path().join("e.pcapng");
    let table = dir.path().join("t.csv");
    let runs: [(&str, PathBuf, &str, PathBuf, &str, PathBuf); 3] = [
        (
            "-o",
            missing.join("t.csv"),
            "--record",
            rec.clone(),
            "--export",
            export.clone(),
        ),
        (
            "-o",
            table.clone(),
            "--record",
            missing.join("r.pcap"),
            "--export",
            export.clone(),
        ),
        (
            "-o",
            table.clone(),
            "--record",
            rec.clone(),
            "--export",
            missing.join("e.pcapng"),
        ),
    ];
    for (o, a, r, b, e, c) in runs {
        let out = busnoop()
            .arg("sport")
            .arg(&cap)
            .args([
                o.as_ref(),
                a.as_os_str(),
                r.as_ref(),
                b.as_os_str(),
                e.as_ref(),
                c.as_os_str(),
            ])
            .output()
            .unwrap();
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(8), "{err}");
        assert!(
            err.contains("no-such-folder") && err.contains("No such file"),
            "{err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(
            std::fs::read(&rec).unwrap(),
            b"keep",
            "the recording was emptied"
        );
        assert!(
            !export.exists() && !table.exists(),
            "an output was created: {err}"
        );
    }
}

/// The project file is an input too: `-o busnoop.toml` (the one in the current folder, read
/// without being named), `--config my.toml -o my.toml`, or a link to it, used to overwrite it
/// with the table (a note said only that .toml is no table format).
#[test]
fn output_onto_the_project_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (cap, _) = capture(dir.path(), "cap");
    let project = b"[sport]\nnames = { Rx = 24 }\n";
    let toml = dir.path().join("busnoop.toml");
    std::fs::write(&toml, project).unwrap();
    let link = dir.path().join("notes.txt");
    std::os::unix::fs::symlink("busnoop.toml", &link).unwrap();
    let mine = dir.path().join("my.toml");
    std::fs::write(&mine, project).unwrap();
    let runs: [(Vec<&OsStr>, &Path); 3] = [
        (vec!["-o".as_ref(), "busnoop.toml".as_ref()], &toml),
        (vec!["-o".as_ref(), link.as_os_str()], &toml),
        (
            vec![
                "--config".as_ref(),
                mine.as_os_str(),
                "-o".as_ref(),
                "./my.toml".as_ref(),
            ],
            &mine,
        ),
    ];
    for (args, file) in runs {
        let out = busnoop()
            .current_dir(dir.path())
            .arg("sport")
            .arg(&cap)
            .args(&args)
            .output()
            .unwrap();
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("project file"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(std::fs::read(file).unwrap(), project, "{args:?}");
    }
}
