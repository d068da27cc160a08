//! Pure reassemblers for serial S-Bus: bytes and times in, telegrams out, no I/O.
//!
//! * [`DataFramer`] (`serial/data.rs`): SM2 data mode and the secure data mode. A raw 0xB5
//!   starts every telegram (inside a telegram B5 and C5 travel as the DLE pairs `C5 00` /
//!   `C5 01`).
//! * [`BreakFramer`] (`serial/break_mode.rs`): SM0 break mode and SM1 parity mode, which have no
//!   framing bytes; the boundaries are found from the command table, the CRC and time gaps
//!   (the readings it tries are in `serial/readings.rs`).
//!
//! This file holds what both deliver ([`Event`], [`Frame`], [`Tele`], [`Garbage`], [`CrcCheck`],
//! [`Secure`]) and what both use (the time-gap rule, the garbage collector).
//!
//! Both framers track the last request themselves, so their output depends only on the bytes
//! and their times, never on how the input was split into chunks.

mod break_mode;
mod data;
mod readings;

pub use break_mode::BreakFramer;
pub use data::DataFramer;

use super::commands::{self, Expect};
use super::telegram::{AT_ACKNAK, AT_REQUEST, AT_RESPONSE, BROADCAST, CrcBasis};

use crate::row::GARBAGE_ROW_MAX;

/// How a telegram's CRC turned out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrcCheck {
    /// Matched, over these bytes.
    Ok(CrcBasis),
    /// Matched neither reading: the CRC field and the values computed over the escaped and the
    /// unescaped bytes (equal without DLE pairs).
    Bad {
        got: u16,
        escaped: u16,
        unescaped: u16,
    },
    /// No CRC (single-character ACK/NAK), or too short to have one.
    None,
}

impl CrcCheck {
    pub fn ok(self) -> bool {
        matches!(self, CrcCheck::Ok(_))
    }
}

/// The secure data-mode header of a telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Secure {
    /// Outer AT: 0x10 request, 0x11 response.
    pub at: u8,
    pub len: u8,
    pub seq: u8,
    /// Logical length of the inner telegram actually received (a DLE pair counts once).
    pub actual: usize,
    /// SEQ 0xC5 sent without DLE escaping (old firmware, FAQ 101180).
    pub seq_unescaped: bool,
}

impl Secure {
    pub fn len_ok(&self) -> bool {
        self.len as usize == self.actual
    }
}

/// A telegram's meaning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tele<'a> {
    Request {
        station: u8,
        cmd: u8,
        body: &'a [u8],
    },
    Response {
        data: &'a [u8],
    },
    /// A data-mode ACK/NAK telegram (`code`), or a break/parity-mode character (`short`: the
    /// character, 06 or 15, and whether `00` followed it).
    AckNak {
        code: u16,
        short: Option<(u8, bool)>,
    },
    /// A data-mode telegram with an attribute busnoop does not know.
    Other {
        at: u8,
        payload: &'a [u8],
    },
    /// Too short to mean anything (a cut telegram).
    Broken,
}

/// One telegram as the framers deliver it.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// Arrival time of the first byte (µs since the capture started), when the source has times.
    pub time: Option<u64>,
    /// Position of the first byte in the stream.
    pub offset: u64,
    /// Bytes exactly as on the wire (secure header, DLE pairs, break character included).
    pub wire: &'a [u8],
    pub tele: Tele<'a>,
    pub crc: CrcCheck,
    pub secure: Option<Secure>,
    /// A framing problem: cut short, an invalid DLE pair, too long.
    pub problem: Option<&'static str>,
    /// Break/parity mode: a 0x00 (break) preceded the request.
    pub break_before: bool,
    /// Break/parity mode: a response whose length does not fit the request (found by CRC).
    pub length_mismatch: bool,
}

/// Bytes that belong to no telegram.
#[derive(Clone, Copy, Debug)]
pub struct Garbage<'a> {
    pub time: Option<u64>,
    pub offset: u64,
    pub bytes: &'a [u8],
}

/// What the framers emit.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    Frame(Frame<'a>),
    Garbage(Garbage<'a>),
}

/// Splits a standard telegram's logical bytes `AT payload CRC` into its meaning.
fn classify(at: u8, payload: &[u8]) -> Tele<'_> {
    match at {
        AT_REQUEST if payload.len() >= 2 => Tele::Request {
            station: payload[0],
            cmd: payload[1],
            body: &payload[2..],
        },
        AT_RESPONSE => Tele::Response { data: payload },
        AT_ACKNAK if payload.len() == 2 => Tele::AckNak {
            code: u16::from_be_bytes([payload[0], payload[1]]),
            short: None,
        },
        AT_REQUEST | AT_ACKNAK => Tele::Broken,
        _ => Tele::Other { at, payload },
    }
}

/// The answer a request expects, as the framers need it.
fn expect_of(station: u8, cmd: u8, body: &[u8]) -> Expect {
    if station == BROADCAST {
        return Expect::Nothing;
    }
    match commands::command(cmd) {
        Some(c) => commands::expected_data_len(&c, body),
        None => Expect::Unknown,
    }
}

/// Time-gap rule shared by both framers.
#[derive(Clone, Copy, Debug, Default)]
struct GapClock {
    gap: Option<u64>,
    last: Option<u64>,
}

impl GapClock {
    /// True when a byte at `time` follows the previous one after more than the gap.
    fn gap_before(&mut self, time: Option<u64>) -> bool {
        let Some(t) = time else { return false };
        let gap = match (self.gap, self.last) {
            (Some(g), Some(last)) => t > last.saturating_add(g),
            _ => false,
        };
        self.last = Some(t);
        gap
    }

    fn idle(&self, now: u64) -> bool {
        matches!((self.gap, self.last), (Some(g), Some(last)) if now > last.saturating_add(g))
    }
}

/// Garbage collector shared by both framers.
#[derive(Clone, Debug, Default)]
struct GarbageRun {
    bytes: Vec<u8>,
    time: Option<u64>,
    offset: u64,
}

impl GarbageRun {
    fn push(&mut self, b: u8, time: Option<u64>, offset: u64, emit: &mut impl FnMut(&Event<'_>)) {
        if self.bytes.is_empty() {
            self.time = time;
            self.offset = offset;
        }
        self.bytes.push(b);
        if self.bytes.len() == GARBAGE_ROW_MAX {
            self.flush(emit);
        }
    }

    fn flush(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
        if !self.bytes.is_empty() {
            emit(&Event::Garbage(Garbage {
                time: self.time,
                offset: self.offset,
                bytes: &self.bytes,
            }));
            self.bytes.clear();
        }
    }
}

/// What the framer tests share: events with their bytes copied, and feeding helpers.
#[cfg(test)]
mod testing {
    use super::{CrcCheck, Event, Secure, Tele};

    /// A telegram's meaning with its bytes copied.
    #[derive(Clone, Debug, PartialEq, Eq)]
    pub(super) enum T {
        Request {
            station: u8,
            cmd: u8,
            body: Vec<u8>,
        },
        Response {
            data: Vec<u8>,
        },
        AckNak {
            code: u16,
            short: Option<(u8, bool)>,
        },
        Other {
            at: u8,
            payload: Vec<u8>,
        },
        Broken,
    }

    /// A framer event with its bytes copied.
    #[derive(Clone, Debug, PartialEq, Eq)]
    pub(super) enum Ev {
        Frame {
            time: Option<u64>,
            offset: u64,
            wire: Vec<u8>,
            tele: T,
            crc: CrcCheck,
            secure: Option<Secure>,
            problem: Option<&'static str>,
            break_before: bool,
            length_mismatch: bool,
        },
        Garbage {
            time: Option<u64>,
            offset: u64,
            bytes: Vec<u8>,
        },
    }

    impl Ev {
        pub(super) fn of(e: &Event<'_>) -> Ev {
            match e {
                Event::Frame(f) => Ev::Frame {
                    time: f.time,
                    offset: f.offset,
                    wire: f.wire.to_vec(),
                    tele: match f.tele {
                        Tele::Request { station, cmd, body } => T::Request {
                            station,
                            cmd,
                            body: body.to_vec(),
                        },
                        Tele::Response { data } => T::Response {
                            data: data.to_vec(),
                        },
                        Tele::AckNak { code, short } => T::AckNak { code, short },
                        Tele::Other { at, payload } => T::Other {
                            at,
                            payload: payload.to_vec(),
                        },
                        Tele::Broken => T::Broken,
                    },
                    crc: f.crc,
                    secure: f.secure,
                    problem: f.problem,
                    break_before: f.break_before,
                    length_mismatch: f.length_mismatch,
                },
                Event::Garbage(g) => Ev::Garbage {
                    time: g.time,
                    offset: g.offset,
                    bytes: g.bytes.to_vec(),
                },
            }
        }

        /// The telegram of a frame (`None` for garbage).
        pub(super) fn tele(&self) -> Option<&T> {
            match self {
                Ev::Frame { tele, .. } => Some(tele),
                Ev::Garbage { .. } => None,
            }
        }

        pub(super) fn crc(&self) -> CrcCheck {
            match self {
                Ev::Frame { crc, .. } => *crc,
                Ev::Garbage { .. } => CrcCheck::None,
            }
        }

        pub(super) fn wire(&self) -> &[u8] {
            match self {
                Ev::Frame { wire, .. } => wire,
                Ev::Garbage { bytes, .. } => bytes,
            }
        }

        pub(super) fn offset(&self) -> u64 {
            match self {
                Ev::Frame { offset, .. } | Ev::Garbage { offset, .. } => *offset,
            }
        }
    }

    /// A framer as the tests drive it (data mode's and break mode's, whose own methods these
    /// are).
    pub(super) trait Framer {
        fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>));
        fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>));
    }

    impl Framer for super::data::DataFramer {
        fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
            super::data::DataFramer::push(self, data, time, emit)
        }
        fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
            super::data::DataFramer::finish(self, emit)
        }
    }

    impl Framer for super::break_mode::BreakFramer {
        fn push(&mut self, data: &[u8], time: Option<u64>, emit: &mut impl FnMut(&Event<'_>)) {
            super::break_mode::BreakFramer::push(self, data, time, emit)
        }
        fn finish(&mut self, emit: &mut impl FnMut(&Event<'_>)) {
            super::break_mode::BreakFramer::finish(self, emit)
        }
    }

    /// Feeds `segments` (bytes, time) to `f`; returns the events before `finish` and all
    /// events.
    pub(super) fn feed(
        f: &mut impl Framer,
        segments: &[(Vec<u8>, Option<u64>)],
    ) -> (usize, Vec<Ev>) {
        let mut evs = Vec::new();
        for (bytes, time) in segments {
            f.push(bytes, *time, &mut |e| evs.push(Ev::of(e)));
        }
        let before = evs.len();
        f.finish(&mut |e| evs.push(Ev::of(e)));
        (before, evs)
    }

    /// Splits timed segments into single bytes that keep their segment's time.
    pub(super) fn bytewise(segments: &[(Vec<u8>, Option<u64>)]) -> Vec<(Vec<u8>, Option<u64>)> {
        segments
            .iter()
            .flat_map(|(bytes, time)| bytes.iter().map(move |&b| (vec![b], *time)))
            .collect()
    }
}
