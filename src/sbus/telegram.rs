//! S-Bus telegrams: CRC, DLE escaping, encoders (for tests and benchmarks), and the decoding of
//! request and response contents into the table's `Sensor #` and `Data` text.

use super::commands::{self, Command, Elem, Expect, Layout, be, push_elem, push_hex_width};
use super::media::{
    LazyWords, MediaSpans, RangeText, media_range, medium_letter, push_bits, push_words,
};
use crate::fmt::{push_hex, push_i64, push_u64};

/// Frame-sync byte of the serial data mode.
pub const FS: u8 = 0xB5;
/// DLE: `C5 00` stands for B5, `C5 01` for C5.
pub const DLE: u8 = 0xC5;
/// Attribute bytes.
pub const AT_REQUEST: u8 = 0x00;
pub const AT_RESPONSE: u8 = 0x01;
pub const AT_ACKNAK: u8 = 0x02;
pub const AT_SECURE_REQUEST: u8 = 0x10;
pub const AT_SECURE_RESPONSE: u8 = 0x11;
/// Break/parity-mode single-character ACK and NAK.
pub const ACK_CHAR: u8 = 0x06;
pub const NAK_CHAR: u8 = 0x15;
/// Station 255 is a broadcast (no answer).
pub const BROADCAST: u8 = 255;

/// CRC-16/XMODEM (poly 0x1021, init 0), sent most significant byte first.
pub const CRC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_XMODEM);

const fn crc_table() -> [u16; 256] {
    let mut t = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut v = (i as u16) << 8;
        let mut k = 0;
        while k < 8 {
            v = if v & 0x8000 != 0 {
                (v << 1) ^ 0x1021
            } else {
                v << 1
            };
            k += 1;
        }
        t[i] = v;
        i += 1;
    }
    t
}

/// Slice-by-8 tables: `TABLES[0]` is the byte table, `TABLES[s][i]` the CRC of byte `i`
/// followed by `s` zero bytes.
static TABLES: [[u16; 256]; 8] = crc_tables();

const fn crc_tables() -> [[u16; 256]; 8] {
    let mut t = [[0u16; 256]; 8];
    t[0] = crc_table();
    let mut s = 1;
    while s < 8 {
        let mut i = 0;
        while i < 256 {
            let prev = t[s - 1][i];
            t[s][i] = (prev << 8) ^ t[0][(prev >> 8) as usize];
            i += 1;
        }
        s += 1;
    }
    t
}

/// One step of CRC-16/XMODEM (for incremental searches; equal to [`CRC`] over whole slices).
#[inline]
pub fn crc_step(crc: u16, byte: u8) -> u16 {
    (crc << 8) ^ TABLES[0][((crc >> 8) as u8 ^ byte) as usize]
}

/// CRC-16/XMODEM of `bytes` continued from `crc`, eight bytes a step: telegrams are mostly
/// shorter than the 16 bytes a step of a slice-by-16 table takes, whose byte-by-byte tail then
/// did most of the work (6-8 % of a serial S-Bus run).
pub fn crc16_from(mut crc: u16, bytes: &[u8]) -> u16 {
    let t = &TABLES;
    let mut steps = bytes.chunks_exact(8);
    for c in &mut steps {
        crc = t[7][usize::from((crc >> 8) as u8 ^ c[0])]
            ^ t[6][usize::from(crc as u8 ^ c[1])]
            ^ t[5][usize::from(c[2])]
            ^ t[4][usize::from(c[3])]
            ^ t[3][usize::from(c[4])]
            ^ t[2][usize::from(c[5])]
            ^ t[1][usize::from(c[6])]
            ^ t[0][usize::from(c[7])];
    }
    // The tail (up to seven bytes) in steps of four, two and one byte: three dependent
    // steps at most instead of seven, each a table lookup after the one before.
    let mut tail = steps.remainder();
    if let [c0, c1, c2, c3, rest @ ..] = tail {
        crc = t[3][usize::from((crc >> 8) as u8 ^ c0)]
            ^ t[2][usize::from(crc as u8 ^ c1)]
            ^ t[1][usize::from(*c2)]
            ^ t[0][usize::from(*c3)];
        tail = rest;
    }
    if let [c0, c1, rest @ ..] = tail {
        crc = t[1][usize::from((crc >> 8) as u8 ^ c0)] ^ t[0][usize::from(crc as u8 ^ c1)];
        tail = rest;
    }
    if let [b] = tail {
        crc = crc_step(crc, *b);
    }
    crc
}

/// CRC-16/XMODEM of `bytes`.
pub fn crc16(bytes: &[u8]) -> u16 {
    crc16_from(0, bytes)
}

/// Appends `byte` DLE-escaped (data mode, every byte after the FS).
pub fn push_dle(out: &mut Vec<u8>, byte: u8) {
    match byte {
        FS => out.extend_from_slice(&[DLE, 0x00]),
        DLE => out.extend_from_slice(&[DLE, 0x01]),
        b => out.push(b),
    }
}

/// Which bytes a data-mode CRC was computed over (the public sources disagree).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrcBasis {
    /// Over the on-wire bytes, DLE pairs included (the vendor example, FAQ 100713).
    Escaped,
    /// Over the logical bytes after undoing the DLE pairs.
    Unescaped,
    /// The telegram has no DLE pair before its CRC: both readings are the same.
    Both,
}

impl CrcBasis {
    pub fn name(self) -> &'static str {
        match self {
            CrcBasis::Escaped => "escaped",
            CrcBasis::Unescaped => "unescaped",
            CrcBasis::Both => "both",
        }
    }
}

/// Encodes a standard data-mode telegram `B5 AT payload CRC` with DLE escaping; the CRC is
/// computed over the escaped (`Escaped`, also used for `Both`) or the unescaped bytes.
pub fn encode_data(out: &mut Vec<u8>, at: u8, payload: &[u8], basis: CrcBasis) {
    let start = out.len();
    out.push(FS);
    push_dle(out, at);
    for &b in payload {
        push_dle(out, b);
    }
    let crc = match basis {
        CrcBasis::Escaped | CrcBasis::Both => crc16(&out[start..]),
        CrcBasis::Unescaped => crc16_from(crc16(&[FS, at]), payload),
    };
    push_dle(out, (crc >> 8) as u8);
    push_dle(out, crc as u8);
}

/// Encodes a secure data-mode telegram: `B5 10|11 LEN SEQ` + a standard telegram.
pub fn encode_secure(
    out: &mut Vec<u8>,
    outer_at: u8,
    seq: u8,
    at: u8,
    payload: &[u8],
    basis: CrcBasis,
) {
    out.push(FS);
    push_dle(out, outer_at);
    push_dle(out, (payload.len() + 4) as u8);
    push_dle(out, seq);
    encode_data(out, at, payload, basis);
}

/// Encodes a break/parity-mode request `station command body CRC`.
pub fn encode_break_request(out: &mut Vec<u8>, station: u8, cmd: u8, body: &[u8]) {
    let start = out.len();
    out.push(station);
    out.push(cmd);
    out.extend_from_slice(body);
    let crc = crc16(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// Encodes a break/parity-mode response `data CRC`.
pub fn encode_break_response(out: &mut Vec<u8>, data: &[u8]) {
    out.extend_from_slice(data);
    out.extend_from_slice(&crc16(data).to_be_bytes());
}

/// Encodes an Ether-S-Bus UDP payload `length version type sequence AT telegram CRC`.
pub fn encode_ether(out: &mut Vec<u8>, seq: u16, at: u8, telegram: &[u8]) {
    let start = out.len();
    let len = 8 + 1 + telegram.len() + 2;
    out.extend_from_slice(&(len as u32).to_be_bytes());
    out.push(0);
    out.push(0);
    out.extend_from_slice(&seq.to_be_bytes());
    out.push(at);
    out.extend_from_slice(telegram);
    let crc = crc16(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// What a request asked for, kept for pairing its answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReqInfo {
    pub station: u8,
    pub cmd: u8,
    /// The first element's address (data-block element for 0x96/0x97).
    pub addr: u32,
    /// Data block or text number.
    pub block: u16,
    pub elem: Option<Elem>,
    pub count: u32,
    pub expect: Expect,
}

impl ReqInfo {
    pub fn command(&self) -> Option<Command> {
        commands::command(self.cmd)
    }

    /// The command's name (or `Command 0xNN`-like text for unknown codes).
    pub fn name(&self) -> &'static str {
        command_name(self.cmd)
    }
}

/// The name of a command code.
pub fn command_name(cmd: u8) -> &'static str {
    match commands::command(cmd) {
        Some(c) => c.name,
        None => "Unknown command",
    }
}

/// The `Sensor #` of a read (`R57`) and its range in the Data cell (`R57..R63`), which starts
/// with the same name: formatted once, copied once. A medium's range is written as one piece
/// ([`media_range`]). A range names no number (`R57..R63`, `0x000010 n=8`: no token is a
/// medium's `name=number`): recorded in `media` as a list of none when it is the whole cell,
/// so that the row need not read the cell back to find that.
fn push_name_and_range(
    name: &mut String,
    data: &mut String,
    elem: Elem,
    block: u16,
    addr: u32,
    count: u32,
    media: Option<&mut MediaSpans>,
) {
    let media = MediaSpans::begin(media, data);
    if let Some(letter) = medium_letter(elem) {
        if let Some(m) = media.as_deref()
            && m.defer
        {
            // written with the row (see `MediaSpans::lazy`)
            if let Some(m) = media {
                m.lazy = Some(LazyWords::range(letter, addr, count));
            }
            return;
        }
        let mut buf = RangeText([0; 32]);
        let (text, first) = media_range(&mut buf, letter, addr, count);
        data.push_str(text);
        name.push_str(text.get(..first).unwrap_or_default());
    } else {
        let from = name.len();
        push_elem(name, elem, block, addr);
        data.push_str(&name[from..]);
        push_range_end(data, elem, block, addr, count);
    }
    if let Some(m) = media {
        m.len = Some(data.len());
    }
}

/// Whether the list just deferred in `media` ([`MediaSpans::lazy`]) starts with the Sensor #
/// name: then it is kept there too (see [`LazyWords::name`]) instead of written.
fn defer_name(media: Option<&mut MediaSpans>) -> bool {
    match media.and_then(|m| m.lazy.as_mut()) {
        Some(l) => {
            l.name = true;
            true
        }
        None => false,
    }
}

/// What follows the first name in a range: `..R63`, ` n=8`, or nothing for one element.
fn push_range_end(out: &mut String, elem: Elem, block: u16, addr: u32, count: u32) {
    if count > 1 {
        match elem {
            Elem::Text | Elem::Byte => {
                out.push_str(" n=");
                push_u64(out, count as u64);
            }
            _ => {
                out.push_str("..");
                push_elem(out, elem, block, addr.wrapping_add(count - 1));
            }
        }
    }
}

/// Appends text with non-printable bytes as `\xNN`.
pub fn push_text(out: &mut String, bytes: &[u8]) {
    for &b in bytes {
        if (0x20..0x7F).contains(&b) && b != b'\\' {
            out.push(b as char);
        } else {
            out.push_str("\\x");
            push_hex_width(out, b as u32, 2);
        }
    }
}

/// The 8 BCD clock bytes: week, weekday, YY, MM, DD, hh, mm, ss.
fn push_clock(out: &mut String, d: &[u8]) {
    if d.len() != 8 {
        push_hex(out, d);
        return;
    }
    let two = |out: &mut String, b: u8| {
        push_hex_width(out, b as u32, 2);
    };
    out.push_str("20");
    two(out, d[2]);
    out.push('-');
    two(out, d[3]);
    out.push('-');
    two(out, d[4]);
    out.push(' ');
    two(out, d[5]);
    out.push(':');
    two(out, d[6]);
    out.push(':');
    two(out, d[7]);
    out.push_str(" week ");
    two(out, d[0]);
    out.push_str(" day ");
    two(out, d[1]);
}

/// Text written for a request.
pub struct RequestText {
    pub info: ReqInfo,
    /// Problems with the request's own layout (length, w-count), for the Note.
    pub layout_problem: Option<&'static str>,
}

/// Decodes a request body into `sensor_no` and `data`; returns what the answer must look like.
pub fn describe_request(
    station: u8,
    cmd: u8,
    body: &[u8],
    sensor_no: &mut String,
    data: &mut String,
) -> RequestText {
    describe_request_media(station, cmd, body, sensor_no, data, None)
}

/// [`describe_request`], recording the numbers of a media list in `media` (when `data` starts
/// empty).
pub(crate) fn describe_request_media(
    station: u8,
    cmd: u8,
    body: &[u8],
    sensor_no: &mut String,
    data: &mut String,
    media: Option<&mut MediaSpans>,
) -> RequestText {
    let mut info = ReqInfo {
        station,
        cmd,
        addr: 0,
        block: 0,
        elem: None,
        count: 0,
        expect: Expect::Unknown,
    };
    let Some(command) = commands::command(cmd) else {
        push_hex(data, body);
        return RequestText {
            info,
            layout_problem: Some("unknown command"),
        };
    };
    info.expect = if station == BROADCAST {
        Expect::Nothing
    } else {
        commands::expected_data_len(&command, body)
    };
    info.count = commands::request_count(command.layout, body).unwrap_or(0);
    info.elem = command.layout.elem();
    let mut problem = match command.layout.body_len(body) {
        Some(Ok(n)) if body.len() < n => Some("request too short"),
        Some(Ok(n)) if body.len() > n => Some("request longer than the command's layout"),
        Some(Err(_)) => Some("request too short"),
        _ => None,
    };
    use Layout::*;
    match command.layout {
        ReadWords(e) | ReadBits(e) if body.len() >= 3 => {
            info.addr = be(&body[1..3]);
            push_name_and_range(sensor_no, data, e, 0, info.addr, info.count, media);
        }
        ReadDb if body.len() >= 5 => {
            info.block = be(&body[1..3]) as u16;
            info.addr = be(&body[3..5]);
            push_name_and_range(
                sensor_no,
                data,
                Elem::DataBlock,
                info.block,
                info.addr,
                info.count,
                media,
            );
        }
        ReadProg(_) | ReadBytes if body.len() >= 4 => {
            let e = command.layout.elem().unwrap_or(Elem::Byte);
            info.addr = be(&body[1..4]);
            push_name_and_range(sensor_no, data, e, 0, info.addr, info.count, media);
        }
        ReadText if body.len() >= 5 => {
            info.block = be(&body[1..3]) as u16;
            info.addr = be(&body[3..5]);
            push_elem(sensor_no, Elem::Text, info.block, 0);
            data.push_str("pos ");
            push_u64(data, info.addr as u64);
            data.push_str(" rc ");
            push_u64(data, body[0] as u64);
        }
        ReadEeprom if body.len() >= 4 => {
            info.addr = be(&body[2..4]);
            push_name_and_range(
                sensor_no,
                data,
                Elem::Eeprom,
                0,
                info.addr,
                info.count,
                media,
            );
        }
        WriteWords(e) if body.len() >= 3 => {
            info.addr = be(&body[1..3]);
            let values = &body[3..];
            if !values.len().is_multiple_of(4) || body[0] as usize + 1 != body.len() - 1 {
                problem = problem.or(Some("w-count does not fit the values"));
            }
            let mut media = media;
            push_words(data, e, 0, info.addr, values, media.as_deref_mut());
            if !defer_name(media) {
                push_elem(sensor_no, e, 0, info.addr);
            }
        }
        WriteBits(e) if body.len() >= 4 => {
            info.addr = be(&body[1..3]);
            push_elem(sensor_no, e, 0, info.addr);
            let bytes = &body[4..];
            if bytes.len() < (info.count as usize).div_ceil(8) {
                problem = problem.or(Some("fio-count needs more data bytes"));
            }
            push_bits(data, e, info.addr, info.count, bytes, media);
        }
        WriteDb if body.len() >= 5 => {
            info.block = be(&body[1..3]) as u16;
            info.addr = be(&body[3..5]);
            push_elem(sensor_no, Elem::DataBlock, info.block, info.addr);
            let values = &body[5..];
            if !values.len().is_multiple_of(4) {
                problem = problem.or(Some("w-count does not fit the values"));
            }
            push_words(data, Elem::DataBlock, info.block, info.addr, values, media);
        }
        WriteProg(e) if body.len() >= 4 => {
            info.addr = be(&body[1..4]);
            push_elem(sensor_no, e, 0, info.addr);
            push_hex(data, &body[4..]);
        }
        WriteText if body.len() >= 5 => {
            info.block = be(&body[1..3]) as u16;
            info.addr = be(&body[3..5]);
            push_elem(sensor_no, Elem::Text, info.block, 0);
            data.push_str("pos ");
            push_u64(data, info.addr as u64);
            data.push_str(": ");
            push_text(data, &body[5..]);
        }
        WriteBytes if body.len() >= 4 => {
            info.addr = be(&body[1..4]);
            push_elem(sensor_no, Elem::Byte, 0, info.addr);
            push_hex(data, &body[4..]);
        }
        WriteEeprom if body.len() >= 7 => {
            info.addr = be(&body[1..3]);
            push_elem(sensor_no, Elem::Eeprom, 0, info.addr);
            data.push('=');
            push_i64(data, be(&body[3..7]) as i32 as i64);
        }
        ReadBlocks if body.len() >= 4 => {
            data.push_str("type ");
            push_u64(data, body[1] as u64);
            data.push_str(" block ");
            push_u64(data, be(&body[2..4]) as u64);
            data.push_str(" n=");
            push_u64(data, info.count as u64);
        }
        Clock => push_clock(data, body),
        Empty => {
            if !body.is_empty() {
                push_hex(data, body);
            }
        }
        _ => push_hex(data, body),
    }
    RequestText {
        info,
        layout_problem: problem,
    }
}

/// Decodes response `data` for the request it answers into `data_out`. Returns whether the
/// length fits the request.
pub fn describe_response(req: &ReqInfo, payload: &[u8], sensor_no: &mut String, out: &mut String) {
    describe_response_media(req, payload, sensor_no, out, None)
}

/// [`describe_response`], recording the numbers of a media list in `media` (when `out` starts
/// empty).
pub(crate) fn describe_response_media(
    req: &ReqInfo,
    payload: &[u8],
    sensor_no: &mut String,
    out: &mut String,
    mut media: Option<&mut MediaSpans>,
) {
    let fits = req.expect.fits(payload);
    let list_at = out.len();
    // A list of a medium starts with the Sensor # text (`R57=…`): copied from there.
    let mut first = 0;
    match (req.cmd, req.elem) {
        (0x00 | 0x06 | 0x07 | 0x96 | 0xA1, Some(e)) if fits => {
            first = push_words(out, e, req.block, req.addr, payload, media.as_deref_mut());
        }
        (0x02 | 0x03 | 0x05, Some(e)) if fits => {
            first = push_bits(out, e, req.addr, req.count, payload, media.as_deref_mut());
        }
        (0x01, _) if fits => {
            out.push_str("display=");
            push_i64(out, be(payload) as i32 as i64);
        }
        (0x04, _) if fits => push_clock(out, payload),
        (0x14..=0x1B, _) if fits => {
            push_text(out, payload);
            out.push_str(" (");
            out.push_str(commands::status_name(payload[0]));
            out.push(')');
        }
        (0x1D, _) if fits => {
            out.push_str("station ");
            push_u64(out, payload[0] as u64);
        }
        (0x20 | 0x21, _) => push_text(out, payload),
        (0x46, _) if fits => {
            let f = payload[0];
            out.push_str("Z=");
            push_u64(out, (f >> 3 & 1) as u64);
            out.push_str(" N=");
            push_u64(out, (f >> 2 & 1) as u64);
            out.push_str(" E=");
            push_u64(out, (f >> 1 & 1) as u64);
            out.push_str(" ACCU=");
            push_u64(out, (f & 1) as u64);
        }
        _ => push_hex(out, payload),
    }
    if let Some(e) = req.elem
        && !defer_name(media)
    {
        match out.get(list_at..list_at + first) {
            Some(name) if first > 0 => sensor_no.push_str(name),
            _ => push_elem(sensor_no, e, req.block, req.addr),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The eight-bytes-a-step CRC against the `crc` crate's, at every length to 40 and from
    /// every start of a running CRC.
    #[test]
    fn crc16_from_equals_the_crate() {
        let bytes: Vec<u8> = (0..40u32).map(|i| (i * 37 + 11) as u8).collect();
        for len in 0..=bytes.len() {
            assert_eq!(crc16(&bytes[..len]), CRC.checksum(&bytes[..len]), "{len}");
            for split in 0..=len {
                let mut d = CRC.digest();
                d.update(&bytes[..len]);
                let head = crc16(&bytes[..split]);
                assert_eq!(crc16_from(head, &bytes[split..len]), d.finalize());
            }
        }
        assert_eq!(crc16(b"123456789"), 0x31C3);
    }
    use crate::fmt::parse_hex;

    #[test]
    fn crc_catalogue_and_step() {
        assert_eq!(crc16(b"123456789"), 0x31C3);
        let mut c = 0;
        for &b in b"123456789" {
            c = crc_step(c, b);
        }
        assert_eq!(c, 0x31C3);
        // RACOM: B5 00 01 06 03 00 00 -> 5F4B
        assert_eq!(crc16(&parse_hex("B5 00 01 06 03 00 00").unwrap()), 0x5F4B);
        // M739E §1.4.2 (CRC computed): 3A 1B
        assert_eq!(
            crc16(&parse_hex("0A 0E 05 00 64 00 00 30 39").unwrap()),
            0x3A1B
        );
    }

    #[test]
    fn encoders_reproduce_the_seeds() {
        let mut v = Vec::new();
        encode_data(&mut v, 0, &[1, 6, 3, 0, 0], CrcBasis::Both);
        assert_eq!(v, parse_hex("B5 00 01 06 03 00 00 5F 4B").unwrap());
        v.clear();
        encode_secure(&mut v, 0x10, 3, 0, &[5, 6, 0, 0, 0xB5], CrcBasis::Escaped);
        assert_eq!(
            v,
            parse_hex("B5 10 09 03 B5 00 05 06 00 00 C5 00 94 C6").unwrap()
        );
        v.clear();
        encode_break_request(&mut v, 2, 6, &[0, 0, 0x0A]);
        assert_eq!(v, parse_hex("02 06 00 00 0A C2 50").unwrap());
        v.clear();
        encode_ether(&mut v, 0xB6, 0, &[0x4B, 6, 0, 0, 0]);
        assert_eq!(
            v,
            parse_hex("00 00 00 10 00 00 00 B6 00 4B 06 00 00 00 DC 62").unwrap()
        );
        v.clear();
        encode_ether(&mut v, 0xB6, 1, &[0x12, 0x34, 0x56, 0x78]);
        assert_eq!(
            v,
            parse_hex("00 00 00 0F 00 00 00 B6 01 12 34 56 78 3E 81").unwrap()
        );
    }

    fn req(station: u8, cmd: u8, body: &str) -> (String, String, RequestText) {
        let (mut s, mut d) = (String::new(), String::new());
        let t = describe_request(station, cmd, &parse_hex(body).unwrap(), &mut s, &mut d);
        (s, d, t)
    }

    #[test]
    fn requests_are_decoded() {
        let (s, d, t) = req(1, 6, "03 00 00");
        assert_eq!((s.as_str(), d.as_str()), ("R0", "R0..R3"));
        assert_eq!(t.info.expect, Expect::Data(16));
        assert!(t.layout_problem.is_none());
        let (s, d, t) = req(2, 0x0D, "03 00 10 03 0F");
        assert_eq!((s.as_str(), d.as_str()), ("O16", "O16=1 O17=1 O18=1 O19=1"));
        assert_eq!(t.info.expect, Expect::AckNak);
        let (s, d, _) = req(10, 0x0E, "05 00 64 00 00 30 39");
        assert_eq!((s.as_str(), d.as_str()), ("R100", "R100=12345"));
        let (s, d, _) = req(10, 0x97, "0B 0F A0 00 02 00 00 00 05 FF FF FF FF");
        assert_eq!(
            (s.as_str(), d.as_str()),
            ("DB4000[2]", "DB4000[2]=5 DB4000[3]=-1")
        );
        let (s, d, _) = req(10, 0x0A, "05 00 03 FF FF FF FF");
        assert_eq!((s.as_str(), d.as_str()), ("C3", "C3=4294967295"));
        let (s, d, _) = req(10, 0x96, "01 0F A0 00 02");
        assert_eq!(
            (s.as_str(), d.as_str()),
            ("DB4000[2]", "DB4000[2]..DB4000[3]")
        );
        let (s, _, t) = req(255, 0x06, "00 00 00");
        assert_eq!(s, "R0");
        assert_eq!(t.info.expect, Expect::Nothing);
        let (_, _, t) = req(1, 0x06, "00 00");
        assert_eq!(t.layout_problem, Some("request too short"));
        let (_, d, _) = req(1, 0x0C, "47 06 26 11 21 23 56 50");
        assert_eq!(d, "2026-11-21 23:56:50 week 47 day 06");
        let (s, d, _) = req(1, 0x25, "06 00 0C 00 05 61 62 0A");
        assert_eq!((s.as_str(), d.as_str()), ("X12", "pos 5: ab\\x0A"));
    }

    /// A medium's range written in one piece against the general path (a name and the range's
    /// end): addresses at the digit-count edges, counts that wrap the address, one element.
    #[test]
    fn media_ranges_are_the_general_text() {
        let media = super::super::media::LETTERED;
        let mut addrs: Vec<u32> = (0..10)
            .flat_map(|p| [10u32.pow(p) - 1, 10u32.pow(p)])
            .collect();
        addrs.extend([0, 57, 65535, 99_999_999, u32::MAX - 1, u32::MAX]);
        let mut x = 0x2545_F491u32;
        for _ in 0..2000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            addrs.push(x >> (x % 32));
        }
        let counts = [0u32, 1, 2, 3, 10, 128, 256, 65536, u32::MAX];
        for elem in media {
            for &addr in &addrs {
                for count in counts {
                    let (mut name, mut data) = (String::from("s"), String::from("d"));
                    push_name_and_range(&mut name, &mut data, elem, 0, addr, count, None);
                    let mut want = String::from("d");
                    push_elem(&mut want, elem, 0, addr);
                    push_range_end(&mut want, elem, 0, addr, count);
                    assert_eq!(data, want, "{elem:?} {addr} {count}");
                    assert_eq!(name, format!("s{}{addr}", elem.prefix()));
                }
            }
        }
    }

    #[test]
    fn responses_are_decoded() {
        let (mut s, mut d) = (String::new(), String::new());
        let t = describe_request(2, 6, &[1, 0, 0x64], &mut s, &mut d);
        let (mut s, mut d) = (String::new(), String::new());
        describe_response(
            &t.info,
            &parse_hex("00 00 01 63 00 00 00 BB").unwrap(),
            &mut s,
            &mut d,
        );
        assert_eq!((s.as_str(), d.as_str()), ("R100", "R100=355 R101=187"));
        let t = describe_request(2, 2, &[7, 0, 0], &mut String::new(), &mut String::new());
        let mut d = String::new();
        describe_response(&t.info, &[0x49], &mut String::new(), &mut d);
        assert_eq!(d, "F0=1 F1=0 F2=0 F3=1 F4=0 F5=0 F6=1 F7=0");
        let t = describe_request(2, 0x1B, &[], &mut String::new(), &mut String::new());
        let mut d = String::new();
        describe_response(&t.info, b"R", &mut String::new(), &mut d);
        assert_eq!(d, "R (run)");
    }
}
