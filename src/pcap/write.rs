//! Writes classic pcap (little endian; microsecond time stamps, or nanosecond ones for a
//! recording of a nanosecond capture): for the recorder, tests, benchmarks and tools.

use super::Packet;

/// Snap length of the recordings of network captures: tcpdump's default, so that a recording
/// of a tcpdump capture has its header (and is the same file when nothing else differs).
pub const SNAPLEN_PACKETS: u32 = 262_144;

/// The 24-byte file header (snap length 256 KiB).
pub fn header(out: &mut Vec<u8>, link_type: u32) {
    header_with_snaplen(out, link_type, SNAPLEN_PACKETS);
}

/// The 24-byte file header with the given snap length.
pub fn header_with_snaplen(out: &mut Vec<u8>, link_type: u32, snaplen: u32) {
    file_header(out, link_type, snaplen, false);
}

/// The 24-byte file header with the given snap length; its records' time stamps are in
/// nanoseconds when `nanos` (the magic readers tell the unit by), microseconds otherwise.
pub fn file_header(out: &mut Vec<u8>, link_type: u32, snaplen: u32, nanos: bool) {
    let magic: u32 = if nanos { 0xA1B2_3C4D } else { 0xA1B2_C3D4 };
    out.extend_from_slice(&magic.to_le_bytes());
    out.extend_from_slice(&2u16.to_le_bytes());
    out.extend_from_slice(&4u16.to_le_bytes());
    out.extend_from_slice(&0i32.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&snaplen.to_le_bytes());
    out.extend_from_slice(&link_type.to_le_bytes());
}

/// The seconds and microseconds fields of a record stamped `ts_micros` (µs since the epoch).
pub fn stamp(ts_micros: i64) -> (u32, u32) {
    (
        ts_micros.div_euclid(1_000_000) as u32,
        ts_micros.rem_euclid(1_000_000) as u32,
    )
}

/// The 16-byte header of a record of `len` bytes stamped `ts_micros`; its bytes follow.
pub fn record_header(out: &mut Vec<u8>, ts_micros: i64, len: usize) {
    let (secs, us) = stamp(ts_micros);
    record_fields(out, secs, us, len as u32, len as u32);
}

/// A record header's four fields: seconds, their fraction (in the file's unit), captured and
/// original length.
fn record_fields(out: &mut Vec<u8>, secs: u32, frac: u32, captured: u32, original: u32) {
    for field in [secs, frac, captured, original] {
        out.extend_from_slice(&field.to_le_bytes());
    }
}

/// A captured packet as a record of a file whose header says `nanos` ([`file_header`]): its
/// time (to the nanosecond when both the file and the packet have them), its bytes and its
/// length on the wire as the capture told it.
pub fn packet(out: &mut Vec<u8>, p: &Packet<'_>, nanos: bool) {
    let (secs, us) = stamp(p.ts_micros);
    let frac = if nanos {
        us * 1000 + u32::from(p.nanos.unwrap_or(0))
    } else {
        us
    };
    record_fields(out, secs, frac, p.data.len() as u32, p.orig_len);
    out.extend_from_slice(p.data);
}

/// One record.
pub fn record(out: &mut Vec<u8>, ts_micros: i64, data: &[u8]) {
    record_header(out, ts_micros, data.len());
    out.extend_from_slice(data);
}

/// An Ethernet/IPv4/UDP frame around `payload` (checksum 0 = none).
pub fn udp4_frame(out: &mut Vec<u8>, src: ([u8; 4], u16), dst: ([u8; 4], u16), payload: &[u8]) {
    out.extend_from_slice(&[0x02, 0, 0, 0, 0, 2, 0x02, 0, 0, 0, 0, 1, 0x08, 0x00]);
    udp4_packet(out, src, dst, payload);
}

/// An IPv4/UDP packet around `payload` (UDP checksum 0 = none), as link type RAW carries it.
pub fn udp4_packet(out: &mut Vec<u8>, src: ([u8; 4], u16), dst: ([u8; 4], u16), payload: &[u8]) {
    let total = 20 + 8 + payload.len();
    let mut ip = [0u8; 20];
    ip[0] = 0x45;
    ip[2..4].copy_from_slice(&(total as u16).to_be_bytes());
    ip[8] = 64;
    ip[9] = 17;
    ip[12..16].copy_from_slice(&src.0);
    ip[16..20].copy_from_slice(&dst.0);
    let mut sum: u32 = 0;
    for c in ip.chunks(2) {
        sum += u16::from_be_bytes([c[0], c[1]]) as u32;
    }
    while sum > 0xFFFF {
        sum = (sum & 0xFFFF) + (sum >> 16);
    }
    ip[10..12].copy_from_slice(&(!(sum as u16)).to_be_bytes());
    out.extend_from_slice(&ip);
    out.extend_from_slice(&src.1.to_be_bytes());
    out.extend_from_slice(&dst.1.to_be_bytes());
    out.extend_from_slice(&((8 + payload.len()) as u16).to_be_bytes());
    out.extend_from_slice(&[0, 0]);
    out.extend_from_slice(payload);
}
