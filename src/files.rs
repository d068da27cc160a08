//! Files busnoop writes, kept apart from the files it reads: the inputs being read are
//! remembered by device and inode ([`protect`]) and never opened for writing ([`create_file`]),
//! whatever name leads there; a FIFO's open waits for its reader without blocking signals; an
//! output's folder and a closed standard output are found before anything is written. Below
//! `source` and `sink`, which both use it.

use std::fs::File;
use std::io;
use std::os::unix::fs::FileTypeExt as _;
use std::path::Path;

/// How often the wait for a FIFO's reader looks for a signal.
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// Creates (truncates) `path` for writing: the table, a recording, an export. A FIFO is opened
/// non-blocking, retried until a reader comes: a plain open waits for the reader inside the
/// kernel, where no signal can end it (`-o FIFO` with no reader ignored Ctrl-C). SIGINT/SIGTERM
/// end the wait with an `Interrupted` error ([`crate::exit::Failure::from_create`]); once open,
/// the FIFO is written blocking like any file.
pub(crate) fn create_file(path: &Path) -> io::Result<File> {
    use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
    if !std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo()) {
        // Opened without truncating, compared with the inputs, then emptied: a name that
        // became the input (a symlink swapped in after the same-file check) is refused
        // untouched.
        let f = std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            // Emptied below, once it is known not to be an input.
            .truncate(false)
            .open(path)?;
        let m = f.metadata()?;
        if is_input(&m) {
            return Err(io::Error::other(
                "it is the input file (it changed since it was checked); nothing written",
            ));
        }
        if m.is_file() {
            f.set_len(0)?;
        }
        return Ok(f);
    }
    loop {
        match std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(path)
        {
            Ok(f) => {
                if is_input(&f.metadata()?) {
                    return Err(io::Error::other("it is the input; nothing written"));
                }
                set_blocking(&f)?;
                return Ok(f);
            }
            // No reader yet.
            Err(e) if e.raw_os_error() == Some(libc::ENXIO) => {
                if crate::signal::Stop::received().is_some() {
                    return Err(io::Error::new(
                        io::ErrorKind::Interrupted,
                        "stopped by a signal",
                    ));
                }
                std::thread::sleep(SIGNAL_POLL);
            }
            Err(e) => return Err(e),
        }
    }
}

/// What [`note_stdout_at_start`] saw of descriptor 1 before the Rust runtime started: 0 not
/// looked (busnoop's functions called from a test, not from the binary), 1 open, 2 closed.
static STDOUT_AT_START: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);

/// Looks whether descriptor 1 is open. Called by the binary's start-up hook (`src/main.rs`)
/// before the Rust runtime's start-up, which puts /dev/null on a closed standard output: only
/// then does a closed one still show as closed.
pub(crate) fn note_stdout_at_start() {
    // SAFETY: F_GETFD on descriptor 1 only reads its flags; it fails with EBADF when closed.
    let closed = unsafe { libc::fcntl(1, libc::F_GETFD) } < 0;
    STDOUT_AT_START.store(1 + u8::from(closed), std::sync::atomic::Ordering::Relaxed);
}

/// Whether standard output was closed when busnoop started (`>&-`). The binary looks before the
/// Rust runtime puts /dev/null there ([`note_stdout_at_start`]); an open /dev/null, whatever
/// its mode (Python's `subprocess.DEVNULL` opens it for reading and writing), is an open
/// standard output. Where nothing looked (no start-up hook on this platform), the runtime's
/// /dev/null is told by its mode: opened for reading and writing, where a shell's `>/dev/null`
/// opens it for writing only.
pub(crate) fn stdout_was_closed() -> bool {
    match STDOUT_AT_START.load(std::sync::atomic::Ordering::Relaxed) {
        1 => return false,
        2 => return true,
        _ => {}
    }
    use std::os::unix::fs::MetadataExt;
    // SAFETY: F_GETFL on descriptor 1 only reads its flags.
    let flags = unsafe { libc::fcntl(1, libc::F_GETFL) };
    if flags < 0 || flags & libc::O_ACCMODE != libc::O_RDWR {
        return false;
    }
    let null = std::fs::metadata("/dev/null").map(|m| m.rdev());
    let out = std::io::stdout();
    let fd = std::os::fd::AsFd::as_fd(&out).try_clone_to_owned();
    match (null, fd.map(File::from).and_then(|f| f.metadata())) {
        (Ok(null), Ok(m)) => m.file_type().is_char_device() && m.rdev() == null,
        _ => false,
    }
}

/// The inputs being read, by device and inode ([`protect`]).
static INPUTS: std::sync::Mutex<Vec<(u64, u64)>> = std::sync::Mutex::new(Vec::new());

/// Marks standard input (a regular file or a FIFO behind it) as never to be written: it stays
/// open as long as busnoop runs, so the mark does too.
pub(crate) fn protect_stdin() {
    mark(std::io::stdin());
}

/// Marks an open input file (a regular file or a FIFO) as never to be written: [`create_file`]
/// refuses to open it, whatever name leads there by then. The mark lasts as long as the
/// returned file is open: a closed file's inode may be given to a new file, which must not be
/// taken for the input (a test's temporary output was refused that way, 1 run in 5 under load).
pub(crate) fn protect(file: File) -> Protected {
    let key = mark(&file);
    Protected { file, key }
}

fn mark(file: impl std::os::fd::AsFd) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    let m = file
        .as_fd()
        .try_clone_to_owned()
        .map(File::from)
        .ok()?
        .metadata()
        .ok()?;
    if !(m.is_file() || m.file_type().is_fifo()) {
        return None;
    }
    let key = (m.dev(), m.ino());
    INPUTS.lock().unwrap_or_else(|e| e.into_inner()).push(key);
    Some(key)
}

/// An input file marked by [`protect`]; closing it lifts the mark.
pub(crate) struct Protected {
    file: File,
    key: Option<(u64, u64)>,
}

impl io::Read for Protected {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.file.read(buf)
    }
}

impl std::os::fd::AsFd for Protected {
    fn as_fd(&self) -> std::os::fd::BorrowedFd<'_> {
        self.file.as_fd()
    }
}

impl Drop for Protected {
    fn drop(&mut self) {
        let Some(key) = self.key else { return };
        let mut inputs = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
        // One mark: the same file may be read twice at once.
        if let Some(i) = inputs.iter().position(|k| *k == key) {
            inputs.swap_remove(i);
        }
    }
}

fn is_input(m: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    INPUTS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .contains(&(m.dev(), m.ino()))
}

/// Refuses an output whose folder does not exist (or is no folder) before any output is
/// created, with the message creating it would give: found only then, the outputs created
/// before it (the recording, the export, the table) were left behind, an existing one emptied.
pub(crate) fn check_folder(path: &Path) -> Result<(), crate::exit::Failure> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let problem = match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => return Ok(()),
        Ok(_) => format!("{} is not a directory", dir.display()),
        Err(e) => e.to_string(),
    };
    Err(crate::exit::Failure::Output(format!(
        "cannot create {}: {problem}",
        path.display()
    )))
}

/// Clears `O_NONBLOCK` on `fd` (opened non-blocking so that the open itself cannot hang).
pub(crate) fn set_blocking(fd: impl std::os::fd::AsFd) -> io::Result<()> {
    use nix::fcntl::{FcntlArg, OFlag, fcntl};
    let flags = OFlag::from_bits_truncate(fcntl(&fd, FcntlArg::F_GETFL)?);
    fcntl(&fd, FcntlArg::F_SETFL(flags - OFlag::O_NONBLOCK))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// L5 (issue 32): a symlink swapped between the same-file check and the open of `-o`
    /// truncated the input (1 in 150 tries). The output is opened first, without truncating,
    /// and compared by device and inode with the inputs read; then truncated.
    #[test]
    fn an_output_that_turned_into_the_input_is_not_truncated() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("capture.bin");
        std::fs::write(&input, b"precious capture").unwrap();
        let _input = protect(File::open(&input).unwrap());
        // The race's outcome: `-o out.tsv` is now a link to the input.
        let out = dir.path().join("out.tsv");
        std::os::unix::fs::symlink(&input, &out).unwrap();
        let e = create_file(&out).unwrap_err();
        assert!(e.to_string().contains("is the input"), "{e}");
        assert_eq!(std::fs::read(&input).unwrap(), b"precious capture");
        // A hard link too.
        let hard = dir.path().join("hard.tsv");
        std::fs::hard_link(&input, &hard).unwrap();
        assert!(create_file(&hard).is_err());
        assert_eq!(std::fs::read(&input).unwrap(), b"precious capture");
        // Another file is created, or emptied, as before.
        let other = dir.path().join("other.tsv");
        std::fs::write(&other, b"old table").unwrap();
        create_file(&other).unwrap();
        assert_eq!(std::fs::read(&other).unwrap(), b"");
        create_file(&dir.path().join("new.tsv")).unwrap();
    }

    /// A closed input's mark stayed for the life of the process, and its inode could be given
    /// to a new file: `cargo test` refused a test's fresh recording as "the input file" (run 21
    /// of the CI loop). The mark goes when the input is closed.
    #[test]
    fn a_closed_input_is_no_longer_protected() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("capture.bin");
        std::fs::write(&input, b"capture").unwrap();
        let opened = protect(File::open(&input).unwrap());
        let again = protect(File::open(&input).unwrap());
        let meta = std::fs::metadata(&input).unwrap();
        assert!(is_input(&meta));
        drop(opened);
        assert!(is_input(&meta), "still open once");
        drop(again);
        assert!(!is_input(&meta));
    }
}
