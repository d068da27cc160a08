//! busnoop: a passive bus sniffer.
//!
//! Data flows one way: a source (`source`, private) yields timestamped byte chunks or packets,
//! a protocol decoder (for example [`sport::SportDecoder`]) reassembles frames from them with
//! pure code and maps them onto the log table ([`row::Row`]), and a sink (`sink`, private)
//! formats the rows as pretty text, TSV, CSV or JSON Lines. The driver (`run`, private) wires
//! the three together and deals with signals, statistics and exit codes.
//!
//! # The public API
//!
//! The binary is [`main`]. As a library, busnoop offers what another program (or a fuzzer,
//! a benchmark, a test) needs to decode a bus without the command line:
//!
//! * the table of protocols, [`protocols::PROTOCOLS`], each a [`protocol::Protocol`]
//!   descriptor (the one place a protocol is registered);
//! * the decoder contract: [`protocol::Decoder`] (push bytes or packets with their times,
//!   `idle`, `finish`; output identical however the input is split), the [`row`] it emits
//!   ([`row::Row`], [`row::RowOut`], the collectors [`row::Collected`] and [`row::Discard`])
//!   and the capture clock [`time::Anchor`];
//! * one module per protocol, each with its decoder, its options and its wire format:
//!   [`sport`] (FrSky S.Port), [`fport`] (FrSky F.Port, F.Port 2 and FBUS), [`sbus`] (Saia
//!   S-Bus serial and Ether-S-Bus), [`sab`] (modm SAB v1 and SAB2), [`crsf`], [`ghst`],
//!   [`futaba`], [`ibus`], and [`logs`] (telemetry logs other tools wrote: a radio's SD-card
//!   CSV, S-Port_Snoop's table);
//! * capture files: [`pcap`] (reading pcap/pcapng, writing pcap and per-frame exports),
//!   [`Recorder`] (busnoop's recordings of a line's bytes or a capture's packets,
//!   [`RecordContent`]), [`edgetx`] (EdgeTX/OpenTX debug-log lines);
//! * hex and number formatting shared by the table ([`fmt`]);
//! * what a run reports: [`Report`] and [`Problems`] (statistics as values), [`Failure`]
//!   (the one-line message and exit code of a failed run).
//!
//! Everything else (command line, sources, sinks, filters, live view, plots, detection) is
//! private to the crate and may change at any time. `selfcheck` (an independent second
//! decoder used by the tests and the fuzzers) exists only with the `selfcheck` feature.

#![deny(clippy::undocumented_unsafe_blocks)]

/// `eprintln!` that never panics. The standard one panics when standard error cannot be
/// written (`2>/dev/full`, a closed descriptor): a warning in the middle of a run ended it
/// there, and the final message turned every exit code into 101. busnoop's messages are
/// advice; a message that cannot be written is lost, and the run goes on with its own exit
/// code. Defined before the modules, so it shadows the standard macro in all of them.
macro_rules! eprintln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod cli;
pub mod crsf;
mod detect;
mod digits;
mod exit;
mod export;
mod files;
mod filter;
pub mod fmt;
pub mod fport;
pub mod futaba;
pub mod ghst;
pub mod ibus;
pub mod logs;
mod merge;
pub mod modbus;
mod numbers;
mod pace;
mod pairing;
pub mod pcap;
mod plot;
pub mod protocol;
pub mod protocols;
mod record;
pub mod row;
mod run;
pub mod sab;
pub mod sbus;
#[cfg(feature = "selfcheck")]
#[doc(hidden)]
pub mod selfcheck;
mod signal;
mod sink;
mod source;
pub mod sport;
mod stats;
mod stats_json;
mod summary;
#[cfg(test)]
mod testing;
pub mod time;
mod top;

pub use cli::main;
pub use exit::Failure;
pub use record::{Content as RecordContent, Recorder};
pub use source::{READ_SIZE, edgetx};
pub use stats::{Problems, Report};

/// For the binary's start-up hook only (`src/main.rs`): notes whether standard output was open
/// before the Rust runtime's start-up.
#[doc(hidden)]
pub fn note_stdout_at_start() {
    files::note_stdout_at_start();
}
