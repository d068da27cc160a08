//! Serial S-Bus in an export (`--export`): each telegram re-wrapped as the Ether-S-Bus datagram
//! a PCD would have sent over UDP, for Wireshark's own `sbus` dissector (docs/wireshark.md,
//! "Serial S-Bus as Ether-S-Bus").

use super::telegram::{self, AT_REQUEST};
use crate::pcap::write;
use crate::protocol::Wrap;
use crate::row::{Row, Unframed};

/// Serial S-Bus telegrams as Ether-S-Bus datagrams (docs/wireshark.md, "Serial S-Bus as
/// Ether-S-Bus"):
///
/// * addresses: station N is 10.0.0.N, UDP port 5050 (broadcast 255 is 10.0.0.255); the master
///   is [`MASTER`] (10.0.1.254, outside 10.0.0.0/24 so that no station shares it), port 5050;
///   a request goes master → station, an answer station → master; an answer busnoop could not
///   pair with a request (so its station is unknown) and bytes that are no telegram come from
///   [`UNKNOWN`] (0.0.0.0);
/// * the Ether-S-Bus header: length, version 0, protocol type 0, a sequence number that
///   increases with every request to the station (from [`FIRST_SEQ`], one count per station,
///   as each station is a conversation of its own; a retry keeps its request's number, as an
///   Ether-S-Bus client does, so Wireshark marks it) and is repeated in the answers;
/// * the telegram as the decoder re-read it (DLE pairs undone, no secure header, no break) and
///   a CRC-16 over the datagram, computed afresh; for a telegram whose serial CRC failed, the
///   received CRC bytes instead, so that Wireshark shows the checksum as bad (inverted in the
///   rare case that they happen to fit the datagram);
/// * bytes that are no telegram (garbage, a cut telegram, an unknown attribute): a datagram of
///   those bytes as they were on the wire, from [`UNKNOWN`], with busnoop's verdict as comment.
#[derive(Clone, Debug)]
pub struct SbusWrap {
    /// The sequence number of each station's last request (its conversation), when there was
    /// one.
    seqs: Box<[Option<u16>; 256]>,
    /// The last request's.
    last: Option<u16>,
    payload: Vec<u8>,
}

impl Default for SbusWrap {
    fn default() -> Self {
        SbusWrap {
            seqs: Box::new([None; 256]),
            last: None,
            payload: Vec::new(),
        }
    }
}

/// The master's address in the S-Bus export.
pub const MASTER: [u8; 4] = [10, 0, 1, 254];
/// The address of unknown senders in the S-Bus export.
pub const UNKNOWN: [u8; 4] = [0, 0, 0, 0];
/// The Ether-S-Bus UDP port.
pub const SBUS_PORT: u16 = 5050;
/// The first sequence number: Wireshark's PANA heuristic takes Ether-S-Bus datagrams with
/// sequence numbers 1-4 for PANA, so the numbers stay clear of them.
pub const FIRST_SEQ: u16 = 0x0100;

/// The address of station `n` in the S-Bus export.
pub fn station_address(n: u8) -> [u8; 4] {
    [10, 0, 0, n]
}

impl Wrap for SbusWrap {
    /// The IPv4/UDP packet of `row` into `out`.
    fn packet(&mut self, row: &Row<'_>, unframed: Option<&Unframed<'_>>, out: &mut Vec<u8>) {
        let Some((&at, tele)) = unframed.and_then(|u| u.bytes.split_first()) else {
            // Bytes that are no telegram: as they were.
            write::udp4_packet(out, (UNKNOWN, SBUS_PORT), (MASTER, SBUS_PORT), row.raw);
            return;
        };
        let seq = if at == AT_REQUEST {
            let station = tele.first().copied().unwrap_or(0) as usize;
            let seq = match self.seqs[station] {
                Some(s) if row.kind == "Retry" => s,
                Some(s) if s < u16::MAX => s + 1,
                _ => FIRST_SEQ,
            };
            self.seqs[station] = Some(seq);
            self.last = Some(seq);
            seq
        } else {
            let of_station = row
                .id
                .and_then(|i| self.seqs.get(i as usize).copied().flatten());
            of_station.or(self.last).unwrap_or(FIRST_SEQ)
        };
        self.payload.clear();
        telegram::encode_ether(&mut self.payload, seq, at, tele);
        if let Some(got) = unframed.and_then(|u| u.bad_check) {
            let n = self.payload.len();
            let fresh = u16::from_be_bytes([self.payload[n - 2], self.payload[n - 1]]);
            let crc = if got == fresh { got ^ 0x00FF } else { got };
            self.payload[n - 2..].copy_from_slice(&crc.to_be_bytes());
        }
        let station = |id: Option<u32>| match id.and_then(|i| u8::try_from(i).ok()) {
            Some(n) => station_address(n),
            None => UNKNOWN,
        };
        let (src, dst) = if at == AT_REQUEST {
            (MASTER, station(tele.first().map(|&s| s as u32)))
        } else {
            (station(row.id), MASTER)
        };
        write::udp4_packet(out, (src, SBUS_PORT), (dst, SBUS_PORT), &self.payload);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcap::linktype;

    #[test]
    fn sbus_telegrams_become_ether_sbus_datagrams() {
        let mut w = SbusWrap::default();
        let mut row = Row::empty(Some(0));
        let mut out = Vec::new();
        let udp = |out: &[u8]| {
            let Extract::Udp(u) = extract(linktype::RAW, out) else {
                panic!("{out:?}")
            };
            (u.src.to_string(), u.dst.to_string(), u.payload.to_vec())
        };
        use crate::sbus::ether::{Extract, extract, parse};
        // A request to station 7, its response, an unpaired response.
        let req = [0u8, 7, 6, 0, 0, 1];
        row.kind = "Request";
        let frame = |bytes, bad_check| Unframed { bytes, bad_check };
        w.packet(&row, Some(&frame(&req, None)), &mut out);
        let (src, dst, payload) = udp(&out);
        assert_eq!(
            (src.as_str(), dst.as_str()),
            ("10.0.1.254:5050", "10.0.0.7:5050")
        );
        let t = parse(&payload).unwrap();
        assert!(t.crc_ok());
        assert_eq!((t.seq, t.at, t.telegram), (FIRST_SEQ, 0, &req[1..]));
        out.clear();
        row.kind = "Response";
        row.id = Some(7);
        w.packet(&row, Some(&frame(&[1, 0, 0, 0, 9], None)), &mut out);
        let (src, _, payload) = udp(&out);
        assert_eq!(src, "10.0.0.7:5050");
        assert_eq!(parse(&payload).unwrap().seq, FIRST_SEQ);
        // A bad CRC stays bad, even when the bytes received happen to fit the datagram.
        let fresh = parse(&payload).unwrap().crc_want;
        for got in [0x1234, fresh] {
            out.clear();
            row.id = None;
            w.packet(&row, Some(&frame(&[1, 0, 0, 0, 9], Some(got))), &mut out);
            let (src, _, payload) = udp(&out);
            assert_eq!(src, "0.0.0.0:5050");
            assert!(!parse(&payload).unwrap().crc_ok());
        }
        // The next request to station 7 counts on; a retry keeps its number.
        for kind in ["Request", "Retry"] {
            out.clear();
            row.kind = kind;
            w.packet(&row, Some(&frame(&req, None)), &mut out);
            assert_eq!(parse(&udp(&out).2).unwrap().seq, FIRST_SEQ + 1);
        }
        // Bytes that are no telegram: as they were.
        out.clear();
        row.raw = &[0x11, 0x22];
        w.packet(&row, None, &mut out);
        assert_eq!(udp(&out).2, [0x11, 0x22]);
    }
}
