//! What the two reassemblers emit: frames (whole, failing their check, or cut short) and
//! garbage, borrowed from the reassembler so that nothing is copied per frame.

use crate::row::GARBAGE_ROW_MAX;

/// How a frame came out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Check {
    /// Whole, and its checksum passed.
    Ok,
    /// Whole by its length, but the checksum failed.
    Bad,
    /// Cut short (by the next frame start, or the end of the input).
    Cut,
}

/// Who sent a frame and what it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Receiver -> flight controller: channels (F.Port 2: also the OTA control frames).
    Control,
    /// Receiver -> flight controller (or sensor): a poll or a request with an S.Port payload.
    Downlink,
    /// Flight controller (or sensor) -> receiver: the answer.
    Uplink,
    /// An F.Port v1 frame of an unknown type.
    Unknown,
}

/// One frame.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// Time of its first byte (µs since the capture started), `None` for sources without time.
    pub time: Option<u64>,
    /// Stream offset of its first wire byte (for time reconstruction).
    pub offset: u64,
    /// The wire bytes (F.Port v1: with the delimiters it took, stuffed).
    pub raw: &'a [u8],
    /// The unstuffed bytes `len type data crc` (or as many as arrived when cut).
    pub body: &'a [u8],
    pub check: Check,
    pub role: Role,
    /// F.Port 2: the direction of a telemetry frame was guessed (no control frame before it).
    pub guessed: bool,
    /// F.Port v1: a 0x7D was followed by something else than 0x5E/0x5D.
    pub unusual_escape: bool,
    /// F.Port v1: the frame came after a 0xFF padding byte (ArduPilot's `RC_OPTIONS` FPort pad).
    pub pad: bool,
    /// F.Port 2 OTA control frame: read with the other data size than its length byte says
    /// (INAV sizes OTA frames by their type: 32 bytes for data, 24 for start and stop).
    pub ota_resized: bool,
}

impl Frame<'_> {
    /// The frame's type byte (v1: 0x00/0x01/0x81; v2: 0xFF, 0xF0-0xF2, or the physical ID byte
    /// of a telemetry frame), if it arrived.
    pub fn kind(&self) -> Option<u8> {
        self.body.get(1).copied()
    }

    /// The bytes between the type byte and the checksum (empty when cut before them).
    pub fn data(&self) -> &[u8] {
        match self.check {
            Check::Cut => self.body.get(2..).unwrap_or(&[]),
            _ => self
                .body
                .get(2..self.body.len().saturating_sub(1))
                .unwrap_or(&[]),
        }
    }
}

/// Bytes outside any frame (at most [`GARBAGE_ROW_MAX`] per event).
#[derive(Clone, Copy, Debug)]
pub struct Garbage<'a> {
    pub time: Option<u64>,
    pub offset: u64,
    pub bytes: &'a [u8],
}

/// What a reassembler emits.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    Frame(Frame<'a>),
    Garbage(Garbage<'a>),
}

/// A run of garbage being collected.
#[derive(Clone, Debug)]
pub(crate) struct Run {
    pub time: Option<u64>,
    pub offset: u64,
    pub bytes: [u8; GARBAGE_ROW_MAX],
    pub len: usize,
}

impl Default for Run {
    fn default() -> Self {
        Run {
            time: None,
            offset: 0,
            bytes: [0; GARBAGE_ROW_MAX],
            len: 0,
        }
    }
}

impl Run {
    /// Adds a byte at stream offset `offset`; a full run is emitted first.
    #[inline]
    pub fn push(
        &mut self,
        b: u8,
        time: Option<u64>,
        offset: u64,
        emit: &mut impl FnMut(Event<'_>),
    ) {
        if self.len == GARBAGE_ROW_MAX {
            self.flush(emit);
        }
        if self.len == 0 {
            self.time = time;
            self.offset = offset;
        }
        self.bytes[self.len] = b;
        self.len += 1;
    }

    /// Emits what was collected.
    pub fn flush(&mut self, emit: &mut impl FnMut(Event<'_>)) {
        if self.len > 0 {
            emit(Event::Garbage(Garbage {
                time: self.time,
                offset: self.offset,
                bytes: &self.bytes[..self.len],
            }));
            self.len = 0;
        }
    }
}
