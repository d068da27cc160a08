//! Ether-S-Bus: UDP datagrams out of captured link-layer packets, and the 8-byte Ether-S-Bus
//! header + telegram + CRC inside them.

use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr};

use etherparse::{EtherType, NetSlice, SlicedPacket, TransportSlice};

use super::telegram::crc16;
use crate::pcap::linktype;

/// A UDP datagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Udp<'a> {
    pub src: SocketAddr,
    pub dst: SocketAddr,
    pub payload: &'a [u8],
}

/// What a captured packet holds, as far as busnoop cares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extract<'a> {
    Udp(Udp<'a>),
    /// A fragment of an IP datagram (not reassembled); ports when it is the first fragment.
    Fragment {
        src: IpAddr,
        dst: IpAddr,
        ports: Option<(u16, u16)>,
    },
    /// Not UDP (ARP, TCP, ICMP, other link protocols).
    Other,
    /// Headers that do not parse.
    Malformed,
    /// A link type busnoop does not read as network traffic.
    UnsupportedLink(u32),
}

/// Whether busnoop reads this link type as network traffic (Ether-S-Bus).
pub fn is_network_link(link_type: u32) -> bool {
    matches!(
        link_type,
        linktype::NULL
            | linktype::ETHERNET
            | linktype::RAW_OLD
            | linktype::RAW_OLD_OPENBSD
            | linktype::RAW
            | linktype::LOOP
            | linktype::LINUX_SLL
            | linktype::IPV4
            | linktype::IPV6
            | linktype::LINUX_SLL2
    )
}

/// Finds the UDP datagram in a captured packet.
pub fn extract(link_type: u32, data: &[u8]) -> Extract<'_> {
    if link_type == linktype::ETHERNET
        && let Some(u) = plain_udp4(data)
    {
        return Extract::Udp(u);
    }
    extract_general(link_type, data)
}

/// The common case read at fixed offsets: Ethernet II (no VLAN tag), IPv4 without options and
/// not fragmented, UDP whose length field fits the IP payload. Anything else (`None`) goes to
/// the general parser, which gives the same answer for these packets (a unit test compares
/// the two on mutated packets).
fn plain_udp4(data: &[u8]) -> Option<Udp<'_>> {
    const IP: usize = 14;
    const UDP: usize = IP + 20;
    let h: &[u8; UDP + 8] = data.get(..UDP + 8)?.try_into().ok()?;
    let be16 = |i: usize| u16::from_be_bytes([h[i], h[i + 1]]);
    // EtherType IPv4, version 4 with a 20-byte header, not a fragment, protocol UDP
    if be16(12) != 0x0800 || h[IP] != 0x45 || be16(IP + 6) & 0x3FFF != 0 || h[IP + 9] != 17 {
        return None;
    }
    let total = be16(IP + 2) as usize;
    let ip_end = IP + total;
    let udp_len = be16(UDP + 4) as usize;
    if total < 20 + 8 || ip_end > data.len() || udp_len < 8 || UDP + udp_len > ip_end {
        return None;
    }
    let ip4 = |i: usize| IpAddr::V4(Ipv4Addr::new(h[i], h[i + 1], h[i + 2], h[i + 3]));
    Some(Udp {
        src: SocketAddr::new(ip4(IP + 12), be16(UDP)),
        dst: SocketAddr::new(ip4(IP + 16), be16(UDP + 2)),
        payload: &data[UDP + 8..UDP + udp_len],
    })
}

/// [`extract`] through etherparse, for every link type and header.
fn extract_general(link_type: u32, data: &[u8]) -> Extract<'_> {
    let sliced = match link_type {
        linktype::ETHERNET => SlicedPacket::from_ethernet(data),
        linktype::LINUX_SLL => SlicedPacket::from_linux_sll(data),
        linktype::RAW
        | linktype::RAW_OLD
        | linktype::RAW_OLD_OPENBSD
        | linktype::IPV4
        | linktype::IPV6 => SlicedPacket::from_ip(data),
        linktype::LINUX_SLL2 => {
            // protocol type(2) reserved(2) ifindex(4) arphrd(2) pkttype(1) addrlen(1) addr(8)
            if data.len() < 20 {
                return Extract::Malformed;
            }
            let proto = u16::from_be_bytes([data[0], data[1]]);
            SlicedPacket::from_ether_type(EtherType(proto), &data[20..])
        }
        linktype::NULL | linktype::LOOP => {
            if data.len() < 4 {
                return Extract::Malformed;
            }
            let raw = [data[0], data[1], data[2], data[3]];
            let family = if link_type == linktype::LOOP {
                u32::from_be_bytes(raw)
            } else if u32::from_le_bytes(raw) < 0x100 {
                // NULL: the writer's byte order; families are small numbers.
                u32::from_le_bytes(raw)
            } else {
                u32::from_be_bytes(raw)
            };
            match family {
                2 | 24 | 28 | 30 => SlicedPacket::from_ip(&data[4..]),
                _ => return Extract::Other,
            }
        }
        other => return Extract::UnsupportedLink(other),
    };
    let Ok(p) = sliced else {
        return Extract::Malformed;
    };
    let (src, dst, payload) = match &p.net {
        Some(NetSlice::Ipv4(v4)) => {
            let h = v4.header();
            (
                IpAddr::V4(Ipv4Addr::from(h.source())),
                IpAddr::V4(Ipv4Addr::from(h.destination())),
                v4.payload(),
            )
        }
        Some(NetSlice::Ipv6(v6)) => {
            let h = v6.header();
            (
                IpAddr::V6(Ipv6Addr::from(h.source())),
                IpAddr::V6(Ipv6Addr::from(h.destination())),
                v6.payload(),
            )
        }
        _ => return Extract::Other,
    };
    if payload.ip_number != etherparse::IpNumber::UDP {
        return Extract::Other;
    }
    if payload.fragmented {
        let b = payload.payload;
        // Only the first fragment (offset 0) starts with the UDP header; etherparse leaves the
        // payload unsliced either way, so take the ports when the header fits.
        let first = match &p.net {
            Some(NetSlice::Ipv4(v4)) => v4.header().fragments_offset().value() == 0,
            Some(NetSlice::Ipv6(v6)) => {
                v6.extensions()
                    .first_header()
                    .is_some_and(|_| v6.is_payload_fragmented())
                    && b.len() >= 8
                    && frag6_offset_zero(v6)
            }
            _ => false,
        };
        let ports = (first && b.len() >= 8).then(|| {
            (
                u16::from_be_bytes([b[0], b[1]]),
                u16::from_be_bytes([b[2], b[3]]),
            )
        });
        return Extract::Fragment { src, dst, ports };
    }
    match p.transport {
        Some(TransportSlice::Udp(u)) => Extract::Udp(Udp {
            src: SocketAddr::new(src, u.source_port()),
            dst: SocketAddr::new(dst, u.destination_port()),
            payload: u.payload(),
        }),
        _ => Extract::Malformed,
    }
}

fn frag6_offset_zero(v6: &etherparse::Ipv6Slice<'_>) -> bool {
    use etherparse::Ipv6ExtensionSlice;
    for ext in v6.extensions().clone().into_iter() {
        if let Ipv6ExtensionSlice::Fragment(f) = ext {
            return f.fragment_offset().value() == 0;
        }
    }
    false
}

/// Ether-S-Bus header length (length, version, type, sequence).
pub const HEADER_LEN: usize = 8;
/// Shortest datagram: header, AT, CRC.
pub const MIN_LEN: usize = HEADER_LEN + 1 + 2;

/// A parsed Ether-S-Bus datagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EtherTele<'a> {
    pub length: u32,
    pub version: u8,
    pub proto: u8,
    pub seq: u16,
    pub at: u8,
    /// Between AT and CRC: `station command data` / response data / ACK/NAK code.
    pub telegram: &'a [u8],
    pub crc_got: u16,
    /// CRC-16/XMODEM over bytes 0 … len−3.
    pub crc_want: u16,
}

impl EtherTele<'_> {
    pub fn crc_ok(&self) -> bool {
        self.crc_got == self.crc_want
    }
}

/// Why a UDP payload is not an Ether-S-Bus telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotSbus {
    /// Shorter than header + AT + CRC.
    TooShort,
    /// The length field says more than the datagram holds (cut by the snap length, or lost).
    Truncated { length: u32 },
    /// The length field differs from the datagram length otherwise.
    LengthMismatch { length: u32 },
    /// Version, protocol type or AT out of range.
    Header,
}

impl NotSbus {
    pub fn text(self) -> &'static str {
        match self {
            NotSbus::TooShort => "UDP payload shorter than an Ether-S-Bus telegram",
            NotSbus::Truncated { .. } => "datagram shorter than its Ether-S-Bus length field",
            NotSbus::LengthMismatch { .. } => {
                "Ether-S-Bus length field does not match the datagram length"
            }
            NotSbus::Header => "version, protocol type or attribute out of range",
        }
    }
}

/// Parses a UDP payload with Wireshark's acceptance rules (length field = payload length,
/// version ≤ 1, type ≤ 1, AT ≤ 2), accepting 11-byte datagrams as DIGI and MBL do.
pub fn parse(p: &[u8]) -> Result<EtherTele<'_>, NotSbus> {
    if p.len() < MIN_LEN {
        return Err(NotSbus::TooShort);
    }
    let length = u32::from_be_bytes([p[0], p[1], p[2], p[3]]);
    if (length as usize) > p.len() {
        return Err(NotSbus::Truncated { length });
    }
    if length as usize != p.len() {
        return Err(NotSbus::LengthMismatch { length });
    }
    let (version, proto, at) = (p[4], p[5], p[8]);
    if version > 1 || proto > 1 || at > 2 {
        return Err(NotSbus::Header);
    }
    let n = p.len();
    Ok(EtherTele {
        length,
        version,
        proto,
        seq: u16::from_be_bytes([p[6], p[7]]),
        at,
        telegram: &p[9..n - 2],
        crc_got: u16::from_be_bytes([p[n - 2], p[n - 1]]),
        crc_want: crc16(&p[..n - 2]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmt::parse_hex;

    #[test]
    fn seeds_parse() {
        let req = parse_hex("00 00 00 10 00 00 00 B6 00 4B 06 00 00 00 DC 62").unwrap();
        let t = parse(&req).unwrap();
        assert_eq!((t.length, t.seq, t.at), (16, 0xB6, 0));
        assert_eq!(t.telegram, &[0x4B, 6, 0, 0, 0]);
        assert!(t.crc_ok());
        let mut bad = req.clone();
        bad[15] ^= 1;
        assert!(!parse(&bad).unwrap().crc_ok());
        assert_eq!(parse(&req[..10]), Err(NotSbus::TooShort));
        assert_eq!(parse(&req[..14]), Err(NotSbus::Truncated { length: 16 }));
        let mut v = req.clone();
        v[4] = 2;
        assert_eq!(parse(&v), Err(NotSbus::Header));
    }

    /// The fixed-offset reading of plain Ethernet/IPv4/UDP packets gives what etherparse
    /// gives, on a valid packet with every byte of its headers (and its length) mutated.
    #[test]
    fn plain_udp4_agrees_with_the_general_parser() {
        let mut eth = Vec::new();
        crate::pcap::write::udp4_frame(
            &mut eth,
            ([192, 168, 1, 100], 5050),
            ([10, 0, 0, 5], 40000),
            b"\0\0\0\x0b\0\0\0\x01\0\x01\x02",
        );
        // Ethernet padding after the IP datagram
        let mut padded = eth.clone();
        padded.extend_from_slice(&[0xEE; 12]);
        let mut checked = 0;
        for base in [&eth, &padded] {
            assert!(plain_udp4(base).is_some());
            assert_eq!(
                extract(linktype::ETHERNET, base),
                extract_general(linktype::ETHERNET, base)
            );
            for i in 0..base.len().min(14 + 20 + 8 + 2) {
                for v in [
                    0u8, 1, 2, 0x05, 0x08, 0x11, 0x20, 0x3F, 0x40, 0x45, 0x46, 0x60, 0x80, 0xFF,
                ] {
                    for delta in [0usize, 1] {
                        let mut p = base.clone();
                        p[i] = v;
                        if delta == 1 {
                            p[i] = p[i].wrapping_add(base[i]);
                        }
                        assert_eq!(
                            extract(linktype::ETHERNET, &p),
                            extract_general(linktype::ETHERNET, &p),
                            "byte {i} = {:#04x}",
                            p[i]
                        );
                        checked += 1;
                    }
                }
            }
            for cut in 0..base.len() {
                assert_eq!(
                    extract(linktype::ETHERNET, &base[..cut]),
                    extract_general(linktype::ETHERNET, &base[..cut])
                );
            }
        }
        // IP total length and UDP length, every small value
        for (off, base) in [(16usize, &eth), (38, &eth), (16, &padded), (38, &padded)] {
            for len in 0..120u16 {
                let mut p = base.clone();
                p[off..off + 2].copy_from_slice(&len.to_be_bytes());
                assert_eq!(
                    extract(linktype::ETHERNET, &p),
                    extract_general(linktype::ETHERNET, &p),
                    "offset {off} length {len}"
                );
            }
        }
        assert!(checked > 1000);
    }

    #[test]
    fn extracts_udp_from_link_types() {
        let mut eth = Vec::new();
        crate::pcap::write::udp4_frame(
            &mut eth,
            ([10, 0, 0, 1], 40000),
            ([10, 0, 0, 5], 5050),
            b"hi",
        );
        let Extract::Udp(u) = extract(linktype::ETHERNET, &eth) else {
            panic!()
        };
        assert_eq!(u.dst.to_string(), "10.0.0.5:5050");
        assert_eq!(u.payload, b"hi");
        let ip = &eth[14..];
        assert!(matches!(extract(linktype::RAW, ip), Extract::Udp(_)));
        let mut null = 2u32.to_le_bytes().to_vec();
        null.extend_from_slice(ip);
        assert!(matches!(extract(linktype::NULL, &null), Extract::Udp(_)));
        let mut lo = 2u32.to_be_bytes().to_vec();
        lo.extend_from_slice(ip);
        assert!(matches!(extract(linktype::LOOP, &lo), Extract::Udp(_)));
        let mut sll2 = vec![0x08, 0x00];
        sll2.extend_from_slice(&[0; 18]);
        sll2.extend_from_slice(ip);
        assert!(matches!(
            extract(linktype::LINUX_SLL2, &sll2),
            Extract::Udp(_)
        ));
        let mut sll = vec![0, 0, 0, 1, 0, 6, 1, 2, 3, 4, 5, 6, 0, 0, 0x08, 0x00];
        sll.extend_from_slice(ip);
        assert!(matches!(
            extract(linktype::LINUX_SLL, &sll),
            Extract::Udp(_)
        ));
        // VLAN tag
        let mut vlan = eth[..12].to_vec();
        vlan.extend_from_slice(&[0x81, 0x00, 0x00, 0x05]);
        vlan.extend_from_slice(&eth[12..]);
        assert!(matches!(
            extract(linktype::ETHERNET, &vlan),
            Extract::Udp(_)
        ));
        // first fragment: MF set
        let mut frag = eth.clone();
        frag[14 + 6] = 0x20;
        assert!(matches!(
            extract(linktype::ETHERNET, &frag),
            Extract::Fragment {
                ports: Some((40000, 5050)),
                ..
            }
        ));
        assert_eq!(extract(linktype::ETHERNET, &eth[..20]), Extract::Malformed);
        // IPv6 (raw IP link type)
        let mut v6 = vec![0x60, 0, 0, 0];
        v6.extend_from_slice(&(8u16 + 2).to_be_bytes());
        v6.push(17);
        v6.push(64);
        let mut src = [0u8; 16];
        src[15] = 1;
        let mut dst = [0u8; 16];
        dst[0] = 0xFD;
        dst[15] = 5;
        v6.extend_from_slice(&src);
        v6.extend_from_slice(&dst);
        v6.extend_from_slice(&40000u16.to_be_bytes());
        v6.extend_from_slice(&5050u16.to_be_bytes());
        v6.extend_from_slice(&10u16.to_be_bytes());
        v6.extend_from_slice(&[0, 0]);
        v6.extend_from_slice(b"hi");
        let Extract::Udp(u) = extract(linktype::RAW, &v6) else {
            panic!("{:?}", extract(linktype::RAW, &v6))
        };
        assert_eq!(u.dst.to_string(), "[fd00::5]:5050");
        assert_eq!(u.payload, b"hi");
        let mut lo6 = 30u32.to_le_bytes().to_vec();
        lo6.extend_from_slice(&v6);
        assert!(matches!(extract(linktype::NULL, &lo6), Extract::Udp(_)));
        assert_eq!(extract(147, &eth), Extract::UnsupportedLink(147));
    }
}
