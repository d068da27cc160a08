//! S.Port app IDs: names, units, precisions and packed formats, as EdgeTX decodes them
//! (`radio/src/telemetry/frsky_sport.cpp` sportSensors[], `frsky_defs.h`, `sensor_names.h`).
//!
//! [`decode`] writes the `Sensor` and `Data` columns of a data frame into reusable buffers and
//! returns the unit; nothing here allocates once the buffers have grown.

use std::fmt::Write as _;

use crate::fmt::{push_fixed, push_i64, push_u64};

/// What kind of value an app ID carries, for the scalar table.
#[derive(Clone, Copy)]
enum Sign {
    S32,
    U32,
}

/// A plain scalar sensor: label, unit, implied decimals, signedness.
struct Scalar {
    label: &'static str,
    unit: &'static str,
    prec: u8,
    sign: Sign,
}

const fn sc(label: &'static str, unit: &'static str, prec: u8, sign: Sign) -> Scalar {
    Scalar {
        label,
        unit,
        prec,
        sign,
    }
}

/// Scalar sensors keyed by the app ID with its instance nibble cleared.
fn scalar(base: u16) -> Option<Scalar> {
    use Sign::*;
    Some(match base {
        0x0100 => sc("Alt", "m", 2, S32),
        0x0110 => sc("Vario", "m/s", 2, S32),
        0x0200 => sc("Amps", "A", 1, U32),
        0x0210 => sc("Volts", "V", 2, U32),
        0x0400 => sc("Tmp1", "degC", 0, S32),
        0x0410 => sc("Tmp2", "degC", 0, S32),
        0x0500 => sc("RPM", "rpm", 0, U32),
        0x0600 => sc("Fuel", "%", 0, U32),
        0x0700 => sc("AccX", "g", 3, S32),
        0x0710 => sc("AccY", "g", 3, S32),
        0x0720 => sc("AccZ", "g", 3, S32),
        0x0820 => sc("GAlt", "m", 2, S32),
        0x0830 => sc("GSpd", "kts", 3, U32),
        0x0840 => sc("Hdg", "deg", 2, U32),
        0x0900 => sc("A3", "V", 2, S32),
        0x0910 => sc("A4", "V", 2, S32),
        0x0A00 => sc("ASpd", "kts", 1, U32),
        0x0A10 => sc("Fuel", "ml", 2, U32),
        0x0B40 => sc("Chan", "", 0, U32),
        0x0D00 => sc("GTp1", "degC", 0, S32),
        0x0D10 => sc("GTp2", "degC", 0, S32),
        0x0D20 => sc("GRPM", "rpm", 0, U32),
        0x0D30 => sc("GRVl", "ml", 0, U32),
        0x0D40 => sc("GRPc", "%", 0, U32),
        0x0D50 => sc("GFlo", "ml/min", 0, U32),
        0x0D60 => sc("GMFl", "ml/min", 0, U32),
        0x0D70 => sc("GAFl", "ml/min", 0, U32),
        _ => return None,
    })
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
        0x0E50 => Pair {
            divisor: 10,
            ..p("BecV/BecA", ("BecV", "V", 2), ("BecA", "A", 2))
        },
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

const HEX_DIGITS: &[u8; 16] = b"0123456789ABCDEF";

/// Upper-case 4-digit hex label of an unknown app ID (`5100`), as EdgeTX names them.
pub fn push_hex_id(out: &mut String, app_id: u16) {
    for shift in [12, 8, 4, 0] {
        out.push(HEX_DIGITS[(app_id >> shift) as usize & 0xF] as char);
    }
}

/// The `Sensor #` column: the app ID in hex without leading zeros (0x0210 → `210`).
pub fn push_sensor_no(out: &mut String, app_id: u16) {
    let mut started = false;
    for shift in [12, 8, 4, 0] {
        let d = (app_id >> shift) as usize & 0xF;
        if d != 0 || started || shift == 0 {
            started = true;
            out.push(HEX_DIGITS[d] as char);
        }
    }
}

/// Sensor label of an app ID without decoding a value (for config frames and notes).
pub fn label(app_id: u16, out: &mut String) {
    let mut data = String::new();
    decode(app_id, 0, out, &mut data);
}

/// Writes the `Sensor` and `Data` columns for a data frame and returns the unit (may be empty).
pub fn decode(app_id: u16, value: u32, sensor: &mut String, data: &mut String) -> &'static str {
    let base = app_id & 0xFFF0;
    if let Some(s) = scalar(base) {
        sensor.push_str(s.label);
        let raw = match s.sign {
            Sign::S32 => value as i32 as i64,
            Sign::U32 => value as i64,
        };
        push_fixed(data, raw, s.prec);
        return s.unit;
    }
    if let Some(p) = pair(base) {
        sensor.push_str(p.label);
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
            push_fixed(data, v, prec);
            data.push_str(unit);
        }
        return "";
    }
    match app_id {
        0x0000..=0x00FF => hub(app_id as u8, value, sensor, data),
        0x0300..=0x030F => {
            sensor.push_str("Cels");
            cells(value, data);
            "V"
        }
        0x0800..=0x080F => {
            sensor.push_str("GPS");
            gps(value, data);
            "deg"
        }
        0x0850..=0x085F => date_time(value, sensor, data),
        0x0B20..=0x0B2F => {
            sensor.push_str("RBCS/RBS");
            rb_status(value, data);
            ""
        }
        0x0B70..=0x0B7F => {
            sensor.push_str("EscT");
            push_u64(data, (value & 0xFF) as u64);
            "degC"
        }
        0x0B80..=0x0B8F => {
            sensor.push_str("RBES");
            rb_extra(value, data);
            ""
        }
        0x5000..=0x50FF => super::passthrough::decode(app_id, value, sensor, data),
        0x6800..=0x680F => {
            sensor.push_str("Servo");
            servo(value, data);
            ""
        }
        0xF010 => {
            sensor.push_str("VFR");
            push_i64(data, 100 - (value & 0xFF) as i64);
            "%"
        }
        0xF101 => {
            sensor.push_str("RSSI");
            push_u64(data, (value & 0xFF) as u64);
            "dB"
        }
        0xF102..=0xF104 => {
            sensor.push_str(match app_id {
                0xF102 => "A1",
                0xF103 => "A2",
                _ => "RxBt",
            });
            push_receiver_volts(data, value as u8);
            "V"
        }
        0xF105 => {
            sensor.push_str("SWR");
            push_u64(data, (value & 0xFF) as u64);
            ""
        }
        0xF106 => {
            sensor.push_str("XJT version");
            push_u64(data, (value & 0xFFFF) as u64);
            ""
        }
        0xF107 => {
            sensor.push_str("R9PW");
            let dbm = value as u8;
            match r9_power_mw(dbm) {
                Some(mw) => push_u64(data, mw),
                None => {
                    data.push_str("dBm=");
                    push_u64(data, dbm as u64);
                }
            }
            "mW"
        }
        _ => {
            push_hex_id(sensor, app_id);
            push_u64(data, value as u64);
            ""
        }
    }
}

/// Receiver analog inputs: low byte, 0..255 = 0..13.2 V with EdgeTX's default ratio. Two
/// decimals, as the radio's CSV log writes them (raw 98 → 5.07).
pub fn push_receiver_volts(data: &mut String, raw: u8) {
    // 13.2 V full scale: volts*100 = raw * 1320 / 255, rounded half up.
    let hundredths = (raw as i64 * 1320 * 2 + 255) / (2 * 255);
    push_fixed(data, hundredths, 2);
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

/// FLVSS cells: bits 0-3 first index, 4-7 count, 8-19 and 20-31 two cells in 2 mV units.
/// EdgeTX keeps `raw / 5` hundredths of a volt (integer division).
fn cells(value: u32, data: &mut String) {
    let index = value & 0x0F;
    let count = (value >> 4) & 0x0F;
    let c0 = (value >> 8) & 0x0FFF;
    let c1 = (value >> 20) & 0x0FFF;
    data.push_str("count=");
    push_u64(data, count as u64);
    for (i, c) in [(index, c0), (index + 1, c1)] {
        if i == index || i < count {
            data.push_str(" cell");
            push_u64(data, i as u64);
            data.push('=');
            push_fixed(data, (c / 5) as i64, 2);
        }
    }
}

/// GPS latitude/longitude: bit 31 = longitude, bit 30 = negative, bits 0-29 = 1/10000 minute.
fn gps(value: u32, data: &mut String) {
    let lon = value & 0x8000_0000 != 0;
    let neg = value & 0x4000_0000 != 0;
    let micro = (value & 0x3FFF_FFFF) as i64 * 5 / 3;
    data.push_str(if lon { "lon=" } else { "lat=" });
    push_fixed(data, if neg { -micro } else { micro }, 6);
}

/// GPS date (low byte ≠ 0) or time (low byte = 0).
fn date_time(value: u32, sensor: &mut String, data: &mut String) -> &'static str {
    let [b0, b1, b2, b3] = value.to_le_bytes();
    if b0 != 0 {
        sensor.push_str("Date");
        let _ = write!(data, "{:04}-{:02}-{:02}", 2000 + b3 as u32, b2, b1);
    } else {
        sensor.push_str("Time");
        let _ = write!(data, "{b3:02}:{b2:02}:{b1:02}");
    }
    ""
}

/// Legacy hub data: cells (ID 0x06) are byte-swapped 16-bit values, the rest plain 16-bit.
fn hub(id: u8, value: u32, sensor: &mut String, data: &mut String) -> &'static str {
    if id == 0x06 {
        sensor.push_str("Hub Cell");
        let lo = value as u8;
        let hi = (value >> 8) as u8;
        let idx = lo >> 4;
        let raw = ((lo as u32 & 0x0F) << 8) | hi as u32;
        data.push_str("idx");
        push_u64(data, idx as u64);
        data.push('=');
        push_fixed(data, (raw / 5) as i64, 2);
        return "V";
    }
    sensor.push_str("Hub ");
    match hub_name(id) {
        Some(n) => sensor.push_str(n),
        None => {
            let _ = write!(sensor, "0x{id:02X}");
        }
    }
    push_u64(data, (value & 0xFFFF) as u64);
    ""
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
fn servo(value: u32, data: &mut String) {
    let [a, v, t, s] = value.to_le_bytes();
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
mod tests {
    use super::*;

    fn d(app_id: u16, value: u32) -> (String, String, &'static str) {
        let (mut s, mut v) = (String::new(), String::new());
        let unit = decode(app_id, value, &mut s, &mut v);
        (s, v, unit)
    }

    #[test]
    fn hex_ids() {
        for id in [0u16, 1, 0x10, 0x0210, 0x5100, 0xF101, 0xFFFF] {
            let (mut a, mut b) = (String::new(), String::new());
            push_sensor_no(&mut a, id);
            push_hex_id(&mut b, id);
            assert_eq!(a, format!("{id:X}"));
            assert_eq!(b, format!("{id:04X}"));
        }
    }

    #[test]
    fn sample_names_and_scaling() {
        assert_eq!(d(0x0100, 6543), ("Alt".into(), "65.43".into(), "m"));
        assert_eq!(d(0x0110, 0), ("Vario".into(), "0.00".into(), "m/s"));
        assert_eq!(d(0x0200, 0), ("Amps".into(), "0.0".into(), "A"));
        assert_eq!(d(0x0210, 0), ("Volts".into(), "0.00".into(), "V"));
        assert_eq!(d(0x0110, 0xFFFF_FF6A).1, "-1.50");
        assert_eq!(d(0x010F, 100).0, "Alt", "instance nibble keeps the name");
    }

    #[test]
    fn packed_values() {
        assert_eq!(d(0x0300, 0x8188_0D30).1, "count=3 cell0=4.12 cell1=4.14");
        assert_eq!(d(0x0300, 0x0008_3432).1, "count=3 cell2=4.20");
        assert_eq!(d(0x0800, 0x8071_0700).1, "lon=12.345600");
        assert_eq!(d(0x0800, 0x4071_0700).1, "lat=-12.345600");
        assert_eq!(
            d(0x0850, 0x0E07_0BFF),
            ("Date".into(), "2014-07-11".into(), "")
        );
        assert_eq!(
            d(0x0850, 0x1629_0100),
            ("Time".into(), "22:41:01".into(), "")
        );
        assert_eq!(d(0xF104, 0x9612_0062).1, "5.07");
        assert_eq!(d(0xF101, 0x9612_005A).1, "90");
        assert_eq!(
            d(0x0006, 0xD007),
            ("Hub Cell".into(), "idx0=4.00".into(), "V")
        );
        assert_eq!(d(0x0010, 638).0, "Hub BARO_ALT_BP");
        assert_eq!(d(0x0B00, 5000 | 120 << 16).1, "RB1V=5.000V RB1A=1.20A");
        assert_eq!(d(0x0730, 0xFF9C_0064).1, "Roll=1.00deg Ptch=-1.00deg");
        assert_eq!(d(0x0E50, 5000 | 1200 << 16).1, "BecV=5.00V BecA=1.20A");
        assert_eq!(d(0x0B60, 123 | 456 << 16).1, "Erpm=12300rpm EscC=456mAh");
        assert_eq!(d(0x0B20, 0x0001_0004).1, "RBCS=CH3 KO RBS=Rx1 Ovl");
        assert_eq!(d(0x0B20, 0).1, "RBCS=OK RBS=Rx OK");
        assert_eq!(d(0x0B80, 0x101).1, "CH17 KO,S.P Ovl");
        assert_eq!(
            d(0x6800, 0x0023_4A0C).1,
            "SrvA=1.2A SrvV=7.4V SrvT=35degC SrvS=OK"
        );
        assert_eq!(d(0xF107, 20).1, "100");
        assert_eq!(d(0xF010, 5).1, "95");
    }

    #[test]
    fn unknown_ids_show_hex_label_and_raw_value() {
        assert_eq!(d(0x5100, 12345), ("5100".into(), "12345".into(), ""));
        assert_eq!(d(0x0420, 7).0, "0420");
        let mut s = String::new();
        push_sensor_no(&mut s, 0x0210);
        assert_eq!(s, "210");
    }
}
