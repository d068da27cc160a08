//! Readings of unframed break/parity-mode bytes: whether a request of the command table or a
//! response of a given length starts at a position and whether its CRC checks, and the rules
//! that make one valid reading give way to another (a CRC-16 with init 0 ignores leading
//! zeros). Used by [`super::BreakFramer`].

use std::cell::Cell;

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
pub(super) fn zero_dominated(b: &[u8], s: usize, at_end: bool, memo: Memo<'_>) -> Cand<()> {
    if b.get(s) != Some(&0) {
        return Cand::No;
    }
    match request_len(b, s + 1, at_end, memo) {
        Cand::Match((_, true)) => Cand::Match(()),
        Cand::More => Cand::More,
        _ => Cand::No,
    }
}

/// Parity mode: a response reading of `0..end` is dominated by a request reading of
/// `0..end + 1` when the next byte is 00. A telegram whose CRC ends in 00 also checks without
/// that byte (and any telegram followed by 00 checks with it): without breaks, a 00 there is
/// more likely the CRC's last byte than a station-0 request.
pub(super) fn tail_dominated(b: &[u8], end: usize, at_end: bool, memo: Memo<'_>) -> Cand<()> {
    match b.get(end) {
        None => {
            if at_end {
                Cand::No
            } else {
                Cand::More
            }
        }
        Some(0) => match request_len(b, 0, at_end, memo) {
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
pub(super) fn request_len(b: &[u8], s: usize, at_end: bool, memo: Memo<'_>) -> Cand<(usize, bool)> {
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
            // (remembered: the framer checks the same request again from other positions)
            let pos = memo.origin + s as u64;
            let slot = memo.table.slot(pos);
            let e = slot.get();
            if e.pos == pos && e.state == CHECKED {
                return Cand::Match((n, e.crc == 1));
            }
            let got = u16::from_be_bytes([b[s + 2 + n], b[s + 3 + n]]);
            let ok = crc16(&b[s..s + 2 + n]) == got;
            slot.set(Progress {
                pos,
                n: 0,
                crc: ok as u16,
                state: CHECKED,
            });
            Cand::Match((n, ok))
        }
        Some(Err(_)) => more,
        None => search(b, s, at_end, cmd, memo),
    }
}

/// Searches the CRC of a request whose command has no known length: the first body length
/// `n` (0 to [`MAX_SEARCH_BODY`]) whose two following bytes are the CRC of `b[s..s + 2 + n]`.
/// The search resumes where an earlier call for the same stream position stopped for lack of
/// bytes (and a finished one is not repeated): the framer asks for the same positions again
/// with every byte that arrives, and a search from scratch each time cost hundreds of CRC
/// steps per byte on bytes that are not S-Bus.
fn search(b: &[u8], s: usize, at_end: bool, cmd: u8, memo: Memo<'_>) -> Cand<(usize, bool)> {
    let pos = memo.origin + s as u64;
    let slot = memo.table.slot(pos);
    let mut e = slot.get();
    if e.pos != pos || e.state == CHECKED {
        e = Progress {
            pos,
            n: 0,
            crc: crc_step(crc_step(0, b[s]), cmd),
            state: SEARCHING,
        };
    }
    match e.state {
        FOUND => return Cand::Match((e.n as usize, true)),
        NOT_FOUND => return Cand::No,
        _ => {}
    }
    let mut n = e.n as usize;
    let mut crc = e.crc;
    let state = loop {
        match (b.get(s + 2 + n), b.get(s + 3 + n)) {
            (Some(&h), Some(&l)) => {
                if u16::from_be_bytes([h, l]) == crc {
                    break FOUND;
                }
            }
            _ => break SEARCHING,
        }
        if n == MAX_SEARCH_BODY {
            break NOT_FOUND;
        }
        n += 1;
        // (present: the previous candidate's CRC field covered it)
        crc = crc_step(crc, b[s + 1 + n]);
    };
    slot.set(Progress {
        pos,
        n: n as u16,
        crc,
        state,
    });
    match state {
        FOUND => Cand::Match((n, true)),
        NOT_FOUND => Cand::No,
        _ if at_end => Cand::No,
        _ => Cand::More,
    }
}

const SEARCHING: u8 = 0;
const FOUND: u8 = 1;
const NOT_FOUND: u8 = 2;
/// A request of known length whose CRC was checked (`crc`: 1 when it matched).
const CHECKED: u8 = 3;

/// Positions remembered by a [`SearchMemo`] (direct-mapped by stream position: the framer looks
/// at positions near its head and inside the readings it tries, at most a few hundred bytes
/// ahead).
const MEMO_SLOTS: usize = 512;

/// How far the CRC search of one stream position got, or the CRC check of a request of known
/// length there.
#[derive(Clone, Copy, Debug)]
struct Progress {
    /// Stream position of the request's first byte (`u64::MAX`: an empty slot).
    pos: u64,
    /// The body length tried next (`SEARCHING`) or found (`FOUND`).
    n: u16,
    /// CRC over the request's bytes up to that body length.
    crc: u16,
    state: u8,
}

/// The CRC searches and checks of recent stream positions (see [`search`]). Bytes at a stream
/// position never change, so what is remembered stays true; a slot taken by another position
/// only costs the work again.
#[derive(Clone, Debug)]
pub(super) struct SearchMemo {
    slots: [Cell<Progress>; MEMO_SLOTS],
}

impl SearchMemo {
    fn slot(&self, pos: u64) -> &Cell<Progress> {
        &self.slots[(pos % MEMO_SLOTS as u64) as usize]
    }
}

impl Default for SearchMemo {
    fn default() -> Self {
        SearchMemo {
            slots: std::array::from_fn(|_| {
                Cell::new(Progress {
                    pos: u64::MAX,
                    n: 0,
                    crc: 0,
                    state: SEARCHING,
                })
            }),
        }
    }
}

/// A [`SearchMemo`] and the stream position of the first byte of the slice searched.
#[derive(Clone, Copy, Debug)]
pub(super) struct Memo<'a> {
    pub table: &'a SearchMemo,
    pub origin: u64,
}

impl<'a> Memo<'a> {
    /// The same memo for the slice that starts `k` bytes later.
    pub fn at(self, k: usize) -> Memo<'a> {
        Memo {
            table: self.table,
            origin: self.origin + k as u64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::noise;

    /// A command code whose request length the table does not know (searched by CRC).
    fn searched_cmd() -> u8 {
        (0..=255u8)
            .find(|&c| searched(&[0, c], 0))
            .expect("the table has commands of unknown length")
    }

    #[test]
    fn a_resumed_search_gives_what_a_search_from_scratch_gives() {
        let cmd = searched_cmd();
        for seed in 1..9u64 {
            // noise with the searched command at every fourth position, and (for some seeds) a
            // real telegram of that command somewhere in it
            let mut b = noise(400, seed);
            for i in (1..b.len()).step_by(4) {
                b[i] = cmd;
            }
            if seed % 2 == 0 {
                let at = (seed as usize * 29) % 300;
                let body = (seed as usize * 3) % 40;
                b[at + 1] = cmd;
                let crc = crc16(&b[at..at + 2 + body]);
                b[at + 2 + body..at + 4 + body].copy_from_slice(&crc.to_be_bytes());
            }
            // the framer's way: every position asked again as each byte arrives, with one memo
            let memo = SearchMemo::default();
            let fresh = SearchMemo::default();
            for len in 1..=b.len() {
                for s in len.saturating_sub(270)..len {
                    for at_end in [false, true] {
                        let m = Memo {
                            table: &memo,
                            origin: 1000,
                        };
                        let got = request_len(&b[..len], s, at_end, m);
                        // from scratch: a new memo each time
                        let f = Memo {
                            table: &fresh,
                            origin: 0,
                        };
                        fresh.slots.iter().for_each(|c| {
                            c.set(Progress {
                                pos: u64::MAX,
                                ..c.get()
                            })
                        });
                        let want = request_len(&b[..len], s, at_end, f);
                        assert_eq!(got, want, "seed {seed}, {len} bytes, at {s}, end {at_end}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_search_finds_the_shortest_body_and_gives_up_after_the_longest() {
        let cmd = searched_cmd();
        let memo = SearchMemo::default();
        let m = Memo {
            table: &memo,
            origin: 0,
        };
        // station 3, a body of 5 bytes, its CRC
        let mut t = vec![3, cmd, 1, 2, 3, 4, 5];
        let crc = crc16(&t);
        t.extend_from_slice(&crc.to_be_bytes());
        for cut in 2..t.len() {
            assert_eq!(request_len(&t[..cut], 0, false, m), Cand::More, "{cut}");
        }
        assert_eq!(request_len(&t, 0, false, m), Cand::Match((5, true)));
        assert_eq!(request_len(&t, 0, true, m), Cand::Match((5, true)));
        // zeros never check after a nonzero start: no CRC within the longest body
        let mut z = vec![3, cmd];
        z.resize(2 + MAX_SEARCH_BODY + 2, 0);
        let memo = SearchMemo::default();
        let m = Memo {
            table: &memo,
            origin: 0,
        };
        assert_eq!(request_len(&z[..100], 0, true, m), Cand::No);
        assert_eq!(request_len(&z[..100], 0, false, m), Cand::More);
        assert_eq!(request_len(&z, 0, false, m), Cand::No);
    }
}
