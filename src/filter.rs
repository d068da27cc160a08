//! Choosing rows and naming devices, for every protocol: `--id`, `--not-id`, `--type`,
//! `--not-type`, `--hide-polls`, `--hide-null`, `--errors`, `--sensor`, `--device` and `--name`.
//!
//! Pure code: a [`Spec`] (the option values as the user wrote them, from the command line or
//! the project file) is checked against what a protocol can show ([`Vocab`], from its
//! descriptor) and compiled into a [`Filter`] and [`Names`]. A filter that could never match on
//! this protocol (an ID outside its range, an unknown sensor or type) is refused with the list
//! of valid values. [`Select`] sits between the decoder and the table: it puts the names into
//! the Device column and lets through the rows the filter keeps; the table still counts the
//! others, so a row's Counter is the same with or without a filter.
//!
//! Rules: several filters combine with AND, the values of one filter with OR. Matching costs
//! no allocation per row.

use std::ops::RangeInclusive;

pub use crate::protocol::vocab::{POLL, Sensor, Vocab};
use crate::protocol::vocab::{did_you_mean, short_list};
use crate::row::{Class, Row, RowOut, RowResult, Unframed};
use crate::sink::Sink;

/// Options as the user wrote them (each `Vec` holds the values of a repeatable option; a value
/// may itself be a comma-separated list).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Spec {
    pub id: Vec<String>,
    pub not_id: Vec<String>,
    pub types: Vec<String>,
    pub not_types: Vec<String>,
    pub hide_polls: bool,
    pub hide_null: bool,
    pub errors: bool,
    pub sensor: Vec<String>,
    pub device: Vec<String>,
    /// `NAME=ID` values.
    pub names: Vec<String>,
}

/// A usage error: the message names the option and the valid values.
pub type Error = String;

/// The options a word of [`Filter::from_words`] may name (without `--`), the ones that take a
/// value first.
const WORD_OPTIONS: [&str; 9] = [
    "id",
    "not-id",
    "type",
    "not-type",
    "sensor",
    "device",
    "hide-polls",
    "hide-null",
    "errors",
];

impl Spec {
    /// Adds `value` to the list option `name` (`id`, `not-id`, `type`, `not-type`, `sensor`,
    /// `device`), or sets the switch `name` (`hide-polls`, `hide-null`, `errors`; a value of
    /// `false`/`no`/`0` clears it). `false` when there is no such option.
    fn set(&mut self, name: &str, value: Option<&str>) -> bool {
        let list = match name {
            "id" => &mut self.id,
            "not-id" => &mut self.not_id,
            "type" => &mut self.types,
            "not-type" => &mut self.not_types,
            "sensor" => &mut self.sensor,
            "device" => &mut self.device,
            _ => {
                let on = !matches!(value, Some("false" | "no" | "0" | "off"));
                let flag = match name {
                    "hide-polls" => &mut self.hide_polls,
                    "hide-null" => &mut self.hide_null,
                    "errors" => &mut self.errors,
                    _ => return false,
                };
                *flag = on;
                return true;
            }
        };
        list.push(value.unwrap_or("").to_owned());
        true
    }
}

/// Names for IDs, shown in the Device column.
#[derive(Clone, Debug, Default)]
pub struct Names {
    by_id: Vec<Option<Box<str>>>,
}

impl Names {
    /// The name of `id`, if one was given.
    pub fn get(&self, id: u32) -> Option<&str> {
        self.by_id.get(id as usize)?.as_deref()
    }

    /// Every (name, ID), in ID order.
    pub fn pairs(&self) -> impl Iterator<Item = (&str, u32)> {
        self.by_id
            .iter()
            .enumerate()
            .filter_map(|(i, n)| Some((n.as_deref()?, i as u32)))
    }

    /// Names `id` (a later name for the same ID wins).
    pub fn set(&mut self, name: &str, id: u32) {
        let i = id as usize;
        if self.by_id.len() <= i {
            self.by_id.resize(i + 1, None);
        }
        self.by_id[i] = Some(name.into());
    }

    /// Parses `NAME=ID` values (`Boiler=10`, `imu=0x12`) for `option`, checking the ID range.
    pub fn parse(values: &[String], option: &str, vocab: &Vocab) -> Result<Names, Error> {
        let mut names = Names::default();
        for v in values {
            let (name, id) = v.rsplit_once('=').ok_or_else(|| {
                format!("{option} {v:?}: expected NAME=ID, for example {option} Boiler=10")
            })?;
            let name = name.trim();
            if name.is_empty() {
                return Err(format!("{option} {v:?}: the name is empty"));
            }
            let id = parse_number(id.trim()).ok_or_else(|| match parse_number(name) {
                // `--name 1=Pack`: the two the other way round.
                Some(_) => format!(
                    "{option} {v:?}: the name comes first, then the ID: {option} {}={name}",
                    id.trim()
                ),
                None => format!("{option} {v:?}: {id:?} is not a number (10 or 0x0A)"),
            })?;
            check_id(id, v, option, vocab)?;
            names.set(name, id);
        }
        Ok(names)
    }
}

/// A compiled filter: which rows to show.
#[derive(Clone, Debug, Default)]
pub struct Filter {
    ids: Vec<RangeInclusive<u32>>,
    not_ids: Vec<RangeInclusive<u32>>,
    types: Vec<Box<str>>,
    not_types: Vec<Box<str>>,
    hide_polls: bool,
    hide_null: bool,
    errors: bool,
    sensors: Vec<Pattern>,
    devices: Vec<Box<str>>,
    /// Any rule at all (otherwise every row is kept without looking).
    active: bool,
}

/// A `--sensor` value: rows whose Sensor or Sensor # column is the text or the column name of
/// a sensor it names, or that carry a number of that name; and its value when it reads as a hex
/// number (`0210`, `0x34`), so that `0210` and `210` match
/// the Sensor # `0x0210`.
#[derive(Clone, Debug)]
struct Pattern {
    /// The value as given: a Sensor or Sensor # text, or the name of a number (a part).
    text: Box<str>,
    /// The Sensor column of each sensor that has this name (`VFAS` → `Volts`).
    columns: Vec<Box<str>>,
    number: Option<u32>,
}

impl Filter {
    /// Checks `spec` against `vocab` (`names`: the names given, which `--device` may use;
    /// `sensors`: names the Sensor column gets from options, SAB's `--command`).
    pub fn new(
        spec: &Spec,
        vocab: &Vocab,
        names: &Names,
        sensors: &[String],
        protocol: &str,
    ) -> Result<Filter, Error> {
        // An empty value would keep every row: `--id ""` from a script whose variable was
        // empty is a mistake to say, not a filter to drop.
        for (values, option) in [
            (&spec.id, "--id"),
            (&spec.not_id, "--not-id"),
            (&spec.types, "--type"),
            (&spec.not_types, "--not-type"),
            (&spec.sensor, "--sensor"),
            (&spec.device, "--device"),
        ] {
            if let Some(v) = values
                .iter()
                .find(|v| v.split(',').all(|s| s.trim().is_empty()))
            {
                return Err(format!(
                    "{option} {v:?}: an empty value; give one or more, comma-separated, or leave \
                     {option} out"
                ));
            }
        }
        let mut f = Filter {
            ids: id_list(&spec.id, "--id", vocab)?,
            not_ids: id_list(&spec.not_id, "--not-id", vocab)?,
            types: type_list(&spec.types, "--type", vocab, protocol)?,
            not_types: type_list(&spec.not_types, "--not-type", vocab, protocol)?,
            hide_polls: spec.hide_polls,
            hide_null: spec.hide_null,
            errors: spec.errors,
            sensors: Vec::new(),
            devices: Vec::new(),
            active: false,
        };
        if spec.hide_polls && !vocab.polls {
            // Said in the protocol's own words: requests with answers, or a stream of frames.
            let (what, example) = if vocab.types.contains(&"Request") {
                ("every request is shown with its answer", "Request")
            } else {
                let rc = vocab.types.iter().find(|t| **t == "RC");
                (
                    "its frames come unasked",
                    rc.or(vocab.types.first()).copied().unwrap_or("TYPE"),
                )
            };
            return Err(format!(
                "--hide-polls: {protocol} has no polls ({what}); to hide a type use --not-type, \
                 e.g. --not-type {example}"
            ));
        }
        if spec.hide_null && !vocab.keepalives {
            return Err(format!(
                "--hide-null: {protocol} has no keep-alive rows; to hide a type use --not-type"
            ));
        }
        let mut known: Option<Vec<Sensor>> = None;
        for v in split(&spec.sensor) {
            let number = if vocab.sensor_no_hex {
                parse_hex(v)
            } else {
                None
            };
            let from_options = sensors.iter().any(|s| s.eq_ignore_ascii_case(v));
            let known = known.get_or_insert_with(|| (vocab.sensors)());
            // Either name of a sensor selects its rows: a number's name also selects the rows
            // of the sensor's column (broken frames carry no numbers, only the column).
            let columns: Vec<Box<str>> = known
                .iter()
                .filter(|s| s.is(v))
                .map(|s| s.column.as_str().into())
                .collect();
            if columns.is_empty() && !from_options && !(vocab.sensor_no)(v) {
                return Err(unknown_sensor(v, known, sensors, vocab, protocol));
            }
            f.sensors.push(Pattern {
                text: v.into(),
                columns,
                number,
            });
        }
        for v in split(&spec.device) {
            let named = names.pairs().any(|(n, _)| n.eq_ignore_ascii_case(v));
            if let (Some(device), Some(ids)) = (vocab.devices, &vocab.ids)
                && !named
            {
                let shown = |id: u32| names.get(id).unwrap_or_else(|| device(id));
                if !ids.clone().any(|id| shown(id).eq_ignore_ascii_case(v)) {
                    let mut all: Vec<&str> = ids.clone().map(shown).collect();
                    all.retain(|s| !s.is_empty());
                    all.sort_unstable();
                    all.dedup();
                    let all = if all.is_empty() {
                        "nothing until devices are named (--name NAME=ID)".to_string()
                    } else {
                        all.join(", ")
                    };
                    return Err(format!(
                        "--device {v:?}: no {protocol} device has this name; the Device column \
                         shows {all}"
                    ));
                }
            }
            f.devices.push(v.into());
        }
        // Options that contradict each other would show nothing at all.
        let has = |list: &[RangeInclusive<u32>], id: u32| list.iter().any(|r| r.contains(&id));
        if !f.ids.is_empty()
            && !f.not_ids.is_empty()
            && vocab
                .ids
                .clone()
                .is_some_and(|mut ids| ids.all(|id| !has(&f.ids, id) || has(&f.not_ids, id)))
        {
            return Err(format!(
                "--not-id leaves no ID of --id ({} minus {}): no row could be shown",
                spec.id.join(","),
                spec.not_id.join(",")
            ));
        }
        if !f.types.is_empty()
            && f.types
                .iter()
                .all(|t| f.not_types.iter().any(|n| n.eq_ignore_ascii_case(t)))
        {
            return Err(format!(
                "--not-type leaves no type of --type ({} minus {}): no row could be shown",
                spec.types.join(","),
                spec.not_types.join(",")
            ));
        }
        f.active = !(f.ids.is_empty()
            && f.not_ids.is_empty()
            && f.types.is_empty()
            && f.not_types.is_empty()
            && !f.hide_polls
            && !f.hide_null
            && !f.errors
            && f.sensors.is_empty()
            && f.devices.is_empty());
        Ok(f)
    }

    /// A filter written as words, as the live view's `f` key takes it: the command line's
    /// filter options without `--` and with `=` or a blank before the value (`id=1`,
    /// `sensor=RSSI,RxBt type=Data`, `not-id 0-9`, `errors`; `--id=1` reads too), checked
    /// against the protocol as on the command line. A bare number is an ID, any other bare
    /// word a sensor (either of its names) or else a device (`1` is ID 1, not every ID with a
    /// 1 in it).
    pub fn from_words(
        text: &str,
        vocab: &Vocab,
        names: &Names,
        sensors: &[String],
        protocol: &str,
    ) -> Result<Filter, Error> {
        let mut spec = Spec::default();
        let mut bare = Vec::new();
        let mut words = text.split_whitespace().peekable();
        while let Some(word) = words.next() {
            let w = word.trim_start_matches('-');
            let (name, value) = match w.split_once(['=', ':']) {
                Some((n, v)) => (n.to_ascii_lowercase(), Some(v.to_owned())),
                None => (w.to_ascii_lowercase(), None),
            };
            let takes_value = WORD_OPTIONS[..6].contains(&name.as_str());
            let value = match value {
                None if takes_value => match words.next() {
                    Some(v) => Some(v.to_owned()),
                    None => return Err(format!("{name}: give a value, e.g. {name}=…")),
                },
                v => v,
            };
            if !WORD_OPTIONS.contains(&name.as_str()) {
                if word.starts_with('-') || value.is_some() {
                    return Err(format!(
                        "{word}: not a filter; filters: {}",
                        WORD_OPTIONS.join(", ")
                    ));
                }
                bare.push(word);
                continue;
            }
            spec.set(&name, value.as_deref());
        }
        for word in bare {
            if parse_number(word).is_some() {
                spec.id.push(word.to_owned());
                continue;
            }
            let mut as_sensor = spec.clone();
            as_sensor.sensor.push(word.to_owned());
            if Filter::new(&as_sensor, vocab, names, sensors, protocol).is_ok() {
                spec = as_sensor;
                continue;
            }
            let mut as_device = spec.clone();
            as_device.device.push(word.to_owned());
            match Filter::new(&as_device, vocab, names, sensors, protocol) {
                Ok(_) => spec = as_device,
                Err(_) => {
                    return Err(format!(
                        "{word}: no {protocol} sensor or device has this name; filters: \
                         id=, sensor=, type=, device=, not-id=, not-type=, errors"
                    ));
                }
            }
        }
        Filter::new(&spec, vocab, names, sensors, protocol)
            .map_err(|e| e.trim_start_matches("--").to_owned())
    }

    /// Whether any rule is set.
    #[cfg(test)]
    pub fn is_active(&self) -> bool {
        self.active
    }

    /// Whether `row` is shown.
    #[inline]
    pub fn keep(&self, row: &Row<'_>) -> bool {
        !self.active || self.check(row)
    }

    fn check(&self, row: &Row<'_>) -> bool {
        let poll = is_poll(row);
        let type_is = |t: &str| {
            if poll {
                t == POLL
            } else {
                t.eq_ignore_ascii_case(row.kind)
            }
        };
        if !self.types.is_empty() && !self.types.iter().any(|t| type_is(t)) {
            return false;
        }
        if self.not_types.iter().any(|t| type_is(t)) {
            return false;
        }
        // busnoop's own rows (an adapter gap, a clock jump) belong to no device: only the type
        // filters hide them, so a filtered log still shows where the capture has holes.
        if row.class == Class::Info {
            return true;
        }
        if !self.ids.is_empty()
            && !row
                .id
                .is_some_and(|id| self.ids.iter().any(|r| r.contains(&id)))
        {
            return false;
        }
        if row
            .id
            .is_some_and(|id| self.not_ids.iter().any(|r| r.contains(&id)))
        {
            return false;
        }
        if self.hide_polls && poll {
            return false;
        }
        if self.hide_null && row.class == Class::Quiet {
            return false;
        }
        if self.errors && !matches!(row.class, Class::Warning | Class::Error | Class::Info) {
            return false;
        }
        if !self.sensors.is_empty() && !self.sensors.iter().any(|p| p.matches(row)) {
            return false;
        }
        if !self.devices.is_empty()
            && !self
                .devices
                .iter()
                .any(|d| d.eq_ignore_ascii_case(row.device))
        {
            return false;
        }
        true
    }
}

impl Pattern {
    fn matches(&self, row: &Row<'_>) -> bool {
        let text = &*self.text;
        if text.eq_ignore_ascii_case(row.sensor)
            || text.eq_ignore_ascii_case(row.sensor_no)
            || self
                .columns
                .iter()
                .any(|c| c.eq_ignore_ascii_case(row.sensor))
            || row.parts.iter().any(|p| text.eq_ignore_ascii_case(p.name))
        {
            return true;
        }
        match self.number {
            Some(n) => !row.sensor_no.is_empty() && parse_hex(row.sensor_no) == Some(n),
            None => false,
        }
    }
}

/// A poll nobody answered: a row with an ID and no Type.
fn is_poll(row: &Row<'_>) -> bool {
    row.kind.is_empty() && row.id.is_some()
}

/// The filter and the names, between the decoder and the table.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    pub filter: Filter,
    pub names: Names,
    /// Names the Sensor column gets from the protocol's options (SAB's `--command`), which
    /// filters written later (the live view's `f`) may name.
    pub sensors: Vec<String>,
}

impl Selection {
    /// Whether every row passes unchanged: no filter rule and no name.
    #[inline]
    pub fn passes_all(&self) -> bool {
        !self.filter.active && self.names.by_id.is_empty()
    }
}

/// A [`RowOut`] that names devices and filters rows into a [`Sink`] (the table or the live
/// view); rows it drops are still counted there.
pub struct Select<'a> {
    pub table: &'a mut dyn Sink,
    pub selection: &'a Selection,
}

impl<'a> Select<'a> {
    /// Where the decoder's rows go: the table itself when there is no filter and no name (every
    /// row would pass unchanged, so the check per row and the extra dynamic call are saved),
    /// else this layer.
    #[inline]
    pub fn out(&mut self) -> &mut dyn RowOut {
        if self.selection.passes_all() {
            &mut *self.table
        } else {
            self
        }
    }

    /// Names the row's device and hands the row on to `write` when the filter keeps it.
    #[inline]
    fn select(
        &mut self,
        row: &Row<'_>,
        write: impl FnOnce(&mut dyn Sink, &Row<'_>) -> RowResult,
    ) -> RowResult {
        let sel = self.selection;
        let named;
        let row = match row.id.and_then(|id| sel.names.get(id)) {
            Some(name) => {
                named = Row {
                    device: name,
                    ..*row
                };
                &named
            }
            None => row,
        };
        if sel.filter.keep(row) {
            write(self.table, row)
        } else {
            self.table.skip();
            Ok(())
        }
    }
}

impl RowOut for Select<'_> {
    #[inline]
    fn row(&mut self, row: &Row<'_>) -> RowResult {
        self.select(row, |t, row| t.row(row))
    }

    fn row_unframed(&mut self, row: &Row<'_>, frame: &Unframed<'_>) -> RowResult {
        self.select(row, |t, row| t.row_unframed(row, frame))
    }
}

/// The values of a repeatable list option, split at commas, trimmed, empty ones dropped.
fn split(values: &[String]) -> impl Iterator<Item = &str> {
    values
        .iter()
        .flat_map(|v| v.split(','))
        .map(str::trim)
        .filter(|s| !s.is_empty())
}

/// A decimal or `0x` hex number.
pub fn parse_number(s: &str) -> Option<u32> {
    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16).ok(),
        None => s.parse().ok(),
    }
}

/// A hex number with or without `0x` (`0210`, `0x34`, `F105`).
fn parse_hex(s: &str) -> Option<u32> {
    let h = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    if h.is_empty() || h.len() > 8 {
        return None;
    }
    u32::from_str_radix(h, 16).ok()
}

fn range_text(ids: &RangeInclusive<u32>) -> String {
    let (a, b) = (*ids.start(), *ids.end());
    format!("{a}-{b} (0x{a:02X}-0x{b:02X})")
}

/// The valid IDs, or the refusal of `option` for a protocol whose rows have none.
fn ids_of<'v>(vocab: &'v Vocab, option: &str) -> Result<&'v RangeInclusive<u32>, Error> {
    vocab.ids.as_ref().ok_or_else(|| {
        format!(
            "{option}: these rows have no ID column to match (select rows with --type or \
             --sensor)"
        )
    })
}

fn check_id(id: u32, text: &str, option: &str, vocab: &Vocab) -> Result<(), Error> {
    let ids = ids_of(vocab, option)?;
    if ids.contains(&id) {
        return Ok(());
    }
    let hint = (vocab.id_hint)(id).map_or(String::new(), |h| format!("; {h}"));
    Err(format!(
        "{option} {text}: outside the {} range {}{hint}",
        vocab.id_name,
        range_text(ids)
    ))
}

/// The refusal of `--sensor v`: the closest name when one is near, and a short line of the
/// names each column can show.
fn unknown_sensor(
    v: &str,
    known: &[Sensor],
    from_options: &[String],
    vocab: &Vocab,
    protocol: &str,
) -> Error {
    let columns: Vec<&str> = known
        .iter()
        .map(|s| s.column.as_str())
        .chain(from_options.iter().map(String::as_str))
        .collect();
    let parts: Vec<&str> = known
        .iter()
        .flat_map(|s| s.parts.iter().map(String::as_str))
        .collect();
    let mut msg = format!("--sensor {v:?}: no {protocol} row shows it");
    if let Some(near) = did_you_mean(v, columns.iter().chain(parts.iter()).copied()) {
        msg.push_str(&format!("; did you mean {near}?"));
    }
    if columns.is_empty() {
        msg.push_str("; the Sensor column has no names without options");
    } else {
        msg.push_str(&format!("; Sensor column: {}", short_list(&columns)));
    }
    if !parts.is_empty() {
        msg.push_str(&format!("; numbers: {}", short_list(&parts)));
    }
    msg.push_str(&format!("; the Sensor # column {}", vocab.sensor_no_text));
    msg
}

/// `2,8`, `0x1B`, `0-9`, `0x10-0x1F`.
fn id_list(
    values: &[String],
    option: &str,
    vocab: &Vocab,
) -> Result<Vec<RangeInclusive<u32>>, Error> {
    let mut out = Vec::new();
    for v in split(values) {
        let range = ids_of(vocab, option)?;
        let bad = || {
            format!(
                "{option} {v:?}: expected IDs like 2, 0x1B or 0-9 ({}s {})",
                vocab.id_name,
                range_text(range)
            )
        };
        let (a, b) = match v.split_once('-') {
            Some((a, b)) => (
                parse_number(a.trim()).ok_or_else(bad)?,
                parse_number(b.trim()).ok_or_else(bad)?,
            ),
            None => {
                let n = parse_number(v).ok_or_else(bad)?;
                (n, n)
            }
        };
        if a > b {
            return Err(format!("{option} {v:?}: the range is empty ({a} > {b})"));
        }
        check_id(a, v, option, vocab)?;
        check_id(b, v, option, vocab)?;
        out.push(a..=b);
    }
    Ok(out)
}

fn type_list(
    values: &[String],
    option: &str,
    vocab: &Vocab,
    protocol: &str,
) -> Result<Vec<Box<str>>, Error> {
    let mut out = Vec::new();
    for v in split(values) {
        let found = vocab
            .types
            .iter()
            .copied()
            .chain(vocab.polls.then_some(POLL))
            .find(|t| t.eq_ignore_ascii_case(v));
        match found {
            Some(t) => out.push(t.into()),
            None => {
                let mut all: Vec<&str> = vocab.types.to_vec();
                if vocab.polls {
                    all.push(POLL);
                }
                return Err(format!(
                    "{option} {v:?}: {protocol} rows have no such type; types: {}",
                    all.join(", ")
                ));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
