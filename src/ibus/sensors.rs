//! iBUS sensor types: names, units and how a measurement's bytes become a number.
//!
//! The types and scales follow Betaflight (`telemetry/ibus_shared.h`, the `IBUS_SENSOR_TYPE_*`
//! list and its comments), INAV's copy of it, and how EdgeTX shows each type
//! (`radio/src/telemetry/flysky_ibus.cpp`, its names from the `STR_SENSOR_*` strings). Types
//! 0x00-0x06 carry the names the issue fixes (`IntV`, `Temp`, `RPM`, `ExtV`, `Cels`, `Curr`,
//! `Fuel`); the table in `docs/ibus.md` lists every type with its source and where the
//! sources disagree.

use crate::numbers::Numbers;

/// How the value bytes of a measurement become numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Enc {
    /// Unsigned 16 bits, `raw / 10^prec`.
    U16,
    /// Signed 16 bits.
    S16,
    /// Temperature: `(raw - 400) / 10` °C (0 = -40.0 °C, 400 = 0.0 °C).
    Temp,
    /// Signed 32 bits.
    S32,
    /// GPS status: satellites in the high byte, fix in the low byte.
    GpsStatus,
    /// Pressure sensor, 32 bits: pressure in the low 19 bits, temperature `(v >> 19) - 400`
    /// in 0.1 °C above them (EdgeTX).
    Pressure,
    /// The sources do not settle the scale: the raw number.
    Raw,
}

/// One sensor type.
#[derive(Clone, Copy, Debug)]
pub struct SensorType {
    pub code: u8,
    /// The Sensor column.
    pub name: &'static str,
    /// The name of the first number (the Value column); the Sensor name for most types.
    pub part: &'static str,
    /// In words, for the Note.
    pub long: &'static str,
    pub unit: &'static str,
    pub prec: u8,
    pub enc: Enc,
}

const fn t(
    code: u8,
    name: &'static str,
    long: &'static str,
    unit: &'static str,
    prec: u8,
    enc: Enc,
) -> SensorType {
    SensorType {
        code,
        name,
        part: name,
        long,
        unit,
        prec,
        enc,
    }
}

/// Every type busnoop names.
pub const TYPES: &[SensorType] = &[
    t(0x00, "IntV", "internal voltage", "V", 2, Enc::U16),
    t(0x01, "Temp", "temperature", "degC", 1, Enc::Temp),
    t(0x02, "RPM", "rotation speed", "rpm", 0, Enc::U16),
    t(0x03, "ExtV", "external voltage", "V", 2, Enc::S16),
    t(0x04, "Cels", "average cell voltage", "V", 2, Enc::U16),
    t(0x05, "Curr", "battery current", "A", 2, Enc::U16),
    t(0x06, "Fuel", "fuel or battery remaining", "%", 0, Enc::U16),
    t(
        0x07,
        "RPM",
        "throttle value or battery capacity",
        "",
        0,
        Enc::U16,
    ),
    t(0x08, "Hdg", "compass heading", "deg", 0, Enc::U16),
    t(0x09, "VSpd", "climb rate", "m/s", 2, Enc::S16),
    t(0x0A, "Hdg", "course over ground", "deg", 2, Enc::U16),
    SensorType {
        part: "Sats",
        ..t(0x0B, "Sats", "GPS status", "", 0, Enc::GpsStatus)
    },
    t(0x0C, "AccX", "acceleration X", "m/s2", 2, Enc::S16),
    t(0x0D, "AccY", "acceleration Y", "m/s2", 2, Enc::S16),
    t(0x0E, "AccZ", "acceleration Z", "m/s2", 2, Enc::S16),
    t(0x0F, "Roll", "roll", "deg", 2, Enc::S16),
    t(0x10, "Ptch", "pitch", "deg", 2, Enc::S16),
    t(0x11, "Yaw", "yaw", "deg", 2, Enc::S16),
    t(0x12, "VSpd", "vertical speed", "m/s", 2, Enc::S16),
    t(0x13, "GSpd", "ground speed", "m/s", 2, Enc::U16),
    t(0x14, "Dist", "distance from home", "m", 0, Enc::U16),
    t(0x15, "Arm", "armed", "", 0, Enc::U16),
    t(0x16, "FM", "flight mode", "", 0, Enc::U16),
    t(
        0x41,
        "Pres",
        "pressure and temperature",
        "",
        0,
        Enc::Pressure,
    ),
    t(0x7C, "Odo1", "odometer 1", "", 0, Enc::Raw),
    t(0x7D, "Odo2", "odometer 2", "", 0, Enc::Raw),
    t(0x7E, "ASpd", "speed", "", 0, Enc::Raw),
    t(0x7F, "TX_V", "transmitter voltage", "V", 2, Enc::U16),
    SensorType {
        part: "Lat",
        ..t(0x80, "GPS", "GPS latitude", "deg", 7, Enc::S32)
    },
    SensorType {
        part: "Lon",
        ..t(0x81, "GPS", "GPS longitude", "deg", 7, Enc::S32)
    },
    t(0x82, "GAlt", "GPS altitude", "m", 2, Enc::S32),
    t(0x83, "Alt", "altitude", "m", 2, Enc::S32),
    t(0xF9, "Alt", "altitude (FlySky native)", "m", 0, Enc::S16),
    t(0xFA, "RSNR", "receiver SNR", "", 0, Enc::Raw),
    t(0xFB, "RNse", "receiver noise", "", 0, Enc::Raw),
    t(0xFC, "RSSI", "receiver RSSI", "", 0, Enc::Raw),
    t(0xFE, "RQly", "receiver error rate", "", 0, Enc::Raw),
];

/// The place in [`TYPES`] of every code, `u8::MAX` for the codes busnoop does not know.
static INDEX: [u8; 256] = {
    let mut index = [u8::MAX; 256];
    let mut i = 0;
    while i < TYPES.len() {
        index[TYPES[i].code as usize] = i as u8;
        i += 1;
    }
    index
};

/// The type of a code, when busnoop knows it.
#[inline]
pub fn sensor_type(code: u8) -> Option<&'static SensorType> {
    TYPES.get(usize::from(INDEX[usize::from(code)]))
}

/// The value bytes' width a type expects (2 or 4), or `None` for the raw ones.
pub fn width(enc: Enc) -> Option<usize> {
    match enc {
        Enc::U16 | Enc::S16 | Enc::Temp | Enc::GpsStatus => Some(2),
        Enc::S32 | Enc::Pressure => Some(4),
        Enc::Raw => None,
    }
}

/// The raw number of little-endian value bytes (1 to 4 bytes; more are cut to 4).
pub fn raw(value: &[u8]) -> u32 {
    let mut b = [0u8; 4];
    let n = value.len().min(4);
    b[..n].copy_from_slice(&value[..n]);
    u32::from_le_bytes(b)
}

/// Writes the numbers of a measurement of type `ty` into `nums`, the Data text into `data`
/// and remarks into `note`; returns the unit of the first number.
pub fn decode<const N: usize>(
    ty: Option<&SensorType>,
    value: &[u8],
    nums: &mut Numbers<N>,
    data: &mut String,
    note: &mut String,
) -> &'static str {
    let r = raw(value);
    let Some(s) = ty else {
        raw_value(value, r, "Raw", nums, data);
        crate::row::note_part(note).push_str("sensor type unknown (no type answer seen): raw");
        return "";
    };
    if let Some(w) = width(s.enc)
        && w != value.len()
    {
        raw_value(value, r, s.part, nums, data);
        let n = crate::row::note_part(note);
        n.push_str(s.long);
        n.push_str(" is sent in ");
        crate::numbers::push_uint(n, w as u64);
        n.push_str(" bytes, not ");
        crate::numbers::push_uint(n, value.len() as u64);
        n.push_str(": raw");
        return "";
    }
    match s.enc {
        Enc::U16 => nums.fixed(s.part, s.unit, i64::from(r as u16), s.prec),
        Enc::S16 => {
            nums.fixed(s.part, s.unit, i64::from(r as u16 as i16), s.prec);
            if s.code == 0x03 && r == 0x8000 {
                crate::row::note_part(note).push_str("0x8000: no value (Betaflight)");
            }
        }
        Enc::Temp => nums.fixed(s.part, s.unit, i64::from(r as u16) - 400, 1),
        Enc::S32 => nums.fixed(s.part, s.unit, i64::from(r as i32), s.prec),
        Enc::GpsStatus => {
            nums.int("Sats", "", i64::from(r >> 8 & 0xFF));
            nums.int("Fix", "", i64::from(r & 0xFF));
        }
        Enc::Pressure => {
            nums.int("Pres", "", i64::from(r & 0x7FFFF));
            nums.fixed("Tmp2", "degC", i64::from(r >> 19) - 400, 1);
        }
        Enc::Raw => {
            raw_value(value, r, s.part, nums, data);
            crate::row::note_part(note).push_str("the sources do not settle the scale: raw");
            return "";
        }
    }
    data.push_str(nums.first_text());
    if s.enc == Enc::GpsStatus {
        data.push_str(" satellites, fix ");
        data.push_str(nums.last_text());
    } else if s.enc == Enc::Pressure {
        data.push_str(", ");
        data.push_str(nums.last_text());
        data.push_str(" degC");
    }
    nums.first_unit()
}

/// The raw number as one part and as `0x…` in Data.
fn raw_value<const N: usize>(
    value: &[u8],
    r: u32,
    name: &'static str,
    nums: &mut Numbers<N>,
    data: &mut String,
) {
    nums.int(name, "", i64::from(r));
    data.push_str("0x");
    for &b in value.iter().take(4).rev() {
        crate::fmt::push_hex_u8(data, b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dec(code: Option<u8>, value: &[u8]) -> (String, Vec<(String, String, String)>, String) {
        let mut nums: Numbers<4> = Numbers::default();
        let (mut data, mut note) = (String::new(), String::new());
        let ty = code.and_then(sensor_type);
        decode(ty, value, &mut nums, &mut data, &mut note);
        let parts = nums.with_parts(|p| {
            p.iter()
                .map(|p| (p.name.to_owned(), p.unit.to_owned(), p.text.to_owned()))
                .collect()
        });
        (data, parts, note)
    }

    #[test]
    fn betaflight_asserted_values() {
        // telemetry_ibus_unittest.cc: 06 A1 64 00 (1.00 V on an external voltage sensor),
        // 06 A2 84 03 (50 °C), DE 03 (59 °C), 6C 07 (150 °C), 06 A3 64 00 (100 RPM).
        let p = |n: &str, u: &str, t: &str| vec![(n.to_owned(), u.to_owned(), t.to_owned())];
        assert_eq!(dec(Some(3), &[0x64, 0x00]).1, p("ExtV", "V", "1.00"));
        assert_eq!(dec(Some(3), &[0x00, 0x00]).1, p("ExtV", "V", "0.00"));
        assert_eq!(dec(Some(1), &[0x84, 0x03]).1, p("Temp", "degC", "50.0"));
        assert_eq!(dec(Some(1), &[0xDE, 0x03]).1, p("Temp", "degC", "59.0"));
        assert_eq!(dec(Some(1), &[0x6C, 0x07]).1, p("Temp", "degC", "150.0"));
        assert_eq!(dec(Some(2), &[0x64, 0x00]).1, p("RPM", "rpm", "100"));
        assert_eq!(dec(Some(0), &[0xF4, 0x01]).1, p("IntV", "V", "5.00"));
        assert_eq!(dec(Some(5), &[0xE8, 0x03]).1, p("Curr", "A", "10.00"));
        assert_eq!(dec(Some(6), &[0x4B, 0x00]).1, p("Fuel", "%", "75"));
        assert_eq!(dec(Some(3), &[0x64, 0x00]).0, "1.00");
    }

    #[test]
    fn signed_unknown_wrong_width_and_packed_values() {
        // The iBus2PPM capture's voltage sensor answers FF FF: -0.01 V read as EdgeTX does.
        assert_eq!(dec(Some(3), &[0xFF, 0xFF]).1[0].2, "-0.01");
        let (data, parts, note) = dec(None, &[0x64, 0x00]);
        assert_eq!(
            (data.as_str(), parts[0].0.as_str(), parts[0].2.as_str()),
            ("0x0064", "Raw", "100")
        );
        assert!(note.contains("unknown"));
        let (data, _, note) = dec(Some(3), &[1, 2, 3, 4]);
        assert_eq!(data, "0x04030201");
        assert!(note.contains("2 bytes, not 4"), "{note}");
        let (data, parts, _) = dec(Some(0x0B), &[0x03, 0x09]);
        assert_eq!(data, "9 satellites, fix 3");
        assert_eq!(parts.len(), 2);
        let lat = (525_200_000i32).to_le_bytes();
        assert_eq!(
            dec(Some(0x80), &lat).1[0],
            ("Lat".into(), "deg".into(), "52.5200000".into())
        );
        assert_eq!(dec(Some(0x09), &(-150i16).to_le_bytes()).1[0].2, "-1.50");
    }

    #[test]
    fn codes_are_unique_and_the_fixed_names_hold() {
        for (i, a) in TYPES.iter().enumerate() {
            assert!(
                TYPES[i + 1..].iter().all(|b| b.code != a.code),
                "{:#x}",
                a.code
            );
        }
        let names: Vec<&str> = [0, 1, 2, 3, 5, 6]
            .iter()
            .map(|&c| sensor_type(c).unwrap().name)
            .collect();
        assert_eq!(names, ["IntV", "Temp", "RPM", "ExtV", "Curr", "Fuel"]);
    }
}
