//! Saleae Logic CSV exports of digital channels: a header `Time [s],Channel 0,Channel 1,…`
//! (Logic 2; Logic 1.x writes `Time[s], Channel 0, …`) and one line per time at which a channel
//! changed, with every channel's level: `0.000104000,0,1`. A level `X` (no data: a channel
//! switched off, a gap in the capture) leaves the level as it was.
//!
//! Times are seconds, read exactly as decimals (picosecond ticks). Time 0 of the export is the
//! trace's time 0; an export that starts before it (a trigger in the middle) starts at its first
//! line instead.

use super::uart::TimeBase;
use super::{Channel, Edge, Header, Lines, Step, Wave, parse_seconds, split_fields};
use crate::exit::Failure;
use crate::source::Opened;

/// Longest line read (a header of many long channel names included).
const MAX_LINE: usize = 64 * 1024;
/// Lines handled per read at most.
const LINES_PER_READ: usize = 16 * 1024;

/// A Saleae digital CSV export as edges.
pub struct DigitalCsv {
    lines: Lines,
    name: String,
    header: Header,
    /// Per channel place: its slot in the selection and its last level.
    slots: Vec<Option<(u16, Option<bool>)>>,
    /// Time 0 (ps in the export's time).
    origin: Option<i128>,
    /// The last line's tick.
    time: u64,
    fields: Vec<(usize, usize)>,
    ended: bool,
}

impl DigitalCsv {
    /// Reads the header line.
    pub fn open(opened: Opened) -> Result<Self, Failure> {
        let name = opened.name.clone();
        let mut lines = Lines::new(opened, MAX_LINE);
        let bad =
            |what: &str| Failure::Input(format!("{name}: not a usable Saleae export: {what}"));
        let mut fields = Vec::new();
        let channels = loop {
            let (line, long, _) = lines
                .next_line()
                .map_err(|e| Failure::Input(format!("cannot read {name}: {e}")))?
                .ok_or_else(|| bad("no header line"))?;
            if long {
                return Err(bad("the header line is over 64 KiB"));
            }
            if line.trim_ascii().is_empty() {
                continue;
            }
            split_fields(line, &mut fields);
            break fields[1..]
                .iter()
                .enumerate()
                .map(|(i, &(a, b))| Channel {
                    number: i,
                    name: String::from_utf8_lossy(&line[a..b]).into_owned(),
                })
                .collect::<Vec<_>>();
        };
        let n = channels.len();
        Ok(DigitalCsv {
            lines,
            name,
            header: Header {
                channels,
                base: TimeBase::PICOS,
                sample_rate: None,
            },
            slots: vec![None; n],
            origin: None,
            time: 0,
            fields,
            ended: false,
        })
    }
}

fn bad_line(name: &str, number: u64, what: &str) -> Failure {
    Failure::Input(format!("{name}: line {number}: {what}"))
}

impl Wave for DigitalCsv {
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
        for _ in 0..LINES_PER_READ {
            let next = self
                .lines
                .next_line()
                .map_err(|e| Failure::Input(format!("cannot read {}: {e}", self.name)))?;
            let Some((line, long, number)) = next else {
                self.ended = true;
                return Ok(Step::End(self.time));
            };
            if long {
                return Err(bad_line(&self.name, number, "over 64 KiB long"));
            }
            if line.trim_ascii().is_empty() {
                continue;
            }
            split_fields(line, &mut self.fields);
            let (a, b) = self.fields[0];
            let Some(ps) = parse_seconds(&line[a..b]) else {
                let what = format!(
                    "{:?} is not a time in seconds",
                    String::from_utf8_lossy(&line[a..b])
                );
                return Err(bad_line(&self.name, number, &what));
            };
            let origin = *self.origin.get_or_insert(ps.min(0));
            let tick = u64::try_from(ps - origin)
                .map_err(|_| bad_line(&self.name, number, "time out of range"))?;
            if tick < self.time {
                return Err(bad_line(&self.name, number, "the time goes back"));
            }
            self.time = tick;
            for (place, slot) in self.slots.iter_mut().enumerate() {
                let Some((slot, last)) = slot else {
                    continue;
                };
                let high = match self.fields.get(place + 1).map(|&(a, b)| &line[a..b]) {
                    Some(b"0") => false,
                    Some(b"1") => true,
                    _ => continue,
                };
                if *last != Some(high) {
                    *last = Some(high);
                    out.push(Edge {
                        tick,
                        slot: *slot,
                        high,
                    });
                }
            }
        }
        Ok(Step::Upto(self.time))
    }
}
