//! Modbus frames for Wireshark: each checked frame as the Modbus/UDP datagram a Modbus/TCP
//! device would send (the MBAP header and the PDU, no CRC), which Wireshark's own `mbudp`
//! dissector decodes on UDP port 502 without any setting (link type RAW, raw IPv4):
//!
//! * addresses: slave N is 10.0.0.N, port 502 (a broadcast, address 0, goes to 10.0.0.255);
//!   the master is [`MASTER`] (10.0.1.254), port [`MASTER_PORT`]; a request goes master →
//!   slave (Wireshark reads a datagram *to* port 502 as a query), a response or exception
//!   slave → master;
//! * the MBAP header: a transaction number that increases with every request (from 1) and
//!   is repeated in its answer (so Wireshark pairs them and names a response's registers from
//!   its request), protocol 0, the length, the unit (the slave address);
//! * bytes that are no checked frame (a bad CRC, a cut frame, garbage): a datagram of those
//!   bytes as they were on the wire from [`UNKNOWN`] port 0 to the master's port 0, which no
//!   dissector claims (the export adds busnoop's verdict as a packet comment).

use crate::pcap::write::udp4_packet;
use crate::protocol::Wrap;
use crate::row::{Row, Unframed};

/// The Modbus/TCP and Modbus/UDP port.
pub const PORT: u16 = 502;
/// The master's address in the export.
pub const MASTER: [u8; 4] = [10, 0, 1, 254];
/// The master's port: any port but 502 (a datagram from port 502 is a response).
pub const MASTER_PORT: u16 = 50_200;
/// The sender of bytes that are no frame.
pub const UNKNOWN: [u8; 4] = [0, 0, 0, 0];

/// The address of slave `n` in the export (a broadcast: 10.0.0.255).
pub fn slave_address(n: u8) -> [u8; 4] {
    [10, 0, 0, if n == 0 { 255 } else { n }]
}

/// What a frame is, as the table shows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Request,
    /// A response or an exception.
    Answer,
    /// No checked frame: its bytes as on the wire.
    Broken,
}

/// The transaction numbers of an export.
#[derive(Clone, Debug)]
pub struct ModbusWrap {
    /// The transaction of each slave's last request.
    tids: Box<[Option<u16>; 256]>,
    next: u16,
    payload: Vec<u8>,
}

impl Default for ModbusWrap {
    fn default() -> Self {
        ModbusWrap {
            tids: Box::new([None; 256]),
            next: 1,
            payload: Vec::with_capacity(260),
        }
    }
}

impl ModbusWrap {
    /// The IPv4/UDP packet of one frame into `out`: `frame` is the address and the PDU (no CRC
    /// or LRC) of a request or answer, the wire bytes of a broken one.
    pub fn packet(&mut self, role: Role, frame: &[u8], out: &mut Vec<u8>) {
        let (Some(&unit), Role::Request | Role::Answer) = (frame.first(), role) else {
            udp4_packet(out, (UNKNOWN, 0), (MASTER, 0), frame);
            return;
        };
        let tid = match role {
            Role::Request => {
                let t = self.next;
                self.next = self.next.checked_add(1).unwrap_or(1);
                self.tids[unit as usize] = Some(t);
                t
            }
            _ => self.tids[unit as usize].unwrap_or(0),
        };
        let p = &mut self.payload;
        p.clear();
        p.extend_from_slice(&tid.to_be_bytes());
        p.extend_from_slice(&[0, 0]);
        p.extend_from_slice(&(frame.len() as u16).to_be_bytes());
        p.extend_from_slice(frame);
        let (master, slave) = ((MASTER, MASTER_PORT), (slave_address(unit), PORT));
        match role {
            Role::Request => udp4_packet(out, master, slave, p),
            _ => udp4_packet(out, slave, master, p),
        }
    }
}

impl Wrap for ModbusWrap {
    /// A row of the table: `Request`, `Response` and `Exception` rows are frames (their address
    /// and PDU as the decoder hands them on, or the RTU bytes without their CRC), everything
    /// else the bytes as they were.
    fn packet(&mut self, row: &Row<'_>, unframed: Option<&Unframed<'_>>, out: &mut Vec<u8>) {
        let role = match row.kind {
            "Request" => Role::Request,
            "Response" | "Exception" => Role::Answer,
            _ => Role::Broken,
        };
        let frame = match (role, unframed) {
            (Role::Broken, _) => row.raw,
            (_, Some(u)) => u.bytes,
            (_, None) => &row.raw[..row.raw.len().saturating_sub(2)],
        };
        ModbusWrap::packet(self, role, frame, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_and_answers_as_modbus_udp() {
        let mut w = ModbusWrap::default();
        let mut out = Vec::new();
        w.packet(
            Role::Request,
            &[0x11, 0x03, 0x00, 0x6B, 0x00, 0x03],
            &mut out,
        );
        assert_eq!(out.len(), 20 + 8 + 7 + 5);
        assert_eq!(&out[12..20], &[10, 0, 1, 254, 10, 0, 0, 0x11]);
        assert_eq!(&out[20..24], &[0xC4, 0x18, 0x01, 0xF6], "ports 50200 → 502");
        assert_eq!(
            &out[28..],
            &[0, 1, 0, 0, 0, 6, 0x11, 0x03, 0x00, 0x6B, 0x00, 0x03]
        );
        out.clear();
        w.packet(Role::Answer, &[0x11, 0x03, 0x02, 0x12, 0x34], &mut out);
        assert_eq!(&out[12..20], &[10, 0, 0, 0x11, 10, 0, 1, 254]);
        assert_eq!(
            &out[28..],
            &[0, 1, 0, 0, 0, 5, 0x11, 0x03, 0x02, 0x12, 0x34]
        );
        out.clear();
        w.packet(
            Role::Request,
            &[0x00, 0x06, 0x00, 0x01, 0x00, 0x02],
            &mut out,
        );
        assert_eq!(&out[16..20], &[10, 0, 0, 255]);
        assert_eq!(&out[28..30], &[0, 2]);
        out.clear();
        w.packet(Role::Broken, &[0xFF, 0x00], &mut out);
        assert_eq!(&out[12..16], &UNKNOWN);
        assert_eq!(&out[20..24], &[0, 0, 0, 0]);
        assert_eq!(&out[28..], &[0xFF, 0x00]);
    }
}
