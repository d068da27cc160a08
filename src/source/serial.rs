//! Live capture from a serial device (USB-serial adapter, on-board UART, pty).
//!
//! The reader thread stamps every chunk with a monotonic time the moment `read` returns and
//! hands it to the decoder. An unplugged adapter (`BrokenPipe`, EIO, `Ok(0)`, `NotFound`, which
//! all come back at once) ends the capture, or with `--reconnect` starts a wait for the same
//! adapter, found again by its stable name or USB serial number.

use std::path::{Path, PathBuf};
use std::sync::mpsc::SyncSender;
use std::time::{Duration, Instant};

use serialport::{DataBits, FlowControl, Parity, SerialPort, SerialPortType, StopBits};

use super::{Batch, Chunk, ChunkReader, Message};
use crate::exit::Failure;
use crate::protocol::{Line, Parity as LineParity};
use crate::time::Anchor;

/// Read timeout: how long a read waits for data before the reader looks around (the crate's
/// default of 0 would make every read return at once).
const READ_TIMEOUT: Duration = Duration::from_millis(50);
/// Bytes per read.
const READ_BUF: usize = 4096;
/// Waiting for an adapter to come back: first and longest pause between attempts.
const RECONNECT_FIRST: Duration = Duration::from_millis(200);
const RECONNECT_MAX: Duration = Duration::from_millis(1000);

/// How to open a serial device: the protocol's line settings (with `--baud`) and what to do
/// with the modem lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SerialConfig {
    pub line: Line,
    pub lines: ModemLines,
}

/// What busnoop does with a serial device's DTR and RTS outputs (`--dtr-rts`). Opening a tty
/// raises both (Linux does it inside open(), before any program can act); on an RS-485 adapter
/// whose driver is enabled by RTS that could drive the bus.
/// (The command line's names for it are in `cli/choices.rs`.)
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ModemLines {
    /// Drop DTR and RTS right after opening and keep them low (they then stay low on close).
    #[default]
    Low,
    /// Leave them as the driver sets them (Linux: raised on open, dropped on close when the
    /// port's HUPCL is set), for adapters powered or enabled by DTR/RTS.
    Keep,
}

/// The serialport crate's names for a line's character format.
fn char_format(line: &Line) -> (DataBits, Parity, StopBits) {
    let data_bits = match line.data_bits {
        5 => DataBits::Five,
        6 => DataBits::Six,
        7 => DataBits::Seven,
        _ => DataBits::Eight,
    };
    let parity = match line.parity {
        LineParity::None => Parity::None,
        LineParity::Odd => Parity::Odd,
        LineParity::Even => Parity::Even,
    };
    let stop_bits = if line.stop_bits == 2 {
        StopBits::Two
    } else {
        StopBits::One
    };
    (data_bits, parity, stop_bits)
}

/// True when `arg` names a serial device rather than a capture file: an existing character
/// device, or a path that looks like one (`/dev/…`, `COMn`) even if it does not exist (so that a
/// missing adapter gets the list of ports instead of "no such file").
pub fn is_device_path(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if let Ok(m) = std::fs::metadata(path) {
            return m.file_type().is_char_device();
        }
    }
    let s = path.to_string_lossy();
    s.starts_with("/dev/")
        || s.to_ascii_uppercase()
            .strip_prefix("COM")
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// One line per available serial port (`busnoop ports` and the "no such device" hint).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PortInfo {
    pub name: String,
    pub kind: &'static str,
    pub vid_pid: Option<(u16, u16)>,
    pub serial_number: Option<String>,
    pub manufacturer: Option<String>,
    pub product: Option<String>,
    /// `/dev/serial/by-id/…` link pointing to this port, when there is one.
    pub by_id: Option<PathBuf>,
}

/// The serial ports the system reports (none rather than an error when it cannot tell).
pub fn list_ports() -> Vec<PortInfo> {
    // The crate's sysfs scan panics when /sys/class/tty does not exist (some containers).
    #[cfg(target_os = "linux")]
    if !Path::new("/sys/class/tty").is_dir() {
        return Vec::new();
    }
    let mut ports: Vec<PortInfo> = serialport::available_ports()
        .unwrap_or_default()
        .into_iter()
        .map(|p| {
            let (kind, vid_pid, serial_number, manufacturer, product) = match p.port_type {
                SerialPortType::UsbPort(u) => (
                    "usb",
                    Some((u.vid, u.pid)),
                    u.serial_number,
                    u.manufacturer,
                    u.product,
                ),
                SerialPortType::PciPort => ("pci", None, None, None, None),
                SerialPortType::BluetoothPort => ("bluetooth", None, None, None, None),
                SerialPortType::Unknown => ("other", None, None, None, None),
            };
            let by_id = by_id_link(Path::new(&p.port_name));
            PortInfo {
                name: p.port_name,
                kind,
                vid_pid,
                serial_number,
                manufacturer,
                product,
                by_id,
            }
        })
        .collect();
    ports.sort_by(|a, b| a.name.cmp(&b.name));
    ports
}

/// The `/dev/serial/by-id/…` symlink that points to `dev`, if any.
pub fn by_id_link(dev: &Path) -> Option<PathBuf> {
    let target = dev.canonicalize().ok()?;
    std::fs::read_dir("/dev/serial/by-id")
        .ok()?
        .flatten()
        .map(|e| e.path())
        .find(|link| link.canonicalize().ok().as_deref() == Some(target.as_path()))
}

/// "available ports: /dev/ttyUSB0 (FT232R USB UART), …" or "no serial ports found".
pub fn ports_hint() -> String {
    let ports = list_ports();
    if ports.is_empty() {
        return "no serial ports found; is the adapter plugged in?".into();
    }
    let names: Vec<String> = ports
        .iter()
        .map(|p| match &p.product {
            Some(prod) => format!("{} ({prod})", p.name),
            None => p.name.clone(),
        })
        .collect();
    format!("available ports: {}", names.join(", "))
}

/// The group owning `path` (for the permission hint).
#[cfg(unix)]
fn group_of(path: &Path) -> Option<String> {
    use std::os::unix::fs::MetadataExt;
    let gid = std::fs::metadata(path).ok()?.gid();
    let group = nix::unistd::Group::from_gid(nix::unistd::Gid::from_raw(gid)).ok()??;
    Some(group.name)
}

#[cfg(not(unix))]
fn group_of(_path: &Path) -> Option<String> {
    None
}

/// The hint for "permission denied" on a serial device.
pub fn permission_hint(path: &Path) -> String {
    match group_of(path).as_deref() {
        Some(g @ ("dialout" | "uucp" | "tty" | "plugdev")) => format!(
            "the device belongs to group '{g}': add yourself with `sudo usermod -aG {g} $USER`, then log out and in again"
        ),
        Some(g) => format!(
            "the device belongs to group '{g}'; serial adapters are usually in group 'dialout' \
             (Debian, Ubuntu, Fedora) or 'uucp' (Arch, macOS): add yourself to it and log in again"
        ),
        None => {
            "add yourself to the 'dialout' group (or 'uucp' on Arch and macOS) and log in again"
                .into()
        }
    }
}

/// Maps an error from opening a serial device to a user-facing failure.
pub fn open_failure(path: &Path, e: &serialport::Error) -> Failure {
    use std::io::ErrorKind as Io;
    match e.kind {
        serialport::ErrorKind::NoDevice => Failure::Busy(path.to_owned()),
        serialport::ErrorKind::Io(Io::NotFound) => Failure::NotFound {
            path: path.to_owned(),
            hint: Some(ports_hint()),
        },
        serialport::ErrorKind::Io(Io::PermissionDenied) => Failure::Permission {
            path: path.to_owned(),
            hint: permission_hint(path),
        },
        _ => Failure::Device {
            path: path.to_owned(),
            message: format!("cannot open the serial port: {}", e.description),
        },
    }
}

/// True when opening failed because the device is not a terminal at all (a plain character
/// device such as /dev/null or /dev/zero): such a source is read as a file.
pub fn is_not_a_tty(e: &serialport::Error) -> bool {
    // ENOTTY: glibc calls it "Inappropriate ioctl for device", nix "Not a typewriter".
    matches!(e.kind, serialport::ErrorKind::Unknown)
        && (e.description.contains("Inappropriate ioctl") || e.description.contains("typewriter"))
}

/// Opens and configures `path` for listening only: read-only (busnoop cannot write to the
/// bus), exclusively (TIOCEXCL and flock, like the serialport crate), without waiting for a
/// carrier (O_NONBLOCK open, CLOCAL), with DTR/RTS dropped at once unless `cfg.lines` is
/// `Keep`. No other setting is changed that outlives busnoop (HUPCL stays as it was).
#[cfg(unix)]
pub fn open(path: &Path, cfg: &SerialConfig) -> Result<Box<dyn SerialPort>, serialport::Error> {
    use nix::errno::Errno;
    use nix::fcntl::OFlag;
    use nix::sys::termios::{self, ControlFlags, InputFlags, SetArg};
    use serialport::{Error, ErrorKind};
    use std::os::fd::{AsRawFd, FromRawFd, IntoRawFd};
    let os = |what: &str, e: Errno| {
        let kind = match e {
            Errno::EBUSY | Errno::EWOULDBLOCK => ErrorKind::NoDevice,
            Errno::ENOENT => ErrorKind::Io(std::io::ErrorKind::NotFound),
            Errno::EACCES | Errno::EPERM => ErrorKind::Io(std::io::ErrorKind::PermissionDenied),
            // ENOTTY and the like: see is_not_a_tty.
            _ => ErrorKind::Unknown,
        };
        Error::new(kind, format!("{what}: {}", std::io::Error::from(e)))
    };
    let flags = OFlag::O_RDONLY | OFlag::O_NOCTTY | OFlag::O_NONBLOCK | OFlag::O_CLOEXEC;
    // Closed on every early return.
    let fd =
        nix::fcntl::open(path, flags, nix::sys::stat::Mode::empty()).map_err(|e| os("open", e))?;
    // A device that refuses the terminal ioctl is no terminal: /dev/null and /dev/zero answer
    // ENOTTY, /dev/urandom EINVAL; both are read as files (`is_not_a_tty`).
    let mut t = termios::tcgetattr(&fd).map_err(|e| match e {
        Errno::EINVAL => os("tcgetattr", Errno::ENOTTY),
        e => os("tcgetattr", e),
    })?;
    // Exclusive, so that a second capture program gets "in use" (before touching any line of
    // a port that someone else holds).
    // SAFETY: TIOCEXCL takes no argument and `fd` is an open descriptor we own.
    if unsafe { libc::ioctl(fd.as_raw_fd(), libc::TIOCEXCL) } != 0 {
        return Err(os("TIOCEXCL", Errno::last()));
    }
    // SAFETY: flock touches no memory; `fd` is open and stays open (owned) until the port
    // closes it, which releases the lock.
    if unsafe { libc::flock(fd.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
        return Err(os("the port is locked by another program", Errno::last()));
    }
    if cfg.lines == ModemLines::Low {
        lower_dtr_rts(fd.as_raw_fd());
    }
    // Raw 8-bit input, no echo, no flow control, modem status ignored (CLOCAL: no carrier wait).
    termios::cfmakeraw(&mut t);
    t.control_flags |= ControlFlags::CREAD | ControlFlags::CLOCAL;
    t.control_flags.remove(ControlFlags::CRTSCTS);
    t.input_flags
        .remove(InputFlags::IXON | InputFlags::IXOFF | InputFlags::IXANY);
    termios::tcsetattr(&fd, SetArg::TCSANOW, &t).map_err(|e| os("tcsetattr", e))?;
    crate::files::set_blocking(&fd).map_err(|e| {
        os(
            "fcntl",
            Errno::from_raw(e.raw_os_error().unwrap_or(libc::EIO)),
        )
    })?;
    // The crate sets speed (any rate, termios2 on Linux) and character format on our descriptor.
    // SAFETY: the descriptor is an open tty that we own and give up here; the port owns and
    // closes it from now on.
    let mut port = unsafe { serialport::TTYPort::from_raw_fd(fd.into_raw_fd()) };
    let (data_bits, parity, stop_bits) = char_format(&cfg.line);
    port.set_baud_rate(cfg.line.baud)?;
    port.set_data_bits(data_bits)?;
    port.set_parity(parity)?;
    port.set_stop_bits(stop_bits)?;
    port.set_flow_control(FlowControl::None)?;
    port.set_timeout(READ_TIMEOUT)?;
    Ok(Box::new(port))
}

/// Drops DTR and RTS. Devices without modem lines (ptys, some USB bridges) refuse; that is fine.
#[cfg(unix)]
fn lower_dtr_rts(fd: i32) {
    let bits: libc::c_int = libc::TIOCM_DTR | libc::TIOCM_RTS;
    // SAFETY: TIOCMBIC reads one c_int through the pointer, which points at `bits` for the
    // whole call; `fd` is an open descriptor of the caller's.
    if unsafe { libc::ioctl(fd, libc::TIOCMBIC, &bits) } != 0 {
        tracing::debug!(
            "cannot drop DTR/RTS: {} (the device has no modem lines)",
            std::io::Error::last_os_error()
        );
    }
}

/// Opens and configures `path`.
#[cfg(not(unix))]
pub fn open(path: &Path, cfg: &SerialConfig) -> Result<Box<dyn SerialPort>, serialport::Error> {
    let (data_bits, parity, stop_bits) = char_format(&cfg.line);
    let builder = serialport::new(path.to_string_lossy(), cfg.line.baud)
        .data_bits(data_bits)
        .parity(parity)
        .stop_bits(stop_bits)
        .flow_control(FlowControl::None)
        .timeout(READ_TIMEOUT);
    match cfg.lines {
        ModemLines::Low => builder.dtr_on_open(false).open(),
        ModemLines::Keep => builder.open(),
    }
}

/// A warning when `dev` is an FTDI adapter whose latency timer holds bytes back for more than
/// 1 ms (Linux sysfs; `sysfs` is normally `/sys`).
pub fn latency_warning(dev: &Path, sysfs: &Path) -> Option<String> {
    let real = dev.canonicalize().unwrap_or_else(|_| dev.to_owned());
    let name = real.file_name()?.to_str()?;
    let attr = sysfs
        .join("bus/usb-serial/devices")
        .join(name)
        .join("latency_timer");
    let ms: u32 = std::fs::read_to_string(&attr).ok()?.trim().parse().ok()?;
    (ms > 1).then(|| {
        format!(
            "the FTDI latency timer of {name} is {ms} ms, so bytes reach busnoop in bursts up to {ms} ms \
             late and timestamps are coarse; lower it with `echo 1 | sudo tee {}` (or a udev rule, see docs/live.md)",
            attr.display()
        )
    })
}

/// How to find the adapter again after it was unplugged.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Identity {
    /// The path the user gave (a `/dev/serial/by-id/…` link survives re-enumeration).
    pub given: PathBuf,
    /// A by-id link to the device, when the user gave the kernel name.
    pub by_id: Option<PathBuf>,
    /// USB vendor, product and serial number, when known.
    pub usb: Option<(u16, u16, String)>,
}

impl Identity {
    /// Learns what can identify the adapter at `path` now.
    pub fn of(path: &Path) -> Identity {
        let real = path.canonicalize().ok();
        let usb = real.as_ref().and_then(|real| {
            list_ports().into_iter().find_map(|p| {
                let same = Path::new(&p.name).canonicalize().ok().as_ref() == Some(real);
                match (same, p.vid_pid, p.serial_number) {
                    (true, Some((v, pid)), Some(sn)) => Some((v, pid, sn)),
                    _ => None,
                }
            })
        });
        let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
        Identity {
            given: path.to_owned(),
            by_id: if is_link { None } else { by_id_link(path) },
            usb,
        }
    }

    /// Where the adapter is now, if it is back.
    pub fn locate(&self) -> Option<PathBuf> {
        if let Some(link) = &self.by_id
            && link.exists()
        {
            return Some(link.clone());
        }
        if let Some((vid, pid, sn)) = &self.usb
            && let Some(p) = list_ports().into_iter().find(|p| {
                p.vid_pid == Some((*vid, *pid)) && p.serial_number.as_deref() == Some(sn.as_str())
            })
        {
            return Some(PathBuf::from(p.name));
        }
        // The given path itself: a symlink re-resolved, or the same node coming back.
        self.given.exists().then(|| self.given.clone())
    }
}

/// Reads a serial port in the reader thread.
pub struct SerialReader {
    path: PathBuf,
    cfg: SerialConfig,
    port: Option<Box<dyn SerialPort>>,
    start: Instant,
    reconnect: bool,
    identity: Identity,
    started: bool,
    buf: Vec<u8>,
}

impl SerialReader {
    /// Reads the port opened at `path` (see [`open`]).
    pub fn new(path: &Path, port: Box<dyn SerialPort>, cfg: SerialConfig, reconnect: bool) -> Self {
        tracing::info!(
            "{}: {} baud, {} bits per character",
            path.display(),
            cfg.line.baud,
            cfg.line.bits_per_char()
        );
        SerialReader {
            path: path.to_owned(),
            cfg,
            port: Some(port),
            start: Instant::now(),
            reconnect,
            identity: if reconnect {
                Identity::of(path)
            } else {
                Identity::default()
            },
            started: false,
            buf: vec![0; READ_BUF],
        }
    }

    /// Counts its capture time from `start` (several ports at once: one clock for all).
    pub fn starting_at(mut self, start: Instant) -> Self {
        self.start = start;
        self
    }

    fn micros(&self) -> u64 {
        self.start.elapsed().as_micros() as u64
    }

    /// Waits until the adapter is back and reopens it. Returns `Err` only when the receiving
    /// side has gone away.
    fn wait_for_adapter(&mut self, tx: &SyncSender<Message>) -> Result<(), ()> {
        let mut pause = RECONNECT_FIRST;
        loop {
            std::thread::sleep(pause);
            pause = (pause * 2).min(RECONNECT_MAX);
            let found = self.identity.locate();
            tracing::debug!("waiting for the adapter: found {found:?}");
            if let Some(p) = found
                && let Ok(port) = open(&p, &self.cfg)
            {
                self.port = Some(port);
                tx.send(Message::LinkUp {
                    micros: self.micros(),
                    path: p,
                })
                .map_err(|_| ())?;
                return Ok(());
            }
        }
    }
}

impl ChunkReader for SerialReader {
    /// A port's reads are a few bytes each; while the decoder is held up (a terminal that
    /// scrolls slowly), its reader goes on reading so the adapter's buffer never overflows.
    fn ahead(&self) -> usize {
        32
    }

    fn next_batch(&mut self, tx: &SyncSender<Message>) -> Result<Option<Chunk>, Failure> {
        use std::io::ErrorKind::*;
        if !self.started {
            self.started = true;
            let _ = tx.send(Message::Anchor(Anchor::Instant(chrono::Utc::now())));
        }
        loop {
            let Some(port) = self.port.as_mut() else {
                return Ok(None);
            };
            let result = port.read(&mut self.buf);
            let gone = match result {
                Ok(0) => true,
                Ok(n) => {
                    let micros = self.micros();
                    return Ok(Some(
                        Batch::single(self.buf[..n].to_vec(), Some(micros)).into(),
                    ));
                }
                Err(e) if matches!(e.kind(), TimedOut | Interrupted | WouldBlock) => false,
                Err(_) => true,
            };
            if !gone {
                continue;
            }
            // Unplugged: these errors come back at once, so never retry the same descriptor.
            self.port = None;
            if !self.reconnect {
                return Err(Failure::Disconnected {
                    path: self.path.clone(),
                    frames: 0,
                });
            }
            if tx
                .send(Message::LinkDown {
                    micros: self.micros(),
                })
                .is_err()
                || self.wait_for_adapter(tx).is_err()
            {
                return Ok(None);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_paths() {
        assert!(is_device_path(Path::new("/dev/ttyUSB99")));
        assert!(is_device_path(Path::new("COM3")));
        assert!(is_device_path(Path::new("com12")));
        assert!(!is_device_path(Path::new("COM")));
        assert!(!is_device_path(Path::new("capture.bin")));
        assert!(is_device_path(Path::new("/dev/null")), "a character device");
    }

    #[test]
    fn latency_timer_warning() {
        let dir = tempfile::tempdir().unwrap();
        let attr = dir.path().join("bus/usb-serial/devices/ttyUSB7");
        std::fs::create_dir_all(&attr).unwrap();
        std::fs::write(attr.join("latency_timer"), "16\n").unwrap();
        let w = latency_warning(Path::new("/dev/ttyUSB7"), dir.path()).unwrap();
        assert!(w.contains("ttyUSB7 is 16 ms"), "{w}");
        std::fs::write(attr.join("latency_timer"), "1\n").unwrap();
        assert_eq!(latency_warning(Path::new("/dev/ttyUSB7"), dir.path()), None);
        assert_eq!(latency_warning(Path::new("/dev/ttyS0"), dir.path()), None);
    }

    #[test]
    fn permission_hint_names_the_group() {
        let h = permission_hint(Path::new("/nonexistent"));
        assert!(h.contains("dialout"), "{h}");
    }
}
