//! Pretty rows fitted to the terminal's width (the pretty table on a terminal, unless
//! `--no-fit`): a row that fits is written as without fitting; a longer one wraps its Data, Note
//! and Raw cells within their columns onto continuation lines, and when the other columns leave
//! them too little room, cuts names (Device, Type, Sensor, text columns of the protocol) with
//! `…`. Numbers (Counter, Millis, ID, Sensor #, `Resp ms`, `Seq`, `Time`) are never cut: a
//! terminal too narrow even for them gets lines longer than it.
//!
//! Files and pipes are never fitted: their bytes stay those of every other run.

/// What may happen to a column on a narrow terminal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// Right-aligned numbers (Counter, Millis, ID): never cut.
    Right,
    /// Left-aligned, never cut (Sensor #, numbers of the protocol, Time).
    Keep,
    /// A name: cut with `…` down to [`CUT_MIN`] when the wrapped columns need the room.
    Cut,
    /// Data, Note, Raw: wrapped within the column.
    Wrap,
}

/// Names are cut down to this many columns at most.
const CUT_MIN: usize = 4;
/// A wrapped column is given at least this many columns when there is room for it.
const WRAP_MIN: usize = 12;
/// Blanks between columns.
const GAP: usize = 2;
/// Wrapped cells under the row (a narrow terminal) are indented this much.
const INDENT: usize = 4;

/// A cell's text as shown: control characters as blanks.
fn shown(cell: &str) -> Vec<char> {
    cell.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// `text` cut with `…` to `width` columns.
fn cut(text: &[char], width: usize) -> Vec<char> {
    if text.len() <= width {
        return text.to_vec();
    }
    let mut v: Vec<char> = text[..width.saturating_sub(1)].to_vec();
    v.push('…');
    v
}

/// `text` in pieces of at most `width` columns, broken after a blank where one is near the
/// end of a piece, else inside a word.
fn wrap(text: &[char], width: usize) -> Vec<Vec<char>> {
    let width = width.max(1);
    let mut out = Vec::new();
    let mut rest = text;
    while rest.len() > width {
        let at = rest[..=width]
            .iter()
            .rposition(|&c| c == ' ')
            .filter(|&i| i > 0)
            .unwrap_or(width);
        let (piece, tail) = rest.split_at(at);
        out.push(piece.to_vec());
        rest = tail;
        while rest.first() == Some(&' ') {
            rest = &rest[1..];
        }
    }
    if !rest.is_empty() || out.is_empty() {
        out.push(rest.to_vec());
    }
    out
}

/// The lines of one row: `cells` in columns `widths` wide (the last column as wide as its
/// cell), fitted to `width` as the module says. Trailing blanks are trimmed.
pub(super) fn lines(cells: &[&str], widths: &[usize], kinds: &[Kind], width: usize) -> Vec<String> {
    let n = cells.len();
    let text: Vec<Vec<char>> = cells.iter().map(|c| shown(c)).collect();
    // The row as without fitting.
    let mut w: Vec<usize> = (0..n)
        .map(|i| {
            let own = widths.get(i).copied().unwrap_or(CUT_MIN);
            if i + 1 == n {
                text[i].len()
            } else {
                own.max(text[i].len())
            }
        })
        .collect();
    let used = (0..n)
        .rposition(|i| !text[i].is_empty())
        .map_or(0, |i| i + 1);
    let total = |w: &[usize]| w[..used].iter().sum::<usize>() + GAP * used.saturating_sub(1);
    if total(&w) <= width {
        return vec![join(&text, &w, kinds, used)];
    }
    let wrapped: Vec<usize> = (0..used).filter(|&i| kinds[i] == Kind::Wrap).collect();
    let need = |i: usize| text[i].len().max(1);
    let fixed = |w: &[usize]| {
        (0..used)
            .filter(|&i| kinds[i] != Kind::Wrap)
            .map(|i| w[i])
            .sum::<usize>()
            + GAP * used.saturating_sub(1)
    };
    let longest = |i: usize| {
        text[i]
            .split(|&c| c == ' ')
            .map(<[char]>::len)
            .max()
            .unwrap_or(0)
            .clamp(1, need(i))
    };
    // Each wrapped column wants its longest word (a number in Data is not broken), and at
    // least a few columns.
    let want_min: usize = wrapped
        .iter()
        .map(|&i| longest(i).max(WRAP_MIN.min(need(i))))
        .sum();
    // Names give up room while the wrapped columns lack it.
    while fixed(&w) + want_min > width {
        let widest = (0..used)
            .filter(|&i| kinds[i] == Kind::Cut && w[i] > CUT_MIN)
            .max_by_key(|&i| w[i]);
        match widest {
            Some(i) => w[i] -= 1,
            None => break,
        }
    }
    // No room beside the other columns (a narrow terminal): the wrapped cells go under them,
    // each on lines of their own, indented.
    if !wrapped.is_empty() && width.saturating_sub(fixed(&w)) < want_min {
        let mut first: Vec<Vec<Vec<char>>> = vec![Vec::new(); used];
        for i in 0..used {
            if kinds[i] == Kind::Wrap {
                w[i] = 0;
            } else {
                if kinds[i] == Kind::Cut {
                    first[i] = vec![cut(&text[i], w[i])];
                } else {
                    w[i] = w[i].max(text[i].len());
                    first[i] = vec![text[i].clone()];
                }
            }
        }
        let row: Vec<Vec<char>> = first
            .iter()
            .map(|c| c.first().cloned().unwrap_or_default())
            .collect();
        let mut out = vec![join(&row, &w, kinds, used)];
        for &i in &wrapped {
            for piece in wrap(&text[i], width.saturating_sub(INDENT).max(WRAP_MIN)) {
                let mut l: String = " ".repeat(INDENT);
                l.extend(piece);
                out.push(l.trim_end().to_owned());
            }
        }
        out.retain(|l| !l.trim().is_empty());
        return out;
    }
    // The room left, shared by the wrapped columns: first each its longest word (Data before
    // Note, so that a number in it is not broken), then an equal share up to its need, then
    // the rest to those that need more, in order.
    let mut room = width.saturating_sub(fixed(&w));
    if !wrapped.is_empty() {
        let mut share: Vec<usize> = vec![0; wrapped.len()];
        for (k, &i) in wrapped.iter().enumerate() {
            // Keep one column for each wrapped column after this one.
            let keep = wrapped.len() - k - 1;
            share[k] = longest(i).min(room.saturating_sub(keep)).max(1);
            room = room.saturating_sub(share[k]);
        }
        let even = room / wrapped.len();
        for (k, &i) in wrapped.iter().enumerate() {
            let more = need(i).saturating_sub(share[k]).min(even);
            share[k] += more;
            room -= more;
        }
        for (k, &i) in wrapped.iter().enumerate() {
            let more = need(i).saturating_sub(share[k]).min(room);
            share[k] += more;
            room -= more;
            w[i] = share[k];
        }
    }
    let cells: Vec<Vec<Vec<char>>> = (0..used)
        .map(|i| match kinds[i] {
            Kind::Wrap => wrap(&text[i], w[i]),
            Kind::Cut => vec![cut(&text[i], w[i])],
            Kind::Right | Kind::Keep => {
                w[i] = w[i].max(text[i].len());
                vec![text[i].clone()]
            }
        })
        .collect();
    let height = cells.iter().map(Vec::len).max().unwrap_or(1);
    (0..height)
        .map(|k| {
            let line: Vec<Vec<char>> = cells
                .iter()
                .map(|c| c.get(k).cloned().unwrap_or_default())
                .collect();
            join(&line, &w, kinds, used)
        })
        .collect()
}

/// One line of the first `used` cells padded to `w` (right-aligned where `kinds` says),
/// trimmed.
fn join(cells: &[Vec<char>], w: &[usize], kinds: &[Kind], used: usize) -> String {
    let mut s = String::new();
    for i in 0..used {
        if i > 0 {
            s.extend(std::iter::repeat_n(' ', GAP));
        }
        let c = &cells[i];
        let pad = w[i].saturating_sub(c.len());
        if kinds[i] == Kind::Right {
            s.extend(std::iter::repeat_n(' ', pad));
            s.extend(c.iter());
        } else {
            s.extend(c.iter());
            if i + 1 < used {
                s.extend(std::iter::repeat_n(' ', pad));
            }
        }
    }
    s.truncate(s.trim_end().len());
    s
}

/// The width to fit a terminal's lines to: its own, else `COLUMNS`, else 80 (a terminal that
/// reports none, 0x0).
pub(super) fn terminal_width() -> usize {
    match ratatui::crossterm::terminal::size() {
        Ok((w, _)) if w > 0 => w as usize,
        _ => {
            let cols = std::env::var("COLUMNS").ok();
            fallback_size(cols.as_deref(), None).0 as usize
        }
    }
}

/// The size to draw at on a terminal that reports none (0x0: some serial consoles, containers
/// and `script` sessions): `COLUMNS` and `LINES` when they hold a size, else 80x24.
pub(crate) fn fallback_size(columns: Option<&str>, lines: Option<&str>) -> (u16, u16) {
    let get = |v: Option<&str>, default: u16| {
        v.and_then(|s| s.trim().parse::<u16>().ok())
            .filter(|&n| (1..=1000).contains(&n))
            .unwrap_or(default)
    };
    (get(columns, 80), get(lines, 24))
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [Kind; 10] = [
        Kind::Right,
        Kind::Right,
        Kind::Right,
        Kind::Cut,
        Kind::Cut,
        Kind::Keep,
        Kind::Cut,
        Kind::Wrap,
        Kind::Cut,
        Kind::Wrap,
    ];
    const WIDTHS: [usize; 10] = [7, 8, 3, 10, 9, 8, 10, 30, 4, 0];

    #[test]
    fn a_row_that_fits_is_as_without_fitting() {
        let cells = [
            "12", "345", "1", "FLVSS", "Data", "0x0300", "Cels", "x", "V", "",
        ];
        let got = lines(&cells, &WIDTHS, &KINDS, 200);
        assert_eq!(
            got,
            [
                "     12       345    1  FLVSS       Data       0x0300    Cels        x                               V"
            ]
        );
    }

    /// Data and Note wrap within their columns, names are cut with `…`, numbers stay whole,
    /// and no line is longer than the terminal. Rows used to run on past the terminal's width
    /// (S.Port's header is 111 columns, SAB2 rows 250), each wrapped by the terminal across
    /// the next line's columns.
    #[test]
    fn long_rows_wrap_data_and_note_and_keep_every_number() {
        let data = "EF BE AD DE (3735928559, -559038737) and more words here";
        let note =
            "framing hdlc: SAB2 framing (0x7E flags, byte stuffing, CRC-16/MODBUS), detected";
        let cells = [
            "123456",
            "98765",
            "18",
            "Receiver-long-name",
            "Request",
            "0xF105",
            "Read register(s)",
            data,
            "V",
            note,
        ];
        for width in [80, 100, 60] {
            let got = lines(&cells, &WIDTHS, &KINDS, width);
            assert!(got.len() > 1, "{got:#?}");
            for l in &got {
                assert!(l.chars().count() <= width, "{width}: {l:?} {got:#?}");
            }
            let all = got.join("\n");
            for number in ["123456", "98765", "18", "0xF105"] {
                assert!(
                    got[0].split_whitespace().any(|w| w == number),
                    "{number}: {got:#?}"
                );
            }
            // Every word of Data is there whole (wrapped at blanks), every word of Note too
            // where the room allows.
            let words: Vec<&str> = all.split_whitespace().collect();
            for word in data.split(' ') {
                assert!(
                    words.contains(&word),
                    "{width}: {word} not whole in {got:#?}"
                );
            }
            if width >= 100 {
                for word in note.split(' ') {
                    assert!(
                        words.contains(&word),
                        "{width}: {word} not whole in {got:#?}"
                    );
                }
            }
        }
        let got = lines(&cells, &WIDTHS, &KINDS, 60);
        assert!(got[0].contains('…'), "a name cut with a mark: {got:#?}");
    }

    #[test]
    fn words_wrap_at_blanks() {
        let t: Vec<char> = "aaa bbb ccc ddd".chars().collect();
        let w: Vec<String> = wrap(&t, 8).iter().map(|p| p.iter().collect()).collect();
        assert_eq!(w, ["aaa bbb", "ccc ddd"]);
        let t: Vec<char> = "abcdefghij".chars().collect();
        let w: Vec<String> = wrap(&t, 4).iter().map(|p| p.iter().collect()).collect();
        assert_eq!(w, ["abcd", "efgh", "ij"]);
    }
}
