//! Readings of unframed break/parity-mode bytes: whether a request of the command table or a
//! response of a given length starts at a position and whether its CRC checks, and the rules
//! that make one valid reading give way to another (a CRC-16 with init 0 ignores leading
//! zeros). Used by [`super::BreakFramer`].

use super::CrcCheck;
use crate::sbus::commands;
use crate::sbus::telegram::{CrcBasis, crc_step, crc16};

/// Longest request body searched by CRC when the table does not know the length.
pub const MAX_SEARCH_BODY: usize = 255;

/// Result of testing one reading of the buffered bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Cand<T> {
    Match(T),
    No,
    More,
}

/// Lengths tried when a response does not fit the request and is looked for by its CRC:
/// what the command table's replies can be (1-16 bytes, 26, and whole registers up to 32).
pub(super) fn plausible_response_len(n: usize) -> bool {
    n <= 16 || n == 26 || (n.is_multiple_of(4) && n <= 128)
}

pub(super) fn map<T, U>(c: Cand<T>, f: impl FnOnce(T) -> U) -> Cand<U> {
    match c {
        Cand::Match(t) => Cand::Match(f(t)),
        Cand::No => Cand::No,
        Cand::More => Cand::More,
    }
}

pub(super) fn crc_of(got: u16, want: u16) -> CrcCheck {
    if got == want {
        CrcCheck::Ok(CrcBasis::Both)
    } else {
        CrcCheck::Bad {
            got,
            escaped: want,
            unescaped: want,
        }
    }
}

/// A response of `n` data bytes + CRC at `k` with a good CRC.
pub(super) fn resp_at(b: &[u8], k: usize, n: usize, at_end: bool) -> Cand<()> {
    if b.len() < k + n + 2 {
        return if at_end { Cand::No } else { Cand::More };
    }
    let got = u16::from_be_bytes([b[k + n], b[k + n + 1]]);
    if crc16(&b[k..k + n]) == got {
        Cand::Match(())
    } else {
        Cand::No
    }
}

/// A valid request reading `00 X …` at `s` is dominated by a valid reading at `s + 1`: a
/// CRC-16 with init 0 ignores a leading zero, and a telegram whose CRC ends in 00 also checks
/// one byte earlier when a 00 (a break, or the previous telegram's last byte) precedes it.
pub(super) fn zero_dominated(b: &[u8], s: usize, at_end: bool) -> Cand<()> {
    if b.get(s) != Some(&0) {
        return Cand::No;
    }
    match request_len(b, s + 1, at_end) {
        Cand::Match((_, true)) => Cand::Match(()),
        Cand::More => Cand::More,
        _ => Cand::No,
    }
}

/// Parity mode: a response reading of `0..end` is dominated by a request reading of
/// `0..end + 1` when the next byte is 00. A telegram whose CRC ends in 00 also checks without
/// that byte (and any telegram followed by 00 checks with it): without breaks, a 00 there is
/// more likely the CRC's last byte than a station-0 request.
pub(super) fn tail_dominated(b: &[u8], end: usize, at_end: bool) -> Cand<()> {
    match b.get(end) {
        None => {
            if at_end {
                Cand::No
            } else {
                Cand::More
            }
        }
        Some(0) => match request_len(b, 0, at_end) {
            Cand::Match((body, true)) if 2 + body + 2 == end + 1 => Cand::Match(()),
            Cand::More => Cand::More,
            _ => Cand::No,
        },
        Some(_) => Cand::No,
    }
}

/// Whether the request at `s` has a command whose length the table does not know.
pub(super) fn searched(b: &[u8], s: usize) -> bool {
    b.get(s + 1)
        .and_then(|&c| commands::command(c))
        .is_some_and(|c| c.layout.body_len(&[]).is_none())
}

/// The body length of a request starting at `s` and whether its CRC checks. Known lengths
/// come from the command table; commands without a known layout are searched by CRC.
pub(super) fn request_len(b: &[u8], s: usize, at_end: bool) -> Cand<(usize, bool)> {
    let more = if at_end { Cand::No } else { Cand::More };
    let Some(&cmd) = b.get(s + 1) else {
        return more;
    };
    let Some(command) = commands::command(cmd) else {
        return Cand::No;
    };
    let body = b.get(s + 2..).unwrap_or(&[]);
    match command.layout.body_len(body) {
        Some(Ok(n)) => {
            if b.len() < s + 2 + n + 2 {
                return more;
            }
            let got = u16::from_be_bytes([b[s + 2 + n], b[s + 3 + n]]);
            Cand::Match((n, crc16(&b[s..s + 2 + n]) == got))
        }
        Some(Err(_)) => more,
        None => {
            let mut crc = crc_step(crc_step(0, b[s]), cmd);
            for n in 0..=MAX_SEARCH_BODY {
                if n > 0 {
                    match b.get(s + 1 + n) {
                        Some(&x) => crc = crc_step(crc, x),
                        None => return more,
                    }
                }
                match (b.get(s + 2 + n), b.get(s + 3 + n)) {
                    (Some(&h), Some(&l)) => {
                        if u16::from_be_bytes([h, l]) == crc {
                            return Cand::Match((n, true));
                        }
                    }
                    _ => return more,
                }
            }
            Cand::No
        }
    }
}
