//! Pseudo-terminal pairs and a busnoop child reading one, for the live tests.
//!
//! pty pairs are not thread-safe to create (serialport's own tests say so): every test that uses
//! one holds [`lock`].

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use serialport::{SerialPort, TTYPort};

static PTY: Mutex<()> = Mutex::new(());

/// Serialises the tests of one test binary that use pty pairs.
pub fn lock() -> std::sync::MutexGuard<'static, ()> {
    PTY.lock().unwrap_or_else(|e| e.into_inner())
}

/// A pty pair: `master` is the bus side the test writes to, `path` the device busnoop opens.
pub struct Bus {
    pub master: TTYPort,
    /// Held open so the device stays usable until the test closes the master.
    pub slave: TTYPort,
    pub path: PathBuf,
}

pub fn bus() -> Bus {
    use std::os::fd::AsRawFd;
    let (master, slave) = TTYPort::pair().expect("pty pair");
    // The pair's descriptors are inheritable: keep them out of busnoop, or closing the bus side
    // here would not close it.
    for fd in [master.as_raw_fd(), slave.as_raw_fd()] {
        unsafe { libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC) };
    }
    let path = PathBuf::from(slave.name().expect("slave name"));
    Bus {
        master,
        slave,
        path,
    }
}

/// The busnoop binary under test.
pub fn bin() -> PathBuf {
    assert_cmd::cargo::cargo_bin("busnoop")
}

/// Starts `busnoop ARGS DEVICE` and collects its stdout lines with the time each one arrived.
pub fn spawn(args: &[&str], device: &Path) -> (Child, Receiver<(Instant, String)>) {
    let mut child = Command::new(bin())
        .args(args)
        .arg(device)
        .env_remove("NO_COLOR")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send((Instant::now(), line)).is_err() {
                break;
            }
        }
    });
    (child, rx)
}

/// The next stdout line and when it arrived; fails after [`super::PATIENCE`] of silence.
pub fn next_line(rx: &Receiver<(Instant, String)>) -> (Instant, String) {
    rx.recv_timeout(super::PATIENCE)
        .expect("busnoop printed nothing for a long time")
}

/// Waits up to [`super::PATIENCE`] for the child to exit.
pub fn wait_exit(child: &mut Child) -> std::process::ExitStatus {
    let deadline = Instant::now() + super::PATIENCE;
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        assert!(Instant::now() < deadline, "busnoop did not exit");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Everything the child wrote on stderr (call after it exited).
pub fn stderr_of(child: &mut Child) -> String {
    let mut s = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut s).unwrap();
    s
}
