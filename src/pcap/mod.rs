//! pcap and pcapng: the one place that knows the capture containers.
//!
//! * `read`: [`PcapStream`], the pure incremental reader: bytes in (any chunking), [`Packet`]s
//!   out, so a `tcpdump -U -w -` pipe yields each packet as soon as its record is complete. It
//!   reads classic pcap (both byte orders, microsecond and nanosecond magics) and pcapng
//!   (section header blocks in both byte orders, several sections, interface description blocks
//!   with their link type, `if_tsresol` and `if_tsoffset`, enhanced, simple and the obsolete
//!   packet blocks; other blocks are skipped). Memory stays bounded: a record or block longer
//!   than its limit ([`MAX_RECORD`]) is an error, never an allocation.
//! * `write`: classic pcap records (the recorder, tests, benchmarks and tools).
//! * `write_ng`: pcapng blocks (recordings named `.pcapng`, the frame export).
//! * `rtac`: the RTAC serial encapsulation busnoop records serial lines in.
//! * [`linktype`]: every link type busnoop names, and [`Packets`], packets with their bytes in one
//!   buffer, as the capture source hands them on.
//!
//! The sources (`crate::source`) open the containers; protocols see [`Packet`]s only.

pub(crate) mod read;
pub(crate) mod rtac;
pub mod write;
pub(crate) mod write_ng;

pub use read::PcapStream;

use std::fmt;

use crate::time::Anchor;

/// Longest record or block accepted (Wireshark's limit for pcapng blocks is 16 MiB too).
pub const MAX_RECORD: usize = 16 * 1024 * 1024;

/// pcapng interfaces kept per section (24 bytes each); a packet naming a later one is an error.
pub const MAX_INTERFACES: usize = 65_536;

/// Well-known link types (LINKTYPE_* values).
pub mod linktype {
    pub const NULL: u32 = 0;
    pub const ETHERNET: u32 = 1;
    pub const RAW_OLD: u32 = 12;
    pub const RAW_OLD_OPENBSD: u32 = 14;
    pub const RAW: u32 = 101;
    pub const LOOP: u32 = 108;
    pub const LINUX_SLL: u32 = 113;
    /// LINKTYPE_USER0 to USER15 (147-162): private use; busnoop's exports take one per
    /// protocol (S.Port USER0, SAB USER1, …), read by the Lua dissectors in contrib/wireshark.
    pub const USER0: u32 = 147;
    pub const USER1: u32 = 148;
    pub const USER2: u32 = 149;
    pub const USER3: u32 = 150;
    pub const USER4: u32 = 151;
    pub const USER5: u32 = 152;
    pub const USER6: u32 = 153;
    pub const IPV4: u32 = 228;
    pub const IPV6: u32 = 229;
    pub const RTAC_SERIAL: u32 = 250;
    pub const LINUX_SLL2: u32 = 276;
}

/// One captured packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Packet<'a> {
    /// Capture time in µs since the Unix epoch.
    pub ts_micros: i64,
    /// Nanoseconds past `ts_micros` (0 to 999) when the capture stamps its packets finer than
    /// microseconds (a nanosecond pcap, a pcapng interface with such an `if_tsresol`); `None`
    /// otherwise. Only a recording uses them (`--record` keeps a nanosecond capture's times);
    /// the decoders work in µs.
    pub nanos: Option<u16>,
    /// Capture time in µs since the first packet of the stream (0 for a packet stamped before
    /// it): the `time` every decoder works with. A packet whose `ts_micros` is not
    /// [`in_calendar`] gets the time of the packet before it (and does not start the stream).
    pub time: u64,
    /// LINKTYPE_* of the interface that captured it.
    pub link_type: u32,
    /// The captured bytes (possibly fewer than `orig_len`).
    pub data: &'a [u8],
    /// Length of the packet on the wire.
    pub orig_len: u32,
    /// pcapng interface ID within its section (0 for classic pcap).
    pub interface: u32,
    /// Bytes of the capture skipped right before this packet (0 normally): a damaged record
    /// header the reader resynchronised after, or a packet it could not place (an interface
    /// beyond [`MAX_INTERFACES`] or never described).
    pub skipped: u64,
}

/// Why a stream cannot be read on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PcapError {
    /// Neither a pcap magic nor a pcapng section header.
    BadMagic([u8; 4]),
    /// A record or block length that cannot be right.
    BadLength { offset: u64, len: u64 },
    /// A pcapng block whose trailing length differs from its leading one.
    LengthMismatch { offset: u64 },
    /// A pcapng packet for an interface no IDB described.
    UnknownInterface { offset: u64, interface: u32 },
    /// A pcapng packet for an interface beyond [`MAX_INTERFACES`].
    TooManyInterfaces { offset: u64, interface: u32 },
    /// A pcapng block before the first section header.
    NoSection { offset: u64 },
    /// The input ended inside a record.
    Truncated { offset: u64, missing: u64 },
    /// Damaged bytes before the end of the input, skipped, with no record after them.
    Damaged { offset: u64, skipped: u64 },
}

impl fmt::Display for PcapError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PcapError::BadMagic(m) => write!(
                f,
                "not a pcap or pcapng file (starts with {:02X} {:02X} {:02X} {:02X})",
                m[0], m[1], m[2], m[3]
            ),
            PcapError::BadLength { offset, len } => {
                write!(f, "impossible record length {len} at byte {offset}")
            }
            PcapError::LengthMismatch { offset } => write!(
                f,
                "pcapng block at byte {offset} has different leading and trailing lengths"
            ),
            PcapError::UnknownInterface { offset, interface } => write!(
                f,
                "pcapng packet at byte {offset} names interface {interface}, which no interface description block defined"
            ),
            PcapError::TooManyInterfaces { offset, interface } => write!(
                f,
                "pcapng packet at byte {offset} names interface {interface}; busnoop keeps the first {MAX_INTERFACES} interfaces of a section"
            ),
            PcapError::NoSection { offset } => {
                write!(f, "pcapng block at byte {offset} before any section header")
            }
            PcapError::Truncated { offset, missing } => write!(
                f,
                "the capture ends inside the record at byte {offset} ({missing} bytes missing)"
            ),
            PcapError::Damaged { offset, skipped } => write!(
                f,
                "{skipped} damaged bytes before the end at byte {offset} skipped: no valid \
                 record after them"
            ),
        }
    }
}

impl std::error::Error for PcapError {}

/// The link type of a classic pcap file from its first 24 bytes (all 32 bits of the field).
pub fn link_type(header: &[u8]) -> Option<u32> {
    let magic: [u8; 4] = header.get(..4)?.try_into().ok()?;
    let lt: [u8; 4] = header.get(20..24)?.try_into().ok()?;
    match magic {
        [0xD4, 0xC3, 0xB2, 0xA1] | [0x4D, 0x3C, 0xB2, 0xA1] => Some(u32::from_le_bytes(lt)),
        [0xA1, 0xB2, 0xC3, 0xD4] | [0xA1, 0xB2, 0x3C, 0x4D] => Some(u32::from_be_bytes(lt)),
        _ => None,
    }
}

/// The link type of the first interface of a pcapng file, from its first bytes: the section
/// header block and the interface description block after it (either byte order). `None` when
/// `prefix` is not pcapng, ends before that field, or the block after the section header is not
/// an interface description.
pub fn pcapng_link_type(prefix: &[u8]) -> Option<u32> {
    pcapng_first_interface(prefix).ok().flatten()
}

/// More bytes are needed to tell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NeedMore;

/// Like [`pcapng_link_type`], telling apart "more bytes needed" (`Err(NeedMore)`) from "not
/// determinable from the start" (`Ok(None)`: not pcapng, or another block first).
pub fn pcapng_first_interface(prefix: &[u8]) -> Result<Option<u32>, NeedMore> {
    let u32_at = |at: usize, le: bool| -> Result<u32, NeedMore> {
        let b: [u8; 4] = prefix
            .get(at..at + 4)
            .ok_or(NeedMore)?
            .try_into()
            .map_err(|_| NeedMore)?;
        Ok(if le {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    };
    match prefix.get(..4) {
        None => return Err(NeedMore),
        Some(m) if m != [0x0A, 0x0D, 0x0D, 0x0A] => return Ok(None),
        Some(_) => {}
    }
    let le = match prefix.get(8..12).ok_or(NeedMore)? {
        [0x4D, 0x3C, 0x2B, 0x1A] => true,
        [0x1A, 0x2B, 0x3C, 0x4D] => false,
        _ => return Ok(None),
    };
    let shb_len = u32_at(4, le)? as usize;
    if shb_len < 28 || !shb_len.is_multiple_of(4) {
        return Ok(None);
    }
    if u32_at(shb_len, le)? != 1 {
        return Ok(None);
    }
    let b: [u8; 2] = prefix
        .get(shb_len + 8..shb_len + 10)
        .ok_or(NeedMore)?
        .try_into()
        .map_err(|_| NeedMore)?;
    Ok(Some(if le {
        u16::from_le_bytes(b)
    } else {
        u16::from_be_bytes(b)
    } as u32))
}

/// An interface a pcapng file describes: its link type and its name (`if_name`), as
/// [`pcapng_interfaces`] reads them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Interface {
    pub link_type: u32,
    pub name: Option<String>,
}

/// The interfaces the first section of a pcapng file describes before its first packet, from
/// the file's first bytes (either byte order; blocks that are neither interfaces nor packets are
/// passed over). Empty when `prefix` is not pcapng; a list cut short by the end of `prefix` or by
/// a block that cannot be right ends there.
pub fn pcapng_interfaces(prefix: &[u8]) -> Vec<Interface> {
    let mut found = Vec::new();
    if prefix.get(..4) != Some(&[0x0A, 0x0D, 0x0D, 0x0A][..]) {
        return found;
    }
    let le = match prefix.get(8..12) {
        Some([0x4D, 0x3C, 0x2B, 0x1A]) => true,
        Some([0x1A, 0x2B, 0x3C, 0x4D]) => false,
        _ => return found,
    };
    let u32_at = |at: usize| -> Option<u32> {
        let b: [u8; 4] = prefix.get(at..at.checked_add(4)?)?.try_into().ok()?;
        Some(if le {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    };
    let u16_at = |at: usize| -> Option<u16> {
        let b: [u8; 2] = prefix.get(at..at.checked_add(2)?)?.try_into().ok()?;
        Some(if le {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    };
    let Some(mut at) = u32_at(4).map(|l| l as usize) else {
        return found;
    };
    while let (Some(kind), Some(len)) = (u32_at(at), u32_at(at + 4)) {
        let len = len as usize;
        if len < 12 || !len.is_multiple_of(4) || at + len > prefix.len() {
            break;
        }
        match kind {
            // Interface description: link type, reserved, snap length, options.
            1 if len >= 20 => {
                let Some(link_type) = u16_at(at + 8) else {
                    break;
                };
                let mut name = None;
                let mut opt = at + 16;
                while let (Some(code), Some(olen)) = (u16_at(opt), u16_at(opt + 2)) {
                    let olen = olen as usize;
                    let Some(value) = prefix.get(opt + 4..opt + 4 + olen) else {
                        break;
                    };
                    if code == 0 || opt + 4 + olen > at + len - 4 {
                        break;
                    }
                    if code == 2 {
                        name = Some(String::from_utf8_lossy(value).into_owned());
                    }
                    opt += 4 + olen.next_multiple_of(4);
                }
                found.push(Interface {
                    link_type: u32::from(link_type),
                    name,
                });
            }
            // Another section, or a packet: the interfaces before the first packet are known.
            0x0A0D_0D0A | 2 | 3 | 6 => break,
            _ => {}
        }
        at += len;
    }
    found
}

/// The wall-clock time of a packet stamped `ts_micros` (the capture's start, for `--time abs`),
/// when it is one.
pub fn anchor(ts_micros: i64) -> Option<Anchor> {
    in_calendar(ts_micros)
        .then(|| chrono::DateTime::from_timestamp_micros(ts_micros).map(Anchor::Instant))
        .flatten()
}

/// A time stamp (µs since the Unix epoch) within the years 1 to 9999, the ones RFC 3339 and
/// the table's `Time` column can write. A stamp outside (a flipped top bit, `if_tsresol` 10^0
/// with a far time) is corrupt: the reader gives its packet the time of the one before, and the
/// sources say so in a `TimeJump` row.
pub fn in_calendar(ts_micros: i64) -> bool {
    // 0001-01-01T00:00:00Z and 9999-12-31T23:59:59.999999Z.
    (-62_135_596_800_000_000..=253_402_300_799_999_999).contains(&ts_micros)
}

/// Where one packet of [`Packets`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Slot {
    ts_micros: i64,
    nanos: Option<u16>,
    time: u64,
    link_type: u32,
    orig_len: u32,
    interface: u32,
    skipped: u64,
    /// Its bytes end here in the shared buffer.
    end: usize,
}

/// Owned packets with their bytes in one buffer: two allocations per batch, whatever the
/// number of packets.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Packets {
    data: Vec<u8>,
    slots: Vec<Slot>,
}

impl Packets {
    /// Room for `bytes` bytes of packet data in about `bytes / 64` packets, so that a batch read
    /// from `bytes` input bytes does not grow its buffers by doubling (the driver holds up to 16
    /// batches in flight; doubled buffers were half empty).
    pub fn for_input(bytes: usize) -> Self {
        Packets {
            data: Vec::with_capacity(bytes),
            slots: Vec::with_capacity(bytes / 64 + 1),
        }
    }

    /// Appends a copy of `p`.
    pub fn push(&mut self, p: &Packet<'_>) {
        self.data.extend_from_slice(p.data);
        self.slots.push(Slot {
            ts_micros: p.ts_micros,
            nanos: p.nanos,
            time: p.time,
            link_type: p.link_type,
            orig_len: p.orig_len,
            interface: p.interface,
            skipped: p.skipped,
            end: self.data.len(),
        });
    }

    /// The `i`th packet.
    pub fn get(&self, i: usize) -> Option<Packet<'_>> {
        let s = self.slots.get(i)?;
        let start = i.checked_sub(1).map_or(0, |j| self.slots[j].end);
        Some(Packet {
            ts_micros: s.ts_micros,
            nanos: s.nanos,
            time: s.time,
            link_type: s.link_type,
            data: &self.data[start..s.end],
            orig_len: s.orig_len,
            interface: s.interface,
            skipped: s.skipped,
        })
    }

    /// The packets in order.
    pub fn iter(&self) -> impl Iterator<Item = Packet<'_>> {
        (0..self.slots.len()).filter_map(|i| self.get(i))
    }

    /// Number of packets.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Captured bytes of all packets together.
    pub fn bytes(&self) -> usize {
        self.data.len()
    }

    /// Empties the batch, keeping its buffers.
    pub fn clear(&mut self) {
        self.data.clear();
        self.slots.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn link_type_from_header() {
        let mut out = Vec::new();
        write::header(&mut out, linktype::RTAC_SERIAL);
        assert_eq!(link_type(&out), Some(linktype::RTAC_SERIAL));
        let mut be = vec![0xA1, 0xB2, 0xC3, 0xD4];
        be.extend_from_slice(&[0; 16]);
        be.extend_from_slice(&1u32.to_be_bytes());
        assert_eq!(link_type(&be), Some(1));
        assert_eq!(link_type(b"hello"), None);
    }

    #[test]
    fn pcapng_link_type_from_first_interface() {
        let mut out = Vec::new();
        write_ng::section_header(&mut out);
        assert_eq!(pcapng_link_type(&out), None);
        write_ng::interface(&mut out, 250, Some("/dev/ttyUSB0"), None);
        assert_eq!(pcapng_link_type(&out), Some(250));
        assert_eq!(pcapng_link_type(&out[..out.len() - 30]), Some(250));
        assert_eq!(pcapng_link_type(b"\x0A\x0D\x0D\x0A"), None);
        let mut classic = Vec::new();
        write::header(&mut classic, 250);
        assert_eq!(pcapng_link_type(&classic), None);
    }

    #[test]
    fn pcapng_interfaces_with_their_names() {
        let mut out = Vec::new();
        write_ng::section_header(&mut out);
        assert_eq!(pcapng_interfaces(&out), []);
        write_ng::interface(&mut out, 250, Some("/dev/ttyUSB0"), Some("S.Port"));
        write_ng::interface(&mut out, 250, None, None);
        write_ng::interface(&mut out, 147, Some("rx.bin"), None);
        let whole = out.len();
        write_ng::packet(&mut out, 0, 5, b"x", None);
        write_ng::interface(&mut out, 1, Some("after a packet"), None);
        let found = pcapng_interfaces(&out);
        let names: Vec<(u32, Option<&str>)> = found
            .iter()
            .map(|i| (i.link_type, i.name.as_deref()))
            .collect();
        assert_eq!(
            names,
            [
                (250, Some("/dev/ttyUSB0")),
                (250, None),
                (147, Some("rx.bin"))
            ]
        );
        // Cut inside the third interface: the first two.
        assert_eq!(pcapng_interfaces(&out[..whole - 4]).len(), 2);
        let mut classic = Vec::new();
        write::header(&mut classic, 250);
        assert_eq!(pcapng_interfaces(&classic), []);
    }

    #[test]
    fn packets_keep_every_field_and_byte() {
        let p = |ts, data: &'static [u8]| Packet {
            ts_micros: ts,
            nanos: Some(ts as u16 * 3),
            time: ts as u64 * 2,
            link_type: 1,
            data,
            orig_len: 99,
            interface: 3,
            skipped: ts as u64,
        };
        let want = [p(5, b"ab"), p(6, b""), p(7, b"cde")];
        let mut b = Packets::default();
        for x in &want {
            b.push(x);
        }
        assert_eq!(b.iter().collect::<Vec<_>>(), want);
        assert_eq!((b.len(), b.bytes(), b.get(3)), (3, 5, None));
        b.clear();
        assert!(b.is_empty());
    }
}
