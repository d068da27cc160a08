//! Live capture on pseudo-terminal pairs: rows appear while the bus is still talking, an
//! unplugged adapter ends the run cleanly (or is waited for), recordings replay to the same rows,
//! and busy / missing / forbidden ports get their messages.

mod common;

use std::io::Write;
use std::process::Command;
use std::time::{Duration, Instant};

use busnoop::sport::wire;
use common::pty::{Bus, bin, bus, lock, next_line, spawn, stderr_of, wait_exit};

/// S.Port traffic for `n` poll slots, one slot's bytes per element: polls of three devices, two
/// of them answering with data.
fn slots(n: usize) -> Vec<Vec<u8>> {
    (0..n)
        .map(|i| {
            let mut b = Vec::new();
            let phys = (i % 3) as u8;
            if phys == 2 {
                wire::encode_poll(&mut b, wire::header_for(phys));
            } else {
                wire::encode_frame(
                    &mut b,
                    wire::header_for(phys),
                    0x10,
                    0x0100,
                    1000 + i as u32,
                );
            }
            b
        })
        .collect()
}

#[test]
fn rows_stream_live_and_unplug_ends_cleanly_and_the_recording_replays() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("live.pcap");
    let raw = dir.path().join("live.bin");
    let mut b = bus();
    let (mut child, rx) = spawn(
        &[
            "sport",
            "-f",
            "tsv",
            "--record",
            rec.to_str().unwrap(),
            "--stats",
        ],
        &b.path,
    );
    let (_, header) = next_line(&rx);
    assert!(header.starts_with("Counter\tMillis\tID"));

    // Write 40 slots at the bus's pace (12 ms per slot).
    let traffic = slots(40);
    let read_before = bytes_read(child.id());
    let mut first_row_at = None;
    let mut live = vec![header];
    let mut all = Vec::new();
    for s in &traffic {
        b.master.write_all(s).unwrap();
        b.master.flush().unwrap();
        all.extend_from_slice(s);
        std::thread::sleep(Duration::from_millis(12));
        if first_row_at.is_none()
            && let Ok((t, line)) = rx.try_recv()
        {
            assert!(line.starts_with("1\t"), "{line}");
            first_row_at = Some(t);
            live.push(line);
        }
    }
    let writer_done = Instant::now();
    let first_row_at = first_row_at.expect("no row appeared while the writer was writing");
    assert!(first_row_at < writer_done);

    // Unplug (close the bus side) once busnoop has read every byte.
    let pid = child.id();
    common::until("busnoop read the traffic", || {
        bytes_read(pid) >= read_before + all.len() as u64
    });
    drop(b.master);
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(7), "adapter disconnected");
    let err = stderr_of(&mut child);
    assert!(
        err.contains("adapter disconnected after 27 frames"),
        "stderr: {err}"
    );
    assert!(err.contains("S.Port statistics (40 rows)"), "{err}");
    while let Ok((_, l)) = rx.recv_timeout(common::PATIENCE) {
        live.push(l);
    }
    assert_eq!(live.len(), 41, "every slot is a row: {live:?}");
    // Millis are real arrival times: about 12 ms apart.
    let millis: Vec<u64> = live[1..]
        .iter()
        .map(|l| l.split('\t').nth(1).unwrap().parse().unwrap())
        .collect();
    assert!(millis.windows(2).all(|w| w[0] <= w[1]));
    assert!(millis[39] - millis[0] >= 39 * 10, "{millis:?}");

    // The recording replays to exactly the rows the live run printed.
    let replay = Command::new(bin())
        .args(["sport", "-f", "tsv"])
        .arg(&rec)
        .output()
        .unwrap();
    assert!(replay.status.success());
    let replayed: Vec<String> = String::from_utf8(replay.stdout)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(replayed, live);

    // A raw recording keeps exactly the bytes.
    let mut b = bus();
    let (mut child, rx) = spawn(&["sport", "--record", raw.to_str().unwrap()], &b.path);
    next_line(&rx);
    b.master.write_all(&all).unwrap();
    b.master.flush().unwrap();
    for _ in 0..40 {
        next_line(&rx);
    }
    drop(b.master);
    wait_exit(&mut child);
    assert_eq!(std::fs::read(&raw).unwrap(), all);
}

#[test]
fn sigterm_flushes_the_output_file() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("out.csv");
    let mut b = bus();
    let (mut child, rx) = spawn(
        &[
            "sport",
            "-o",
            csv.to_str().unwrap(),
            "--time",
            "abs",
            "--utc",
        ],
        &b.path,
    );
    for s in slots(10) {
        b.master.write_all(&s).unwrap();
    }
    b.master.flush().unwrap();
    let deadline = Instant::now() + common::PATIENCE;
    while std::fs::read_to_string(&csv)
        .unwrap_or_default()
        .lines()
        .count()
        < 11
    {
        assert!(Instant::now() < deadline);
        std::thread::sleep(Duration::from_millis(10));
    }
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    assert_eq!(wait_exit(&mut child).code(), Some(143));
    drop(rx);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 11);
    assert!(text.ends_with("\r\n"));
    // --time abs --utc: RFC 3339 wall-clock times with milliseconds, close to now.
    let mut r = csv::Reader::from_reader(text.as_bytes());
    assert_eq!(r.headers().unwrap().iter().next_back(), Some("Time"));
    let first = r.records().next().unwrap().unwrap();
    let t = first.iter().next_back().unwrap();
    assert_eq!(t.len(), "2026-01-02T03:04:05.678Z".len(), "{t}");
    let t: chrono::DateTime<chrono::Utc> = t.parse().unwrap();
    assert!((chrono::Utc::now() - t).num_seconds().abs() < 60, "{t}");
}

#[test]
fn reconnect_waits_for_the_adapter_and_marks_the_gap() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("adapter");
    let b = bus();
    std::os::unix::fs::symlink(&b.path, &link).unwrap();
    let (mut child, rx) = spawn(&["sport", "-f", "tsv", "--reconnect"], &link);
    next_line(&rx);
    let Bus {
        mut master, slave, ..
    } = b;
    master.write_all(&slots(3).concat()).unwrap();
    master.flush().unwrap();
    // Two data rows; the third slot is a poll that stays open until something follows it.
    for _ in 0..2 {
        next_line(&rx);
    }
    // Unplug: the device disappears. The open poll is closed, then the gap is marked.
    drop(master);
    drop(slave);
    let (_, poll) = next_line(&rx);
    assert!(
        poll.starts_with("3\t") && poll.contains("\tFAS-40S\t"),
        "{poll}"
    );
    let (_, down) = next_line(&rx);
    assert!(down.contains("\tLinkDown\t"), "{down}");
    assert!(
        down.contains("adapter disconnected after 2 frames"),
        "{down}"
    );
    // Plug in again: the stable name now points to a new device node.
    std::thread::sleep(Duration::from_millis(300));
    let mut b2 = bus();
    let tmp = dir.path().join("adapter.new");
    std::os::unix::fs::symlink(&b2.path, &tmp).unwrap();
    std::fs::rename(&tmp, &link).unwrap();
    let (_, up) = next_line(&rx);
    assert!(up.contains("\tLinkUp\t"), "{up}");
    assert!(up.contains("adapter back at"), "{up}");
    b2.master.write_all(&slots(3).concat()).unwrap();
    b2.master.flush().unwrap();
    for i in 0..2 {
        let (_, row) = next_line(&rx);
        assert!(row.starts_with(&format!("{}\t", 6 + i)), "{row}");
        assert!(row.contains("\tData\t"), "{row}");
    }
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert_eq!(wait_exit(&mut child).code(), Some(130));
    let err = stderr_of(&mut child);
    assert!(err.contains("waiting for it"), "{err}");
}

#[test]
fn a_busy_port_is_reported() {
    let _g = lock();
    let b = bus();
    // Another program holds the port (serialport opens exclusively, as most tools do).
    let _holder = serialport::new(b.path.to_string_lossy(), 57_600)
        .timeout(Duration::from_millis(50))
        .open_native()
        .unwrap();
    let out = Command::new(bin())
        .arg("sport")
        .arg(&b.path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(5));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(
        err,
        format!(
            "busnoop: {} is in use by another program (close it, or find it with `fuser {}`)\n",
            b.path.display(),
            b.path.display()
        )
    );
}

#[test]
fn a_missing_port_lists_the_ports_that_exist() {
    let _g = lock();
    let out = Command::new(bin())
        .args(["sport", "/dev/ttyBUSNOOP_MISSING"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.starts_with("busnoop: /dev/ttyBUSNOOP_MISSING: no such file or device (")
            && (err.contains("available ports: ") || err.contains("no serial ports found")),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1);
}

#[test]
fn a_forbidden_port_gets_the_group_hint() {
    use std::os::unix::fs::PermissionsExt;
    let _g = lock();
    let b = bus();
    // Owner-only (root's pty when the tests run as root; busnoop then runs unprivileged), or no
    // access at all for the owner.
    let root = unsafe { libc::geteuid() } == 0;
    let mode = if root { 0o600 } else { 0o000 };
    std::fs::set_permissions(&b.path, std::fs::Permissions::from_mode(mode)).unwrap();
    let (_keep, mut cmd) = common::unprivileged_busnoop();
    let out = cmd.arg("sport").arg(&b.path).output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.starts_with(&format!(
            "busnoop: {}: permission denied (",
            b.path.display()
        )),
        "{err}"
    );
    assert!(err.contains("group"), "{err}");
    assert_eq!(err.lines().count(), 1);
}

#[test]
fn a_silent_line_with_noise_gets_the_wiring_hint() {
    let _g = lock();
    let mut b = bus();
    let (mut child, rx) = spawn(&["sport", "-f", "tsv"], &b.path);
    next_line(&rx);
    // Its stderr, line by line as it comes.
    let err_lines = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    let reader = {
        let stderr = child.stderr.take().unwrap();
        let lines = err_lines.clone();
        std::thread::spawn(move || {
            use std::io::BufRead;
            for l in std::io::BufReader::new(stderr)
                .lines()
                .map_while(Result::ok)
            {
                let mut s = lines.lock().unwrap();
                s.push_str(&l);
                s.push('\n');
            }
        })
    };
    // What a non-inverted S.Port line looks like: bytes, but never a frame, until the hint.
    let start = Instant::now();
    while !err_lines.lock().unwrap().contains("no valid S.Port frame") {
        assert!(start.elapsed() < common::PATIENCE, "no wiring hint");
        b.master
            .write_all(&[0xA0, 0xA0, 0xE6, 0x57, 0x7F, 0x81])
            .unwrap();
        b.master.flush().unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(start.elapsed() >= Duration::from_secs(3), "not before 3 s");
    drop(b.master);
    wait_exit(&mut child);
    reader.join().unwrap();
    let err = err_lines.lock().unwrap().clone();
    let hints: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("no valid S.Port frame"))
        .collect();
    assert_eq!(hints.len(), 1, "{err}");
    assert!(hints[0].contains("not inverted"), "{err}");
    assert!(hints[0].contains("57600"), "{err}");
}

/// The flags of the descriptor `pid` holds on `dev`, from /proc.
fn open_flags(pid: u32, dev: &std::path::Path) -> Option<i32> {
    for e in std::fs::read_dir(format!("/proc/{pid}/fd")).ok()?.flatten() {
        if std::fs::read_link(e.path()).ok().as_deref() == Some(dev) {
            let info = std::fs::read_to_string(format!(
                "/proc/{pid}/fdinfo/{}",
                e.file_name().to_string_lossy()
            ))
            .ok()?;
            let flags = info.lines().find_map(|l| l.strip_prefix("flags:"))?;
            return i32::from_str_radix(flags.trim(), 8).ok();
        }
    }
    None
}

/// The slave's termios c_cflag, read through the master.
fn cflag(b: &Bus) -> libc::tcflag_t {
    use std::os::fd::AsRawFd;
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    assert_eq!(unsafe { libc::tcgetattr(b.master.as_raw_fd(), &mut t) }, 0);
    t.c_cflag
}

#[test]
fn the_device_is_opened_read_only_and_nothing_reaches_the_bus() {
    let _g = lock();
    let mut b = bus();
    let hupcl_before = cflag(&b) & libc::HUPCL;
    let (mut child, rx) = spawn(&["sport", "-f", "tsv"], &b.path);
    next_line(&rx);
    // busnoop cannot write: its descriptor on the device is read-only.
    let flags = open_flags(child.id(), &b.path).expect("busnoop holds the device open");
    assert_eq!(flags & libc::O_ACCMODE, libc::O_RDONLY, "flags {flags:o}");
    // Traffic decodes, and not one byte comes back on the bus side (no echo, no write).
    b.master.write_all(&slots(6).concat()).unwrap();
    b.master.flush().unwrap();
    for _ in 0..4 {
        next_line(&rx);
    }
    serialport::SerialPort::set_timeout(&mut b.master, Duration::from_millis(300)).unwrap();
    let mut buf = [0u8; 64];
    match std::io::Read::read(&mut b.master, &mut buf) {
        Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
        other => panic!("the bus side received {other:?}: {:?}", &buf[..8]),
    }
    // HUPCL is left as it was: busnoop changes no setting that outlives it.
    assert_eq!(cflag(&b) & libc::HUPCL, hupcl_before);
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert_eq!(wait_exit(&mut child).code(), Some(130));
    // The same with --dtr-rts keep.
    let (mut child, rx) = spawn(&["sport", "-f", "tsv", "--dtr-rts", "keep"], &b.path);
    next_line(&rx);
    let flags = open_flags(child.id(), &b.path).expect("busnoop holds the device open");
    assert_eq!(flags & libc::O_ACCMODE, libc::O_RDONLY, "flags {flags:o}");
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert_eq!(wait_exit(&mut child).code(), Some(130));
}

/// Whether process `pid` has `path` open (its /proc/PID/fd links).
fn has_open(pid: u32, path: &std::path::Path) -> bool {
    std::fs::read_dir(format!("/proc/{pid}/fd"))
        .map(|d| {
            d.flatten()
                .any(|e| std::fs::read_link(e.path()).is_ok_and(|t| t == path))
        })
        .unwrap_or(false)
}

/// What process `pid` holds open (the targets of /proc/PID/fd).
fn open_files(pid: u32) -> Vec<std::path::PathBuf> {
    std::fs::read_dir(format!("/proc/{pid}/fd"))
        .map(|d| {
            d.flatten()
                .filter_map(|e| std::fs::read_link(e.path()).ok())
                .collect()
        })
        .unwrap_or_default()
}

/// L13 (issue 32): a Wireshark capture through the extcap with `--reconnect` wrote the unplug
/// notices on stderr, which Wireshark shows as an error when the capture stops. The extcap's
/// stderr stays empty; the gap is in the capture (the export) and its rows.
#[test]
fn extcap_with_reconnect_keeps_stderr_empty_through_an_unplug() {
    let _g = lock();
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("adapter");
    let fifo = dir.path().join("wireshark.fifo");
    common::mkfifo(&fifo);
    let b = bus();
    std::os::unix::fs::symlink(&b.path, &link).unwrap();
    let mut child = Command::new(bin())
        .args([
            "extcap",
            "--capture",
            "--extcap-interface",
            "busnoop-sport",
            "--reconnect",
        ])
        .arg("--fifo")
        .arg(&fifo)
        .arg("--port")
        .arg(&link)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap_or_default())
    };
    let pid = child.id();
    let first = b.path.clone();
    common::until("the port is open", || has_open(pid, &first));
    let Bus {
        mut master, slave, ..
    } = b;
    master.write_all(&slots(3).concat()).unwrap();
    master.flush().unwrap();
    // Unplug, and wait until busnoop let go of the device.
    drop(master);
    drop(slave);
    common::until("the unplugged port is closed", || !has_open(pid, &first));
    // Plug in again under the same stable name.
    let mut b2 = bus();
    let tmp = dir.path().join("adapter.new");
    std::os::unix::fs::symlink(&b2.path, &tmp).unwrap();
    std::fs::rename(&tmp, &link).unwrap();
    let second = b2.path.clone();
    // Failed once in a CI loop under load (run 31) without saying why: on a timeout, what
    // busnoop holds open and what it said.
    let deadline = Instant::now() + common::PATIENCE;
    while !has_open(pid, &second) {
        if Instant::now() >= deadline {
            let held = open_files(pid);
            let exited = child.try_wait().unwrap();
            unsafe { libc::kill(pid as i32, libc::SIGTERM) };
            let _ = wait_exit(&mut child);
            panic!(
                "the port is not open again: busnoop (exited: {exited:?}) holds {held:?} (first \
                 {}, second {}); stderr: {}",
                first.display(),
                second.display(),
                stderr_of(&mut child)
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    b2.master.write_all(&slots(3).concat()).unwrap();
    b2.master.flush().unwrap();
    unsafe { libc::kill(pid as i32, libc::SIGTERM) };
    let status = wait_exit(&mut child);
    assert_eq!(
        status.code(),
        Some(0),
        "Wireshark's SIGTERM is the normal end"
    );
    let err = stderr_of(&mut child);
    assert_eq!(err, "", "nothing for Wireshark to show as an error");
    let capture = reader.join().unwrap();
    assert!(capture.len() > 100, "{} bytes captured", capture.len());
}

/// Bytes process `pid` has read so far (`rchar` of /proc/PID/io).
fn bytes_read(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/io"))
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix("rchar: "))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(0)
}

/// Starts `busnoop detect DEVICE` at two rates and waits until it has read S.Port traffic
/// at the first one.
fn detect_hearing_sport(b: &mut Bus) -> std::process::Child {
    use std::io::BufRead;
    let mut cmd = Command::new(bin());
    cmd.args(["detect", "--listen-ms", "4000", "--baud", "57600,115200"])
        .arg(&b.path)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    // SIGHUP as a terminal would start it, also when the tests run under `nohup` (which
    // passes it on ignored, and busnoop then keeps ignoring it).
    // SAFETY: only signal() in the child before exec.
    unsafe {
        use std::os::unix::process::CommandExt;
        cmd.pre_exec(|| {
            libc::signal(libc::SIGHUP, libc::SIG_DFL);
            Ok(())
        });
    }
    let mut child = cmd.spawn().unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    assert!(line.contains("listening to"), "{line}");
    child.stderr = Some(err.into_inner());
    let before = bytes_read(child.id());
    let traffic = slots(30).concat();
    b.master.write_all(&traffic).unwrap();
    b.master.flush().unwrap();
    let pid = child.id();
    common::until("detect read the traffic", || {
        bytes_read(pid) >= before + traffic.len() as u64
    });
    child
}

/// L14 (issue 32): `detect` on a serial port lost all its evidence on Ctrl-C, SIGTERM, SIGHUP
/// or an unplug, and suggested `--reconnect`, which detect does not have. What was heard is
/// judged and shown, and the message says what ended the listening.
#[test]
fn detect_on_a_port_keeps_its_evidence_when_stopped_or_unplugged() {
    let _g = lock();
    for (sig, code) in [
        (libc::SIGINT, 130),
        (libc::SIGTERM, 143),
        (libc::SIGHUP, 129),
    ] {
        let mut b = bus();
        let mut child = detect_hearing_sport(&mut b);
        unsafe { libc::kill(child.id() as i32, sig) };
        let status = wait_exit(&mut child);
        let out = {
            let mut s = String::new();
            std::io::Read::read_to_string(child.stdout.as_mut().unwrap(), &mut s).unwrap();
            s
        };
        let err = stderr_of(&mut child);
        assert_eq!(status.code(), Some(code), "signal {sig}: {err}");
        assert!(
            out.contains("57600 baud") && out.contains("verdict: S.Port"),
            "{out}"
        );
        assert!(
            err.contains("interrupted") && err.contains("the verdict is on what was heard"),
            "{err}"
        );
    }
    // Unplugged while listening.
    let mut b = bus();
    let mut child = detect_hearing_sport(&mut b);
    let Bus { master, slave, .. } = b;
    drop(master);
    drop(slave);
    let status = wait_exit(&mut child);
    let mut out = String::new();
    std::io::Read::read_to_string(child.stdout.as_mut().unwrap(), &mut out).unwrap();
    let err = stderr_of(&mut child);
    assert_eq!(status.code(), Some(7), "{err}");
    assert!(out.contains("verdict: S.Port"), "out: {out}\nerr: {err}");
    assert!(
        err.contains("went away") && !err.contains("--reconnect"),
        "{err}"
    );
}
