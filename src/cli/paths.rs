//! Never write to a path that is also an input: device and inode of the source, `-o` and
//! `--record`, compared before anything is opened for writing.

use std::path::{Path, PathBuf};

use super::is_dash;
use crate::exit::Failure;
use crate::source::Input;

/// What a file argument is, for telling whether two of them are one file.
#[derive(Debug, PartialEq, Eq)]
enum FileId {
    /// An existing regular file: device and inode (so symlinks and hard links compare equal).
    Inode(u64, u64),
    /// A file that does not exist yet: its absolute name, with the directory's links resolved.
    Name(PathBuf),
}

impl FileId {
    /// Regular files only: special files (/dev/null, a terminal, a pipe) may well be shared.
    fn of_metadata(m: &std::fs::Metadata) -> Option<FileId> {
        use std::os::unix::fs::MetadataExt;
        m.is_file().then(|| FileId::Inode(m.dev(), m.ino()))
    }

    fn of_path(p: &Path) -> Option<FileId> {
        match std::fs::metadata(p) {
            Ok(m) => FileId::of_metadata(&m),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                // A dangling symlink would be created at its target: no name to compare.
                if std::fs::symlink_metadata(p).is_ok() {
                    return None;
                }
                let name = p.file_name()?;
                let dir = match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                Some(FileId::Name(std::fs::canonicalize(dir).ok()?.join(name)))
            }
            Err(_) => None,
        }
    }

    /// The file behind an open descriptor (standard input or output).
    fn of_fd(fd: std::os::fd::BorrowedFd<'_>) -> Option<FileId> {
        let file = std::fs::File::from(fd.try_clone_to_owned().ok()?);
        FileId::of_metadata(&file.metadata().ok()?)
    }
}

/// Refuses, before anything is opened for writing, an output (`-o`, standard output) or a
/// recording that is the input file itself (by device and inode: symlinks, hard links and
/// `- < file` included), or an output and a recording that are one file.
pub(super) fn check_distinct(
    input: &Input,
    output: Option<&Path>,
    record: Option<&Path>,
) -> Result<(), Failure> {
    use std::os::fd::AsFd;
    let stdout_id = || FileId::of_fd(std::io::stdout().as_fd());
    let (source, source_name) = match input {
        Input::Stdin => (
            FileId::of_fd(std::io::stdin().as_fd()),
            "standard input (the input)".to_string(),
        ),
        Input::File(p) => (FileId::of_path(p), format!("the input {}", p.display())),
        Input::Device(_) => (None, String::new()),
    };
    let (out, out_name) = match output {
        Some(p) => (FileId::of_path(p), format!("-o {}", p.display())),
        None => (stdout_id(), "standard output".to_string()),
    };
    let (rec, rec_name) = match record {
        Some(p) if is_dash(p) => (stdout_id(), "--record - (standard output)".to_string()),
        Some(p) => (FileId::of_path(p), format!("--record {}", p.display())),
        None => (None, String::new()),
    };
    let same = |a: &Option<FileId>, b: &Option<FileId>| a.is_some() && a == b;
    for (id, name) in [(&out, &out_name), (&rec, &rec_name)] {
        if same(&source, id) {
            return Err(Failure::Usage(format!(
                "{name} is the same file as {source_name}: writing it would destroy the \
                 capture; write somewhere else"
            )));
        }
    }
    if same(&out, &rec) {
        return Err(Failure::Usage(format!(
            "{out_name} and {rec_name} are the same file; give them different names"
        )));
    }
    Ok(())
}
