//! The decoder both CRSF and GHST use: the reassembler of [`super::wire`], the mapping of every
//! event onto a row (a [`Dialect`] describes the valid frames), the time of untimed inputs and
//! the statistics.

use super::wire::{Addresses, Event, Kind, Reassembler};
use crate::fmt::{push_0x, push_hex, push_u64};
use crate::numbers::Numbers;
use crate::protocol::{Decoder, Line, untimed_micros};
use crate::row::{Class, Latch, Parts, Row, RowOut, RowResult};
use crate::stats::{Column, Problems, Report};

/// Extra columns after the eight base columns.
pub const COLUMNS: &[&str] = &["Unit", "Note"];

/// The most numbers a frame carries (29 cell voltages or temperatures in a 60-byte payload).
pub const MAX_NUMBERS: usize = 32;

/// Scratch buffers reused for every row.
#[derive(Default)]
pub(crate) struct Scratch {
    /// The Sensor column; empty: the first number's name.
    pub sensor: String,
    /// The Data column; empty: every number as `name=value+unit`.
    pub data: String,
    pub note: String,
    /// The Sensor # column.
    pub sensor_no: String,
    pub nums: Numbers<MAX_NUMBERS>,
}

impl Scratch {
    fn clear(&mut self) {
        self.sensor.clear();
        self.data.clear();
        self.note.clear();
        self.sensor_no.clear();
        self.nums.clear();
    }

    /// Starts a new part of the Note and returns the note to write it into.
    pub fn note(&mut self) -> &mut String {
        crate::row::note_part(&mut self.note)
    }
}

/// What a dialect says about a valid frame, besides what it wrote into the [`Scratch`].
pub(crate) struct Described {
    /// The Type column.
    pub kind: &'static str,
    pub class: Class,
    /// A link-quality sample (uplink, percent) the frame carries.
    pub lq: Option<u8>,
    /// A check inside the frame failed (a command's inner CRC).
    pub inner_crc_error: bool,
}

impl Described {
    pub fn plain(kind: &'static str) -> Self {
        Described {
            kind,
            class: Class::Plain,
            lq: None,
            inner_crc_error: false,
        }
    }
}

/// A protocol on the CRSF frame shape: its start bytes, its device and type names, and how a
/// valid frame becomes a row.
pub(crate) trait Dialect: Default + Send {
    /// The protocol's name in messages ("CRSF").
    const NAME: &'static str;
    /// The bytes a frame may start with.
    const ADDRESSES: &'static Addresses;
    /// The Device column of an address byte.
    fn device(addr: u8) -> &'static str;
    /// The name of frame type `ty` sent to `addr`, for the notes of bad frames and the
    /// statistics.
    fn type_name(addr: u8, ty: u8) -> Option<&'static str>;
    /// Fills the scratch for a frame whose CRC passed.
    fn describe(&mut self, f: &Event<'_>, sc: &mut Scratch) -> Described;
    /// Writes the row of a frame whose CRC passed (`wire`: address to CRC) straight into the
    /// table ([`crate::row::direct`]) when it can: `Some` with the link-quality sample the
    /// frame carries; `None` leaves the frame to [`Dialect::describe`].
    #[inline]
    fn direct(&mut self, _wire: &[u8], _micros: u64, _out: &mut Latch<'_>) -> Option<Option<u8>> {
        None
    }
    /// The hint for a live line where no frame turns up.
    fn no_frames_hint() -> &'static str;
}

/// Counters of one (address, type) pair.
#[derive(Clone, Debug, Default)]
struct TypeStats {
    frames: u64,
    first: u64,
    last: u64,
}

/// The counters of every (address, type) pair seen, found by an index rather than a search.
#[derive(Clone, Debug, Default)]
struct PerType {
    /// `address << 8 | type` → position in `list` + 1 (0: not seen); empty before the first
    /// frame.
    index: Vec<u32>,
    list: Vec<((u8, u8), TypeStats)>,
}

impl PerType {
    #[inline]
    fn entry(&mut self, addr: u8, ty: u8) -> &mut TypeStats {
        if self.index.is_empty() {
            self.index = vec![0; 1 << 16];
        }
        let slot = &mut self.index[usize::from(addr) << 8 | usize::from(ty)];
        if *slot == 0 {
            self.list.push(((addr, ty), TypeStats::default()));
            *slot = self.list.len() as u32;
        }
        &mut self.list[*slot as usize - 1].1
    }

    /// The pairs in the order of their keys.
    fn sorted(&self) -> Vec<&((u8, u8), TypeStats)> {
        let mut v: Vec<_> = self.list.iter().collect();
        v.sort_by_key(|e| e.0);
        v
    }
}

/// Counters kept while decoding (`--stats`).
#[derive(Clone, Debug, Default)]
struct Stats {
    per: PerType,
    valid_frames: u64,
    crc_errors: u64,
    inner_crc_errors: u64,
    truncated: u64,
    garbage_bytes: u64,
    garbage_runs: u64,
    false_starts: u64,
    resyncs: u64,
    /// Bytes that were not a valid frame followed the last valid one.
    lost: bool,
    first: Option<u64>,
    last: u64,
    lq_frames: u64,
    lq_sum: u64,
    lq_min: u8,
    lq_last: u8,
}

/// The decoder of a [`Dialect`].
pub(crate) struct LinkDecoder<D: Dialect> {
    re: Reassembler,
    map: Mapper<D>,
}

/// Maps events onto rows and keeps the statistics.
struct Mapper<D: Dialect> {
    dialect: D,
    sc: Scratch,
    stats: Stats,
    line: Line,
}

impl<D: Dialect> LinkDecoder<D> {
    /// `line` gives untimed inputs their byte times.
    pub fn new(line: Line) -> Self {
        LinkDecoder {
            re: Reassembler::new(D::ADDRESSES),
            map: Mapper {
                dialect: D::default(),
                sc: Scratch::default(),
                stats: Stats::default(),
                line,
            },
        }
    }
}

impl Stats {
    /// A valid frame at `micros` (its link-quality sample, if it carries one).
    #[inline]
    fn frame(&mut self, addr: u8, ty: u8, micros: u64, lq: Option<u8>) {
        self.valid_frames += 1;
        if self.lost {
            self.resyncs += 1;
            self.lost = false;
        }
        self.first.get_or_insert(micros);
        self.last = micros;
        let t = self.per.entry(addr, ty);
        if t.frames == 0 {
            t.first = micros;
        }
        t.frames += 1;
        t.last = micros;
        if let Some(lq) = lq {
            self.lq_min = if self.lq_frames == 0 {
                lq
            } else {
                self.lq_min.min(lq)
            };
            self.lq_frames += 1;
            self.lq_sum += u64::from(lq);
            self.lq_last = lq;
        }
    }
}

impl<D: Dialect> Mapper<D> {
    fn event(&mut self, ev: &Event<'_>, out: &mut Latch<'_>) {
        if out.stopped() {
            return;
        }
        let micros = ev.time.unwrap_or_else(|| {
            untimed_micros(ev.offset, self.line.bits_per_char(), self.line.baud)
        });
        if ev.kind == Kind::Frame
            && let Some(lq) = self.dialect.direct(ev.wire, micros, out)
        {
            self.stats
                .frame(ev.addr(), ev.ty().unwrap_or(0), micros, lq);
            return;
        }
        let _ = self.row(ev, micros, out);
    }

    fn row(&mut self, ev: &Event<'_>, micros: u64, out: &mut dyn RowOut) -> RowResult {
        self.sc.clear();
        let sc = &mut self.sc;
        let st = &mut self.stats;
        let mut id = Some(u32::from(ev.addr()));
        let mut device = D::device(ev.addr());
        let mut class = Class::Error;
        let kind: &str = match ev.kind {
            Kind::Frame => {
                let ty = ev.ty().unwrap_or(0);
                push_0x(&mut sc.sensor_no, ty);
                let d = self.dialect.describe(ev, sc);
                st.frame(ev.addr(), ty, micros, d.lq);
                st.inner_crc_errors += u64::from(d.inner_crc_error);
                class = d.class;
                d.kind
            }
            Kind::BadCrc => {
                st.crc_errors += 1;
                st.lost |= st.valid_frames > 0;
                let ty = ev.ty().unwrap_or(0);
                push_0x(&mut sc.sensor_no, ty);
                push_hex(&mut sc.data, ev.payload());
                let (got, want) = ev.crcs().unwrap_or((0, 0));
                let note = sc.note();
                note.push_str("CRC ");
                push_0x(note, got);
                note.push_str(", expected ");
                push_0x(note, want);
                match D::type_name(ev.addr(), ty) {
                    Some(name) => {
                        note.push_str(" (");
                        note.push_str(name);
                        note.push_str(" frame)");
                    }
                    None => note.push_str(" (a frame of unknown type)"),
                }
                crate::row::kind::BAD_CRC
            }
            Kind::Truncated => {
                st.truncated += 1;
                st.lost |= st.valid_frames > 0;
                push_hex(&mut sc.data, ev.wire);
                let note = sc.note();
                push_u64(note, ev.wire.len() as u64);
                if let Some(&len) = ev.wire.get(1) {
                    note.push_str(" of ");
                    push_u64(note, u64::from(len) + 2);
                }
                note.push_str(" bytes, cut by the end of the input");
                if let Some(ty) = ev.ty() {
                    push_0x(&mut sc.sensor_no, ty);
                }
                crate::row::kind::TRUNCATED
            }
            Kind::Garbage => {
                st.garbage_bytes += ev.wire.len() as u64;
                st.garbage_runs += 1;
                st.false_starts += u64::from(ev.false_starts);
                st.lost |= st.valid_frames > 0;
                id = None;
                device = "";
                push_hex(&mut sc.data, ev.wire);
                let note = sc.note();
                push_u64(note, ev.wire.len() as u64);
                note.push_str(if ev.wire.len() == 1 {
                    " byte"
                } else {
                    " bytes"
                });
                note.push_str(if ev.before_first {
                    " before the first frame"
                } else {
                    " outside any frame"
                });
                if ev.false_starts > 0 {
                    let note = sc.note();
                    push_u64(note, u64::from(ev.false_starts));
                    note.push_str(if ev.false_starts == 1 {
                        " false frame start (a frame began inside it)"
                    } else {
                        " false frame starts (a frame began inside each)"
                    });
                }
                crate::row::kind::GARBAGE
            }
        };
        let sc = &mut self.sc;
        if sc.sensor.is_empty() || sc.data.is_empty() {
            let (sensor, data) = (&mut sc.sensor, &mut sc.data);
            let fill_sensor = sensor.is_empty();
            let fill_data = data.is_empty();
            sc.nums.with_parts(|parts| {
                if fill_sensor && let Some(p) = parts.first() {
                    sensor.push_str(p.name);
                }
                if fill_data {
                    for (i, p) in parts.iter().enumerate() {
                        if i > 0 {
                            data.push(' ');
                        }
                        data.push_str(p.name);
                        data.push('=');
                        data.push_str(p.text);
                        data.push_str(p.unit);
                    }
                }
            });
        }
        let extra = [sc.nums.first_unit(), sc.note.as_str()];
        let (sensor_no, sensor, data) = (&sc.sensor_no, &sc.sensor, &sc.data);
        sc.nums.with_parts(|parts| {
            out.row(&Row {
                stamp: 0,
                micros: Some(micros),
                id,
                device,
                kind,
                class,
                sensor_no,
                sensor,
                data,
                extra: &extra,
                parts: Parts::List(parts),
                raw: ev.wire,
            })
        })
    }
}

impl<D: Dialect> Decoder for LinkDecoder<D> {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }

    fn push(&mut self, data: &[u8], time: Option<u64>, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        let map = &mut self.map;
        self.re.push(data, time, &mut |e| map.event(e, &mut out));
        out.result()
    }

    fn idle(&mut self, _now: u64, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        let map = &mut self.map;
        self.re.flush_garbage(&mut |e| map.event(e, &mut out));
        out.result()
    }

    fn finish(&mut self, out: &mut dyn RowOut) -> RowResult {
        let mut out = Latch::new(out);
        let map = &mut self.map;
        self.re.finish(&mut |e| map.event(e, &mut out));
        out.result()
    }

    fn valid_frames(&self) -> u64 {
        self.map.stats.valid_frames
    }

    fn stats(&self) -> Report {
        let st = &self.map.stats;
        let mut r = Report::new(&[
            Column::right("ID", 4),
            Column::left("Device", 14).gap(2),
            Column::right("Type", 4),
            Column::left("Name", 12).gap(2),
            Column::right("Frames", 8),
            Column::right("Per s", 8),
        ]);
        r.head.push(
            "ID: the address byte; Per s: frames per second between the first and the last \
             frame of the kind"
                .into(),
        );
        for &((addr, ty), ref t) in st.per.sorted() {
            r.row(vec![
                format!("0x{addr:02X}"),
                D::device(addr).to_owned(),
                format!("0x{ty:02X}"),
                D::type_name(addr, ty).unwrap_or("Unknown").to_owned(),
                t.frames.to_string(),
                rate(t.frames, t.first, t.last),
            ]);
        }
        let first = st.first.unwrap_or(0);
        r.total_row(vec![
            "all".to_owned(),
            String::new(),
            String::new(),
            String::new(),
            st.valid_frames.to_string(),
            rate(st.valid_frames, first, st.last),
        ]);
        r.totals.push(format!(
            "valid frames {}, CRC errors {}, truncated {}, garbage {}, \
             false frame starts {}, resyncs {}, command CRC errors {}",
            st.valid_frames,
            st.crc_errors,
            st.truncated,
            crate::stats::garbage(st.garbage_bytes, st.garbage_runs),
            st.false_starts,
            st.resyncs,
            st.inner_crc_errors
        ));
        if st.lq_frames > 0 {
            r.totals.push(format!(
                "link quality: last {} %, min {} %, mean {:.1} % in {} frames",
                st.lq_last,
                st.lq_min,
                st.lq_sum as f64 / st.lq_frames as f64,
                st.lq_frames
            ));
        } else {
            r.totals.push("link quality: no link statistics".into());
        }
        r
    }

    fn problems(&self) -> Problems {
        let st = &self.map.stats;
        let mut p = Problems::new(D::NAME);
        p.count("crc_errors", st.crc_errors, "CRC error", "CRC errors")
            .count(
                "truncated_frames",
                st.truncated,
                "truncated frame",
                "truncated frames",
            )
            .garbage(st.garbage_bytes, st.garbage_runs)
            .count("resyncs", st.resyncs, "resync", "resyncs")
            .count(
                "command_crc_errors",
                st.inner_crc_errors,
                "command CRC error",
                "command CRC errors",
            )
            .in_valid(st.valid_frames, "valid frame", "valid frames");
        p
    }

    fn no_frames_hint(&self) -> &'static str {
        D::no_frames_hint()
    }
}

/// `frames` per second between `first` and `last` (µs), or `-`.
fn rate(frames: u64, first: u64, last: u64) -> String {
    let span = last.saturating_sub(first);
    if frames < 2 || span == 0 {
        return "-".into();
    }
    format!("{:.1}", (frames - 1) as f64 * 1e6 / span as f64)
}
