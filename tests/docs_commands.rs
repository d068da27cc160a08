//! Every `busnoop …` command in README.md and docs/*.md is run, so that the documentation never
//! drifts from the program (docs/usage.md, "Documentation tests", states these rules):
//!
//! - A command is a line of a fenced code block (```` ```sh ````, ```` ```console ````, or a
//!   block without a language) that starts with `busnoop ` or `$ busnoop `, or pipes into
//!   `busnoop` or runs it after `&&` (`cat f | busnoop sport -`, `mkdir -p d && busnoop …`). A line ending in `\` goes on on the next one.
//! - It runs in `bash -o pipefail` in a scratch directory holding a copy of `fixtures/` and an
//!   empty `docs/`, with HOME there too and this build's busnoop first on PATH, standard input
//!   empty, and must exit 0 within 20 s.
//! - `<!-- doc-test: skip REASON -->` on the line before a block: its commands are not run (a
//!   serial port, Wireshark); the reason is required. `<!-- doc-test: exit N -->`: they must
//!   exit with code N.
//! - The names the examples give a user's own files are there too, made from the fixtures for
//!   each document ([`EXAMPLES`]): `flight.log` is the EdgeTX S.Port log, `capture.bin` the
//!   document's protocol's capture, `flight.pcap` a recording of the flight, and so on.
//! - In a block whose commands start with `$ `, the lines after a command up to the next `$ `
//!   line are its output: each one (spaces collapsed; `...` and `…` lines skipped) must be a
//!   line of what the command writes (stdout or stderr). A decoded table is
//!   shown as a terminal shows it (pretty): when the output as written does not hold the lines,
//!   the command is run once more with `-f pretty`, which is what a terminal gets.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// One command of the documentation.
#[derive(Debug)]
struct Doc {
    file: String,
    line: usize,
    command: String,
    exit: i32,
    /// The lines shown as its output (console blocks).
    shown: Vec<String>,
}

/// The example files of each document (`*` for all): a name, and either a fixture to copy or
/// the busnoop arguments that record it (in the scratch directory, after the copies).
const EXAMPLES: &[(&str, &str, Example)] = &[
    (
        "*",
        "flight.log",
        Copy("edgetx-MODELE24-2014-07-11-sport.log"),
    ),
    (
        "*",
        "flight.pcap",
        Record("sport flight.log --record flight.pcap"),
    ),
    (
        "*",
        "rx.pcapng",
        Record("sport fixtures/sport-sample.bin --record rx.pcapng"),
    ),
    (
        "*",
        "tx.pcapng",
        Record("sport flight.log --record tx.pcapng"),
    ),
    ("*", "robot.bin", Copy("sab2-session.bin")),
    (
        "*",
        "robot.pcap",
        Record("sab2 robot.bin --record robot.pcap"),
    ),
    (
        "*",
        "robot.pcapng",
        Record("sab2 robot.bin --record robot.pcapng"),
    ),
    ("*", "capture.pcapng", Copy("sbus-digimat.pcap")),
    ("*", "servo.bin", Copy("ibus-rc.bin")),
    ("docs/usage.md", "capture.bin", Copy("sport-sample.bin")),
    ("docs/plot.md", "capture.bin", Copy("sport-sample.bin")),
    ("docs/sab.md", "capture.bin", Copy("sab2-session.bin")),
    ("docs/futaba.md", "capture.bin", Copy("futaba-session.bin")),
    ("docs/ibus.md", "capture.bin", Copy("ibus-sensors.bin")),
];

#[derive(Clone, std::marker::Copy)]
enum Example {
    Copy(&'static str),
    Record(&'static str),
}
use Example::{Copy, Record};

/// A scratch directory for the commands of `doc`: the fixtures, an empty docs/, the examples.
fn scratch(doc: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    copy_dir(&root().join("fixtures"), &dir.path().join("fixtures"));
    std::fs::create_dir_all(dir.path().join("docs")).unwrap();
    let mine = EXAMPLES.iter().filter(|(d, _, _)| *d == "*" || *d == doc);
    for (_, name, how) in mine.clone() {
        if let Copy(f) = how {
            std::fs::copy(root().join("fixtures").join(f), dir.path().join(name)).unwrap();
        }
    }
    for (_, name, how) in mine {
        if let Record(args) = how {
            let (code, text) = run(&format!("busnoop {args} -q --lenient"), dir.path());
            assert_eq!(code, Some(0), "{name}: {text}");
        }
    }
    dir
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The documentation files: README.md and every docs/*.md.
fn documents() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// Whether `line` is a command: `busnoop` as its first word or after a pipe.
fn is_command(line: &str) -> bool {
    line.starts_with("busnoop ")
        || line == "busnoop"
        || line
            .split(['|', '&'])
            .skip(1)
            .any(|p| p.trim_start().starts_with("busnoop "))
}

/// The commands of one document.
fn commands(file: &Path) -> Vec<Doc> {
    let text = std::fs::read_to_string(file).unwrap();
    let name = file.strip_prefix(root()).unwrap().display().to_string();
    let mut out: Vec<Doc> = Vec::new();
    let mut in_block = false;
    let mut code = true;
    let mut skip: Option<String> = None;
    let mut exit = 0;
    let mut marker = (None::<String>, 0);
    let mut pending = String::new();
    let mut console = false;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if !in_block {
            if let Some(m) = trimmed
                .strip_prefix("<!-- doc-test:")
                .and_then(|m| m.strip_suffix("-->"))
            {
                let m = m.trim();
                if let Some(reason) = m.strip_prefix("skip") {
                    assert!(
                        !reason.trim().is_empty(),
                        "{name}:{}: doc-test: skip needs a reason",
                        i + 1
                    );
                    marker = (Some(reason.trim().to_string()), 0);
                } else if let Some(n) = m.strip_prefix("exit") {
                    marker = (None, n.trim().parse().expect("doc-test: exit N"));
                } else {
                    panic!("{name}:{}: unknown doc-test marker {m:?}", i + 1);
                }
                continue;
            }
            if let Some(lang) = trimmed.strip_prefix("```") {
                in_block = true;
                code = matches!(lang, "" | "sh" | "console" | "shell" | "bash");
                console = false;
                (skip, exit) = std::mem::take(&mut marker);
                continue;
            }
            if !trimmed.is_empty() {
                marker = (None, 0);
            }
            continue;
        }
        if trimmed.starts_with("```") {
            in_block = false;
            continue;
        }
        if !code || skip.is_some() {
            continue;
        }
        let (cmd, dollar) = match trimmed.strip_prefix("$ ") {
            Some(c) => (c, true),
            None => (trimmed, false),
        };
        if !pending.is_empty() {
            pending.push(' ');
            pending.push_str(trimmed.trim_end_matches('\\'));
            if !trimmed.ends_with('\\')
                && let Some(d) = out.last_mut()
            {
                d.command = std::mem::take(&mut pending);
            }
            continue;
        }
        if is_command(cmd) {
            console |= dollar;
            let command = cmd.trim_end_matches('\\').trim_end().to_string();
            if cmd.ends_with('\\') {
                pending = command.clone();
            }
            out.push(Doc {
                file: name.clone(),
                line: i + 1,
                command,
                exit,
                shown: Vec::new(),
            });
        } else if dollar {
            // Another tool's command: its output is not busnoop's.
            console = false;
        } else if console && let Some(d) = out.last_mut() {
            let l = collapse(line);
            if !l.is_empty() && l != "..." && l != "…" {
                d.shown.push(l);
            }
        }
    }
    out
}

/// Spaces and tabs collapsed, the ends trimmed.
fn collapse(line: &str) -> String {
    line.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// Runs `command` in `dir`: its exit code and what it wrote (stdout, then stderr).
fn run(command: &str, dir: &Path) -> (Option<i32>, String) {
    let bin = assert_cmd::cargo::cargo_bin("busnoop");
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    // A command that waits (a serial port with --reconnect) is cut after 20 s: exit 124.
    let out = Command::new("timeout")
        .args(["20", "bash", "-o", "pipefail", "-c", command])
        .current_dir(dir)
        .env("HOME", dir)
        .env("PATH", path)
        .env_remove("NO_COLOR")
        .env_remove("RUST_LOG")
        .env_remove("COLUMNS")
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    let mut text = common::text(&out.stdout);
    text.push_str(&common::text(&out.stderr));
    (out.status.code(), text)
}

/// Whether each of `shown` is a line of `written` (spaces collapsed; stdout and stderr are
/// apart, so not in order).
fn shows(shown: &[String], written: &str) -> Result<(), String> {
    let lines: Vec<String> = written.lines().map(collapse).collect();
    match shown.iter().find(|s| !lines.contains(s)) {
        Some(s) => Err(s.clone()),
        None => Ok(()),
    }
}

#[test]
fn every_documented_command_runs() {
    let docs: Vec<Doc> = documents().iter().flat_map(|f| commands(f)).collect();
    assert!(docs.len() > 40, "{} commands found", docs.len());
    // Issue 30: the first command a reader can run was at line 70, after completions and man
    // pages. It is in the first screen, with what it prints.
    let first = docs
        .iter()
        .find(|d| d.file == "README.md")
        .expect("a README command");
    assert!(
        first.line <= 40,
        "the README's first run is at line {}",
        first.line
    );
    assert!(
        !first.shown.is_empty(),
        "the README's first run shows its output"
    );
    let mut failures = Vec::new();
    let mut dirs: Vec<(String, tempfile::TempDir)> = Vec::new();
    for d in &docs {
        if !dirs.iter().any(|(f, _)| *f == d.file) {
            dirs.push((d.file.clone(), scratch(&d.file)));
        }
        let scratch = &dirs.iter().find(|(f, _)| *f == d.file).unwrap().1;
        let (code, written) = run(&d.command, scratch.path());
        if code != Some(d.exit) {
            failures.push(format!(
                "{}:{}: `{}` exited {code:?}, not {}:\n{}",
                d.file,
                d.line,
                d.command,
                d.exit,
                written.lines().take(6).collect::<Vec<_>>().join("\n")
            ));
            continue;
        }
        if d.shown.is_empty() {
            continue;
        }
        if let Err(first) = shows(&d.shown, &written) {
            let pretty = run(&format!("{} -f pretty", d.command), scratch.path());
            if let Err(missing) = shows(&d.shown, &pretty.1) {
                failures.push(format!(
                    "{}:{}: `{}` does not write the line shown:\n  {}\n(as written, first \
                     missing: {first})\nit wrote:\n{}",
                    d.file,
                    d.line,
                    d.command,
                    missing,
                    pretty.1.lines().take(12).collect::<Vec<_>>().join("\n")
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} documented commands fail:\n\n{}",
        failures.len(),
        docs.len(),
        failures.join("\n\n")
    );
}

/// The reader itself: markers, continuation lines, console output, other tools' commands.
#[test]
fn the_reader_finds_commands_markers_and_output() {
    let dir = tempfile::tempdir().unwrap();
    let md = dir.path().join("x.md");
    std::fs::write(
        &md,
        "text `busnoop inline` is no command\n\
         ```sh\n\
         busnoop sport a.bin   # comment\n\
         cat a.bin | busnoop sport -\n\
         mkdir x\n\
         busnoop sport a.bin \\\n  --stats\n\
         ```\n\
         <!-- doc-test: skip needs a serial port -->\n\
         ```sh\n\
         busnoop sport /dev/ttyUSB0\n\
         ```\n\
         <!-- doc-test: exit 11 -->\n\
         ```console\n\
         $ busnoop detect noise.bin\n\
         verdict:   no known protocol\n\
         ...\n\
         $ ls\n\
         a.bin\n\
         ```\n\
         ```text\n\
         busnoop sport in-a-text-block\n\
         ```\n",
    )
    .unwrap();
    // `commands` names files relative to the crate: read it from there.
    let here = root().join("target").join("doc-test-reader.md");
    std::fs::copy(&md, &here).unwrap();
    let docs = commands(&here);
    let _ = std::fs::remove_file(&here);
    let got: Vec<(&str, i32, usize)> = docs
        .iter()
        .map(|d| (d.command.as_str(), d.exit, d.shown.len()))
        .collect();
    assert_eq!(
        got,
        [
            ("busnoop sport a.bin   # comment", 0, 0),
            ("cat a.bin | busnoop sport -", 0, 0),
            ("busnoop sport a.bin --stats", 0, 0),
            ("busnoop detect noise.bin", 11, 1),
        ]
    );
    assert_eq!(docs[3].shown, ["verdict: no known protocol"]);
    assert!(shows(&docs[3].shown, "x\nverdict:  no known protocol\n").is_ok());
    assert!(shows(&docs[3].shown, "verdict: S.Port\n").is_err());
}
