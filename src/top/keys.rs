//! The keys of the live view, read from the terminal's descriptor without crossterm's event
//! reader: every byte of a burst is read and parsed (crossterm's parser left the keys after the
//! first 1023 bytes of a burst, a `q` among them, until another key came), and the end of the
//! terminal (`read` = 0, or an error: the terminal or its session is gone) is seen instead of
//! being polled for again and again (100 % CPU on `read(0) = 0`).

use std::os::fd::RawFd;
use std::time::Duration;

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

/// Bytes read from the terminal at most per call: far more than a person types between two
/// frames; a longer burst is read on at the next call.
const READ_MAX: usize = 64 * 1024;

/// An escape sequence longer than this is not one the view knows: it is dropped.
const SEQUENCE_MAX: usize = 32;

/// What reading the terminal gave.
#[derive(Debug, PartialEq, Eq)]
pub enum Read {
    Keys(Vec<KeyEvent>),
    /// End of file or an error on the terminal: it is gone.
    Gone,
}

/// Reads keys from a terminal descriptor in raw mode.
pub struct Keys {
    fd: RawFd,
    parser: Parser,
    buf: Vec<u8>,
}

impl Keys {
    pub fn new(fd: RawFd) -> Self {
        Keys {
            fd,
            parser: Parser::default(),
            buf: vec![0; 4096],
        }
    }

    /// Waits up to `wait` for input, then reads everything that is there (up to
    /// [`READ_MAX`] bytes) and returns its keys.
    pub fn read(&mut self, wait: Duration) -> Read {
        let mut keys = Vec::new();
        let mut wait = wait;
        let mut total = 0;
        while total < READ_MAX {
            let mut pfd = libc::pollfd {
                fd: self.fd,
                events: libc::POLLIN,
                revents: 0,
            };
            let ms = wait.as_millis().min(i32::MAX as u128) as i32;
            // SAFETY: one valid pollfd.
            let n = unsafe { libc::poll(&mut pfd, 1, ms) };
            wait = Duration::ZERO;
            if n < 0 {
                if std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted {
                    continue;
                }
                return Read::Gone;
            }
            if n == 0 {
                break;
            }
            if pfd.revents & libc::POLLNVAL != 0 {
                return Read::Gone;
            }
            // SAFETY: reads into our own buffer of that length.
            let got = unsafe { libc::read(self.fd, self.buf.as_mut_ptr().cast(), self.buf.len()) };
            match got {
                0 => return Read::Gone,
                n if n < 0 => match std::io::Error::last_os_error().kind() {
                    std::io::ErrorKind::Interrupted | std::io::ErrorKind::WouldBlock => break,
                    _ => return Read::Gone,
                },
                n => {
                    let n = n as usize;
                    total += n;
                    self.parser.feed(&self.buf[..n], &mut keys);
                }
            }
        }
        self.parser.end_of_read(&mut keys);
        Read::Keys(keys)
    }
}

/// Turns the bytes a terminal sends into keys.
#[derive(Debug, Default)]
pub struct Parser {
    /// An escape sequence or UTF-8 character not complete yet.
    pending: Vec<u8>,
}

fn key(code: KeyCode, modifiers: KeyModifiers) -> KeyEvent {
    KeyEvent::new(code, modifiers)
}

impl Parser {
    /// Parses `bytes`; keys go to `out`. An unfinished sequence waits for the next bytes.
    pub fn feed(&mut self, bytes: &[u8], out: &mut Vec<KeyEvent>) {
        for &b in bytes {
            self.pending.push(b);
            self.parse(out, false);
        }
    }

    /// The read is over: a lone ESC left waiting is the Esc key (as terminals send it).
    pub fn end_of_read(&mut self, out: &mut Vec<KeyEvent>) {
        self.parse(out, true);
    }

    fn parse(&mut self, out: &mut Vec<KeyEvent>, end: bool) {
        let p = &self.pending;
        let Some(&first) = p.first() else { return };
        let none = KeyModifiers::NONE;
        let done = match first {
            0x1B => match p.get(1) {
                None if end => Some(key(KeyCode::Esc, none)),
                None => None,
                Some(b'[') => csi(p),
                Some(b'O') => p
                    .get(2)
                    .map(|&c| key(cursor(c).unwrap_or(KeyCode::Null), none)),
                // Alt and a key.
                Some(&c) => Some(key(KeyCode::Char(c as char), KeyModifiers::ALT)),
            },
            b'\r' | b'\n' => Some(key(KeyCode::Enter, none)),
            0x7F | 0x08 => Some(key(KeyCode::Backspace, none)),
            b'\t' => Some(key(KeyCode::Tab, none)),
            0x00 => Some(key(KeyCode::Null, none)),
            c @ 0x01..=0x1A => Some(key(
                KeyCode::Char((b'a' + c - 1) as char),
                KeyModifiers::CONTROL,
            )),
            0x1C => Some(key(KeyCode::Char('\\'), KeyModifiers::CONTROL)),
            0x1D..=0x1F => Some(key(KeyCode::Null, none)),
            _ => match std::str::from_utf8(p) {
                Ok(s) => s.chars().next().map(|c| key(KeyCode::Char(c), none)),
                // Not complete yet, or not UTF-8 at all.
                Err(e) if e.error_len().is_none() && p.len() < 4 => None,
                Err(_) => Some(key(KeyCode::Null, none)),
            },
        };
        match done {
            Some(k) => {
                if k.code != KeyCode::Null {
                    out.push(k);
                }
                self.pending.clear();
            }
            None if self.pending.len() > SEQUENCE_MAX => self.pending.clear(),
            None => {}
        }
    }
}

/// The key of a cursor or editing final byte (`ESC [ A`, `ESC O H`).
fn cursor(c: u8) -> Option<KeyCode> {
    Some(match c {
        b'A' => KeyCode::Up,
        b'B' => KeyCode::Down,
        b'C' => KeyCode::Right,
        b'D' => KeyCode::Left,
        b'H' => KeyCode::Home,
        b'F' => KeyCode::End,
        _ => return None,
    })
}

/// A CSI sequence (`ESC [ params final`): its key when complete (`KeyCode::Null` for one the
/// view does not use), `None` while it is not.
fn csi(p: &[u8]) -> Option<KeyEvent> {
    let rest = &p[2..];
    let end = rest.iter().position(|b| (0x40..=0x7E).contains(b))?;
    let (params, fin) = (&rest[..end], rest[end]);
    let code = match fin {
        b'~' => match params.split(|&b| b == b';').next().unwrap_or(&[]) {
            b"1" | b"7" => KeyCode::Home,
            b"4" | b"8" => KeyCode::End,
            b"5" => KeyCode::PageUp,
            b"6" => KeyCode::PageDown,
            b"3" => KeyCode::Delete,
            _ => KeyCode::Null,
        },
        c => cursor(c).unwrap_or(KeyCode::Null),
    };
    Some(key(code, KeyModifiers::NONE))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(chunks: &[&[u8]]) -> Vec<KeyCode> {
        let mut p = Parser::default();
        let mut out = Vec::new();
        for c in chunks {
            p.feed(c, &mut out);
            p.end_of_read(&mut out);
        }
        out.into_iter().map(|k| k.code).collect()
    }

    #[test]
    fn keys_and_sequences() {
        use KeyCode::*;
        assert_eq!(
            keys(&[b"q\x1b[A\x1b[B\x1bOH\x1b[5~\x1b[6;2~ \r\x7f\x1b"]),
            [
                Char('q'),
                Up,
                Down,
                Home,
                PageUp,
                PageDown,
                Char(' '),
                Enter,
                Backspace,
                Esc
            ]
        );
        // A sequence split between two reads.
        assert_eq!(keys(&[b"\x1b[", b"A", b"\x1b[1", b"5~x"]), [Up, Char('x')]);
        // UTF-8 split between two reads, a control key.
        assert_eq!(keys(&[b"\xc3", b"\xa4\x03"]), [Char('ä'), Char('c')]);
        // Unknown sequences are dropped, the keys after them kept.
        assert_eq!(keys(&[b"\x1b[200~\x1b[99Zq"]), [Char('q')]);
    }

    /// Every key of a long burst comes out, the last one too.
    #[test]
    fn a_burst_loses_nothing() {
        let mut burst = b"\x1b[A\x1b[Bx".repeat(5000);
        burst.push(b'q');
        let k = keys(&[&burst]);
        assert_eq!(k.len(), 15_001);
        assert_eq!(k.last(), Some(&KeyCode::Char('q')));
    }

    /// The end of the terminal is seen: a pipe whose writer closed reads as gone, at once.
    #[test]
    fn end_of_file_is_gone() {
        let (r, w) = nix::unistd::pipe().unwrap();
        nix::unistd::write(&w, b"ab").unwrap();
        let mut k = Keys::new(std::os::fd::AsRawFd::as_raw_fd(&r));
        assert!(matches!(k.read(Duration::ZERO), Read::Keys(v) if v.len() == 2));
        drop(w);
        let t = std::time::Instant::now();
        assert_eq!(k.read(Duration::from_secs(5)), Read::Gone);
        assert!(t.elapsed() < Duration::from_secs(1));
    }
}
