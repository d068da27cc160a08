//! CRSF broadcast frames (types below 0x28: telemetry and RC channels) as numbers, named as
//! EdgeTX names its sensors, in the units EdgeTX and Betaflight show (see `docs/crsf.md` for
//! every field and where the TBS text says otherwise).

use super::link::{Described, Scratch};
use super::names;
use super::read::{Reader, push_text};
use super::wire::unpack_bits;
use crate::fmt::{push_0x, push_hex, push_u64};
use crate::numbers::push_uint;

/// The channels of an RC frame in µs on Betaflight's scale: `0.62477120195241 * raw + 881`,
/// rounded to the nearest µs (172 → 988, 992 → 1501, 1811 → 2012).
pub fn channel_us(raw: u16) -> i64 {
    (0.624_771_201_952_41 * f64::from(raw) + 881.0).round() as i64
}

/// Writes the parts `CH<first+1>`… of `raw` channels with `us` giving each one's µs as
/// `(value, decimals)`, the raw values into the Note (`<label> 172 992 …`), and the µs values
/// into a compact Data cell.
pub(crate) fn channels(
    sc: &mut Scratch,
    first: usize,
    raw: &[u16],
    label: &str,
    us: impl Fn(u16) -> (i64, u8),
) {
    let note = sc.note();
    note.push_str(label);
    for &r in raw {
        note.push(' ');
        push_uint(note, u64::from(r));
    }
    for (i, &r) in raw.iter().enumerate() {
        let (v, prec) = us(r);
        sc.nums
            .fixed_with(|n| channel_name(n, first + i + 1), "us", v, prec);
        if !sc.data.is_empty() {
            sc.data.push(' ');
        }
        sc.data.push_str(sc.nums.last_text());
    }
}

/// `CH<n>`.
fn channel_name(out: &mut String, n: usize) {
    out.push_str("CH");
    push_uint(out, n as u64);
}

/// RSSI in dBm from a link-statistics byte. The TBS text and Betaflight send `dBm * -1` (a
/// positive byte, 62 for -62 dBm); EdgeTX reads the byte as a signed number, which is right for
/// senders that put the negative dBm value itself (0xC2 for -62). Both readings give a value of
/// 0 or below: a byte of 128 or more is taken as signed, a smaller one as `dBm * -1`.
pub fn rssi_dbm(b: u8) -> i64 {
    if b >= 0x80 {
        i64::from(b as i8)
    } else {
        -i64::from(b)
    }
}

/// Notes payload bytes beyond the fields read (a newer sender: the TBS text says to ignore
/// them), or a payload too short for them.
pub(crate) fn note_length(sc: &mut Scratch, r: &Reader<'_>, want: usize) {
    let got = r.pos + r.rest().len();
    if got < want {
        let note = sc.note();
        note.push_str("short payload: ");
        push_u64(note, got as u64);
        note.push_str(" of ");
        push_u64(note, want as u64);
        note.push_str(" bytes");
    } else if got > want {
        let note = sc.note();
        push_u64(note, (got - want) as u64);
        note.push_str(" bytes more than the fields: ");
        push_hex(
            note,
            &r.rest()[r.rest().len() - (got - want).min(r.rest().len())..],
        );
    }
}

/// Describes a broadcast frame of type `ty` (below 0x28); `None` for a type this module does
/// not decode.
pub(crate) fn broadcast(ty: u8, payload: &[u8], sc: &mut Scratch) -> Option<Described> {
    let mut r = Reader::new(payload);
    let kind = names::frame_type(ty).unwrap_or("Unknown");
    let mut d = Described::plain(kind);
    let n = &mut sc.nums;
    match ty {
        0x02 => {
            sc.sensor.push_str("GPS");
            if let Some(v) = r.be_i32() {
                n.fixed("Lat", "deg", v.into(), 7);
            }
            if let Some(v) = r.be_i32() {
                n.fixed("Lon", "deg", v.into(), 7);
            }
            if let Some(v) = r.be_u16() {
                n.fixed("GSpd", "km/h", v.into(), 1);
            }
            if let Some(v) = r.be_u16() {
                n.fixed("Hdg", "deg", v.into(), 2);
            }
            if let Some(v) = r.be_u16() {
                n.int("Alt", "m", i64::from(v) - 1000);
            }
            if let Some(v) = r.u8() {
                n.int("Sats", "", v.into());
            }
            note_length(sc, &r, 15);
        }
        0x03 => {
            sc.sensor.push_str("Date");
            gps_time(&mut r, &mut sc.data);
            note_length(sc, &r, 9);
        }
        0x06 => {
            if let Some(v) = r.u8() {
                n.int("Fix", "", v.into());
            }
            for (name, unit, prec) in [
                ("NSpd", "m/s", 2),
                ("ESpd", "m/s", 2),
                ("GVSp", "m/s", 2),
                ("SAcc", "m/s", 2),
                ("TAcc", "deg", 1),
                ("EAlt", "m", 0),
                ("HAcc", "m", 2),
                ("VAcc", "m", 2),
            ] {
                if let Some(v) = r.be_i16() {
                    n.fixed(name, unit, v.into(), prec);
                }
            }
            let _reserved = r.u8();
            if let Some(v) = r.u8() {
                n.fixed("HDOP", "", v.into(), 1);
            }
            if let Some(v) = r.u8() {
                n.fixed("VDOP", "", v.into(), 1);
            }
            note_length(sc, &r, 22);
        }
        0x07 => {
            if let Some(v) = r.be_i16() {
                n.fixed("VSpd", "m/s", v.into(), 2);
            }
            note_length(sc, &r, 2);
        }
        0x08 => {
            if let Some(v) = r.be_i16() {
                n.fixed("RxBt", "V", v.into(), 1);
            }
            if let Some(v) = r.be_i16() {
                n.fixed("Curr", "A", v.into(), 1);
            }
            if let Some(v) = r.be_u24() {
                n.int("Capa", "mAh", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("Bat%", "%", v.into());
            }
            note_length(sc, &r, 8);
        }
        0x09 => baro(&mut r, sc),
        0x0A => {
            if let Some(v) = r.be_u16() {
                n.fixed("ASpd", "km/h", v.into(), 1);
            }
            note_length(sc, &r, 2);
        }
        0x0B => {
            if let Some(v) = r.be_i16() {
                let a = v as u8;
                sc.data.push_str("from ");
                let name = names::device(a);
                if !name.is_empty() {
                    sc.data.push_str(name);
                    sc.data.push(' ');
                }
                sc.data.push('(');
                push_0x(&mut sc.data, a);
                sc.data.push(')');
            }
            note_length(sc, &r, 2);
        }
        0x0C => group(&mut r, sc, "RPM", "rpm", 3, 0),
        0x0D => group(&mut r, sc, "Tmp", "degC", 2, 1),
        0x0E => group(&mut r, sc, "Cel", "V", 2, 3),
        0x10 => vtx(&mut r, sc),
        0x14 => {
            for name in ["1RSS", "2RSS"] {
                if let Some(v) = r.u8() {
                    n.int(name, "dBm", rssi_dbm(v));
                }
            }
            if let Some(v) = r.u8() {
                n.int("RQly", "%", v.into());
                d.lq = Some(v);
            }
            if let Some(v) = r.i8() {
                n.int("RSNR", "dB", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("ANT", "", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("RFMD", "", v.into());
            }
            if let Some(v) = r.u8() {
                match names::RF_POWER_MW.get(v as usize) {
                    Some(&mw) => n.int("TPWR", "mW", mw.into()),
                    None => {
                        let note = sc.note();
                        note.push_str("TPWR: unknown power index ");
                        push_u64(note, v.into());
                    }
                }
            }
            let n = &mut sc.nums;
            if let Some(v) = r.u8() {
                n.int("TRSS", "dBm", rssi_dbm(v));
            }
            if let Some(v) = r.u8() {
                n.int("TQly", "%", v.into());
            }
            if let Some(v) = r.i8() {
                n.int("TSNR", "dB", v.into());
            }
            note_length(sc, &r, 10);
        }
        0x16 => {
            let mut raw = [0u16; 16];
            unpack_bits(payload, 11, 16, &mut raw);
            channels(sc, 0, &raw, "raw", |r| (channel_us(r), 0));
            if payload.len() != 22 {
                let note = sc.note();
                note.push_str("payload of ");
                push_u64(note, payload.len() as u64);
                note.push_str(" bytes, 22 expected");
            }
        }
        0x17 => subset(payload, sc),
        0x18 => {
            let mut raw = [0u16; 16];
            unpack_bits(payload, 11, 16, &mut raw);
            channels(sc, 0, &raw, "raw", |r| (9880 + i64::from(r) * 5, 1));
        }
        0x1C => {
            if let Some(v) = r.u8() {
                n.int("RRSS", "dBm", rssi_dbm(v));
            }
            if let Some(v) = r.u8() {
                n.int("RRSP", "%", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("RQly", "%", v.into());
                d.lq = Some(v);
            }
            if let Some(v) = r.i8() {
                n.int("RSNR", "dB", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("TPWR", "dBm", v.into());
            }
            note_length(sc, &r, 5);
        }
        0x1D => {
            if let Some(v) = r.u8() {
                n.int("TRSS", "dBm", rssi_dbm(v));
            }
            if let Some(v) = r.u8() {
                n.int("TRSP", "%", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("TQly", "%", v.into());
            }
            if let Some(v) = r.i8() {
                n.int("TSNR", "dB", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("RPWR", "dBm", v.into());
            }
            if let Some(v) = r.u8() {
                n.int("TFPS", "Hz", i64::from(v) * 10);
            }
            note_length(sc, &r, 6);
        }
        0x1E => {
            for name in ["Ptch", "Roll", "Yaw"] {
                if let Some(v) = r.be_i16() {
                    n.fixed(name, "rad", v.into(), 4);
                }
            }
            note_length(sc, &r, 6);
        }
        0x1F => {
            let data = &mut sc.data;
            if let Some(v) = r.be_i16() {
                data.push_str("airspeed=");
                crate::fmt::push_i64(data, v.into());
            }
            if let Some(v) = r.u8() {
                data.push_str(" base_mode=");
                push_0x(data, v);
            }
            if let Some(v) = r.be_u32() {
                data.push_str(" custom_mode=");
                push_u64(data, v.into());
            }
            if let Some(v) = r.u8() {
                data.push_str(" autopilot=");
                push_u64(data, v.into());
            }
            if let Some(v) = r.u8() {
                data.push_str(" type=");
                push_u64(data, v.into());
            }
            note_length(sc, &r, 9);
        }
        0x21 => {
            sc.sensor.push_str("FM");
            let (text, terminated) = r.cstr();
            push_text(&mut sc.data, text);
            if !terminated {
                sc.note().push_str("no NUL at the end of the text");
            } else if !r.rest().is_empty() {
                let note = sc.note();
                note.push_str("after the NUL: ");
                push_hex(note, r.rest());
            }
        }
        0x22 => {
            let data = &mut sc.data;
            if let Some(v) = r.u8() {
                data.push_str("seat ");
                push_u64(data, v.into());
            }
            if let Some(v) = r.u8() {
                data.push_str(" lap ");
                push_u64(data, v.into());
            }
            for n in [15, 15, 20] {
                let Some(t) = r
                    .bytes(n)
                    .or_else(|| (!r.rest().is_empty()).then(|| r.rest()))
                else {
                    break;
                };
                let end = t.iter().position(|&b| b == 0).unwrap_or(t.len());
                data.push_str(" \"");
                push_text(data, &t[..end]);
                data.push('"');
                if t.len() < n {
                    break;
                }
            }
        }
        _ => return None,
    }
    Some(d)
}

/// GPS time (0x03): `year month day hour minute second millisecond`.
fn gps_time(r: &mut Reader<'_>, data: &mut String) {
    let two = |data: &mut String, v: u8| {
        if v < 10 {
            data.push('0');
        }
        push_u64(data, v.into());
    };
    if let Some(y) = r.be_i16() {
        crate::fmt::push_i64(data, y.into());
    }
    // Month, day, hour, minute, second, each after its separator.
    for sep in ['-', '-', ' ', ':', ':'] {
        if let Some(v) = r.u8() {
            data.push(sep);
            two(data, v);
        }
    }
    if let Some(ms) = r.be_u16() {
        data.push('.');
        let ms = u64::from(ms);
        if ms < 100 {
            data.push('0');
        }
        if ms < 10 {
            data.push('0');
        }
        push_u64(data, ms);
    }
}

/// Barometric altitude (0x09). The altitude is packed: bit 15 set, metres; clear, decimetres
/// plus 10000. The vertical speed has two readings, chosen by the payload's length: 3 bytes,
/// the TBS text's logarithmic int8; 4 bytes or more, EdgeTX's int16 in cm/s.
fn baro(r: &mut Reader<'_>, sc: &mut Scratch) {
    let n = &mut sc.nums;
    let len = r.rest().len();
    if let Some(p) = r.be_u16() {
        let dm = if p & 0x8000 != 0 {
            i64::from(p & 0x7FFF) * 10
        } else {
            i64::from(p) - 10_000
        };
        n.fixed("BAlt", "m", dm, 1);
    }
    match len {
        3 => {
            if let Some(v) = r.i8() {
                n.fixed("VSpd", "m/s", vspeed_cm_s(v), 2);
                sc.note().push_str("vertical speed: TBS logarithmic int8");
            }
        }
        4.. => {
            if let Some(v) = r.be_i16() {
                n.fixed("VSpd", "m/s", v.into(), 2);
                sc.note().push_str("vertical speed: EdgeTX int16 cm/s");
            }
        }
        _ => {}
    }
    note_length(sc, r, len.clamp(2, 4));
}

/// The TBS text's logarithmic vertical speed (cm/s): `(e^(|v| * 0.026) - 1) * 100`, signed,
/// truncated as the C reference does.
pub fn vspeed_cm_s(v: i8) -> i64 {
    let mag = ((f64::from(v.unsigned_abs()) * 0.026).exp() - 1.0) * 100.0;
    let mag = mag as i64;
    if v < 0 { -mag } else { mag }
}

/// A source ID and a list of values (RPM 0x0C: int24; temperatures 0x0D: int16 deci-degrees;
/// voltages 0x0E: uint16 mV), named `<base><n>` from 1, with `_<source>` added when the source
/// is not 0. Voltages from sources 0-127 are cells (`Cel1`…`Cel9`, `Cl10`…, as EdgeTX names
/// cells), from 128 up general voltages (`Volt1`…).
fn group(
    r: &mut Reader<'_>,
    sc: &mut Scratch,
    base: &str,
    unit: &'static str,
    size: usize,
    prec: u8,
) {
    let Some(src) = r.u8() else {
        sc.note().push_str("empty payload");
        return;
    };
    let cells = base == "Cel";
    let mut i = 0u64;
    while r.rest().len() >= size {
        let v = match size {
            3 => r.be_i24().map(i64::from),
            2 if cells => r.be_u16().map(i64::from),
            _ => r.be_i16().map(i64::from),
        };
        let Some(v) = v else { break };
        i += 1;
        sc.nums.fixed_with(
            |out| {
                if cells && src >= 128 {
                    out.push_str("Volt");
                } else if cells && i >= 10 {
                    out.push_str("Cl");
                } else {
                    out.push_str(base);
                }
                push_uint(out, i);
                if src != 0 {
                    out.push('_');
                    push_uint(out, src.into());
                }
            },
            unit,
            v,
            prec,
        );
    }
    let note = sc.note();
    note.push_str("source ");
    push_uint(note, src.into());
    if !r.rest().is_empty() {
        note.push_str(", ");
        push_u64(note, r.rest().len() as u64);
        note.push_str(" bytes left over");
    }
}

/// VTX telemetry (0x10): origin, power in dBm, frequency in MHz, pit-mode bits (read from the
/// least significant bit: pit mode, 2 bits control, 4 bits switch).
fn vtx(r: &mut Reader<'_>, sc: &mut Scratch) {
    let origin = r.u8();
    if let Some(v) = r.u8() {
        sc.nums.int("VPwr", "dBm", v.into());
    }
    if let Some(v) = r.be_u16() {
        sc.nums.int("VFrq", "MHz", v.into());
    }
    let pit = r.u8();
    let note = sc.note();
    if let Some(o) = origin {
        note.push_str("from ");
        note.push_str(names::device(o));
        note.push_str(" (");
        push_0x(note, o);
        note.push(')');
    }
    if let Some(p) = pit {
        note.push_str(if p & 1 != 0 {
            ", pit mode on"
        } else {
            ", pit mode off"
        });
        note.push_str(", control ");
        note.push_str(["off", "on", "switch", "failsafe"][usize::from((p >> 1) & 3)]);
        note.push_str(", switch ");
        push_uint(note, u64::from((p >> 3) & 0x0F));
    }
}

/// Subset RC channels (0x17): a configuration byte (starting channel in bits 0-4, resolution
/// in bits 5-6: 10, 11, 12 or 13 bits, digital-switch flag in bit 7), then as many channels of
/// that resolution as fit; µs = 988 + raw × (1, ½, ¼ or ⅛), Betaflight's and the TBS text's
/// conversion.
fn subset(payload: &[u8], sc: &mut Scratch) {
    let Some((&conf, rest)) = payload.split_first() else {
        sc.note().push_str("empty payload");
        return;
    };
    let start = usize::from(conf & 0x1F);
    let res = u32::from((conf >> 5) & 3);
    let bits = 10 + res;
    let count = (rest.len() * 8 / bits as usize).min(crate::crsf::link::MAX_NUMBERS);
    let mut raw = [0u16; crate::crsf::link::MAX_NUMBERS];
    unpack_bits(rest, bits, count, &mut raw);
    // µs × 10^res exactly: 988 + raw / 2^res.
    let scale = [1i64, 5, 25, 125][res as usize];
    let base = [988i64, 9_880, 98_800, 988_000][res as usize];
    channels(sc, start, &raw[..count], "raw", |r| {
        (base + i64::from(r) * scale, res as u8)
    });
    let note = sc.note();
    note.push_str("first channel CH");
    push_uint(note, start as u64 + 1);
    note.push_str(", ");
    push_uint(note, bits.into());
    note.push_str(" bits");
    if conf & 0x80 != 0 {
        note.push_str(", digital switch flag set");
    }
    if start + count > 16 {
        note.push_str(", channels beyond CH16 (Betaflight drops the frame)");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn betaflight_channel_scale() {
        assert_eq!(
            [172, 992, 1811, 189, 993, 978, 983].map(channel_us),
            [988, 1501, 2012, 999, 1501, 1492, 1495]
        );
        // Betaflight computes in float32: every raw value rounds the same way.
        for raw in 0..2048u16 {
            let f = (0.624_771_2_f32 * f32::from(raw) + 881.0).round() as i64;
            assert_eq!(f, channel_us(raw), "{raw}");
        }
    }

    #[test]
    fn rssi_readings() {
        assert_eq!(
            [62, 0xC2, 0, 0x80, 127].map(rssi_dbm),
            [-62, -62, 0, -128, -127]
        );
    }

    #[test]
    fn logarithmic_vertical_speed() {
        // The TBS text: ±2500 cm/s range, 3 cm/s steps at low speed.
        assert_eq!(vspeed_cm_s(0), 0);
        assert_eq!(vspeed_cm_s(1), 2);
        assert_eq!(vspeed_cm_s(-1), -2);
        assert!((2400..2600).contains(&vspeed_cm_s(125)));
    }
}
