//! S.Port app IDs: names, units, precisions and packed formats, as EdgeTX decodes them
//! (`radio/src/telemetry/frsky_sport.cpp` sportSensors[], `frsky_defs.h`, `sensor_names.h`).
//!
//! [`decode`] writes the `Sensor` and `Data` columns of a data frame into reusable buffers and
//! returns the unit; [`decode_numbers`] also keeps every number of the frame (`Numbers`) for
//! the `Value` column, JSON and the wide export. Nothing here allocates once the buffers have
//! grown.
//!
//! Numbers keep the full wire precision (FLVSS cells: 12 bits of 2 mV, raw 1959 → 3.918 V; SBEC
//! mV and mA → 3 decimals; GPS 1/10000 minute → degrees with 7 decimals), where EdgeTX rounds
//! (`raw / 5` hundredths for cells, `/ 10` for the SBEC). `docs/sport.md` lists every scale and
//! its source.

use std::fmt::Write as _;

use crate::fmt::{push_fixed, push_u64};
use crate::numbers::{Numbers, push_uint};

/// The numbers one S.Port frame can carry (a servo frame has three).
pub type SportNumbers = Numbers<4>;

/// The physical ID flight controllers answer on (Betaflight/INAV FSSP_SENSOR_ID1): their AccX/Y/Z
/// are in 0.01 g, see [`acc_prec`].
pub const FC_PHYS: u8 = 0x1B;

/// The name EdgeTX gives a sensor in its logs and the wide export (`VFAS(V)`), where busnoop's
/// `Sensor` column follows the S-Port_Snoop sample (`Volts`).
const fn log_name(label: &'static str) -> &'static str {
    match label.as_bytes() {
        b"Vario" => "VSpd",
        b"Amps" => "Curr",
        b"Volts" => "VFAS",
        _ => label,
    }
}

/// Decimals of AccX/Y/Z: EdgeTX reads 0.001 g (prec 3, OpenTX PR #7847) and FrSky's own sensors
/// send that; Betaflight (`lrintf(100 * acc.accADC[X] * acc.dev.acc_1G_rec)`, "Multiply by 100
/// to show as x.xx g on Taranis") and INAV (`lrintf(100 * acc.accADCf[X])`) send 0.01 g from the
/// flight-controller slot (physical ID 0x1B), so that slot is read as 0.01 g.
pub fn acc_prec(phys: u8) -> u8 {
    if phys == FC_PHYS { 2 } else { 3 }
}

/// What kind of value an app ID carries, for the scalar table.
#[derive(Clone, Copy, Debug)]
enum Sign {
    S32,
    U32,
}

/// A plain scalar sensor: label, the name its number has in logs ([`log_name`]), unit,
/// implied decimals, signedness.
#[derive(Debug)]
pub(crate) struct Scalar {
    pub label: &'static str,
    pub name: &'static str,
    pub unit: &'static str,
    prec: u8,
    sign: Sign,
}

const fn sc(
    base: u16,
    label: &'static str,
    unit: &'static str,
    prec: u8,
    sign: Sign,
) -> (u16, Scalar) {
    (
        base,
        Scalar {
            label,
            name: label,
            unit,
            prec,
            sign,
        },
    )
}

/// Scalar sensors with the app ID of their first instance (the instance nibble cleared).
static SCALARS: [(u16, Scalar); 27] = {
    use Sign::*;
    let mut t = [
        sc(0x0100, "Alt", "m", 2, S32),
        sc(0x0110, "Vario", "m/s", 2, S32),
        sc(0x0200, "Amps", "A", 1, U32),
        sc(0x0210, "Volts", "V", 2, U32),
        sc(0x0400, "Tmp1", "degC", 0, S32),
        sc(0x0410, "Tmp2", "degC", 0, S32),
        sc(0x0500, "RPM", "rpm", 0, U32),
        sc(0x0600, "Fuel", "%", 0, U32),
        sc(0x0700, "AccX", "g", 3, S32),
        sc(0x0710, "AccY", "g", 3, S32),
        sc(0x0720, "AccZ", "g", 3, S32),
        sc(0x0820, "GAlt", "m", 2, S32),
        sc(0x0830, "GSpd", "kts", 3, U32),
        sc(0x0840, "Hdg", "deg", 2, U32),
        sc(0x0900, "A3", "V", 2, S32),
        sc(0x0910, "A4", "V", 2, S32),
        sc(0x0A00, "ASpd", "kts", 1, U32),
        sc(0x0A10, "Fuel", "ml", 2, U32),
        sc(0x0B40, "Chan", "", 0, U32),
        sc(0x0D00, "GTp1", "degC", 0, S32),
        sc(0x0D10, "GTp2", "degC", 0, S32),
        sc(0x0D20, "GRPM", "rpm", 0, U32),
        sc(0x0D30, "GRVl", "ml", 0, U32),
        sc(0x0D40, "GRPc", "%", 0, U32),
        sc(0x0D50, "GFlo", "ml/min", 0, U32),
        sc(0x0D60, "GMFl", "ml/min", 0, U32),
        sc(0x0D70, "GAFl", "ml/min", 0, U32),
    ];
    let mut i = 0;
    while i < t.len() {
        t[i].1.name = log_name(t[i].1.label);
        i += 1;
    }
    t
};

/// App IDs (instance nibble cleared) by `base >> 4` below this have a kind in [`KINDS`].
const KINDS_LEN: usize = 0xE0;
/// [`KINDS`]: no common sensor.
const K_NONE: u8 = 0xFF;
/// [`KINDS`]: FLVSS cells.
const K_CELLS: u8 = 0xFE;
/// [`KINDS`]: a GPS coordinate.
const K_GPS: u8 = 0xFD;

/// What an app ID (instance nibble cleared) carries, by `base >> 4`: the index of its scalar
/// in [`SCALARS`], or [`K_CELLS`], [`K_GPS`], [`K_NONE`]. One load instead of a search.
static KINDS: [u8; KINDS_LEN] = {
    let mut k = [K_NONE; KINDS_LEN];
    let mut i = 0;
    while i < SCALARS.len() {
        k[(SCALARS[i].0 >> 4) as usize] = i as u8;
        i += 1;
    }
    k[0x030] = K_CELLS;
    k[0x080] = K_GPS;
    k
};

/// The kind of `base` (see [`KINDS`]).
#[inline(always)]
fn kind(base: u16) -> u8 {
    KINDS.get(usize::from(base >> 4)).copied().unwrap_or(K_NONE)
}

/// Scalar sensors keyed by the app ID with its instance nibble cleared.
#[inline]
fn scalar(base: u16) -> Option<&'static Scalar> {
    SCALARS.get(usize::from(kind(base))).map(|(_, s)| s)
}

/// A data frame's value as a table row shows the most common sensors, for rows written
/// straight into the table (`super::direct`): a plain scalar (its Sensor, its number's name,
/// unit, raw value and decimals, as [`decode_row`] reads them), FLVSS cells or a GPS
/// coordinate; `None` for every other app ID.
#[inline]
pub(crate) fn common(phys: u8, app_id: u16, value: u32) -> Option<Common> {
    let base = app_id & 0xFFF0;
    let k = kind(base);
    if let Some((_, s)) = SCALARS.get(usize::from(k)) {
        let raw = match s.sign {
            Sign::S32 => value as i32 as i64,
            Sign::U32 => value as i64,
        };
        let prec = if matches!(base, 0x0700..=0x0720) {
            acc_prec(phys)
        } else {
            s.prec
        };
        return Some(Common::Scalar { s, raw, prec });
    }
    match k {
        K_CELLS => Some(Common::Cells),
        K_GPS => Some(Common::Gps),
        _ => None,
    }
}

/// See [`common`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum Common {
    Scalar {
        s: &'static Scalar,
        raw: i64,
        prec: u8,
    },
    Cells,
    Gps,
}

/// `count=N`, as [`cells`] writes it.
pub(crate) fn cell_count_text(value: u32) -> &'static str {
    CELL_COUNTS[((value >> 4) & 0x0F) as usize]
}

/// ` cellN=` and `CellN` of the 0-based cell index `i`, as [`cells`] writes them.
pub(crate) fn cell_key_name(i: u32) -> (&'static str, &'static str) {
    (CELL_KEYS[(i & 0x0F) as usize], cell_name(i))
}

/// Two 16-bit halves of one value feeding two sensors (EdgeTX `subId` 0 and 1).
struct Pair {
    label: &'static str,
    first: (&'static str, &'static str, u8),
    second: (&'static str, &'static str, u8),
    signed: bool,
    /// Each half is divided by this before applying the precision (SBEC sends mV/mA).
    divisor: i64,
    /// The first half is multiplied by this (ESC RPM is sent in hundreds).
    first_multiplier: i64,
}

fn pair(base: u16) -> Option<Pair> {
    let p = |label, first, second| Pair {
        label,
        first,
        second,
        signed: false,
        divisor: 1,
        first_multiplier: 1,
    };
    Some(match base {
        0x0730 => Pair {
            signed: true,
            ..p("Roll/Ptch", ("Roll", "deg", 2), ("Ptch", "deg", 2))
        },
        0x0B00 => p("RB1V/RB1A", ("RB1V", "V", 3), ("RB1A", "A", 2)),
        0x0B10 => p("RB2V/RB2A", ("RB2V", "V", 3), ("RB2A", "A", 2)),
        0x0B30 => p("RB1C/RB2C", ("RB1C", "mAh", 0), ("RB2C", "mAh", 0)),
        0x0B50 => p("EscV/EscA", ("EscV", "V", 2), ("EscA", "A", 2)),
        0x0B60 => Pair {
            first_multiplier: 100,
            ..p("Erpm/EscC", ("Erpm", "rpm", 0), ("EscC", "mAh", 0))
        },
        0x0B90 => p("CH1A/CH2A", ("CH1A", "A", 2), ("CH2A", "A", 2)),
        0x0BA0 => p("CH3A/CH4A", ("CH3A", "A", 2), ("CH4A", "A", 2)),
        0x0BB0 => p("CH5A/CH6A", ("CH5A", "A", 2), ("CH6A", "A", 2)),
        0x0BC0 => p("CH7A/CH8A", ("CH7A", "A", 2), ("CH8A", "A", 2)),
        // The SBEC sends mV and mA; EdgeTX divides by 10, busnoop keeps the mV and mA.
        0x0E50 => p("BecV/BecA", ("BecV", "V", 3), ("BecA", "A", 3)),
        _ => return None,
    })
}

/// Legacy FrSky D hub IDs (app IDs 0x0000-0x00FF carry them inside S.Port).
fn hub_name(id: u8) -> Option<&'static str> {
    Some(match id {
        0x01 => "GPS_ALT_BP",
        0x02 => "TEMP1",
        0x03 => "RPM",
        0x04 => "FUEL",
        0x05 => "TEMP2",
        0x06 => "VOLTS",
        0x09 => "GPS_ALT_AP",
        0x10 => "BARO_ALT_BP",
        0x11 => "GPS_SPEED_BP",
        0x12 => "GPS_LONG_BP",
        0x13 => "GPS_LAT_BP",
        0x14 => "GPS_COURS_BP",
        0x15 => "GPS_DAY_MONTH",
        0x16 => "GPS_YEAR",
        0x17 => "GPS_HOUR_MIN",
        0x18 => "GPS_SEC",
        0x19 => "GPS_SPEED_AP",
        0x1A => "GPS_LONG_AP",
        0x1B => "GPS_LAT_AP",
        0x1C => "GPS_COURS_AP",
        0x21 => "BARO_ALT_AP",
        0x22 => "GPS_LONG_EW",
        0x23 => "GPS_LAT_NS",
        0x24 => "ACCEL_X",
        0x25 => "ACCEL_Y",
        0x26 => "ACCEL_Z",
        0x28 => "CURRENT",
        0x30 => "VARIO",
        0x39 => "VFAS",
        0x3A => "VOLTS_BP",
        0x3B => "VOLTS_AP",
        _ => return None,
    })
}

/// An app ID in busnoop's one hex notation: `0x` and four upper-case digits, the wire's 16 bits
/// (`0x0210`, `0xF101`). A spreadsheet keeps it as text, where `210` would become the decimal
/// number 210 (docs/sport.md, "Hex numbers").
pub fn push_hex_id(out: &mut String, app_id: u16) {
    // Digits computed (not looked up) so that each is known to be ASCII: one byte per push.
    let digit = |shift: u16| {
        let d = (app_id >> shift) as u8 & 0xF;
        char::from(if d < 10 { b'0' + d } else { b'A' - 10 + d })
    };
    out.reserve(6);
    out.push_str("0x");
    out.push(digit(12));
    out.push(digit(8));
    out.push(digit(4));
    out.push(digit(0));
}

/// The `Sensor #` column: the app ID as `0x0210` ([`push_hex_id`]; the S-Port_Snoop sample
/// writes `210`).
pub fn push_sensor_no(out: &mut String, app_id: u16) {
    push_hex_id(out, app_id);
}

/// Sensor label of an app ID without decoding a value (for config frames and notes).
pub fn label(app_id: u16, out: &mut String) {
    let mut data = String::new();
    decode(app_id, 0, out, &mut data);
}

/// Writes the `Sensor` and `Data` columns for a data frame and returns the unit (may be empty).
/// Reads AccX/Y/Z as a FrSky sensor sends them (0.001 g).
pub fn decode(app_id: u16, value: u32, sensor: &mut String, data: &mut String) -> &'static str {
    let mut nums = SportNumbers::default();
    decode_numbers(0, app_id, value, sensor, data, &mut nums)
}

/// [`decode`] for a frame from physical ID `phys`, keeping its numbers in `nums`. Returns the
/// unit of the first number (the `Value` column), or of the Data column when it has none.
pub fn decode_numbers(
    phys: u8,
    app_id: u16,
    value: u32,
    sensor: &mut String,
    data: &mut String,
    nums: &mut SportNumbers,
) -> &'static str {
    let d = decode_row(phys, app_id, value, sensor, data, nums);
    if let Some(label) = d.sensor {
        sensor.push_str(label);
    }
    if d.data_is_value {
        data.push_str(nums.first_text());
    }
    d.unit
}

/// What [`decode_row`] did not write into the buffers.
pub(crate) struct Decoded {
    /// The unit of the first number (the `Value` column), or of the Data column.
    pub unit: &'static str,
    /// The Sensor column when it is a constant (then nothing was written into `sensor`).
    pub sensor: Option<&'static str>,
    /// The Data column is the first number's text (then nothing was written into `data`).
    pub data_is_value: bool,
}

impl Decoded {
    const fn new(unit: &'static str, sensor: &'static str) -> Self {
        Decoded {
            unit,
            sensor: Some(sensor),
            data_is_value: false,
        }
    }

    /// A single number shown as it is in Data.
    const fn value(unit: &'static str, sensor: &'static str) -> Self {
        Decoded {
            unit,
            sensor: Some(sensor),
            data_is_value: true,
        }
    }

    /// The Sensor column was written into the buffer.
    pub(crate) const fn built(unit: &'static str) -> Self {
        Decoded {
            unit,
            sensor: None,
            data_is_value: false,
        }
    }
}

/// [`decode_numbers`] without copying what is constant or already formatted: the row's Sensor
/// and Data columns are the buffers unless [`Decoded`] says otherwise.
pub(crate) fn decode_row(
    phys: u8,
    app_id: u16,
    value: u32,
    sensor: &mut String,
    data: &mut String,
    nums: &mut SportNumbers,
) -> Decoded {
    let base = app_id & 0xFFF0;
    if let Some(s) = scalar(base) {
        let raw = match s.sign {
            Sign::S32 => value as i32 as i64,
            Sign::U32 => value as i64,
        };
        let prec = if matches!(base, 0x0700..=0x0720) {
            acc_prec(phys)
        } else {
            s.prec
        };
        nums.fixed(s.name, s.unit, raw, prec);
        return Decoded::value(s.unit, s.label);
    }
    if let Some(p) = pair(base) {
        let half = |h: u16| {
            if p.signed { h as i16 as i64 } else { h as i64 }
        };
        let lo = half(value as u16) * p.first_multiplier / p.divisor;
        let hi = half((value >> 16) as u16) / p.divisor;
        for (i, ((name, unit, prec), v)) in [(p.first, lo), (p.second, hi)].into_iter().enumerate()
        {
            if i > 0 {
                data.push(' ');
            }
            data.push_str(name);
            data.push('=');
            nums.fixed(name, unit, v, prec);
            data.push_str(nums.last_text());
            data.push_str(unit);
        }
        return Decoded::new(p.first.1, p.label);
    }
    let mut d = other(app_id, value, sensor, data, nums);
    if !nums.is_empty() {
        d.unit = nums.first_unit();
    }
    d
}

/// The app IDs that are neither plain scalars nor pairs.
fn other(
    app_id: u16,
    value: u32,
    sensor: &mut String,
    data: &mut String,
    nums: &mut SportNumbers,
) -> Decoded {
    match app_id {
        0x0000..=0x00FF => hub(app_id as u8, value, sensor, data, nums),
        0x0300..=0x030F => {
            cells(value, data, nums);
            Decoded::new("V", "Cels")
        }
        0x0800..=0x080F => {
            gps(value, data, nums);
            Decoded::new("deg", "GPS")
        }
        0x0850..=0x085F => date_time(value, data),
        0x0B20..=0x0B2F => {
            rb_status(value, data);
            Decoded::new("", "RBCS/RBS")
        }
        0x0B70..=0x0B7F => {
            nums.int("EscT", "degC", (value & 0xFF) as i64);
            Decoded::value("degC", "EscT")
        }
        0x0B80..=0x0B8F => {
            rb_extra(value, data);
            Decoded::new("", "RBES")
        }
        0x5000..=0x50FF => match super::passthrough::decode_row(app_id, value, data) {
            Some(label) => Decoded::new("", label),
            None => {
                let _ = write!(sensor, "0x{app_id:04X}");
                push_u64(data, value as u64);
                Decoded::built("")
            }
        },
        0x6800..=0x680F => {
            servo(value, data, nums);
            Decoded::new("", "Servo")
        }
        0xF010 => {
            nums.int("VFR", "%", 100 - (value & 0xFF) as i64);
            Decoded::value("%", "VFR")
        }
        0xF101 => {
            nums.int("RSSI", "dB", (value & 0xFF) as i64);
            Decoded::value("dB", "RSSI")
        }
        0xF102..=0xF104 => {
            let name = match app_id {
                0xF102 => "A1",
                0xF103 => "A2",
                _ => "RxBt",
            };
            nums.fixed(name, "V", receiver_centivolts(value as u8), 2);
            Decoded::value("V", name)
        }
        0xF105 => {
            nums.int("SWR", "", (value & 0xFF) as i64);
            Decoded::value("", "SWR")
        }
        0xF106 => {
            nums.int("XJT version", "", (value & 0xFFFF) as i64);
            Decoded::value("", "XJT version")
        }
        0xF107 => {
            let dbm = value as u8;
            match r9_power_mw(dbm) {
                Some(mw) => {
                    nums.int("R9PW", "mW", mw as i64);
                    Decoded::value("mW", "R9PW")
                }
                None => {
                    data.push_str("dBm=");
                    push_u64(data, dbm as u64);
                    Decoded::new("mW", "R9PW")
                }
            }
        }
        _ => {
            push_hex_id(sensor, app_id);
            nums.int_with(|n| push_hex_id(n, app_id), "", value as i64);
            Decoded {
                unit: "",
                sensor: None,
                data_is_value: true,
            }
        }
    }
}

/// Receiver analog inputs: low byte, 0..255 = 0..13.2 V with EdgeTX's default ratio. Two
/// decimals, as the radio's CSV log writes them (raw 98 → 5.07): one raw step is 52 mV, so a
/// third decimal would only show the ratio's arithmetic, not the wire.
///
/// Hundredths of a volt of a receiver analog input (raw * 1320 / 255, rounded half up).
fn receiver_centivolts(raw: u8) -> i64 {
    (raw as i64 * 1320 * 2 + 255) / (2 * 255)
}

/// `Cell1` … `Cell16` (1-based, as the radio's logs name them) for the 0-based index 0-15.
fn cell_name(index: u32) -> &'static str {
    const NAMES: [&str; 16] = [
        "Cell1", "Cell2", "Cell3", "Cell4", "Cell5", "Cell6", "Cell7", "Cell8", "Cell9", "Cell10",
        "Cell11", "Cell12", "Cell13", "Cell14", "Cell15", "Cell16",
    ];
    NAMES[(index & 0x0F) as usize]
}

fn r9_power_mw(dbm: u8) -> Option<u64> {
    Some(match dbm {
        0 => 1,
        5 => 3,
        10 => 10,
        13 => 20,
        14 => 25,
        20 => 100,
        23 => 200,
        27 => 500,
        30 => 1000,
        _ => return None,
    })
}

/// `count=` and the cell count (0-15) of an FLVSS frame, as constants (one copy a row).
const CELL_COUNTS: [&str; 16] = [
    "count=0", "count=1", "count=2", "count=3", "count=4", "count=5", "count=6", "count=7",
    "count=8", "count=9", "count=10", "count=11", "count=12", "count=13", "count=14", "count=15",
];

/// ` cell`, the number of a cell from 1 as the radio numbers them (`Cell1` … `Cell16`; the
/// wire's 0-based index 0-15, the second cell of a frame shown only when its index is below the
/// count) and `=`, as constants.
const CELL_KEYS: [&str; 16] = [
    " cell1=", " cell2=", " cell3=", " cell4=", " cell5=", " cell6=", " cell7=", " cell8=",
    " cell9=", " cell10=", " cell11=", " cell12=", " cell13=", " cell14=", " cell15=", " cell16=",
];

/// FLVSS cells: bits 0-3 first index, 4-7 count, 8-19 and 20-31 two cells in 2 mV units,
/// shown to the millivolt (raw 1959 → 3.918). EdgeTX keeps `raw / 5` hundredths of a volt
/// (integer division: 3.91).
fn cells(value: u32, data: &mut String, nums: &mut SportNumbers) {
    let index = value & 0x0F;
    let count = (value >> 4) & 0x0F;
    let c0 = (value >> 8) & 0x0FFF;
    let c1 = (value >> 20) & 0x0FFF;
    data.push_str(CELL_COUNTS[count as usize]);
    for (i, c) in [(index, c0), (index + 1, c1)] {
        if i == index || i < count {
            data.push_str(CELL_KEYS[(i & 0x0F) as usize]);
            nums.fixed(cell_name(i), "V", (c * 2) as i64, 3);
            data.push_str(nums.last_text());
        }
    }
}

/// GPS latitude/longitude: bit 31 = longitude, bit 30 = negative, bits 0-29 = 1/10000 minute.
/// Degrees with 7 decimals, rounded (one wire step is 1/600000 degree, 0.19 m).
fn gps(value: u32, data: &mut String, nums: &mut SportNumbers) {
    let lon = value & 0x8000_0000 != 0;
    let neg = value & 0x4000_0000 != 0;
    // 1e-7 degree = raw * 1e7 / 600000 = raw * 50 / 3, rounded half up.
    let e7 = ((value & 0x3FFF_FFFF) as i64 * 100 + 3) / 6;
    let v = if neg { -e7 } else { e7 };
    data.push_str(if lon { "lon=" } else { "lat=" });
    nums.fixed(if lon { "Lon" } else { "Lat" }, "deg", v, 7);
    data.push_str(nums.last_text());
}

/// GPS date (low byte ≠ 0) or time (low byte = 0).
/// Whether the Sensor column of a data frame with this app ID names something its value
/// decides: only the GPS date/time frame does (`Date` or `Time`, [`date_time`]). Every other
/// Sensor follows from the app ID alone (what the rows' stamps rely on).
pub(crate) fn sensor_from_value(app_id: u16, value: u32) -> bool {
    matches!(app_id, 0x0850..=0x085F) && value & 0xFF != 0
}

fn date_time(value: u32, data: &mut String) -> Decoded {
    let [b0, b1, b2, b3] = value.to_le_bytes();
    if b0 != 0 {
        push_uint(data, 2000 + b3 as u64);
        data.push('-');
        push_2(data, b2);
        data.push('-');
        push_2(data, b1);
        Decoded::new("", "Date")
    } else {
        push_2(data, b3);
        data.push(':');
        push_2(data, b2);
        data.push(':');
        push_2(data, b1);
        Decoded::new("", "Time")
    }
}

/// At least two digits (`{:02}`); two digits are pushed as they are, not through `itoa`.
fn push_2(data: &mut String, v: u8) {
    if v < 100 {
        data.push(char::from(b'0' + v / 10));
        data.push(char::from(b'0' + v % 10));
    } else {
        push_uint(data, v as u64);
    }
}

/// Legacy hub data: cells (ID 0x06) are byte-swapped 16-bit values, the rest plain 16-bit.
fn hub(
    id: u8,
    value: u32,
    sensor: &mut String,
    data: &mut String,
    nums: &mut SportNumbers,
) -> Decoded {
    if id == 0x06 {
        let lo = value as u8;
        let hi = (value >> 8) as u8;
        let idx = lo >> 4;
        let raw = ((lo as u32 & 0x0F) << 8) | hi as u32;
        // Numbered from 1, like FLVSS cells and the radio (`Cell1`).
        data.push_str("idx");
        push_uint(data, idx as u64 + 1);
        data.push('=');
        nums.fixed(cell_name(idx as u32), "V", (raw * 2) as i64, 3);
        data.push_str(nums.last_text());
        return Decoded::new("V", "Hub Cell");
    }
    sensor.push_str("Hub ");
    let start = sensor.len();
    match hub_name(id) {
        Some(n) => sensor.push_str(n),
        None => {
            let _ = write!(sensor, "0x{id:02X}");
        }
    }
    nums.int_with(
        |n| n.push_str(&sensor[start..]),
        "",
        (value & 0xFFFF) as i64,
    );
    Decoded {
        unit: "",
        sensor: None,
        data_is_value: true,
    }
}

const RB_STATUS: [&str; 15] = [
    "Rx1 Ovl", "Rx2 Ovl", "SBUS Ovl", "Rx1 FS", "Rx1 LF", "Rx2 FS", "Rx2 LF", "Rx1 Lost",
    "Rx2 Lost", "Rx1 NS", "Rx2 NS", "Rx3 FS", "Rx3 LF", "Rx3 Lost", "Rx3 NS",
];

/// Redundancy box: low u16 channel failures (bit n → CHn+1 KO), high u16 box status.
fn rb_status(value: u32, data: &mut String) {
    let chans = value & 0xFFFF;
    let status = value >> 16;
    data.push_str("RBCS=");
    if chans == 0 {
        data.push_str("OK");
    } else {
        let mut first = true;
        for bit in 0..16 {
            if chans & (1 << bit) != 0 {
                if !first {
                    data.push(',');
                }
                first = false;
                data.push_str("CH");
                push_u64(data, bit + 1);
                data.push_str(" KO");
            }
        }
    }
    data.push_str(" RBS=");
    if status == 0 {
        data.push_str("Rx OK");
    } else {
        let mut first = true;
        for (bit, name) in RB_STATUS.iter().enumerate() {
            if status & (1 << bit) != 0 {
                if !first {
                    data.push(',');
                }
                first = false;
                data.push_str(name);
            }
        }
        if status >> 15 != 0 {
            if !first {
                data.push(',');
            }
            let _ = write!(data, "0x{:04X}", status & 0x8000);
        }
    }
}

/// RB3040 extra state: bits 0-7 → CH17..CH24 KO, bit 8 → S.P Ovl.
fn rb_extra(value: u32, data: &mut String) {
    if value == 0 {
        data.push_str("OK");
        return;
    }
    let mut first = true;
    let mut sep = |data: &mut String| {
        if !first {
            data.push(',');
        }
        first = false;
    };
    for bit in 0..8 {
        if value & (1 << bit) != 0 {
            sep(data);
            data.push_str("CH");
            push_u64(data, 17 + bit);
            data.push_str(" KO");
        }
    }
    if value & 0x100 != 0 {
        sep(data);
        data.push_str("S.P Ovl");
    }
    if value >> 9 != 0 {
        sep(data);
        let _ = write!(data, "0x{:08X}", value & !0x1FF);
    }
}

/// Xact servo: byte0 A×10, byte1 V×10, byte2 °C, byte3 0 = OK, else STALL.
fn servo(value: u32, data: &mut String, nums: &mut SportNumbers) {
    let [a, v, t, s] = value.to_le_bytes();
    nums.fixed("SrvA", "A", a as i64, 1);
    nums.fixed("SrvV", "V", v as i64, 1);
    nums.int("SrvT", "degC", t as i64);
    data.push_str("SrvA=");
    push_fixed(data, a as i64, 1);
    data.push_str("A SrvV=");
    push_fixed(data, v as i64, 1);
    data.push_str("V SrvT=");
    push_u64(data, t as u64);
    data.push_str("degC SrvS=");
    data.push_str(if s == 0 { "OK" } else { "STALL" });
}

#[cfg(test)]
mod tests;
