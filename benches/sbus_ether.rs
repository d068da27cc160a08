//! Ether-S-Bus throughput: busnoop against `tshark -r` and `tshark -T fields` on the same
//! generated capture.
//!
//! ```sh
//! cargo bench --bench sbus_ether                                # 1 000 000 packets
//! BUSNOOP_BENCH_PACKETS=4000000 cargo bench --bench sbus_ether  # more
//! BUSNOOP_BENCH_BIN=/path/to/busnoop cargo bench --bench sbus_ether   # another build
//! BUSNOOP_BENCH_TSHARK_RUNS=3 cargo bench --bench sbus_ether    # tshark's best of three
//! ```
//!
//! Generates `target/bench-data/sbus-ether-<N>.pcap` (Ethernet/IPv4/UDP, 4 clients polling 8
//! PLCs: register reads of 1-16 registers, flag reads, register and flag writes answered by
//! ACK, 2 % NAKs), then measures in one run: busnoop decoding in process (rows rendered and
//! discarded), the release binary writing TSV to /dev/null, `tshark -r FILE` writing its
//! summary lines and `tshark -T fields` writing the fields of busnoop's columns (see
//! [`TSHARK_FIELDS`]) to /dev/null (skipped with a message when tshark is not installed), all
//! pinned to CPU 0. Times are CPU times (user + system; the machine is shared), busnoop's the
//! best of three runs, tshark's the best of `BUSNOOP_BENCH_TSHARK_RUNS` (1; each run's time is
//! printed: tshark's own times spread by a third from run to run on a shared machine).

mod common;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use busnoop::pcap::write as pw;
use busnoop::sbus::telegram::encode_ether;
use common::{Rng, cpu_time, cpu_time_command, decode_file, pin_to_core0};

/// Writes the capture; returns the number of packets.
pub fn generate(path: &Path, packets: u64) -> std::io::Result<u64> {
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    let mut buf = Vec::with_capacity(1 << 16);
    pw::header(&mut buf, 1);
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut t: i64 = 1_750_000_000_000_000;
    let mut seq = [[0u16; 8]; 4];
    let mut payload = Vec::with_capacity(256);
    let mut frame = Vec::with_capacity(512);
    let mut n = 0;
    while n < packets {
        let c = (rng.next() % 4) as usize;
        let p = (rng.next() % 8) as usize;
        let client = ([192, 168, 1, 10 + c as u8], 40_000 + c as u16);
        let plc = ([192, 168, 1, 100 + p as u8], 5050);
        let station = 1 + p as u8;
        seq[c][p] = seq[c][p].wrapping_add(1);
        let s = seq[c][p];
        let addr = (rng.next() % 2000) as u16;
        let [ah, al] = addr.to_be_bytes();
        let kind = rng.next() % 100;
        let mut req = vec![station];
        let (at, resp): (u8, Vec<u8>) = if kind < 2 {
            req.extend_from_slice(&[0x06, 0, ah, al]);
            (2, vec![0, 1])
        } else if kind < 60 {
            let cnt = 1 + (rng.next() % 16) as u8;
            req.extend_from_slice(&[0x06, cnt - 1, ah, al]);
            (1, (0..4 * cnt as usize).map(|_| rng.next() as u8).collect())
        } else if kind < 80 {
            let bits = 1 + (rng.next() % 32) as u8;
            req.extend_from_slice(&[0x02, bits - 1, ah, al]);
            (
                1,
                (0..(bits as usize).div_ceil(8))
                    .map(|_| rng.next() as u8)
                    .collect(),
            )
        } else if kind < 92 {
            req.extend_from_slice(&[0x0E, 9, ah, al]);
            req.extend((0..8).map(|_| rng.next() as u8));
            (2, vec![0, 0])
        } else {
            req.extend_from_slice(&[0x0B, 3, ah, al, 7, rng.next() as u8]);
            (2, vec![0, 0])
        };
        payload.clear();
        encode_ether(&mut payload, s, 0, &req);
        frame.clear();
        pw::udp4_frame(&mut frame, client, plc, &payload);
        pw::record(&mut buf, t, &frame);
        t += 300 + (rng.next() % 2000) as i64;
        payload.clear();
        encode_ether(&mut payload, s, at, &resp);
        frame.clear();
        pw::udp4_frame(&mut frame, plc, client, &payload);
        pw::record(&mut buf, t, &frame);
        t += 100 + (rng.next() % 500) as i64;
        n += 2;
        if buf.len() > 1 << 20 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    out.write_all(&buf)?;
    out.flush()?;
    Ok(n)
}

/// Decodes in this process; returns the CPU time and the number of rows.
fn decode_in_process(path: &Path) -> (Duration, u64) {
    let before = cpu_time(libc::RUSAGE_SELF);
    let (_, rows) = decode_file(
        path,
        &mut busnoop::protocol::PcapBytes::new(busnoop::sbus::EtherDecoder::new(
            &busnoop::sbus::Options::default(),
        )),
    );
    (cpu_time(libc::RUSAGE_SELF) - before, rows)
}

/// The fields `tshark -T fields` writes: what busnoop's TSV columns hold (frame number, time,
/// addresses and ports, sequence, telegram attribute, station, command, register count, data,
/// ACK/NAK code, CRC status, response time).
const TSHARK_FIELDS: &[&str] = &[
    "frame.number",
    "frame.time_relative",
    "ip.src",
    "udp.srcport",
    "ip.dst",
    "udp.dstport",
    "sbus.seq",
    "sbus.att",
    "sbus.destination",
    "sbus.cmd",
    "sbus.rcount",
    "sbus.data_rtc",
    "sbus.nakcode",
    "sbus.crc.status",
    "sbus.response_time",
];

fn rate(packets: u64, d: Duration) -> f64 {
    packets as f64 / d.as_secs_f64()
}

fn main() {
    let packets = common::env_u64("BUSNOOP_BENCH_PACKETS", 1_000_000);
    let path = common::data_dir().join(format!("sbus-ether-{packets}.pcap"));
    let packets = if path.exists() {
        packets.div_ceil(2) * 2
    } else {
        eprintln!("generating {} ...", path.display());
        generate(&path, packets).unwrap()
    };
    let size = std::fs::metadata(&path).unwrap().len();
    println!(
        "capture: {} ({} packets, {:.1} MiB)",
        path.display(),
        packets,
        size as f64 / (1 << 20) as f64
    );

    // busnoop in process, best of three
    pin_to_core0();
    let mut best = Duration::MAX;
    let mut rows = 0;
    for _ in 0..3 {
        let (d, r) = decode_in_process(&path);
        best = best.min(d);
        rows = r;
    }
    assert_eq!(rows, packets, "one row per packet");
    let decode = rate(packets, best);
    println!(
        "busnoop decode only:        {:>8.3} s  {:>12.0} packets/s",
        best.as_secs_f64(),
        decode
    );

    // the release binary to TSV, best of three
    let exe = std::env::var_os("BUSNOOP_BENCH_BIN")
        .unwrap_or_else(|| env!("CARGO_BIN_EXE_busnoop").into());
    let mut best = Duration::MAX;
    for _ in 0..3 {
        let mut cmd = Command::new(&exe);
        cmd.args(["sbus", "--no-config", "-f", "tsv"]).arg(&path);
        let d = cpu_time_command(&mut cmd).expect("busnoop failed");
        best = best.min(d);
    }
    let binary = rate(packets, best);
    println!(
        "busnoop sbus -f tsv FILE:   {:>8.3} s  {:>12.0} packets/s, peak RSS {} kB",
        best.as_secs_f64(),
        binary,
        common::children_peak_kb()
    );

    // tshark, once each by default (it is slow); the best of BUSNOOP_BENCH_TSHARK_RUNS runs
    // against busnoop's best, with every run's time shown (tshark's own spread is wide)
    let tshark_runs = common::env_u64("BUSNOOP_BENCH_TSHARK_RUNS", 1).max(1);
    let mut fields = Command::new("tshark");
    fields.arg("-r").arg(&path).args(["-T", "fields"]);
    for f in TSHARK_FIELDS {
        fields.args(["-e", f]);
    }
    let mut summary = Command::new("tshark");
    summary.arg("-r").arg(&path);
    for (label, mut cmd) in [("tshark -r FILE:", summary), ("tshark -T fields:", fields)] {
        let times: Option<Vec<Duration>> = (0..tshark_runs)
            .map(|_| cpu_time_command(&mut cmd))
            .collect();
        let Some(times) = times else {
            println!("{label} tshark is not installed (or failed): skipped");
            continue;
        };
        let best = times.iter().copied().min().unwrap_or_default();
        let ts = rate(packets, best);
        let all: Vec<String> = times
            .iter()
            .map(|d| format!("{:.2}", d.as_secs_f64()))
            .collect();
        println!(
            "{label:<27} {:>8.3} s  {:>12.0} packets/s (best of {tshark_runs}: {} s)",
            best.as_secs_f64(),
            ts,
            all.join(", ")
        );
        println!(
            "  busnoop / {}: {:.1}× (binary to TSV), {:.1}× (decode only)",
            label.trim_end_matches(':'),
            binary / ts,
            decode / ts
        );
    }
}
