//! [`PcapStream`]: the pure incremental pcap/pcapng reader (see [`crate::pcap`]).

use super::{MAX_INTERFACES, MAX_RECORD, Packet, PcapError};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Iface {
    link_type: u32,
    snaplen: u32,
    /// Timestamp units per second: 10^n or 2^n.
    units: Resolution,
    offset_secs: i64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Resolution {
    Pow10(u8),
    Pow2(u8),
}

impl Resolution {
    fn to_micros(self, ts: u64) -> i64 {
        let ts = ts as i128;
        let v = match self {
            Resolution::Pow10(6) => ts,
            Resolution::Pow10(n) if n < 6 => ts * 10i128.pow(6 - n as u32),
            Resolution::Pow10(n) => ts / 10i128.pow((n as u32 - 6).min(38)),
            Resolution::Pow2(n) => (ts * 1_000_000) >> n.min(127),
        };
        v.clamp(i64::MIN as i128, i64::MAX as i128) as i64
    }

    /// The nanoseconds a stamp of `ts` units holds past its whole microseconds
    /// ([`Packet::nanos`]); `None` when a unit is a microsecond or longer. Truncates as
    /// [`Resolution::to_micros`] does, so that the two together are the time in ns.
    fn sub_micros(self, ts: u64) -> Option<u16> {
        let ts = ts as i128;
        let ns = match self {
            Resolution::Pow10(n) if n <= 6 => return None,
            Resolution::Pow10(n) if n <= 9 => ts * 10i128.pow(9 - n as u32),
            Resolution::Pow10(n) => ts / 10i128.pow((n as u32 - 9).min(38)),
            // 2^20 units a second are the first that are shorter than a microsecond.
            Resolution::Pow2(n) if n < 20 => return None,
            Resolution::Pow2(n) => (ts * 1_000_000_000) >> n.min(127),
        };
        Some((ns % 1000) as u16)
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Format {
    /// Not yet known (fewer than 4 bytes seen).
    Unknown,
    Pcap {
        big: bool,
        nanos: bool,
        link_type: u32,
        /// The header's snap length (0: none given).
        snaplen: u32,
        header_done: bool,
    },
    Pcapng {
        big: bool,
        /// The first [`MAX_INTERFACES`] interfaces of the section.
        ifaces: Vec<Iface>,
        /// Interfaces the section defined (kept or not).
        defined: u64,
        in_section: bool,
    },
    /// A previous error: nothing more is read.
    Failed,
}

/// Pure incremental pcap/pcapng reader.
#[derive(Clone, Debug)]
pub struct PcapStream {
    format: Format,
    /// Bytes of an incomplete record carried over between pushes.
    pending: Vec<u8>,
    /// Stream offset of the first byte not yet consumed.
    offset: u64,
    /// Last packet time (for simple packet blocks, which carry none).
    last_ts: i64,
    /// [`Packet::time`] of the packet before: a packet stamped outside the calendar gets it.
    last_time: u64,
    /// Time of the first packet: [`Packet::time`] counts from it.
    first_ts: Option<i64>,
    /// The link type of a classic pcap's header or of the first pcapng interface, kept after
    /// an error (see [`PcapStream::link_type`]).
    first_link_type: Option<u32>,
    packets: u64,
    /// Longest record or block accepted.
    max_record: usize,
    /// Bytes skipped since the last packet (a damaged record, a packet that could not be
    /// placed): told on the next packet ([`Packet::skipped`]), or by [`PcapStream::finish`].
    skip: u64,
    /// Where the bytes skipped last began.
    skip_offset: u64,
    /// Bytes skipped in all, and how many times.
    skipped_total: u64,
    skips: u64,
    /// Looking for the next plausible classic record after a damaged one.
    resyncing: bool,
}

impl Default for PcapStream {
    fn default() -> Self {
        Self::new()
    }
}

fn rd16(b: &[u8], big: bool) -> u16 {
    let a = [b[0], b[1]];
    if big {
        u16::from_be_bytes(a)
    } else {
        u16::from_le_bytes(a)
    }
}

fn rd32(b: &[u8], big: bool) -> u32 {
    let a = [b[0], b[1], b[2], b[3]];
    if big {
        u32::from_be_bytes(a)
    } else {
        u32::from_le_bytes(a)
    }
}

/// Outcome of parsing at the start of a buffer.
enum Step {
    /// Consumed this many bytes.
    Took(usize),
    /// Needs at least this many bytes in total.
    Need(usize),
}

impl PcapStream {
    pub fn new() -> Self {
        PcapStream {
            format: Format::Unknown,
            pending: Vec::new(),
            offset: 0,
            last_ts: 0,
            last_time: 0,
            first_ts: None,
            first_link_type: None,
            packets: 0,
            max_record: MAX_RECORD,
            skip: 0,
            skip_offset: 0,
            skipped_total: 0,
            skips: 0,
            resyncing: false,
        }
    }

    /// A reader that refuses records longer than `max` bytes (at most [`MAX_RECORD`]) with
    /// [`PcapError::BadLength`].
    pub fn with_max_record(max: usize) -> Self {
        PcapStream {
            max_record: max.min(MAX_RECORD),
            ..Self::new()
        }
    }

    /// Time stamp of the first packet (the capture's start), once one was read.
    pub fn start(&self) -> Option<i64> {
        self.first_ts
    }

    /// The capture's link type as soon as its headers tell it: a classic pcap's, or that of the
    /// first interface a pcapng described; for a recording of a capture without packets.
    pub fn link_type(&self) -> Option<u32> {
        self.first_link_type
    }

    /// Bytes of an unfinished record held until the rest arrives.
    pub fn buffered(&self) -> usize {
        self.pending.len()
    }

    /// µs since the first packet for a packet stamped `ts` (the first one sets the start).
    fn time(&mut self, ts: i64) -> u64 {
        if !super::in_calendar(ts) {
            return self.last_time;
        }
        let first = *self.first_ts.get_or_insert(ts);
        self.last_time = ts.saturating_sub(first).max(0) as u64;
        self.last_time
    }

    /// pcapng interfaces kept for the current section (for tests of the bound).
    #[doc(hidden)]
    pub fn interfaces_kept(&self) -> usize {
        match &self.format {
            Format::Pcapng { ifaces, .. } => ifaces.len(),
            _ => 0,
        }
    }

    /// Bytes skipped in all (damaged records, packets that could not be placed) and how many
    /// times the reader skipped.
    pub fn skipped(&self) -> (u64, u64) {
        (self.skipped_total, self.skips)
    }

    /// Notes `n` bytes skipped at stream offset `at`.
    fn skip_bytes(&mut self, at: u64, n: u64) {
        if self.skip == 0 {
            self.skip_offset = at;
            self.skips += 1;
        }
        self.skip += n;
        self.skipped_total += n;
    }

    /// Packets emitted so far.
    pub fn packets(&self) -> u64 {
        self.packets
    }

    /// Stream position of the first byte not yet consumed.
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// Feeds bytes; `emit` is called for every packet completed by them. After an error the
    /// stream stays failed and ignores further input.
    pub fn push(
        &mut self,
        bytes: &[u8],
        emit: &mut impl FnMut(Packet<'_>),
    ) -> Result<(), PcapError> {
        if self.format == Format::Failed {
            return Ok(());
        }
        let r = self.push_inner(bytes, emit);
        if r.is_err() {
            self.format = Format::Failed;
            self.pending = Vec::new();
        }
        r
    }

    fn push_inner(
        &mut self,
        mut bytes: &[u8],
        emit: &mut impl FnMut(Packet<'_>),
    ) -> Result<(), PcapError> {
        // Complete a carried-over unit first, taking only the bytes it needs.
        while !self.pending.is_empty() {
            let mut pending = std::mem::take(&mut self.pending);
            match self.step(&pending, emit)? {
                Step::Took(n) => {
                    if n < pending.len() {
                        pending.drain(..n);
                        self.pending = pending;
                    }
                }
                Step::Need(need) => {
                    if bytes.is_empty() {
                        self.pending = pending;
                        return Ok(());
                    }
                    let take = need.saturating_sub(pending.len()).min(bytes.len());
                    pending.extend_from_slice(&bytes[..take]);
                    bytes = &bytes[take..];
                    self.pending = pending;
                }
            }
        }
        // Parse straight from the input; keep the incomplete tail.
        while !bytes.is_empty() {
            match self.step(bytes, emit)? {
                Step::Took(n) => bytes = &bytes[n..],
                Step::Need(_) => {
                    self.pending.extend_from_slice(bytes);
                    break;
                }
            }
        }
        Ok(())
    }

    /// End of input: an error when the input stopped inside a record (or was not a capture).
    pub fn finish(&mut self) -> Result<(), PcapError> {
        if self.format == Format::Failed {
            return Ok(());
        }
        if self.resyncing || self.skip > 0 {
            // Damaged bytes to the end, no record after them.
            let skipped = std::mem::take(&mut self.skip) + self.pending.len() as u64;
            let offset = if skipped > self.pending.len() as u64 {
                self.skip_offset
            } else {
                self.offset
            };
            self.format = Format::Failed;
            return Err(PcapError::Damaged { offset, skipped });
        }
        if self.pending.is_empty() {
            return Ok(());
        }
        let have = self.pending.len();
        let need = match self.step(&self.pending.clone(), &mut |_| {}) {
            Ok(Step::Need(n)) => n,
            _ => have,
        };
        if self.format == Format::Unknown {
            let mut m = [0u8; 4];
            m[..have.min(4)].copy_from_slice(&self.pending[..have.min(4)]);
            self.format = Format::Failed;
            return Err(PcapError::BadMagic(m));
        }
        self.format = Format::Failed;
        Err(PcapError::Truncated {
            offset: self.offset,
            missing: need.saturating_sub(have) as u64,
        })
    }

    /// Parses one unit (file header, record or block) at the start of `b`.
    fn step(&mut self, b: &[u8], emit: &mut impl FnMut(Packet<'_>)) -> Result<Step, PcapError> {
        let r = match &self.format {
            Format::Unknown => self.detect(b),
            Format::Pcap { header_done, .. } => {
                if *header_done {
                    self.pcap_records(b, emit)
                } else {
                    self.pcap_header(b)
                }
            }
            Format::Pcapng { .. } => self.pcapng_block(b, emit),
            Format::Failed => Ok(Step::Took(b.len())),
        }?;
        if let Step::Took(n) = r {
            self.offset += n as u64;
        }
        Ok(r)
    }

    fn detect(&mut self, b: &[u8]) -> Result<Step, PcapError> {
        if b.len() < 4 {
            return Ok(Step::Need(4));
        }
        let m = [b[0], b[1], b[2], b[3]];
        let (big, nanos) = match m {
            [0xD4, 0xC3, 0xB2, 0xA1] => (false, false),
            [0xA1, 0xB2, 0xC3, 0xD4] => (true, false),
            [0x4D, 0x3C, 0xB2, 0xA1] => (false, true),
            [0xA1, 0xB2, 0x3C, 0x4D] => (true, true),
            [0x0A, 0x0D, 0x0D, 0x0A] => {
                self.format = Format::Pcapng {
                    big: false,
                    ifaces: Vec::new(),
                    defined: 0,
                    in_section: false,
                };
                return Ok(Step::Took(0));
            }
            _ => return Err(PcapError::BadMagic(m)),
        };
        self.format = Format::Pcap {
            big,
            nanos,
            link_type: 0,
            snaplen: 0,
            header_done: false,
        };
        Ok(Step::Took(0))
    }

    fn pcap_header(&mut self, b: &[u8]) -> Result<Step, PcapError> {
        if b.len() < 24 {
            return Ok(Step::Need(24));
        }
        if let Format::Pcap {
            big,
            link_type,
            snaplen,
            header_done,
            ..
        } = &mut self.format
        {
            *snaplen = rd32(&b[16..], *big);
            // The upper bits may carry FCS information; the link type is the low 16 bits.
            *link_type = rd32(&b[20..], *big) & 0xFFFF;
            *header_done = true;
            self.first_link_type.get_or_insert(*link_type);
        }
        Ok(Step::Took(24))
    }

    /// The classic pcap records at the start of `b`: every complete one, in one call (a read
    /// of 256 KiB holds thousands, and a call per record matched the format and moved the
    /// offset for each). Stops before a record that is incomplete or too long: that one comes
    /// back as the first of the next call, which reports it as before (`Need`, or the error at
    /// its offset).
    fn pcap_records(
        &mut self,
        b: &[u8],
        emit: &mut impl FnMut(Packet<'_>),
    ) -> Result<Step, PcapError> {
        let Format::Pcap {
            big,
            nanos,
            link_type,
            snaplen,
            ..
        } = self.format
        else {
            unreachable!("pcap_records on a pcap stream")
        };
        if self.resyncing {
            if b.len() < 16 {
                return Ok(Step::Need(16));
            }
            return Ok(self.pcap_resync(b, 0, big, nanos, snaplen));
        }
        let mut at = 0;
        while let Some(r) = b.get(at..) {
            let Some(h) = r.first_chunk::<16>() else {
                return Ok(if at == 0 {
                    Step::Need(16)
                } else {
                    Step::Took(at)
                });
            };
            // The record header's four words in the file's byte order (one test of the order).
            let word = |i: usize| [h[i], h[i + 1], h[i + 2], h[i + 3]];
            let [secs, frac, incl, orig] = if big {
                [0, 4, 8, 12].map(|i| u32::from_be_bytes(word(i)))
            } else {
                [0, 4, 8, 12].map(|i| u32::from_le_bytes(word(i)))
            };
            let incl = incl as usize;
            if !self.sound_record(incl, orig, snaplen) {
                // A damaged header (a flipped bit): the records before it go out first, then
                // the reader looks for the next plausible one.
                if at > 0 {
                    return Ok(Step::Took(at));
                }
                self.resyncing = true;
                return Ok(self.pcap_resync(b, 1, big, nanos, snaplen));
            }
            let Some(data) = r.get(16..16 + incl) else {
                return Ok(if at == 0 {
                    Step::Need(16 + incl)
                } else {
                    Step::Took(at)
                });
            };
            let (secs, frac) = (secs as i64, frac as i64);
            let ts = secs * 1_000_000 + if nanos { frac / 1000 } else { frac };
            self.last_ts = ts;
            self.packets += 1;
            let time = self.time(ts);
            emit(Packet {
                ts_micros: ts,
                nanos: nanos.then_some((frac % 1000) as u16),
                time,
                link_type,
                data,
                orig_len: orig,
                interface: 0,
                skipped: std::mem::take(&mut self.skip),
            });
            at += 16 + incl;
        }
        Ok(Step::Took(at))
    }

    /// A classic record header whose lengths can be right: no more captured than on the
    /// wire, within the snap length (with room for writers that exceed it a little) and the
    /// record limit. (Its time is not judged: a flipped bit there is a time out of range, which
    /// costs no record, see [`super::in_calendar`].)
    fn sound_record(&self, incl: usize, orig: u32, snaplen: u32) -> bool {
        incl <= orig as usize
            && incl <= self.max_record
            && (snaplen == 0 || incl <= (snaplen as usize).max(262_144))
    }

    /// After a damaged classic record header (at the start of `b`, or before it: `from` is
    /// where the search goes on): skips to the next offset where a plausible record starts (sound lengths, its fraction of a second below one
    /// second, its time within a day before and a year after the last good record) and the
    /// record after it is plausible too, or the input ends right after it. Without one in
    /// `b`, skips all but a header's worth; waits for more input when a candidate's successor
    /// is not in `b` yet.
    fn pcap_resync(&mut self, b: &[u8], from: usize, big: bool, nanos: bool, snaplen: u32) -> Step {
        let rd = |at: usize| -> Option<[u32; 4]> {
            let h = b.get(at..at + 16)?;
            Some([0, 4, 8, 12].map(|i| rd32(&h[i..], big)))
        };
        let last_secs = (self.packets > 0).then_some(self.last_ts.div_euclid(1_000_000));
        let plausible = |[secs, frac, incl, orig]: [u32; 4]| {
            let frac_max = if nanos { 1_000_000_000 } else { 1_000_000 };
            let near = last_secs
                .is_none_or(|l| (l - 86_400..=l + 366 * 86_400).contains(&i64::from(secs)));
            frac < frac_max && near && self.sound_record(incl as usize, orig, snaplen)
        };
        for q in from..b.len() {
            let Some(h) = rd(q) else {
                // Not a whole header left: wait for more.
                break;
            };
            if !plausible(h) {
                continue;
            }
            // Its successor must be plausible too: waited for when it is not here yet, so that
            // how the input is cut never changes the choice.
            let next = q + 16 + h[2] as usize;
            match rd(next) {
                Some(n) if !plausible(n) => continue,
                Some(_) => {}
                None => {
                    if q > 0 {
                        self.skip_bytes(self.offset, q as u64);
                    }
                    return if q > 0 {
                        Step::Took(q)
                    } else {
                        Step::Need(next + 16)
                    };
                }
            }
            if q > 0 {
                self.skip_bytes(self.offset, q as u64);
            }
            self.resyncing = false;
            return Step::Took(q);
        }
        let keep = 15.min(b.len().saturating_sub(1));
        let n = b.len() - keep;
        self.skip_bytes(self.offset, n as u64);
        Step::Took(n)
    }

    /// After a damaged pcapng block at the start of `b` (4-byte aligned, as every block; `from`
    /// is where the search goes on, 0 when it went on past the start of an earlier call):
    /// skips to the next 4-byte step where a block of a known type with a sound length starts
    /// (its trailing length is checked when the block is parsed; a wrong one resynchronises
    /// again). Without one in `b`, skips to where the unexamined last bytes begin.
    fn pcapng_resync(&mut self, b: &[u8], from: usize, big: bool) -> Step {
        const TYPES: [u32; 9] = [1, 2, 3, 4, 5, 6, 10, 0x0BAD, 0x4000_0BAD];
        self.resyncing = true;
        let mut q = from;
        while q + 8 <= b.len() {
            let kind = rd32(&b[q..], big);
            let len = rd32(&b[q + 4..], big) as usize;
            let sound = (12..=self.max_record).contains(&len) && len.is_multiple_of(4);
            let shb = b[q..q + 4] == [0x0A, 0x0D, 0x0D, 0x0A];
            if shb {
                if q > 0 {
                    self.skip_bytes(self.offset, q as u64);
                }
                self.resyncing = false;
                return Step::Took(q);
            }
            if TYPES.contains(&kind) && sound {
                // The trailing length (`sound`: at least 12) must match; waited for when it is
                // not here yet, so that how the input is cut never changes the choice.
                match b.get(q + len - 4..q + len) {
                    None if q > 0 => {
                        // Examined again, at the start, when the rest is here.
                        self.skip_bytes(self.offset, q as u64);
                        return Step::Took(q);
                    }
                    None => return Step::Need(len),
                    Some(t) if rd32(t, big) as usize == len => {
                        if q > 0 {
                            self.skip_bytes(self.offset, q as u64);
                        }
                        self.resyncing = false;
                        return Step::Took(q);
                    }
                    Some(_) => {}
                }
            }
            q += 4;
        }
        // Every 4-byte step before `q` was looked at.
        if q == 0 {
            return Step::Need(8);
        }
        self.skip_bytes(self.offset, q as u64);
        Step::Took(q)
    }

    fn pcapng_block(
        &mut self,
        b: &[u8],
        emit: &mut impl FnMut(Packet<'_>),
    ) -> Result<Step, PcapError> {
        if b.len() < 12 {
            return Ok(Step::Need(12));
        }
        let is_shb = b[..4] == [0x0A, 0x0D, 0x0D, 0x0A];
        if self.resyncing {
            let big = match &self.format {
                Format::Pcapng { big, .. } => *big,
                _ => false,
            };
            return Ok(self.pcapng_resync(b, 0, big));
        }
        let (section_big, in_section) = match &self.format {
            Format::Pcapng {
                big, in_section, ..
            } => (*big, *in_section),
            _ => (false, false),
        };
        let big = if is_shb {
            match b[8..12] {
                [0x1A, 0x2B, 0x3C, 0x4D] => true,
                [0x4D, 0x3C, 0x2B, 0x1A] => false,
                // A damaged section header inside the file: skipped like any damaged block.
                _ if in_section => return Ok(self.pcapng_resync(b, 4, section_big)),
                _ => {
                    return Err(PcapError::BadMagic([b[8], b[9], b[10], b[11]]));
                }
            }
        } else {
            section_big
        };
        let block_type = rd32(b, big);
        let len = rd32(&b[4..], big) as usize;
        if len < 12 || !len.is_multiple_of(4) || len > self.max_record {
            if in_section {
                return Ok(self.pcapng_resync(b, 4, big));
            }
            return Err(PcapError::BadLength {
                offset: self.offset,
                len: len as u64,
            });
        }
        if b.len() < len {
            return Ok(Step::Need(len));
        }
        if rd32(&b[len - 4..], big) as usize != len {
            if in_section {
                return Ok(self.pcapng_resync(b, 4, big));
            }
            return Err(PcapError::LengthMismatch {
                offset: self.offset,
            });
        }
        let body = &b[8..len - 4];
        let offset = self.offset;
        let Format::Pcapng {
            big: fbig,
            ifaces,
            defined,
            in_section,
        } = &mut self.format
        else {
            unreachable!("pcapng_block on a pcapng stream")
        };
        if is_shb {
            *fbig = big;
            ifaces.clear();
            ifaces.shrink_to(16);
            *defined = 0;
            *in_section = true;
            return Ok(Step::Took(len));
        }
        if !*in_section {
            return Err(PcapError::NoSection { offset });
        }
        match block_type {
            // Interface description block.
            1 => {
                if body.len() < 8 {
                    return Err(PcapError::BadLength {
                        offset,
                        len: len as u64,
                    });
                }
                let mut iface = Iface {
                    link_type: rd16(body, big) as u32,
                    snaplen: rd32(&body[4..], big),
                    units: Resolution::Pow10(6),
                    offset_secs: 0,
                };
                let mut opts = &body[8..];
                while opts.len() >= 4 {
                    let code = rd16(opts, big);
                    let olen = rd16(&opts[2..], big) as usize;
                    let padded = olen.div_ceil(4) * 4;
                    if code == 0 || opts.len() < 4 + olen {
                        break;
                    }
                    let v = &opts[4..4 + olen];
                    match (code, olen) {
                        (9, 1) => {
                            iface.units = if v[0] & 0x80 != 0 {
                                Resolution::Pow2(v[0] & 0x7F)
                            } else {
                                Resolution::Pow10(v[0])
                            }
                        }
                        (14, 8) => {
                            let a = [v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]];
                            iface.offset_secs = if big {
                                i64::from_be_bytes(a)
                            } else {
                                i64::from_le_bytes(a)
                            };
                        }
                        _ => {}
                    }
                    opts = opts.get(4 + padded..).unwrap_or(&[]);
                }
                *defined += 1;
                self.first_link_type.get_or_insert(iface.link_type);
                if ifaces.len() < MAX_INTERFACES {
                    ifaces.push(iface);
                }
            }
            // Enhanced packet block and the obsolete packet block.
            6 | 2 => {
                if body.len() < 20 {
                    return Err(PcapError::BadLength {
                        offset,
                        len: len as u64,
                    });
                }
                let interface = if block_type == 6 {
                    rd32(body, big)
                } else {
                    rd16(body, big) as u32
                };
                let ts = (rd32(&body[4..], big) as u64) << 32 | rd32(&body[8..], big) as u64;
                let cap = rd32(&body[12..], big) as usize;
                let orig = rd32(&body[16..], big);
                if cap > body.len() - 20 {
                    // A damaged captured length inside a sound block: the block is skipped.
                    self.skip_bytes(offset, len as u64);
                    return Ok(Step::Took(len));
                }
                let Some(iface) = ifaces.get(interface as usize) else {
                    // An interface beyond the ones kept, or one never described (a flipped
                    // bit): the packet cannot be placed. It is skipped and counted; the
                    // packets after it are read.
                    self.skip_bytes(offset, len as u64);
                    return Ok(Step::Took(len));
                };
                let ts_micros = iface
                    .units
                    .to_micros(ts)
                    .saturating_add(iface.offset_secs.saturating_mul(1_000_000));
                let nanos = iface.units.sub_micros(ts);
                let link_type = iface.link_type;
                self.last_ts = ts_micros;
                self.packets += 1;
                let time = self.time(ts_micros);
                emit(Packet {
                    ts_micros,
                    nanos,
                    time,
                    link_type,
                    data: &body[20..20 + cap],
                    orig_len: orig,
                    interface,
                    skipped: std::mem::take(&mut self.skip),
                });
            }
            // Simple packet block: interface 0, no time.
            3 => {
                if body.len() < 4 {
                    return Err(PcapError::BadLength {
                        offset,
                        len: len as u64,
                    });
                }
                let Some(iface) = ifaces.first() else {
                    self.skip_bytes(offset, len as u64);
                    return Ok(Step::Took(len));
                };
                let orig = rd32(body, big);
                let mut cap = (orig as usize).min(body.len() - 4);
                if iface.snaplen > 0 {
                    cap = cap.min(iface.snaplen as usize);
                }
                let link_type = iface.link_type;
                self.packets += 1;
                let time = self.time(self.last_ts);
                emit(Packet {
                    ts_micros: self.last_ts,
                    // No time of its own: the last one's, to the microsecond.
                    nanos: None,
                    time,
                    link_type,
                    data: &body[4..4 + cap],
                    orig_len: orig,
                    interface: 0,
                    skipped: std::mem::take(&mut self.skip),
                });
            }
            _ => {}
        }
        Ok(Step::Took(len))
    }
}

#[cfg(test)]
mod tests;
