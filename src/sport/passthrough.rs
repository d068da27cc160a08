//! ArduPilot S.Port passthrough (app IDs 0x5000-0x50FF), as ArduPilot packs it
//! (`libraries/AP_Frsky_Telem/AP_Frsky_SPort_Passthrough.cpp`, `AP_Frsky_SPort.cpp` prep_number).

use std::fmt::Write as _;

use crate::fmt::push_i64;
use crate::numbers::{push_decimal, push_uint};

/// `bits` bits of `v` starting at bit `from`.
fn field(v: u32, from: u32, bits: u32) -> u32 {
    (v >> from) & ((1u32 << bits) - 1)
}

/// A compressed number: `exp_bits` of power of ten, then `mant_bits` of mantissa, then
/// (when `signed`) a sign bit, starting at bit `from` of `v`.
fn compressed(v: u32, from: u32, exp_bits: u32, mant_bits: u32, signed: bool) -> i64 {
    let exp = field(v, from, exp_bits);
    let mant = field(v, from + exp_bits, mant_bits) as i64;
    let n = mant * 10i64.pow(exp);
    if signed && field(v, from + exp_bits + mant_bits, 1) == 1 {
        -n
    } else {
        n
    }
}

/// Starts a `key=value` field: `key_eq` is the key with its `=` (one copy, not two), after a
/// blank unless the field is the first.
#[inline]
fn kv(data: &mut String, key_eq: &str) {
    if !data.is_empty() {
        data.push(' ');
    }
    data.push_str(key_eq);
}

/// Writes the Data column of a passthrough frame and returns its Sensor label; `None` (and
/// nothing written) for an app ID without a known layout.
pub(crate) fn decode_row(app_id: u16, v: u32, data: &mut String) -> Option<&'static str> {
    let label: &'static str;
    match app_id {
        0x5000 => {
            label = "AP Text";
            text(v, data);
        }
        0x5001 => {
            label = "AP Status";
            let mode = field(v, 0, 5);
            kv(data, "mode=");
            if mode == 0 {
                data.push('?');
            } else {
                push_uint(data, (mode - 1) as u64);
            }
            // The flags follow `mode=`: each is ` name=` and one digit.
            for (bit, blank_name_eq) in [
                (5, " simple="),
                (6, " ssimple="),
                (7, " flying="),
                (8, " armed="),
                (9, " batt_fs="),
                (10, " ekf_fs="),
                (12, " fs="),
                (13, " fence="),
                (14, " breach="),
            ] {
                data.push_str(blank_name_eq);
                data.push(if field(v, bit, 1) == 1 { '1' } else { '0' });
            }
            // (2,0) signed: magnitude in bits 0-5, sign in bit 6; -63..63 = -100..100 %.
            let t = field(v, 19, 7);
            let mag = (t & 0x3F) as i64;
            let thr = if t & 0x40 != 0 { -mag } else { mag };
            kv(data, "thr=");
            push_i64(data, (thr * 100 + thr.signum() * 31) / 63);
            data.push('%');
            kv(data, "imu_temp=");
            push_uint(data, (field(v, 26, 6) + 19) as u64);
            data.push_str("degC");
        }
        0x5002 => {
            label = "AP GPS";
            kv(data, "sats=");
            push_uint(data, field(v, 0, 4) as u64);
            kv(data, "fix=");
            push_uint(data, field(v, 4, 2) as u64);
            kv(data, "hdop=");
            push_decimal(data, compressed(v, 6, 1, 7, false), 1);
            kv(data, "adv_fix=");
            push_uint(data, field(v, 14, 2) as u64);
            kv(data, "alt_msl=");
            push_decimal(data, compressed(v, 22, 2, 7, true), 1);
            data.push('m');
        }
        0x5003 | 0x5008 => {
            label = if app_id == 0x5003 {
                "AP Batt1"
            } else {
                "AP Batt2"
            };
            kv(data, "volts=");
            push_decimal(data, field(v, 0, 9) as i64, 1);
            data.push('V');
            kv(data, "amps=");
            push_decimal(data, compressed(v, 9, 1, 7, false), 1);
            data.push('A');
            kv(data, "used=");
            push_uint(data, field(v, 17, 15) as u64);
            data.push_str("mAh");
        }
        0x5004 => {
            label = "AP Home";
            kv(data, "dist=");
            push_i64(data, compressed(v, 0, 2, 10, false));
            data.push('m');
            kv(data, "alt=");
            push_decimal(data, compressed(v, 12, 2, 10, true), 1);
            data.push('m');
            kv(data, "bearing=");
            push_uint(data, field(v, 25, 7) as u64 * 3);
            data.push_str("deg");
        }
        0x5005 => {
            label = "AP Vel/Yaw";
            kv(data, "vspd=");
            push_decimal(data, compressed(v, 0, 1, 7, true), 1);
            data.push_str("m/s");
            kv(
                data,
                if field(v, 28, 1) == 1 {
                    "aspd="
                } else {
                    "hspd="
                },
            );
            push_decimal(data, compressed(v, 9, 1, 7, false), 1);
            data.push_str("m/s");
            kv(data, "yaw=");
            push_decimal(data, field(v, 17, 11) as i64 * 2, 1);
            data.push_str("deg");
        }
        0x5006 => {
            label = "AP Attitude";
            // (angle + offset) * 5 → tenths of a degree = raw * 2 - offset * 10.
            kv(data, "roll=");
            push_decimal(data, field(v, 0, 11) as i64 * 2 - 1800, 1);
            data.push_str("deg");
            kv(data, "pitch=");
            push_decimal(data, field(v, 11, 10) as i64 * 2 - 900, 1);
            data.push_str("deg");
            kv(data, "range=");
            push_i64(data, compressed(v, 21, 1, 10, false));
            data.push_str("cm");
        }
        0x5007 => {
            label = "AP Param";
            let id = field(v, 24, 8);
            kv(data, "id=");
            push_uint(data, id as u64);
            let name = match id {
                1 => Some("frame_type"),
                2 => Some("batt_fs_volt"),
                3 => Some("batt_fs_cap"),
                4 => Some("batt1_cap"),
                5 => Some("batt2_cap"),
                6 => Some("features"),
                _ => None,
            };
            if let Some(n) = name {
                data.push(' ');
                data.push_str(n);
            }
            kv(data, "value=");
            push_uint(data, field(v, 0, 24) as u64);
        }
        0x500A => {
            label = "AP RPM";
            kv(data, "rpm1=");
            push_i64(data, (v as u16 as i16) as i64 * 10);
            kv(data, "rpm2=");
            push_i64(data, ((v >> 16) as u16 as i16) as i64 * 10);
        }
        0x500B => {
            label = "AP Terrain";
            kv(data, "height=");
            push_decimal(data, compressed(v, 0, 2, 10, true), 1);
            data.push('m');
            kv(data, "unhealthy=");
            push_uint(data, field(v, 13, 1) as u64);
        }
        0x500C => {
            label = "AP Wind";
            kv(data, "dir=");
            push_uint(data, field(v, 0, 7) as u64 * 3);
            data.push_str("deg");
            kv(data, "speed=");
            push_decimal(data, compressed(v, 7, 1, 7, false), 1);
            data.push_str("m/s");
        }
        0x500D => {
            label = "AP Waypoint";
            kv(data, "num=");
            push_uint(data, field(v, 0, 11) as u64);
            kv(data, "dist=");
            push_i64(data, compressed(v, 11, 2, 10, false));
            data.push('m');
            kv(data, "bearing=");
            push_uint(data, field(v, 23, 7) as u64 * 3);
            data.push_str("deg");
        }
        _ => return None,
    }
    Some(label)
}

/// Status text: four 7-bit characters, first in bits 24-31. A zero character ends the message;
/// on the last chunk the MAVLink severity is spread over bits 23, 15 and 7.
fn text(v: u32, data: &mut String) {
    data.push('"');
    let mut ended = false;
    for shift in [24, 16, 8, 0] {
        let c = ((v >> shift) & 0x7F) as u8;
        if c == 0 {
            ended = true;
            break;
        }
        if c.is_ascii_graphic() || c == b' ' {
            data.push(c as char);
        } else {
            let _ = write!(data, "\\x{c:02X}");
        }
    }
    data.push('"');
    if ended {
        let sev = (field(v, 23, 1) << 2) | (field(v, 15, 1) << 1) | field(v, 7, 1);
        data.push_str(" end severity=");
        push_uint(data, sev as u64);
    }
}

#[cfg(test)]
mod tests {

    /// Sensor and Data of a passthrough frame, as the row mapping writes them.
    fn d(app_id: u16, v: u32) -> (String, String) {
        let (mut s, mut data) = (String::new(), String::new());
        crate::sport::values::decode(app_id, v, &mut s, &mut data);
        (s, data)
    }

    #[test]
    fn battery_and_compressed_numbers() {
        // 16.8 V, 12.3 A → (2,1): 123 > 127? no: mantissa 123, exponent 0 → 123 << 1
        let v = 168 | (123 << 1) << 9 | 1500 << 17;
        assert_eq!(d(0x5003, v).1, "volts=16.8V amps=12.3A used=1500mAh");
        // mantissa 50, exponent 1 → 500 dA = 50.0 A
        let v = 120 | ((50 << 1) | 1) << 9;
        assert_eq!(d(0x5008, v).1, "volts=12.0V amps=50.0A used=0mAh");
    }

    #[test]
    fn attitude_and_text() {
        let v = 900 | 450 << 11 | (123 << 1) << 21; // roll 0, pitch 0, 123 cm
        assert_eq!(d(0x5006, v).1, "roll=0.0deg pitch=0.0deg range=123cm");
        let v = u32::from_be_bytes([b'A', b'r', b'm', b'e']);
        assert_eq!(d(0x5000, v).1, "\"Arme\"");
        let v = u32::from_be_bytes([b'd', 0x80, 0, 0x80]); // "d", end, severity 5 (bits 23 and 7)
        assert_eq!(d(0x5000, v).1, "\"d\" end severity=5");
    }

    #[test]
    fn status_and_unknown() {
        let v = 6 | 1 << 8 | (63 << 19) | (10 << 26);
        assert_eq!(
            d(0x5001, v).1,
            "mode=5 simple=0 ssimple=0 flying=0 armed=1 batt_fs=0 ekf_fs=0 fs=0 fence=0 breach=0 thr=100% imu_temp=29degC"
        );
        // Every flag set, mode unknown (0), throttle -100 %.
        let flags = [5, 6, 7, 8, 9, 10, 12, 13, 14]
            .iter()
            .fold(0, |v, b| v | 1 << b);
        assert_eq!(
            d(0x5001, flags | (127 << 19)).1,
            "mode=? simple=1 ssimple=1 flying=1 armed=1 batt_fs=1 ekf_fs=1 fs=1 fence=1 breach=1 thr=-100% imu_temp=19degC"
        );
        assert_eq!(d(0x5099, 7), ("0x5099".into(), "7".into()));
    }
}
