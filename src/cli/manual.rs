//! `busnoop completions SHELL` and `busnoop man`: the shell completion scripts and the manual
//! pages, generated from the command-line definition itself so they never drift from it.

use std::path::Path;

use crate::exit::Failure;

/// Writes the completion script for `shell` to standard output.
pub fn completions(shell: clap_complete::Shell) -> Result<(), Failure> {
    let mut cmd = super::command();
    let mut buf = Vec::new();
    clap_complete::generate(shell, &mut cmd, "busnoop", &mut buf);
    crate::exit::write_stdout(&buf)
}

/// The exit codes as busnoop(1) lists them under EXIT STATUS (README.md and docs/usage.md,
/// "Exit codes", say the same at length).
pub const EXIT_CODES: &[(u8, &str)] = {
    use crate::exit::code::*;
    &[
        (
            OK,
            "the whole input was read (bad frames, if any, are rows and counted)",
        ),
        (INTERNAL, "internal error"),
        (
            USAGE,
            "wrong command-line usage, a value out of its range, an output that is the input",
        ),
        (NOT_FOUND, "input file or device not found, or a directory"),
        (PERMISSION, "permission denied (file or serial device)"),
        (BUSY, "serial port in use by another program"),
        (DEVICE, "serial device could not be opened or configured"),
        (DISCONNECTED, "adapter disconnected during a live capture"),
        (OUTPUT, "the output could not be written (a full disk)"),
        (
            INPUT,
            "the input could not be read, or is not usable by this protocol",
        ),
        (
            NOTHING_DECODED,
            "nothing decoded: an empty input, or not one frame of the protocol",
        ),
        (
            NO_PROTOCOL,
            "detect, or a SOURCE without a protocol: no known protocol, or no clear one",
        ),
        (
            CONFIG,
            "the project file (busnoop.toml, --config) is unusable",
        ),
        (
            POOR,
            "mostly not valid frames of the protocol (rows written); --lenient accepts",
        ),
        (
            SIGHUP,
            "stopped by a hangup (SIGHUP) after writing every decoded row",
        ),
        (
            SIGINT,
            "stopped by Ctrl-C (SIGINT) after writing every decoded row",
        ),
        (
            BROKEN_PIPE,
            "standard output (or a pipe written to) was closed by its reader",
        ),
        (
            SIGTERM,
            "stopped by SIGTERM after writing every decoded row",
        ),
    ]
};

/// The command line as the manual pages show it: no `help` subcommand (its page is not
/// written), so no page names one that `man --dir` does not write.
fn for_man() -> clap::Command {
    super::command().disable_help_subcommand(true)
}

/// A section rendered alone, without roff's preamble (the page has it once).
fn section(render: impl FnOnce(&mut Vec<u8>) -> std::io::Result<()>) -> std::io::Result<String> {
    let mut buf = Vec::new();
    render(&mut buf)?;
    let text = String::from_utf8_lossy(&buf).into_owned();
    Ok(text
        .lines()
        .filter(|l| !l.starts_with(".ie \\n(.g .ds Aq") && !l.starts_with(".el .ds Aq"))
        .map(|l| format!("{l}\n"))
        .collect())
}

/// Text for a roff paragraph: backslashes, hyphens and a leading dot escaped.
fn roff_text(t: &str) -> String {
    let t = t.replace('\\', "\\e").replace('-', "\\-");
    match t.starts_with('.') || t.starts_with('\'') {
        true => format!("\\&{t}"),
        false => t,
    }
}

/// The options every protocol's subcommand takes, with their general texts (each
/// subcommand's page says them in the protocol's words), grouped as in `--help`.
fn shared_options() -> std::io::Result<String> {
    use clap::Args;
    let mut cmd = super::args::CaptureArgs::augment_args(clap::Command::new("busnoop"));
    cmd = cmd
        .mut_arg("source", |a| a.hide(true))
        .mut_arg("more", |a| a.hide(true));
    let text = section(|w| clap_mangen::Man::new(cmd).render_options_section(w))?;
    let mut out = String::new();
    for line in text.lines() {
        match line.strip_prefix(".SH ") {
            Some("OPTIONS") => {
                out.push_str(".SH \"SHARED OPTIONS\"\n");
                out.push_str(&roff_text(
                    "Every protocol subcommand (busnoop PROTOCOL SOURCE [OPTIONS], and a bare \
                     busnoop SOURCE) takes these; busnoop PROTOCOL --help says them in the \
                     protocol's words (its IDs, sensors, default speed) with its own options.",
                ));
                out.push('\n');
            }
            Some(heading) => out.push_str(&format!(".SS {heading}\n")),
            None => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    Ok(out)
}

/// The manual page of busnoop(1) in roff: the synopsis, the options every protocol shares,
/// every subcommand (each has its page from [`man_to_dir`]), SOURCE, the exit codes in their
/// own section, and the pages to see.
pub fn man_page() -> Result<Vec<u8>, Failure> {
    render_page().map_err(|e| Failure::Internal(format!("cannot render the manual page: {e}")))
}

fn render_page() -> std::io::Result<Vec<u8>> {
    let cmd = for_man();
    // The root's after_help (SOURCE and the exit codes on one line for -h) is said below.
    let man = clap_mangen::Man::new(cmd.clone().after_help(""));
    let mut page = Vec::new();
    man.render_title(&mut page)?;
    let mut text = String::new();
    text.push_str(&section(|w| man.render_name_section(w))?);
    text.push_str(&section(|w| man.render_synopsis_section(w))?);
    text.push_str(&section(|w| man.render_description_section(w))?);
    text.push_str(&section(|w| man.render_options_section(w))?);
    text.push_str(&shared_options()?);
    text.push_str(&section(|w| man.render_subcommands_section(w))?);
    text.push_str(".SH SOURCE\n");
    text.push_str(&roff_text(
        "A serial device (/dev/ttyUSB0, COM3: a live capture), a capture file (raw bytes, an \
         EdgeTX debug log, a pcap or pcapng recording, a network capture; recognised by \
         content), or - for standard input (with a PROTOCOL). Several sources give one table \
         with a Port column. Without a PROTOCOL, busnoop detects it, says on standard error what \
         it chose and why, and decodes.",
    ));
    text.push('\n');
    text.push_str(".SH \"EXIT STATUS\"\n");
    for (code, meaning) in EXIT_CODES {
        text.push_str(&format!(".TP\n{code}\n{}\n", roff_text(meaning)));
    }
    text.push_str(".SH \"SEE ALSO\"\n");
    let pages: Vec<String> = cmd
        .get_subcommands()
        .filter(|c| !c.is_hide_set())
        .map(|c| format!("busnoop\\-{}(1)", c.get_name()))
        .collect();
    text.push_str(&pages.join(", "));
    text.push_str(
        "\n.PP\nREADME.md and docs/ in the source: per protocol (docs/sport.md, docs/sbus.md, \
         \u{2026}) and per feature (docs/usage.md, docs/detect.md, docs/live.md).\n",
    );
    text.push_str(&section(|w| man.render_version_section(w))?);
    page.extend_from_slice(text.as_bytes());
    Ok(page)
}

/// `busnoop man`: busnoop(1) on standard output, or with `dir` one page per command
/// (busnoop.1, busnoop-sport.1, …) written into that directory.
pub fn man(dir: Option<&Path>) -> Result<(), Failure> {
    match dir {
        None => crate::exit::write_stdout(&man_page()?),
        Some(d) => man_to_dir(d),
    }
}

/// Writes busnoop.1 and one page per subcommand into `dir` (which must exist).
pub fn man_to_dir(dir: &Path) -> Result<(), Failure> {
    let meta = std::fs::metadata(dir).map_err(|e| Failure::from_input_io(dir, &e))?;
    if !meta.is_dir() {
        return Err(Failure::Usage(format!(
            "--dir {}: not a directory; give the directory the pages go to (for example \
             ~/.local/share/man/man1)",
            dir.display()
        )));
    }
    let failed =
        |e: std::io::Error| Failure::Output(format!("cannot write to {}: {e}", dir.display()));
    clap_mangen::generate_to(for_man(), dir).map_err(failed)?;
    // busnoop.1 is the page of `busnoop man` (shared options, exit codes, see also).
    std::fs::write(dir.join("busnoop.1"), man_page()?).map_err(failed)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_manual_page_names_every_subcommand_and_the_exit_codes() {
        let page = String::from_utf8(man_page().unwrap()).unwrap();
        assert!(page.starts_with(".ie"), "{}", &page[..80]);
        let protocols = crate::protocols::PROTOCOLS.iter().map(|p| p.command);
        for sub in protocols.chain(["detect", "ports", "completions", "man"]) {
            assert!(page.contains(sub), "{sub}");
        }
        assert!(page.contains("EXIT STATUS"));
    }

    /// The EXIT STATUS section lists every code of `exit::code`, once.
    #[test]
    fn every_exit_code_is_in_the_manual() {
        let src = include_str!("../exit.rs");
        let module = &src[src.find("pub mod code").unwrap()..];
        let module = &module[..module.find("\n}\n").unwrap()];
        let consts = module.matches("pub const ").count();
        assert_eq!(consts, EXIT_CODES.len());
        let mut codes: Vec<u8> = EXIT_CODES.iter().map(|(c, _)| *c).collect();
        codes.dedup();
        assert_eq!(codes.len(), EXIT_CODES.len());
    }
}
