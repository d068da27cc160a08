//! The words before clap sees them: `busnoop SOURCE` without a subcommand (detect the protocol,
//! then decode as it), and options written before the subcommand (`busnoop -f csv sport FILE`),
//! which go after it.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use crate::exit::Failure;

/// The command line, arranged.
pub enum Words {
    /// For clap as it is (a subcommand first, or help).
    Clap(Vec<OsString>),
    /// No subcommand: the word at `at` is SOURCE.
    Bare { argv: Vec<OsString>, at: usize },
}

/// Finds the first word that is not an option or an option's value: a subcommand (options
/// before it move after it), or SOURCE.
pub fn arrange(argv: Vec<OsString>) -> Words {
    let mut cmd = super::command();
    cmd.build();
    let takes_value = value_options(&cmd);
    let mut i = 1;
    let first = loop {
        let Some(a) = argv.get(i).map(|a| a.to_string_lossy()) else {
            break None;
        };
        if a == "--" {
            break (i + 1 < argv.len()).then_some(i + 1);
        }
        if let Some(long) = a.strip_prefix("--") {
            let takes = !long.contains('=') && takes_value.iter().any(|(_, l)| l == long);
            i += if takes { 2 } else { 1 };
        } else if a.len() > 1 && a.starts_with('-') {
            // A cluster of short options (`-vv`, `-fcsv`): the first that takes a value takes
            // the rest of the word, or the next word.
            let mut next = 1;
            for (k, c) in a.char_indices().skip(1) {
                if takes_value.iter().any(|(s, _)| *s == Some(c)) {
                    if k + c.len_utf8() == a.len() {
                        next = 2;
                    }
                    break;
                }
            }
            i += next;
        } else {
            break Some(i);
        }
    };
    let Some(at) = first else {
        return Words::Clap(argv);
    };
    let word = argv[at].to_string_lossy();
    let help = argv[1..at].iter().any(|a| {
        let a = a.to_string_lossy();
        matches!(a.as_ref(), "-h" | "--help" | "-V" | "--version")
    });
    // After `--`, a word is SOURCE even when it names a subcommand.
    if (is_subcommand(&cmd, &word) && argv[at - 1] != "--") || help {
        if at == 1 || help {
            return Words::Clap(argv);
        }
        // `busnoop -f csv sport FILE`: the subcommand first.
        let mut out = vec![argv[0].clone(), argv[at].clone()];
        out.extend(argv[1..at].iter().cloned());
        out.extend(argv[at + 1..].iter().cloned());
        return Words::Clap(out);
    }
    Words::Bare { argv, at }
}

/// The options that take a value, by short and long name (every subcommand's).
fn value_options(cmd: &clap::Command) -> Vec<(Option<char>, String)> {
    let mut out = Vec::new();
    let mut add = |c: &clap::Command| {
        for a in c.get_arguments() {
            if a.is_positional() || !a.get_action().takes_values() {
                continue;
            }
            if let Some(l) = a.get_long() {
                out.push((a.get_short(), l.to_owned()));
                for alias in a.get_all_aliases().into_iter().flatten() {
                    out.push((None, alias.to_owned()));
                }
            }
        }
    };
    add(cmd);
    for sub in cmd.get_subcommands() {
        add(sub);
    }
    out
}

/// A subcommand of busnoop (a protocol's, an alias, or one of the others).
fn is_subcommand(cmd: &clap::Command, word: &str) -> bool {
    word == "help"
        || cmd
            .get_subcommands()
            .any(|s| s.get_name() == word || s.get_all_aliases().any(|a| a == word))
}

/// `busnoop SOURCE [OPTIONS]`: detects SOURCE's protocol (a file's start, or a serial port at
/// each usual speed), says on stderr what was chosen and why, and returns the command line of
/// that protocol's subcommand. A pipe cannot be detected and then read again; an input without
/// a clear winner gets the detect report on stderr and exit code 11.
pub fn resolve(argv: Vec<OsString>, at: usize) -> Result<Vec<OsString>, Failure> {
    let source = PathBuf::from(&argv[at]);
    let commands = crate::protocols::commands();
    if super::is_dash(&source) || is_fifo(&source) {
        return Err(Failure::Usage(format!(
            "{}: a pipe can be read only once, so busnoop cannot detect its protocol and then \
             decode it; name the protocol: busnoop {commands} {}",
            shown(&source),
            source.display()
        )));
    }
    let word = source.to_string_lossy();
    if std::fs::symlink_metadata(&source).is_err() && !word.contains(['/', '.', '\\']) {
        // A mistyped subcommand rather than a file.
        let near = crate::protocols::PROTOCOLS
            .iter()
            .map(|p| p.command)
            .chain(["detect", "plot", "ports", "extcap", "completions", "man"])
            .find(|c| distance(c, &word) <= 2);
        let hint = match near {
            Some(c) => format!("; did you mean `busnoop {c}`?"),
            None => String::new(),
        };
        return Err(Failure::Usage(format!(
            "`{word}` is neither a subcommand nor a file or device{hint} (busnoop --help lists \
             the subcommands)"
        )));
    }
    let rest: Vec<String> = argv[1..]
        .iter()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let baud = value_of(&rest, "--baud");
    let bauds: Vec<u32> = baud
        .iter()
        .filter_map(|b| super::parse_baud(b).ok())
        .collect();
    let dtr_rts = match value_of(&rest, "--dtr-rts").as_deref() {
        Some("keep") => crate::source::serial::ModemLines::Keep,
        _ => crate::source::serial::ModemLines::default(),
    };
    let chosen = crate::detect::choose(&source, &bauds, dtr_rts).map_err(|f| match f {
        Failure::NoProtocol(m) => Failure::NoProtocol(format!(
            "{m}; to decode it anyway, name the protocol: busnoop {commands} {}",
            crate::detect::shell_quote(&source)
        )),
        f => f,
    })?;
    let p = chosen.protocol;
    let mut command = format!("busnoop {}", p.command);
    for a in chosen.args {
        command.push(' ');
        command.push_str(a);
    }
    let at_baud = chosen.baud.filter(|&b| b != p.line.baud && baud.is_none());
    if let Some(b) = at_baud {
        command.push_str(&format!(" --baud {b}"));
    }
    command.push(' ');
    command.push_str(&crate::detect::shell_quote(&source));
    if chosen.inverted {
        return Err(Failure::NoProtocol(format!(
            "{}: {} with inverted bytes; busnoop decodes it once the line is inverted back \
             (the report above says how), with {command}",
            shown(&source),
            p.name
        )));
    }
    if let Some(rival) = &chosen.rival {
        return Err(Failure::NoProtocol(format!(
            "{}: {} and {rival} fit about as well (the report above); name the protocol: \
             {command}, or busnoop detect {} for the evidence",
            shown(&source),
            chosen.label,
            crate::detect::shell_quote(&source)
        )));
    }
    let heard = chosen
        .baud
        .map_or(String::new(), |b| format!(" at {b} baud"));
    eprintln!(
        "busnoop: decoding as {}{heard}: {} (detected; `{command}` skips the detection)",
        chosen.label, chosen.why
    );
    let mut out = vec![argv[0].clone(), OsString::from(p.command)];
    out.extend(chosen.args.iter().map(OsString::from));
    if let Some(b) = at_baud {
        out.push("--baud".into());
        out.push(b.to_string().into());
    }
    out.extend(argv[1..].iter().cloned());
    Ok(out)
}

/// The value of `--name VALUE` or `--name=VALUE`, the last one given.
fn value_of(args: &[String], name: &str) -> Option<String> {
    let mut found = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == name {
            found = it.next().cloned();
        } else if let Some(v) = a.strip_prefix(name).and_then(|r| r.strip_prefix('=')) {
            found = Some(v.to_owned());
        }
    }
    found
}

fn is_fifo(p: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::metadata(p).is_ok_and(|m| m.file_type().is_fifo())
}

/// Standard input by its name.
fn shown(p: &Path) -> String {
    if super::is_dash(p) {
        "standard input".into()
    } else {
        p.display().to_string()
    }
}

/// Edit distance (insertions, deletions, substitutions) between two short words.
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(w: &[&str]) -> Words {
        arrange(w.iter().map(OsString::from).collect())
    }

    fn clap(w: Words) -> Vec<String> {
        match w {
            Words::Clap(v) => v.iter().map(|a| a.to_string_lossy().into_owned()).collect(),
            Words::Bare { .. } => panic!("bare"),
        }
    }

    #[test]
    fn options_before_the_subcommand_go_after_it() {
        assert_eq!(
            clap(words(&["busnoop", "-f", "csv", "sport", "x.bin"])),
            ["busnoop", "sport", "-f", "csv", "x.bin"]
        );
        assert_eq!(
            clap(words(&["busnoop", "--stats", "-fcsv", "sab", "x"])),
            ["busnoop", "sab", "--stats", "-fcsv", "x"]
        );
        assert_eq!(
            clap(words(&["busnoop", "sport", "-f", "csv", "x"])),
            ["busnoop", "sport", "-f", "csv", "x"]
        );
        // Help before a subcommand stays clap's.
        assert_eq!(
            clap(words(&["busnoop", "--help", "sport"])),
            ["busnoop", "--help", "sport"]
        );
        assert_eq!(clap(words(&["busnoop"])), ["busnoop"]);
        assert_eq!(clap(words(&["busnoop", "-V"])), ["busnoop", "-V"]);
    }

    #[test]
    fn a_word_that_is_no_subcommand_is_the_source() {
        for (w, at) in [
            (&["busnoop", "x.bin"][..], 1),
            (&["busnoop", "-f", "csv", "x.bin", "--stats"][..], 3),
            (&["busnoop", "--baud=9600", "-o", "sport", "x"][..], 4),
            (&["busnoop", "-v", "--", "sport"][..], 3),
        ] {
            match words(w) {
                Words::Bare { at: a, .. } => assert_eq!(a, at, "{w:?}"),
                Words::Clap(_) => panic!("{w:?}"),
            }
        }
    }

    #[test]
    fn edit_distance() {
        assert_eq!(distance("sport", "sprot"), 2);
        assert_eq!(distance("sport", "sport"), 0);
        assert_eq!(distance("detect", "detetc"), 2);
        assert_eq!(distance("sab2", "sbus"), 3);
    }
}
