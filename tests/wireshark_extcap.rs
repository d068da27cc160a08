//! busnoop's extcap as tshark itself finds and runs it (docs/wireshark.md, "Live in
//! Wireshark"): `tshark -D` lists the interfaces, and `tshark -i busnoop-…` captures a serial
//! line (a pty) through busnoop into the packets `--export` writes for the same bytes.
//!
//! Nothing outside a temporary directory is touched: tshark finds the extcap through
//! `WIRESHARK_EXTCAP_DIR`. Wireshark ignores that variable for root, so as root tshark runs as
//! the unprivileged user 65534. Skipped with a message when tshark is not installed, or when it
//! does not honour the variable (then `.ci/run`'s link in the global extcap folder, if any, is
//! used instead).

mod common;

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::fixture;
use common::pty::{bus, lock};
use common::{ok, text};

fn root() -> bool {
    unsafe { libc::geteuid() == 0 }
}

/// Whether any user may run `bin` (every folder on the way searchable, the file executable).
fn reachable_by_all(bin: &Path) -> bool {
    let x = |p: &Path| std::fs::metadata(p).is_ok_and(|m| m.permissions().mode() & 0o001 != 0);
    x(bin) && bin.ancestors().skip(1).all(x)
}

/// tshark with busnoop installed as an extcap in a temporary folder of its own.
struct Tshark {
    dir: tempfile::TempDir,
}

impl Tshark {
    /// `None` (with a message) when tshark is missing.
    fn new() -> Option<Tshark> {
        if !Command::new("tshark")
            .arg("-v")
            .output()
            .is_ok_and(|o| o.status.success())
        {
            eprintln!("tshark is not installed: skipping the extcap tests with tshark");
            return None;
        }
        let dir = tempfile::tempdir().unwrap();
        let mode = |p: &Path, m| std::fs::set_permissions(p, std::fs::Permissions::from_mode(m));
        mode(dir.path(), 0o755).unwrap();
        let extcap = dir.path().join("extcap");
        let home = dir.path().join("home");
        std::fs::create_dir(&extcap).unwrap();
        std::fs::create_dir(&home).unwrap();
        mode(&extcap, 0o755).unwrap();
        // The unprivileged user writes its profile and the capture here.
        mode(&home, 0o777).unwrap();
        let bin = assert_cmd::cargo::cargo_bin("busnoop");
        let link = extcap.join("busnoop");
        if root() && !reachable_by_all(&bin) {
            // The user 65534 cannot reach the checkout: a copy.
            std::fs::copy(&bin, &link).unwrap();
            mode(&link, 0o755).unwrap();
        } else {
            // As the install instructions say: a link.
            std::os::unix::fs::symlink(&bin, &link).unwrap();
        }
        Some(Tshark { dir })
    }

    fn extcap_dir(&self) -> PathBuf {
        self.dir.path().join("extcap")
    }

    fn home(&self) -> PathBuf {
        self.dir.path().join("home")
    }

    fn command(&self) -> Command {
        let mut c = Command::new("tshark");
        c.env_clear()
            .env("PATH", std::env::var_os("PATH").unwrap_or_default())
            .env("HOME", self.home())
            .env("WIRESHARK_CONFIG_DIR", self.home().join("profile"))
            .env("WIRESHARK_EXTCAP_DIR", self.extcap_dir())
            .current_dir(self.home());
        if root() {
            common::as_nobody(&mut c);
        }
        c
    }

    /// Whether this tshark searches our extcap folder; a message when not.
    fn finds_extcaps(&self) -> bool {
        let folders = ok(&self.command().args(["-G", "folders"]).output().unwrap());
        let ours = self.extcap_dir().display().to_string();
        let honoured = folders
            .lines()
            .any(|l| l.starts_with("Extcap path:") && l.contains(&ours));
        if !honoured {
            eprintln!(
                "this tshark does not search WIRESHARK_EXTCAP_DIR (its folders: {folders}): \
                 skipping; install busnoop in the global extcap folder to run it"
            );
        }
        honoured
    }
}

/// The packet bytes of a pcap or pcapng file, with their link type.
fn packets(path: &Path) -> Vec<(u32, Vec<u8>)> {
    let mut got = Vec::new();
    let mut s = busnoop::pcap::PcapStream::default();
    s.push(&std::fs::read(path).unwrap(), &mut |p| {
        got.push((p.link_type, p.data.to_vec()))
    })
    .unwrap();
    got
}

/// The export (`busnoop PROTOCOL INPUT --export`) of `bytes`.
fn export_of(protocol: &str, bytes: &[u8]) -> Vec<(u32, Vec<u8>)> {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("input.bin");
    std::fs::write(&input, bytes).unwrap();
    let e = dir.path().join("e.pcapng");
    ok(&Command::new(assert_cmd::cargo::cargo_bin("busnoop"))
        .arg(protocol)
        .arg(&input)
        .arg("--export")
        .arg(&e)
        .args(["-o", "/dev/null"])
        .output()
        .unwrap());
    packets(&e)
}

#[test]
fn tshark_lists_the_extcap_interfaces() {
    let Some(t) = Tshark::new() else { return };
    if !t.finds_extcaps() {
        return;
    }
    let list = ok(&t.command().arg("-D").output().unwrap());
    for want in [
        "busnoop-sport (FrSky S.Port (busnoop))",
        "busnoop-sab2 (modm SAB / SAB2 (busnoop))",
        "busnoop-sbus (Saia S-Bus, serial (busnoop))",
    ] {
        assert!(list.lines().any(|l| l.ends_with(want)), "{want}: {list}");
    }
    // The options Wireshark shows for an interface are busnoop's --extcap-config.
    let prefs = ok(&t.command().args(["-G", "currentprefs"]).output().unwrap());
    for want in [
        "#extcap.busnoop_sport.port: ",
        "#extcap.busnoop_sport.baud: 57600",
        "#extcap.busnoop_sbus.baud: 9600",
    ] {
        assert!(prefs.lines().any(|l| l == want), "{want}");
    }
}

/// `tshark -i IFACE` on a pty carrying `traffic`, until `count` packets: the capture file's
/// packets, and tshark's stderr.
fn capture(t: &Tshark, iface: &str, traffic: &[u8], count: usize) -> (Vec<(u32, Vec<u8>)>, String) {
    use std::io::Write;
    let _g = lock();
    let mut b = bus();
    // busnoop runs as tshark's user: as root that is 65534, which needs the pty opened up.
    std::fs::set_permissions(&b.path, std::fs::Permissions::from_mode(0o666)).unwrap();
    let out = t.home().join(format!("{iface}.pcapng"));
    let pref = format!(
        "extcap.{}.port:{}",
        iface.replace('-', "_"),
        b.path.display()
    );
    let child = t
        .command()
        .args(["-i", iface, "-o", &pref, "-c", &count.to_string()])
        .args(["-a", "duration:30", "-w"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The bytes wait in the pty until busnoop opens it.
    b.master.write_all(traffic).unwrap();
    b.master.flush().unwrap();
    let done = child.wait_with_output().unwrap();
    let err = text(&done.stderr);
    assert_eq!(done.status.code(), Some(0), "{err}");
    drop(b);
    (packets(&out), err)
}

#[test]
fn tshark_captures_a_serial_bus_through_the_extcap() {
    let Some(t) = Tshark::new() else { return };
    if !t.finds_extcaps() {
        return;
    }
    let traffic = std::fs::read(fixture("sport-sample.bin")).unwrap();
    let want = export_of("sport", &traffic);
    let (got, err) = capture(&t, "busnoop-sport", &traffic, 20);
    assert_eq!(got.len(), 20, "{err}");
    assert_eq!(got[..], want[..20], "{err}");
    // busnoop keeps stderr quiet: Wireshark would show anything there as an error.
    assert!(!err.contains("extcap pipe"), "{err}");
}

#[test]
fn tshark_captures_serial_sbus_through_the_extcap_as_ether_sbus() {
    use busnoop::sbus::telegram::{CrcBasis, encode_data};
    let Some(t) = Tshark::new() else { return };
    if !t.finds_extcaps() {
        return;
    }
    // Station n: a read of R(n) answered with the value 1000 + n.
    let mut traffic = Vec::new();
    for n in 1..=6u8 {
        encode_data(&mut traffic, 0, &[n, 0x06, 0, 0, n], CrcBasis::Both);
        let v = 1000u32 + n as u32;
        encode_data(&mut traffic, 1, &v.to_be_bytes(), CrcBasis::Both);
    }
    let want = export_of("sbus", &traffic);
    let (got, err) = capture(&t, "busnoop-sbus", &traffic, 12);
    assert_eq!(got.len(), 12, "{err}");
    assert_eq!(got[..], want[..], "{err}");
    assert!(got.iter().all(|p| p.0 == busnoop::pcap::linktype::RAW));
    // Wireshark's own dissector reads them.
    let file = t.home().join("busnoop-sbus.pcapng");
    let fields = ok(&t
        .command()
        .arg("-r")
        .arg(&file)
        .args([
            "-T",
            "fields",
            "-e",
            "sbus.destination",
            "-e",
            "sbus.data_rtc",
        ])
        .output()
        .unwrap());
    let want: String = (1..=6)
        .map(|n| format!("{n}\t\n\t{}\n", 1000 + n))
        .collect();
    assert_eq!(fields, want);
}
