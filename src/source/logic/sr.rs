//! sigrok session files (`.sr`, as PulseView and `sigrok-cli -o` save them): a zip archive
//! holding `version`, `metadata` (INI: the sample rate, the probe names, the bytes per sample)
//! and the samples in chunks `logic-1-1`, `logic-1-2`, … (`logic-1` in version 1 files), each
//! sample `unitsize` bytes, little-endian, probe `k` (1-based) in bit `k - 1`.
//!
//! The archive is read as a stream, entry after entry in the order they are stored (the
//! central directory at the end is not needed, so standard input works too), by the `zip`
//! crate in a thread of its own that hands on the decompressed bytes in blocks over a bounded
//! channel: memory stays flat however large the session. Analog chunks are skipped.

use std::io::Read;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};

use super::uart::TimeBase;
use super::{Channel, Edge, Header, Step, whole_input};
use crate::exit::Failure;
use crate::source::Opened;

/// Decompressed bytes handed on at a time.
const BLOCK: usize = 64 * 1024;
/// The metadata entry is at most this long.
const MAX_METADATA: usize = 64 * 1024;

/// What the unzipping thread hands on.
enum Part {
    /// An entry starts.
    Entry(String),
    /// Bytes of the current entry.
    Data(Vec<u8>),
    /// The entries ended (the central directory starts).
    End,
    /// The archive is broken.
    Failed(String),
}

/// Reads the archive's entries in order into `tx` until it ends or the receiver is gone.
fn unzip(mut reader: Box<dyn Read + Send>, tx: SyncSender<Part>) {
    loop {
        let mut file = match zip::read::read_zipfile_from_stream(&mut reader) {
            Ok(Some(f)) => f,
            Ok(None) => {
                let _ = tx.send(Part::End);
                return;
            }
            Err(e) => {
                let _ = tx.send(Part::Failed(zip_error(&e)));
                return;
            }
        };
        let name = String::from_utf8_lossy(file.name_raw()).into_owned();
        if tx.send(Part::Entry(name)).is_err() {
            return;
        }
        loop {
            let mut block = vec![0; BLOCK];
            let mut n = 0;
            while n < BLOCK {
                match file.read(&mut block[n..]) {
                    Ok(0) => break,
                    Ok(k) => n += k,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        let _ = tx.send(Part::Failed(io_error(&e)));
                        return;
                    }
                }
            }
            if n == 0 {
                break;
            }
            block.truncate(n);
            if tx.send(Part::Data(block)).is_err() {
                return;
            }
            if n < BLOCK {
                break;
            }
        }
    }
}

/// What went wrong in the archive, in words.
fn zip_error(e: &zip::result::ZipError) -> String {
    match e {
        zip::result::ZipError::Io(e) => io_error(e),
        e => e.to_string(),
    }
}

fn io_error(e: &std::io::Error) -> String {
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        "the archive ends early (cut short?)".into()
    } else {
        e.to_string()
    }
}

/// The parts of the metadata busnoop uses.
#[derive(Debug, PartialEq, Eq)]
struct Metadata {
    capturefile: String,
    rate: u64,
    unitsize: usize,
    /// Probe bit and name.
    probes: Vec<(usize, String)>,
}

/// Parses the INI metadata: the first `[device N]` section with a `capturefile`.
fn parse_metadata(text: &str) -> Result<Metadata, String> {
    let mut in_device = false;
    let mut found: Option<Metadata> = None;
    let mut current = Metadata {
        capturefile: String::new(),
        rate: 0,
        unitsize: 1,
        probes: Vec::new(),
    };
    let finish = |m: Metadata, found: &mut Option<Metadata>| {
        if found.is_none() && !m.capturefile.is_empty() {
            *found = Some(m);
        }
    };
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            finish(
                std::mem::replace(
                    &mut current,
                    Metadata {
                        capturefile: String::new(),
                        rate: 0,
                        unitsize: 1,
                        probes: Vec::new(),
                    },
                ),
                &mut found,
            );
            in_device = line.starts_with("[device");
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        if !in_device {
            continue;
        }
        let (key, value) = (key.trim(), value.trim());
        match key {
            "capturefile" => current.capturefile = value.to_owned(),
            "samplerate" => {
                current.rate =
                    parse_rate(value).ok_or_else(|| format!("unreadable samplerate {value:?}"))?
            }
            "unitsize" => {
                current.unitsize = value
                    .parse()
                    .ok()
                    .filter(|u| (1..=8).contains(u))
                    .ok_or_else(|| format!("unitsize {value:?} is not 1 to 8"))?
            }
            _ => {
                if let Some(k) = key.strip_prefix("probe")
                    && let Ok(k) = k.parse::<usize>()
                    && (1..=64).contains(&k)
                {
                    current.probes.push((k - 1, value.to_owned()));
                }
            }
        }
    }
    finish(current, &mut found);
    let mut m = found.ok_or("no [device] section with a capturefile")?;
    if m.rate == 0 {
        return Err("no samplerate".into());
    }
    m.probes.retain(|&(bit, _)| bit < 8 * m.unitsize);
    m.probes.sort_by_key(|p| p.0);
    m.probes.dedup_by_key(|p| p.0);
    Ok(m)
}

/// `1 MHz`, `500 kHz`, `1.5 GHz`, `200 Hz`, `1000000` in Hz.
fn parse_rate(text: &str) -> Option<u64> {
    let text = text.trim();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len());
    let (num, unit) = (&text[..split], text[split..].trim());
    let scale: u32 = match unit {
        "" | "Hz" => 0,
        "kHz" | "k" => 3,
        "MHz" | "M" => 6,
        "GHz" | "G" => 9,
        _ => return None,
    };
    let (int, frac) = num.split_once('.').unwrap_or((num, ""));
    if int.is_empty() || frac.len() > scale as usize {
        return None;
    }
    let digits = format!("{int}{frac}{}", "0".repeat(scale as usize - frac.len()));
    digits.parse().ok().filter(|&r| r > 0)
}

/// A sigrok session's logic samples as edges.
pub struct SrWave {
    /// `None` once dropped (then the unzipping thread stops at its next hand-over).
    rx: Option<Receiver<Part>>,
    unzipper: Option<std::thread::JoinHandle<()>>,
    name: String,
    header: Header,
    /// A part received while looking for the metadata.
    pending: Option<Part>,
    unitsize: usize,
    capturefile: String,
    /// Per probe place in the header: byte in the sample and bit mask.
    probes: Vec<(usize, u8)>,
    /// Selected probes (places) with their last level.
    selected: Vec<(usize, u8, Option<bool>)>,
    /// The current entry holds logic samples.
    in_logic: bool,
    /// The last chunk number seen.
    chunk: u64,
    /// Bytes of a sample cut by the end of a block.
    carry: Vec<u8>,
    /// Samples read so far.
    samples: u64,
    ended: bool,
}

impl SrWave {
    /// Starts reading the archive and reads up to its metadata.
    pub fn open(opened: Opened) -> Result<Self, Failure> {
        let (reader, name) = whole_input(opened);
        let (tx, rx) = sync_channel(2);
        let unzipper = std::thread::Builder::new()
            .name("busnoop-unzip".into())
            .spawn(move || unzip(reader, tx))
            .map_err(|e| Failure::Internal(format!("cannot start a thread: {e}")))?;
        let mut wave = SrWave {
            rx: Some(rx),
            unzipper: Some(unzipper),
            name,
            header: Header {
                channels: Vec::new(),
                base: TimeBase::rate(1),
                sample_rate: None,
            },
            pending: None,
            unitsize: 1,
            capturefile: String::new(),
            probes: Vec::new(),
            selected: Vec::new(),
            in_logic: false,
            chunk: 0,
            carry: Vec::new(),
            samples: 0,
            ended: false,
        };
        wave.read_metadata()?;
        Ok(wave)
    }

    /// Reads the entries up to the metadata; it must come before the samples.
    fn read_metadata(&mut self) -> Result<(), Failure> {
        let name = self.name.clone();
        let bad =
            |what: String| Failure::Input(format!("{name}: not a usable sigrok session: {what}"));
        let Some(rx) = self.rx.as_ref() else {
            return Err(bad("the archive reader stopped".into()));
        };
        // Entries up to the metadata; it must come before the samples.
        let mut entry = String::new();
        let mut metadata: Option<Vec<u8>> = None;
        let pending = loop {
            let part = rx
                .recv()
                .map_err(|_| bad("the archive reader stopped".into()))?;
            match part {
                Part::Entry(e) => {
                    if metadata.is_some() {
                        break Part::Entry(e);
                    }
                    if e.starts_with("logic-") {
                        return Err(bad(format!("samples ({e}) before the metadata")));
                    }
                    entry = e;
                    if entry == "metadata" {
                        metadata = Some(Vec::new());
                    }
                }
                Part::Data(d) if entry == "metadata" => {
                    let m = metadata.get_or_insert_with(Vec::new);
                    if m.len() + d.len() > MAX_METADATA {
                        return Err(bad("the metadata is over 64 KiB".into()));
                    }
                    m.extend_from_slice(&d);
                }
                Part::Data(_) => {}
                Part::End if metadata.is_some() => break Part::End,
                Part::End => return Err(bad("a zip archive without sigrok metadata".into())),
                Part::Failed(e) => return Err(bad(e)),
            }
        };
        let metadata = metadata.unwrap_or_default();
        let text = String::from_utf8_lossy(&metadata);
        let m = parse_metadata(&text).map_err(|e| bad(format!("metadata: {e}")))?;
        let channels = m
            .probes
            .iter()
            .map(|(bit, name)| Channel {
                number: *bit,
                name: name.clone(),
            })
            .collect();
        self.probes = m
            .probes
            .iter()
            .map(|&(bit, _)| (bit / 8, 1u8 << (bit % 8)))
            .collect();
        self.header = Header {
            channels,
            base: TimeBase::rate(m.rate),
            sample_rate: Some(m.rate),
        };
        self.pending = Some(pending);
        self.unitsize = m.unitsize;
        self.capturefile = m.capturefile;
        Ok(())
    }

    fn bad(&self, what: &str) -> Failure {
        Failure::Input(format!(
            "{}: not a usable sigrok session: {what}",
            self.name
        ))
    }

    /// An entry starts: is it the next chunk of logic samples?
    fn entry(&mut self, e: &str) -> Result<(), Failure> {
        self.in_logic = false;
        let Some(rest) = e.strip_prefix(self.capturefile.as_str()) else {
            return Ok(());
        };
        let number = if rest.is_empty() {
            1
        } else {
            match rest.strip_prefix('-').and_then(|n| n.parse::<u64>().ok()) {
                Some(n) => n,
                None => return Ok(()),
            }
        };
        if number != self.chunk + 1 {
            return Err(self.bad(&format!(
                "sample chunk {e} where chunk {} belongs",
                self.chunk + 1
            )));
        }
        self.chunk = number;
        self.in_logic = true;
        Ok(())
    }

    /// The edges of the selected probes in `data` (whole samples).
    fn scan(&mut self, data: &[u8], out: &mut Vec<Edge>) {
        let us = self.unitsize;
        let first = self.samples;
        for (slot, sel) in self.selected.iter_mut().enumerate() {
            let (byte, mask, ref mut last) = *sel;
            let slot = slot as u16;
            for (i, sample) in data.chunks_exact(us).enumerate() {
                let high = sample[byte] & mask != 0;
                if *last != Some(high) {
                    *last = Some(high);
                    out.push(Edge {
                        tick: first + i as u64,
                        slot,
                        high,
                    });
                }
            }
        }
        if self.selected.len() > 1 {
            out.sort_by_key(|e| e.tick);
        }
        self.samples += (data.len() / us) as u64;
    }
}

impl Drop for SrWave {
    /// Stops the unzipping thread (its next hand-over fails) and waits for it, so no thread
    /// outlives its reader.
    fn drop(&mut self) {
        self.rx = None;
        if let Some(t) = self.unzipper.take() {
            let _ = t.join();
        }
    }
}

impl super::Wave for SrWave {
    fn header(&self) -> &Header {
        &self.header
    }

    fn select(&mut self, channels: &[usize]) {
        let old = std::mem::take(&mut self.selected);
        self.selected = channels
            .iter()
            .filter_map(|&c| self.probes.get(c).copied())
            .map(|(byte, mask)| {
                let last = old
                    .iter()
                    .find(|o| o.0 == byte && o.1 == mask)
                    .and_then(|o| o.2);
                (byte, mask, last)
            })
            .collect();
    }

    fn read(&mut self, out: &mut Vec<Edge>) -> Result<Step, Failure> {
        loop {
            if self.ended {
                return Ok(Step::End(self.samples));
            }
            let part = match self.pending.take() {
                Some(p) => p,
                None => self
                    .rx
                    .as_ref()
                    .and_then(|rx| rx.recv().ok())
                    .ok_or_else(|| self.bad("the archive reader stopped"))?,
            };
            match part {
                Part::Entry(e) => {
                    if !self.carry.is_empty() {
                        return Err(self.bad("a sample chunk ends inside a sample"));
                    }
                    self.entry(&e)?;
                }
                Part::Data(d) if self.in_logic => {
                    let us = self.unitsize;
                    let mut d = &d[..];
                    if !self.carry.is_empty() {
                        let take = (us - self.carry.len()).min(d.len());
                        self.carry.extend_from_slice(&d[..take]);
                        d = &d[take..];
                        if self.carry.len() == us {
                            let sample = std::mem::take(&mut self.carry);
                            self.scan(&sample, out);
                        }
                    }
                    let whole = d.len() / us * us;
                    self.scan(&d[..whole], out);
                    self.carry.extend_from_slice(&d[whole..]);
                    return Ok(Step::Upto(self.samples));
                }
                Part::Data(_) => {}
                Part::End => {
                    self.ended = true;
                    if self.chunk == 0 {
                        return Err(self.bad("no logic samples"));
                    }
                    if !self.carry.is_empty() {
                        return Err(self.bad("the samples end inside a sample"));
                    }
                }
                Part::Failed(e) => return Err(self.bad(&e)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_metadata_of_old_and_new_sessions() {
        let old = "[global]\nsigrok version=0.3.0\n\n[device 1]\ncapturefile=logic-1\n\
                   total probes=16\nsamplerate=1 MHz\nprobe1=0\nprobe2=1\nunitsize=2\n";
        assert_eq!(
            parse_metadata(old).unwrap(),
            Metadata {
                capturefile: "logic-1".into(),
                rate: 1_000_000,
                unitsize: 2,
                probes: vec![(0, "0".into()), (1, "1".into())],
            }
        );
        let new = "[global]\nsigrok version=0.5.1\n[device 1]\ncapturefile=logic-1\n\
                   total probes=8\nsamplerate=24 MHz\ntotal analog=0\nprobe1=RX\nprobe3=BA+\n\
                   unitsize=1\n";
        let m = parse_metadata(new).unwrap();
        assert_eq!(m.rate, 24_000_000);
        assert_eq!(m.probes, [(0, "RX".into()), (2, "BA+".into())]);
        assert!(parse_metadata("[device 1]\ncapturefile=logic-1\n").is_err());
        assert!(parse_metadata("[global]\n").is_err());
    }

    #[test]
    fn reads_sample_rates() {
        assert_eq!(parse_rate("1 MHz"), Some(1_000_000));
        assert_eq!(parse_rate("500 kHz"), Some(500_000));
        assert_eq!(parse_rate("1.5 MHz"), Some(1_500_000));
        assert_eq!(parse_rate("200 Hz"), Some(200));
        assert_eq!(parse_rate("12000000"), Some(12_000_000));
        assert_eq!(parse_rate("0 Hz"), None);
        assert_eq!(parse_rate("fast"), None);
        assert_eq!(parse_rate("1.0000000001 GHz"), None);
    }
}
