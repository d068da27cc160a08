//! The Modbus decoder: the framer's events become rows (docs/modbus.md, "The table"), requests
//! and answers are paired, and everything is counted per slave and function.

use super::ascii::AsciiFramer;
use super::fast::Fast;
use super::function;
use super::pairing::{Answer, Outstanding, Pairing, Reason, RequestKind};
use super::pdu::{Content, describe, request_info};
use super::stats::{self, Table, Totals};
use super::wire::{Broken, Event, Frame, Framer, Junk, Kind};
use super::{COLUMNS, Framing, Options};
use crate::fmt::{hex_0x, push_fixed, push_hex};
use crate::numbers::push_uint;
use crate::pairing::Open;
use crate::protocol::{Decoder, untimed_micros};
use crate::row::{self, Class, Latch, Parts, Row, RowOut, RowResult, Unframed};
use crate::stats::{Problems, Report};

enum Framers {
    Rtu(Box<Framer>),
    Ascii(Box<AsciiFramer>),
}

/// The Modbus decoder (RTU or ASCII framing).
pub struct ModbusDecoder {
    framer: Framers,
    core: Core,
}

struct Core {
    opts: Options,
    bits: u32,
    pairing: Pairing,
    table: Table,
    totals: Totals,
    /// The row being built, and the Timeout row (written while a row is being built).
    c: Content,
    tc: Content,
    resp: String,
    /// The Data cell and numbers of the common frames ([`super::fast`]).
    fast: Fast,
}

impl ModbusDecoder {
    pub fn new(opts: Options) -> Self {
        let timeout = opts.timeout_ms.saturating_mul(1000);
        // 40 characters of silence (at least 100 ms) settle the bytes held.
        let settle = untimed_micros(40, opts.line.bits_per_char(), opts.line.baud);
        let framer = match opts.framing {
            Framing::Rtu => Framers::Rtu(Box::new(Framer::new(timeout).settling_after(settle))),
            Framing::Ascii => {
                Framers::Ascii(Box::new(AsciiFramer::new(timeout).settling_after(settle)))
            }
        };
        ModbusDecoder {
            framer,
            core: Core {
                bits: opts.line.bits_per_char(),
                pairing: Pairing::new(timeout),
                table: Table::default(),
                totals: Totals::default(),
                c: Content::default(),
                tc: Content::default(),
                resp: String::new(),
                fast: Fast::default(),
                opts,
            },
        }
    }

    /// The counters of the whole input.
    pub fn totals(&self) -> &Totals {
        &self.core.totals
    }

    /// The counters of a slave and function, if it was seen in a valid frame.
    pub fn function_stats(&self, slave: u8, function: u8) -> Option<&super::FunctionStats> {
        self.core.table.get(slave, function)
    }

    /// Feeds bytes (`Some`), a silence until a time (`Err`), or the end (`None`).
    fn feed(&mut self, data: Option<(&[u8], Option<u64>)>, out: &mut dyn RowOut) -> RowResult {
        self.feed_event(data.ok_or(None), out)
    }

    fn feed_event(
        &mut self,
        what: Result<(&[u8], Option<u64>), Option<u64>>,
        out: &mut dyn RowOut,
    ) -> RowResult {
        let (core, framer) = (&mut self.core, &mut self.framer);
        Latch::with(out, |latch| {
            let mut emit = |ev: &Event<'_>| {
                if !latch.stopped() {
                    let _ = core.event(ev, latch);
                }
            };
            match (framer, what) {
                (Framers::Rtu(f), Ok((d, t))) => f.push(d, t, &mut emit),
                (Framers::Rtu(f), Err(Some(now))) => f.idle(now, &mut emit),
                (Framers::Rtu(f), Err(None)) => f.finish(&mut emit),
                (Framers::Ascii(f), Ok((d, t))) => f.push(d, t, &mut emit),
                (Framers::Ascii(f), Err(Some(now))) => f.idle(now, &mut emit),
                (Framers::Ascii(f), Err(None)) => f.finish(&mut emit),
            }
        })
    }
}

/// The Device column of a slave.
fn device(opts: &Options, slave: Option<u8>) -> &str {
    slave
        .and_then(|s| opts.map.slave_name(s))
        .unwrap_or_default()
}

/// The slave and function a frame's first bytes name, when they could be a frame's.
fn header(b: &[u8]) -> Option<(u8, u8)> {
    match *b {
        [s, f, ..] if s <= function::MAX_SLAVE && function::is_public(f & 0x7F) => Some((s, f)),
        _ => None,
    }
}

impl Core {
    fn micros(&self, time: Option<u64>, offset: u64) -> u64 {
        time.unwrap_or_else(|| untimed_micros(offset, self.bits, self.opts.line.baud))
    }

    fn event(&mut self, ev: &Event<'_>, out: &mut dyn RowOut) -> RowResult {
        match ev {
            Event::Frame(f) => self.frame(f, out),
            Event::Junk(j) => self.junk(j, out),
        }
    }

    /// Reports the waiting request if its timeout passed at `now`.
    fn expire(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        if let Some(p) = self.pairing.expire(now) {
            let at = p.time.saturating_add(self.pairing.timeout);
            self.timeout_row(&p, Reason::Deadline, at, out)?;
        }
        Ok(())
    }

    fn timeout_row(
        &mut self,
        p: &Outstanding,
        why: Reason,
        at: u64,
        out: &mut dyn RowOut,
    ) -> RowResult {
        self.totals.timeouts += 1;
        self.table
            .valid(p.slave, p.function, &mut self.totals)
            .timeouts += 1;
        let c = &mut self.tc;
        c.clear();
        if matches!(p.function, 1..=4 | 15 | 16 | 23) {
            c.data.push_str("start=");
            push_uint(&mut c.data, p.start as u64);
            c.data.push_str(" count=");
            push_uint(&mut c.data, p.count as u64);
        }
        let timeout = self.pairing.timeout;
        c.note_with(|n| match why {
            Reason::Deadline => {
                n.push_str("no answer within ");
                push_uint(n, timeout / 1000);
                n.push_str(" ms");
            }
            Reason::NextRequest => n.push_str("no answer before the next request"),
            Reason::Retry => n.push_str("no answer before the retry"),
            _ => n.push_str("no answer before the end of the capture"),
        });
        let extra = ["", "", c.note.as_str()];
        out.row(&Row {
            stamp: 0,
            micros: Some(at),
            id: Some(p.slave as u32),
            device: device(&self.opts, Some(p.slave)),
            kind: row::kind::TIMEOUT,
            class: Class::Warning,
            sensor_no: hex_0x(p.function),
            sensor: function::name(p.function),
            data: &c.data,
            extra: &extra,
            parts: Parts::NONE,
            raw: &[],
        })
    }

    fn frame(&mut self, f: &Frame<'_>, out: &mut dyn RowOut) -> RowResult {
        let t = self.micros(f.time, f.offset);
        let timed = f.time.is_some();
        self.expire(t, out)?;
        self.c.clear();
        self.resp.clear();
        let (slave, fc) = (f.pdu[0], f.pdu[1]);
        self.totals.valid += 1;
        self.totals.ambiguous += u64::from(f.ambiguous);
        let mut class = Class::Plain;
        let (kind, req) = match f.kind {
            Kind::Request => {
                self.totals.requests += 1;
                let info = request_info(f.pdu);
                let (rk, ended) = self.pairing.request(f.pdu, Open::at(info, t, timed));
                if let Some((p, why)) = ended {
                    self.timeout_row(&p, why, t, out)?;
                }
                let st = self.table.valid(slave, fc, &mut self.totals);
                st.requests += 1;
                if slave == 0 {
                    st.broadcasts += 1;
                    self.c.note("broadcast");
                }
                if let RequestKind::Retry { n, since } = rk {
                    st.retries += 1;
                    self.totals.retries += 1;
                    class = Class::Warning;
                    self.c.note_with(|s| {
                        s.push_str("retry ");
                        push_uint(s, n as u64);
                        if timed {
                            s.push_str(", ");
                            push_fixed(s, (since as i64 + 50) / 100, 1);
                            s.push_str(" ms after the first");
                        }
                    });
                }
                ("Request", None)
            }
            Kind::Unknown => {
                class = Class::Warning;
                self.c
                    .note("a function whose frames busnoop cannot tell apart");
                ("Unknown", None)
            }
            Kind::Response | Kind::Exception => {
                let exception = f.kind == Kind::Exception;
                if exception {
                    self.totals.exceptions += 1;
                    class = Class::Warning;
                } else {
                    self.totals.responses += 1;
                }
                let answer = self.pairing.answer(slave, fc, t);
                let st = self.table.valid(slave, fc, &mut self.totals);
                if exception {
                    let code = f.pdu.get(2).copied().unwrap_or(0) as usize;
                    st.exceptions[if code < 16 { code } else { 0 }] += 1;
                } else {
                    st.responses += 1;
                }
                let req = match answer {
                    Answer::Paired { req, elapsed, late } => {
                        if timed {
                            st.times.add(elapsed);
                            push_fixed(
                                &mut self.resp,
                                (elapsed.min(i64::MAX as u64 / 2) as i64 + 50) / 100,
                                1,
                            );
                        }
                        if late {
                            st.late += 1;
                            self.totals.late += 1;
                            class = Class::Warning;
                            let ms = self.pairing.timeout / 1000;
                            self.c.note_with(|n| {
                                n.push_str("late: after the ");
                                push_uint(n, ms);
                                n.push_str(" ms timeout");
                            });
                        }
                        Some(req.req)
                    }
                    Answer::Mismatch { req } => {
                        self.totals.unpaired += 1;
                        self.c.note_with(|n| {
                            n.push_str("no request for it (slave ");
                            push_uint(n, req.slave as u64);
                            n.push_str(" function ");
                            n.push_str(hex_0x(req.function));
                            n.push_str(" waits)");
                        });
                        None
                    }
                    Answer::NoRequest => {
                        self.totals.unpaired += 1;
                        self.c.note("no request seen");
                        None
                    }
                };
                (if exception { "Exception" } else { "Response" }, req)
            }
        };
        let fast = self.opts.map.registers().is_empty()
            && self.fast.describe(f.pdu, f.kind, req.as_ref(), &mut self.c);
        if !fast {
            describe(f.pdu, f.kind, req.as_ref(), &self.opts.map, &mut self.c);
        }
        if f.kind == Kind::Exception {
            self.c.note_with(|n| {
                n.push_str("function ");
                n.push_str(hex_0x(fc));
            });
        }
        if f.ambiguous && req.is_none() && f.kind != Kind::Request {
            self.c
                .note("read as a response by its place after the request");
        }
        let Core {
            opts,
            c,
            resp,
            fast: written,
            ..
        } = self;
        let unit = c.nums.first_unit(&opts.map);
        let extra = [unit, resp.as_str(), c.note.as_str()];
        let dev = device(opts, Some(slave));
        let fc = fc & 0x7F;
        let frame = Unframed {
            bytes: f.pdu,
            bad_check: None,
        };
        let row = |data: &str, parts: Parts<'_>, out: &mut dyn RowOut| {
            out.row_unframed(
                &Row {
                    stamp: 0,
                    micros: Some(t),
                    id: Some(slave as u32),
                    device: dev,
                    kind,
                    class,
                    sensor_no: hex_0x(fc),
                    sensor: function::name(fc),
                    data,
                    extra: &extra,
                    parts,
                    raw: f.bytes,
                },
                &frame,
            )
        };
        if fast {
            let text = written.text();
            return row(text, written.parts(text), out);
        }
        let data = c.data.as_str();
        c.nums
            .with_parts(&opts.map, |parts| row(data, Parts::List(parts), out))
    }

    fn junk(&mut self, j: &Junk<'_>, out: &mut dyn RowOut) -> RowResult {
        let t = self.micros(j.time, j.offset);
        self.expire(t, out)?;
        let c = &mut self.c;
        c.clear();
        push_hex(&mut c.data, j.bytes);
        let head = header(j.bytes).filter(|_| j.what != Broken::Garbage);
        let kind = match j.what {
            Broken::Garbage => {
                self.totals.garbage_bytes += j.bytes.len() as u64;
                self.totals.garbage_runs += 1;
                c.note_with(|n| {
                    push_uint(n, j.bytes.len() as u64);
                    n.push_str(if j.bytes.len() == 1 {
                        " byte outside any frame"
                    } else {
                        " bytes outside any frame"
                    });
                });
                row::kind::GARBAGE
            }
            Broken::BadCrc => {
                self.totals.crc_errors += 1;
                let n = j.bytes.len();
                if n >= 2 {
                    let got = u16::from_le_bytes([j.bytes[n - 2], j.bytes[n - 1]]);
                    let want = super::wire::crc16(&j.bytes[..n - 2]);
                    c.note_with(|s| {
                        s.push_str("CRC ");
                        crate::fmt::push_0x16(s, got);
                        s.push_str(", computed ");
                        crate::fmt::push_0x16(s, want);
                    });
                }
                if let Some((s, f)) = head {
                    match self.table.seen(s, f) {
                        Some(st) => st.crc_errors += 1,
                        None => self.totals.unattributed += 1,
                    }
                }
                row::kind::BAD_CRC
            }
            Broken::Truncated => {
                self.totals.truncated += 1;
                c.note_with(|s| {
                    s.push_str("cut after ");
                    push_uint(s, j.bytes.len() as u64);
                    s.push_str(" bytes");
                });
                if head.is_some_and(|(s, f)| self.table.seen(s, f).is_none()) {
                    self.totals.unattributed += 1;
                }
                row::kind::TRUNCATED
            }
        };
        // A broken frame from the slave asked may have been its answer: no Timeout row.
        if let (Some((s, _)), Some(p)) = (head, self.pairing.pending())
            && p.slave == s
        {
            self.pairing.bad_answer();
        }
        let extra = ["", "", self.c.note.as_str()];
        let fc = head.map(|(_, f)| f & 0x7F);
        out.row(&Row {
            stamp: 0,
            micros: Some(t),
            id: head.map(|(s, _)| s as u32),
            device: device(&self.opts, head.map(|(s, _)| s)),
            kind,
            class: Class::Error,
            sensor_no: fc.map_or("", hex_0x),
            sensor: fc.map_or("", function::name),
            data: &self.c.data,
            extra: &extra,
            parts: Parts::NONE,
            raw: j.bytes,
        })
    }

    fn finish(&mut self) {
        // A request still waiting at the end: its answer may simply not have been captured, so
        // it is counted, not reported as a timeout.
        if self.pairing.finish().is_some() {
            self.totals.unanswered_at_end += 1;
        }
    }
}

impl Decoder for ModbusDecoder {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        self.feed(Some((data, time)), out)
    }

    fn idle(&mut self, now: u64, out: &mut dyn RowOut) -> RowResult {
        self.feed_event(Err(Some(now)), out)?;
        // Bytes held since before `now` (a long answer still arriving) become rows no earlier
        // than their first byte: a request's deadline is judged at that time, as a replay of
        // the same bytes judges it.
        let held = match &self.framer {
            Framers::Rtu(f) => f.held_since(),
            Framers::Ascii(f) => f.held_since(),
        };
        self.core.expire(held.map_or(now, |h| h.min(now)), out)
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        self.feed(None, out)?;
        self.core.finish();
        Ok(())
    }

    fn valid_frames(&self) -> u64 {
        self.core.totals.valid
    }

    fn stats(&self) -> Report {
        let c = &self.core;
        let framing = match c.opts.framing {
            Framing::Rtu => "RTU",
            Framing::Ascii => "ASCII",
        };
        let head = format!(
            "Modbus {framing}, {} {}, master timeout {} ms",
            c.opts.line.baud,
            c.opts.line.format(),
            c.pairing.timeout / 1000
        );
        stats::report(head, &c.table, &c.totals, |s| {
            device(&c.opts, Some(s)).to_owned()
        })
    }

    fn problems(&self) -> Problems {
        stats::problems(&self.core.totals)
    }

    fn no_frames_hint(&self) -> &'static str {
        "check the baud rate and parity (Modbus defaults to 19200 8E1; 9600 8N1 is common) and \
         that the adapter listens to A/B of the RS-485 pair"
    }
}
