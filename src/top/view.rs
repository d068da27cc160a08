//! Drawing the live view: header, one line per device/sensor, the last error rows, key help.

use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line as Text, Span};
use ratatui::widgets::{Cell, Paragraph, Row as TableRow, Table};

use super::model::{Key, Model, Sort, Track};
use crate::filter::{Filter, Names, Vocab};
use crate::row::Class;

/// What the header says about the source.
#[derive(Clone, Debug, Default)]
pub struct Info {
    /// Protocol name ("S.Port").
    pub protocol: String,
    /// SOURCE as given.
    pub source: String,
    /// Line speed of a serial source.
    pub baud: Option<u32>,
    /// Replay speed (`None`: live, or as fast as possible).
    pub speed: Option<f64>,
    pub live: bool,
    /// What the `f` filter is checked against, as the command line's filters: the protocol's
    /// vocabulary (`None`: any words are refused), the names given to IDs, and the sensor names
    /// the protocol's options add.
    pub vocab: Option<&'static Vocab>,
    pub names: Names,
    pub sensors: Vec<String>,
}

/// The user's choices and the view's own state.
#[derive(Clone, Debug)]
pub struct Ui {
    pub sort: Sort,
    /// Applied filter, as typed (`id=1 sensor=RSSI`), and compiled.
    pub filter: String,
    pub compiled: Option<Filter>,
    /// Why the filter typed last was refused (the one applied before stays).
    pub filter_error: Option<String>,
    /// The filter being typed (`f`), shown in the footer.
    pub editing: Option<String>,
    pub paused: bool,
    /// The line under the cursor.
    pub selected: Option<Key>,
    /// The lines shown last, in order (for the cursor keys).
    pub shown: Vec<Key>,
    /// The input ended (replay done): the view stays until `q`.
    pub ended: bool,
    /// Message lines (busnoop's own stderr) for the bottom.
    pub messages: Vec<String>,
    /// The widest cell seen in each column so far: columns grow and never shrink, so that
    /// they do not jump as the values change.
    pub needs: Vec<usize>,
    pub value_min: usize,
}

impl Default for Ui {
    fn default() -> Ui {
        Ui {
            sort: Sort::Id,
            filter: String::new(),
            compiled: None,
            filter_error: None,
            editing: None,
            paused: false,
            selected: None,
            shown: Vec::new(),
            ended: false,
            messages: Vec::new(),
            needs: Vec::new(),
            value_min: 0,
        }
    }
}

impl Ui {
    /// Applies the filter `text` (the command line's filters as words, see
    /// [`Filter::from_words`]); an empty text shows every line. A filter the protocol cannot
    /// match is refused with the reason, and the one before stays.
    pub fn apply_filter(&mut self, text: String, info: &Info) {
        self.filter_error = None;
        // Other lines: the columns fit them anew.
        self.needs.clear();
        self.value_min = 0;
        if text.trim().is_empty() {
            self.filter.clear();
            self.compiled = None;
            return;
        }
        let compiled = match info.vocab {
            Some(v) => Filter::from_words(&text, v, &info.names, &info.sensors, &info.protocol),
            None => Err("no filters for this view".to_string()),
        };
        match compiled {
            Ok(f) => {
                self.filter = text;
                self.compiled = Some(f);
            }
            Err(e) => self.filter_error = Some(e),
        }
    }

    /// Moves the cursor `by` lines (negative: up) among the lines shown last.
    pub fn move_cursor(&mut self, by: isize) {
        if self.shown.is_empty() {
            return;
        }
        let at = self
            .selected
            .as_ref()
            .and_then(|k| self.shown.iter().position(|s| s == k));
        let next = match at {
            None => 0,
            Some(i) => (i as isize + by).clamp(0, self.shown.len() as isize - 1) as usize,
        };
        self.selected = Some(self.shown[next].clone());
    }
}

/// Error rows shown at the bottom (fewer on a small screen).
const EVENT_ROWS: usize = 5;

/// Draws the whole screen for capture time `now`.
pub fn draw(frame: &mut Frame<'_>, model: &Model, ui: &mut Ui, info: &Info, now: u64) {
    let area = frame.area();
    let events = EVENT_ROWS.min(model.events.len() + ui.messages.len());
    let events = if area.height < 16 {
        events.min(2)
    } else {
        events
    };
    let [head, body, bottom, foot] = Layout::vertical([
        Constraint::Length(2),
        Constraint::Min(3),
        Constraint::Length(events as u16 + u16::from(events > 0)),
        Constraint::Length(1),
    ])
    .areas(area);
    header(frame, head, model, ui, info, now);
    lines(frame, body, model, ui, now);
    if events > 0 {
        errors(frame, bottom, model, ui, events);
    }
    footer(frame, foot, model, ui);
}

fn header(frame: &mut Frame<'_>, area: Rect, model: &Model, ui: &Ui, info: &Info, now: u64) {
    let bold = Style::new().add_modifier(Modifier::BOLD);
    let mut first = vec![
        Span::styled(" busnoop ", bold.fg(Color::Black).bg(Color::Cyan)),
        Span::styled(format!(" {} ", info.protocol), bold),
    ];
    let mut rest = Vec::new();
    if let Some(b) = info.baud {
        rest.push(Span::raw(format!("  {b} baud")));
    }
    match (info.live, info.speed) {
        (true, _) => rest.push(Span::raw("  live")),
        (false, Some(s)) => rest.push(Span::raw(format!("  replay ×{}", num(s)))),
        (false, None) => rest.push(Span::raw("  replay, full speed")),
    }
    let elapsed = model.first.map_or(0, |f| now.saturating_sub(f));
    rest.push(Span::raw(format!("  elapsed {}", clock(elapsed))));
    if ui.paused {
        rest.push(Span::styled("  PAUSED", bold.fg(Color::Yellow)));
    }
    if ui.ended {
        rest.push(Span::styled("  END OF INPUT", bold.fg(Color::Yellow)));
    }
    // The source takes the room the rest leaves, cut at its start (`…/flight.log`).
    let used: usize = first
        .iter()
        .chain(&rest)
        .map(|s| s.content.chars().count())
        .sum();
    let room = (area.width as usize).saturating_sub(used);
    let source = &info.source;
    let n = source.chars().count();
    let source = if n <= room {
        source.clone()
    } else if room == 0 {
        String::new()
    } else {
        let tail: String = source.chars().skip(n - room + 1).collect();
        format!("…{tail}")
    };
    first.push(Span::raw(source));
    first.extend(rest);
    let bps = model
        .bytes_per_second(now)
        .map_or("-".into(), |b| format!("{b:.0}"));
    let valid = model
        .valid_percent()
        .map_or("-".into(), |v| format!("{v:.1} %"));
    let mut second = vec![Span::raw(format!(
        " bytes/s {bps}  valid {valid}  rows {}  lines {}  CRC {}  T/O+NAK {}  sort {}",
        model.rows,
        model.shown_lines(),
        model.crc_errors,
        model.timeouts,
        ui.sort.label()
    ))];
    if !ui.filter.is_empty() {
        second.push(Span::styled(
            format!("  filter \"{}\"", ui.filter),
            Style::new().fg(Color::Cyan),
        ));
    }
    if let Some(e) = &ui.filter_error {
        second.push(Span::styled(
            format!("  filter refused: {e}"),
            Style::new().fg(Color::Red),
        ));
    }
    let text = vec![Text::from(first), Text::from(second)];
    frame.render_widget(Paragraph::new(text), area);
}

/// The columns of the lines, in order: heading, what may happen to it when the screen is
/// narrow, and its place in the order of columns given up (lowest first; 0: never).
const COLUMNS: [(&str, Fit, u8); 15] = [
    ("", Fit::Number, 0),
    ("ID", Fit::Number, 0),
    ("Device", Fit::Text(4), 9),
    ("Sensor #", Fit::Number, 8),
    ("Sensor", Fit::Text(4), 0),
    ("Part", Fit::Text(4), 0),
    ("Value", Fit::Value, 0),
    ("Unit", Fit::Number, 7),
    ("Rate/s", Fit::Number, 5),
    ("Age", Fit::Number, 4),
    ("Min", Fit::Number, 6),
    ("Max", Fit::Number, 6),
    ("Frames", Fit::Number, 1),
    ("CRC", Fit::Number, 3),
    ("T/O", Fit::Number, 2),
];
const VALUE: usize = 6;

/// How a column fits a narrow screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fit {
    /// Numbers and codes: never cut; the column is given up whole when there is no room.
    Number,
    /// Names: cut with `…` down to this width, after the other columns were given up.
    Text(usize),
    /// The Value column: numbers never cut, Data texts cut with `…`.
    Value,
}

/// The width of each column for cells needing `need` (heading included) on a screen `width`
/// wide, one blank between columns: `None` for a column given up. Names shrink first (down
/// to their least width), then whole columns are given up in the order of [`COLUMNS`]; a
/// column of numbers is never narrower than its widest number. `value_min`: the widest number
/// in the Value column.
fn widths(need: &[usize], value_min: usize, width: usize) -> Vec<Option<usize>> {
    let mut w: Vec<Option<usize>> = need.iter().map(|&n| Some(n)).collect();
    let total = |w: &[Option<usize>]| -> usize {
        let cols: Vec<usize> = w.iter().flatten().copied().collect();
        cols.iter().sum::<usize>() + cols.len().saturating_sub(1)
    };
    let least = |i: usize| match COLUMNS[i].1 {
        Fit::Number => need[i],
        Fit::Text(min) => need[i].min(min),
        Fit::Value => need[i].min(value_min.max(8)),
    };
    // Names shrink, longest first, one column at a time.
    while total(&w) > width {
        let widest = (0..w.len())
            .filter(|&i| w[i].is_some_and(|x| x > least(i)))
            .filter(|&i| COLUMNS[i].1 != Fit::Value)
            .max_by_key(|&i| w[i]);
        match widest {
            Some(i) => w[i] = w[i].map(|x| x - 1),
            None => break,
        }
    }
    // Then columns are given up, the least useful first.
    let mut order: Vec<usize> = (0..w.len()).filter(|&i| COLUMNS[i].2 > 0).collect();
    order.sort_by_key(|&i| COLUMNS[i].2);
    for i in order {
        if total(&w) <= width {
            break;
        }
        w[i] = None;
    }
    // Last, a Data text in the Value column.
    if let Some(v) = w[VALUE] {
        let over = total(&w).saturating_sub(width);
        w[VALUE] = Some(v.saturating_sub(over).max(least(VALUE)));
    }
    w
}

/// `text` in `width` columns: as it is, or cut with `…` at the end.
fn fit_text(text: &str, width: usize) -> String {
    if text.chars().count() <= width {
        return text.to_owned();
    }
    let mut s: String = text.chars().take(width.saturating_sub(1)).collect();
    s.push('…');
    s
}

fn lines(frame: &mut Frame<'_>, area: Rect, model: &Model, ui: &mut Ui, now: u64) {
    let order = model.order(ui.sort, ui.compiled.as_ref(), now);
    ui.shown = order
        .iter()
        .map(|&i| model.lines()[i].key.clone())
        .collect();
    if ui.selected.as_ref().is_some_and(|k| !ui.shown.contains(k)) {
        ui.selected = None;
    }
    let room = area.height.saturating_sub(1) as usize;
    let more = model.overflow_rows > 0 || order.len() > room;
    let room = if more { room.saturating_sub(1) } else { room };
    // Keep the cursor on screen.
    let at = ui
        .selected
        .as_ref()
        .and_then(|k| ui.shown.iter().position(|s| s == k))
        .unwrap_or(0);
    let skip = (at + 1).saturating_sub(room);
    let shown: Vec<&Track> = order
        .iter()
        .skip(skip)
        .take(room)
        .map(|&i| &model.lines()[i])
        .collect();
    let cells: Vec<[String; 15]> = shown.iter().map(|l| line_cells(l, now)).collect();
    if ui.needs.len() != COLUMNS.len() {
        ui.needs = COLUMNS.iter().map(|c| c.0.chars().count()).collect();
        // The Part column only once a line's number has a name of its own.
        ui.needs[5] = 0;
    }
    for (c, l) in cells.iter().zip(&shown) {
        for (n, text) in ui.needs.iter_mut().zip(c) {
            if !text.is_empty() {
                *n = (*n).max(text.chars().count()).max(1);
            }
        }
        if l.numeric {
            ui.value_min = ui.value_min.max(c[VALUE].chars().count());
        }
    }
    if ui.needs[5] > 0 {
        ui.needs[5] = ui.needs[5].max(COLUMNS[5].0.len());
    }
    let mut w = widths(&ui.needs, ui.value_min, area.width as usize);
    if ui.needs[5] == 0 {
        w[5] = None;
    }
    let kept: Vec<usize> = (0..COLUMNS.len()).filter(|&i| w[i].is_some()).collect();
    let rows: Vec<TableRow<'_>> = cells
        .into_iter()
        .zip(&shown)
        .map(|(c, l)| line_row(l, c, &w, ui.selected.as_ref(), now))
        .collect();
    if more {
        let hidden = order.len().saturating_sub(room);
        let mut text = format!("  … {hidden} more lines (↑↓ to scroll, f to filter)");
        if model.overflow_rows > 0 {
            text.push_str(&format!(
                " ({} rows of further keys not shown: more than {} lines)",
                model.overflow_rows,
                super::model::MAX_LINES
            ));
        }
        let y = area.y + 1 + room as u16;
        if y < area.y + area.height {
            let at = Rect::new(area.x, y, area.width, 1);
            frame.render_widget(Paragraph::new(text).style(dim()), at);
        }
    }
    let header = TableRow::new(
        kept.iter()
            .map(|&i| fit_text(COLUMNS[i].0, w[i].unwrap_or(0))),
    )
    .style(
        Style::new()
            .add_modifier(Modifier::BOLD)
            .add_modifier(Modifier::UNDERLINED),
    );
    let constraints: Vec<Constraint> = kept
        .iter()
        .map(|&i| Constraint::Length(w[i].unwrap_or(0) as u16))
        .collect();
    let table = Table::new(rows, constraints)
        .header(header)
        .column_spacing(1)
        .flex(ratatui::layout::Flex::Start);
    let mut table_area = area;
    table_area.height = (room as u16 + 1).min(area.height);
    frame.render_widget(table, table_area);
}

fn dim() -> Style {
    Style::new().add_modifier(Modifier::DIM)
}

/// The texts of a line's cells, in the order of [`COLUMNS`].
fn line_cells(l: &Track, now: u64) -> [String; 15] {
    let count = |n: u64| if n == 0 { String::new() } else { n.to_string() };
    [
        (if l.marked { "*" } else { "" }).to_owned(),
        l.key.id.map_or(String::new(), |i| i.to_string()),
        on_port(&l.key.port, &l.device).into_owned(),
        l.key.sensor_no.clone(),
        l.key.sensor.clone(),
        l.part_label().to_owned(),
        l.value.clone(),
        l.unit.clone(),
        l.rate(now).map_or("-".into(), |r| format!("{r:.1}")),
        age(l.age(now)),
        l.min.as_ref().map_or(String::new(), |n| n.text.clone()),
        l.max.as_ref().map_or(String::new(), |n| n.text.clone()),
        l.frames.to_string(),
        count(l.crc_errors),
        count(l.timeouts),
    ]
}

/// A device with its port (several sources): the port's file name first, `ttyUSB1: FAS-40S`.
fn on_port<'a>(port: &str, device: &'a str) -> std::borrow::Cow<'a, str> {
    if port.is_empty() {
        return device.into();
    }
    let short = std::path::Path::new(port)
        .file_name()
        .map_or(port.into(), |n| n.to_string_lossy());
    format!("{short}: {device}").into()
}

fn line_row<'a>(
    l: &Track,
    cells: [String; 15],
    w: &[Option<usize>],
    selected: Option<&Key>,
    now: u64,
) -> TableRow<'a> {
    let red = |i: usize, c: Cell<'a>| {
        if (i == 13 && l.crc_errors > 0) || (i == 14 && l.timeouts > 0) {
            c.style(Style::new().fg(Color::Red))
        } else {
            c
        }
    };
    let mut out = Vec::new();
    for (i, text) in cells.into_iter().enumerate() {
        let Some(width) = w[i] else { continue };
        let cell = Cell::from(fit_text(&text, width));
        let cell = if i == VALUE && l.changed(now) {
            cell.style(
                Style::new()
                    .fg(Color::Yellow)
                    .add_modifier(Modifier::BOLD | Modifier::REVERSED),
            )
        } else {
            red(i, cell)
        };
        out.push(cell);
    }
    let mut style = Style::new();
    if l.stale(now) {
        style = style.add_modifier(Modifier::DIM);
    }
    if l.marked {
        style = style.add_modifier(Modifier::BOLD).fg(Color::Cyan);
    }
    if selected == Some(&l.key) {
        style = style.add_modifier(Modifier::REVERSED);
    }
    TableRow::new(out).style(style)
}

fn errors(frame: &mut Frame<'_>, area: Rect, model: &Model, ui: &Ui, n: usize) {
    let mut text = vec![Text::styled(
        " last errors and events",
        Style::new().add_modifier(Modifier::BOLD),
    )];
    // busnoop's own messages first (a hint matters more than the tenth bad CRC), then rows.
    let from_messages: Vec<Text<'_>> = ui
        .messages
        .iter()
        .rev()
        .take(n)
        .rev()
        .map(|m| {
            Text::styled(
                fit_text(&format!(" {m}"), area.width as usize),
                Style::new().fg(Color::Cyan),
            )
        })
        .collect();
    let rows = n - from_messages.len();
    let skip = model.events.len().saturating_sub(rows);
    for e in model.events.iter().skip(skip) {
        let style = match e.class {
            Class::Error => Style::new().fg(Color::Red),
            Class::Warning => Style::new().fg(Color::Yellow),
            Class::Info => Style::new().fg(Color::Cyan),
            _ => Style::new(),
        };
        let id = e.id.map_or(String::new(), |i| i.to_string());
        let line = format!(
            " {:>9} {:<10} {:>3} {:<14} {}",
            e.micros.map_or(String::new(), |m| format!("{}", m / 1000)),
            e.kind,
            id,
            on_port(&e.port, &e.device),
            e.text
        );
        text.push(Text::styled(fit_text(&line, area.width as usize), style));
    }
    text.extend(from_messages);
    frame.render_widget(Paragraph::new(text), area);
}

fn footer(frame: &mut Frame<'_>, area: Rect, model: &Model, ui: &Ui) {
    let key = Style::new().add_modifier(Modifier::BOLD).fg(Color::Cyan);
    let text = match &ui.editing {
        Some(f) => Text::from(vec![
            Span::styled(" filter: ", key),
            Span::raw(format!("{f}_")),
            Span::raw(
                "   (id=1 sensor=RSSI type=Data device=… errors, or a name; Enter apply, Esc clear)",
            ),
        ]),
        None => {
            let mut spans = Vec::new();
            for (k, what) in [
                ("q", "quit"),
                ("p", if ui.paused { "resume" } else { "pause" }),
                ("s", "sort"),
                ("f", "filter"),
                ("space", "mark"),
                ("↑↓", "move"),
            ] {
                spans.push(Span::styled(format!(" {k}"), key));
                spans.push(Span::raw(format!(" {what} ")));
            }
            if model.lines().is_empty() && model.rows > 0 {
                spans.push(Span::raw(
                    "  (no sensor rows yet: polls and keep-alives only)",
                ));
            }
            Text::from(spans)
        }
    };
    frame.render_widget(Paragraph::new(text), area);
}

/// A duration as `0.3s`, `12s`, `5m`, `2h`.
pub fn age(micros: u64) -> String {
    let s = micros as f64 / 1e6;
    if s < 10.0 {
        format!("{s:.1}s")
    } else if s < 600.0 {
        format!("{s:.0}s")
    } else if s < 36_000.0 {
        format!("{:.0}m", s / 60.0)
    } else {
        format!("{:.0}h", s / 3600.0)
    }
}

/// Elapsed time as `hh:mm:ss`.
pub fn clock(micros: u64) -> String {
    let s = micros / 1_000_000;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// A number without needless decimals (`12`, `11.93`, `0.001`).
pub fn num(n: f64) -> String {
    if n.fract() == 0.0 && n.abs() < 1e15 {
        return format!("{n:.0}");
    }
    let s = format!("{n:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::row::{Part, Parts};
    use ratatui::Terminal;
    use ratatui::backend::TestBackend;

    /// The screen as text, one string per line, trailing blanks cut.
    fn screen(t: &Terminal<TestBackend>) -> String {
        let buf = t.backend().buffer();
        let mut out = String::new();
        for y in 0..buf.area.height {
            let mut line = String::new();
            for x in 0..buf.area.width {
                line.push_str(buf[(x, y)].symbol());
            }
            out.push_str(line.trim_end());
            out.push('\n');
        }
        out
    }

    /// A fixture through a decoder into a model, each row at its own time, with its numbers.
    pub(crate) fn model_of(mut d: Box<dyn crate::protocol::Decoder>, fixture: &str) -> Model {
        let path = format!("{}/fixtures/{fixture}", env!("CARGO_MANIFEST_DIR"));
        let bytes = std::fs::read(path).unwrap();
        let mut rows = crate::row::Collected::default();
        if fixture.ends_with(".log") {
            // An EdgeTX log: each line's bytes at its time.
            let mut start = None;
            for line in bytes.split(|&b| b == b'\n') {
                if let Some(l) = crate::source::edgetx::parse_line(line) {
                    let t0 = *start.get_or_insert(l.time);
                    let us = (l.time - t0).num_microseconds().unwrap() as u64;
                    d.push(&l.bytes, Some(us), &mut rows).unwrap();
                }
            }
        } else {
            d.push(&bytes, None, &mut rows).unwrap();
        }
        d.finish(&mut rows).unwrap();
        let mut m = Model::new(d.columns());
        for o in &rows.rows {
            let extra: Vec<&str> = o.extra.iter().map(String::as_str).collect();
            let parts: Vec<Part<'_>> = o
                .parts
                .iter()
                .map(|(name, unit, text)| Part {
                    name,
                    unit,
                    text,
                    value: text.parse().unwrap(),
                })
                .collect();
            let row = crate::row::Row {
                stamp: 0,
                micros: o.micros,
                id: o.id,
                device: &o.device,
                kind: &o.kind,
                class: o.class,
                sensor_no: &o.sensor_no,
                sensor: &o.sensor,
                data: &o.data,
                extra: &extra,
                parts: Parts::List(&parts),
                raw: &o.raw,
            };
            m.row(&row, o.micros.unwrap());
        }
        m
    }

    fn info(protocol: &'static crate::protocol::Protocol, source: &str) -> Info {
        Info {
            protocol: protocol.name.into(),
            source: source.into(),
            baud: None,
            speed: Some(1.0),
            live: false,
            vocab: Some(protocol.vocab),
            names: Names::default(),
            sensors: Vec::new(),
        }
    }

    fn render(m: &Model, ui: &mut Ui, info: &Info, now: u64, w: u16, h: u16) -> String {
        let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
        t.draw(|f| draw(f, m, ui, info, now)).unwrap();
        screen(&t)
    }

    fn edgetx() -> Model {
        model_of(
            crate::sport::decoder(),
            "edgetx-MODELE24-2014-07-11-sport.log",
        )
    }

    fn sbus() -> Model {
        model_of(
            Box::new(crate::protocol::PcapBytes::new(
                crate::sbus::EtherDecoder::new(&Default::default()),
            )),
            "sbus-digimat.pcap",
        )
    }

    fn sab() -> Model {
        model_of(crate::sab::decoder(Default::default()), "sab2-session.bin")
    }

    #[test]
    fn snapshot_of_the_sport_sample() {
        let m = model_of(crate::sport::decoder(), "sport-sample.bin");
        let info = info(&crate::sport::PROTOCOL, "fixtures/sport-sample.bin");
        let got = render(&m, &mut Ui::default(), &info, 1_000_000, 120, 12);
        let expected = "
 busnoop  S.Port fixtures/sport-sample.bin  replay ×1  elapsed 00:00:01
 bytes/s 220  valid 100.0 %  rows 30  lines 4  CRC 0  T/O+NAK 0  sort ID
 ID Device  Sensor # Sensor Part Value Unit Rate/s Age  Min   Max   Frames CRC T/O
 0  Vario   0x0100   Alt         65.43 m    -      0.7s 65.43 65.43 1
 0  Vario   0x0110   Vario  VSpd 0.00  m/s  -      0.8s 0.00  0.00  1
 2  FAS-40S 0x0200   Amps   Curr 0.0   A    -      0.9s 0.0   0.0   1
 2  FAS-40S 0x0210   Volts  VFAS 0.00  V    -      0.9s 0.00  0.00  1




 q quit  p pause  s sort  f filter  space mark  ↑↓ move
";
        assert_eq!(got, expected[1..], "\n{got}");
    }

    /// On any width, the numbers on the screen are whole: every shown line's ID, Sensor #,
    /// value, minimum and maximum stand in its screen line as they are; a name that had to be
    /// cut ends in `…`. They used to be cut without a mark: SAB's maximum 3735928559 as
    /// 373592855, at 80 columns `R0=3054198` and a minimum of 30541, the app IDs 0xF101,
    /// 0xF104 and 0xF105 all as `0xF1`, the device 127.0.0.1:5050 as `127.0`.
    #[test]
    fn numbers_are_never_cut() {
        let cases = [
            (edgetx(), &crate::sport::PROTOCOL, "edgetx.log"),
            (sbus(), &crate::sbus::PROTOCOL, "sbus-digimat.pcap"),
            (sab(), &crate::sab::PROTOCOL, "sab2-session.bin"),
        ];
        let mut checked = 0;
        for (m, protocol, name) in &cases {
            for width in [60u16, 80, 100, 160] {
                let mut ui = Ui::default();
                let now = m.last.unwrap() + 1_000_000;
                let text = render(m, &mut ui, &info(protocol, name), now, width, 40);
                let screen: Vec<&str> = text.lines().collect();
                for (k, key) in ui.shown.iter().enumerate() {
                    let Some(line) = screen.get(3 + k) else { break };
                    if line.contains("more lines") || line.is_empty() {
                        break;
                    }
                    let l = m.lines().iter().find(|l| &l.key == key).unwrap();
                    let words: Vec<&str> = line.split_whitespace().collect();
                    let mut numbers = vec![l.key.id.map(|i| i.to_string()).unwrap_or_default()];
                    numbers.push(l.key.sensor_no.clone());
                    if l.numeric {
                        numbers.push(l.value.clone());
                    }
                    for n in [&l.min, &l.max].into_iter().flatten() {
                        numbers.push(n.text.clone());
                    }
                    for n in numbers.iter().filter(|n| !n.is_empty()) {
                        assert!(
                            words.contains(&n.as_str()),
                            "{name} at {width} columns: {n} not whole in {line:?}\n{text}"
                        );
                        checked += 1;
                    }
                    // A cut name says so.
                    for name in [&l.device, &l.key.sensor] {
                        let first = name.split_whitespace().next().unwrap_or("");
                        if !name.is_empty() && !line.contains(name.as_str()) {
                            assert!(line.contains('…'), "{name} cut without a mark: {line:?}");
                            assert!(!words.contains(&first) || first.len() < name.len());
                        }
                    }
                    assert!(line.chars().count() <= width as usize);
                }
            }
        }
        assert!(checked > 500, "{checked}");
    }

    #[test]
    fn snapshot_of_sbus_with_a_nak_sorted_by_rate_and_filtered() {
        let m = sbus();
        let mut info = info(&crate::sbus::PROTOCOL, "fixtures/sbus-digimat.pcap");
        info.speed = None;
        let mut ui = Ui::default();
        let got = render(&m, &mut ui, &info, m.last.unwrap() + 2_000_000, 120, 24);
        let expected = "
 busnoop  S-Bus fixtures/sbus-digimat.pcap  replay, full speed  elapsed 00:00:05
 bytes/s 153  valid 100.0 %  rows 50  lines 44  CRC 0  T/O+NAK 1  sort ID
 ID Device         Sensor # Sensor                Part Value             Unit Rate/s Age  Min  Max  Frames CRC T/O
 10 127.0.0.1:5050          Read DBX                   1F 00 06 00 00 00      0.0    5.2s           1          1
 10 127.0.0.1:5050          Read PCD status (own)      R (run)                0.0    5.2s           2
 10 127.0.0.1:5050 C0       Read counter(s)       C0   4321                   0.5    2.0s 4321 4321 2
 10 127.0.0.1:5050 C0       Read counter(s)       C1   0                      0.5    2.0s 0    0    2
 10 127.0.0.1:5050 C0       Read counter(s)       C2   0                      0.5    2.0s 0    0    2
 10 127.0.0.1:5050 C0       Read counter(s)       C3   0                      0.5    2.0s 0    0    2
 10 127.0.0.1:5050 C0       Read counter(s)       C4   0                      0.5    2.0s 0    0    2
 10 127.0.0.1:5050 C0       Read counter(s)       C5   99                     0.5    2.0s 99   99   2
 10 127.0.0.1:5050 C0       Write counter(s)      C0   4321                   -      4.1s 4321 4321 1
 10 127.0.0.1:5050 C5       Read counter(s)       C5   99                     -      4.1s 99   99   1
 10 127.0.0.1:5050 F0       Read flag(s)          F0   1                      -      4.2s 1    1    1
 10 127.0.0.1:5050 F1       Read flag(s)          F1   0                      -      4.2s 0    0    1
 10 127.0.0.1:5050 F1       Read flag(s)          F2   0                      -      4.2s 0    0    1
 10 127.0.0.1:5050 F1       Read flag(s)          F3   1                      -      4.2s 1    1    1
 10 127.0.0.1:5050 F1       Read flag(s)          F4   0                      -      4.2s 0    0    1
 10 127.0.0.1:5050 F1       Read flag(s)          F5   0                      -      4.2s 0    0    1
 10 127.0.0.1:5050 F1       Read flag(s)          F6   1                      -      4.2s 1    1    1
  … 27 more lines (↑↓ to scroll, f to filter)
 last errors and events
        71 NAK         10 127.0.0.1:5050 Read DBX NAK, no reason specified (0x0001)
 q quit  p pause  s sort  f filter  space mark  ↑↓ move
";
        assert_eq!(got, expected[1..], "\n{got}");
        ui.sort = Sort::Rate;
        ui.apply_filter("sensor=R0,R1".into(), &info);
        ui.paused = true;
        let got = render(&m, &mut ui, &info, m.last.unwrap() + 2_000_000, 120, 24);
        let expected = "
 busnoop  S-Bus fixtures/sbus-digimat.pcap  replay, full speed  elapsed 00:00:05  PAUSED
 bytes/s 153  valid 100.0 %  rows 50  lines 44  CRC 0  T/O+NAK 1  sort rate  filter \"sensor=R0,R1\"
 ID Device         Sensor # Sensor            Part Value       Unit Rate/s Age  Min         Max         Frames CRC T/O
 10 127.0.0.1:5050 R1       Read register(s)  R1   181              0.5    2.0s 181         181         2
 10 127.0.0.1:5050 R1       Read register(s)  R2   -1245334075      0.5    2.0s -1245334075 -1245334075 2
 10 127.0.0.1:5050 R1       Read register(s)  R3   42               0.5    2.0s 42          42          2
 10 127.0.0.1:5050 R0       Read register(s)  R0   305419896        -      4.2s 305419896   305419896   1
 10 127.0.0.1:5050 R0       Read register(s)  R1   100              -      4.2s 100         100         1
 10 127.0.0.1:5050 R0       Read register(s)  R2   -1245334075      -      4.2s -1245334075 -1245334075 1
 10 127.0.0.1:5050 R0       Read register(s)  R3   42               -      4.2s 42          42          1
 10 127.0.0.1:5050 R1       Write register(s) R1   181              -      4.1s 181         181         1










 last errors and events
        71 NAK         10 127.0.0.1:5050 Read DBX NAK, no reason specified (0x0001)
 q quit  p resume  s sort  f filter  space mark  ↑↓ move
";
        assert_eq!(got, expected[1..], "\n{got}");
        // A filter that cannot match is refused with the reason; the one before stays.
        ui.apply_filter("id=999".into(), &info);
        assert_eq!(ui.filter, "sensor=R0,R1");
        assert!(ui.filter_error.as_ref().unwrap().contains("outside"));
    }

    /// docs/top.md's picture of `--top` is what the program draws (rendered here into a buffer of
    /// the same size and compared), so the two never drift apart.
    #[test]
    fn docs_top_shows_what_top_draws() {
        let readme =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/top.md")).unwrap();
        let start = readme
            .find("<!-- top-screenshot -->")
            .expect("docs/top.md's --top picture");
        let block = &readme[start..];
        let from = block.find("```text\n").unwrap() + "```text\n".len();
        let to = block[from..].find("```").unwrap();
        let shown = &block[from..from + to];
        let m = edgetx();
        let info = Info {
            speed: Some(1.0),
            ..info(
                &crate::sport::PROTOCOL,
                "fixtures/edgetx-MODELE24-2014-07-11-sport.log",
            )
        };
        let mut ui = Ui {
            ended: true,
            ..Ui::default()
        };
        let got = render(&m, &mut ui, &info, m.last.unwrap(), 100, 14);
        assert_eq!(shown, got, "docs/top.md's --top picture:\n{got}");
    }
}
