//! `busnoop extcap`: busnoop as a Wireshark extcap, so that Wireshark captures an S.Port, SAB
//! or serial S-Bus line live (docs/wireshark.md, "Live in Wireshark").
//!
//! Wireshark runs the extcap with `--extcap-interfaces`, `--extcap-dlts`, `--extcap-config` to
//! list what it offers, and with `--capture --fifo PATH` to capture: busnoop then decodes the
//! chosen serial port as `busnoop PROTOCOL PORT --export PATH` would, writing one pcapng packet
//! per frame into Wireshark's FIFO (the link types of [`crate::export`]), until Wireshark stops
//! it (SIGTERM).

use std::path::PathBuf;

use clap::Args;

use crate::exit::Failure;
use crate::protocol::{Export, Protocol};
use crate::protocols::PROTOCOLS;

/// The protocols Wireshark can capture: those with an export, as `busnoop-COMMAND`.
fn interfaces() -> impl Iterator<Item = (&'static Protocol, Export)> {
    PROTOCOLS.iter().filter_map(|&p| p.export.map(|e| (p, e)))
}

/// The interface's name in Wireshark's list: `busnoop-sport`.
fn value(p: &Protocol) -> String {
    format!("busnoop-{}", p.command)
}

/// The options Wireshark passes (see the extcap documentation of Wireshark).
#[derive(Args, Clone, Debug, Default)]
pub struct ExtcapArgs {
    /// List the interfaces.
    #[arg(long)]
    pub extcap_interfaces: bool,
    /// Wireshark's version (ignored).
    #[arg(long, value_name = "VERSION")]
    pub extcap_version: Option<String>,
    /// The interface the other options are about.
    #[arg(long, value_name = "NAME")]
    pub extcap_interface: Option<String>,
    /// List the interface's link types.
    #[arg(long)]
    pub extcap_dlts: bool,
    /// List the interface's options.
    #[arg(long)]
    pub extcap_config: bool,
    /// Capture.
    #[arg(long)]
    pub capture: bool,
    /// The FIFO to write the pcapng into.
    #[arg(long, value_name = "PATH")]
    pub fifo: Option<PathBuf>,
    /// Capture filter (not supported; an error when given).
    #[arg(long, value_name = "FILTER")]
    pub extcap_capture_filter: Option<String>,
    /// The serial port to capture.
    #[arg(long, value_name = "DEVICE")]
    pub port: Option<PathBuf>,
    /// Line speed.
    #[arg(long, value_name = "BAUD")]
    pub baud: Option<u32>,
    /// Character format (8N1, 8E1, …), the protocol's by default.
    #[arg(long, value_name = "FORMAT")]
    pub line: Option<String>,
    /// Wait for an unplugged adapter.
    #[arg(long)]
    pub reconnect: bool,
}

/// The character formats the extcap offers besides the protocol's own.
const LINE_FORMATS: &[&str] = &["8N1", "8E1", "8O1", "8N2", "8E2", "8O2", "7E1", "7O1"];

fn interface(name: Option<&str>) -> Result<(&'static Protocol, Export), Failure> {
    let name =
        name.ok_or_else(|| Failure::Usage("extcap: --extcap-interface NAME is needed".into()))?;
    interfaces().find(|(p, _)| value(p) == name).ok_or_else(|| {
        let known: Vec<String> = interfaces().map(|(p, _)| value(p)).collect();
        Failure::Usage(format!(
            "extcap: unknown interface {name}; known: {}",
            known.join(", ")
        ))
    })
}

/// The answer to `--extcap-interfaces`, `--extcap-dlts` or `--extcap-config` (no capture).
pub fn describe(args: &ExtcapArgs, ports: &[String]) -> Result<String, Failure> {
    let mut s = String::new();
    if args.extcap_interfaces {
        s.push_str(&format!(
            "extcap {{version={}}}{{help=https://github.com/busnoop/busnoop/blob/main/docs/wireshark.md}}\n",
            env!("CARGO_PKG_VERSION")
        ));
        for (p, e) in interfaces() {
            s.push_str(&format!(
                "interface {{value={}}}{{display={}}}\n",
                value(p),
                e.extcap
            ));
        }
        return Ok(s);
    }
    let (p, e) = interface(args.extcap_interface.as_deref())?;
    if args.extcap_dlts {
        s.push_str(&format!(
            "dlt {{number={}}}{{name={}}}{{display={} frames}}\n",
            e.linktype, e.linktype_name, e.extcap
        ));
        return Ok(s);
    }
    if args.extcap_config {
        s.push_str(
            "arg {number=0}{call=--port}{display=Serial port}{type=selector}{required=true}\
             {tooltip=The serial port on the bus (read-only, passive)}\n",
        );
        for (n, p) in ports.iter().enumerate() {
            let default = if n == 0 { "{default=true}" } else { "" };
            s.push_str(&format!(
                "value {{arg=0}}{{value={p}}}{{display={p}}}{default}\n"
            ));
        }
        s.push_str(&format!(
            "arg {{number=1}}{{call=--baud}}{{display=Baud rate}}{{type=integer}}\
             {{range=300,4000000}}{{default={}}}{{tooltip=Line speed of the bus}}\n",
            p.line.baud
        ));
        s.push_str(
            "arg {number=2}{call=--reconnect}{display=Wait for the adapter when it is unplugged}\
             {type=boolflag}{default=false}\n",
        );
        // The character format: a Modbus bus at 8N1 instead of the standard's 8E1, a SAB bus
        // at 8E1.
        s.push_str(
            "arg {number=3}{call=--line}{display=Character format}{type=selector}\
             {tooltip=Data bits, parity and stop bits of the bus}\n",
        );
        let own = p.line.format();
        let mut formats = vec![own.clone()];
        for f in LINE_FORMATS {
            if *f != own {
                formats.push((*f).to_string());
            }
        }
        for f in formats {
            let default = if f == own { "{default=true}" } else { "" };
            s.push_str(&format!(
                "value {{arg=3}}{{value={f}}}{{display={f}}}{default}\n"
            ));
        }
        return Ok(s);
    }
    Err(Failure::Usage(
        "extcap: give --extcap-interfaces, --extcap-dlts, --extcap-config or --capture \
         (Wireshark does; see docs/wireshark.md)"
            .into(),
    ))
}

/// The busnoop command line a capture runs.
pub fn capture_command(args: &ExtcapArgs) -> Result<Vec<std::ffi::OsString>, Failure> {
    let (p, _) = interface(args.extcap_interface.as_deref())?;
    if args
        .extcap_capture_filter
        .as_deref()
        .is_some_and(|f| !f.trim().is_empty())
    {
        return Err(Failure::Usage(
            "extcap: capture filters are not supported; use a display filter".into(),
        ));
    }
    let fifo = args
        .fifo
        .as_ref()
        .ok_or_else(|| Failure::Usage("extcap: --capture needs --fifo PATH".into()))?;
    let port = args.port.as_ref().ok_or_else(|| {
        Failure::Usage("extcap: --capture needs --port DEVICE (a serial port)".into())
    })?;
    let mut cmd: Vec<std::ffi::OsString> = vec![
        p.command.into(),
        port.into(),
        "--export".into(),
        fifo.into(),
        "-o".into(),
        "/dev/null".into(),
        "--baud".into(),
        args.baud.unwrap_or(p.line.baud).to_string().into(),
    ];
    if let Some(f) = &args.line {
        cmd.push("--line".into());
        cmd.push(f.into());
    }
    if args.reconnect {
        cmd.push("--reconnect".into());
    }
    Ok(cmd)
}

/// `busnoop extcap …`.
pub fn run(args: &ExtcapArgs) -> Result<(), Failure> {
    if args.capture {
        let cmd = capture_command(args)?;
        let mut argv = vec![std::ffi::OsString::from("busnoop")];
        argv.extend(cmd);
        let (cli, _) =
            crate::cli::Parsed::from(argv).map_err(|e| Failure::Usage(format!("extcap: {e}")))?;
        // Wireshark shows an extcap's stderr as an error: no end-of-run summary.
        crate::cli::QUIET_REPORT.store(true, std::sync::atomic::Ordering::Relaxed);
        // Wireshark ends every capture with SIGTERM, or closes the FIFO: the normal end (exit
        // code 0).
        return match crate::cli::run(cli) {
            Err(Failure::Signal(_) | Failure::BrokenPipe) => Ok(()),
            other => other,
        };
    }
    let ports: Vec<String> = crate::source::serial::list_ports()
        .into_iter()
        .map(|p| p.name)
        .collect();
    let text = describe(args, &ports)?;
    crate::exit::write_stdout(text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_interfaces_dlts_and_config() {
        let list = ExtcapArgs {
            extcap_interfaces: true,
            ..Default::default()
        };
        let s = describe(&list, &[]).unwrap();
        assert!(s.starts_with("extcap {version="), "{s}");
        assert!(s.contains("interface {value=busnoop-sport}"), "{s}");
        let dlts = ExtcapArgs {
            extcap_dlts: true,
            extcap_interface: Some("busnoop-sab2".into()),
            ..Default::default()
        };
        assert!(
            describe(&dlts, &[])
                .unwrap()
                .contains("{number=148}{name=USER1}")
        );
        let sbus = ExtcapArgs {
            extcap_interface: Some("busnoop-sbus".into()),
            ..dlts
        };
        assert!(
            describe(&sbus, &[])
                .unwrap()
                .contains("{number=101}{name=RAW}")
        );
        let config = ExtcapArgs {
            extcap_config: true,
            extcap_interface: Some("busnoop-sport".into()),
            ..Default::default()
        };
        let s = describe(&config, &["/dev/ttyUSB0".into(), "/dev/ttyS0".into()]).unwrap();
        assert!(
            s.contains("value {arg=0}{value=/dev/ttyUSB0}{display=/dev/ttyUSB0}{default=true}")
        );
        assert!(
            s.contains("{call=--baud}") && s.contains("{default=57600}"),
            "{s}"
        );
        // The character format: the protocol's own first and by default (Modbus: 8E1).
        let modbus = ExtcapArgs {
            extcap_config: true,
            extcap_interface: Some("busnoop-modbus".into()),
            ..Default::default()
        };
        let s = describe(&modbus, &[]).unwrap();
        assert!(s.contains("{call=--line}"), "{s}");
        assert!(
            s.contains("value {arg=3}{value=8E1}{display=8E1}{default=true}\n")
                && s.contains("value {arg=3}{value=8N1}{display=8N1}\n"),
            "{s}"
        );
        assert_eq!(s.matches("{value=8E1}").count(), 1, "{s}");
        let bad = ExtcapArgs {
            extcap_dlts: true,
            extcap_interface: Some("eth0".into()),
            ..Default::default()
        };
        assert!(matches!(describe(&bad, &[]), Err(Failure::Usage(_))));
    }

    #[test]
    fn a_capture_is_the_export_into_the_fifo() {
        let args = ExtcapArgs {
            capture: true,
            extcap_interface: Some("busnoop-sport".into()),
            fifo: Some("/tmp/fifo".into()),
            port: Some("/dev/ttyUSB0".into()),
            reconnect: true,
            ..Default::default()
        };
        let cmd = capture_command(&args).unwrap();
        let cmd: Vec<_> = cmd.iter().map(|s| s.to_str().unwrap()).collect();
        assert_eq!(
            cmd,
            [
                "sport",
                "/dev/ttyUSB0",
                "--export",
                "/tmp/fifo",
                "-o",
                "/dev/null",
                "--baud",
                "57600",
                "--reconnect"
            ]
        );
        let at_8n1 = ExtcapArgs {
            line: Some("8N1".into()),
            reconnect: false,
            ..args.clone()
        };
        let cmd = capture_command(&at_8n1).unwrap();
        assert_eq!(&cmd[cmd.len() - 2..], ["--line", "8N1"]);
        let no_fifo = ExtcapArgs { fifo: None, ..args };
        assert!(capture_command(&no_fifo).is_err());
    }
}
