//! Writes pcapng (little endian; microsecond time stamps, or nanosecond ones for a recording
//! of a nanosecond capture): the section header, interface descriptions naming the device, and
//! enhanced packet blocks with optional comments. Used by the recorder (`--record
//! FILE.pcapng`) and the frame export (`--export FILE.pcapng`).
//!
//! Every function appends one whole block to `out`; blocks are padded to 32 bits as the format
//! requires, and options strings are written as UTF-8 without a terminating NUL.

use super::Packet;

const SHB: u32 = 0x0A0D_0D0A;
const IDB: u32 = 0x0000_0001;
const EPB: u32 = 0x0000_0006;
const BYTE_ORDER_MAGIC: u32 = 0x1A2B_3C4D;

const OPT_END: u16 = 0;
const OPT_COMMENT: u16 = 1;
const SHB_USERAPPL: u16 = 4;
const IF_NAME: u16 = 2;
const IF_DESCRIPTION: u16 = 3;
const IF_TSRESOL: u16 = 9;

/// Snap length of the interfaces busnoop describes (matches the `.pcap` recordings).
pub const SNAPLEN: u32 = 65_535;

fn pad(out: &mut Vec<u8>) {
    while !out.len().is_multiple_of(4) {
        out.push(0);
    }
}

fn option(body: &mut Vec<u8>, code: u16, value: &[u8]) {
    // An option value longer than 65535 bytes cannot be written; keep its start.
    let value = &value[..value.len().min(u16::MAX as usize - 3)];
    body.extend_from_slice(&code.to_le_bytes());
    body.extend_from_slice(&(value.len() as u16).to_le_bytes());
    body.extend_from_slice(value);
    pad(body);
}

fn end_options(body: &mut Vec<u8>, any: bool) {
    if any {
        body.extend_from_slice(&OPT_END.to_le_bytes());
        body.extend_from_slice(&0u16.to_le_bytes());
    }
}

/// Appends a block of `kind` around `body` (already padded).
fn block(out: &mut Vec<u8>, kind: u32, body: &[u8]) {
    let len = (12 + body.len()) as u32;
    out.extend_from_slice(&kind.to_le_bytes());
    out.extend_from_slice(&len.to_le_bytes());
    out.extend_from_slice(body);
    out.extend_from_slice(&len.to_le_bytes());
}

/// The section header block, naming busnoop as the writing application.
pub fn section_header(out: &mut Vec<u8>) {
    let mut body = Vec::with_capacity(48);
    body.extend_from_slice(&BYTE_ORDER_MAGIC.to_le_bytes());
    body.extend_from_slice(&1u16.to_le_bytes());
    body.extend_from_slice(&0u16.to_le_bytes());
    body.extend_from_slice(&(-1i64).to_le_bytes()); // section length unknown
    let appl = format!("busnoop {}", env!("CARGO_PKG_VERSION"));
    option(&mut body, SHB_USERAPPL, appl.as_bytes());
    end_options(&mut body, true);
    block(out, SHB, &body);
}

/// An interface description block: `link_type`, microsecond time stamps, snap length
/// [`SNAPLEN`], and the interface's name (`if_name`, e.g. the device path) and description
/// (`if_description`, e.g. the protocol and baud rate) when given.
pub fn interface(out: &mut Vec<u8>, link_type: u16, name: Option<&str>, description: Option<&str>) {
    interface_block(out, link_type, SNAPLEN, false, name, description);
}

/// Like [`interface`] with the given snap length, and nanosecond time stamps (`if_tsresol` 9)
/// when `nanos`.
pub fn interface_block(
    out: &mut Vec<u8>,
    link_type: u16,
    snaplen: u32,
    nanos: bool,
    name: Option<&str>,
    description: Option<&str>,
) {
    let mut body = Vec::with_capacity(64);
    body.extend_from_slice(&link_type.to_le_bytes());
    body.extend_from_slice(&0u16.to_le_bytes());
    body.extend_from_slice(&snaplen.to_le_bytes());
    if let Some(n) = name {
        option(&mut body, IF_NAME, n.as_bytes());
    }
    if let Some(d) = description {
        option(&mut body, IF_DESCRIPTION, d.as_bytes());
    }
    option(&mut body, IF_TSRESOL, &[if nanos { 9 } else { 6 }]);
    end_options(&mut body, true);
    block(out, IDB, &body);
}

/// An enhanced packet block on `interface`, stamped `ts_micros` (µs since the epoch), with an
/// optional comment (`opt_comment`).
pub fn packet(
    out: &mut Vec<u8>,
    interface: u32,
    ts_micros: i64,
    data: &[u8],
    comment: Option<&str>,
) {
    let ts = ts_micros.max(0) as u64;
    packet_block(out, interface, ts, data, data.len() as u32, comment);
}

/// A captured packet as an enhanced packet block on `interface`, whose description says
/// `nanos` ([`interface_block`]): its time (to the nanosecond when both the interface and the
/// packet have them), its bytes and its length on the wire as the capture told it.
pub fn captured(out: &mut Vec<u8>, interface: u32, p: &Packet<'_>, nanos: bool) {
    let micros = p.ts_micros.max(0) as u64;
    let ts = if nanos {
        micros
            .saturating_mul(1000)
            .saturating_add(u64::from(p.nanos.unwrap_or(0)))
    } else {
        micros
    };
    packet_block(out, interface, ts, p.data, p.orig_len, None);
}

/// An enhanced packet block: `ts` in the interface's units, `data` captured of `original`
/// bytes on the wire, an optional comment.
fn packet_block(
    out: &mut Vec<u8>,
    interface: u32,
    ts: u64,
    data: &[u8],
    original: u32,
    comment: Option<&str>,
) {
    let start = out.len();
    out.extend_from_slice(&EPB.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes()); // length, set below
    out.extend_from_slice(&interface.to_le_bytes());
    out.extend_from_slice(&((ts >> 32) as u32).to_le_bytes());
    out.extend_from_slice(&(ts as u32).to_le_bytes());
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(&original.to_le_bytes());
    out.extend_from_slice(data);
    pad(out);
    if let Some(c) = comment {
        let mut opts = Vec::with_capacity(c.len() + 12);
        option(&mut opts, OPT_COMMENT, c.as_bytes());
        end_options(&mut opts, true);
        out.extend_from_slice(&opts);
    }
    let len = (out.len() - start + 4) as u32;
    out[start + 4..start + 8].copy_from_slice(&len.to_le_bytes());
    out.extend_from_slice(&len.to_le_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcap::PcapStream;

    #[test]
    fn reads_back_with_link_type_times_and_bytes() {
        let mut out = Vec::new();
        section_header(&mut out);
        interface(
            &mut out,
            250,
            Some("/dev/ttyUSB0"),
            Some("sport 57600 baud"),
        );
        packet(
            &mut out,
            0,
            1_700_000_000_123_456,
            b"abc",
            Some("link down"),
        );
        packet(&mut out, 0, 1_700_000_001_000_000, b"", None);
        assert_eq!(out.len() % 4, 0);
        let mut got = Vec::new();
        let mut s = PcapStream::default();
        s.push(&out, &mut |p| {
            got.push((p.ts_micros, p.link_type, p.data.to_vec()))
        })
        .unwrap();
        s.finish().unwrap();
        assert_eq!(
            got,
            [
                (1_700_000_000_123_456, 250, b"abc".to_vec()),
                (1_700_000_001_000_000, 250, vec![]),
            ]
        );
    }
}
