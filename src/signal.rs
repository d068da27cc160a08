//! SIGINT/SIGTERM/SIGHUP: asked once, busnoop stops cleanly (every decoded row written); asked
//! twice, it ends at once (after [`at_exit`]: the live view gives the terminal back). The sources'
//! waits and the driver both look here.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// SIGINT/SIGTERM/SIGHUP catcher. The first signal asks busnoop to stop cleanly; a second one of
/// the same kind ends the process at once. A hangup (the SSH session or the terminal gone) is
/// caught like SIGTERM, so that the rows still buffered reach `-o FILE`, unless SIGHUP is
/// ignored (`nohup busnoop …`: the capture is meant to go on). Signals are process-wide, so
/// there is one catcher.
#[derive(Clone)]
pub struct Stop {
    signal: Arc<AtomicUsize>,
}

static STOP: OnceLock<Stop> = OnceLock::new();

/// What the second signal's handler runs before the process ends: see [`at_exit`].
static AT_EXIT: OnceLock<fn()> = OnceLock::new();

/// Sets what a second signal runs right before the process ends (the live view puts the
/// terminal back). It runs inside the signal handler: only async-signal-safe calls, no lock, no
/// allocation. Only the first call counts.
pub fn at_exit(f: fn()) {
    let _ = AT_EXIT.set(f);
}

impl Stop {
    /// Installs the handlers (once per process; later calls return the same catcher).
    pub fn install() -> std::io::Result<Stop> {
        if let Some(s) = STOP.get() {
            return Ok(s.clone());
        }
        let signal = Arc::new(AtomicUsize::new(0));
        let hangup = (!hangup_ignored()).then_some(signal_hook::consts::SIGHUP);
        let signals = [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM];
        for sig in signals.into_iter().chain(hangup) {
            let armed = Arc::new(AtomicBool::new(false));
            // Second signal: exit immediately with the conventional code, the live view's
            // terminal put back first (raw mode off, main screen).
            let second = armed.clone();
            // SAFETY: the action only loads atomics, calls the `at_exit` function (which must be
            // async-signal-safe, see there) and `_exit`.
            unsafe {
                signal_hook::low_level::register(sig, move || {
                    if second.load(Ordering::SeqCst) {
                        if let Some(f) = AT_EXIT.get() {
                            f();
                        }
                        signal_hook::low_level::exit(128 + sig);
                    }
                })
            }?;
            signal_hook::flag::register(sig, armed)?;
            signal_hook::flag::register_usize(sig, signal.clone(), sig as usize)?;
        }
        Ok(STOP.get_or_init(|| Stop { signal }).clone())
    }

    /// The signal received, if any.
    pub fn signal(&self) -> Option<i32> {
        match self.signal.load(Ordering::Relaxed) {
            0 => None,
            s => Some(s as i32),
        }
    }

    /// The signal received, if the handlers are installed and one came (for waits outside the
    /// driver, such as opening a FIFO).
    pub fn received() -> Option<i32> {
        STOP.get().and_then(Stop::signal)
    }
}

/// Whether SIGHUP is ignored, as `nohup` starts a program: a handler would undo that.
fn hangup_ignored() -> bool {
    // SAFETY: `sigaction` with no new action only reads the current one into `old`, a plain C
    // struct for which all zeros is a valid value.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(libc::SIGHUP, std::ptr::null(), &mut old) == 0
            && old.sa_sigaction == libc::SIG_IGN
    }
}
