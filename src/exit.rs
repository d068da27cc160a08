//! Failures the user can meet, each with a one-line message and its own exit code.
//!
//! The table of exit codes is documented in docs/usage.md ("Exit codes") and busnoop(1); keep the two in step.

use std::fmt;
use std::path::{Path, PathBuf};

/// Exit codes (docs/usage.md, "Exit codes").
pub mod code {
    /// Everything was read; rows may still include bad frames (see the summary line).
    pub const OK: u8 = 0;
    /// An unexpected internal error.
    pub const INTERNAL: u8 = 1;
    /// Wrong command-line usage (clap's convention).
    pub const USAGE: u8 = 2;
    /// The input file or device does not exist, or is a directory.
    pub const NOT_FOUND: u8 = 3;
    /// Permission denied on the input file or serial device.
    pub const PERMISSION: u8 = 4;
    /// The serial port is in use by another program.
    pub const BUSY: u8 = 5;
    /// The serial device could not be opened or configured for another reason.
    pub const DEVICE: u8 = 6;
    /// The adapter disappeared during a live capture.
    pub const DISCONNECTED: u8 = 7;
    /// Writing the output (or a recording) failed, for example a full disk.
    pub const OUTPUT: u8 = 8;
    /// Reading the input failed after it was opened, or its content cannot be used.
    pub const INPUT: u8 = 9;
    /// Nothing decoded: the input was empty, or holds no frame of the protocol (files and
    /// streams); `detect`: no bytes arrived on a serial line.
    pub const NOTHING_DECODED: u8 = 10;
    /// `detect`: bytes, but no known protocol in them.
    pub const NO_PROTOCOL: u8 = 11;
    /// The project file (`busnoop.toml`, `--config`) cannot be used: bad TOML, an unknown key,
    /// a value out of range.
    pub const CONFIG: u8 = 12;
    /// A file or stream decoded, but mostly not as valid frames of the protocol: another
    /// protocol fits much better, or fewer than half of the bytes examined are in valid frames
    /// (`detect::advise::POOR_SHARE`); the rows were written. `--lenient` accepts such a run.
    pub const POOR: u8 = 13;
    /// Hung up (SIGHUP: the SSH session or the terminal gone): 128 + 1.
    pub const SIGHUP: u8 = 129;
    /// Interrupted by Ctrl-C (SIGINT): 128 + 2.
    pub const SIGINT: u8 = 130;
    /// Standard output was closed by the reader (`busnoop … | head`): 128 + 13 (SIGPIPE).
    pub const BROKEN_PIPE: u8 = 141;
    /// Terminated by SIGTERM: 128 + 15.
    pub const SIGTERM: u8 = 143;
}

/// A failure that ends the run.
#[derive(Debug)]
pub enum Failure {
    /// A file or device that does not exist.
    NotFound { path: PathBuf, hint: Option<String> },
    /// A directory given where a file was expected.
    IsDirectory(PathBuf),
    /// Permission denied, with a hint.
    Permission { path: PathBuf, hint: String },
    /// Serial port held by another program.
    Busy(PathBuf),
    /// Serial device could not be opened or configured.
    Device { path: PathBuf, message: String },
    /// Adapter gone during capture.
    Disconnected { path: PathBuf, frames: u64 },
    /// The device went away where waiting for it is no option (`detect`): the message.
    Unplugged(String),
    /// Output could not be written.
    Output(String),
    /// Input could not be read or used.
    Input(String),
    /// Stopped by a signal (SIGINT, SIGTERM or SIGHUP); not an error message.
    Signal(Interrupt),
    /// Standard output closed by the reader: quiet.
    BrokenPipe,
    /// Nothing decoded (an empty input, or no frame of the protocol), with the message.
    NothingDecoded(String),
    /// `detect` recognised no protocol.
    NoProtocol(String),
    /// Decoded, but mostly not valid frames of the protocol (the rows were written).
    Poor(String),
    /// A combination of options that cannot work (clap reports the other usage errors).
    Usage(String),
    /// Anything else.
    Internal(String),
    /// The project file is unusable (the message names the file and the line).
    Config(String),
}

/// How a run was stopped by a signal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Interrupt {
    /// SIGINT, SIGTERM or SIGHUP.
    pub signal: i32,
    /// How much of a file or stream was decoded and how much was left, e.g.
    /// "4194304 of 1073741824 bytes of the input decoded, 1069547520 not decoded"; `None` for
    /// live devices and when the signal came before any input.
    pub input: Option<String>,
}

impl Interrupt {
    pub fn new(signal: i32) -> Self {
        Interrupt {
            signal,
            input: None,
        }
    }

    /// "; <input>" or nothing, to end the "interrupted after N rows" line.
    pub fn input_note(&self) -> String {
        self.input
            .as_ref()
            .map_or(String::new(), |i| format!("; {i}"))
    }
}

impl Failure {
    pub fn exit_code(&self) -> u8 {
        match self {
            Failure::NotFound { .. } | Failure::IsDirectory(_) => code::NOT_FOUND,
            Failure::Permission { .. } => code::PERMISSION,
            Failure::Busy(_) => code::BUSY,
            Failure::Device { .. } => code::DEVICE,
            Failure::Disconnected { .. } | Failure::Unplugged(_) => code::DISCONNECTED,
            Failure::Output(_) => code::OUTPUT,
            Failure::Input(_) => code::INPUT,
            Failure::NothingDecoded(_) => code::NOTHING_DECODED,
            Failure::NoProtocol(_) => code::NO_PROTOCOL,
            Failure::Poor(_) => code::POOR,
            Failure::Signal(i) if i.signal == libc::SIGTERM => code::SIGTERM,
            Failure::Signal(i) if i.signal == libc::SIGHUP => code::SIGHUP,
            Failure::Signal(_) => code::SIGINT,
            Failure::BrokenPipe => code::BROKEN_PIPE,
            Failure::Internal(_) => code::INTERNAL,
            Failure::Usage(_) => code::USAGE,
            Failure::Config(_) => code::CONFIG,
        }
    }

    /// Whether a message should be printed at all.
    pub fn is_quiet(&self) -> bool {
        matches!(self, Failure::BrokenPipe | Failure::Signal(_))
    }

    /// Maps an error from creating an output (`what`: "cannot create recording FILE"): the
    /// signal that ended the wait for a FIFO's reader (`files::create_file`), or an
    /// output error.
    pub fn from_create(what: &str, e: &std::io::Error) -> Failure {
        match crate::signal::Stop::received() {
            Some(sig) if e.kind() == std::io::ErrorKind::Interrupted => {
                Failure::Signal(Interrupt::new(sig))
            }
            _ => Failure::Output(format!("{what}: {e}")),
        }
    }

    /// Maps an error from opening or reading an input file.
    pub fn from_input_io(path: &Path, e: &std::io::Error) -> Failure {
        use std::io::ErrorKind::*;
        match e.kind() {
            NotFound => Failure::NotFound {
                path: path.to_owned(),
                hint: None,
            },
            PermissionDenied => Failure::Permission {
                path: path.to_owned(),
                hint: "check the file's permissions".into(),
            },
            IsADirectory => Failure::IsDirectory(path.to_owned()),
            _ => Failure::Input(format!("cannot read {}: {}", path.display(), e)),
        }
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::NotFound { path, hint } => {
                write!(f, "{}: no such file or device", path.display())?;
                if let Some(h) = hint {
                    write!(f, " ({h})")?;
                }
                Ok(())
            }
            Failure::IsDirectory(p) => write!(
                f,
                "{} is a directory; give a capture file, a serial device or - for standard input",
                p.display()
            ),
            Failure::Permission { path, hint } => {
                write!(f, "{}: permission denied ({hint})", path.display())
            }
            Failure::Busy(p) => write!(
                f,
                "{} is in use by another program (close it, or find it with `fuser {}`)",
                p.display(),
                p.display()
            ),
            Failure::Device { path, message } => write!(f, "{}: {message}", path.display()),
            Failure::Unplugged(m) => write!(f, "{m}"),
            Failure::Disconnected { path, frames } => write!(
                f,
                "adapter disconnected after {} ({}); use --reconnect to wait for it",
                count(*frames, "frame", "frames"),
                path.display()
            ),
            Failure::Output(m)
            | Failure::Input(m)
            | Failure::Internal(m)
            | Failure::Usage(m)
            | Failure::NothingDecoded(m)
            | Failure::NoProtocol(m)
            | Failure::Poor(m)
            | Failure::Config(m) => f.write_str(m),
            Failure::Signal(i) => write!(f, "stopped by signal {}", i.signal),
            Failure::BrokenPipe => f.write_str("output closed"),
        }
    }
}

impl From<crate::row::OutputError> for Failure {
    fn from(e: crate::row::OutputError) -> Self {
        // A closed pipe is a closed pipe whether it is standard output or `-o /dev/stdout`
        // (or a FIFO): the reader went away, quietly.
        if e.error.kind() == std::io::ErrorKind::BrokenPipe {
            Failure::BrokenPipe
        } else {
            Failure::Output(e.to_string())
        }
    }
}

/// Writes `bytes` to standard output for the commands that print (`detect`, `ports`, `man`,
/// `completions`, `extcap`): a reader that went away (`… | head`) ends busnoop quietly
/// ([`Failure::BrokenPipe`], 141) as it does for the tables; another error is exit 8.
pub fn write_stdout(bytes: &[u8]) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(bytes).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(Failure::BrokenPipe),
        Err(e) => Err(Failure::Output(format!(
            "cannot write to standard output: {e}"
        ))),
    }
}

/// `1 frame`, `2 frames`.
pub fn count(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}
