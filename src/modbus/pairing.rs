//! Pairing responses with requests on a serial line: the Modbus rules on top of the core in
//! `crate::pairing`, as S-Bus serial has them (`crate::sbus::pairing`).
//!
//! One master polls, so at most one request waits. A response pairs with it when it comes from
//! the slave asked and carries its function (or the function's exception). The same request
//! again while it waits is a retry; a different one ends the wait (`Timeout`, "no answer before
//! the next request"). With real times, a request whose master timeout passed is reported
//! (`Timeout`) and an answer after it is late. A broadcast (address 0) waits for nothing.

use crate::pairing::Open;

pub use crate::pairing::Reason;

/// What a response needs of its request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Req {
    pub slave: u8,
    pub function: u8,
    /// First address (registers, coils; function 23: the read), or the sub-function (8), the
    /// FIFO pointer (24), the object id (43).
    pub start: u16,
    /// Registers or coils asked for (function 23: read).
    pub count: u16,
}

/// A request waiting for its answer; reads like its [`Req`].
pub type Outstanding = Open<Req>;

/// How a new request relates to the previous one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RequestKind {
    New,
    /// The same request again: `n` is the retry number (1 = second transmission), `since` the
    /// time since the first transmission (µs).
    Retry {
        n: u8,
        since: u64,
    },
}

/// What an answer was paired with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    Paired {
        req: Outstanding,
        /// From the request's start to the answer's (µs).
        elapsed: u64,
        /// After the master timeout.
        late: bool,
    },
    /// A request waits, but for another slave or function.
    Mismatch { req: Outstanding },
    /// No request waits.
    NoRequest,
}

/// Serial line pairing: one request waits at a time.
#[derive(Clone, Debug)]
pub struct Pairing {
    pending: Option<Outstanding>,
    /// The bytes of the last request (CRC left out), to recognise a retry.
    last: Vec<u8>,
    last_answered: bool,
    pub timeout: u64,
}

impl Pairing {
    pub fn new(timeout: u64) -> Self {
        Pairing {
            pending: None,
            last: Vec::with_capacity(256),
            last_answered: true,
            timeout,
        }
    }

    /// The request waiting for an answer.
    pub fn pending(&self) -> Option<&Outstanding> {
        self.pending.as_ref()
    }

    /// A new request with the bytes `pdu` (address and PDU, no CRC). Returns how it relates
    /// to the previous one and, when the previous one got no answer and was not reported yet,
    /// that request and why it ends.
    pub fn request(
        &mut self,
        pdu: &[u8],
        req: Outstanding,
    ) -> (RequestKind, Option<(Outstanding, Reason)>) {
        let expects = req.slave != 0;
        let same = !self.last_answered && self.last == pdu;
        let mut kind = RequestKind::New;
        let mut ended = None;
        let mut next = req;
        if let Some(p) = self.pending.take() {
            if p.due() {
                ended = Some((
                    p,
                    if same {
                        Reason::Retry
                    } else {
                        Reason::NextRequest
                    },
                ));
            }
            if same {
                let r = next.resend_of(&p);
                kind = RequestKind::Retry {
                    n: r.n,
                    since: r.since,
                };
            }
        }
        self.last.clear();
        self.last.extend_from_slice(pdu);
        self.last_answered = !expects;
        if expects {
            self.pending = Some(next);
        }
        (kind, ended)
    }

    /// An answer from `slave` with function code `function` (an exception's with the high bit)
    /// at `time`.
    pub fn answer(&mut self, slave: u8, function: u8, time: u64) -> Answer {
        let Some(mut p) = self.pending else {
            return Answer::NoRequest;
        };
        if p.slave != slave || p.function != function & 0x7F {
            return Answer::Mismatch { req: p };
        }
        self.pending = None;
        self.last_answered = true;
        let reply = p.answer(time, self.timeout);
        Answer::Paired {
            req: p,
            elapsed: reply.elapsed,
            late: reply.overdue,
        }
    }

    /// A broken frame (bad CRC) arrived while a request waits: it may have been the answer,
    /// so the request gets no Timeout row.
    pub fn bad_answer(&mut self) {
        if let Some(p) = self.pending.as_mut() {
            p.spoiled = true;
        }
    }

    /// The waiting request, when its timeout passed at `now` and was not reported yet (it stays
    /// waiting: a late answer still pairs with it).
    pub fn expire(&mut self, now: u64) -> Option<Outstanding> {
        let p = self.pending.as_mut()?;
        p.expire(now, self.timeout).map(|_| *p)
    }

    /// End of the input (or a gap): the waiting request, unless it was reported already.
    pub fn finish(&mut self) -> Option<Outstanding> {
        self.last_answered = true;
        self.pending.take().filter(Open::due)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(slave: u8, time: u64) -> Outstanding {
        Open::at(
            Req {
                slave,
                function: 3,
                start: 0,
                count: 2,
            },
            time,
            true,
        )
    }

    #[test]
    fn retry_timeout_late_and_mismatch() {
        let mut p = Pairing::new(500_000);
        let pdu = [1, 3, 0, 0, 0, 2];
        assert_eq!(p.request(&pdu, req(1, 0)), (RequestKind::New, None));
        assert_eq!(p.expire(400_000), None);
        assert_eq!(p.expire(600_000).unwrap().slave, 1);
        assert_eq!(p.expire(700_000), None, "reported once");
        // the retry: no second Timeout row
        let (kind, ended) = p.request(&pdu, req(1, 800_000));
        assert_eq!(
            kind,
            RequestKind::Retry {
                n: 1,
                since: 800_000
            }
        );
        assert_eq!(ended, None);
        assert!(matches!(p.answer(2, 3, 810_000), Answer::Mismatch { .. }));
        assert!(matches!(p.answer(1, 4, 810_000), Answer::Mismatch { .. }));
        match p.answer(1, 0x83, 1_400_000) {
            Answer::Paired { req, elapsed, late } => {
                assert_eq!((req.sends, elapsed, late), (2, 600_000, true));
            }
            a => panic!("{a:?}"),
        }
        assert_eq!(p.answer(1, 3, 1_500_000), Answer::NoRequest);
        // an answered request sent again is a new request
        assert_eq!(p.request(&pdu, req(1, 2_000_000)).0, RequestKind::New);
        // another request before the answer ends the wait
        let (_, ended) = p.request(&[2, 3, 0, 0, 0, 2], req(2, 2_100_000));
        assert_eq!(ended.unwrap().1, Reason::NextRequest);
        // a bad answer spoils it: no Timeout row
        p.bad_answer();
        assert_eq!(p.expire(9_000_000), None);
        assert_eq!(p.finish(), None);
    }

    #[test]
    fn broadcasts_wait_for_nothing() {
        let mut p = Pairing::new(500_000);
        let pdu = [0, 6, 0, 1, 0, 3];
        p.request(&pdu, req(0, 0));
        assert!(p.pending().is_none());
        // the same broadcast again is not a retry
        assert_eq!(p.request(&pdu, req(0, 10)).0, RequestKind::New);
        assert_eq!(p.answer(1, 6, 20), Answer::NoRequest);
    }
}
