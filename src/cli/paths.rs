//! Never write to a path that is also an input: device and inode of the source, `-o` and
//! `--record` (the device number of a serial port), compared before anything is opened for
//! writing.

use std::path::{Path, PathBuf};

use super::is_dash;
use crate::exit::Failure;
use crate::source::Input;

/// What a file argument is, for telling whether two of them are one file.
#[derive(Debug, PartialEq, Eq)]
enum FileId {
    /// An existing regular file: device and inode (so symlinks and hard links compare equal).
    Inode(u64, u64),
    /// A pipe or FIFO, the same way (`/dev/stdin` names the pipe standard input reads).
    Pipe(u64, u64),
    /// A file that does not exist yet: its absolute name, with the directory's links resolved.
    Name(PathBuf),
    /// A character device, by its device number: only for a serial port given as the input
    /// and the outputs compared with it.
    Device(u64),
}

impl FileId {
    /// Regular files and pipes; character devices only with `devices`: a terminal or
    /// `/dev/null` may well be shared by outputs, or by an input on standard input and the
    /// table. `/dev/null` is never anything (reading it gives nothing, writing it keeps
    /// nothing).
    fn of_metadata(m: &std::fs::Metadata, devices: bool) -> Option<FileId> {
        use std::os::unix::fs::{FileTypeExt, MetadataExt};
        let t = m.file_type();
        if t.is_file() {
            Some(FileId::Inode(m.dev(), m.ino()))
        } else if t.is_fifo() {
            Some(FileId::Pipe(m.dev(), m.ino()))
        } else if devices && t.is_char_device() && !is_dev_null(m) {
            Some(FileId::Device(m.rdev()))
        } else {
            None
        }
    }

    fn of_path(p: &Path, devices: bool) -> Option<FileId> {
        match std::fs::metadata(p) {
            Ok(m) => FileId::of_metadata(&m, devices),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                // A dangling symlink is created at its target (relative to the link's
                // directory): `-o out.csv` with `out.csv -> r.pcap` writes r.pcap. A loop of
                // links is ELOOP, not NotFound, so this ends.
                if let Ok(target) = std::fs::read_link(p) {
                    let base = p.parent().unwrap_or(Path::new(""));
                    return FileId::of_path(&base.join(target), devices);
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
    fn of_fd(fd: std::os::fd::BorrowedFd<'_>, devices: bool) -> Option<FileId> {
        let file = std::fs::File::from(fd.try_clone_to_owned().ok()?);
        FileId::of_metadata(&file.metadata().ok()?, devices)
    }

    /// What writing into the input through this file would do.
    fn consequence(&self) -> &'static str {
        match self {
            FileId::Pipe(..) => "feed busnoop its own output",
            FileId::Device(_) => "transmit on the bus busnoop listens to (busnoop never sends)",
            FileId::Inode(..) | FileId::Name(_) => "destroy the capture",
        }
    }
}

/// Points standard error away from the input it turned out to be: to the controlling terminal
/// when there is one, else to /dev/null.
fn away_from_input() {
    use std::os::fd::AsRawFd;
    let to = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/tty")
        .or_else(|_| std::fs::OpenOptions::new().write(true).open("/dev/null"));
    if let Ok(f) = to {
        // SAFETY: dup2 onto descriptor 2, open for the whole process.
        unsafe { libc::dup2(f.as_raw_fd(), 2) };
    }
}

/// Whether `m` is the device `/dev/null` is.
fn is_dev_null(m: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata("/dev/null").is_ok_and(|null| null.rdev() == m.rdev())
}

/// Refuses, before anything is opened for writing, an output (`-o`, standard output), a
/// recording or an export that is the input itself: the input file (by device and inode:
/// symlinks, hard links and `- < file` included), the pipe or FIFO it comes through (`… |
/// busnoop sport - -o /dev/stdin` would feed busnoop its own rows and never end), or the serial
/// port it listens to (writing there would send on the bus). Also two of the outputs that are
/// one file, however they are named (`--record x.pcapng --export ./x.pcapng` would interleave
/// the two), and an output that is the project file the run reads (`project`: `-o
/// busnoop.toml`).
pub(super) fn check_distinct(
    input: &Input,
    output: Option<&Path>,
    record: Option<&Path>,
    export: Option<&Path>,
    project: Option<&Path>,
) -> Result<(), Failure> {
    use std::os::fd::AsFd;
    // A serial port is compared with the outputs by its device number: writing there would
    // send on the bus. Other character devices (a terminal, /dev/null) may be shared.
    let devices = matches!(input, Input::Device(_));
    let stdout_id = || FileId::of_fd(std::io::stdout().as_fd(), devices);
    let (source, source_name) = match input {
        Input::Stdin => (
            FileId::of_fd(std::io::stdin().as_fd(), false),
            "standard input (the input)".to_string(),
        ),
        Input::File(p) => (
            FileId::of_path(p, false),
            format!("the input {}", p.display()),
        ),
        Input::Device(p) => (
            FileId::of_path(p, true),
            format!("the input {}", p.display()),
        ),
    };
    let mut outputs = vec![match output {
        Some(p) => (FileId::of_path(p, devices), format!("-o {}", p.display())),
        None => (stdout_id(), "standard output".to_string()),
    }];
    match record {
        Some(p) if is_dash(p) => {
            outputs.push((stdout_id(), "--record - (standard output)".to_string()));
        }
        Some(p) => outputs.push((
            FileId::of_path(p, devices),
            format!("--record {}", p.display()),
        )),
        None => {}
    }
    if let Some(p) = export {
        outputs.push((
            FileId::of_path(p, devices),
            format!("--export {}", p.display()),
        ));
    }
    let same = |a: &Option<FileId>, b: &Option<FileId>| a.is_some() && a == b;
    for (id, name) in &outputs {
        if let Some(s) = source.as_ref().filter(|_| same(&source, id)) {
            return Err(Failure::Usage(format!(
                "{name} is the same file as {source_name}: writing it would {}; write \
                 somewhere else",
                s.consequence()
            )));
        }
    }
    // Standard error too: `2>>capture.bin` put busnoop's own messages into the capture it
    // reads. The refusal cannot go there: it goes to the terminal, if there is one.
    if same(&source, &FileId::of_fd(std::io::stderr().as_fd(), devices)) {
        away_from_input();
        return Err(Failure::Usage(format!(
            "standard error is the same file as {source_name}: busnoop's messages would go into \
             it; send them somewhere else (2>FILE)"
        )));
    }
    if let Some(p) = project {
        let id = FileId::of_path(p, false);
        if let Some((_, name)) = outputs.iter().find(|(o, _)| same(&id, o)) {
            return Err(Failure::Usage(format!(
                "{name} is the project file {}: writing it would destroy the project file; \
                 write somewhere else",
                p.display()
            )));
        }
    }
    // Two outputs on one serial port are refused above already; on one terminal they are not
    // a clash.
    for (i, (a, a_name)) in outputs.iter().enumerate() {
        for (b, b_name) in &outputs[i + 1..] {
            if same(a, b) && !matches!(a, Some(FileId::Device(_))) {
                return Err(Failure::Usage(format!(
                    "{a_name} and {b_name} are the same file; give them different names"
                )));
            }
        }
    }
    Ok(())
}
