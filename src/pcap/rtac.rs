//! The RTAC serial encapsulation (pcap link type 250), as busnoop records a serial line.
//!
//! Every record starts with a 12-byte header: the arrival time (seconds and microseconds,
//! big-endian), the event type, the control lines (CTS 0x01, DCD 0x02, DSR 0x04, RTS 0x08,
//! DTR 0x10, RING 0x20, MBOK 0x40) and a 2-byte footer; the bytes of the line follow. Event
//! types are named as Wireshark's `rtacser` dissector names them.

/// Length of the header before the line's bytes.
pub const HEADER_LEN: usize = 12;

pub const EVENT_STATUS: u8 = 0x00;
pub const EVENT_TX_START: u8 = 0x01;
pub const EVENT_RX_DATA: u8 = 0x02;
pub const EVENT_RX_END: u8 = 0x04;
pub const EVENT_DATA_LOST: u8 = 0x05;
pub const EVENT_OVERFLOW: u8 = 0x0A;

/// Payloads of the status records busnoop writes.
pub const START: &[u8] = b"busnoop capture start";
pub const START_UNTIMED: &[u8] = b"busnoop capture start (untimed)";
pub const LINK_DOWN: &[u8] = b"busnoop link down";
pub const LINK_UP: &[u8] = b"busnoop link up";
/// After [`LINK_UP`], before the device the adapter is back at (recordings since issue 32;
/// older ones have none, and a replay names the recording instead).
pub const LINK_UP_AT: &[u8] = b" at ";

/// One pcap record (stamped `ts_micros`, µs since the epoch): the RTAC serial header with
/// `event` (control lines unknown) and then `data`.
pub fn record(out: &mut Vec<u8>, ts_micros: i64, event: u8, data: &[u8]) {
    super::write::record_header(out, ts_micros, HEADER_LEN + data.len());
    payload(out, ts_micros, event, data);
}

/// The packet bytes of one record: the RTAC serial header and then `data` (the body of a pcap
/// record or of a pcapng enhanced packet block).
pub fn payload(out: &mut Vec<u8>, ts_micros: i64, event: u8, data: &[u8]) {
    let (secs, us) = super::write::stamp(ts_micros);
    out.extend_from_slice(&secs.to_be_bytes());
    out.extend_from_slice(&us.to_be_bytes());
    out.push(event);
    out.push(0); // control lines unknown
    out.extend_from_slice(&[0, 0]); // footer
    out.extend_from_slice(data);
}

/// A record's event type, control lines and line bytes; `None` when it is shorter than the
/// header.
pub fn parse(record: &[u8]) -> Option<(u8, u8, &[u8])> {
    (record.len() >= HEADER_LEN).then(|| (record[8], record[9], &record[HEADER_LEN..]))
}
