//! Writes classic pcap (microseconds, little endian): for the recorder, tests, benchmarks and
//! tools.

/// The 24-byte file header (snap length 256 KiB).
pub fn header(out: &mut Vec<u8>, link_type: u32) {
    header_with_snaplen(out, link_type, 262_144);
}

/// The 24-byte file header with the given snap length.
pub fn header_with_snaplen(out: &mut Vec<u8>, link_type: u32, snaplen: u32) {
    out.extend_from_slice(&0xA1B2_C3D4u32.to_le_bytes()); // microsecond time stamps
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
    out.extend_from_slice(&secs.to_le_bytes());
    out.extend_from_slice(&us.to_le_bytes());
    out.extend_from_slice(&(len as u32).to_le_bytes());
    out.extend_from_slice(&(len as u32).to_le_bytes());
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
