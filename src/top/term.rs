//! The terminal of the live view: raw mode and the alternate screen, restored on every way out
//! (normal end, error, panic, signal), and busnoop's own stderr kept off the screen.

use std::io::{self, Stdout, Write};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Arc, Mutex, Once, OnceLock};

use crate::sink::fallback_size;
use ratatui::backend::{Backend, CrosstermBackend};
use ratatui::crossterm::cursor::{Hide, Show};
use ratatui::crossterm::execute;
use ratatui::crossterm::terminal::{
    EnterAlternateScreen, LeaveAlternateScreen, disable_raw_mode, enable_raw_mode,
};
use ratatui::layout::Rect;
use ratatui::{Terminal, TerminalOptions, Viewport};

/// The terminal is in raw mode on the alternate screen.
static ACTIVE: AtomicBool = AtomicBool::new(false);
/// The real stderr while it is captured (-1: not captured).
static SAVED_STDERR: AtomicI32 = AtomicI32::new(-1);

/// The terminal's descriptor (-1: none) and its settings before raw mode, for
/// [`restore_at_exit`], which runs inside a signal handler and can take no lock.
static TTY_FD: AtomicI32 = AtomicI32::new(-1);
static TTY_SETTINGS: OnceLock<libc::termios> = OnceLock::new();

/// Lines of stderr kept while the view runs; more are counted.
const KEPT_LINES: usize = 1000;

/// The view draws into at most this many columns and rows of the terminal: its buffers are
/// allocated by the area (a 5000×5000 terminal took 2 GB and froze, 65535×65535 aborted with the
/// terminal left raw). Far more than the view's lines fill.
const MAX_COLS: u16 = 512;
const MAX_ROWS: u16 = 256;

/// The view was stopped (SIGTSTP, Ctrl-Z) with the terminal put back, and continued since:
/// raw mode and the alternate screen are to be set up again.
static RESUMED: AtomicBool = AtomicBool::new(false);

/// The descriptor keys are read from: the one raw mode is set on (standard input when it is a
/// terminal, else `/dev/tty`); -1 before the view opened.
pub fn input_fd() -> RawFd {
    TTY_FD.load(Ordering::SeqCst)
}

/// Whether the view was continued after a stop since the last call.
pub fn resumed() -> bool {
    RESUMED.swap(false, Ordering::SeqCst)
}

/// The terminal put back as it was (from a signal handler: only tcsetattr and write), the
/// view left active: for a stop, after which it is set up again.
fn suspend_at_signal() {
    let fd = TTY_FD.load(Ordering::SeqCst);
    if let (true, Some(t)) = (fd >= 0, TTY_SETTINGS.get()) {
        // SAFETY: see `restore_at_exit`.
        unsafe { libc::tcsetattr(fd, libc::TCSANOW, t) };
    }
    const BACK: &[u8] = b"\x1b[?1049l\x1b[?25h";
    // SAFETY: writes a constant buffer to descriptor 1; write is async-signal-safe.
    unsafe { libc::write(1, BACK.as_ptr().cast(), BACK.len()) };
}

/// SIGTSTP (an external `kill -TSTP`, or Ctrl-Z typed in the view) and SIGQUIT put the
/// terminal back first, so that the shell gets a cooked terminal. A stop then stops the process as the
/// default action would, and marks the view to be set up again when it continues; SIGQUIT
/// ends it as SIGQUIT does.
fn install_stop_and_quit() -> io::Result<()> {
    // SAFETY: the actions only load and store atomics and call async-signal-safe functions
    // (tcsetattr, write, dup2, raise, sigaction through emulate_default_handler).
    unsafe {
        signal_hook::low_level::register(libc::SIGTSTP, || {
            let active = ACTIVE.load(Ordering::SeqCst);
            if active {
                suspend_at_signal();
            }
            let _ = signal_hook::low_level::raise(libc::SIGSTOP);
            if active {
                RESUMED.store(true, Ordering::SeqCst);
            }
        })?;
        signal_hook::low_level::register(libc::SIGQUIT, || {
            restore_at_exit();
            let _ = signal_hook::low_level::emulate_default_handler(libc::SIGQUIT);
        })?;
    }
    Ok(())
}

/// The terminal is gone: standard output and error, where they are that terminal, go to
/// /dev/null, so that the messages still to come (the summary line) do not fail. (A hung-up
/// terminal is no terminal to `isatty` any more: the device numbers tell.)
pub fn detach_from_terminal() {
    let device = |fd: RawFd| {
        // SAFETY: a zeroed stat (plain integers) is a valid value to read into.
        let mut st: libc::stat = unsafe { std::mem::zeroed() };
        // SAFETY: fstat on a descriptor number into our own stat; a closed one fails.
        let ok = fd >= 0 && unsafe { libc::fstat(fd, &mut st) } == 0;
        (ok && st.st_mode & libc::S_IFMT == libc::S_IFCHR).then_some(st.st_rdev)
    };
    let Some(tty) = device(TTY_FD.load(Ordering::SeqCst)) else {
        return;
    };
    let Ok(null) = std::fs::OpenOptions::new().write(true).open("/dev/null") else {
        return;
    };
    for fd in [1, 2] {
        if device(fd) == Some(tty) {
            // SAFETY: dup2 onto a standard descriptor, open for the whole process.
            unsafe { libc::dup2(null.as_raw_fd(), fd) };
        }
    }
}

/// The area the view draws into: the terminal's, at most [`MAX_COLS`] × [`MAX_ROWS`].
fn bounded(size: ratatui::layout::Size) -> Rect {
    // A terminal that reports no size (0x0: some serial consoles and containers) is drawn at
    // COLUMNS x LINES, else 80x24 (at 0x0 the screen stayed empty).
    let (w, h) = if size.width == 0 || size.height == 0 {
        let var = |name: &str| std::env::var(name).ok();
        fallback_size(var("COLUMNS").as_deref(), var("LINES").as_deref())
    } else {
        (size.width, size.height)
    };
    Rect::new(0, 0, w.min(MAX_COLS), h.min(MAX_ROWS))
}

/// Puts the terminal back: leaves raw mode and the alternate screen, shows the cursor, and
/// gives stderr back. Safe to call more than once.
pub fn restore() {
    if ACTIVE.swap(false, Ordering::SeqCst) {
        let _ = disable_raw_mode();
        let _ = execute!(io::stdout(), LeaveAlternateScreen, Show);
        let _ = io::stdout().flush();
    }
    let saved = SAVED_STDERR.swap(-1, Ordering::SeqCst);
    if saved >= 0 {
        // SAFETY: `saved` is the descriptor `Capture::start` duplicated from stderr and owns;
        // dup2 onto 2 only replaces the pipe's write end.
        unsafe { libc::dup2(saved, 2) };
    }
}

/// Puts the terminal back from a signal handler, just before the process ends at once (a
/// second Ctrl-C or SIGTERM, [`crate::signal`]): only async-signal-safe calls (`tcsetattr`,
/// `write`, `dup2`), with the settings saved when the view opened. Nothing when the view is
/// not open.
pub fn restore_at_exit() {
    if ACTIVE.swap(false, Ordering::SeqCst) {
        let fd = TTY_FD.load(Ordering::SeqCst);
        if let (true, Some(t)) = (fd >= 0, TTY_SETTINGS.get()) {
            // SAFETY: `fd` is the terminal's descriptor, open for the whole process; `t` is a
            // termios read from it. tcsetattr is async-signal-safe.
            unsafe { libc::tcsetattr(fd, libc::TCSANOW, t) };
        }
        // Leave the alternate screen, show the cursor (what `restore` writes through
        // crossterm).
        const BACK: &[u8] = b"\x1b[?1049l\x1b[?25h";
        // SAFETY: writes a constant buffer to descriptor 1; write is async-signal-safe.
        unsafe { libc::write(1, BACK.as_ptr().cast(), BACK.len()) };
    }
    let saved = SAVED_STDERR.swap(-1, Ordering::SeqCst);
    if saved >= 0 {
        // SAFETY: see `restore`; dup2 is async-signal-safe.
        unsafe { libc::dup2(saved, 2) };
    }
}

/// Saves the terminal's settings before raw mode, for [`restore_at_exit`]: the descriptor
/// crossterm sets raw mode on (standard input when it is a terminal, else `/dev/tty`).
fn save_settings() {
    if TTY_FD.load(Ordering::SeqCst) < 0 {
        let fd = if nix::unistd::isatty(io::stdin()).unwrap_or(false) {
            0
        } else {
            match std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open("/dev/tty")
            {
                // Kept open for the rest of the process (the handler may need it at any time).
                Ok(f) => std::os::fd::IntoRawFd::into_raw_fd(f),
                Err(_) => return,
            }
        };
        TTY_FD.store(fd, Ordering::SeqCst);
    }
    let fd = TTY_FD.load(Ordering::SeqCst);
    // SAFETY: a zeroed termios (integers and arrays of them) is a valid value to read into.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    // SAFETY: `fd` is open (standard input, or /dev/tty kept open); `t` is writable.
    if unsafe { libc::tcgetattr(fd, &mut t) } == 0 {
        let _ = TTY_SETTINGS.set(t);
    }
}

/// What was written to stderr while the view ran.
#[derive(Default, Debug)]
pub struct Captured {
    pub lines: Vec<String>,
    pub dropped: u64,
    /// The lines were also written to the real stderr as they came (it is not the terminal).
    passed_on: bool,
}

/// Stderr redirected into a pipe read by a thread.
struct Capture {
    saved: OwnedFd,
    thread: Option<std::thread::JoinHandle<()>>,
    captured: Arc<Mutex<Captured>>,
}

impl Capture {
    fn start() -> io::Result<Capture> {
        let (r, w) = nix::unistd::pipe()?;
        // SAFETY: duplicating stderr, which is open for the whole process.
        let saved = unsafe { libc::dup(2) };
        if saved < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: `saved` was just returned by dup and is owned by nobody else.
        let saved = unsafe { OwnedFd::from_raw_fd(saved) };
        let _ = nix::fcntl::fcntl(
            &saved,
            nix::fcntl::FcntlArg::F_SETFD(nix::fcntl::FdFlag::FD_CLOEXEC),
        );
        let _ = nix::fcntl::fcntl(
            &r,
            nix::fcntl::FcntlArg::F_SETFD(nix::fcntl::FdFlag::FD_CLOEXEC),
        );
        // SAFETY: replaces descriptor 2 with the pipe's write end; `w` stays owned and is
        // closed below, so only descriptor 2 holds the write end.
        if unsafe { libc::dup2(w.as_raw_fd(), 2) } < 0 {
            return Err(io::Error::last_os_error());
        }
        drop(w);
        let through = !nix::unistd::isatty(&saved).unwrap_or(false);
        let captured = Arc::new(Mutex::new(Captured {
            passed_on: through,
            ..Captured::default()
        }));
        let raw_saved: RawFd = saved.as_raw_fd();
        SAVED_STDERR.store(raw_saved, Ordering::SeqCst);
        let sink = captured.clone();
        let out_fd = saved.try_clone()?;
        let thread = std::thread::Builder::new()
            .name("busnoop-stderr".into())
            .spawn(move || {
                use std::io::BufRead;
                let mut out = std::fs::File::from(out_fd);
                for line in io::BufReader::new(std::fs::File::from(r)).lines() {
                    let Ok(line) = line else { break };
                    if through {
                        let _ = writeln!(out, "{line}");
                    }
                    let mut c = sink.lock().unwrap_or_else(|e| e.into_inner());
                    if c.lines.len() < KEPT_LINES {
                        c.lines.push(line);
                    } else {
                        c.dropped += 1;
                    }
                }
            })?;
        Ok(Capture {
            saved,
            thread: Some(thread),
            captured,
        })
    }

    /// Gives stderr back and writes what was kept (unless it went through already).
    fn finish(mut self) {
        if SAVED_STDERR.swap(-1, Ordering::SeqCst) >= 0 {
            // SAFETY: see `restore`.
            unsafe { libc::dup2(self.saved.as_raw_fd(), 2) };
        }
        // Descriptor 2 no longer holds the pipe: the thread reads to the end and stops.
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        let c = self.captured.lock().unwrap_or_else(|e| e.into_inner());
        if !c.passed_on {
            let mut err = io::stderr().lock();
            for l in &c.lines {
                let _ = writeln!(err, "{l}");
            }
            if c.dropped > 0 {
                let _ = writeln!(
                    err,
                    "busnoop: {} more lines of messages were not kept",
                    c.dropped
                );
            }
        }
    }
}

/// The live view's terminal.
pub struct Screen {
    pub terminal: Terminal<CrosstermBackend<Stdout>>,
    capture: Option<Capture>,
}

impl Screen {
    /// Raw mode, alternate screen, hidden cursor; stderr captured.
    pub fn open() -> io::Result<Screen> {
        static HOOK: Once = Once::new();
        HOOK.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                restore();
                previous(info);
            }));
            let _ = install_stop_and_quit();
        });
        let capture = Capture::start().ok();
        let opened = (|| {
            save_settings();
            crate::signal::at_exit(restore_at_exit);
            enable_raw_mode()?;
            ACTIVE.store(true, Ordering::SeqCst);
            execute!(io::stdout(), EnterAlternateScreen, Hide)?;
            let backend = CrosstermBackend::new(io::stdout());
            let viewport = Viewport::Fixed(bounded(backend.size().unwrap_or_default()));
            Terminal::with_options(backend, TerminalOptions { viewport })
        })();
        match opened {
            // (Sized at each draw: a terminal that goes away meanwhile then closes the view
            // like one that gives no more input, instead of failing the run here.)
            Ok(terminal) => Ok(Screen { terminal, capture }),
            Err(e) => {
                restore();
                if let Some(c) = capture {
                    c.finish();
                }
                Err(e)
            }
        }
    }

    /// Follows the terminal's size (within the bound) before a frame is drawn.
    pub fn fit(&mut self) -> io::Result<()> {
        let area = bounded(self.terminal.backend().size().unwrap_or_default());
        if area != self.terminal.get_frame().area() {
            self.terminal.resize(area)?;
        }
        Ok(())
    }

    /// Sets raw mode and the alternate screen up again after a stop ([`resumed`]); the next
    /// frame is drawn whole.
    pub fn resume(&mut self) -> io::Result<()> {
        // crossterm still thinks raw mode is on (the handler put the settings back behind its
        // back) and would do nothing: off first, then on.
        disable_raw_mode()?;
        enable_raw_mode()?;
        execute!(io::stdout(), EnterAlternateScreen, Hide)?;
        self.terminal.clear()
    }

    /// The last `n` lines written to stderr while the view runs.
    pub fn messages(&self, n: usize) -> Vec<String> {
        match &self.capture {
            Some(c) => {
                let c = c.captured.lock().unwrap_or_else(|e| e.into_inner());
                let from = c.lines.len().saturating_sub(n);
                c.lines[from..].to_vec()
            }
            None => Vec::new(),
        }
    }
}

impl Drop for Screen {
    fn drop(&mut self) {
        restore();
        if let Some(c) = self.capture.take() {
            c.finish();
        }
        // The drawing library's own clean-up (its `Terminal` drops after this) shows a cursor
        // a drawing hid and, when that fails, says so with `eprintln!`, which panics when
        // stderr is a terminal that went away. Shown here first: where it fails, the terminal
        // is gone, and the standard descriptors that were it go to /dev/null.
        if self.terminal.show_cursor().is_err() {
            detach_from_terminal();
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::sink::fallback_size;

    #[test]
    fn a_terminal_without_size_is_drawn_at_columns_and_lines_or_80x24() {
        assert_eq!(fallback_size(Some("132"), Some("43")), (132, 43));
        assert_eq!(fallback_size(None, None), (80, 24));
        assert_eq!(fallback_size(Some("0"), Some("x")), (80, 24));
        assert_eq!(fallback_size(Some("99999"), Some(" 30 ")), (80, 30));
    }
}
