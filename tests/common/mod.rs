//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

pub mod pty;

/// How long a test waits for an event (a line, a file, an exit) before it fails: far more than
/// any of them takes, so that a loaded machine (two busy loops on two cores, parallel test
/// binaries) never fails a test that would pass alone.
pub const PATIENCE: std::time::Duration = std::time::Duration::from_secs(30);

use busnoop::protocol::Decoder;
use busnoop::row::{Collected, OwnedRow};

/// The busnoop binary of this build, without the caller's `NO_COLOR` and `RUST_LOG`.
pub fn busnoop() -> std::process::Command {
    let mut c = std::process::Command::new(assert_cmd::cargo::cargo_bin("busnoop"));
    c.env_remove("NO_COLOR").env_remove("RUST_LOG");
    c
}

/// Output bytes as text (lossy).
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Standard output of a run that must have succeeded (its stderr in the message otherwise).
pub fn ok(out: &std::process::Output) -> String {
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    text(&out.stdout)
}

/// Deterministic pseudo-random bytes (xorshift).
pub fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect()
}

/// Path of a file in `fixtures/`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// Reads a tab-separated fixture with a header line into maps of column name → value.
pub fn read_tsv(name: &str) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(fixture(name)).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut fields: Vec<&str> = l.split('\t').collect();
            fields.resize(header.len(), "");
            header
                .iter()
                .zip(fields)
                .map(|(h, f)| (h.to_string(), f.to_string()))
                .collect()
        })
        .collect()
}

/// Feeds `(bytes, time)` segments through a decoder and returns every row.
pub fn decode<'a>(
    decoder: &mut dyn Decoder,
    segments: impl IntoIterator<Item = (&'a [u8], Option<u64>)>,
) -> Vec<OwnedRow> {
    let mut out = Collected::default();
    for (bytes, time) in segments {
        decoder.push(bytes, time, &mut out).unwrap();
    }
    decoder.finish(&mut out).unwrap();
    out.rows
}

/// Decodes untimed bytes in one piece with a fresh S.Port decoder.
pub fn sport_rows(bytes: &[u8]) -> Vec<OwnedRow> {
    let mut d = busnoop::sport::SportDecoder::new();
    decode(&mut d, [(bytes, None)])
}

/// A command running busnoop as an unprivileged user (uid/gid 65534) when the tests run as root,
/// since root may open anything; otherwise the normal binary. Root runs a copy of the binary in
/// a world-readable temporary directory, so the checkout's own permissions do not matter.
/// Keep the returned directory alive while the command runs.
pub fn unprivileged_busnoop() -> (Option<tempfile::TempDir>, std::process::Command) {
    use std::os::unix::fs::PermissionsExt;
    let bin = assert_cmd::cargo::cargo_bin("busnoop");
    if unsafe { libc::geteuid() } != 0 {
        return (None, std::process::Command::new(bin));
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let copy = dir.path().join("busnoop");
    std::fs::copy(&bin, &copy).unwrap();
    std::fs::set_permissions(&copy, std::fs::Permissions::from_mode(0o755)).unwrap();
    let mut cmd = std::process::Command::new(&copy);
    as_nobody(&mut cmd);
    (Some(dir), cmd)
}

/// Makes `cmd` run as user and group 65534 (nobody), without supplementary groups.
pub fn as_nobody(cmd: &mut std::process::Command) {
    use std::os::unix::process::CommandExt;
    unsafe {
        cmd.pre_exec(|| {
            if libc::setgroups(0, std::ptr::null()) != 0
                || libc::setgid(65534) != 0
                || libc::setuid(65534) != 0
            {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// Makes a FIFO at `path`.
pub fn mkfifo(path: &std::path::Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

/// Writes `dir/big.bin`: `n` valid S.Port frames of `app_id` (physical IDs 0 to 27 in turn,
/// the values counting up), enough rows to fill a pipe or a file size limit.
pub fn big_sport(dir: &std::path::Path, n: u32, app_id: u16) -> PathBuf {
    use busnoop::sport::wire;
    let mut bytes = Vec::new();
    for i in 0..n {
        wire::encode_frame(
            &mut bytes,
            wire::header_for((i % 28) as u8),
            0x10,
            app_id,
            i,
        );
    }
    let p = dir.join("big.bin");
    std::fs::write(&p, bytes).unwrap();
    p
}

/// The run did not panic.
pub fn no_panic(out: &std::process::Output) {
    let err = text(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
}

/// A copy of the S.Port sample, repeated so that it is more than one read chunk, in `dir` under
/// `name` (no capture extension: the extension guard of `-o` must not be what saves it).
pub fn capture(dir: &std::path::Path, name: &str) -> (PathBuf, Vec<u8>) {
    let sample = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let bytes = sample.repeat(400);
    let p = dir.join(name);
    std::fs::write(&p, &bytes).unwrap();
    (p, bytes)
}

/// Runs `cmd` (standard input from `stdin`, written and closed by a thread; standard output to
/// `stdout`) and returns its output; kills it and fails when it has not exited within
/// [`PATIENCE`] (a run that writes into its own input pipe never ends).
pub fn output_within(
    cmd: &mut std::process::Command,
    stdin: Option<Vec<u8>>,
    stdout: std::process::Stdio,
) -> std::process::Output {
    use std::io::Write;
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let mut child = cmd
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(stdout)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    if let Some(bytes) = stdin {
        let mut pipe = child.stdin.take().unwrap();
        // busnoop may refuse before reading anything: a broken pipe is fine.
        std::thread::spawn(move || pipe.write_all(&bytes));
    }
    let deadline = Instant::now() + PATIENCE;
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("busnoop did not exit within {PATIENCE:?}: {cmd:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}

/// A pcapng file of one interface of `link_type` whose time stamps count in units of
/// 10^-`tsresol` s (`if_tsresol`), holding `packets` as (time stamp in those units, bytes).
pub fn pcapng(link_type: u16, tsresol: u8, packets: &[(u64, &[u8])]) -> Vec<u8> {
    fn block(out: &mut Vec<u8>, kind: u32, body: &[u8]) {
        let pad = (4 - body.len() % 4) % 4;
        let len = (12 + body.len() + pad) as u32;
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(body);
        out.extend_from_slice(&[0; 3][..pad]);
        out.extend_from_slice(&len.to_le_bytes());
    }
    let mut out = Vec::new();
    let mut shb = Vec::new();
    shb.extend_from_slice(&0x1A2B_3C4Du32.to_le_bytes());
    shb.extend_from_slice(&[1, 0, 0, 0]);
    shb.extend_from_slice(&(-1i64).to_le_bytes());
    block(&mut out, 0x0A0D_0D0A, &shb);
    let mut idb = Vec::new();
    idb.extend_from_slice(&link_type.to_le_bytes());
    idb.extend_from_slice(&[0, 0, 0, 0, 0, 0]);
    // if_tsresol, then the end of options.
    idb.extend_from_slice(&[9, 0, 1, 0, tsresol, 0, 0, 0, 0, 0, 0, 0]);
    block(&mut out, 1, &idb);
    for &(ts, data) in packets {
        let mut epb = Vec::new();
        epb.extend_from_slice(&0u32.to_le_bytes());
        epb.extend_from_slice(&((ts >> 32) as u32).to_le_bytes());
        epb.extend_from_slice(&(ts as u32).to_le_bytes());
        epb.extend_from_slice(&(data.len() as u32).to_le_bytes());
        epb.extend_from_slice(&(data.len() as u32).to_le_bytes());
        epb.extend_from_slice(data);
        block(&mut out, 6, &epb);
    }
    out
}

/// The packets of a classic pcap file (little-endian, microsecond magic) as (µs since 1970,
/// bytes), and its link type.
pub fn pcap_packets(file: &[u8]) -> (u32, Vec<(u64, Vec<u8>)>) {
    let u32_at = |i: usize| u32::from_le_bytes(file[i..i + 4].try_into().unwrap());
    assert_eq!(u32_at(0), 0xA1B2_C3D4, "a little-endian microsecond pcap");
    let mut packets = Vec::new();
    let mut at = 24;
    while at + 16 <= file.len() {
        let ts = u32_at(at) as u64 * 1_000_000 + u32_at(at + 4) as u64;
        let len = u32_at(at + 8) as usize;
        packets.push((ts, file[at + 16..at + 16 + len].to_vec()));
        at += 16 + len;
    }
    (u32_at(20), packets)
}

/// Makes the disk "full" for `cmd` after `bytes` bytes of any file it writes (a file size
/// limit, with SIGXFSZ ignored so that the write fails with EFBIG instead of killing it).
pub fn limit_file_size(cmd: &mut std::process::Command, bytes: libc::rlim_t) {
    use std::os::unix::process::CommandExt;
    // SAFETY: only signal() and setrlimit() in the child before exec.
    unsafe {
        cmd.pre_exec(move || {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let lim = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// Waits until the child has its signal handlers in place (so a signal is not fatal by default).
pub fn wait_for_handlers(child: &std::process::Child) {
    let deadline = std::time::Instant::now() + PATIENCE;
    let status = format!("/proc/{}/status", child.id());
    loop {
        let text = std::fs::read_to_string(&status).unwrap_or_default();
        let caught = text
            .lines()
            .find_map(|l| l.strip_prefix("SigCgt:"))
            .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
            .unwrap_or(0);
        let mask = (1 << (libc::SIGINT - 1)) | (1 << (libc::SIGTERM - 1));
        if caught & mask == mask {
            return;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "busnoop installed no handlers"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// Unread bytes in the pipe or FIFO whose end `fd` is (`FIONREAD`; either end).
pub fn pipe_unread(fd: &impl std::os::fd::AsRawFd) -> i32 {
    let mut n: libc::c_int = 0;
    // SAFETY: FIONREAD into our own int.
    unsafe { libc::ioctl(fd.as_raw_fd(), libc::FIONREAD, &mut n) };
    n
}

/// Whether a thread of process `pid` waits in a kernel function whose name holds `what`
/// (`/proc/PID/task/*/wchan`: `pipe_write`, `pipe_read`, `poll`).
pub fn waits_in(pid: u32, what: &str) -> bool {
    std::fs::read_dir(format!("/proc/{pid}/task"))
        .map(|d| {
            d.flatten().any(|t| {
                std::fs::read_to_string(t.path().join("wchan")).is_ok_and(|w| w.contains(what))
            })
        })
        .unwrap_or(false)
}

/// Whether a thread of process `pid` waits for input (blocked in a pipe read or in poll):
/// with its input pipe empty, it has taken in everything written so far.
pub fn waits_for_input(pid: u32) -> bool {
    waits_in(pid, "pipe_read") || waits_in(pid, "poll")
}

/// Waits up to [`PATIENCE`] for `what` to hold.
pub fn until(what: &str, mut f: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + PATIENCE;
    while !f() {
        assert!(std::time::Instant::now() < deadline, "{what}");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}
