//! Drawing the live view: header, one line per device/sensor, the last error rows, key help.

use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line as Text, Span};
use ratatui::widgets::{Cell, Paragraph, Row as TableRow, Table};

use super::model::{Key, Model, Sort, Track};
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
}

/// The user's choices and the view's own state.
#[derive(Clone, Debug)]
pub struct Ui {
    pub sort: Sort,
    /// Applied filter (an ID/name substring).
    pub filter: String,
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
}

impl Default for Ui {
    fn default() -> Ui {
        Ui {
            sort: Sort::Id,
            filter: String::new(),
            editing: None,
            paused: false,
            selected: None,
            shown: Vec::new(),
            ended: false,
            messages: Vec::new(),
        }
    }
}

impl Ui {
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
        Span::raw(info.source.clone()),
    ];
    if let Some(b) = info.baud {
        first.push(Span::raw(format!("  {b} baud")));
    }
    match (info.live, info.speed) {
        (true, _) => first.push(Span::raw("  live")),
        (false, Some(s)) => first.push(Span::raw(format!("  replay ×{}", num(s)))),
        (false, None) => first.push(Span::raw("  replay, full speed")),
    }
    let elapsed = model.first.map_or(0, |f| now.saturating_sub(f));
    first.push(Span::raw(format!("  elapsed {}", clock(elapsed))));
    if ui.paused {
        first.push(Span::styled("  PAUSED", bold.fg(Color::Yellow)));
    }
    if ui.ended {
        first.push(Span::styled("  END OF INPUT", bold.fg(Color::Yellow)));
    }
    let bps = model
        .bytes_per_second(now)
        .map_or("-".into(), |b| format!("{b:.0}"));
    let valid = model
        .valid_percent()
        .map_or("-".into(), |v| format!("{v:.1} %"));
    let mut second = vec![Span::raw(format!(
        " bytes/s {bps}  valid {valid}  rows {}  lines {}  CRC {}  T/O+NAK {}  sort {}",
        model.rows,
        model.lines().len(),
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
    let text = vec![Text::from(first), Text::from(second)];
    frame.render_widget(Paragraph::new(text), area);
}

const COLUMNS: [&str; 14] = [
    "", "ID", "Device", "Sensor #", "Sensor", "Value", "Unit", "Rate/s", "Age", "Min", "Max",
    "Frames", "CRC", "T/O",
];

fn lines(frame: &mut Frame<'_>, area: Rect, model: &Model, ui: &mut Ui, now: u64) {
    let order = model.order(ui.sort, &ui.filter, now);
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
    let rows: Vec<TableRow<'_>> = order
        .iter()
        .skip(skip)
        .take(room)
        .map(|&i| line_row(&model.lines()[i], ui.selected.as_ref(), now))
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
    let header = TableRow::new(COLUMNS).style(
        Style::new()
            .add_modifier(Modifier::BOLD)
            .add_modifier(Modifier::UNDERLINED),
    );
    let widths = [
        Constraint::Length(1),
        Constraint::Length(4),
        Constraint::Length(14),
        Constraint::Length(8),
        Constraint::Length(16),
        Constraint::Min(10),
        Constraint::Length(5),
        Constraint::Length(6),
        Constraint::Length(5),
        Constraint::Length(9),
        Constraint::Length(9),
        Constraint::Length(7),
        Constraint::Length(4),
        Constraint::Length(4),
    ];
    let table = Table::new(rows, widths).header(header).column_spacing(1);
    let mut table_area = area;
    table_area.height = (room as u16 + 1).min(area.height);
    frame.render_widget(table, table_area);
}

fn dim() -> Style {
    Style::new().add_modifier(Modifier::DIM)
}

fn line_row<'a>(l: &'a Track, selected: Option<&Key>, now: u64) -> TableRow<'a> {
    let count = |n: u64| {
        let c = Cell::from(if n == 0 { String::new() } else { n.to_string() });
        if n > 0 {
            c.style(Style::new().fg(Color::Red))
        } else {
            c
        }
    };
    let value = Cell::from(l.value.as_str());
    let value = if l.changed(now) {
        value.style(
            Style::new()
                .fg(Color::Yellow)
                .add_modifier(Modifier::BOLD | Modifier::REVERSED),
        )
    } else {
        value
    };
    let cells = vec![
        Cell::from(if l.marked { "*" } else { "" }),
        Cell::from(l.key.id.map_or(String::new(), |i| i.to_string())),
        Cell::from(l.device.as_str()),
        Cell::from(l.key.sensor_no.as_str()),
        Cell::from(l.key.sensor.as_str()),
        value,
        Cell::from(l.unit.as_str()),
        Cell::from(l.rate(now).map_or("-".into(), |r| format!("{r:.1}"))),
        Cell::from(age(l.age(now))),
        Cell::from(l.min.map_or(String::new(), num)),
        Cell::from(l.max.map_or(String::new(), num)),
        Cell::from(l.frames.to_string()),
        count(l.crc_errors),
        count(l.timeouts),
    ];
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
    TableRow::new(cells).style(style)
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
        .map(|m| Text::styled(format!(" {m}"), Style::new().fg(Color::Cyan)))
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
        text.push(Text::styled(
            format!(
                " {:>9} {:<10} {:>3} {:<14} {}",
                e.micros.map_or(String::new(), |m| format!("{}", m / 1000)),
                e.kind,
                id,
                e.device,
                e.text
            ),
            style,
        ));
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
            Span::raw("   (ID or name; Enter apply, Esc clear)"),
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

    /// A fixture through a decoder into a model, each row at its own time.
    fn model_of(mut d: Box<dyn crate::protocol::Decoder>, fixture: &str) -> Model {
        let path = format!("{}/fixtures/{fixture}", env!("CARGO_MANIFEST_DIR"));
        let bytes = std::fs::read(path).unwrap();
        let mut rows = crate::row::Collected::default();
        d.push(&bytes, None, &mut rows).unwrap();
        d.finish(&mut rows).unwrap();
        let mut m = Model::new(d.columns());
        for o in &rows.rows {
            let extra: Vec<&str> = o.extra.iter().map(String::as_str).collect();
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
                parts: crate::row::Parts::NONE,
                raw: &o.raw,
            };
            m.row(&row, o.micros.unwrap());
        }
        m
    }

    fn info() -> Info {
        Info {
            protocol: "S.Port".into(),
            source: "fixtures/sport-sample.bin".into(),
            baud: None,
            speed: Some(1.0),
            live: false,
        }
    }

    fn render(m: &Model, ui: &mut Ui, info: &Info, now: u64, w: u16, h: u16) -> String {
        let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
        t.draw(|f| draw(f, m, ui, info, now)).unwrap();
        screen(&t)
    }

    #[test]
    fn snapshot_of_the_sport_sample() {
        let m = model_of(crate::sport::decoder(), "sport-sample.bin");
        let got = render(&m, &mut Ui::default(), &info(), 1_000_000, 120, 12);
        let expected = "
 busnoop  S.Port fixtures/sport-sample.bin  replay ×1  elapsed 00:00:01
 bytes/s 220  valid 100.0 %  rows 30  lines 4  CRC 0  T/O+NAK 0  sort ID
  ID   Device         Sensor # Sensor           Value           Unit  Rate/s Age   Min       Max       Frames  CRC  T/O
  0    Vario          0x0100   Alt              65.43           m     -      0.7s  65.43     65.43     1
  0    Vario          0x0110   Vario            0.00            m/s   -      0.8s  0         0         1
  2    FAS-40S        0x0200   Amps             0.0             A     -      0.9s  0         0         1
  2    FAS-40S        0x0210   Volts            0.00            V     -      0.9s  0         0         1




 q quit  p pause  s sort  f filter  space mark  ↑↓ move
";
        assert_eq!(got, expected[1..], "\n{got}");
    }

    #[test]
    fn snapshot_of_sbus_with_a_nak_sorted_by_rate_and_filtered() {
        let m = model_of(
            Box::new(crate::protocol::PcapBytes::new(
                crate::sbus::EtherDecoder::new(&Default::default()),
            )),
            "sbus-digimat.pcap",
        );
        let info = Info {
            protocol: "S-Bus".into(),
            source: "fixtures/sbus-digimat.pcap".into(),
            baud: None,
            speed: None,
            live: false,
        };
        let mut ui = Ui::default();
        let got = render(&m, &mut ui, &info, m.last.unwrap() + 2_000_000, 120, 24);
        let expected = "
 busnoop  S-Bus fixtures/sbus-digimat.pcap  replay, full speed  elapsed 00:00:05
 bytes/s 153  valid 100.0 %  rows 50  lines 21  CRC 0  T/O+NAK 1  sort ID
  ID   Device         Sensor # Sensor           Value           Unit  Rate/s Age   Min       Max       Frames  CRC  T/O
  10   127.0.0.1:5050          Read DBX         1F 00 06 00 00        0.0    5.2s  0         0         2            1
  10   127.0.0.1:5050          Read PCD status  R (run)               0.0    5.2s                      2
  10   127.0.0.1:5050 C0       Read counter(s)  C0=4321 C1=0 C2       1.0    2.0s  4321      4321      4
  10   127.0.0.1:5050 C0       Write counter(s) C0=4321               0.5    4.1s  4321      4321      2
  10   127.0.0.1:5050 C5       Read counter(s)  C5=99                 0.5    4.1s  99        99        2
  10   127.0.0.1:5050 F0       Read flag(s)     F0=1                  0.5    4.2s  1         1         2
  10   127.0.0.1:5050 F1       Read flag(s)     F1=0 F2=0 F3=1        0.5    4.2s  0         0         2
  10   127.0.0.1:5050 F3       Read flag(s)     F3=0 F4=0 F5=0        0.5    4.1s  0         0         2
  10   127.0.0.1:5050 F3       Write flag(s)    F3=0                  0.5    4.1s  0         0         2
  10   127.0.0.1:5050 F9       Read flag(s)     F9=1                  1.0    2.0s  1         1         2
  10   127.0.0.1:5050 F9       Write flag(s)    F9=1                  0.5    4.1s  1         1         2
  10   127.0.0.1:5050 I1       Read input(s)    I1=0                  0.5    4.2s  0         0         2
  10   127.0.0.1:5050 O1       Read output(s)   O1=1 O2=1             1.0    2.0s  1         1         4
  10   127.0.0.1:5050 O1       Write output(s)  O1=1                  0.5    4.1s  1         1         2
  10   127.0.0.1:5050 O2       Read output(s)   O2=1                  0.5    4.2s  1         1         2
  10   127.0.0.1:5050 R0       Read register(s) R0=305419896 R1       0.5    4.2s  305419896 305419896 2
  10   127.0.0.1:5050 R1       Read register(s) R1=181 R2=-1245       1.0    2.0s  181       181       4
  … 4 more lines (↑↓ to scroll, f to filter)
 last errors and events
        71 NAK         10 127.0.0.1:5050 Read DBX NAK, no reason specified (0x0001)
 q quit  p pause  s sort  f filter  space mark  ↑↓ move
";
        assert_eq!(got, expected[1..], "\n{got}");
        ui.sort = Sort::Rate;
        ui.filter = "regis".into();
        ui.paused = true;
        let got = render(&m, &mut ui, &info, m.last.unwrap() + 2_000_000, 120, 24);
        let expected = "
 busnoop  S-Bus fixtures/sbus-digimat.pcap  replay, full speed  elapsed 00:00:05  PAUSED
 bytes/s 153  valid 100.0 %  rows 50  lines 21  CRC 0  T/O+NAK 1  sort rate  filter \"regis\"
  ID   Device         Sensor # Sensor           Value           Unit  Rate/s Age   Min       Max       Frames  CRC  T/O
  10   127.0.0.1:5050 R1       Read register(s) R1=181 R2=-1245       1.0    2.0s  181       181       4
  10   127.0.0.1:5050 R1       Write register(s R1=181                0.5    4.1s  181       181       2
  10   127.0.0.1:5050 R0       Read register(s) R0=305419896 R1       0.5    4.2s  305419896 305419896 2















 last errors and events
        71 NAK         10 127.0.0.1:5050 Read DBX NAK, no reason specified (0x0001)
 q quit  p resume  s sort  f filter  space mark  ↑↓ move
";
        assert_eq!(got, expected[1..], "\n{got}");
    }
}
