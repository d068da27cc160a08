//! `--top`: a full-screen live view of the bus, one line per device and sensor, updating in
//! place (like `cansniffer` for CAN).
//!
//! The view is a [`Sink`] built on the table rows, so it works for every protocol: [`model`]
//! aggregates the rows (pure, tested with fixed times), [`view`] draws them with ratatui, and
//! [`Top`] runs the terminal inside the driver's loop: the driver flushes its sink after every
//! batch and on every idle tick (20 ms), which is when keys are read and the screen redrawn (at
//! most 10 times a second). The table (`-o FILE`) is written as without the view.

mod keys;
pub mod model;
mod term;
pub mod view;

use std::time::{Duration, Instant};

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

use crate::pace::Pacer;
use crate::row::{OutputError, Row, RowOut, RowResult};
use crate::sink::Sink;
use crate::sink::Table;
use model::Model;
use view::{Info, Ui};

/// The screen is redrawn at most this often (and at once after a key or a resize).
const FRAME: Duration = Duration::from_millis(100);
/// busnoop's own messages shown at the bottom.
const MESSAGES: usize = 3;

/// Why the view closed before the run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Closed {
    /// The terminal gave end of file or an error: gone without a SIGHUP (a dying supervisor
    /// pty, `nohup`).
    Gone,
    /// `q` in a replay with a table.
    Quit,
}

/// The live view as the driver's sink.
pub struct Top<'a> {
    model: Model,
    /// While paused on a live source: the model as it was, and its time.
    frozen: Option<(Model, u64)>,
    ui: Ui,
    info: Info,
    table: Option<&'a mut Table>,
    pacer: Option<Pacer>,
    /// `None` once the view is closed (its terminal gone, or `q` in a replay with `-o`): the
    /// rows go on into the table.
    screen: Option<term::Screen>,
    keys: keys::Keys,
    /// The newest row time and when it came, to run the clock between rows.
    latest: Option<(u64, Instant)>,
    floor: u64,
    start: Instant,
    last_draw: Option<Instant>,
    dirty: bool,
    quit: bool,
}

impl<'a> Top<'a> {
    /// Takes over the terminal. `table`: the table to write as well (`-o FILE`); `columns`: the
    /// decoder's extra columns.
    pub fn open(
        table: Option<&'a mut Table>,
        columns: &[&str],
        info: Info,
        pacer: Option<Pacer>,
    ) -> std::io::Result<Top<'a>> {
        let screen = Some(term::Screen::open()?);
        let keys = keys::Keys::new(term::input_fd());
        Ok(Top {
            model: Model::new(columns),
            frozen: None,
            ui: Ui::default(),
            info,
            table,
            pacer,
            screen,
            keys,
            latest: None,
            floor: 0,
            start: Instant::now(),
            last_draw: None,
            dirty: true,
            quit: false,
        })
    }

    /// Rows the view took in.
    pub fn rows(&self) -> u64 {
        self.model.rows
    }

    /// Capture time now: the newest row's time, run on by the wall clock at the replay speed
    /// (live: real time; paused, ended or as fast as possible: stopped).
    fn now(&mut self) -> u64 {
        let factor = if self.ui.ended || self.quit {
            0.0
        } else if self.info.live {
            1.0
        } else if self.ui.paused {
            0.0
        } else {
            self.pacer.as_ref().map_or(0.0, Pacer::speed)
        };
        let t = match self.latest {
            Some((m, at)) => m.saturating_add((at.elapsed().as_micros() as f64 * factor) as u64),
            None if self.info.live => self.start.elapsed().as_micros() as u64,
            None => 0,
        };
        self.floor = self.floor.max(t);
        self.floor
    }

    /// Reads the keys that came and redraws when due. `wait`: how long to wait for a key.
    fn tick(&mut self, wait: Duration) -> std::io::Result<()> {
        let Some(screen) = self.screen.as_mut() else {
            return Ok(());
        };
        if term::resumed() {
            // Continued after a stop (SIGTSTP): the terminal was put back for the shell.
            if screen.resume().is_err() {
                self.close_view(Closed::Gone);
                return Ok(());
            }
            self.dirty = true;
        }
        match self.keys.read(wait) {
            keys::Read::Keys(keys) => {
                for k in keys {
                    self.key(k);
                    if self.screen.is_none() {
                        return Ok(());
                    }
                }
            }
            keys::Read::Gone => {
                self.close_view(Closed::Gone);
                return Ok(());
            }
        }
        let due = self.last_draw.is_none_or(|t| t.elapsed() >= FRAME);
        if (self.dirty || due) && self.draw().is_err() {
            // A terminal that takes no more output is gone, as one that gives no more input.
            self.close_view(Closed::Gone);
        }
        Ok(())
    }

    fn draw(&mut self) -> std::io::Result<()> {
        let now = self.now();
        let Some(screen) = self.screen.as_mut() else {
            return Ok(());
        };
        screen.fit()?;
        self.ui.messages = screen.messages(MESSAGES);
        let (model, now) = match &self.frozen {
            Some((m, t)) => (m, *t),
            None => (&self.model, now),
        };
        let (ui, info) = (&mut self.ui, &self.info);
        screen
            .terminal
            .draw(|f| view::draw(f, model, ui, info, now))?;
        self.last_draw = Some(Instant::now());
        self.dirty = false;
        Ok(())
    }

    /// Closes the view: the terminal is put back (stderr too, with what was said meanwhile),
    /// and the rows go on into the table without pacing, nobody watching. Without a table
    /// there is nothing left to do: the run ends.
    fn close_view(&mut self, why: Closed) {
        let Some(screen) = self.screen.take() else {
            return;
        };
        drop(screen);
        self.stop_pacing();
        if why == Closed::Gone {
            // Its output goes nowhere now: a message written there would fail.
            term::detach_from_terminal();
        }
        match (&self.table, why) {
            (None, _) => self.quit = true,
            (Some(_), Closed::Quit) => eprintln!(
                "busnoop: q: the view is closed; the rest of the replay goes on into the table \
                 at full speed (Ctrl-C stops it)"
            ),
            (Some(_), Closed::Gone) => {}
        }
    }

    fn key(&mut self, k: KeyEvent) {
        if k.kind == KeyEventKind::Release {
            return;
        }
        self.dirty = true;
        if k.modifiers.contains(KeyModifiers::CONTROL)
            && let KeyCode::Char(c @ ('z' | 'Z' | '\\')) = k.code
        {
            // Ctrl-Z and Ctrl-\ as a shell gives them: the handlers put the terminal back.
            let sig = if c == '\\' {
                libc::SIGQUIT
            } else {
                libc::SIGTSTP
            };
            // SAFETY: raise runs the process's own handlers (term::install_stop_and_quit).
            unsafe { libc::raise(sig) };
            return;
        }
        if k.modifiers.contains(KeyModifiers::CONTROL)
            && matches!(k.code, KeyCode::Char('c') | KeyCode::Char('C'))
        {
            // Raw mode turns Ctrl-C into a key: make it the signal it would have been, once.
            if crate::signal::Stop::received().is_none() {
                // SAFETY: raise only runs the process's own handlers (signal-hook's flag).
                unsafe { libc::raise(libc::SIGINT) };
            }
            self.stop_pacing();
            return;
        }
        if let Some(edit) = &mut self.ui.editing {
            match k.code {
                KeyCode::Enter => {
                    let text = std::mem::take(edit);
                    self.ui.editing = None;
                    self.ui.apply_filter(text, &self.info);
                }
                KeyCode::Esc => {
                    self.ui.editing = None;
                    self.ui.apply_filter(String::new(), &self.info);
                }
                KeyCode::Backspace => {
                    edit.pop();
                }
                KeyCode::Char(c) if edit.chars().count() < 120 => edit.push(c),
                _ => {}
            }
            return;
        }
        match k.code {
            KeyCode::Char('q') | KeyCode::Char('Q') | KeyCode::Esc => {
                if self.table.is_some() && !self.info.live && !self.ui.ended {
                    // A replay into a table: the view closes and the rest of the replay still
                    // goes into the table, so that it is whole.
                    self.close_view(Closed::Quit);
                } else {
                    self.quit = true;
                    self.stop_pacing();
                }
            }
            KeyCode::Char('p') | KeyCode::Char('P') => self.pause(),
            KeyCode::Char('s') | KeyCode::Char('S') => self.ui.sort = self.ui.sort.next(),
            KeyCode::Char('f') | KeyCode::Char('F') | KeyCode::Char('/') => {
                self.ui.editing = Some(self.ui.filter.clone())
            }
            KeyCode::Char(' ') => {
                if self.ui.selected.is_none() {
                    self.ui.move_cursor(0);
                }
                if let Some(key) = &self.ui.selected {
                    let i = self.model.lines().iter().position(|l| &l.key == key);
                    if let Some(i) = i {
                        self.model.toggle_mark(i);
                    }
                    if let Some((m, _)) = &mut self.frozen
                        && let Some(i) = m.lines().iter().position(|l| &l.key == key)
                    {
                        m.toggle_mark(i);
                    }
                }
            }
            KeyCode::Up | KeyCode::Char('k') => self.ui.move_cursor(-1),
            KeyCode::Down | KeyCode::Char('j') => self.ui.move_cursor(1),
            KeyCode::PageUp => self.ui.move_cursor(-20),
            KeyCode::PageDown => self.ui.move_cursor(20),
            KeyCode::Home => self.ui.move_cursor(-(isize::MAX / 2)),
            KeyCode::End => self.ui.move_cursor(isize::MAX / 2),
            _ => {}
        }
    }

    fn pause(&mut self) {
        let now = self.now();
        self.ui.paused = !self.ui.paused;
        let at = Instant::now();
        if self.info.live {
            // A live bus does not wait: the screen stands still, decoding (and -o) goes on.
            self.frozen = self.ui.paused.then(|| (self.model.clone(), now));
        } else {
            // A replay waits where it is.
            if let Some((m, t)) = &mut self.latest {
                *m = now;
                *t = at;
            }
            if let Some(p) = &mut self.pacer {
                if self.ui.paused {
                    p.hold(at);
                } else {
                    p.release(at);
                }
            }
        }
    }

    fn stop_pacing(&mut self) {
        if let Some(p) = &mut self.pacer {
            p.turn_off();
        }
    }

    fn stopping(&self) -> bool {
        self.quit || crate::signal::Stop::received().is_some()
    }

    /// Keeps the view up after the input ended, until the user quits or a signal comes.
    pub fn hold(&mut self) {
        if self.stopping() || self.screen.is_none() {
            return;
        }
        self.ui.ended = true;
        self.dirty = true;
        while !self.stopping() && self.screen.is_some() {
            if self.tick(Duration::from_millis(100)).is_err() {
                return;
            }
        }
    }

    fn view_error(e: std::io::Error) -> OutputError {
        OutputError {
            path: None,
            error: e,
        }
    }
}

impl RowOut for Top<'_> {
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        // Replays wait here for the row's time (and while paused), the view live meanwhile.
        loop {
            if self.stopping() || self.screen.is_none() {
                break;
            }
            let wait = if self.ui.paused && !self.info.live {
                Some(Duration::from_millis(50))
            } else {
                match (&mut self.pacer, row.micros) {
                    (Some(p), Some(t)) => p.due_in(t, Instant::now()),
                    _ => None,
                }
            };
            let Some(wait) = wait else { break };
            if let Some(t) = self.table.as_deref_mut() {
                t.flush()?;
            }
            self.tick(wait.min(Duration::from_millis(20)))
                .map_err(Self::view_error)?;
        }
        if let Some(t) = self.table.as_deref_mut() {
            t.write(row)?;
        }
        let now = match row.micros {
            Some(m) => {
                self.latest = Some((m, Instant::now()));
                self.floor = m;
                m
            }
            None => self.now(),
        };
        self.model.row(row, now);
        Ok(())
    }
}

impl Sink for Top<'_> {
    fn flush(&mut self) -> Result<(), OutputError> {
        if let Some(t) = self.table.as_deref_mut() {
            t.flush()?;
        }
        self.tick(Duration::ZERO).map_err(Self::view_error)
    }

    fn close(&mut self) -> Result<(), OutputError> {
        match self.table.as_deref_mut() {
            Some(t) => t.close(),
            None => Ok(()),
        }
    }

    fn set_anchor(&mut self, anchor: Option<crate::time::Anchor>) {
        if let Some(t) = self.table.as_deref_mut() {
            t.set_anchor(anchor);
        }
    }

    fn quit(&self) -> bool {
        self.quit
    }

    fn skip(&mut self) {
        if let Some(t) = self.table.as_deref_mut() {
            t.skip();
        }
    }
}
