//! Invariant checks on arbitrary input, shared by the fuzz targets (`fuzz/`) and the test that
//! replays their corpus (`tests/fuzz_corpus.rs`). Every function panics when an invariant is
//! violated, and must not panic otherwise, whatever the input.

use std::io::{self, Read};
use std::sync::mpsc::sync_channel;

use crate::protocol::InputKind;
use crate::protocol::{Decoder, PcapBytes};
use crate::row::Class;
use crate::row::{Collected, OwnedRow};
use crate::sbus::Resolved;
use crate::source::{Batch, ChunkReader, Message, Opened};

/// Split points derived from the data itself, so a fuzzer explores chunkings too.
fn chunk_lengths(data: &[u8]) -> impl Iterator<Item = usize> + '_ {
    data.iter().cycle().map(|b| 1 + (*b as usize % 7))
}

/// Decodes `data` (untimed) in one piece, byte by byte, and in data-driven chunks; the rows
/// must be identical. Returns them.
pub fn same_rows_however_chunked(new: &dyn Fn() -> Box<dyn Decoder>, data: &[u8]) -> Vec<OwnedRow> {
    let run = |pieces: &mut dyn Iterator<Item = &[u8]>| {
        let mut d = new();
        let mut out = Collected::default();
        for p in pieces {
            d.push(p, None, &mut out).unwrap();
        }
        d.finish(&mut out).unwrap();
        out.rows
    };
    let whole = run(&mut std::iter::once(data));
    let bytes = run(&mut data.chunks(1));
    assert_eq!(whole, bytes, "byte-by-byte input changed the rows");
    let mut rest = data;
    let mut lens = chunk_lengths(data);
    let mut pieces = Vec::new();
    while !rest.is_empty() {
        let n = lens.next().unwrap().min(rest.len());
        pieces.push(&rest[..n]);
        rest = &rest[n..];
    }
    let chunked = run(&mut pieces.into_iter());
    assert_eq!(whole, chunked, "chunked input changed the rows");
    whole
}

/// S.Port: chunking invariance, every byte in exactly one row, and no row that is not flagged
/// carries a frame failing its CRC.
pub fn sport(data: &[u8]) {
    use crate::sport::wire;
    let rows = same_rows_however_chunked(&|| Box::new(crate::sport::SportDecoder::new()), data);
    let total: usize = rows.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, data.len(), "bytes lost or duplicated");
    for r in &rows {
        let flagged = matches!(r.class, Class::Error);
        if flagged || r.kind.is_empty() || r.kind == "FwUpdate" {
            continue;
        }
        // An accepted frame: its wire bytes must unstuff to 8 bytes with a valid CRC.
        let mut body = Vec::new();
        let mut esc = false;
        for &b in &r.raw[2..] {
            if esc {
                body.push(b ^ 0x20);
                esc = false;
            } else if b == wire::ESCAPE {
                esc = true;
            } else {
                body.push(b);
            }
        }
        let body: [u8; 8] = body
            .try_into()
            .unwrap_or_else(|b| panic!("accepted frame of wrong length {b:?} in {r:?}"));
        assert!(
            wire::crc_ok(&body),
            "frame with a bad CRC not flagged: {r:?}"
        );
    }
}

/// A reader that returns a few bytes per read, as a slow pipe does (the sizes come from the
/// data, to vary how a source sees its input).
struct Trickle {
    data: Vec<u8>,
    pos: usize,
}

impl Read for Trickle {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let rest = &self.data[self.pos..];
        let seed = rest.first().copied().unwrap_or(0) as usize;
        let n = (1 + seed % 7).min(buf.len()).min(rest.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.pos += n;
        Ok(n)
    }
}

/// Runs a file reader over `data`, read whole or in small pieces; returns the bytes with their
/// per-byte times and the other messages, which must not depend on the read sizes.
fn read_all(
    make: fn(Opened) -> Box<dyn ChunkReader>,
    kind: InputKind,
    data: &[u8],
) -> (Vec<(u8, Option<u64>)>, Vec<String>) {
    let collect = |reader: Box<dyn Read + Send>| {
        let opened = Opened {
            kind,
            prefix: Vec::new(),
            reader,
            name: "fuzz".into(),
        };
        let mut r = make(opened);
        let (tx, rx) = sync_channel(1 << 16);
        let mut bytes = Vec::new();
        let mut failure = None;
        loop {
            match r.next_batch(&tx) {
                Ok(Some(c)) => tx.send(c.into()).unwrap(),
                Ok(None) => break,
                Err(f) => {
                    failure = Some(f.to_string());
                    break;
                }
            }
        }
        drop(tx);
        let mut other = Vec::new();
        for m in rx.try_iter() {
            match m {
                Message::Data(b) => flatten(&b, &mut bytes),
                m => other.push(format!("{m:?}")),
            }
        }
        other.extend(failure);
        (bytes, other)
    };
    let whole = collect(Box::new(io::Cursor::new(data.to_vec())));
    let trickled = collect(Box::new(Trickle {
        data: data.to_vec(),
        pos: 0,
    }));
    assert_eq!(
        whole, trickled,
        "read sizes changed what the reader produced"
    );
    whole
}

fn flatten(b: &Batch, out: &mut Vec<(u8, Option<u64>)>) {
    for (bytes, t) in b.segments() {
        out.extend(bytes.iter().map(|&x| (x, t)));
    }
}

/// EdgeTX log reader: never panics, read sizes do not matter, and the S.Port decoder accepts
/// whatever it yields.
pub fn edgetx_log(data: &[u8]) {
    let (bytes, _) = read_all(
        |o| Box::new(crate::source::edgetx::EdgeTxReader::new(o)),
        InputKind::EdgeTxLog,
        data,
    );
    let raw: Vec<u8> = bytes.iter().map(|b| b.0).collect();
    sport(&raw);
}

/// Recording (pcap) reader: never panics, read sizes do not matter.
pub fn recording(data: &[u8]) {
    let (bytes, _) = read_all(
        |o| Box::new(crate::source::recording::RecordingReader::new(o)),
        InputKind::Recording,
        data,
    );
    let mut d = crate::sport::SportDecoder::new();
    let mut out = Collected::default();
    for (b, t) in bytes {
        d.push(&[b], t, &mut out).unwrap();
    }
    d.finish(&mut out).unwrap();
}

/// Writers of logic-analyzer traces from known characters (sigrok sessions, VCD, Saleae CSV),
/// for the tests.
pub use crate::source::logic::write as trace_writer;

/// A reader that fails at once (a trace whose header is unusable).
struct Refused(Option<crate::exit::Failure>);

impl ChunkReader for Refused {
    fn next_batch(
        &mut self,
        _tx: &std::sync::mpsc::SyncSender<Message>,
    ) -> Result<Option<crate::source::Chunk>, crate::exit::Failure> {
        self.0.take().map_or(Ok(None), Err)
    }
}

/// Opens a logic-analyzer trace as `source::open` does: its first bytes read for detection.
fn open_trace(mut o: Opened) -> Box<dyn ChunkReader> {
    use crate::source::logic::{self, Options};
    let mut buf = [0u8; crate::source::DETECT_LEN];
    let mut n = 0;
    while n < buf.len() {
        match o.reader.read(&mut buf[n..]) {
            Ok(0) | Err(_) => break,
            Ok(k) => n += k,
        }
    }
    o.prefix = buf[..n].to_vec();
    // A line whose rate the pulses will usually contradict: measuring is exercised too.
    let line = crate::protocol::Line {
        parity: crate::protocol::Parity::Even,
        ..crate::protocol::Line::n81(57_600)
    };
    match logic::reader(o, &Options::new(line)) {
        Ok(r) => r,
        Err(f) => Box::new(Refused(Some(f))),
    }
}

/// Logic-analyzer trace readers (sigrok sessions, VCD, Saleae CSV exports, through the software
/// UART): never panic, read sizes do not matter, every character's time is at or after the
/// one before, and the S.Port decoder accepts whatever they yield.
pub fn logic_trace(data: &[u8]) {
    let (bytes, _) = read_all(open_trace, InputKind::Trace, data);
    let times: Vec<u64> = bytes
        .iter()
        .map(|b| b.1.expect("a trace's characters have times"))
        .collect();
    assert!(
        times.windows(2).all(|w| w[0] <= w[1]),
        "a character's time goes back"
    );
    let mut d = crate::sport::SportDecoder::new();
    let mut out = Collected::default();
    for (b, t) in bytes {
        d.push(&[b], t, &mut out).unwrap();
    }
    d.finish(&mut out).unwrap();
}

/// S-Bus serial decoder in every mode: chunking invariance, and every input byte in exactly one
/// row (Timeout rows carry none); an accepted telegram passes its CRC under the reading the rows
/// were made with (the mode given, or the one auto mode settled on), and in data mode starts
/// with 0xB5.
pub fn sbus_serial(data: &[u8]) {
    use crate::sbus::{Mode, Options, SerialDecoder};
    for mode in [
        Mode::Auto,
        Mode::Data,
        Mode::Secure,
        Mode::Break,
        Mode::Parity,
    ] {
        let opts = Options {
            mode,
            ..Options::default()
        };
        let rows = same_rows_however_chunked(&|| Box::new(SerialDecoder::new(opts.clone())), data);
        let total: usize = rows.iter().map(|r| r.raw.len()).sum();
        assert_eq!(total, data.len(), "{mode:?}: bytes lost or duplicated");
        // Which framing made the rows: a raw B5 is a frame start only in data mode; in break and
        // parity mode it is an ordinary byte (station 181, data, a CRC byte).
        let reading = {
            let mut d = SerialDecoder::new(opts);
            let mut out = Collected::default();
            d.push(data, None, &mut out).unwrap();
            d.finish(&mut out).unwrap();
            d.resolved()
        };
        for r in &rows {
            let accepted = matches!(
                r.kind.as_str(),
                "Request" | "Response" | "ACK" | "NAK" | "Retry"
            );
            if accepted && reading == Some(Resolved::Data) {
                assert_eq!(r.raw.first(), Some(&0xB5), "{mode:?}: {r:?}");
            }
            if r.kind == crate::row::kind::TIMEOUT {
                assert!(r.raw.is_empty());
            }
            if accepted && r.class != Class::Error {
                let reading = reading.unwrap_or_else(|| {
                    panic!("{mode:?}: a telegram before auto mode settled: {r:?}")
                });
                assert!(
                    sbus_serial_crc_ok(&r.raw, reading),
                    "{mode:?} (read as {reading:?}): bad CRC accepted: {r:?}"
                );
            }
        }
    }
}

/// Whether the wire bytes of an accepted serial S-Bus telegram pass its CRC under `reading`:
/// data mode over the escaped or the unescaped bytes (either is accepted), secure telegrams
/// over the inner telegram; break/parity mode over all bytes before the CRC (B5 and C5 travel
/// raw there, no DLE), where a lone ACK/NAK character has none.
fn sbus_serial_crc_ok(raw: &[u8], reading: Resolved) -> bool {
    use crate::sbus::telegram::crc16;
    if reading != Resolved::Data {
        if raw.len() <= 2 && matches!(raw.first(), Some(0x06 | 0x15)) {
            return true;
        }
        let n = raw.len();
        return n >= 3 && crc16(&raw[..n - 2]) == u16::from_be_bytes([raw[n - 2], raw[n - 1]]);
    }
    if raw.first() != Some(&0xB5) {
        return false;
    }
    // Tokens: a byte, or a DLE pair standing for one byte; (wire bytes, value).
    let mut tokens: Vec<(&[u8], u8)> = Vec::new();
    let mut i = 0;
    while i < raw.len() {
        if raw[i] == 0xC5 && i + 1 < raw.len() && raw[i + 1] <= 1 {
            tokens.push((&raw[i..i + 2], if raw[i + 1] == 0 { 0xB5 } else { 0xC5 }));
            i += 2;
        } else {
            tokens.push((&raw[i..i + 1], raw[i]));
            i += 1;
        }
    }
    // A dangling DLE after the CRC (`… CRC C5` cut by the next B5) is noted by the decoder and
    // is not part of the telegram.
    if tokens.last().is_some_and(|t| t.0 == [0xC5]) {
        tokens.pop();
    }
    // A secure telegram carries a standard telegram after `B5 1x LEN SEQ`, with its own CRC
    // (a malformed one may lack the inner B5; it is noted, and its CRC still has to check).
    if tokens.len() > 4 && matches!(tokens[1].1, 0x10 | 0x11) {
        tokens.drain(..4);
    }
    if tokens.len() < 3 {
        return false;
    }
    let (body, crc) = tokens.split_at(tokens.len() - 2);
    let want = u16::from_be_bytes([crc[0].1, crc[1].1]);
    let escaped: Vec<u8> = body.iter().flat_map(|t| t.0.iter().copied()).collect();
    let unescaped: Vec<u8> = body.iter().map(|t| t.1).collect();
    crc16(&escaped) == want || crc16(&unescaped) == want
}

/// The Ether-S-Bus decoder behind the pcap reader, taking capture bytes.
fn ether_decoder() -> PcapBytes<crate::sbus::EtherDecoder> {
    PcapBytes::new(crate::sbus::EtherDecoder::new(
        &crate::sbus::Options::default(),
    ))
}

/// Ether-S-Bus decoder on arbitrary capture bytes (through the pcap reader): never panics,
/// chunking does not matter, and every accepted telegram's UDP payload passes the CRC over the
/// whole payload.
pub fn sbus_ether(data: &[u8]) {
    let check = |rows: &[OwnedRow]| {
        for r in rows {
            if r.class != Class::Error
                && matches!(
                    r.kind.as_str(),
                    "Request" | "Response" | "ACK" | "NAK" | "Retry"
                )
            {
                let n = r.raw.len();
                assert!(
                    n >= 11
                        && crate::sbus::telegram::crc16(&r.raw[..n - 2])
                            == u16::from_be_bytes([r.raw[n - 2], r.raw[n - 1]]),
                    "bad CRC accepted: {r:?}"
                );
            }
        }
    };
    let rows = same_rows_however_chunked(&|| Box::new(ether_decoder()), data);
    check(&rows);
    // The same bytes behind a pcap header (link type Ethernet) reach the packet parsers.
    let mut f = Vec::new();
    crate::pcap::write::header(&mut f, 1);
    f.extend_from_slice(data);
    let rows = same_rows_however_chunked(&|| Box::new(ether_decoder()), &f);
    check(&rows);
}

/// modm SAB / SAB2, detected and with each framing forced: chunking invariance, rows in time
/// order (forced framings), every accepted frame passes its framing's CRC when re-checked from
/// its wire bytes, and SAB v1 rows cover every byte exactly once.
pub fn sab(data: &[u8]) {
    use crate::sab::{self, FramingChoice, Options, hdlc, sync};
    for framing in [
        FramingChoice::Auto,
        FramingChoice::Sync,
        FramingChoice::Hdlc,
    ] {
        let o = Options {
            framing,
            ..Options::default()
        };
        let rows = same_rows_however_chunked(&|| Box::new(sab::SabDecoder::new(o.clone())), data);
        let framing_col = sab::COLUMNS.iter().position(|c| *c == "Framing").unwrap();
        let mut last = 0;
        for r in &rows {
            let micros = r.micros.expect("every SAB row has a time");
            if framing != FramingChoice::Auto {
                assert!(micros >= last, "rows out of time order: {r:?}");
                last = micros;
            }
            if !matches!(r.kind.as_str(), "Request" | "ACK" | "NACK" | "Reserved") {
                continue;
            }
            let raw = &r.raw;
            match r.extra[framing_col].as_str() {
                "sync" => {
                    assert!(raw.len() >= sync::OVERHEAD && raw[0] == sync::SYNC, "{r:?}");
                    assert_eq!(raw[1] as usize + sync::OVERHEAD, raw.len(), "{r:?}");
                    let n = raw.len();
                    assert_eq!(
                        sync::crc8(&raw[1..n - 1]),
                        raw[n - 1],
                        "bad CRC accepted: {r:?}"
                    );
                }
                "hdlc" => {
                    let n = raw.len();
                    assert!(
                        n >= 6 && raw[0] == hdlc::FLAG && raw[n - 1] == hdlc::FLAG,
                        "{r:?}"
                    );
                    let mut body = Vec::new();
                    let mut esc = false;
                    for &b in &raw[1..n - 1] {
                        if b == hdlc::ESCAPE {
                            esc = true;
                        } else if esc {
                            body.push(b ^ 0x20);
                            esc = false;
                        } else {
                            body.push(b);
                        }
                    }
                    assert!(body.len() >= 4, "{r:?}");
                    assert_eq!(hdlc::crc16(&body), 0, "bad CRC accepted: {r:?}");
                }
                f => panic!("unknown framing {f:?} in {r:?}"),
            }
        }
        if framing == FramingChoice::Sync {
            let total: usize = rows.iter().map(|r| r.raw.len()).sum();
            assert_eq!(total, data.len(), "SAB v1 bytes lost or duplicated");
        }
    }
}

/// CRSF: [`frame_shape`] with CRSF's start bytes.
pub fn crsf(data: &[u8]) {
    let o = crate::crsf::Options::default();
    frame_shape(
        &|| crate::crsf::decoder(o.clone()),
        &crate::crsf::wire::CRSF_ADDRESSES,
        data,
    );
}

/// GHST: [`frame_shape`] with GHST's start bytes.
pub fn ghst(data: &[u8]) {
    let o = crate::ghst::Options::default();
    frame_shape(
        &|| crate::ghst::decoder(o.clone()),
        &crate::ghst::ADDRESSES,
        data,
    );
}

/// The CRSF frame shape (`addr len type payload crc`, CRC-8 0xD5): chunking invariance, and
/// the rows are exactly those of a second, deliberately naive reading of the resync rule
/// (`crate::crsf::wire`) over the whole input: a frame at the earliest position where a
/// complete candidate passes its CRC, a failed candidate with a valid frame starting inside it
/// costs one byte of garbage, one without is a bad (or, cut by the end, truncated) frame,
/// garbage in runs of at most 64 bytes. Times only grow.
fn frame_shape(new: &dyn Fn() -> Box<dyn Decoder>, addrs: &[bool; 256], data: &[u8]) {
    let rows = same_rows_however_chunked(new, data);
    let want = naive_frames(addrs, data);
    let got: Vec<(&str, &[u8])> = rows
        .iter()
        .map(|r| {
            let k = match r.kind.as_str() {
                "BadCRC" => "BadCRC",
                "Truncated" => "Truncated",
                "Garbage" => "Garbage",
                _ => "Frame",
            };
            (k, r.raw.as_slice())
        })
        .collect();
    let want: Vec<(&str, &[u8])> = want.iter().map(|(k, r)| (*k, &data[r.clone()])).collect();
    assert_eq!(
        got, want,
        "rows differ from the naive reading of the resync rule"
    );
    let mut last = 0;
    for r in &rows {
        let m = r.micros.expect("every row has a time");
        assert!(m >= last, "time went back: {r:?}");
        last = m;
        if r.kind == "Garbage" {
            assert!(r.id.is_none() && r.parts.is_empty(), "{r:?}");
        } else {
            assert_eq!(r.id, Some(u32::from(r.raw[0])), "{r:?}");
        }
        if matches!(r.kind.as_str(), "BadCRC" | "Truncated") {
            assert!(r.parts.is_empty(), "numbers of a broken frame: {r:?}");
        }
    }
}

/// CRC-8, polynomial 0xD5, bit by bit (a second reading of the table in `crsf::wire`).
fn crc8_d5_bitwise(bytes: &[u8]) -> u8 {
    let mut c = 0u8;
    for &b in bytes {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ 0xD5
            } else {
                c << 1
            };
        }
    }
    c
}

/// The rows' kinds and byte ranges by the resync rule, over the whole input at once.
fn naive_frames(addrs: &[bool; 256], data: &[u8]) -> Vec<(&'static str, std::ops::Range<usize>)> {
    // (span, valid) of the candidate at p: `None` when p starts none.
    let cand = |p: usize| -> Option<(usize, bool)> {
        let a = *data.get(p)?;
        if !addrs[a as usize] {
            return None;
        }
        let Some(&len) = data.get(p + 1) else {
            return Some((1, false));
        };
        if !(2..=62).contains(&len) {
            return None;
        }
        let end = p + len as usize + 2;
        if end > data.len() {
            return Some((data.len() - p, false));
        }
        Some((
            end - p,
            crc8_d5_bitwise(&data[p + 2..end - 1]) == data[end - 1],
        ))
    };
    let complete = |p: usize, span: usize| {
        p + span <= data.len() && data.get(p + 1).is_some_and(|&l| l as usize + 2 == span)
    };
    let valid = |p: usize| matches!(cand(p), Some((span, true)) if complete(p, span));
    let mut out: Vec<(&'static str, std::ops::Range<usize>)> = Vec::new();
    let mut garbage: Option<usize> = None;
    let flush = |out: &mut Vec<(&'static str, std::ops::Range<usize>)>,
                 g: &mut Option<usize>,
                 to: usize| {
        if let Some(s) = g.take() {
            let mut a = s;
            while a < to {
                let b = (a + crate::row::GARBAGE_ROW_MAX).min(to);
                out.push(("Garbage", a..b));
                a = b;
            }
        }
    };
    let mut p = 0;
    while p < data.len() {
        match cand(p) {
            Some((span, true)) => {
                flush(&mut out, &mut garbage, p);
                out.push(("Frame", p..p + span));
                p += span;
            }
            Some((span, false)) if !(p + 1..p + span).any(valid) => {
                flush(&mut out, &mut garbage, p);
                let kind = if complete(p, span) {
                    "BadCRC"
                } else {
                    "Truncated"
                };
                out.push((kind, p..p + span));
                p += span;
            }
            _ => {
                garbage.get_or_insert(p);
                p += 1;
            }
        }
    }
    flush(&mut out, &mut garbage, p);
    out
}

/// Futaba SBUS: chunking invariance, every byte in exactly one row, every channel row a `0F`
/// frame of 25 bytes with an end byte, every slot row three bytes starting with a slot id.
pub fn futaba(data: &[u8]) {
    use crate::futaba::{self, wire};
    let rows = same_rows_however_chunked(&|| futaba::decoder(futaba::Options::default()), data);
    let total: usize = rows.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, data.len(), "bytes lost or duplicated");
    for r in &rows {
        match r.kind.as_str() {
            futaba::CHANNELS_TYPE => {
                assert_eq!(r.raw.len(), wire::FRAME_LEN, "{r:?}");
                assert_eq!(r.raw[0], wire::START, "{r:?}");
                assert!(wire::end_ok(r.raw[24]), "wrong end byte accepted: {r:?}");
                assert_eq!(r.parts.len(), wire::CHANNELS + 4, "{r:?}");
            }
            futaba::SLOT_TYPE => {
                assert_eq!(r.raw.len(), wire::SLOT_LEN, "{r:?}");
                assert_eq!(wire::slot_number(r.raw[0]).map(u32::from), r.id, "{r:?}");
            }
            _ => assert_eq!(r.class, Class::Error, "{r:?}"),
        }
    }
}

/// FlySky iBUS: chunking invariance, every byte in exactly one row, and every row that is not
/// flagged holds whole frames (a poll and its answer, or one frame) whose checksums pass.
pub fn ibus(data: &[u8]) {
    use crate::ibus::{self, wire};
    let rows = same_rows_however_chunked(&|| ibus::decoder(ibus::Options::default()), data);
    let total: usize = rows.iter().map(|r| r.raw.len()).sum();
    assert_eq!(total, data.len(), "bytes lost or duplicated");
    for r in &rows {
        if r.class == Class::Error {
            continue;
        }
        let mut rest = &r.raw[..];
        let mut frames = 0;
        while !rest.is_empty() {
            let n = usize::from(rest[0]);
            assert!(n >= wire::MIN_LEN && n <= rest.len(), "{r:?}");
            assert!(wire::check_ok(&rest[..n]), "bad checksum accepted: {r:?}");
            rest = &rest[n..];
            frames += 1;
        }
        assert!((1..=2).contains(&frames), "{r:?}");
        if r.kind.is_empty() {
            assert!(r.id.is_some() && wire::is_poll(&r.raw), "poll row: {r:?}");
        }
    }
}

/// Telemetry logs: chunking invariance, every byte in at most one row (blank bytes at the end
/// and a header without lines are in none), rows of at most one line, garbage rows of at most
/// `GARBAGE_ROW_MAX` bytes, and every number part a plain decimal of the row's line.
pub fn logs(data: &[u8]) {
    let rows = same_rows_however_chunked(&crate::logs::decoder, data);
    let total: usize = rows.iter().map(|r| r.raw.len()).sum();
    assert!(total <= data.len(), "bytes duplicated");
    let mut at = 0;
    for r in &rows {
        // Rows are the input's bytes in order.
        let found = data[at..]
            .windows(r.raw.len().max(1))
            .position(|w| r.raw.is_empty() || w == &r.raw[..]);
        let found = found.unwrap_or_else(|| panic!("row bytes not in the input: {r:?}"));
        at += found + r.raw.len();
        if r.kind == crate::row::kind::GARBAGE {
            assert_eq!(r.class, Class::Error, "{r:?}");
            continue;
        }
        let line = String::from_utf8_lossy(&r.raw);
        for (name, _, text) in &r.parts {
            assert!(
                text.parse::<f64>().is_ok(),
                "part {name}={text} not a number: {r:?}"
            );
            assert!(line.contains(text.as_str()), "{r:?}");
        }
    }
}

/// Modbus, RTU and ASCII framing: chunking invariance (untimed, and timed with the data's own
/// split points as read times), every byte in exactly one row, every frame shown as a request,
/// response or exception passes its check, and every `BadCRC` row fails it.
pub fn modbus(data: &[u8]) {
    use crate::modbus::{self, Framing, Options, ascii, wire};
    for framing in [Framing::Rtu, Framing::Ascii] {
        let o = Options {
            framing,
            ..Options::default()
        };
        let rows = same_rows_however_chunked(&|| modbus::decoder(o.clone()), data);
        let total: usize = rows.iter().map(|r| r.raw.len()).sum();
        assert_eq!(total, data.len(), "Modbus bytes lost or duplicated");
        let ok = |raw: &[u8]| match framing {
            Framing::Rtu => wire::crc_ok(raw),
            Framing::Ascii => {
                let body = raw.strip_suffix(b"\n").unwrap_or(raw);
                let body = body.strip_suffix(b"\r").unwrap_or(body);
                let hex = body.get(1..).unwrap_or_default();
                if hex.len() % 2 != 0 {
                    return false;
                }
                let bytes: Option<Vec<u8>> = hex
                    .chunks(2)
                    .map(|p| u8::from_str_radix(std::str::from_utf8(p).ok()?, 16).ok())
                    .collect();
                bytes.is_some_and(|b| b.len() >= 3 && ascii::lrc(&b) == 0)
            }
        };
        for r in &rows {
            match r.kind.as_str() {
                "Request" | "Response" | "Exception" | "Unknown" => {
                    assert!(ok(&r.raw), "frame with a bad check accepted: {r:?}")
                }
                "BadCRC" => assert!(!ok(&r.raw), "good frame shown as BadCRC: {r:?}"),
                _ => {}
            }
        }
        // timed: each data-driven piece read at its own time
        let timed = |d: &[u8]| {
            let mut dec = modbus::decoder(o.clone());
            let mut out = Collected::default();
            let mut at = 0;
            let mut t = 0u64;
            for n in chunk_lengths(d) {
                if at >= d.len() {
                    break;
                }
                let n = n.min(d.len() - at);
                t += d[at] as u64 * 10_000;
                dec.push(&d[at..at + n], Some(t), &mut out).unwrap();
                at += n;
            }
            dec.finish(&mut out).unwrap();
            out.rows
        };
        let rows = timed(data);
        let total: usize = rows.iter().map(|r| r.raw.len()).sum();
        assert_eq!(total, data.len(), "Modbus bytes lost or duplicated (timed)");
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// From the proptest seed of `sbus::tests::props::garbage_never_panics` (its biased input): in
    /// break and parity mode one request of station 0xB5 (181), command 0xAC, 79 data bytes
    /// and the CRC `B5 C5`, which is CRC-16/XMODEM over the 83 bytes before it. B5 and C5
    /// travel raw in those modes; read as data mode the same bytes are a dozen broken frames.
    pub(crate) const STATION_B5_REQUEST: [u8; 85] = [
        0xB5, 0xAC, 0x11, 0x00, 0xC5, 0xB5, 0xC5, 0x06, 0x06, 0xB5, 0x00, 0xC5, 0xAD, 0x06, 0x00,
        0xC5, 0xC5, 0xC5, 0x34, 0x00, 0x00, 0x00, 0x22, 0xA0, 0xC5, 0x22, 0x34, 0x52, 0xCB, 0xB5,
        0x06, 0x0B, 0x64, 0x5F, 0x00, 0x1D, 0xB5, 0xB5, 0xB5, 0xEF, 0xB5, 0x00, 0x06, 0x5F, 0xB5,
        0x00, 0xB5, 0x00, 0x00, 0x1C, 0xC5, 0xC5, 0x47, 0x64, 0xB5, 0x06, 0x06, 0x95, 0x00, 0x00,
        0xC5, 0x52, 0x06, 0xA1, 0x00, 0x06, 0x47, 0xB5, 0xB5, 0x06, 0xB5, 0x06, 0x16, 0x06, 0xE8,
        0x00, 0xB5, 0xC5, 0x16, 0xCB, 0xB5, 0x23, 0xB9, 0xB5, 0xC5,
    ];

    #[test]
    fn a_break_mode_telegram_of_station_b5_is_checked_as_break_mode() {
        let raw = &STATION_B5_REQUEST;
        assert_eq!(crate::sbus::telegram::crc16(&raw[..83]), 0xB5C5);
        // Break/parity reading: CRC over every byte before it.
        assert!(sbus_serial_crc_ok(raw, Resolved::Break));
        assert!(sbus_serial_crc_ok(raw, Resolved::Parity));
        // The data-mode reading takes the final C5 for a dangling DLE and `B9 B5` for the CRC:
        // these bytes are no data-mode telegram (nor does the data-mode framer make one of them).
        assert!(!sbus_serial_crc_ok(raw, Resolved::Data));
        // The whole invariant check, every mode: it used to read the break-mode row as data
        // mode because it starts with B5, and panic "bad CRC accepted".
        sbus_serial(raw);
    }

    /// The EdgeTX resync stream and noise around frames satisfy the CRSF checks.
    #[test]
    fn crsf_and_ghst_checks_hold_on_frames_and_noise() {
        let mut data = crate::testing::noise(600, 5);
        for i in 0..20u8 {
            crate::crsf::wire::encode(&mut data, 0xC8, 0x14, &[i; 10]);
            crate::crsf::wire::encode(&mut data, 0x82, 0x10, &[i; 10]);
            data.extend(crate::testing::noise(usize::from(i), u64::from(i) + 1));
        }
        data.extend([0xC8, 0x0A, 0x08]);
        crsf(&data);
        ghst(&data);
        assert!(
            naive_frames(&crate::crsf::wire::CRSF_ADDRESSES, &data)
                .iter()
                .any(|(k, _)| *k == "BadCRC")
        );
    }
}
