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

/// The manual page of busnoop(1) in roff: every subcommand with its options (the pages of
/// the subcommands are written by [`man_to_dir`]).
pub fn man_page() -> Result<Vec<u8>, Failure> {
    let cmd = super::command();
    let mut buf = Vec::new();
    clap_mangen::Man::new(cmd)
        .render(&mut buf)
        .map_err(|e| Failure::Internal(format!("cannot render the manual page: {e}")))?;
    Ok(buf)
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
    clap_mangen::generate_to(super::command(), dir)
        .map_err(|e| Failure::Output(format!("cannot write to {}: {e}", dir.display())))?;
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
        assert!(page.contains("Exit codes"));
    }
}
