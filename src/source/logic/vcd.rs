//! Value change dumps (`.vcd`), as PulseView, `sigrok-cli -O vcd`, Saleae Logic and HDL
//! simulators write them: a header (`$timescale`, `$scope`, `$var wire 1 ! RX $end`, …,
//! `$enddefinitions`), then `#time` stamps and value changes (`0!`, `1!`, `b1 !`). Parsed with
//! the `vcd` crate command by command (its header parser would recurse into nested scopes,
//! without a limit; scopes are not needed here), so memory stays flat.
//!
//! Every 1-bit variable is a channel, named by its reference (`RX`, `D0`, `data[3]`), numbered
//! in the order of the header. Unknown and high-impedance values (`x`, `z`) leave the level as
//! it was. Times are ticks of the `$timescale` (1 ns when the header has none).

use std::collections::HashMap;
use std::io::{BufReader, Read};

use vcd::{Command, IdCode, Value};

use super::uart::TimeBase;
use super::{Channel, Edge, Header, Step, Wave, whole_input};
use crate::exit::Failure;
use crate::source::Opened;

/// Commands handled per read at most (bounds the edges a read hands out).
const COMMANDS_PER_READ: usize = 64 * 1024;

/// A VCD file's 1-bit variables as edges.
pub struct VcdWave {
    parser: vcd::Parser<BufReader<Box<dyn Read + Send>>>,
    name: String,
    header: Header,
    /// Channel places by identifier code (several variables may share one).
    ids: HashMap<IdCode, Vec<usize>>,
    /// Per channel place: its slot in the selection and its last level.
    slots: Vec<Option<(u16, Option<bool>)>>,
    /// The current time.
    time: u64,
    /// A timestamp was read (the end of the trace is the last one).
    ended: bool,
}

impl VcdWave {
    /// Reads the header.
    pub fn open(opened: Opened) -> Result<Self, Failure> {
        let (reader, name) = whole_input(opened);
        let mut parser = vcd::Parser::new(BufReader::with_capacity(64 * 1024, reader));
        let bad = |what: String| Failure::Input(format!("{name}: not a usable VCD file: {what}"));
        let mut channels = Vec::new();
        let mut ids: HashMap<IdCode, Vec<usize>> = HashMap::new();
        let mut timescale = None;
        loop {
            let cmd = match parser.next() {
                Some(Ok(c)) => c,
                Some(Err(e)) => return Err(bad(e.to_string())),
                None => return Err(bad("the file ends before $enddefinitions".into())),
            };
            match cmd {
                Command::Enddefinitions => break,
                Command::Timescale(n, unit) => timescale = Some((n, unit)),
                Command::VarDef(_, 1, code, reference, index) => {
                    let name = match index {
                        Some(i) => format!("{reference}{i}"),
                        None => reference,
                    };
                    let place = channels.len();
                    channels.push(Channel {
                        number: place,
                        name,
                    });
                    ids.entry(code).or_default().push(place);
                }
                Command::VarDef(..)
                | Command::ScopeDef(..)
                | Command::Upscope
                | Command::Comment(_)
                | Command::Date(_)
                | Command::Version(_) => {}
                other => {
                    return Err(bad(format!(
                        "{other:?} in the header (line {})",
                        parser.line()
                    )));
                }
            }
        }
        let base = match timescale {
            None => TimeBase::rate(1_000_000_000),
            Some((n, unit)) => {
                use vcd::TimescaleUnit::*;
                let den = match unit {
                    S => 1,
                    MS => 1_000,
                    US => 1_000_000,
                    NS => 1_000_000_000,
                    PS => 1_000_000_000_000,
                    FS => 1_000_000_000_000_000,
                };
                if n == 0 {
                    return Err(bad("a timescale of 0".into()));
                }
                TimeBase {
                    num: u64::from(n),
                    den,
                }
            }
        };
        let n = channels.len();
        Ok(VcdWave {
            parser,
            name,
            header: Header {
                channels,
                base,
                sample_rate: None,
            },
            ids,
            slots: vec![None; n],
            time: 0,
            ended: false,
        })
    }

    /// Channel places of `code` at level `high` from now on.
    fn change(&mut self, code: IdCode, high: bool, out: &mut Vec<Edge>) {
        let Some(places) = self.ids.get(&code) else {
            return;
        };
        for &p in places {
            if let Some(Some((slot, last))) = self.slots.get_mut(p)
                && *last != Some(high)
            {
                *last = Some(high);
                out.push(Edge {
                    tick: self.time,
                    slot: *slot,
                    high,
                });
            }
        }
    }
}

impl Wave for VcdWave {
    fn header(&self) -> &Header {
        &self.header
    }

    fn select(&mut self, channels: &[usize]) {
        let old = std::mem::replace(&mut self.slots, vec![None; self.header.channels.len()]);
        for (slot, &c) in channels.iter().enumerate() {
            if let Some(s) = self.slots.get_mut(c) {
                let last = old.get(c).copied().flatten().and_then(|o| o.1);
                *s = Some((slot as u16, last));
            }
        }
    }

    fn read(&mut self, out: &mut Vec<Edge>) -> Result<Step, Failure> {
        if self.ended {
            return Ok(Step::End(self.time));
        }
        for _ in 0..COMMANDS_PER_READ {
            let cmd = match self.parser.next() {
                Some(Ok(c)) => c,
                Some(Err(e)) => {
                    return Err(Failure::Input(format!(
                        "{}: broken VCD data: {e}",
                        self.name
                    )));
                }
                None => {
                    self.ended = true;
                    return Ok(Step::End(self.time));
                }
            };
            match cmd {
                Command::Timestamp(t) => {
                    if t < self.time {
                        return Err(Failure::Input(format!(
                            "{}: the time goes back from #{} to #{t} (line {})",
                            self.name,
                            self.time,
                            self.parser.line()
                        )));
                    }
                    self.time = t;
                }
                Command::ChangeScalar(code, v) => match v {
                    Value::V0 => self.change(code, false, out),
                    Value::V1 => self.change(code, true, out),
                    _ => {}
                },
                Command::ChangeVector(code, v) if v.len() >= 1 => match v.get(v.len() - 1) {
                    Some(Value::V0) => self.change(code, false, out),
                    Some(Value::V1) => self.change(code, true, out),
                    _ => {}
                },
                _ => {}
            }
        }
        Ok(Step::Upto(self.time))
    }
}
