//! Decoder tests: every function's rows, the register map, pairing and timeouts, statistics,
//! chunking.

use super::wire::push_crc;
use super::*;
use crate::row::{Class, Collected, OwnedRow};

/// A frame from its bytes without the CRC.
pub(crate) fn f(bytes: &[u8]) -> Vec<u8> {
    let mut v = bytes.to_vec();
    push_crc(&mut v);
    v
}

/// One request and its response for every public function (MODBUS Application Protocol
/// V1.1b3's examples where it has them), and an exception.
pub(crate) fn exchanges() -> Vec<(Vec<u8>, Vec<u8>)> {
    let mut dev = vec![0x01, 0x2B, 0x0E, 0x01, 0x01, 0x00, 0x00, 0x03];
    for (id, text) in [(0u8, &b"Company"[..]), (1, b"PROD1"), (2, b"V2.11")] {
        dev.extend_from_slice(&[id, text.len() as u8]);
        dev.extend_from_slice(text);
    }
    let pairs: Vec<(Vec<u8>, Vec<u8>)> = vec![
        (vec![1, 1, 0, 0x13, 0, 0x0A], vec![1, 1, 2, 0xCD, 0x01]),
        (
            vec![1, 2, 0, 0xC4, 0, 0x16],
            vec![1, 2, 3, 0xAC, 0xDB, 0x35],
        ),
        (
            vec![1, 3, 0, 0x6B, 0, 3],
            vec![1, 3, 6, 0x02, 0x2B, 0, 0, 0, 0x64],
        ),
        (vec![1, 4, 0, 8, 0, 1], vec![1, 4, 2, 0, 0x0A]),
        (vec![1, 5, 0, 0xAC, 0xFF, 0], vec![1, 5, 0, 0xAC, 0xFF, 0]),
        (vec![1, 6, 0, 1, 0, 3], vec![1, 6, 0, 1, 0, 3]),
        (vec![1, 7], vec![1, 7, 0x6D]),
        (vec![1, 8, 0, 0, 0xA5, 0x37], vec![1, 8, 0, 0, 0xA5, 0x37]),
        (vec![1, 0x0B], vec![1, 0x0B, 0xFF, 0xFF, 0x01, 0x08]),
        (
            vec![1, 0x0C],
            vec![1, 0x0C, 8, 0, 0, 1, 8, 1, 0x21, 0x20, 0],
        ),
        (
            vec![1, 0x0F, 0, 0x13, 0, 0x0A, 2, 0xCD, 0x01],
            vec![1, 0x0F, 0, 0x13, 0, 0x0A],
        ),
        (
            vec![1, 0x10, 0, 1, 0, 2, 4, 0, 0x0A, 1, 2],
            vec![1, 0x10, 0, 1, 0, 2],
        ),
        (vec![1, 0x11], vec![1, 0x11, 3, 0x42, 0xFF, 0x07]),
        (
            vec![1, 0x14, 0x0E, 6, 0, 4, 0, 1, 0, 2, 6, 0, 3, 0, 9, 0, 2],
            vec![
                1, 0x14, 0x0C, 5, 6, 0x0D, 0xFE, 0, 0x20, 5, 6, 0x33, 0xCD, 0, 0x40,
            ],
        ),
        (
            vec![
                1, 0x15, 0x0D, 6, 0, 4, 0, 7, 0, 3, 0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D,
            ],
            vec![
                1, 0x15, 0x0D, 6, 0, 4, 0, 7, 0, 3, 0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D,
            ],
        ),
        (
            vec![1, 0x16, 0, 4, 0, 0xF2, 0, 0x25],
            vec![1, 0x16, 0, 4, 0, 0xF2, 0, 0x25],
        ),
        (
            vec![
                1, 0x17, 0, 3, 0, 6, 0, 0x0E, 0, 3, 6, 0, 0xFF, 0, 0xFF, 0, 0xFF,
            ],
            vec![
                1, 0x17, 0x0C, 0, 0xFE, 0x0A, 0xCD, 0, 1, 0, 3, 0, 0x0D, 0, 0xFF,
            ],
        ),
        (
            vec![1, 0x18, 0x04, 0xDE],
            vec![1, 0x18, 0, 6, 0, 2, 0x01, 0xB8, 0x12, 0x84],
        ),
        (vec![1, 0x2B, 0x0E, 1, 0], dev),
        (vec![1, 3, 0, 0, 0, 0x7F], vec![1, 0x83, 3]),
    ];
    pairs.into_iter().map(|(a, b)| (f(&a), f(&b))).collect()
}

/// Decodes `segments` (bytes, time) with `opts`; checks that byte-by-byte feeding gives the
/// same rows.
pub(crate) fn decode(opts: &Options, segments: &[(Vec<u8>, Option<u64>)]) -> Vec<OwnedRow> {
    let run = |segs: &mut dyn Iterator<Item = (&[u8], Option<u64>)>| {
        let mut d = ModbusDecoder::new(opts.clone());
        let mut out = Collected::default();
        for (b, t) in segs {
            d.push(b, t, &mut out).unwrap();
        }
        d.finish(&mut out).unwrap();
        out.rows
    };
    let whole = run(&mut segments.iter().map(|(b, t)| (&b[..], *t)));
    let bytes = run(&mut segments
        .iter()
        .flat_map(|(b, t)| b.chunks(1).map(move |c| (c, *t))));
    assert_eq!(whole, bytes, "byte by byte");
    whole
}

fn untimed(bytes: &[u8]) -> Vec<OwnedRow> {
    decode(&Options::default(), &[(bytes.to_vec(), None)])
}

fn part<'a>(r: &'a OwnedRow, name: &str) -> Option<&'a str> {
    r.parts.iter().find(|p| p.0 == name).map(|p| p.2.as_str())
}

fn names(r: &OwnedRow) -> Vec<&str> {
    r.parts.iter().map(|p| p.0.as_str()).collect()
}

#[test]
fn every_function_request_and_response_rows() {
    for (req, resp) in exchanges() {
        let rows = untimed(&[req.clone(), resp.clone()].concat());
        assert_eq!(rows.len(), 2, "{rows:?}");
        let fc = req[1];
        let (q, a) = (&rows[0], &rows[1]);
        assert_eq!(q.kind, "Request");
        assert_eq!(q.id, Some(1));
        assert_eq!(q.sensor_no, format!("0x{fc:02X}"));
        assert_eq!(q.sensor, function::name(fc));
        assert_eq!(q.raw, req);
        assert_eq!(
            a.kind,
            if resp[1] & 0x80 != 0 {
                "Exception"
            } else {
                "Response"
            }
        );
        assert_eq!(
            a.sensor_no, q.sensor_no,
            "an exception names the function it answers"
        );
        assert_eq!(a.raw, resp);
        assert!(!a.extra[2].contains("no request"), "{a:?}");
    }
}

#[test]
fn parts_follow_the_output_contract() {
    let ex = exchanges();
    let rows = |i: usize| untimed(&[ex[i].0.clone(), ex[i].1.clone()].concat());
    // FC 1: 10 coils from 0x13
    let r = rows(0);
    assert_eq!(
        (part(&r[0], "start"), part(&r[0], "count")),
        (Some("19"), Some("10"))
    );
    assert_eq!(
        names(&r[1]),
        [
            "C19", "C20", "C21", "C22", "C23", "C24", "C25", "C26", "C27", "C28"
        ]
    );
    // 0xCD = 1100 1101, first coil in bit 0
    let bits: Vec<&str> = r[1].parts.iter().map(|p| p.2.as_str()).collect();
    assert_eq!(bits, ["1", "0", "1", "1", "0", "0", "1", "1", "1", "0"]);
    // FC 3: three registers from 107
    let r = rows(2);
    assert_eq!(names(&r[1]), ["R107", "R108", "R109"]);
    assert_eq!(r[1].value(), "555");
    assert_eq!(r[1].data, "R107=555 R108=0 R109=100");
    assert_eq!(r[0].data, "start=107 count=3");
    // FC 5 and 6: the echo carries the value
    let r = rows(4);
    assert_eq!(names(&r[0]), ["start", "count", "C172"]);
    assert_eq!(names(&r[1]), ["C172"]);
    assert_eq!(part(&r[1], "C172"), Some("1"));
    let r = rows(5);
    assert_eq!(part(&r[0], "R1"), Some("3"));
    assert_eq!(names(&r[1]), ["R1"]);
    // FC 16: the written values, then the response's start and count
    let r = rows(11);
    assert_eq!(names(&r[0]), ["start", "count", "R1", "R2"]);
    assert_eq!(r[0].data, "start=1 count=2 R1=10 R2=258");
    assert_eq!(names(&r[1]), ["start", "count"]);
    // FC 23: the read's start and count; the answer's registers at the read's addresses
    let r = rows(16);
    assert_eq!(part(&r[0], "start"), Some("3"));
    assert_eq!(part(&r[0], "write_start"), Some("14"));
    assert_eq!(names(&r[1])[..2], ["R3", "R4"]);
    // FC 43/14: the objects in the Data cell
    let r = rows(18);
    assert_eq!(
        r[1].data,
        "VendorName=\"Company\" ProductCode=\"PROD1\" MajorMinorRevision=\"V2.11\""
    );
    // the exception: its code
    let r = rows(19);
    assert_eq!(r[1].kind, "Exception");
    assert_eq!(names(&r[1]), ["code"]);
    assert_eq!(part(&r[1], "code"), Some("3"));
    assert_eq!(r[1].data, "Illegal Data Value (3)");
    assert_eq!(r[1].class, Class::Warning);
}

#[test]
fn unpaired_responses_count_from_their_first_value() {
    let ex = exchanges();
    let rows = untimed(&ex[2].1);
    assert_eq!(rows[0].kind, "Response");
    assert_eq!(names(&rows[0]), ["R+0", "R+1", "R+2"]);
    assert!(rows[0].extra[2].contains("no request seen"));
}

/// The reads of a busnoop recording (classic pcap, RTAC serial records): (µs since the first
/// record, bytes).
fn recording_reads(pcap: &[u8]) -> Vec<(Vec<u8>, Option<u64>)> {
    let mut out = Vec::new();
    let mut at = 24;
    let mut first = None;
    while at + 16 <= pcap.len() {
        let word = |i: usize| u32::from_le_bytes(pcap[i..i + 4].try_into().unwrap()) as u64;
        let us = word(at) * 1_000_000 + word(at + 4);
        let len = word(at + 8) as usize;
        let rec = &pcap[at + 16..at + 16 + len];
        let t0 = *first.get_or_insert(us);
        if rec[8] == crate::pcap::rtac::EVENT_RX_DATA {
            out.push((rec[12..].to_vec(), Some(us - t0)));
        }
        at += 16 + len;
    }
    out
}

/// The rows the generator says the session shows: (type, id, function); `timed`: with the rows
/// only a timed source shows.
fn generated_expect(timed: bool) -> Vec<(String, String, String)> {
    include_str!("../../fixtures/modbus-gen.expect")
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split(' ').collect::<Vec<_>>())
        .filter(|w| timed || w.get(3) != Some(&"timed"))
        .map(|w| (w[0].to_owned(), w[1].to_owned(), w[2].to_owned()))
        .collect()
}

fn signature(rows: &[OwnedRow]) -> Vec<(String, String, String)> {
    rows.iter()
        .map(|r| {
            let id = r.id.map_or("-".into(), |i| i.to_string());
            let fc = if r.sensor_no.is_empty() {
                "-".into()
            } else {
                r.sensor_no.clone()
            };
            (r.kind.clone(), id, fc)
        })
        .collect()
}

#[test]
fn generated_session_timed_and_untimed() {
    let reads = recording_reads(include_bytes!("../../fixtures/modbus-gen.pcap"));
    assert!(reads.len() > 100);
    let rows = decode(&Options::default(), &reads);
    assert_eq!(signature(&rows), generated_expect(true));
    // the long response: one row of 125 registers, from many reads
    let long = rows.iter().find(|r| r.parts.len() == 125).unwrap();
    assert_eq!(long.raw.len(), 255);
    assert_eq!(long.parts[124], ("R124".into(), "".into(), "868".into()));
    let longest_read = reads.iter().map(|r| r.0.len()).max().unwrap();
    assert!(longest_read <= 62, "{longest_read}");
    // timeouts, the late answer, the retry, response times
    let timeouts: Vec<&OwnedRow> = rows.iter().filter(|r| r.kind == "Timeout").collect();
    assert_eq!(timeouts.len(), 3);
    assert!(
        timeouts[0].extra[2].contains("no answer within 1000 ms"),
        "{:?}",
        timeouts[0]
    );
    assert!(
        rows.iter().any(|r| r.extra[2].starts_with("retry 1, 12")),
        "retry note"
    );
    assert!(
        rows.iter()
            .any(|r| r.kind == "Response" && r.extra[2].contains("late"))
    );
    let answered = rows
        .iter()
        .filter(|r| r.kind == "Response" && !r.extra[1].is_empty());
    assert!(answered.count() > 40);
    // the same bytes without times
    let bytes = include_bytes!("../../fixtures/modbus-gen.bin");
    let rows = decode(&Options::default(), &[(bytes.to_vec(), None)]);
    assert_eq!(signature(&rows), generated_expect(false));
    assert_eq!(bytes.len(), reads.iter().map(|r| r.0.len()).sum::<usize>());
}

/// A small deterministic generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn word(&mut self, below: u64) -> [u8; 2] {
        (self.below(below) as u16).to_be_bytes()
    }
}

/// A generated session: its segments (bytes, read time) and the rows it must show.
struct Session {
    segments: Vec<(Vec<u8>, Option<u64>)>,
    expect: Vec<(String, String, String)>,
}

/// `n` exchanges of a master with slaves 1-9: reads of registers (start addresses whose high
/// byte reads as a plausible byte count too) and coils, writes, read/write, the fixed examples
/// of every function, exceptions, unanswered requests (and their retries), responses with a
/// bit error, broadcasts, long responses; RS-485 turnaround bytes after a fifth of the frames.
/// `timed`: frames get read times (a few glued into one read), 30-90 ms apart, 1.5 s after an
/// unanswered request.
fn session(seed: u64, n: usize, timed: bool) -> Session {
    let mut r = Rng(seed | 1);
    let fixed = exchanges();
    let mut b = Builder {
        s: Session {
            segments: Vec::new(),
            expect: Vec::new(),
        },
        t: 0,
        glue: false,
        timed,
    };
    let gap = |r: &mut Rng| 30_000 + r.below(60_000);
    for _ in 0..n {
        let slave = 1 + r.below(9) as u8;
        let (req, resp): (Vec<u8>, Option<Vec<u8>>) = match r.below(12) {
            0..=2 => {
                let fc = 3 + r.below(2) as u8;
                let count = 1 + r.below(125) as u16;
                let mut resp = vec![slave, fc, 2 * count as u8];
                for _ in 0..count {
                    resp.extend_from_slice(&r.word(65_536));
                }
                let start = r.word(0x0800);
                let req = vec![slave, fc, start[0], start[1], 0, count as u8];
                (f(&req), Some(f(&resp)))
            }
            3 => {
                let fc = 1 + r.below(2) as u8;
                let count = 1 + r.below(2000) as u16;
                let nb = count.div_ceil(8) as usize;
                let mut resp = vec![slave, fc, nb as u8];
                resp.extend((0..nb).map(|_| r.next() as u8));
                let start = r.word(0x0300);
                let c = count.to_be_bytes();
                (
                    f(&[slave, fc, start[0], start[1], c[0], c[1]]),
                    Some(f(&resp)),
                )
            }
            4..=5 => {
                let (q, a) = fixed[r.below(fixed.len() as u64) as usize].clone();
                let (mut q, mut a) = (q[..q.len() - 2].to_vec(), a[..a.len() - 2].to_vec());
                q[0] = slave;
                a[0] = slave;
                (f(&q), Some(f(&a)))
            }
            6 => {
                let v = r.word(65_536);
                let q = f(&[slave, 6, 0, r.below(200) as u8, v[0], v[1]]);
                (q.clone(), Some(q))
            }
            7 => {
                let n = 1 + r.below(20) as u8;
                let mut q = vec![slave, 16, 0, 10, 0, n, 2 * n];
                for _ in 0..n {
                    q.extend_from_slice(&r.word(65_536));
                }
                (f(&q), Some(f(&[slave, 16, 0, 10, 0, n])))
            }
            8 => (
                f(&[slave, 3, 0x27, 0x10, 0, 2]),
                Some(f(&[slave, 0x83, 1 + r.below(4) as u8])),
            ),
            9 => (f(&[slave, 4, 0, r.below(100) as u8, 0, 2]), None),
            10 => {
                // a bit error in the response's data
                let q = f(&[slave, 3, 0, 0, 0, 2]);
                let mut a = f(&[slave, 3, 4, 1, 2, 3, 4]);
                a[3 + r.below(4) as usize] ^= 1 << r.below(8);
                (q, Some(a))
            }
            _ => {
                let v = r.word(65_536);
                (f(&[0, 6, 0, 1, v[0], v[1]]), None)
            }
        };
        let fc = req[1];
        let g = gap(&mut r);
        b.send(&mut r, req.clone(), ("Request", req[0], fc), g);
        match resp {
            Some(a) if crate::modbus::wire::crc_ok(&a) => {
                let kind = if a[1] & 0x80 != 0 {
                    "Exception"
                } else {
                    "Response"
                };
                let g = 3_000 + r.below(20_000);
                b.send(&mut r, a, (kind, slave, fc), g);
            }
            Some(a) => {
                let g = 3_000 + r.below(20_000);
                b.send(&mut r, a, ("BadCRC", slave, fc), g)
            }
            None if req[0] == 0 => {}
            None => {
                // unanswered: a Timeout row comes before whatever is next; sometimes a retry
                let timeout = ("Timeout".into(), slave.to_string(), format!("0x{fc:02X}"));
                b.s.expect.push(timeout);
                b.t += 1_500_000;
                b.glue = false;
                if r.below(2) == 0 {
                    b.send(&mut r, req.clone(), ("Request", slave, fc), 0);
                    let a = f(&[slave, 4, 4, 0, 1, 0, 2]);
                    b.send(&mut r, a, ("Response", slave, fc), 5_000);
                }
            }
        }
    }
    // A request unanswered at the end is counted, not a row.
    if b.s.expect.last().is_some_and(|e| e.0 == "Timeout") {
        b.s.expect.pop();
    }
    b.s
}

struct Builder {
    s: Session,
    t: u64,
    glue: bool,
    timed: bool,
}

impl Builder {
    /// A frame `gap` µs after the last, shown as `row`; maybe glued to the read before, maybe
    /// followed by a turnaround byte.
    fn send(&mut self, r: &mut Rng, bytes: Vec<u8>, row: (&str, u8, u8), gap: u64) {
        self.t += gap;
        let s = &mut self.s;
        // Two frames come in one read when the second follows within the adapter's latency.
        match s.segments.last_mut() {
            Some(last) if self.glue && gap < 16_000 => last.0.extend_from_slice(&bytes),
            _ => s.segments.push((bytes, self.timed.then_some(self.t))),
        }
        self.glue = r.below(4) == 0;
        s.expect
            .push((row.0.into(), row.1.to_string(), format!("0x{:02X}", row.2)));
        if r.below(5) == 0 {
            let stray = [0x00u8, 0xFF, 0xFE][r.below(3) as usize];
            s.segments.last_mut().unwrap().0.push(stray);
            s.expect.push(("Garbage".into(), "-".into(), "-".into()));
        }
    }
}

/// Splits segments at the given cut points (a chunk never mixes two times).
fn rechunk(segments: &[(Vec<u8>, Option<u64>)], cuts: &[usize]) -> Vec<(Vec<u8>, Option<u64>)> {
    let mut out = Vec::new();
    let mut c = cuts.iter().cycle();
    for (bytes, time) in segments {
        let mut rest = &bytes[..];
        while !rest.is_empty() {
            let n = (*c.next().unwrap_or(&1)).clamp(1, rest.len());
            out.push((rest[..n].to_vec(), *time));
            rest = &rest[n..];
        }
    }
    out
}

#[test]
fn generated_sessions_decode_as_made() {
    for seed in 0..40 {
        for timed in [false, true] {
            let s = session(seed * 7919 + 1, 30, timed);
            let rows = decode(&Options::default(), &s.segments);
            let got = signature(&rows);
            if got != s.expect {
                let i = (0..got.len().min(s.expect.len()))
                    .find(|&i| got[i] != s.expect[i])
                    .unwrap_or(0);
                panic!(
                    "seed {seed} timed {timed}: row {i}: got {:?}, want {:?}\n{:#?}",
                    &got[i..(i + 3).min(got.len())],
                    &s.expect[i..(i + 3).min(s.expect.len())],
                    &rows[i.saturating_sub(2)..(i + 3).min(rows.len())]
                );
            }
        }
    }
}

mod props {
    use super::*;
    use proptest::prelude::*;

    fn config() -> ProptestConfig {
        let mut c = ProptestConfig::with_cases(
            std::env::var("PROPTEST_CASES")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(48),
        );
        if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
            c.rng_seed = proptest::test_runner::RngSeed::Fixed(0x0DB0_5028);
        }
        c
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn chunking_does_not_change_rows(
            timed in any::<bool>(),
            seed in any::<u64>(),
            cuts in proptest::collection::vec(1usize..70, 1..20),
        ) {
            let s = session(seed, 25, timed);
            let whole = if timed {
                s.segments.clone()
            } else {
                vec![(s.segments.iter().flat_map(|x| x.0.clone()).collect(), None)]
            };
            let a = decode(&Options::default(), &whole);
            let b = decode(&Options::default(), &rechunk(&s.segments, &cuts));
            prop_assert_eq!(&a, &b);
            prop_assert_eq!(signature(&a), s.expect);
        }

        #[test]
        fn recovery_after_garbage(
            seed in any::<u64>(),
            garbage in proptest::collection::vec(any::<u8>(), 1..300),
        ) {
            let s = session(seed, 12, false);
            let mut all = garbage.clone();
            all.extend(s.segments.iter().flat_map(|x| x.0.clone()));
            let rows = decode(&Options::default(), &[(all, None)]);
            let got = signature(&rows);
            // every row of the session after the garbage; the first request may be taken
            // for the answer to a request read in the garbage, so compare from the second
            let want = &s.expect[1..];
            prop_assert!(got.ends_with(want), "{:?}\nwant {:?}", &got, want);
        }

        #[test]
        fn garbage_never_panics(
            data in proptest::collection::vec(any::<u8>(), 0..700),
            cut in 1usize..64,
        ) {
            let segs: Vec<(Vec<u8>, Option<u64>)> = data
                .chunks(cut)
                .enumerate()
                .map(|(i, c)| (c.to_vec(), Some(i as u64 * 7_000)))
                .collect();
            decode(&Options::default(), &segs);
            // biased: addresses, function codes, zero bytes, ':' and hex digits
            let biased: Vec<u8> = data.iter().map(|b| match b % 7 {
                0 => 1, 1 => 3, 2 => 0, 3 => b':', 4 => b'0' + b % 10, _ => *b }).collect();
            let ascii = Options { framing: Framing::Ascii, ..Options::default() };
            decode(&ascii, &[(biased.clone(), None)]);
            #[cfg(feature = "selfcheck")]
            {
                crate::selfcheck::modbus(&data);
                crate::selfcheck::modbus(&biased);
            }
        }
    }
}

#[test]
fn the_register_map_names_values_with_units() {
    let map = RegisterMap::parse(
        r#"
[modbus.slaves]
Boiler = 1
[modbus.registers]
"Boiler/100" = { name = "Flow temperature", type = "i16", scale = 0.1, unit = "°C" }
"1/101" = { name = "Power", type = "f32", order = "CDAB", unit = "kW" }
"*/200" = "Mode"
"#,
    )
    .unwrap();
    let opts = Options {
        map,
        ..Options::default()
    };
    // 100..104: -1.5 °C, 123.456 kW (low register first), an unnamed register, one half of a
    // value that does not fit
    let req = f(&[1, 3, 0, 100, 0, 4]);
    let resp = f(&[1, 3, 8, 0xFF, 0xF1, 0xE9, 0x79, 0x42, 0xF6, 0x00, 0x07]);
    let rows = decode(&opts, &[([req, resp].concat(), None)]);
    let r = &rows[1];
    assert_eq!(r.device, "Boiler");
    assert_eq!(
        r.parts,
        [
            ("Flow temperature".into(), "°C".into(), "-1.5".into()),
            ("Power".into(), "kW".into(), "123.456".into()),
            ("R103".into(), "".into(), "7".into()),
        ]
    );
    assert_eq!(r.data, "Flow temperature=-1.5 °C Power=123.456 kW R103=7");
    assert_eq!(r.extra[0], "°C", "the Unit column: the first value's");
    // a read that ends in the middle of the f32: its first register stays raw
    let req = f(&[1, 3, 0, 100, 0, 2]);
    let resp = f(&[1, 3, 4, 0, 10, 0xE9, 0x79]);
    let rows = decode(&opts, &[([req, resp].concat(), None)]);
    assert_eq!(rows[1].data, "Flow temperature=1.0 °C R101=59769");
    // every slave's register 200, in a write too; another slave has no name
    let w = f(&[9, 6, 0, 200, 0, 3]);
    let rows = decode(&opts, &[([w.clone(), w].concat(), None)]);
    assert_eq!(rows[0].data, "start=200 count=1 Mode=3");
    assert_eq!(rows[1].data, "Mode=3");
    assert_eq!(rows[1].device, "");
    // input registers: the same names (no table given)
    let req = f(&[1, 4, 0, 100, 0, 1]);
    let resp = f(&[1, 4, 2, 0, 5]);
    let rows = decode(&opts, &[([req, resp].concat(), None)]);
    assert_eq!(rows[1].data, "Flow temperature=0.5 °C");
}

#[test]
fn timeouts_late_answers_and_statistics() {
    let opts = Options {
        timeout_ms: 200,
        ..Options::default()
    };
    let req = f(&[3, 4, 0, 0, 0, 1]);
    let resp = f(&[3, 4, 2, 0, 9]);
    let exc = f(&[3, 0x84, 2]);
    let segs = vec![
        (req.clone(), Some(0)),
        (resp.clone(), Some(12_000)),
        (req.clone(), Some(100_000)),
        // no answer: the deadline passes before the next request
        (req.clone(), Some(500_000)),
        (resp.clone(), Some(900_000)), // late
        (req.clone(), Some(1_000_000)),
        (exc, Some(1_020_000)),
        (req.clone(), Some(2_000_000)),
    ];
    let mut d = ModbusDecoder::new(opts.clone());
    let mut out = Collected::default();
    for (b, t) in &segs {
        crate::protocol::Decoder::push(&mut d, b, *t, &mut out).unwrap();
    }
    crate::protocol::Decoder::idle(&mut d, 2_100_000, &mut out).unwrap();
    crate::protocol::Decoder::idle(&mut d, 2_300_000, &mut out).unwrap();
    crate::protocol::Decoder::finish(&mut d, &mut out).unwrap();
    let kinds: Vec<&str> = out.rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(
        kinds,
        [
            "Request",
            "Response",
            "Request",
            "Timeout",
            "Request",
            "Timeout",
            "Response",
            "Request",
            "Exception",
            "Request",
            "Timeout"
        ]
    );
    let r = &out.rows;
    assert_eq!(r[1].extra[1], "12.0", "response time");
    assert_eq!(r[3].micros, Some(300_000), "at the deadline");
    assert_eq!(r[3].extra[2], "no answer within 200 ms");
    assert_eq!(r[3].data, "start=0 count=1");
    assert!(r[4].extra[2].starts_with("retry 1, 400.0 ms"), "{:?}", r[4]);
    assert_eq!(r[6].extra[2], "late: after the 200 ms timeout");
    assert_eq!(r[6].extra[1], "400.0");
    assert_eq!(r[10].micros, Some(2_200_000), "reported on an idle line");
    let st = d.function_stats(3, 4).unwrap();
    assert_eq!(
        (
            st.requests,
            st.responses,
            st.exception_total(),
            st.retries,
            st.timeouts,
            st.late
        ),
        (5, 2, 1, 1, 3, 1)
    );
    assert_eq!(st.times.count, 3);
    let report = crate::protocol::Decoder::stats(&d).to_string();
    assert!(
        report.starts_with("Modbus RTU, 19200 8E1, master timeout 200 ms"),
        "{report}"
    );
    assert!(report.contains("0x04 Read Input Registers"), "{report}");
    assert!(
        report.contains("exceptions: 2 Illegal Data Address ×1"),
        "{report}"
    );
    let problems = crate::protocol::Decoder::problems(&d).line().unwrap();
    assert_eq!(
        problems,
        "Modbus: 3 timeouts, 1 retry, 1 exception in 8 valid frames"
    );
}

#[test]
fn bad_answers_spoil_the_timeout_and_count_for_their_pair() {
    let req = f(&[5, 3, 0, 0, 0, 1]);
    let mut bad = f(&[5, 3, 2, 0, 1]);
    bad[4] ^= 1;
    let resp = f(&[5, 3, 2, 0, 1]);
    let rows = decode(
        &Options::default(),
        &[([req.clone(), resp, req.clone(), bad, req].concat(), None)],
    );
    let kinds: Vec<&str> = rows.iter().map(|r| r.kind.as_str()).collect();
    assert_eq!(
        kinds,
        ["Request", "Response", "Request", "BadCRC", "Request"]
    );
    assert_eq!((rows[3].id, rows[3].sensor_no.as_str()), (Some(5), "0x03"));
    assert!(rows[3].parts.is_empty());
    assert_eq!(rows[3].class, Class::Error);
}

/// The Data cell and numbers of the common frames written in one pass (`fast.rs`) are those
/// `describe` writes: every function's example, paired and unpaired, and random frames of
/// functions 1-6, 15 and 16 (any length, counts that do not fit, coil values that are neither
/// on nor off, responses paired with any request).
#[test]
fn fast_cells_match_describe() {
    use super::fast::Fast;
    use super::pairing::Req;
    use super::pdu::{Content, describe, request_info};
    use super::wire::Kind;
    let map = RegisterMap::default();
    let mut cases: Vec<(Vec<u8>, Kind, Option<Req>)> = Vec::new();
    for (req, resp) in exchanges() {
        let info = request_info(&req);
        let kind = if resp[1] & 0x80 != 0 {
            Kind::Exception
        } else {
            Kind::Response
        };
        cases.push((req, Kind::Request, None));
        cases.push((resp.clone(), kind, Some(info)));
        cases.push((resp, kind, None));
    }
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    for _ in 0..50_000 {
        let fc = [1u8, 2, 3, 4, 5, 6, 15, 16][(next() % 8) as usize];
        let len = 2 + (next() % 40) as usize;
        let mut pdu: Vec<u8> = (0..len).map(|_| next() as u8).collect();
        pdu[1] = fc;
        if next() % 2 == 0 && len > 6 {
            pdu[5] %= 20; // counts that fit now and then
            pdu[4] = 0;
        }
        let kind = if next() % 2 == 0 {
            Kind::Request
        } else {
            Kind::Response
        };
        let req = (next() % 3 != 0).then(|| Req {
            slave: pdu[0],
            function: if next() % 4 == 0 { 3 } else { fc },
            start: next() as u16,
            count: (next() % 300) as u16,
        });
        cases.push((pdu, kind, req));
    }
    let mut fast = Fast::default();
    let mut covered = 0;
    for (pdu, kind, req) in cases {
        let mut want = Content::default();
        describe(&pdu, kind, req.as_ref(), &map, &mut want);
        let mut got = Content::default();
        if !fast.describe(&pdu, kind, req.as_ref(), &mut got) {
            continue;
        }
        covered += 1;
        let text = fast.text();
        assert_eq!(text, want.data, "{pdu:02X?} {kind:?} {req:?}");
        assert_eq!(got.note, want.note, "{pdu:02X?} {kind:?} {req:?}");
        let parts: Vec<(String, String, String, f64)> = want.nums.with_parts(&map, |p| {
            p.iter()
                .map(|p| (p.name.into(), p.unit.into(), p.text.into(), p.value))
                .collect()
        });
        let fast_parts: Vec<(String, String, String, f64)> = fast
            .parts(text)
            .iter()
            .map(|p| (p.name.into(), p.unit.into(), p.text.into(), p.value))
            .collect();
        assert_eq!(fast_parts, parts, "{pdu:02X?} {kind:?} {req:?}");
    }
    assert!(covered > 30_000, "{covered}");
}
