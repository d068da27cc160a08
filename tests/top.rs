//! `--top` on pseudo-terminals: the device is one pty, busnoop's terminal (stdin, stdout,
//! stderr) another. The test reads the screen, presses keys, and checks the terminal is given
//! back as it was; and the hint for a port that stays silent.

mod common;

use std::io::{BufRead, Read, Write};
use std::os::fd::{AsRawFd, OwnedFd};
use std::os::unix::fs::OpenOptionsExt;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use busnoop::sport::wire;
use common::pty::{bin, bus, lock, wait_exit};
use serialport::{SerialPort, TTYPort};

/// A terminal for busnoop: the test holds `master` (the screen and keyboard), busnoop gets
/// the slave as stdin, stdout and stderr, `cols`×`rows` big.
struct Term {
    master: TTYPort,
    slave: TTYPort,
}

fn terminal(cols: u16, rows: u16) -> Term {
    let (master, slave) = TTYPort::pair().expect("pty pair");
    for fd in [master.as_raw_fd(), slave.as_raw_fd()] {
        unsafe { libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC) };
    }
    let ws = libc::winsize {
        ws_row: rows,
        ws_col: cols,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    assert_eq!(
        unsafe { libc::ioctl(slave.as_raw_fd(), libc::TIOCSWINSZ, &ws) },
        0
    );
    // A terminal as a shell leaves it (pty pairs start raw): line editing, echo, signals.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    assert_eq!(unsafe { libc::tcgetattr(slave.as_raw_fd(), &mut t) }, 0);
    t.c_lflag |= libc::ICANON | libc::ECHO | libc::ISIG | libc::IEXTEN;
    assert_eq!(
        unsafe { libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t) },
        0
    );
    Term { master, slave }
}

/// A child killed when the test fails before it exited.
struct Kill(Child);

impl std::ops::Deref for Kill {
    type Target = Child;
    fn deref(&self) -> &Child {
        &self.0
    }
}

impl std::ops::DerefMut for Kill {
    fn deref_mut(&mut self) -> &mut Child {
        &mut self.0
    }
}

impl Drop for Kill {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

impl Term {
    /// Starts busnoop with `args` on this terminal (stdin, stdout and stderr), `TERM=xterm`.
    fn run(&self, args: &[&dyn AsRef<std::ffi::OsStr>]) -> Kill {
        Kill(
            Command::new(bin())
                .args(args.iter().map(|a| a.as_ref()))
                .stdin(self.stdio())
                .stdout(self.stdio())
                .stderr(self.stdio())
                .env("TERM", "xterm")
                .spawn()
                .unwrap(),
        )
    }

    fn stdio(&self) -> Stdio {
        let fd = unsafe { libc::dup(self.slave.as_raw_fd()) };
        assert!(fd >= 0);
        Stdio::from(unsafe { <OwnedFd as std::os::fd::FromRawFd>::from_raw_fd(fd) })
    }

    fn lflag(&self) -> libc::tcflag_t {
        let mut t: libc::termios = unsafe { std::mem::zeroed() };
        assert_eq!(
            unsafe { libc::tcgetattr(self.slave.as_raw_fd(), &mut t) },
            0
        );
        t.c_lflag
    }
}

/// Everything busnoop drew, collected by a thread.
fn collect(master: &TTYPort) -> Arc<Mutex<Vec<u8>>> {
    let screen = Arc::new(Mutex::new(Vec::new()));
    let mut reader = master.try_clone_native().unwrap();
    reader.set_timeout(Duration::from_millis(50)).unwrap();
    let s = screen.clone();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        loop {
            match reader.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => s.lock().unwrap().extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(_) => break,
            }
        }
    });
    screen
}

/// Waits up to 10 s for `text` in what was drawn after byte `from`; returns where it ends.
fn wait_for(screen: &Mutex<Vec<u8>>, from: usize, text: &str) -> usize {
    let deadline = Instant::now() + common::PATIENCE;
    loop {
        {
            let s = screen.lock().unwrap();
            if let Some(i) = s[from.min(s.len())..]
                .windows(text.len())
                .position(|w| w == text.as_bytes())
            {
                return from + i + text.len();
            }
        }
        assert!(
            Instant::now() < deadline,
            "{text:?} not on the screen; drawn: {}",
            String::from_utf8_lossy(&screen.lock().unwrap()[from..])
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn top_on_a_live_port_shows_the_sensors_and_gives_the_terminal_back() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("table.tsv");
    let rec = dir.path().join("wire.bin");
    let mut b = bus();
    let term = terminal(120, 30);
    let before = term.lflag();
    let screen = collect(&term.master);
    let mut child = term.run(&[
        &"sport",
        &"--top",
        &"-o",
        &table,
        &"--record",
        &rec,
        &b.path,
    ]);
    // The alternate screen, the header, the key help.
    let at = wait_for(&screen, 0, "\x1b[?1049h");
    let at = wait_for(&screen, at, "S.Port");
    wait_for(&screen, at, "quit");
    assert_eq!(
        term.lflag() & libc::ICANON,
        0,
        "raw mode while the view runs"
    );

    // Nothing on the bus: after 5 s the hint shows at the bottom of the view.
    let at = wait_for(&screen, at, "no bytes from");
    wait_for(&screen, at, "check RX wiring");

    // Frames: an altitude (physical ID 0) and a poll without answer.
    let mut wire_bytes = Vec::new();
    for i in 0..20u32 {
        let mut f = Vec::new();
        wire::encode_frame(&mut f, wire::header_for(0), 0x10, 0x0100, 6500 + i);
        wire::encode_poll(&mut f, wire::header_for(3));
        b.master.write_all(&f).unwrap();
        wire_bytes.extend_from_slice(&f);
        std::thread::sleep(Duration::from_millis(12));
    }
    let at = wait_for(&screen, at, "Alt");
    wait_for(&screen, at, "65.19");

    // Keys: sort, pause, filter (typed and applied), then quit.
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"s")
        .unwrap();
    let at = wait_for(&screen, at, "sort rate");
    let mut keys = term.master.try_clone_native().unwrap();
    keys.write_all(b"fsensor=Alt\r").unwrap();
    let at = wait_for(&screen, at, "filter \"sensor=Alt\"");
    keys.write_all(b"p").unwrap();
    let at = wait_for(&screen, at, "PAUSED");
    keys.write_all(b"q").unwrap();
    let status = wait_exit(&mut child);
    assert!(status.success(), "{status:?}");

    // The terminal is given back: alternate screen left, cursor shown, cooked mode again (the
    // screen reader may still be on its way to the last bytes: wait for them).
    let left = wait_for(&screen, at, "\x1b[?1049l");
    wait_for(&screen, left, "\x1b[?25h");
    assert_eq!(term.lflag(), before, "terminal modes restored");
    // What was said on stderr during the view is repeated on the terminal after it.
    wait_for(&screen, left, "no bytes from");

    // Nothing lost: the table has every frame, the recording every byte.
    let rows = std::fs::read_to_string(&table).unwrap();
    let alt = rows.lines().filter(|l| l.contains("\tAlt\t")).count();
    assert_eq!(alt, 20, "{rows}");
    assert_eq!(std::fs::read(&rec).unwrap(), wire_bytes);
    drop(b);
}

#[test]
fn a_silent_port_gets_the_wiring_hint_in_the_table_mode() {
    let _g = lock();
    let b = bus();
    let mut child = Command::new(bin())
        .args(["sport", "-f", "tsv"])
        .arg(&b.path)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stderr).lines() {
            let Ok(line) = line else { break };
            let _ = tx.send(line);
        }
    });
    let line = loop {
        let l = rx.recv_timeout(common::PATIENCE).expect("no hint");
        if l.contains("no bytes") {
            break l;
        }
    };
    assert!(
        started.elapsed() >= Duration::from_secs(5),
        "not before 5 s"
    );
    assert_eq!(
        line,
        format!(
            "busnoop: no bytes from {} in 5 s: check RX wiring and that the bus is powered",
            b.path.display()
        )
    );
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    wait_exit(&mut child);
}

#[test]
fn top_needs_a_terminal_and_keeps_stdout_for_itself() {
    let out = Command::new(bin())
        .args(["sport", "--top", "fixtures/sport-sample.bin"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--top needs a terminal"));
    let out = Command::new(bin())
        .args(["sport", "--top", "-o", "-", "fixtures/sport-sample.bin"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("write the table with -o FILE"));
}

#[test]
fn speed_paces_the_table_of_a_replay() {
    // sport-sample.bin spans 336 ms of bus time: at --speed 1 the table takes about that long,
    // at the default (0) no time at all.
    let t = Instant::now();
    let paced = Command::new(bin())
        .args([
            "sport",
            "-f",
            "tsv",
            "--speed",
            "1",
            "fixtures/sport-sample.bin",
        ])
        .output()
        .unwrap();
    let took = t.elapsed();
    assert!(paced.status.success());
    assert!(took >= Duration::from_millis(300), "{took:?}");
    let fast = Command::new(bin())
        .args(["sport", "-f", "tsv", "fixtures/sport-sample.bin"])
        .output()
        .unwrap();
    assert_eq!(paced.stdout, fast.stdout, "the same rows");
    let bad = Command::new(bin())
        .args(["sport", "--speed", "-1", "fixtures/sport-sample.bin"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}

#[test]
fn ctrl_c_in_a_paced_replay_stops_like_sigint_and_restores_the_terminal() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    // 30 s of S.Port at the bus rate.
    let sample = std::fs::read("fixtures/sport-sample.bin").unwrap();
    let long = dir.path().join("long.bin");
    std::fs::write(&long, sample.repeat(80)).unwrap();
    let table = dir.path().join("t.tsv");
    let term = terminal(100, 24);
    let before = term.lflag();
    let screen = collect(&term.master);
    let mut child = term.run(&[&"sport", &"--top", &"-o", &table, &long]);
    let at = wait_for(&screen, 0, "×1");
    let at = wait_for(&screen, at, "Volts");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"\x03")
        .unwrap();
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(130));
    let at = wait_for(&screen, at, "\x1b[?1049l");
    wait_for(&screen, at, "interrupted after");
    assert_eq!(term.lflag(), before);
    // Paced: far from all of the 30 s were decoded, and what was is in the table.
    let rows = std::fs::read_to_string(&table).unwrap().lines().count();
    assert!(rows > 1 && rows < 2400, "{rows}");
}

#[test]
fn a_second_sigterm_ends_at_once_and_still_gives_the_terminal_back() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let sample = std::fs::read("fixtures/sport-sample.bin").unwrap();
    let long = dir.path().join("long.bin");
    std::fs::write(&long, sample.repeat(400)).unwrap();
    // The table goes into a FIFO that is open but never read: once its buffer is full, the
    // table's write blocks, so the first SIGTERM cannot end the run cleanly and the second one
    // has to end it at once.
    let fifo = dir.path().join("table.fifo");
    common::mkfifo(&fifo);
    let reader = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(&fifo)
        .unwrap();
    let term = terminal(100, 24);
    let before = term.lflag();
    let screen = collect(&term.master);
    let mut child = term.run(&[
        &"sport", &"--top", &"--speed", &"0", &"-f", &"tsv", &"-o", &fifo, &long,
    ]);
    let at = wait_for(&screen, 0, "\x1b[?1049h");
    // Once the FIFO is full the table's write blocks.
    let pid = child.id();
    common::until("the table's write blocks", || {
        common::waits_in(pid, "pipe_write")
    });
    assert_ne!(term.lflag(), before, "raw mode while the view runs");
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    std::thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "still blocked");
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(143));
    wait_for(&screen, at, "\x1b[?1049l");
    assert_eq!(term.lflag(), before, "terminal modes restored");
    drop(reader);
}

/// A terminal that reports no size (0x0: some serial consoles and containers) gets the view at
/// COLUMNS x LINES (else 80x24). It used to be drawn at 0x0: an empty screen.
#[test]
fn a_terminal_without_size_gets_the_view_at_columns_and_lines() {
    let _g = lock();
    let term = terminal(0, 0);
    let screen = collect(&term.master);
    let mut child = Command::new(bin())
        .args([
            "sport",
            "--top",
            "--speed",
            "0",
            "fixtures/sport-sample.bin",
        ])
        .stdin(term.stdio())
        .stdout(term.stdio())
        .stderr(term.stdio())
        .env("TERM", "xterm")
        .env("COLUMNS", "100")
        .env("LINES", "20")
        .spawn()
        .unwrap();
    let at = wait_for(&screen, 0, "\x1b[?1049h");
    let at = wait_for(&screen, at, "S.Port");
    let at = wait_for(&screen, at, "Volts");
    wait_for(&screen, at, "quit");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"q")
        .unwrap();
    let status = wait_exit(&mut child);
    assert!(status.success(), "{status:?}");
}

/// The screen as the terminal shows it after `bytes` (a tiny emulator of what the view
/// writes: cursor moves `ESC[r;cH`, colours and modes ignored, text at the cursor).
fn emulate(bytes: &[u8], w: usize, h: usize) -> Vec<String> {
    let text = String::from_utf8_lossy(bytes);
    let mut grid = vec![vec![' '; w]; h];
    let (mut row, mut col) = (0usize, 0usize);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\x1b' {
            if chars.peek() != Some(&'[') {
                chars.next();
                continue;
            }
            chars.next();
            let mut params = String::new();
            let mut end = ' ';
            for c in chars.by_ref() {
                if c.is_ascii_alphabetic() || c == '~' {
                    end = c;
                    break;
                }
                params.push(c);
            }
            match end {
                'H' => {
                    let mut n = params.split(';').map(|p| p.parse::<usize>().unwrap_or(1));
                    row = n.next().unwrap_or(1).saturating_sub(1);
                    col = n.next().unwrap_or(1).saturating_sub(1);
                }
                'J' if params == "2" => grid = vec![vec![' '; w]; h],
                _ => {}
            }
        } else if c == '\r' {
            col = 0;
        } else if c == '\n' {
            row += 1;
        } else if row < h && col < w {
            grid[row][col] = c;
            col += 1;
        }
    }
    grid.into_iter().map(|l| l.into_iter().collect()).collect()
}

/// At 80 columns the view shows each FLVSS cell on a line of its own with its own minimum and
/// maximum (the typed numbers, not the cell count the Data text starts with), and every number
/// whole: the app IDs 0xF101, 0xF104, 0xF105 (once all cut to `0xF1`), the S-Bus register
/// 305419896 (once `30541`).
#[test]
fn top_at_80_columns_shows_each_cell_and_every_number_whole() {
    let _g = lock();
    for (protocol, file, want) in [
        (
            "sport",
            "fixtures/edgetx-MODELE24-2014-07-11-sport.log",
            &[
                "Cell1", "Cell3", "4.200", "0xF101", "0xF104", "0xF105", "5.07",
            ][..],
        ),
        (
            "sbus",
            "fixtures/sbus-digimat.pcap",
            &["305419896", "-1245334075"][..],
        ),
    ] {
        let term = terminal(80, 40);
        let screen = collect(&term.master);
        let mut child = term.run(&[&protocol, &"--top", &"--speed", &"0", &file]);
        wait_for(&screen, 0, "END OF INPUT");
        if protocol == "sbus" {
            // The registers: filtered like the command line.
            term.master
                .try_clone_native()
                .unwrap()
                .write_all(b"fsensor=R0\r")
                .unwrap();
        }
        // The screen as it stands once the view is still.
        let deadline = Instant::now() + Duration::from_secs(10);
        let shown = loop {
            let lines = emulate(&screen.lock().unwrap(), 80, 40);
            let words: Vec<&str> = lines.iter().flat_map(|l| l.split_whitespace()).collect();
            if want.iter().all(|w| words.contains(w)) {
                break lines;
            }
            if Instant::now() > deadline {
                let _ = child.kill();
                panic!(
                    "{want:?} not all whole on the screen:\n{}",
                    lines.join("\n")
                );
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        assert!(shown.iter().all(|l| l.trim_end().chars().count() <= 80));
        term.master
            .try_clone_native()
            .unwrap()
            .write_all(b"q")
            .unwrap();
        let status = wait_exit(&mut child);
        assert!(status.success(), "{status:?}");
    }
}

/// The pretty table (the default on a terminal) fits the terminal's width: on 80 columns no
/// line is longer, every row is there with its numbers (Counter, Millis, ID, Sensor #) whole,
/// and Data is wrapped, not lost. It ignored the width: the S.Port header was 111 columns, SAB2
/// rows reached 250, and every row wrapped across the next one's columns. `--no-fit` keeps the
/// full lines.
#[test]
fn the_pretty_table_fits_the_terminal() {
    let _g = lock();
    for (protocol, file) in [
        ("sab2", "fixtures/sab2-session.bin"),
        ("sport", "fixtures/sport-sample.bin"),
        ("sbus", "fixtures/sbus-digimat.pcap"),
    ] {
        let rows = Command::new(bin())
            .args([protocol, file, "-f", "tsv"])
            .output()
            .unwrap();
        let tsv = String::from_utf8(rows.stdout).unwrap();
        for (fit, args) in [(true, &[][..]), (false, &["--no-fit"][..])] {
            let term = terminal(80, 24);
            let screen = collect(&term.master);
            let mut child = Command::new(bin())
                .args([protocol, file])
                .args(args)
                .stdin(term.stdio())
                .stdout(term.stdio())
                .stderr(Stdio::null())
                .env("TERM", "xterm")
                .env("NO_COLOR", "1")
                .spawn()
                .unwrap();
            assert!(wait_exit(&mut child).success());
            std::thread::sleep(Duration::from_millis(200));
            let out = String::from_utf8_lossy(&screen.lock().unwrap()).replace('\r', "");
            let lines: Vec<&str> = out.lines().collect();
            let longest = lines.iter().map(|l| l.chars().count()).max().unwrap();
            if !fit {
                assert!(longest > 80, "{protocol} --no-fit: {longest}");
                continue;
            }
            assert!(longest <= 80, "{protocol}: a line of {longest}:\n{out}");
            let words: Vec<&str> = out.split_whitespace().collect();
            for row in tsv.lines().skip(1) {
                let c: Vec<&str> = row.split('\t').collect();
                // The row's first line starts with its Counter and Millis.
                let start = format!("{} {}", c[0], c[1]);
                assert!(
                    lines.iter().any(|l| l
                        .split_whitespace()
                        .collect::<Vec<_>>()
                        .join(" ")
                        .starts_with(&start)),
                    "{protocol}: row {} missing:\n{out}",
                    c[0]
                );
                for cell in [c[2], c[5]].into_iter().chain(c[7].split(' ')) {
                    if !cell.is_empty() {
                        assert!(
                            words.contains(&cell),
                            "{protocol}: {cell} not whole:\n{out}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn top_shows_the_rc_buses_sensors_and_channels() {
    let _g = lock();
    // iBUS: a sensor per address, with its value in units.
    let term = terminal(140, 30);
    let screen = collect(&term.master);
    let mut child = term.run(&[&"ibus", &"--top", &"fixtures/ibus-sensors.bin"]);
    let at = wait_for(&screen, 0, "FlySky iBUS");
    let at = wait_for(&screen, at, "ExtV");
    wait_for(&screen, at, "Curr");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"q")
        .unwrap();
    assert!(wait_exit(&mut child).success());
    // Futaba: the channel frames (a line per channel) and the receiver voltage slot.
    let term = terminal(140, 30);
    let screen = collect(&term.master);
    let mut child = term.run(&[&"futaba", &"--top", &"fixtures/futaba-session.bin"]);
    let at = wait_for(&screen, 0, "Futaba SBUS");
    wait_for(&screen, at, "CH16");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"q")
        .unwrap();
    assert!(wait_exit(&mut child).success());
    let term = terminal(140, 30);
    let screen = collect(&term.master);
    let mut child = term.run(&[
        &"futaba",
        &"--top",
        &"--type",
        &"Slot",
        &"fixtures/futaba-session.bin",
    ]);
    let at = wait_for(&screen, 0, "Futaba SBUS");
    wait_for(&screen, at, "RxV");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"q")
        .unwrap();
    assert!(wait_exit(&mut child).success());
}

/// Several sources: each line names its port with its device (the port's file name), and two
/// ports with the same ID and sensor keep a line each.
#[test]
fn top_with_two_sources_keeps_a_line_per_port() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let t0 = 1_700_000_000_000_000i64;
    let mut files = Vec::new();
    for (name, shift) in [("left.pcap", 0), ("right.pcap", 6_000)] {
        let mut out = Vec::new();
        busnoop::pcap::write::header(&mut out, busnoop::pcap::linktype::USER0);
        for i in 0..20u32 {
            let mut f = Vec::new();
            wire::encode_frame(&mut f, wire::header_for(0), 0x10, 0x0100, 6500 + i);
            busnoop::pcap::write::record(&mut out, t0 + shift + 12_000 * i as i64, &f);
        }
        let path = dir.path().join(name);
        std::fs::write(&path, out).unwrap();
        files.push(path);
    }
    let term = terminal(120, 30);
    let screen = collect(&term.master);
    let mut child = term.run(&[&"sport", &"--top", &"--speed", &"0", &files[0], &files[1]]);
    let at = wait_for(&screen, 0, "S.Port");
    // `left.pcap: Vario` (the screen is drawn with cursor moves over the blanks).
    wait_for(&screen, at, "left.pcap:");
    wait_for(&screen, at, "right.pcap:");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"q")
        .unwrap();
    let status = wait_exit(&mut child);
    assert!(status.success(), "{status:?}");
}

/// Modbus in the live view: one line per slave and function, showing the answer's registers by
/// the register map's names and units.
#[test]
fn top_shows_modbus_registers_by_their_map_names() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("busnoop.toml");
    std::fs::write(
        &cfg,
        "[modbus.slaves]\nBoiler = 1\n[modbus.registers]\n\
         \"1/100\" = { name = \"Flow temperature\", type = \"i16\", scale = 0.1, unit = \"°C\" }\n",
    )
    .unwrap();
    let mut b = bus();
    let term = terminal(120, 30);
    let screen = collect(&term.master);
    let mut child = term.run(&[&"modbus", &"--top", &"--config", &cfg, &b.path]);
    let at = wait_for(&screen, 0, "\x1b[?1049h");
    let f = |bytes: &[u8]| {
        let mut v = bytes.to_vec();
        busnoop::modbus::wire::push_crc(&mut v);
        v
    };
    for i in 0..10u16 {
        let t = (600 + i).to_be_bytes();
        b.master.write_all(&f(&[1, 3, 0, 100, 0, 1])).unwrap();
        std::thread::sleep(Duration::from_millis(10));
        b.master.write_all(&f(&[1, 3, 2, t[0], t[1]])).unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    let at = wait_for(&screen, at, "Boiler");
    // (the view draws word by word and only what changed, and cuts the value to its column;
    // the unit has its own)
    let at = wait_for(&screen, at, "Flow temperatur");
    wait_for(&screen, at, "°C");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"q")
        .unwrap();
    assert!(wait_exit(&mut child).success());
    drop(b);
}

/// H1 (issue 32): a time stamp beyond the calendar panicked inside `--top` (the table's
/// `--time abs`), leaving an empty table and a raw terminal. Now it is a `TimeJump` row.
#[test]
fn top_on_a_time_stamp_beyond_the_calendar_keeps_every_row() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let sample = std::fs::read("fixtures/sport-sample.bin").unwrap();
    let t0 = 1_700_000_000_000_000u64;
    let input = dir.path().join("far.pcapng");
    std::fs::write(
        &input,
        common::pcapng(
            147,
            6,
            &[(t0, &sample), (t0 | 1 << 63, &sample), (t0 + 1, &sample)],
        ),
    )
    .unwrap();
    let table = dir.path().join("t.tsv");
    let term = terminal(100, 24);
    let before = term.lflag();
    let screen = collect(&term.master);
    let mut child = term.run(&[
        &"sport", &"--top", &"--time", &"abs", &"-f", &"tsv", &"-o", &table, &input,
    ]);
    let at = wait_for(&screen, 0, "END OF INPUT");
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(b"q")
        .unwrap();
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(0));
    wait_for(&screen, at, "\x1b[?1049l");
    assert_eq!(term.lflag(), before);
    let table = std::fs::read_to_string(&table).unwrap();
    assert_eq!(table.lines().count(), 92, "{table}");
    assert_eq!(table.matches("\tTimeJump\t").count(), 1, "{table}");
}

/// Types `keys` on the terminal.
fn press(term: &Term, keys: &[u8]) {
    term.master
        .try_clone_native()
        .unwrap()
        .write_all(keys)
        .unwrap();
}

/// A field of /proc/PID/status (`VmHWM`, in kB).
fn status_kb(pid: u32, field: &str) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    s.lines()
        .find_map(|l| l.strip_prefix(field))
        .and_then(|v| {
            v.trim_start_matches(':')
                .split_whitespace()
                .next()?
                .parse()
                .ok()
        })
        .unwrap_or(0)
}

/// The process state letter of /proc/PID/stat (`T`: stopped).
fn state(pid: u32) -> char {
    let s = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    s.rsplit(')')
        .next()
        .and_then(|r| r.trim().chars().next())
        .unwrap_or('?')
}

/// The long table of `file` as busnoop writes it without the view.
fn full_table(file: &std::path::Path) -> String {
    let out = Command::new(bin())
        .args(["sport", "-f", "tsv"])
        .arg(file)
        .output()
        .unwrap();
    String::from_utf8(out.stdout).unwrap()
}

/// L1 (issue 32): the view allocated by the terminal's size (5000×5000: 2 GB and frozen;
/// 65535×65535: SIGABRT with the terminal left raw). The drawn area is bounded.
#[test]
fn a_huge_terminal_is_drawn_in_a_bounded_area() {
    let _g = lock();
    for (cols, rows) in [(5000, 5000), (65535, 65535)] {
        let term = terminal(cols, rows);
        let before = term.lflag();
        let screen = collect(&term.master);
        let mut child = term.run(&[
            &"sport",
            &"--top",
            &"--speed",
            &"0",
            &"fixtures/sport-sample.bin",
        ]);
        let at = wait_for(&screen, 0, "END OF INPUT");
        let peak = status_kb(child.id(), "VmHWM");
        assert!(peak < 200_000, "{cols}x{rows}: {peak} kB");
        press(&term, b"q");
        assert_eq!(wait_exit(&mut child).code(), Some(0));
        wait_for(&screen, at, "\x1b[?1049l");
        assert_eq!(term.lflag(), before);
    }
}

/// L2 (issue 32): keys after the first 1023 bytes of a burst (a `q` among them) were ignored
/// until another key came. Every byte of a burst is read.
#[test]
fn a_key_after_a_long_burst_is_not_lost() {
    let _g = lock();
    let term = terminal(100, 24);
    let before = term.lflag();
    let screen = collect(&term.master);
    let mut child = term.run(&[
        &"sport",
        &"--top",
        &"--speed",
        &"0",
        &"fixtures/sport-sample.bin",
    ]);
    let at = wait_for(&screen, 0, "END OF INPUT");
    // 3000 bytes of arrow keys and letters the view ignores, then q, in one write.
    let mut burst = b"\x1b[A\x1b[Bx".repeat(400);
    burst.push(b'q');
    press(&term, &burst);
    assert_eq!(wait_exit(&mut child).code(), Some(0));
    wait_for(&screen, at, "\x1b[?1049l");
    assert_eq!(term.lflag(), before);
}

/// L3 (issue 32): an external SIGTSTP or SIGQUIT left the terminal raw. SIGTSTP now puts the
/// terminal back before stopping, SIGCONT takes the view up again; SIGQUIT puts it back before
/// the process ends as SIGQUIT ends it.
#[test]
fn stop_continue_and_quit_signals_give_the_terminal_back() {
    let _g = lock();
    let term = terminal(100, 24);
    let before = term.lflag();
    let screen = collect(&term.master);
    let mut child = term.run(&[
        &"sport",
        &"--top",
        &"--speed",
        &"0",
        &"fixtures/sport-sample.bin",
    ]);
    let at = wait_for(&screen, 0, "END OF INPUT");
    assert_ne!(term.lflag(), before);
    let pid = child.id();
    unsafe { libc::kill(pid as i32, libc::SIGTSTP) };
    common::until("busnoop stops on SIGTSTP", || state(pid) == 'T');
    assert_eq!(term.lflag(), before, "cooked while stopped");
    let at = wait_for(&screen, at, "\x1b[?1049l");
    unsafe { libc::kill(pid as i32, libc::SIGCONT) };
    let at = wait_for(&screen, at, "\x1b[?1049h");
    let at = wait_for(&screen, at, "END OF INPUT");
    common::until("raw again after SIGCONT", || term.lflag() != before);
    unsafe { libc::kill(pid as i32, libc::SIGQUIT) };
    let status = wait_exit(&mut child);
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(status.signal(), Some(libc::SIGQUIT), "{status:?}");
    wait_for(&screen, at, "\x1b[?1049l");
    assert_eq!(term.lflag(), before, "cooked after SIGQUIT");
}

/// M5 (issue 32): a terminal that goes away without a SIGHUP reaching busnoop (nohup, a dying
/// supervisor pty) made `--top` spin at 100 % CPU on `read(0) = 0` and stop decoding. End of
/// file on the terminal ends the view; rows keep going to `-o` and the replay ends as usual.
#[test]
fn a_terminal_that_goes_away_ends_the_view_and_the_table_goes_on() {
    terminal_goes_away(b"\x1b[?1049h");
}

/// A terminal that went away after the view's first drawing: busnoop ended with a panic (exit
/// 101, found under load in CI), as the drawing library's clean-up, failing to show the cursor
/// on the dead terminal, said so on stderr (that terminal too) with `eprintln!`.
#[test]
fn a_terminal_that_goes_away_after_the_first_drawing_ends_the_view_without_a_panic() {
    terminal_goes_away(b" busnoop");
}

/// Runs a paced `--top` replay with `-o`, waits for `seen` on the terminal, then hangs the
/// terminal up (closes its master side): busnoop ends with 0 and the table is whole.
fn terminal_goes_away(seen_first: &[u8]) {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let sample = std::fs::read("fixtures/sport-sample.bin").unwrap();
    // About 3 s of bus time, paced at --speed 1.
    let long = dir.path().join("long.bin");
    std::fs::write(&long, sample.repeat(9)).unwrap();
    let table = dir.path().join("t.tsv");
    let term = terminal(100, 24);
    let mut child = term.run(&[
        &"sport", &"--top", &"--speed", &"1", &"-f", &"tsv", &"-o", &table, &long,
    ]);
    let Term { master, slave } = term;
    drop(slave);
    // Wait for the view, then hang the terminal up by closing its master side.
    let mut reader = master.try_clone_native().unwrap();
    reader.set_timeout(Duration::from_millis(50)).unwrap();
    let mut seen = Vec::new();
    common::until("the view opens", || {
        let mut buf = [0u8; 4096];
        if let Ok(n) = reader.read(&mut buf) {
            seen.extend_from_slice(&buf[..n]);
        }
        seen.windows(seen_first.len()).any(|w| w == seen_first)
    });
    drop(reader);
    drop(master);
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(0), "{status:?}");
    let usage = unsafe {
        let mut r: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut r);
        r.ru_utime.tv_sec + r.ru_stime.tv_sec
    };
    assert!(usage < 5, "{usage} s of CPU");
    assert_eq!(std::fs::read_to_string(&table).unwrap(), full_table(&long));
}

/// L16 (issue 32): `q` during a replay dropped the last row from `-o` (591 of 592 of the EdgeTX
/// capture). `q` closes the view; the rest of the replay goes to `-o` at full speed.
#[test]
fn q_during_a_replay_closes_the_view_and_the_table_is_whole() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let log = std::path::PathBuf::from("fixtures/edgetx-MODELE24-2014-07-11-sport.log");
    let table = dir.path().join("t.tsv");
    let term = terminal(100, 24);
    let before = term.lflag();
    let screen = collect(&term.master);
    let mut child = term.run(&[&"sport", &"--top", &"-f", &"tsv", &"-o", &table, &log]);
    let at = wait_for(&screen, 0, "FLVSS");
    press(&term, b"q");
    assert_eq!(wait_exit(&mut child).code(), Some(0));
    wait_for(&screen, at, "\x1b[?1049l");
    assert_eq!(term.lflag(), before);
    let full = full_table(&log);
    assert_eq!(full.lines().count(), 593);
    assert!(
        std::fs::read_to_string(&table).unwrap() == full,
        "the whole table"
    );
}
