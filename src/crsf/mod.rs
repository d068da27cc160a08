//! CRSF (TBS Crossfire, ExpressLRS): reassembly, the log table mapping, and statistics.
//!
//! One row per frame: ID = the address byte (named in Device), Type = the frame type's name,
//! Sensor # = the type code (`0x16`), the frame's numbers as parts named as EdgeTX names its
//! sensors (`CH1`…`CH16` in µs on Betaflight's scale, `RxBt`, `1RSS`, `RQly`, `GSpd`…); Sensor
//! names the first of them, Value and Unit give its value and unit, Data lists them all. The
//! mapping, the units and where the TBS text disagrees with EdgeTX and Betaflight are in
//! `docs/crsf.md`. GHST (`crate::ghst`) reuses the frame format, the CRC, the reassembler
//! ([`wire`]) and the decoder skeleton of this module.

mod args;
mod direct;
pub(crate) mod ext;
pub(crate) mod link;
pub mod names;
pub(crate) mod read;
pub(crate) mod values;
pub(crate) mod vocab;
pub mod wire;

#[cfg(test)]
mod tests;

use crate::protocol::{Decoder, Export, Front, InputKind, Line, Probe, Protocol, Variant};
use crate::row::{Class, Latch};
use link::{Described, Dialect, LinkDecoder, Scratch};
use wire::Event;

pub use link::COLUMNS;
pub use values::{channel_us, rssi_dbm, vspeed_cm_s};

/// The flight controller's wires (receiver to FC and back): 420000 baud 8N1, not inverted
/// (ExpressLRS, Betaflight and EdgeTX; the TBS text says 416666).
pub const DEFAULT_BAUD: u32 = 420_000;
/// EdgeTX's telemetry mirror on an AUX serial port.
pub const MIRROR_BAUD: u32 = 115_200;
/// The module bay (radio to TX module, one wire, half duplex).
pub const MODULE_BAUD: u32 = 400_000;

/// CRSF: 420000 baud 8N1, not inverted; 115200 on EdgeTX's mirror, 400000 in the module bay.
pub const PROTOCOL: Protocol = Protocol {
    name: "CRSF",
    command: "crsf",
    aliases: &["elrs", "crossfire"],
    summary: "CRSF (TBS Crossfire, ExpressLRS): RC channels, link statistics and telemetry, CRC-8 \
              checked (420000 baud)",
    about: "CRSF, the protocol of TBS Crossfire and ExpressLRS: `[addr][len][type][payload][crc]` \
            frames, CRC-8 0xD5, resynchronised byte by byte. One row per frame: ID the address, \
            Type the frame type, RC channels in µs on Betaflight's scale, telemetry named as \
            EdgeTX names it. 420000 baud 8N1, not inverted, on the receiver's wires to the flight \
            controller (one adapter per wire, both in one run: `busnoop crsf RX TX`); --baud 115200 for EdgeTX's \
            telemetry mirror, 400000 for the module bay (docs/crsf.md).",
    examples: "Examples:\n  busnoop crsf /dev/ttyUSB0\n  busnoop crsf /dev/ttyUSB0 /dev/ttyUSB1\n  busnoop crsf /dev/ttyUSB0 --baud 115200 \
               --wide\n  busnoop crsf capture.bin --type LinkStats --stats\n  \
               busnoop crsf capture.bin -f jsonl",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, a busnoop .pcap or .pcapng recording) or `-` for \
                  standard input. File kinds are recognised by content; `--baud` also sets the \
                  byte times of raw files.",
    line: Line::n81(DEFAULT_BAUD),
    inverted: false,
    rates: &[DEFAULT_BAUD, MIRROR_BAUD, MODULE_BAUD],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 3, 9, 9, 8, 6, 40, 4, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[],
    export: Some(Export {
        linktype: crate::pcap::linktype::USER2,
        linktype_name: "USER2",
        dissector: "busnoop-crsf.lua",
        extcap: "CRSF (busnoop)",
        wrap: None,
    }),
};

/// `detect` reads CRSF one way, at the line it listens at.
fn variants(probe: &Probe) -> Vec<Variant> {
    vec![Variant {
        label: "CRSF",
        args: &[],
        decoder: decoder(Options { line: probe.line }),
    }]
}

/// Decoder settings.
#[derive(Clone, Debug)]
pub struct Options {
    /// The line, for the time of inputs without time (raw captures): byte *n* starts at *n* ×
    /// its bits per character / baud.
    pub line: Line,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            line: Line::n81(DEFAULT_BAUD),
        }
    }
}

/// The CRSF decoder (every input kind [`PROTOCOL`] accepts is a byte stream).
pub fn decoder(opts: Options) -> Box<dyn Decoder> {
    Box::new(LinkDecoder::<Crsf>::new(opts.line))
}

/// CRSF as a [`Dialect`] of the shared decoder.
#[derive(Default)]
pub(crate) struct Crsf {
    state: ext::State,
}

impl Dialect for Crsf {
    const NAME: &'static str = "CRSF";
    const ADDRESSES: &'static wire::Addresses = &wire::CRSF_ADDRESSES;

    fn device(addr: u8) -> &'static str {
        names::device(addr)
    }

    fn type_name(_addr: u8, ty: u8) -> Option<&'static str> {
        names::frame_type(ty)
    }

    #[inline]
    fn direct(&mut self, wire: &[u8], micros: u64, out: &mut Latch<'_>) -> Option<Option<u8>> {
        direct::frame(wire, micros, out)
    }

    fn describe(&mut self, f: &Event<'_>, sc: &mut Scratch) -> Described {
        let ty = f.ty().unwrap_or(0);
        let payload = f.payload();
        if let Some(d) = values::broadcast(ty, payload, sc) {
            return d;
        }
        match ty {
            0x80 if payload.starts_with(&[0x4F, 0x57]) => {
                crate::fmt::push_hex(&mut sc.data, payload);
                sc.note().push_str("mLRS mBridge message");
                Described::plain("mLRS")
            }
            0x80 => {
                ext::ardupilot(payload, sc);
                Described::plain("APPassthru")
            }
            0xAA => {
                ext::mavlink(payload, sc);
                Described::plain("MAVLink")
            }
            0xAC => {
                let mut r = read::Reader::new(payload);
                for name in ["present", "enabled", "health"] {
                    if let Some(v) = r.be_u32() {
                        if !sc.data.is_empty() {
                            sc.data.push(' ');
                        }
                        sc.data.push_str(name);
                        sc.data.push_str("=0x");
                        for b in v.to_be_bytes() {
                            crate::fmt::push_hex_u8(&mut sc.data, b);
                        }
                    }
                }
                Described::plain("MAVSysStatus")
            }
            0x34 => {
                let mut r = read::Reader::new(payload);
                if let (Some(t), Some(ts)) = (r.be_u16(), r.be_u32()) {
                    sc.data.push_str("log type ");
                    crate::fmt::push_u64(&mut sc.data, t.into());
                    sc.data.push_str(" at ");
                    crate::fmt::push_u64(&mut sc.data, ts.into());
                    while let Some(p) = r.be_u32() {
                        sc.data.push(' ');
                        crate::fmt::push_u64(&mut sc.data, p.into());
                    }
                } else {
                    crate::fmt::push_hex(&mut sc.data, payload);
                }
                Described::plain("Logging")
            }
            t if names::extended(t) => ext::extended(t, payload, sc, &mut self.state),
            t => {
                crate::fmt::push_hex(&mut sc.data, payload);
                let mut d = Described::plain(names::frame_type(t).unwrap_or("Unknown"));
                if names::frame_type(t).is_none() {
                    d.class = Class::Warning;
                    let note = sc.note();
                    note.push_str("unknown frame type ");
                    crate::fmt::push_0x(note, t);
                }
                d
            }
        }
    }

    fn no_frames_hint() -> &'static str {
        "check the baud rate (CRSF runs at 420000 on the flight controller's wires, 400000 in \
         the module bay, 115200 on EdgeTX's telemetry mirror; many CP210x/CH340 adapters cannot \
         do 420000, FTDI can) and that the line is not inverted"
    }
}
