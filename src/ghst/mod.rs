//! GHST (ImmersionRC Ghost): the same frame shape as CRSF (`[addr][len][type][payload][crc]`,
//! CRC-8 0xD5 over type and payload), so it reuses CRSF's wire format, reassembler and decoder
//! skeleton (`crate::crsf::wire`, `crate::crsf::link`); what differs is here: the addresses
//! (0x80-0x89), the frame types, the 12-bit channels and the telemetry. The mapping onto the
//! table and the units are in `docs/ghst.md`.

mod args;
mod direct;
pub mod names;
mod values;
pub(crate) mod vocab;

#[cfg(test)]
mod tests;

use crate::crsf::link::{Described, Dialect, LinkDecoder, Scratch};
use crate::crsf::wire::{self, Event};
use crate::protocol::{Decoder, Export, Front, InputKind, Line, Probe, Protocol, Variant};
use crate::row::Latch;

pub use crate::crsf::link::COLUMNS;
pub use values::{aux_us, primary_us100};

/// The receiver's wire to the flight controller: 420000 baud 8N1, one wire, half duplex
/// (Betaflight `GHST_RX_BAUDRATE`).
pub const DEFAULT_BAUD: u32 = 420_000;
/// The module bay: pulses and telemetry at 400000 (Betaflight `GHST_TX_BAUDRATE_FAST`).
pub const MODULE_BAUD: u32 = 400_000;
/// The module bay of radios that cannot receive 400000: telemetry at 115200
/// (`GHST_TX_BAUDRATE_SLOW`, the TX module's address is then 0x88).
pub const SLOW_TELEMETRY_BAUD: u32 = 115_200;

/// The start bytes: every GHST address.
pub const ADDRESSES: wire::Addresses =
    wire::addresses(&[0x80, 0x81, 0x82, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89]);

/// GHST: 420000 baud 8N1, not inverted; 400000 in the module bay.
pub const PROTOCOL: Protocol = Protocol {
    name: "GHST",
    command: "ghst",
    aliases: &["ghost"],
    summary: "GHST (ImmersionRC Ghost): 12-bit RC channels, link statistics and telemetry, CRC-8 \
              checked (420000 baud)",
    about: "GHST, the protocol of ImmersionRC Ghost: CRSF's frame shape (`[addr][len][type] \
            [payload][crc]`, CRC-8 0xD5) with Ghost's addresses, 12-bit channels (CH1-4 in every \
            RC frame, four aux channels per frame type) and telemetry. 420000 baud 8N1, not \
            inverted, one wire between receiver and flight controller; --baud 400000 for the \
            module bay (docs/ghst.md).",
    examples: "Examples:\n  busnoop ghst /dev/ttyUSB0\n  busnoop ghst capture.bin --wide\n  \
               busnoop ghst capture.bin --stats",
    source_help: "What to read: a serial device (/dev/ttyUSB0, /dev/serial/by-id/…, COM3), a \
                  capture file (raw wire bytes, a busnoop .pcap or .pcapng recording) or `-` for \
                  standard input. File kinds are recognised by content; `--baud` also sets the \
                  byte times of raw files.",
    line: Line::n81(DEFAULT_BAUD),
    inverted: false,
    rates: &[DEFAULT_BAUD, MODULE_BAUD, SLOW_TELEMETRY_BAUD],
    accepts: &[InputKind::Raw, InputKind::Serial, InputKind::Recording],
    accepts_text: "raw wire bytes or busnoop recordings",
    // Counter Millis ID Device Type Sensor# Sensor Data | Unit Note
    pretty_widths: &[7, 8, 3, 9, 9, 8, 6, 40, 4, 0],
    vocab: &vocab::VOCAB,
    front: Front::of::<args::Args>(),
    variants,
    config_keys: &[],
    export: Some(Export {
        linktype: crate::pcap::linktype::USER3,
        linktype_name: "USER3",
        dissector: "busnoop-crsf.lua",
        extcap: "GHST (busnoop)",
        wrap: None,
    }),
};

/// `detect` reads GHST one way, at the line it listens at.
fn variants(probe: &Probe) -> Vec<Variant> {
    vec![Variant {
        label: "GHST",
        args: &[],
        decoder: decoder(Options { line: probe.line }),
    }]
}

/// Decoder settings.
#[derive(Clone, Debug)]
pub struct Options {
    /// The line, for the time of inputs without time (raw captures).
    pub line: Line,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            line: Line::n81(DEFAULT_BAUD),
        }
    }
}

/// The GHST decoder.
pub fn decoder(opts: Options) -> Box<dyn Decoder> {
    Box::new(LinkDecoder::<Ghst>::new(opts.line))
}

/// GHST as a [`Dialect`] of CRSF's decoder.
#[derive(Default)]
pub(crate) struct Ghst;

impl Dialect for Ghst {
    const NAME: &'static str = "GHST";
    const ADDRESSES: &'static wire::Addresses = &ADDRESSES;

    fn device(addr: u8) -> &'static str {
        names::device(addr)
    }

    fn type_name(addr: u8, ty: u8) -> Option<&'static str> {
        names::frame_type(addr, ty)
    }

    #[inline]
    fn direct(&mut self, wire: &[u8], micros: u64, out: &mut Latch<'_>) -> Option<Option<u8>> {
        direct::frame(wire, micros, out)
    }

    fn describe(&mut self, f: &Event<'_>, sc: &mut Scratch) -> Described {
        values::describe(f.addr(), f.ty().unwrap_or(0), f.payload(), sc)
    }

    fn no_frames_hint() -> &'static str {
        "check the baud rate (GHST runs at 420000 between receiver and flight controller, \
         400000 in the module bay, telemetry at 115200 on radios that cannot receive 400000) \
         and that the line is not inverted"
    }
}
