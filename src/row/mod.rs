//! The log table every protocol maps its frames onto.
//!
//! The first eight columns follow the S-Port_Snoop sample exactly: `Counter, Millis, ID, Device,
//! Type, Sensor #, Sensor, Data`. A protocol adds its own extra columns after them (see
//! [`crate::protocol::Decoder::columns`]); the sinks add `Raw` (with `--raw`) and `Time` (with
//! `--time abs`) last.

pub mod direct;
pub(crate) mod line;
pub(crate) mod part_keys;
pub(crate) mod pretty;
pub(crate) mod spans;
pub mod text;

pub use direct::{Cells, Direct, Fmt, Mark, WriteRow};
pub use part_keys::PartNames;

/// The eight fixed columns, in order.
pub const BASE_COLUMNS: [&str; 8] = [
    "Counter", "Millis", "ID", "Device", "Type", "Sensor #", "Sensor", "Data",
];

/// The column of the source a row came from, with several sources (`busnoop PROTO SRC1 SRC2`):
/// the first of the extra columns (after `Value`; in pretty output after `Data`), JSON key
/// `port`. A protocol's own extra columns never take this name.
pub const PORT_COLUMN: &str = "Port";

/// The `Type` names every protocol shares. A protocol's own types (`Data`, `Poll`, `ACK`, …)
/// are its business; these mean the same everywhere and filters and summaries rely on them.
pub mod kind {
    /// A frame whose check (CRC, checksum) fails.
    pub const BAD_CRC: &str = "BadCRC";
    /// A frame cut short (by the end of the input, a gap or the next frame start).
    pub const TRUNCATED: &str = "Truncated";
    /// Bytes between frames that belong to no frame.
    pub const GARBAGE: &str = "Garbage";
    /// A request the master's timeout passed without an answer.
    pub const TIMEOUT: &str = "Timeout";
    /// The adapter disappeared (live capture with `--reconnect`, or a recording of one).
    pub const LINK_DOWN: &str = "LinkDown";
    /// The adapter is back.
    pub const LINK_UP: &str = "LinkUp";
    /// The source's own clock went back (EdgeTX logs).
    pub const TIME_JUMP: &str = "TimeJump";
}

/// Starts a new part of a row's Note: the parts of a note are joined with `; ` in every
/// protocol. Returns the note to write the part into.
pub fn note_part(note: &mut String) -> &mut String {
    if !note.is_empty() {
        note.push_str("; ");
    }
    note
}

/// Garbage is shown in rows of at most this many bytes, so that a long run of noise stays
/// readable and every byte is still in exactly one row.
pub const GARBAGE_ROW_MAX: usize = 64;

/// How a row is styled in pretty output and counted in summaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Class {
    /// A poll without an answer, or a normal frame.
    Plain,
    /// A keep-alive without data (S.Port `Null`): dimmed.
    Quiet,
    /// Unusual but not broken (wrong check bits, retries, timeouts): yellow.
    Warning,
    /// Broken: bad CRC, truncated frame, garbage: red.
    Error,
    /// A line inserted by busnoop itself (reconnect gap, notices): cyan.
    Info,
}

/// One number of a row, named (`Cell1`, `VFAS`, `R100`): see [`Row::parts`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part<'a> {
    /// Column name in the wide export and key in JSON (`Cell1`, `Lat`, `RB1V`, `R100`).
    pub name: &'a str,
    /// Unit (`V`, `m`), or "".
    pub unit: &'a str,
    /// Plain decimal with the sensor's full wire precision (`3.918`); what the sinks print.
    pub text: &'a str,
    /// The same number (for the wide export and plots).
    pub value: f64,
}

impl Part<'static> {
    pub const EMPTY: Part<'static> = Part {
        name: "",
        unit: "",
        text: "",
        value: 0.0,
    };
}

/// A row's numbers ([`Row::parts`]): a list of [`Part`]s, or the places of `name=number`
/// pairs in one text cell (an S-Bus media list, `R57=-859895076 R58=…`), which become parts
/// only when a reader asks for them, so that a table that shows the first number alone does
/// not build the rest.
#[derive(Clone, Copy, Debug)]
pub enum Parts<'a> {
    List(&'a [Part<'a>]),
    /// `name = text[start..eq]`, `text = text[eq + 1..end]`, no unit.
    Spans {
        text: &'a str,
        spans: &'a [PartSpan],
    },
}

/// One `name=number` in a text cell: byte offsets (see [`Parts::Spans`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartSpan {
    pub start: u32,
    /// The `=` (the name ends here, the number starts after it).
    pub eq: u32,
    pub end: u32,
    pub value: f64,
}

impl<'a> Parts<'a> {
    /// No numbers.
    pub const NONE: Parts<'static> = Parts::List(&[]);

    pub fn len(&self) -> usize {
        match self {
            Parts::List(l) => l.len(),
            Parts::Spans { spans, .. } => spans.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The `i`-th number. A span that does not lie on the text's character boundaries (which
    /// its writer never records) gives empty strings rather than a panic.
    #[inline]
    pub fn get(&self, i: usize) -> Option<Part<'a>> {
        match *self {
            Parts::List(l) => l.get(i).copied(),
            Parts::Spans { text, spans } => spans.get(i).map(|s| s.part(text)),
        }
    }

    pub fn first(&self) -> Option<Part<'a>> {
        self.get(0)
    }

    pub fn iter(&self) -> PartsIter<'a> {
        match *self {
            Parts::List(l) => PartsIter::List(l.iter()),
            Parts::Spans { text, spans } => PartsIter::Spans(text, spans.iter()),
        }
    }
}

impl PartSpan {
    /// The part this span marks in `text`.
    #[inline]
    fn part<'a>(&self, text: &'a str) -> Part<'a> {
        let cut = |a: u32, b: u32| text.get(a as usize..b as usize).unwrap_or("");
        Part {
            name: cut(self.start, self.eq),
            unit: "",
            text: cut(self.eq.saturating_add(1), self.end),
            value: self.value,
        }
    }
}

impl<'a> From<&'a [Part<'a>]> for Parts<'a> {
    fn from(list: &'a [Part<'a>]) -> Self {
        Parts::List(list)
    }
}

impl<'a> IntoIterator for Parts<'a> {
    type Item = Part<'a>;
    type IntoIter = PartsIter<'a>;
    fn into_iter(self) -> PartsIter<'a> {
        self.iter()
    }
}

/// The numbers of a [`Parts`], in order.
#[derive(Clone, Debug)]
pub enum PartsIter<'a> {
    List(std::slice::Iter<'a, Part<'a>>),
    Spans(&'a str, std::slice::Iter<'a, PartSpan>),
}

impl<'a> Iterator for PartsIter<'a> {
    type Item = Part<'a>;
    #[inline]
    fn next(&mut self) -> Option<Part<'a>> {
        match self {
            PartsIter::List(l) => l.next().copied(),
            PartsIter::Spans(text, spans) => spans.next().map(|s| s.part(text)),
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        match self {
            PartsIter::List(l) => l.size_hint(),
            PartsIter::Spans(_, spans) => spans.size_hint(),
        }
    }
}

/// One row of the table. Strings are borrowed from the decoder's scratch buffers so that
/// producing a row allocates nothing.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// Microseconds since the capture started (`Millis` = this / 1000). `None` leaves Millis empty.
    pub micros: Option<u64>,
    /// `ID` column: physical ID, station or address.
    pub id: Option<u32>,
    pub device: &'a str,
    /// `Type` column.
    pub kind: &'a str,
    pub class: Class,
    /// `Sensor #` column.
    pub sensor_no: &'a str,
    pub sensor: &'a str,
    pub data: &'a str,
    /// Values of the decoder's extra columns, in the order of its column list.
    pub extra: &'a [&'a str],
    /// Every number the row carries, in wire order; empty when it carries none, for frames
    /// whose check failed, and for frames flagged as corrupted though their check passed (S.Port's
    /// non-standard check bits: the ID, outside the CRC, is damaged), so that a corrupted frame
    /// never enters the wide table, a plot or JSON `parts`. The first is the `Value` column; a packed value (an FLVSS frame's two
    /// cells, a pair of halves, several registers) has one part per number, so every number is
    /// reachable (JSON `parts`, one wide column each).
    pub parts: Parts<'a>,
    /// The row's bytes as they were on the wire (for `--raw` and recordings).
    pub raw: &'a [u8],
    /// 0, or a number the decoder gives every row of one kind: two rows of one run with the
    /// same non-zero stamp have the same `id`, `device`, `kind`, `sensor_no` and `sensor`
    /// (S.Port: the physical ID, the frame type and the app ID). The table writes those cells
    /// once per stamp and copies them for the next rows with it. A wrapper that changes one of
    /// these cells must change it the same way for every row with the stamp (as naming a
    /// device by its ID does), or set the stamp to 0.
    pub stamp: u32,
}

impl<'a> Row<'a> {
    /// A row with every text column empty.
    pub fn empty(micros: Option<u64>) -> Row<'static> {
        Row {
            stamp: 0,
            micros,
            id: None,
            device: "",
            kind: "",
            class: Class::Plain,
            sensor_no: "",
            sensor: "",
            data: "",
            extra: &[],
            parts: Parts::NONE,
            raw: &[],
        }
    }

    /// The `Value` column: the first number's text, or "".
    pub fn value(&self) -> &'a str {
        self.parts.first().map_or("", |p| p.text)
    }
}

/// Writing a row failed: the table's output (a file or standard output) and the error, intact,
/// so that the driver can report it as it happened.
#[derive(Debug)]
pub struct OutputError {
    /// `None` for standard output.
    pub path: Option<std::path::PathBuf>,
    pub error: std::io::Error,
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.path {
            Some(p) => write!(f, "cannot write to {}: {}", p.display(), self.error),
            None => write!(f, "cannot write to standard output: {}", self.error),
        }
    }
}

impl std::error::Error for OutputError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

/// What writing rows gives back.
pub type RowResult = Result<(), OutputError>;

/// Receives the rows a decoder produces. An error ends the run: the decoder stops writing and
/// hands the error back unchanged (`?`), the driver reports it.
pub trait RowOut {
    fn row(&mut self, row: &Row<'_>) -> RowResult;

    /// The table's output, lent for one row written straight from a decoded frame
    /// ([`direct`]): only the table gives it, when nothing between the decoder and the table
    /// needs the [`Row`] and the table has the decoder's extra `columns`; everything else
    /// (filters, wrappers, `--wide`, plots) gives `None`, and the decoder writes a `Row`.
    #[inline]
    fn direct(&mut self, _columns: &'static [&'static str]) -> Option<Direct<'_>> {
        None
    }

    /// A row whose frame comes with its content re-read ([`Unframed`]), for a sink that
    /// re-wraps frames (the serial S-Bus export). Everything else takes the row alone.
    fn row_unframed(&mut self, row: &Row<'_>, _frame: &Unframed<'_>) -> RowResult {
        self.row(row)
    }
}

/// A frame's content without its framing, escaping and check, for a sink that re-wraps frames
/// in another protocol (`--export` of serial S-Bus as Ether-S-Bus datagrams), where
/// [`Row::raw`] (the bytes as on the wire) is not enough: in break mode nothing on the wire
/// tells a request from a response. The decoder hands it on with the row
/// ([`RowOut::row_unframed`]); filters and wrappers pass it on with the row they keep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unframed<'a> {
    /// The frame in its protocol's own layout, unescaped (S-Bus: the attribute byte, 0x00
    /// request, 0x01 response, 0x02 ACK/NAK, then `station command data`, the response data,
    /// or the 2-byte ACK/NAK code).
    pub bytes: &'a [u8],
    /// The check as received when it failed; `None` when it passed or the frame has none.
    pub bad_check: Option<u16>,
}

/// Collects rows as owned strings (tests, tools).
#[derive(Default, Debug, Clone)]
pub struct Collected {
    pub rows: Vec<OwnedRow>,
}

/// An owned copy of a [`Row`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OwnedRow {
    pub micros: Option<u64>,
    pub id: Option<u32>,
    pub device: String,
    pub kind: String,
    pub class: Class,
    pub sensor_no: String,
    pub sensor: String,
    pub data: String,
    pub extra: Vec<String>,
    /// (name, unit, text) of every number.
    pub parts: Vec<(String, String, String)>,
    pub raw: Vec<u8>,
}

impl OwnedRow {
    /// The `Value` column.
    pub fn value(&self) -> &str {
        self.parts.first().map_or("", |p| p.2.as_str())
    }

    pub fn millis(&self) -> Option<u64> {
        self.micros.map(|m| m / 1000)
    }
}

impl RowOut for Collected {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        self.rows.push(OwnedRow {
            micros: row.micros,
            id: row.id,
            device: row.device.to_owned(),
            kind: row.kind.to_owned(),
            class: row.class,
            sensor_no: row.sensor_no.to_owned(),
            sensor: row.sensor.to_owned(),
            data: row.data.to_owned(),
            extra: row.extra.iter().map(|s| (*s).to_owned()).collect(),
            parts: row
                .parts
                .iter()
                .map(|p| (p.name.to_owned(), p.unit.to_owned(), p.text.to_owned()))
                .collect(),
            raw: row.raw.to_vec(),
        });
        Ok(())
    }
}

/// Counts rows and throws them away (decode-only benchmarks).
#[derive(Default, Debug)]
pub struct Discard {
    pub rows: u64,
}

impl RowOut for Discard {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        std::hint::black_box(row);
        self.rows += 1;
        Ok(())
    }
}

/// Passes rows on to `out` until the first write error, then drops the rest and keeps that
/// error, whole, for [`Latch::result`]. For reassemblers whose frame callbacks cannot return
/// an error: the decoder maps each frame through the latch, and returns `latch.result()` from
/// `push`/`finish`. Once stopped, no row is formatted any more.
pub struct Latch<'a> {
    out: &'a mut dyn RowOut,
    error: Option<OutputError>,
}

impl<'a> Latch<'a> {
    pub fn new(out: &'a mut dyn RowOut) -> Self {
        Latch { out, error: None }
    }

    /// Runs `f` with a latch on `out` and returns the first write error: the body of a
    /// decoder's `push` or `finish` around a reassembler whose frame callback cannot return one
    /// (`Latch::with(out, |out| re.push(data, time, &mut |e| map.event(e, out)))`).
    pub fn with(out: &'a mut dyn RowOut, f: impl FnOnce(&mut Latch<'a>)) -> RowResult {
        let mut latch = Latch::new(out);
        f(&mut latch);
        latch.result()
    }

    /// A write failed: later rows are dropped.
    pub fn stopped(&self) -> bool {
        self.error.is_some()
    }

    /// The first write error, if any.
    pub fn result(self) -> RowResult {
        match self.error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

impl Latch<'_> {
    fn keep(&mut self, written: RowResult) -> RowResult {
        if let Err(e) = written {
            self.error = Some(e);
        }
        Ok(())
    }
}

impl RowOut for Latch<'_> {
    #[inline]
    fn direct(&mut self, columns: &'static [&'static str]) -> Option<Direct<'_>> {
        if self.error.is_some() {
            return None;
        }
        self.out.direct(columns)
    }

    fn row(&mut self, row: &Row<'_>) -> RowResult {
        if self.error.is_some() {
            return Ok(());
        }
        let written = self.out.row(row);
        self.keep(written)
    }

    fn row_unframed(&mut self, row: &Row<'_>, frame: &Unframed<'_>) -> RowResult {
        if self.error.is_some() {
            return Ok(());
        }
        let written = self.out.row_unframed(row, frame);
        self.keep(written)
    }
}

#[cfg(test)]
#[path = "tests/direct.rs"]
mod direct_tests;

#[cfg(test)]
#[path = "tests/cells.rs"]
mod cells_tests;

#[cfg(test)]
mod tests {
    use super::*;

    /// Spans into a text give the parts a list of the same numbers gives; a span off the
    /// text's character boundaries or beyond it gives empty strings, not a panic.
    #[test]
    fn spans_give_the_parts_of_a_list() {
        let text = "R57=-8 R58=12 Fü=1";
        let span = |start, eq, end, value| PartSpan {
            start,
            eq,
            end,
            value,
        };
        let spans = [span(0, 3, 6, -8.0), span(7, 10, 13, 12.0)];
        let list = [
            Part {
                name: "R57",
                unit: "",
                text: "-8",
                value: -8.0,
            },
            Part {
                name: "R58",
                unit: "",
                text: "12",
                value: 12.0,
            },
        ];
        let from_spans = Parts::Spans {
            text,
            spans: &spans,
        };
        let from_list = Parts::from(&list[..]);
        assert_eq!(from_spans.len(), 2);
        assert_eq!(from_spans.first(), Some(list[0]));
        assert_eq!(from_spans.iter().collect::<Vec<_>>(), list);
        assert_eq!(from_list.into_iter().collect::<Vec<_>>(), list);
        assert_eq!(from_spans.get(2), None);
        assert!(Parts::NONE.is_empty() && Parts::NONE.first().is_none());
        // `ü` is bytes 15-16: 16 is inside it (and 18..16 runs backwards); 40 is past the end;
        // eq at u32::MAX.
        let bad = [
            span(16, 17, 16, 1.0),
            span(0, 3, 40, 2.0),
            span(0, u32::MAX, 3, 3.0),
        ];
        let odd = Parts::Spans { text, spans: &bad };
        let got: Vec<(&str, &str)> = odd.iter().map(|p| (p.name, p.text)).collect();
        assert_eq!(got, [("", ""), ("R57", ""), ("", "")]);
    }
}
