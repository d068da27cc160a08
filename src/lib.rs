//! busnoop: a passive bus sniffer.
//!
//! Data flows one way: a [`source`] yields timestamped byte chunks, a protocol decoder (for
//! example [`sport`]) reassembles frames from them with pure code and maps them onto the log
//! table ([`row::Row`]), and a [`sink`] formats the rows as pretty text, TSV, CSV or JSON Lines.
//! [`run`] wires the three together and deals with signals, statistics and exit codes.

#![deny(clippy::undocumented_unsafe_blocks)]

pub mod cli;
pub mod detect;
pub mod exit;
pub mod export;
pub mod filter;
pub mod fmt;
pub mod numbers;
pub mod pace;
pub mod pairing;
pub mod pcap;
pub mod plot;
pub mod protocol;
pub mod protocols;
pub mod record;
pub mod row;
pub mod run;
pub mod sab;
pub mod sbus;
#[cfg(feature = "selfcheck")]
#[doc(hidden)]
pub mod selfcheck;
pub mod signal;
pub mod sink;
pub mod source;
pub mod sport;
pub mod stats;
pub mod stats_json;
pub mod summary;
pub mod time;
pub mod top;
