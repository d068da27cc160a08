//! Request/response pairing and the master timeout (pure: times in, decisions out).
//!
//! SAB has one master, and modm's `sab::Master` runs one query at a time: it sends a REQUEST,
//! restarts a 10 ms timer and waits for the response. A slave answers with its own address and
//! the request's command. So:
//!
//! * a response pairs with the open request when address and command match;
//! * the open request **times out** when the capture's time passes its deadline
//!   (request start + timeout) without a response, or when the next request comes first
//!   ("no response before the next request", the only test available without real time);
//! * a response that arrives after the deadline is paired but *late* (the master had given
//!   up; the request still times out), and one that matches a request already closed by the
//!   next request is late too;
//! * a `Timeout` is reported once the capture's time has passed the deadline (or at the next
//!   request, or at the end), so rows stay in time order;
//! * a second response to the same request is a *repeat* (two slaves on one address?).
//!
//! The response time is measured from the first byte of the request to the last byte of the
//! response: modm's master starts its timer when it queues the request and stops waiting when
//! the whole response has arrived.

use crate::pairing::{Keep, LateWindow, Open};

pub use crate::pairing::Reason as Why;

/// A request as pairing needs it. Times in µs since the capture started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    pub address: u8,
    pub command: u8,
    /// Time of the request's first byte.
    pub start: u64,
}

/// A request that timed out: emit a `Timeout` row at `at`. SAB's reasons are
/// [`Why::Deadline`], [`Why::NextRequest`] and [`Why::End`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Expired {
    pub request: Request,
    /// Time for the `Timeout` row.
    pub at: u64,
    pub why: Why,
    /// How long the request had waited when it was closed (µs).
    pub waited: u64,
}

/// Whether a paired response came in time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lateness {
    OnTime,
    /// After the master's timeout.
    AfterTimeout,
    /// After the master had sent its next request.
    AfterNextRequest,
}

/// What a response is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    Paired {
        request: Request,
        /// Response time in µs (first byte of the request to last byte of the response).
        micros: u64,
        late: Lateness,
        /// Not the first response to this request.
        repeat: bool,
    },
    /// No request matches; `open` is the request the master was waiting for, if any.
    Unpaired { open: Option<Request> },
}

/// Requests closed without a response that a late response may still match.
const RECENT: usize = 4;

/// The pairing state.
#[derive(Clone, Debug)]
pub struct Pairing {
    timeout: u64,
    open: Option<Open<Request>>,
    /// Closed without a response, by (address, command): the last [`RECENT`] closings.
    recent: LateWindow<(u8, u8), Request>,
}

impl Pairing {
    /// `timeout` in µs.
    pub fn new(timeout: u64) -> Self {
        Pairing {
            timeout,
            open: None,
            recent: LateWindow::new(RECENT, Keep::Expiries),
        }
    }

    pub fn timeout(&self) -> u64 {
        self.timeout
    }

    /// The request the master is waiting for, if any.
    pub fn waiting(&self) -> Option<Request> {
        self.open
            .filter(|o| o.answers == 0 && !o.reported)
            .map(|o| o.req)
    }

    /// The capture's time reached `now`: the open request expires when its deadline passed
    /// without a response in time.
    pub fn advance(&mut self, now: u64) -> Option<Expired> {
        let timeout = self.timeout;
        let o = self.open.as_mut()?;
        let at = o.expire(now, timeout)?;
        Some(Expired {
            request: o.req,
            at,
            why: Why::Deadline,
            waited: timeout,
        })
    }

    /// A request was sent: it becomes the open request; the previous one, if its timeout is
    /// still unreported, times out now (at the deadline or the new request's start, whichever
    /// comes first, to keep rows in time order).
    pub fn request(&mut self, req: Request) -> Option<Expired> {
        let mut result = None;
        if let Some(prev) = self.open.take() {
            let deadline = prev.time.saturating_add(self.timeout);
            if prev.due() {
                let (why, waited) = if prev.answers == 0 {
                    (Why::NextRequest, req.start.saturating_sub(prev.time))
                } else {
                    (Why::Deadline, self.timeout)
                };
                result = Some(Expired {
                    request: prev.req,
                    at: deadline.min(req.start),
                    why,
                    waited,
                });
            }
            if prev.answers == 0 {
                let why = if prev.reported {
                    Why::Deadline
                } else {
                    Why::NextRequest
                };
                self.recent.push((prev.address, prev.command), prev, why);
            }
        }
        self.open = Some(Open::at(req, req.start, true));
        result
    }

    /// A response from `address` for `command` ended at `end`.
    pub fn response(&mut self, address: u8, command: u8, end: u64) -> Answer {
        if let Some(o) = self.open.as_mut()
            && o.address == address
            && o.command == command
        {
            let expired = o.reported;
            let reply = o.answer(end, self.timeout);
            // A late first response's Timeout is reported by `advance` once the capture's
            // time passes the deadline.
            return Answer::Paired {
                request: o.req,
                micros: reply.elapsed,
                late: if expired || reply.overdue {
                    Lateness::AfterTimeout
                } else {
                    Lateness::OnTime
                },
                repeat: reply.repeat,
            };
        }
        // A late answer to a request that was already closed?
        if let Some((req, why)) = self.recent.take(|k| *k == (address, command)) {
            return Answer::Paired {
                request: req.req,
                micros: end.saturating_sub(req.time),
                late: match why {
                    Why::NextRequest => Lateness::AfterNextRequest,
                    _ => Lateness::AfterTimeout,
                },
                repeat: false,
            };
        }
        Answer::Unpaired {
            open: self.waiting(),
        }
    }

    /// End of the capture at `now`: an open request without a response times out.
    pub fn finish(&mut self, now: u64) -> Option<Expired> {
        let timeout = self.timeout;
        let o = self.open.take()?;
        if !o.due() {
            return None;
        }
        let deadline = o.time.saturating_add(timeout);
        Some(if now > deadline {
            Expired {
                request: o.req,
                at: deadline,
                why: Why::Deadline,
                waited: timeout,
            }
        } else {
            Expired {
                request: o.req,
                at: now.max(o.time),
                why: Why::End,
                waited: now.saturating_sub(o.time),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: u64 = 10_000;

    fn req(address: u8, command: u8, start: u64) -> Request {
        Request {
            address,
            command,
            start,
        }
    }

    #[test]
    fn paired_on_time() {
        let mut p = Pairing::new(T);
        assert_eq!(p.request(req(5, 0x10, 1000)), None);
        assert_eq!(p.advance(2000), None);
        match p.response(5, 0x10, 2500) {
            Answer::Paired {
                micros,
                late,
                repeat,
                ..
            } => {
                assert_eq!(micros, 1500);
                assert_eq!(late, Lateness::OnTime);
                assert!(!repeat);
            }
            a => panic!("{a:?}"),
        }
        // Answered requests never time out.
        assert_eq!(p.advance(1_000_000), None);
        assert_eq!(p.finish(1_000_000), None);
    }

    #[test]
    fn deadline_and_late_response() {
        let mut p = Pairing::new(T);
        p.request(req(5, 0x10, 1000));
        assert_eq!(
            p.advance(11_000),
            None,
            "exactly at the deadline is in time"
        );
        let x = p.advance(11_001).unwrap();
        assert_eq!((x.at, x.why, x.waited), (11_000, Why::Deadline, T));
        assert_eq!(p.advance(20_000), None, "reported once");
        match p.response(5, 0x10, 15_000) {
            Answer::Paired { micros, late, .. } => {
                assert_eq!(micros, 14_000);
                assert_eq!(late, Lateness::AfterTimeout);
                // Already reported by `advance`: not again.
                assert_eq!(p.finish(30_000), None);
            }
            a => panic!("{a:?}"),
        }
    }

    #[test]
    fn response_straddling_the_deadline() {
        let mut p = Pairing::new(T);
        p.request(req(1, 2, 0));
        assert_eq!(p.advance(9_000), None);
        // Started before the deadline, ended after it: late, and the timeout is reported
        // once the time passes the deadline (not before rows that start earlier).
        assert!(matches!(
            p.response(1, 2, 10_500),
            Answer::Paired {
                late: Lateness::AfterTimeout,
                ..
            }
        ));
        assert_eq!(p.advance(9_950), None);
        let x = p.advance(10_001).unwrap();
        assert_eq!((x.at, x.why), (T, Why::Deadline));
        assert_eq!(p.advance(20_000), None);
        // Or at the next request, clamped to its start.
        p.request(req(1, 3, 20_000));
        p.response(1, 3, 30_500);
        let x = p.request(req(1, 4, 29_990)).unwrap();
        assert_eq!((x.at, x.why), (29_990, Why::Deadline));
        // Or at the end of the capture.
        p.response(1, 4, 40_000);
        let x = p.finish(40_000).unwrap();
        assert_eq!((x.at, x.why), (39_990, Why::Deadline));
    }

    #[test]
    fn next_request_closes_the_previous_one() {
        let mut p = Pairing::new(T);
        p.request(req(5, 0x10, 0));
        let x = p.request(req(6, 0x20, 900)).unwrap();
        assert_eq!(x.request, req(5, 0x10, 0));
        assert_eq!((x.at, x.why, x.waited), (900, Why::NextRequest, 900));
        // The late answer to the first request still pairs, flagged.
        match p.response(5, 0x10, 1500) {
            Answer::Paired { late, micros, .. } => {
                assert_eq!(late, Lateness::AfterNextRequest);
                assert_eq!(micros, 1500);
            }
            a => panic!("{a:?}"),
        }
        // But only once.
        assert_eq!(
            p.response(5, 0x10, 1600),
            Answer::Unpaired {
                open: Some(req(6, 0x20, 900))
            }
        );
    }

    #[test]
    fn unpaired_and_repeated() {
        let mut p = Pairing::new(T);
        assert_eq!(p.response(1, 1, 5), Answer::Unpaired { open: None });
        p.request(req(1, 1, 10));
        assert_eq!(
            p.response(1, 2, 20),
            Answer::Unpaired {
                open: Some(req(1, 1, 10))
            }
        );
        assert!(matches!(
            p.response(1, 1, 30),
            Answer::Paired { repeat: false, .. }
        ));
        assert!(matches!(
            p.response(1, 1, 40),
            Answer::Paired { repeat: true, .. }
        ));
    }

    #[test]
    fn end_of_capture() {
        let mut p = Pairing::new(T);
        p.request(req(1, 1, 100));
        let x = p.finish(2_000).unwrap();
        assert_eq!((x.at, x.why, x.waited), (2_000, Why::End, 1_900));
        let mut p = Pairing::new(T);
        p.request(req(1, 1, 100));
        let x = p.finish(50_000).unwrap();
        assert_eq!((x.at, x.why), (10_100, Why::Deadline));
        assert_eq!(p.finish(60_000), None);
    }
}
