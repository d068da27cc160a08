//! Writers of logic-analyzer traces from known characters, for the tests and the fuzz seeds:
//! characters on a line ([`levels`]: at a chosen sample rate, inverted or not, with jitter and
//! glitches), then the samples as a sigrok session, a VCD file or a Saleae CSV export, and
//! characters as a Saleae async-serial export.

use std::io::Write;

use crate::protocol::{Line, Parity};

/// How characters are sent.
#[derive(Clone, Copy, Debug)]
pub struct Signal {
    pub line: Line,
    /// The sender's real rate (may be off the nominal one).
    pub baud: f64,
    /// Idle low.
    pub inverted: bool,
}

/// A channel sampled: its level at sample 0 and the samples at which it changes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Levels {
    pub start_high: bool,
    /// Strictly increasing sample numbers of level changes.
    pub changes: Vec<u64>,
    /// Samples in the trace.
    pub samples: u64,
    /// The sample at which each character's start bit is first seen.
    pub starts: Vec<u64>,
}

impl Levels {
    /// The level at sample `i`.
    pub fn at(&self, i: u64) -> bool {
        let flips = self.changes.partition_point(|&c| c <= i);
        self.start_high ^ (flips % 2 == 1)
    }

    /// µs of each character's start, as a reader of the trace at `rate` Hz must give them.
    pub fn start_micros(&self, rate: u64) -> Vec<u64> {
        self.starts
            .iter()
            .map(|&s| (u128::from(s) * 1_000_000 / u128::from(rate)) as u64)
            .collect()
    }
}

/// Disturbances of the ideal waveform.
#[derive(Clone, Debug, Default)]
pub struct Noise {
    /// Every edge moves by up to this fraction of a bit, either way (seeded, repeatable).
    pub jitter: f64,
    pub seed: u64,
    /// Pulses of the opposite level: (start, width) in ns.
    pub glitches: Vec<(u64, u64)>,
}

/// The bits of one character on the wire (logical: true = idle level).
fn char_bits(line: &Line, value: u8) -> Vec<bool> {
    let mut bits = vec![false];
    let data = usize::from(line.data_bits.clamp(5, 8));
    bits.extend((0..data).map(|i| value >> i & 1 == 1));
    let ones = (value & ((1u16 << data) - 1) as u8).count_ones();
    match line.parity {
        Parity::None => {}
        Parity::Even => bits.push(ones % 2 == 1),
        Parity::Odd => bits.push(ones.is_multiple_of(2)),
    }
    bits.extend(std::iter::repeat_n(
        true,
        usize::from(line.stop_bits.max(1)),
    ));
    bits
}

/// A small repeatable random number generator (xorshift).
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `chars` (start time in ns, value; in order, not overlapping) sent as `signal` and sampled at
/// `rate` Hz for `end_ns`.
pub fn levels(
    signal: &Signal,
    chars: &[(u64, u8)],
    rate: u64,
    end_ns: u64,
    noise: &Noise,
) -> Levels {
    let bit_ns = 1e9 / signal.baud;
    // Ideal logical edges: (ns, level from then on); the line idles before the first.
    let mut edges: Vec<(f64, bool)> = Vec::new();
    let mut start_edges = Vec::new();
    for &(t, v) in chars {
        let mut level = true;
        for (i, b) in char_bits(&signal.line, v).into_iter().enumerate() {
            if b != level {
                if i == 0 {
                    start_edges.push(edges.len());
                }
                edges.push((t as f64 + i as f64 * bit_ns, b));
                level = b;
            }
        }
    }
    let mut rng = Rng(noise.seed | 1);
    for e in &mut edges {
        e.0 += (rng.unit() * 2.0 - 1.0) * noise.jitter * bit_ns;
    }
    // Sample numbers at which each edge is first seen.
    let sample = |ns: f64| (ns.max(0.0) * rate as f64 / 1e9).ceil() as u64;
    let starts = start_edges.iter().map(|&i| sample(edges[i].0)).collect();
    let mut flips: Vec<u64> = Vec::new();
    let mut level = true;
    for &(ns, l) in &edges {
        if l != level {
            flips.push(sample(ns));
            level = l;
        }
    }
    for &(at, width) in &noise.glitches {
        flips.push(sample(at as f64));
        flips.push(sample((at + width) as f64));
    }
    flips.sort_unstable();
    // Two flips at one sample cancel.
    let mut changes: Vec<u64> = Vec::new();
    for f in flips {
        if changes.last() == Some(&f) {
            changes.pop();
        } else {
            changes.push(f);
        }
    }
    let samples = sample(end_ns as f64).max(changes.last().map_or(1, |&c| c + 1));
    // A change at sample 0 is the level there.
    let mut start_high = !signal.inverted;
    if changes.first() == Some(&0) {
        changes.remove(0);
        start_high = !start_high;
    }
    Levels {
        start_high,
        changes,
        samples,
        starts,
    }
}

/// Characters `chars` back to back with `gap_bits` idle bits between them from `start_ns`,
/// with their start times.
pub fn back_to_back(
    line: &Line,
    baud: f64,
    bytes: &[u8],
    start_ns: u64,
    gap_bits: f64,
) -> Vec<(u64, u8)> {
    let per = (f64::from(line.bits_per_char()) + gap_bits) * 1e9 / baud;
    bytes
        .iter()
        .enumerate()
        .map(|(i, &b)| (start_ns + (i as f64 * per).round() as u64, b))
        .collect()
}

/// The samples of `channels` (probe k = channel k) as a sigrok session file.
pub fn sr(channels: &[(&str, &Levels)], rate: u64, chunk_samples: u64, deflate: bool) -> Vec<u8> {
    use zip::write::SimpleFileOptions;
    let unitsize = channels.len().div_ceil(8).max(1);
    let samples = channels.iter().map(|c| c.1.samples).max().unwrap_or(0);
    let method = if deflate {
        zip::CompressionMethod::Deflated
    } else {
        zip::CompressionMethod::Stored
    };
    let opts = SimpleFileOptions::default().compression_method(method);
    let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    z.start_file("version", SimpleFileOptions::default())
        .unwrap();
    z.write_all(b"2").unwrap();
    z.start_file("metadata", opts).unwrap();
    let mut meta = format!(
        "[global]\nsigrok version=0.5.2\n\n[device 1]\ncapturefile=logic-1\n\
         total probes={}\nsamplerate={}\ntotal analog=0\n",
        8 * unitsize,
        rate_text(rate)
    );
    for (i, (name, _)) in channels.iter().enumerate() {
        meta.push_str(&format!("probe{}={name}\n", i + 1));
    }
    meta.push_str(&format!("unitsize={unitsize}\n"));
    z.write_all(meta.as_bytes()).unwrap();
    // Levels walked change by change.
    let mut cursors: Vec<(bool, usize)> = channels.iter().map(|c| (c.1.start_high, 0)).collect();
    let mut chunk = 1;
    let mut i = 0;
    while i < samples {
        z.start_file(format!("logic-1-{chunk}"), opts).unwrap();
        let end = (i + chunk_samples.max(1)).min(samples);
        let mut data = Vec::with_capacity(((end - i) as usize) * unitsize);
        for s in i..end {
            let mut sample = vec![0u8; unitsize];
            for (k, (_, lv)) in channels.iter().enumerate() {
                let (level, next) = &mut cursors[k];
                while lv.changes.get(*next) == Some(&s) {
                    *level = !*level;
                    *next += 1;
                }
                if *level {
                    sample[k / 8] |= 1 << (k % 8);
                }
            }
            data.extend_from_slice(&sample);
        }
        z.write_all(&data).unwrap();
        chunk += 1;
        i = end;
    }
    z.finish().unwrap().into_inner()
}

/// `1 MHz`, `500 kHz`, `1234 Hz`, as sigrok writes rates.
fn rate_text(rate: u64) -> String {
    for (unit, scale) in [("GHz", 1_000_000_000), ("MHz", 1_000_000), ("kHz", 1_000)] {
        if rate >= scale && rate.is_multiple_of(scale) {
            return format!("{} {unit}", rate / scale);
        }
    }
    format!("{rate} Hz")
}

/// Merged changes of all channels: (sample, channel, level).
fn merged(channels: &[(&str, &Levels)]) -> Vec<(u64, usize, bool)> {
    let mut all = Vec::new();
    for (k, (_, lv)) in channels.iter().enumerate() {
        let mut level = lv.start_high;
        for &c in &lv.changes {
            level = !level;
            all.push((c, k, level));
        }
    }
    all.sort_by_key(|a| (a.0, a.1));
    all
}

/// The samples as a VCD file with a timescale of `tick_ps` picoseconds (which must divide the
/// sample period), as sigrok writes it.
pub fn vcd(channels: &[(&str, &Levels)], rate: u64, tick_ps: u64) -> Vec<u8> {
    let period_ps = 1_000_000_000_000 / rate;
    assert_eq!(
        period_ps * rate,
        1_000_000_000_000,
        "rate must divide 1 THz"
    );
    assert_eq!(period_ps % tick_ps, 0, "tick must divide the sample period");
    let per = period_ps / tick_ps;
    let id = |k: usize| char::from(b'!' + k as u8);
    let mut s = String::from("$date Thu Jan  1 00:00:00 2026 $end\n$version busnoop test $end\n");
    s.push_str(&format!(
        "$comment\n  Acquisition with {n}/{n} channels at {}\n$end\n",
        rate_text(rate),
        n = channels.len()
    ));
    s.push_str(&format!(
        "$timescale {tick_ps} ps $end\n$scope module libsigrok $end\n"
    ));
    for (k, (name, _)) in channels.iter().enumerate() {
        s.push_str(&format!("$var wire 1 {} {name} $end\n", id(k)));
    }
    s.push_str("$upscope $end\n$enddefinitions $end\n#0");
    for (k, (_, lv)) in channels.iter().enumerate() {
        s.push_str(&format!(" {}{}", u8::from(lv.start_high), id(k)));
    }
    s.push('\n');
    let mut last = 0;
    for (sample, k, level) in merged(channels) {
        if sample != last {
            s.push_str(&format!("#{}", sample * per));
            last = sample;
        }
        s.push_str(&format!(" {}{}\n", u8::from(level), id(k)));
    }
    let samples = channels.iter().map(|c| c.1.samples).max().unwrap_or(0);
    s.push_str(&format!("#{}\n", samples * per));
    s.into_bytes()
}

/// Seconds with 12 decimals: `sample / rate` rounded down to the picosecond.
fn seconds(sample: u64, rate: u64) -> String {
    let ps = u128::from(sample) * 1_000_000_000_000 / u128::from(rate);
    format!("{}.{:012}", ps / 1_000_000_000_000, ps % 1_000_000_000_000)
}

/// The samples as a Saleae Logic 2 digital CSV export (a last line at the end of the trace).
pub fn saleae_csv(channels: &[(&str, &Levels)], rate: u64) -> Vec<u8> {
    let mut s = String::from("Time [s]");
    for (name, _) in channels {
        s.push(',');
        s.push_str(name);
    }
    s.push('\n');
    let mut levels: Vec<bool> = channels.iter().map(|c| c.1.start_high).collect();
    let row = |s: &mut String, sample: u64, levels: &[bool]| {
        s.push_str(&seconds(sample, rate));
        for &l in levels {
            s.push(',');
            s.push(if l { '1' } else { '0' });
        }
        s.push('\n');
    };
    row(&mut s, 0, &levels);
    let all = merged(channels);
    let mut i = 0;
    while i < all.len() {
        let sample = all[i].0;
        while i < all.len() && all[i].0 == sample {
            levels[all[i].1] = all[i].2;
            i += 1;
        }
        row(&mut s, sample, &levels);
    }
    let samples = channels.iter().map(|c| c.1.samples).max().unwrap_or(0);
    row(&mut s, samples, &levels);
    s.into_bytes()
}

/// Characters (µs, value, framing error, parity error) as a Saleae Logic 1 async-serial
/// export.
pub fn saleae_serial(chars: &[(u64, u8, bool, bool)]) -> Vec<u8> {
    let mut s = String::from("Time [s],Value,Parity Error,Framing Error\n");
    for &(us, v, framing, parity) in chars {
        s.push_str(&format!(
            "{}.{:06},0x{v:02X},{},{}\n",
            us / 1_000_000,
            us % 1_000_000,
            if parity { "Error" } else { "" },
            if framing { "Error" } else { "" }
        ));
    }
    s.into_bytes()
}
