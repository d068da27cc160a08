//! The Ether-S-Bus front end: pcap/pcapng packets in, UDP datagrams on the S-Bus port picked
//! out ([`super::ether`]), conversations (client, PLC) paired by sequence number, a statistics
//! row per PLC (bounded); every telegram goes through the shared mapper ([`super::map`]).

use std::fmt::Write as _;
use std::net::{SocketAddr, SocketAddrV4};

use super::ether;
use super::map::{Mapper, put_row};
use super::pairing::{
    self, Conversation, EtherPairing, Expired, Outstanding, TableSizes, TimeoutWhy,
};
use super::stats::{self, MAX_PLCS, StationStats, Totals};
use super::telegram;
use super::{COLUMNS, DEFAULT_ETHER_TIMEOUT_MS, Options};
use crate::fmt::{push_hex, push_u64};
use crate::pcap::{Packet, PcapError};
use crate::protocol::Decoder;
use crate::row::{Class, OutputError, RowOut, RowResult};
use crate::stats::{Problems, Report};

/// Addresses of PLCs beyond [`MAX_PLCS`] remembered to count them once.
const MERGED_PLCS_KEPT: usize = 4_096;

/// A conversation's ends, client and server: the key of [`EtherPairing`], looked up for every
/// datagram. IPv4 ends (nearly every capture) are packed into one word each (address and
/// port), which hash in two steps and compare in two; a pair of `SocketAddr`s hashed its
/// variants, lengths and every address byte one by one and compared as enums (about 100
/// instructions a packet for the lookup). Other ends keep their addresses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Ends {
    V4 {
        client: u64,
        server: u64,
    },
    Other {
        client: SocketAddr,
        server: SocketAddr,
    },
}

impl Ends {
    fn new(client: &SocketAddr, server: &SocketAddr) -> Self {
        /// Address and port in the low 48 bits: distinct ends give distinct words.
        fn word(a: &SocketAddrV4) -> u64 {
            u64::from(a.ip().to_bits()) << 16 | u64::from(a.port())
        }
        match (client, server) {
            (SocketAddr::V4(c), SocketAddr::V4(s)) => Ends::V4 {
                client: word(c),
                server: word(s),
            },
            _ => Ends::Other {
                client: *client,
                server: *server,
            },
        }
    }
}

struct Plc {
    name: String,
    stats: StationStats,
}

/// The Ether-S-Bus decoder: packets in (the source reads the pcap/pcapng container), rows out.
pub struct EtherDecoder {
    core: EtherCore,
}

struct EtherCore {
    port: u16,
    /// Conversations are keyed by their ends; their tag is the PLC's index.
    pairing: EtherPairing<Ends>,
    /// At most [`MAX_PLCS`] + 1 (the last one: every other PLC).
    plcs: Vec<Plc>,
    plc_index: pairing::FastMap<SocketAddr, usize>,
    /// PLCs beyond [`MAX_PLCS`] (at most [`MERGED_PLCS_KEPT`], to count them once).
    merged: pairing::FastMap<SocketAddr, ()>,
    /// The Device column for a PLC beyond [`MAX_PLCS`].
    device: String,
    /// The row mapper (scratch and totals).
    map: Mapper,
    expired: Vec<Expired>,
    last_micros: u64,
    /// Packets whose link type is a serial recording: reported once.
    serial_link_noted: bool,
    failed: bool,
}

impl EtherDecoder {
    pub fn new(opts: &Options) -> Self {
        EtherDecoder {
            core: EtherCore {
                port: opts.port,
                pairing: EtherPairing::new(
                    opts.timeout_ms.unwrap_or(DEFAULT_ETHER_TIMEOUT_MS) * 1000,
                ),
                plcs: Vec::new(),
                plc_index: pairing::FastMap::default(),
                merged: pairing::FastMap::default(),
                device: String::new(),
                map: Mapper::new(false),
                expired: Vec::new(),
                last_micros: 0,
                serial_link_noted: false,
                failed: false,
            },
        }
    }

    pub fn totals(&self) -> &Totals {
        &self.core.map.totals
    }

    /// Sizes of the decoder's tables (for tests of the bounds).
    #[doc(hidden)]
    pub fn table_sizes(&self) -> TableSizes {
        TableSizes {
            plcs: self.core.plcs.len(),
            ..self.core.pairing.sizes()
        }
    }

    /// (PLC name, statistics) for every PLC seen.
    pub fn plc_stats(&self) -> impl Iterator<Item = (&str, &StationStats)> {
        self.core.plcs.iter().map(|p| (p.name.as_str(), &p.stats))
    }

    fn pcap_failed(&mut self, e: &PcapError, out: &mut dyn RowOut) -> RowResult {
        let c = &mut self.core;
        c.failed = true;
        c.map.totals.pcap_error = Some(e.to_string());
        c.map.sc.clear();
        c.map.sc.note(&e.to_string());
        put_row(
            out,
            &mut c.map.sc,
            c.last_micros,
            None,
            "",
            crate::row::kind::TRUNCATED,
            Class::Error,
            "",
            &[],
        )
    }
}

impl EtherCore {
    fn plc(&mut self, addr: SocketAddr) -> usize {
        if let Some(&i) = self.plc_index.get(&addr) {
            return i;
        }
        if self.plc_index.len() < MAX_PLCS {
            let i = self.plcs.len();
            self.plcs.push(Plc {
                name: addr.to_string(),
                stats: StationStats::default(),
            });
            self.plc_index.insert(addr, i);
            return i;
        }
        // Every further PLC shares one statistics row.
        if self.plcs.len() == MAX_PLCS {
            self.plcs.push(Plc {
                name: String::new(),
                stats: StationStats::default(),
            });
        }
        let new = if self.merged.len() < MERGED_PLCS_KEPT {
            self.merged.insert(addr, ()).is_none()
        } else {
            !self.merged.contains_key(&addr)
        };
        if new {
            self.map.totals.plcs_merged += 1;
            let other = &mut self.plcs[MAX_PLCS].name;
            other.clear();
            let _ = write!(other, "other PLCs ({})", self.map.totals.plcs_merged);
        }
        MAX_PLCS
    }

    /// The conversation of `client` and `server` at `t` and its PLC (`request`: the sequence of
    /// a request the pairing will open, see [`EtherPairing::conversation`]). The open request
    /// of a conversation dropped to make room gets its Timeout row here.
    fn conv(
        &mut self,
        client: &SocketAddr,
        server: &SocketAddr,
        t: u64,
        request: Option<u16>,
        out: &mut dyn RowOut,
    ) -> Result<(Conversation, usize), OutputError> {
        let mut fresh = false;
        let ends = Ends::new(client, server);
        let conv = self.pairing.conversation(
            ends,
            t,
            request,
            || {
                fresh = true;
                u32::MAX
            },
            &mut self.expired,
        );
        let plc = if fresh {
            let i = self.plc(*server);
            self.pairing.set_tag(ends, i as u32);
            i
        } else {
            conv.tag as usize
        };
        self.timeout_rows(out).map(|_| (conv, plc))
    }

    /// Timeout rows for the requests the pairing gave up into `self.expired`. Nearly always
    /// there are none: that test is inlined, the rows are written out of line.
    #[inline]
    fn timeout_rows(&mut self, out: &mut dyn RowOut) -> RowResult {
        if self.expired.is_empty() {
            Ok(())
        } else {
            self.write_timeout_rows(out)
        }
    }

    #[cold]
    #[inline(never)]
    fn write_timeout_rows(&mut self, out: &mut dyn RowOut) -> RowResult {
        let mut expired = std::mem::take(&mut self.expired);
        let r = expired
            .iter()
            .try_for_each(|e| self.timeout_row(&e.req, e.why, e.at, out));
        expired.clear();
        self.expired = expired;
        r
    }

    fn sync_forgotten(&mut self) {
        let f = self.pairing.forgotten;
        let t = &mut self.map.totals;
        t.conversations = f.conversations;
        t.conversations_expired = f.expired;
        t.conversations_dropped = f.dropped;
        t.requests_dropped = f.requests;
    }

    fn packet(&mut self, p: &Packet<'_>, out: &mut dyn RowOut) -> RowResult {
        self.map.totals.packets += 1;
        let t = p.time;
        self.expire(t, out)?;
        self.last_micros = t;
        match ether::extract(p.link_type, p.data) {
            ether::Extract::Udp(u) => {
                if u.src.port() != self.port && u.dst.port() != self.port {
                    return Ok(());
                }
                self.datagram(&u, t, out)
            }
            ether::Extract::Fragment { src, dst, ports } => {
                self.map.totals.fragments += 1;
                match ports {
                    Some((sp, dp)) if sp == self.port || dp == self.port => {
                        self.map.sc.clear();
                        self.map.sc.note_with(|n| {
                            let _ = write!(
                                n,
                                "fragmented IP datagram {src}:{sp} -> {dst}:{dp} skipped (not reassembled)"
                            );
                        });
                        put_row(
                            out,
                            &mut self.map.sc,
                            t,
                            None,
                            "",
                            "Fragment",
                            Class::Warning,
                            "",
                            &[],
                        )
                    }
                    _ => Ok(()),
                }
            }
            ether::Extract::Other => Ok(()),
            ether::Extract::Malformed => {
                self.map.totals.malformed += 1;
                Ok(())
            }
            ether::Extract::UnsupportedLink(lt) => {
                self.map.totals.other_links += 1;
                if !self.serial_link_noted {
                    self.serial_link_noted = true;
                    self.map.sc.clear();
                    self.map.sc.note_with(|n| {
                        let _ = write!(
                            n,
                            "packets with link type {lt} are not network traffic; busnoop sbus reads Ethernet, Linux cooked, raw IP and loopback captures"
                        );
                    });
                    return put_row(
                        out,
                        &mut self.map.sc,
                        t,
                        None,
                        "",
                        "Skipped",
                        Class::Warning,
                        "",
                        &[],
                    );
                }
                Ok(())
            }
        }
    }

    fn expire(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        self.pairing.expire(now, &mut self.expired);
        self.timeout_rows(out)
    }

    fn timeout_row(
        &mut self,
        p: &Outstanding,
        why: TimeoutWhy,
        at: u64,
        out: &mut dyn RowOut,
    ) -> RowResult {
        let (name, st) = match self.plcs.get_mut(p.tag as usize) {
            Some(pl) => (pl.name.as_str(), Some(&mut pl.stats)),
            None => ("", None),
        };
        self.map
            .timeout(p, why, at, self.pairing.timeout, name, st, out)
    }

    fn datagram(&mut self, u: &ether::Udp<'_>, t: u64, out: &mut dyn RowOut) -> RowResult {
        self.map.sc.clear();
        let tele = match ether::parse(u.payload) {
            Ok(tele) => tele,
            Err(why) => {
                self.map.totals.not_sbus += 1;
                let kind = match why {
                    ether::NotSbus::Truncated { .. } => {
                        self.map.totals.broken += 1;
                        crate::row::kind::TRUNCATED
                    }
                    _ => crate::row::kind::GARBAGE,
                };
                push_hex(&mut self.map.sc.data, u.payload);
                self.map.sc.note_with(|n| {
                    n.push_str(why.text());
                    let _ = write!(n, " ({} -> {})", u.src, u.dst);
                });
                return put_row(
                    out,
                    &mut self.map.sc,
                    t,
                    None,
                    "",
                    kind,
                    Class::Error,
                    "",
                    u.payload,
                );
            }
        };
        self.map.totals.datagrams += 1;
        self.map.sc.seq(tele.seq);
        if tele.version != 0 || tele.proto != 0 {
            self.map.sc.note_with(|n| {
                let _ = write!(n, "version {}, protocol type {}", tele.version, tele.proto);
            });
        }
        // The PLC is the server: the destination of a request, the source of an answer.
        let (client, server) = if tele.at == telegram::AT_REQUEST {
            (&u.src, &u.dst)
        } else {
            (&u.dst, &u.src)
        };
        // Whether the telegram has the length its attribute asks for (a request its station
        // and command, an ACK/NAK its code). A good request of that shape is opened in the
        // pairing ([`EtherCore::request`]), which the conversation is told beforehand.
        let shaped = match tele.at {
            telegram::AT_REQUEST => tele.telegram.len() >= 2,
            telegram::AT_ACKNAK => tele.telegram.len() == 2,
            _ => true,
        };
        let opens = tele.at == telegram::AT_REQUEST && tele.crc_ok() && shaped;
        let (conv, plc) = self.conv(client, server, t, opens.then_some(tele.seq), out)?;
        if plc >= MAX_PLCS {
            self.device.clear();
            let _ = write!(self.device, "{server}");
        }
        let (id, kind, class, sensor) = if !tele.crc_ok() {
            self.bad_crc(&tele, &conv, plc)
        } else {
            if shaped {
                self.map.totals.valid += 1;
            }
            if tele.at == telegram::AT_REQUEST {
                self.request(&tele, conv, plc, t, out)?
            } else {
                self.answer(&tele, &conv, plc, t)
            }
        };
        let device = if plc < MAX_PLCS {
            &self.plcs[plc].name
        } else {
            &self.device
        };
        put_row(
            out,
            &mut self.map.sc,
            t,
            id,
            device,
            kind,
            class,
            sensor,
            u.payload,
        )
    }

    /// A telegram with a bad CRC: (ID, kind, class, Sensor) of its row.
    fn bad_crc(&mut self, tele: &ether::EtherTele<'_>, conv: &Conversation, plc: usize) -> RowHead {
        self.map.bad_crc(tele.crc_got, tele.crc_want, None);
        self.plcs[plc].stats.crc_errors += 1;
        if tele.at != telegram::AT_REQUEST {
            // The client got an unusable answer: it retries; no Timeout row.
            self.pairing.bad_answer(conv, tele.seq);
        }
        let sc = &mut self.map.sc;
        let (id, sensor) = match tele.at {
            telegram::AT_REQUEST if tele.telegram.len() >= 2 => {
                let tg = tele.telegram;
                telegram::describe_request(tg[0], tg[1], &tg[2..], &mut sc.sensor_no, &mut sc.data);
                (Some(tg[0] as u32), telegram::command_name(tg[1]))
            }
            _ => {
                push_hex(&mut sc.data, tele.telegram);
                (None, "")
            }
        };
        (id, crate::row::kind::BAD_CRC, Class::Error, sensor)
    }

    /// A request with a good CRC: paired by its sequence number, checked for gaps.
    fn request(
        &mut self,
        tele: &ether::EtherTele<'_>,
        conv: Conversation,
        plc: usize,
        t: u64,
        out: &mut dyn RowOut,
    ) -> Result<RowHead, OutputError> {
        let tg = tele.telegram;
        if tg.len() < 2 {
            self.map.totals.broken += 1;
            push_hex(&mut self.map.sc.data, tg);
            self.map.sc.note("request without station and command");
            return Ok((None, crate::row::kind::TRUNCATED, Class::Error, ""));
        }
        let (station, cmd) = (tg[0], tg[1]);
        let mut class = Class::Plain;
        let st = &mut self.plcs[plc].stats;
        let info = self.map.request(station, cmd, &tg[2..], st, &mut class);
        let mut req = Outstanding::new(info, t, true, Some(tele.seq));
        req.tag = plc as u32;
        let (kind, gap) = self.pairing.request(conv, tele.seq, req, &mut self.expired);
        self.timeout_rows(out)?;
        let st = &mut self.plcs[plc].stats;
        if let Some(g) = gap {
            st.seq_gaps += 1;
            self.map.totals.seq_gaps += 1;
            match g.missing {
                Some(m) => {
                    st.seq_missing += m as u64;
                    self.map.sc.note_with(|n| {
                        n.push_str("sequence gap: ");
                        push_u64(n, m as u64);
                        n.push_str(" skipped");
                    });
                }
                None => self
                    .map
                    .sc
                    .note("sequence went backwards (client restart?)"),
            }
        }
        let kind = self.map.request_kind(kind, true, st, &mut class);
        Ok((
            Some(station as u32),
            kind,
            class,
            telegram::command_name(cmd),
        ))
    }

    /// A response or ACK/NAK with a good CRC, paired by its sequence number.
    fn answer(
        &mut self,
        tele: &ether::EtherTele<'_>,
        conv: &Conversation,
        plc: usize,
        t: u64,
    ) -> RowHead {
        let mut class = Class::Plain;
        let answer = self.pairing.answer(conv, tele.seq, t);
        let st = &mut self.plcs[plc].stats;
        let timeout = self.pairing.timeout;
        let info = self
            .map
            .answer(&answer, true, timeout, move |_| st, &mut class);
        let sensor = info.as_ref().map_or("", |i| i.name());
        let paired = info.as_ref().map(|i| (i, &mut self.plcs[plc].stats));
        let kind = if tele.at == telegram::AT_RESPONSE {
            self.map.response(paired, tele.telegram, &mut class);
            "Response"
        } else if let &[hi, lo] = tele.telegram {
            let code = u16::from_be_bytes([hi, lo]);
            self.map.ack_nak(code, None, paired, &mut class)
        } else {
            self.map.totals.broken += 1;
            push_hex(&mut self.map.sc.data, tele.telegram);
            self.map.sc.note("ACK/NAK telegram without a 2-byte code");
            class = Class::Error;
            crate::row::kind::TRUNCATED
        };
        (info.map(|i| i.station as u32), kind, class, sensor)
    }
}

/// What a row needs besides the scratch: ID, kind, class and Sensor.
type RowHead = (Option<u32>, &'static str, Class, &'static str);

impl Decoder for EtherDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    /// Ether-S-Bus comes in packets only ([`Decoder::packet`]); bytes are ignored.
    fn push(&mut self, _data: &[u8], _time: Option<u64>, _out: &mut dyn RowOut) -> RowResult {
        Ok(())
    }

    fn packet(&mut self, p: &Packet<'_>, out: &mut dyn RowOut) -> RowResult {
        if self.core.failed {
            return Ok(());
        }
        let r = self.core.packet(p, out);
        self.core.sync_forgotten();
        r
    }

    fn capture_error(&mut self, e: &PcapError, out: &mut dyn RowOut) -> RowResult {
        if self.core.failed {
            return Ok(());
        }
        self.pcap_failed(e, out)
    }

    fn finish(&mut self, _out: &mut dyn RowOut) -> RowResult {
        let c = &mut self.core;
        c.map.totals.unanswered_at_end += c.pairing.finish();
        c.sync_forgotten();
        Ok(())
    }

    fn valid_frames(&self) -> u64 {
        self.core.map.totals.valid
    }

    fn stats(&self) -> Report {
        let c = &self.core;
        stats::report(
            format!(
                "Ether-S-Bus on UDP port {}, timeout {} ms",
                c.port,
                c.pairing.timeout / 1000
            ),
            c.plcs
                .iter()
                .map(|p| (String::from("-"), p.name.as_str(), &p.stats)),
            &c.map.totals,
            true,
        )
    }

    fn problems(&self) -> Problems {
        stats::problems(&self.core.map.totals)
    }

    fn no_frames_hint(&self) -> &'static str {
        "no Ether-S-Bus datagram yet: check the UDP port (--udp-port) and the tcpdump filter"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::{Ipv4Addr, Ipv6Addr, SocketAddrV6};

    /// Two pairs of ends make the same key exactly when they are the same addresses: IPv4
    /// packed, IPv6 and mixed pairs kept, at the edges of every address byte and port.
    #[test]
    fn ends_are_equal_exactly_when_the_addresses_are() {
        let mut addrs = Vec::new();
        for ip in [
            0u32,
            1,
            0xFF,
            0x100,
            0xC0A8_0164,
            0x0A00_0005,
            0xFFFF_FFFF,
            0x8000_0000,
        ] {
            for port in [0u16, 1, 5050, 0x8000, 0xFFFF] {
                addrs.push(SocketAddr::V4(SocketAddrV4::new(
                    Ipv4Addr::from_bits(ip),
                    port,
                )));
            }
        }
        for ip in [0u128, 1, 0xC0A8_0164, u128::MAX] {
            for port in [0u16, 5050] {
                let v6 = SocketAddrV6::new(Ipv6Addr::from_bits(ip), port, 0, 0);
                addrs.push(SocketAddr::V6(v6));
            }
        }
        let pairs: Vec<_> = addrs
            .iter()
            .flat_map(|&c| addrs.iter().step_by(3).map(move |&s| (c, s)))
            .collect();
        for &a in &pairs {
            let ka = Ends::new(&a.0, &a.1);
            for &b in &pairs {
                assert_eq!(ka == Ends::new(&b.0, &b.1), a == b, "{a:?} {b:?}");
            }
        }
    }
}
