//! The S-Bus command table: names, request layouts, count conventions and expected replies.
//!
//! Facts from the SAIA design document DD-EPFW6-027 (syntax of codes ≤ 0xA6) and the names
//! Wireshark's `sbus` dissector shows (its Info text, without the `*` it puts on PGU-only
//! commands); see `docs/sbus.md`.
//!
//! Count conventions: an **r-count** byte is the number of elements − 1; a **w-count** byte is
//! the number of bytes that follow it in the telegram (CRC excluded) − 1; a **fio-count** is
//! the number of bits − 1.

use crate::fmt::{push_i64, push_u64};

/// Memory areas, with their S-Bus notation prefix.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Elem {
    Register,
    Flag,
    Input,
    Output,
    Timer,
    Counter,
    DataBlock,
    Text,
    UserMemory,
    ProgramLine,
    Byte,
    Eeprom,
}

impl Elem {
    /// The prefix used in the `Sensor #` column (`R100`, `F5`, `DB4000[2]`, `X12`).
    pub const fn prefix(self) -> &'static str {
        match self {
            Elem::Register => "R",
            Elem::Flag => "F",
            Elem::Input => "I",
            Elem::Output => "O",
            Elem::Timer => "T",
            Elem::Counter => "C",
            Elem::DataBlock => "DB",
            Elem::Text => "X",
            Elem::UserMemory => "UM",
            Elem::ProgramLine => "PL",
            Elem::Byte => "M",
            Elem::Eeprom => "EE",
        }
    }

    /// Flags, inputs and outputs travel as packed bits.
    pub const fn is_bit(self) -> bool {
        matches!(self, Elem::Flag | Elem::Input | Elem::Output)
    }

    /// Timers and counters are non-negative; registers and the rest are shown signed.
    pub const fn is_unsigned(self) -> bool {
        matches!(self, Elem::Timer | Elem::Counter)
    }
}

/// How the request body after `station command` is laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// No body.
    Empty,
    /// `rc addr(2)`: registers, timers, counters.
    ReadWords(Elem),
    /// `rc addr(2)`: flags, inputs, outputs.
    ReadBits(Elem),
    /// `wc addr(2) value(4)×n`, n = (wc − 1) / 4.
    WriteWords(Elem),
    /// `wc addr(2) fio-count data…`, bits = fio-count + 1, data bytes = wc − 2.
    WriteBits(Elem),
    /// `rc db(2) element(2)`.
    ReadDb,
    /// `wc db(2) element(2) value(4)×n`, n = (wc − 3) / 4.
    WriteDb,
    /// `rc addr-prog(3)`: user memory, program lines (4 bytes per element).
    ReadProg(Elem),
    /// `wc addr-prog(3) value(4)×n`, n = (wc − 2) / 4.
    WriteProg(Elem),
    /// `rc text(2) position(2)`.
    ReadText,
    /// `wc text(2) position(2) chars…`, chars = wc − 3.
    WriteText,
    /// `rc addr-68k(3)`: rc + 1 bytes.
    ReadBytes,
    /// `wc addr-68k(3) bytes…`, bytes = wc − 2.
    WriteBytes,
    /// `02 rc addr(2)`.
    ReadEeprom,
    /// `05 addr(2) value(4)`.
    WriteEeprom,
    /// `rc block-type block-number(2)`.
    ReadBlocks,
    /// 8 BCD bytes.
    Clock,
    /// A fixed number of bytes, shown as hex.
    Raw(u8),
    /// `wc` followed by wc + 1 bytes, shown as hex.
    Counted,
    /// Not documented; the length can only come from the framing (or the CRC).
    Undocumented,
}

impl Layout {
    /// Length of the request body after `station command`, given the first bytes of the body
    /// (`Err(n)`: at least `n` body bytes are needed to tell). `None` when the table does not
    /// know the length.
    pub fn body_len(self, body: &[u8]) -> Option<Result<usize, usize>> {
        use Layout::*;
        Some(Ok(match self {
            Empty => 0,
            ReadWords(_) | ReadBits(_) => 3,
            ReadDb | ReadText => 5,
            ReadProg(_) | ReadBytes | ReadEeprom | ReadBlocks => 4,
            WriteEeprom => 7,
            Clock => 8,
            Raw(n) => n as usize,
            WriteWords(_) | WriteBits(_) | WriteDb | WriteProg(_) | WriteText | WriteBytes
            | Counted => match body.first() {
                Some(&wc) => 1 + wc as usize + 1,
                None => return Some(Err(1)),
            },
            Undocumented => return None,
        }))
    }

    /// The element kind a request addresses, if any.
    pub fn elem(self) -> Option<Elem> {
        use Layout::*;
        match self {
            ReadWords(e) | ReadBits(e) | WriteWords(e) | WriteBits(e) | ReadProg(e)
            | WriteProg(e) => Some(e),
            ReadDb | WriteDb => Some(Elem::DataBlock),
            ReadText | WriteText => Some(Elem::Text),
            ReadBytes | WriteBytes => Some(Elem::Byte),
            ReadEeprom | WriteEeprom => Some(Elem::Eeprom),
            _ => None,
        }
    }
}

/// What a request expects back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reply {
    /// An ACK/NAK telegram.
    AckNak,
    /// A response of exactly this many data bytes.
    Fixed(u16),
    /// `n` bytes per element, elements = count.
    PerElem(u8),
    /// Packed bits, ⌈count / 8⌉ bytes.
    Bits,
    /// A length byte (absolute count of the bytes that follow) and the bytes.
    LengthPrefixed,
    /// Not known from the table.
    Unknown,
}

/// One command of the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Command {
    pub code: u8,
    pub name: &'static str,
    pub layout: Layout,
    pub reply: Reply,
    /// Part of the reduced protocol every slave port accepts (others need a PGU port).
    pub reduced: bool,
    /// A PGU command that changes the controller (run/stop/restart/clear/erase, program and
    /// text changes, EEPROM and system writes): flagged in the Note.
    pub pgu_change: bool,
}

const fn c(code: u8, name: &'static str, layout: Layout, reply: Reply) -> Command {
    Command {
        code,
        name,
        layout,
        reply,
        reduced: false,
        pgu_change: false,
    }
}

const fn reduced(mut cmd: Command) -> Command {
    cmd.reduced = true;
    cmd
}

const fn change(mut cmd: Command) -> Command {
    cmd.pgu_change = true;
    cmd
}

/// Looks a command code up (a table lookup: the framers ask for every candidate byte).
#[inline]
pub fn command(code: u8) -> Option<Command> {
    TABLE[code as usize]
}

/// [`lookup`] of every code, built at compile time.
static TABLE: [Option<Command>; 256] = {
    let mut t = [None; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = lookup(i as u8);
        i += 1;
    }
    t
};

/// The command table itself.
const fn lookup(code: u8) -> Option<Command> {
    use Elem::*;
    use Layout::*;
    use Reply::*;
    Some(match code {
        0x00 => reduced(c(code, "Read counter(s)", ReadWords(Counter), PerElem(4))),
        0x01 => reduced(c(code, "Read display register", Empty, Fixed(4))),
        0x02 => reduced(c(code, "Read flag(s)", ReadBits(Flag), Bits)),
        0x03 => reduced(c(code, "Read input(s)", ReadBits(Input), Bits)),
        0x04 => reduced(c(code, "Read real time clock", Empty, Fixed(8))),
        0x05 => reduced(c(code, "Read output(s)", ReadBits(Output), Bits)),
        0x06 => reduced(c(code, "Read register(s)", ReadWords(Register), PerElem(4))),
        0x07 => reduced(c(code, "Read timer(s)", ReadWords(Timer), PerElem(4))),
        0x0A => reduced(c(code, "Write counter(s)", WriteWords(Counter), AckNak)),
        0x0B => reduced(c(code, "Write flag(s)", WriteBits(Flag), AckNak)),
        0x0C => reduced(c(code, "Write real time clock", Clock, AckNak)),
        0x0D => reduced(c(code, "Write output(s)", WriteBits(Output), AckNak)),
        0x0E => reduced(c(code, "Write register(s)", WriteWords(Register), AckNak)),
        0x0F => reduced(c(code, "Write timer(s)", WriteWords(Timer), AckNak)),
        0x13 => c(code, "Read/write multi-medias", Undocumented, Unknown),
        0x14 => reduced(c(code, "Read PCD status, CPU 0", Empty, Fixed(1))),
        0x15 => reduced(c(code, "Read PCD status, CPU 1", Empty, Fixed(1))),
        0x16 => reduced(c(code, "Read PCD status, CPU 2", Empty, Fixed(1))),
        0x17 => reduced(c(code, "Read PCD status, CPU 3", Empty, Fixed(1))),
        0x18 => reduced(c(code, "Read PCD status, CPU 4", Empty, Fixed(1))),
        0x19 => reduced(c(code, "Read PCD status, CPU 5", Empty, Fixed(1))),
        0x1A => reduced(c(code, "Read PCD status, CPU 6", Empty, Fixed(1))),
        0x1B => reduced(c(code, "Read PCD status (own)", Empty, Fixed(1))),
        0x1D => c(code, "Read S-Bus station number", Empty, Fixed(1)),
        0x1E => c(code, "Read user memory", ReadProg(UserMemory), PerElem(4)),
        0x1F => c(code, "Read program line", ReadProg(ProgramLine), PerElem(4)),
        0x20 => c(code, "Read firmware version", Empty, Fixed(9)),
        0x21 => c(code, "Read text", ReadText, Unknown),
        0x22 => c(code, "Read active transition", Raw(1), LengthPrefixed),
        0x23 => change(c(code, "Write user memory", WriteProg(UserMemory), AckNak)),
        0x24 => change(c(
            code,
            "Write program line",
            WriteProg(ProgramLine),
            AckNak,
        )),
        0x25 => change(c(code, "Write text", WriteText, AckNak)),
        0x28 => change(c(code, "Run procedure, CPU 0", Empty, AckNak)),
        0x29 => change(c(code, "Run procedure, CPU 1", Empty, AckNak)),
        0x2A => change(c(code, "Run procedure, CPU 2", Empty, AckNak)),
        0x2B => change(c(code, "Run procedure, CPU 3", Empty, AckNak)),
        0x2C => change(c(code, "Run procedure, CPU 4", Empty, AckNak)),
        0x2D => change(c(code, "Run procedure, CPU 5", Empty, AckNak)),
        0x2E => change(c(code, "Run procedure, CPU 6", Empty, AckNak)),
        0x2F => change(c(code, "Run procedure (own CPU)", Empty, AckNak)),
        0x30 => change(c(code, "Run procedure (all CPUs)", Empty, AckNak)),
        0x32 => change(c(code, "Restart cold CPU 1", Empty, AckNak)),
        0x33 => change(c(code, "Restart cold CPU 2", Empty, AckNak)),
        0x34 => change(c(code, "Restart cold CPU 3", Empty, AckNak)),
        0x35 => change(c(code, "Restart cold CPU 4", Empty, AckNak)),
        0x36 => change(c(code, "Restart cold CPU 5", Empty, AckNak)),
        0x37 => change(c(code, "Restart cold CPU 6", Empty, AckNak)),
        0x38 => change(c(code, "Restart cold own CPU", Empty, AckNak)),
        0x39 => change(c(code, "Restart cold all CPUs", Empty, AckNak)),
        0x3C => change(c(code, "Stop procedure, CPU 0", Empty, AckNak)),
        0x3D => change(c(code, "Stop procedure, CPU 1", Empty, AckNak)),
        0x3E => change(c(code, "Stop procedure, CPU 2", Empty, AckNak)),
        0x3F => change(c(code, "Stop procedure, CPU 3", Empty, AckNak)),
        0x40 => change(c(code, "Stop procedure, CPU 4", Empty, AckNak)),
        0x41 => change(c(code, "Stop procedure, CPU 5", Empty, AckNak)),
        0x42 => change(c(code, "Stop procedure, CPU 6", Empty, AckNak)),
        0x43 => change(c(code, "Stop procedure (own CPU)", Empty, AckNak)),
        0x44 => change(c(code, "Stop procedure (all CPUs)", Empty, AckNak)),
        0x46 => c(code, "Read arithmetic status and ACCU", Empty, Fixed(1)),
        0x47 => c(code, "Read byte(s)", ReadBytes, PerElem(1)),
        0x48 => c(code, "Read halt failure register", Empty, Fixed(26)),
        0x49 => c(code, "Read index register", Empty, Fixed(2)),
        0x4A => c(code, "Read instruction pointer", Empty, Fixed(3)),
        0x4B => c(code, "Find history", Empty, Fixed(5)),
        0x50 => change(c(code, "Write arithmetic status and ACCU", Raw(1), AckNak)),
        0x51 => c(code, "Write byte(s)", WriteBytes, AckNak),
        0x52 => change(c(code, "Write index register", Raw(2), AckNak)),
        0x53 => change(c(code, "Write instruction pointer", Raw(3), AckNak)),
        0x5A => change(c(code, "Clear all (F, O, R, T)", Empty, AckNak)),
        0x5B => change(c(code, "Clear flags", Empty, AckNak)),
        0x5C => change(c(code, "Clear outputs", Empty, AckNak)),
        0x5D => change(c(code, "Clear registers", Empty, AckNak)),
        0x5E => change(c(code, "Clear timers", Empty, AckNak)),
        0x64 => change(c(code, "Restart warm CPU 1", Empty, AckNak)),
        0x65 => change(c(code, "Restart warm CPU 2", Empty, AckNak)),
        0x66 => change(c(code, "Restart warm CPU 3", Empty, AckNak)),
        0x67 => change(c(code, "Restart warm CPU 4", Empty, AckNak)),
        0x68 => change(c(code, "Restart warm CPU 5", Empty, AckNak)),
        0x69 => change(c(code, "Restart warm CPU 6", Empty, AckNak)),
        0x6A => change(c(code, "Restart warm (own CPU)", Empty, AckNak)),
        0x6B => change(c(code, "Restart warm (all CPUs)", Empty, AckNak)),
        0x6E => change(c(code, "Change block", Raw(6), AckNak)),
        0x6F => change(c(code, "Clear history failure", Empty, AckNak)),
        0x70 => change(c(code, "Delete program line", Raw(3), AckNak)),
        0x71 => change(c(code, "Go conditional", Undocumented, AckNak)),
        0x72 => change(c(code, "Insert program line", Raw(3), AckNak)),
        0x73 => change(c(code, "Local cycles", Empty, AckNak)),
        0x74 => change(c(code, "All cycles", Empty, AckNak)),
        0x75 => change(c(code, "Make text", Raw(4), AckNak)),
        0x76 => change(c(code, "Execute single instruction", Undocumented, AckNak)),
        0x77 => change(c(code, "Single step", Empty, AckNak)),
        0x82 => c(code, "XOB 17 interrupt", Empty, AckNak),
        0x83 => c(code, "XOB 18 interrupt", Empty, AckNak),
        0x84 => c(code, "XOB 19 interrupt", Empty, AckNak),
        0x91 => c(code, "Hang-up timeout", Raw(2), AckNak),
        0x96 => reduced(c(code, "Read data block", ReadDb, PerElem(4))),
        0x97 => reduced(c(code, "Write data block", WriteDb, AckNak)),
        0x98 => change(c(code, "Make data block", Undocumented, AckNak)),
        0x99 => change(c(code, "Clear data block", Raw(2), AckNak)),
        0x9A => change(c(code, "Clear text", Raw(2), AckNak)),
        0x9B => c(code, "Read block address", ReadBlocks, PerElem(3)),
        0x9C => c(code, "Read block sizes", ReadBlocks, Unknown),
        0x9D => c(code, "Read current block", Empty, Fixed(3)),
        0x9E => c(code, "Read call stack", Empty, LengthPrefixed),
        0x9F => c(code, "Read DBX", Undocumented, Unknown),
        0xA1 => c(code, "Read user EEPROM register", ReadEeprom, PerElem(4)),
        0xA3 => change(c(code, "Write user EEPROM register", WriteEeprom, AckNak)),
        0xA5 => change(c(code, "Erase flash", Raw(1), AckNak)),
        0xA6 => change(c(code, "Restart cold flag", Empty, AckNak)),
        0xA7 => change(c(code, "Write system buffer", Undocumented, Unknown)),
        0xA8 => c(code, "Read system buffer", Undocumented, Unknown),
        0xA9 => change(c(code, "Read/write block data", Undocumented, Unknown)),
        0xAA => c(code, "Get diagnostic", Undocumented, Unknown),
        0xAB => c(code, "Read system information", Raw(2), Unknown),
        0xAC => change(c(code, "Change blocks on run", Undocumented, Unknown)),
        0xAD => change(c(code, "Flash card telegram", Undocumented, Unknown)),
        0xAE => change(c(code, "Download firmware", Undocumented, Unknown)),
        0xAF => c(
            code,
            "Web server serial communication",
            Undocumented,
            Unknown,
        ),
        _ => return None,
    })
}

/// The count a request carries: elements for reads (r-count + 1), derived for writes.
pub fn request_count(layout: Layout, body: &[u8]) -> Option<u32> {
    use Layout::*;
    let first = *body.first()? as u32;
    Some(match layout {
        ReadWords(_) | ReadBits(_) | ReadDb | ReadProg(_) | ReadText | ReadBytes | ReadBlocks => {
            first + 1
        }
        ReadEeprom => *body.get(1)? as u32 + 1,
        WriteWords(_) => first.saturating_sub(1) / 4,
        WriteBits(_) => *body.get(3)? as u32 + 1,
        WriteDb => first.saturating_sub(3) / 4,
        WriteProg(_) => first.saturating_sub(2) / 4,
        WriteText => first.saturating_sub(3),
        WriteBytes => first.saturating_sub(2),
        WriteEeprom => 1,
        _ => return None,
    })
}

/// The length of the response data a request expects, or `None` when it expects an ACK/NAK
/// or the table does not know. `Some(Err(()))` for a length-prefixed reply.
pub fn expected_data_len(cmd: &Command, body: &[u8]) -> Expect {
    match cmd.reply {
        Reply::AckNak => Expect::AckNak,
        Reply::Fixed(n) => Expect::Data(n as usize),
        Reply::PerElem(n) => match request_count(cmd.layout, body) {
            Some(count) => Expect::Data(count as usize * n as usize),
            None => Expect::Unknown,
        },
        Reply::Bits => match request_count(cmd.layout, body) {
            Some(count) => Expect::Data((count as usize).div_ceil(8)),
            None => Expect::Unknown,
        },
        Reply::LengthPrefixed => Expect::LengthPrefixed,
        Reply::Unknown => Expect::Unknown,
    }
}

/// What should answer a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expect {
    /// Nothing (broadcast).
    Nothing,
    AckNak,
    /// A response with exactly this many data bytes.
    Data(usize),
    /// A response whose first byte counts the bytes after it.
    LengthPrefixed,
    /// A response of unknown length.
    Unknown,
}

impl Expect {
    /// Whether a response with `len` data bytes fits.
    pub fn fits(self, data: &[u8]) -> bool {
        match self {
            Expect::Data(n) => data.len() == n,
            Expect::LengthPrefixed => data.first().is_some_and(|&n| data.len() == 1 + n as usize),
            Expect::Unknown => true,
            Expect::Nothing | Expect::AckNak => false,
        }
    }

    /// The data length when it is known before the data arrives.
    pub fn known_len(self) -> Option<usize> {
        match self {
            Expect::Data(n) => Some(n),
            _ => None,
        }
    }
}

/// ACK/NAK code meanings (Wireshark's `sbus_ack_nak_vals`).
pub fn ack_nak_name(code: u16) -> &'static str {
    match code {
        0x0000 => "ACK",
        0x0001 => "NAK, no reason specified",
        0x0002 => "NAK, because of password",
        0x0003 => "NAK, PGU port is in reduced protocol",
        0x0004 => "NAK, PGU port is already used",
        _ => "NAK, unknown code",
    }
}

/// PCD status characters (commands 0x14-0x1B).
pub fn status_name(ch: u8) -> &'static str {
    match ch {
        b'R' => "run",
        b'S' => "stop",
        b'H' => "halt",
        b'C' => "conditional run",
        b'D' => "disconnected",
        b'X' => "exceptional intermediate",
        _ => "unknown",
    }
}

// Element names and values as the table shows them, shared by the telegram decoding and the
// media lists.

/// A big-endian number of up to four bytes.
pub fn be(bytes: &[u8]) -> u32 {
    bytes.iter().fold(0u32, |a, &b| a << 8 | b as u32)
}

/// Appends the S-Bus name of element `index` after the first (`R101`, `DB4000[3]`).
pub fn push_elem(out: &mut String, elem: Elem, block: u16, addr: u32) {
    match elem {
        Elem::DataBlock => {
            out.push_str("DB");
            push_u64(out, block as u64);
            out.push('[');
            push_u64(out, addr as u64);
            out.push(']');
        }
        Elem::Byte => {
            out.push_str("0x");
            push_hex_width(out, addr, 6);
        }
        Elem::Text => {
            out.push('X');
            push_u64(out, block as u64);
        }
        e => {
            out.push_str(e.prefix());
            push_u64(out, addr as u64);
        }
    }
}

/// `v` as `width` upper-case hex digits.
pub(super) fn push_hex_width(out: &mut String, v: u32, width: usize) {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    for i in (0..width).rev() {
        out.push(HEX[((v >> (i * 4)) & 0xF) as usize] as char);
    }
}

/// An element's value: timers and counters unsigned, registers and the rest signed.
pub(super) fn push_value(out: &mut String, elem: Elem, v: u32) {
    if elem.is_unsigned() {
        push_u64(out, v as u64);
    } else {
        push_i64(out, v as i32 as i64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_consistent() {
        let mut known = 0;
        for code in 0..=255u8 {
            if let Some(cmd) = command(code) {
                known += 1;
                assert_eq!(cmd.code, code);
                assert!(!cmd.name.is_empty());
                assert!(!cmd.name.contains('*'));
            }
        }
        assert_eq!(known, 118);
        assert!(command(0x08).is_none());
        assert!(command(0xFF).is_none());
    }

    #[test]
    fn counts_follow_the_conventions() {
        let read = command(0x06).unwrap();
        // RACOM: B5 00 01 06 03 00 00: r-count 3 = 4 registers
        assert_eq!(request_count(read.layout, &[3, 0, 0]), Some(4));
        assert_eq!(expected_data_len(&read, &[3, 0, 0]), Expect::Data(16));
        assert_eq!(read.layout.body_len(&[]), Some(Ok(3)));
        let flags = command(0x02).unwrap();
        assert_eq!(expected_data_len(&flags, &[7, 0, 0]), Expect::Data(1));
        assert_eq!(expected_data_len(&flags, &[8, 0, 0]), Expect::Data(2));
        // write outputs O16-O19: wc 3, addr 0010, fio-count 3, data 0F
        let wo = command(0x0D).unwrap();
        let body = [3, 0x00, 0x10, 3, 0x0F];
        assert_eq!(wo.layout.body_len(&body), Some(Ok(5)));
        assert_eq!(request_count(wo.layout, &body), Some(4));
        // write R100 = 12345: wc 5 = addr(2) + 4 bytes - 1
        let wr = command(0x0E).unwrap();
        let body = [5, 0, 0x64, 0, 0, 0x30, 0x39];
        assert_eq!(wr.layout.body_len(&body), Some(Ok(7)));
        assert_eq!(request_count(wr.layout, &body), Some(1));
        assert_eq!(wr.layout.body_len(&[]), Some(Err(1)));
        assert_eq!(command(0x9F).unwrap().layout.body_len(&[1, 2]), None);
        let ee = command(0xA1).unwrap();
        assert_eq!(expected_data_len(&ee, &[2, 1, 0, 0]), Expect::Data(8));
    }

    #[test]
    fn expectations() {
        assert!(Expect::Data(4).fits(&[1, 2, 3, 4]));
        assert!(!Expect::Data(4).fits(&[1, 2, 3]));
        assert!(Expect::LengthPrefixed.fits(&[2, 9, 9]));
        assert!(Expect::LengthPrefixed.fits(&[0]));
        assert!(!Expect::LengthPrefixed.fits(&[]));
        assert!(Expect::Unknown.fits(&[]));
        assert_eq!(ack_nak_name(2), "NAK, because of password");
    }
}
