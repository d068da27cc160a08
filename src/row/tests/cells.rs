//! The batched writers of [`crate::row::Cells`] write what the pieces they replace write, in
//! every format, with room to spare or not (a line longer than the room is written again).

use crate::row::text::{Format, Text};
use crate::row::{Cells, Class, Direct, Fmt, Mark, PartNames, WriteRow};

const FORMATS: [Format; 4] = [Format::Tsv, Format::Csv, Format::Jsonl, Format::Pretty];
const EXTRA: [&str; 3] = ["Unit", "Resp ms", "Note"];

/// One row written straight into a table of `format` whose output has `room` bytes.
fn line(format: Format, raw: bool, room: usize, row: &impl WriteRow) -> String {
    let mut text = Text::new(format, false, raw, &EXTRA, Vec::new());
    let (mut buf, mut len) = (vec![0u8; room], 0);
    for _ in 0..2 {
        let d = Direct {
            text: &mut text,
            buf: &mut buf,
            len: &mut len,
        };
        d.row(Some(12_345), Class::Plain, &[0x7E, 0x01], row);
    }
    buf.truncate(len);
    String::from_utf8(buf).unwrap()
}

static NAMES: PartNames<4> = PartNames::new(["CH1", "FrameLost", "Bat%", "ABCDEFGHIJKL"]);
static ODD: PartNames<3> = PartNames::new(["CH1", "a \"b\"", "thirteen char"]);

/// A row with numbers in Data (and a quote there, to be escaped, when `quote`), then the
/// members of `parts` for the first `n` numbers and `n` texts: batched or one by one.
struct Numbers {
    numbers: [&'static str; 4],
    quote: bool,
    n: usize,
    batched: bool,
    odd: bool,
}

impl WriteRow for Numbers {
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        if c.stamp(0) {
            c.id(Some(7));
            c.text("Dev");
            c.text("Data");
            c.text("0x01");
            c.text("CH1");
            c.stamp_end();
        }
        c.begin();
        if self.quote {
            c.str("\"");
        }
        let mut marks = [Mark::default(); 4];
        for (i, num) in self.numbers.iter().enumerate() {
            if i > 0 {
                c.put_ascii(b" ");
            }
            let a = c.here();
            c.put_ascii(num.as_bytes());
            marks[i] = Mark::new(a, c.here());
        }
        c.end();
        c.value(Some(marks[0]));
        c.text("us");
        c.empty();
        c.text("note");
        let texts = &self.numbers[..self.n];
        let marks = &marks[..self.n];
        if self.odd {
            if self.batched {
                c.parts_marked(&ODD, &marks[..self.n.min(3)]);
                c.parts_text(&ODD, &texts[..self.n.min(3)]);
            } else {
                for (name, &m) in ODD.names().iter().zip(marks) {
                    c.part(name, m);
                }
                for (name, t) in ODD.names().iter().zip(texts) {
                    c.part_text(name, t);
                }
            }
        } else if self.batched {
            c.parts_marked(&NAMES, marks);
            c.parts_text(&NAMES, texts);
        } else {
            for (name, &m) in NAMES.names().iter().zip(marks) {
                c.part_static(name, m);
            }
            for (name, t) in NAMES.names().iter().zip(texts) {
                c.part_text(name, t);
            }
        }
    }
}

#[test]
fn listed_parts_write_what_each_part_writes() {
    let numbers = [
        ["1", "-0.5", "22", "3"],
        ["1500", "1", "-1234567.1234567", "0"],
        ["1", "1234567890123456789012345678901234567890", "2", "3"],
    ];
    for format in FORMATS {
        for numbers in numbers {
            for quote in [false, true] {
                for odd in [false, true] {
                    for n in 0..=4 {
                        for room in [16, 200, 400, 4096] {
                            let row = |batched| Numbers {
                                numbers,
                                quote,
                                n,
                                batched,
                                odd,
                            };
                            assert_eq!(
                                line(format, false, room, &row(true)),
                                line(format, false, room, &row(false)),
                                "{format:?} {numbers:?} {quote} {odd} {n} {room}"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// A row whose cells from column `from` on are empty: in one piece or one by one.
struct Empty {
    from: usize,
    batched: bool,
}

impl WriteRow for Empty {
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        if c.stamp(0) {
            c.id(None);
            c.text("Dev");
            c.text("Null");
            c.empty();
            c.empty();
            c.stamp_end();
        }
        let mut col = 7;
        while col < self.from {
            match col {
                7 => c.text("data"),
                8 => c.value_text(Some("1")),
                _ => c.text("x"),
            }
            col += 1;
        }
        if self.batched {
            c.empty_to_end();
            return;
        }
        while col < 9 + EXTRA.len() {
            if col == 8 {
                c.value(None);
            } else {
                c.empty();
            }
            col += 1;
        }
    }
}

#[test]
fn empty_to_end_writes_what_each_empty_cell_writes() {
    for format in FORMATS {
        for raw in [false, true] {
            for from in 7..=9 + EXTRA.len() {
                for room in [16, 4096] {
                    let row = |batched| Empty { from, batched };
                    assert_eq!(
                        line(format, raw, room, &row(true)),
                        line(format, raw, room, &row(false)),
                        "{format:?} {raw} {from} {room}"
                    );
                }
            }
        }
    }
}

/// A row whose Data cell and last extra column hold commas (`B5 (181, -75)`): begun with
/// [`Cells::begin_listed`] (CSV's opening quote written first) or written as any text (quoted
/// at its end, from a copy), a number marked in Data read back for Value and `parts`.
struct Listed {
    pieces: &'static [&'static [u8]],
    listed: bool,
}

impl Listed {
    fn cell<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) -> Mark {
        if self.listed {
            c.begin_listed();
        } else {
            c.begin();
        }
        let mut mark = Mark::default();
        for (i, piece) in self.pieces.iter().enumerate() {
            if i == 1 {
                let a = c.here();
                c.dec(181);
                mark = Mark::new(a, c.here());
            }
            if !self.listed {
                c.str(std::str::from_utf8(piece).unwrap());
            } else if piece.contains(&b',') {
                c.put_listed(piece);
            } else {
                c.put_ascii(piece);
            }
        }
        c.end();
        mark
    }
}

impl WriteRow for Listed {
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        data_and_note(c, ["Dev", "ACK", "0x40", ""], "us", |c| self.cell(c));
    }
}

/// A row of device 7 with the cells Device to Sensor `stamped`, a Data cell written by `cell`
/// (its mark read back for Value and `parts`), Unit `unit`, and a Note written by `cell` again.
fn data_and_note<F: Fmt>(
    c: &mut Cells<'_, '_, F>,
    stamped: [&str; 4],
    unit: &str,
    cell: impl Fn(&mut Cells<'_, '_, F>) -> Mark,
) {
    if c.stamp(0) {
        c.id(Some(7));
        for t in stamped {
            c.text(t);
        }
        c.stamp_end();
    }
    let m = cell(c);
    c.value(Some(m));
    c.text(unit);
    c.empty();
    cell(c);
    c.part("CH1", m);
}

#[test]
fn listed_cells_write_what_any_text_writes() {
    let pieces: [&[&[u8]]; 4] = [
        &[b"B5 (", b", -75)"],
        &[b"A2 DB (", b", -", b"9310)"],
        &[b",", b","],
        &[b"1, 2, 3 (", b")"],
    ];
    for format in FORMATS {
        for raw in [false, true] {
            for pieces in pieces {
                for room in [16, 64, 4096] {
                    let row = |listed| Listed { pieces, listed };
                    assert_eq!(
                        line(format, raw, room, &row(true)),
                        line(format, raw, room, &row(false)),
                        "{format:?} {raw} {pieces:?} {room}"
                    );
                }
            }
        }
    }
}

/// A row whose Data cell is written again (a quote in it) and whose Note, written in place
/// after it, is written again too: the numbers marked in Data must still be read from Data's
/// copy, not from Note's.
struct TwoRewrites {
    /// Note's text, written in place.
    note: &'static str,
}

impl WriteRow for TwoRewrites {
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        if c.stamp(0) {
            c.id(Some(7));
            c.text("Dev");
            c.text("Data");
            c.text("0x01");
            c.text("CH1");
            c.stamp_end();
        }
        c.begin();
        c.str("\"q\" ");
        let a = c.here();
        c.put_ascii(b"1234");
        let first = Mark::new(a, c.here());
        c.put_ascii(b" ");
        let a = c.here();
        c.put_ascii(b"-56.5");
        let second = Mark::new(a, c.here());
        c.end();
        c.value(Some(first));
        c.text("us");
        c.empty();
        c.begin();
        c.str(self.note);
        c.end();
        c.parts_marked(&NAMES, &[first, second]);
    }
}

#[test]
fn marks_in_a_rewritten_data_cell_survive_a_later_rewritten_cell() {
    for note in [
        "plain note",
        "a \"quoted\" note",
        "back\\slash",
        "tab\there",
    ] {
        for room in [16, 400, 4096] {
            let out = line(Format::Jsonl, false, room, &TwoRewrites { note });
            for l in out.lines() {
                let v: serde_json::Value = serde_json::from_str(l)
                    .unwrap_or_else(|e| panic!("{note:?} {room}: not JSON ({e}): {l}"));
                assert_eq!(v["data"], "\"q\" 1234 -56.5", "{l}");
                assert_eq!(v["note"], note, "{l}");
                assert_eq!(v["value"], 1234, "{l}");
                assert_eq!(v["parts"]["CH1"], 1234, "{note:?} {room}: {l}");
                assert_eq!(v["parts"]["FrameLost"], -56.5, "{note:?} {room}: {l}");
            }
            // CSV and TSV read Value before Note: the same numbers.
            for format in [Format::Csv, Format::Tsv] {
                let out = line(format, false, room, &TwoRewrites { note });
                let sep = if format == Format::Csv {
                    ",1234,"
                } else {
                    "\t1234\t"
                };
                assert!(out.lines().all(|l| l.contains(sep)), "{format:?} {out}");
            }
        }
    }
}

/// A row whose Data cell and Note end in characters beyond ASCII (`1500 …`, `5 µs`): written
/// with [`Cells::put_glyphs`] (the cell stays plain) or as any text (looked at again, its
/// width counted in pretty text).
struct Glyphs {
    pieces: &'static [&'static str],
    glyphs: bool,
}

impl Glyphs {
    fn cell<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) -> Mark {
        c.begin();
        let a = c.here();
        c.dec(1500);
        let mark = Mark::new(a, c.here());
        for piece in self.pieces {
            if !self.glyphs {
                c.str(piece);
            } else if piece.is_ascii() {
                c.put_ascii(piece.as_bytes());
            } else {
                c.put_glyphs(piece);
            }
        }
        c.end();
        mark
    }
}

impl WriteRow for Glyphs {
    fn write<F: Fmt>(&self, c: &mut Cells<'_, '_, F>) {
        data_and_note(c, ["Receiver", "Control", "", "Channels"], "µs", |c| {
            self.cell(c)
        });
    }
}

#[test]
fn glyph_pieces_write_what_any_text_writes() {
    let pieces: [&[&str]; 6] = [
        &[" 1490 1491", " …"],
        &[" µs"],
        &["…", "…", " 12 ", "°C"],
        &[" \u{1F680}", " x"],
        &[""],
        &["\u{2026}\u{2026}\u{2026}", "x"],
    ];
    for format in FORMATS {
        for raw in [false, true] {
            for pieces in pieces {
                // Every room up to a whole line: a glyph piece with no room left is dropped
                // while a shorter piece after it may still fit (the line is written again).
                for room in (8..=160).chain([4096]) {
                    let row = |glyphs| Glyphs { pieces, glyphs };
                    assert_eq!(
                        line(format, raw, room, &row(true)),
                        line(format, raw, room, &row(false)),
                        "{format:?} {raw} {pieces:?} {room}"
                    );
                }
            }
        }
    }
}
