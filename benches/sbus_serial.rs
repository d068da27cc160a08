//! Serial S-Bus replay benchmark: generates a raw data-mode (SM2) capture and a break-mode (SM0)
//! capture of a master polling eight stations, and measures decode-only and to-TSV throughput
//! and peak memory, pinned to one core.
//!
//! ```sh
//! cargo bench --bench sbus_serial                       # 64 MiB per mode
//! BUSNOOP_BENCH_MB=256 cargo bench --bench sbus_serial
//! ```

mod common;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use busnoop::sbus::telegram::{CrcBasis, encode_break_request, encode_break_response, encode_data};
use busnoop::sbus::{Mode, Options, SerialDecoder};
use common::{Rng, best_of, busnoop, children_peak_kb, decode_file, pin_to_core0};

/// One request/answer exchange: read 1-8 registers (answered with their values), write a
/// register (ACK) or read 8 flags; 2 % NAK, 1 % no answer; register values that need DLE
/// escaping (B5/C5) in a quarter of the answers.
fn exchange(rng: &mut Rng, mode: Mode, out: &mut Vec<u8>) {
    let station = 1 + rng.below(8) as u8;
    let kind = rng.below(10);
    let (request, answer): (Vec<u8>, Option<Vec<u8>>) = match kind {
        0..=5 => {
            let n = 1 + rng.below(8) as u8;
            let addr = rng.below(1000) as u16;
            let mut req = vec![station, 0x06, n - 1];
            req.extend_from_slice(&addr.to_be_bytes());
            let mut data = Vec::new();
            for _ in 0..n {
                let mut v = rng.next() as u32;
                if rng.below(4) == 0 {
                    v = (v & 0xFFFF_0000) | 0xB5C5;
                }
                data.extend_from_slice(&v.to_be_bytes());
            }
            (req, Some(data))
        }
        6..=7 => {
            let addr = rng.below(1000) as u16;
            let mut req = vec![station, 0x0E, 5];
            req.extend_from_slice(&addr.to_be_bytes());
            req.extend_from_slice(&(rng.next() as u32).to_be_bytes());
            (req, None)
        }
        _ => {
            let addr = rng.below(1000) as u16;
            let mut req = vec![station, 0x02, 7];
            req.extend_from_slice(&addr.to_be_bytes());
            (req, Some(vec![rng.next() as u8]))
        }
    };
    let fate = rng.below(100);
    match mode {
        Mode::Break => {
            out.push(0x00); // the break before the station address
            encode_break_request(out, request[0], request[1], &request[2..]);
            match (fate, answer) {
                (0, _) => {}
                (1 | 2, _) => out.push(0x15),
                (_, Some(data)) => encode_break_response(out, &data),
                (_, None) => out.push(0x06),
            }
        }
        _ => {
            encode_data(out, 0x00, &request, CrcBasis::Escaped);
            match (fate, answer) {
                (0, _) => {}
                (1 | 2, _) => encode_data(out, 0x02, &[0x00, 0x01], CrcBasis::Escaped),
                (_, Some(data)) => encode_data(out, 0x01, &data, CrcBasis::Escaped),
                (_, None) => encode_data(out, 0x02, &[0x00, 0x00], CrcBasis::Escaped),
            }
        }
    }
}

pub fn generate(path: &Path, mode: Mode, target: u64) -> u64 {
    let mut out = BufWriter::new(File::create(path).unwrap());
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut written = 0u64;
    let mut buf = Vec::with_capacity(1 << 16);
    while written < target {
        buf.clear();
        for _ in 0..1024 {
            exchange(&mut rng, mode, &mut buf);
        }
        out.write_all(&buf).unwrap();
        written += buf.len() as u64;
    }
    out.flush().unwrap();
    written
}

fn main() {
    let mb = common::env_u64("BUSNOOP_BENCH_MB", 64);
    let runs = common::env_u64("BUSNOOP_BENCH_RUNS", 3).max(1);
    pin_to_core0();
    println!("serial S-Bus replay benchmark, pinned to CPU 0, best of {runs} runs");
    for (mode, name) in [(Mode::Data, "data"), (Mode::Break, "break")] {
        let path = common::data_dir().join(format!("sbus-{name}-{mb}mib.bin"));
        let target = mb << 20;
        let size = match std::fs::metadata(&path) {
            Ok(m) if m.len() >= target && m.len() < target + (1 << 20) => m.len(),
            _ => {
                eprintln!("generating {} ...", path.display());
                generate(&path, mode, target)
            }
        };
        let mib = size as f64 / (1 << 20) as f64;
        println!("{name} mode, capture {} ({mib:.0} MiB)", path.display());
        let decode = || {
            decode_file(
                &path,
                &mut SerialDecoder::new(Options {
                    mode,
                    ..Options::default()
                }),
            )
        };
        decode(); // warm the page cache
        let (t, rows) = best_of(runs, decode);
        let secs = t.as_secs_f64();
        println!(
            "  decode only (--mode {name}): {:.1} MiB/s, {:.2} M rows/s ({rows} rows in {secs:.2} s)",
            mib / secs,
            rows as f64 / secs / 1e6
        );
        for auto in [false, true] {
            let mode_arg = if auto { "auto" } else { name };
            let (t, peak) = best_of(runs, || {
                let t = common::time_command(
                    busnoop()
                        .args(["sbus", "-f", "tsv", "--mode", mode_arg])
                        .arg(&path),
                )
                .expect("busnoop failed");
                (t, children_peak_kb())
            });
            let secs = t.as_secs_f64();
            println!(
                "  busnoop sbus --mode {mode_arg} -f tsv > /dev/null: {:.1} MiB/s, {:.2} M rows/s ({secs:.2} s), peak RSS {peak} kB",
                mib / secs,
                rows as f64 / secs / 1e6
            );
        }
    }
}
