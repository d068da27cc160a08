//! GHST frames as numbers: the RC frames' channels in µs on Betaflight's scales, the
//! telemetry named as EdgeTX names the Ghost sensors (see `docs/ghst.md`). Telemetry numbers
//! are little-endian (Betaflight writes them with `sbufWriteU16`), the radio's sync frame
//! big-endian (EdgeTX reads it "hifirst").

use super::names;
use crate::crsf::ext::msp;
use crate::crsf::link::{Described, Scratch};
use crate::crsf::read::{Reader, push_text};
use crate::crsf::values::{channels, note_length};
use crate::crsf::wire::unpack_bits;
use crate::fmt::{push_0x, push_hex, push_u64};
use crate::row::Class;

/// The µs of a primary (12-bit) channel, ×100: frame types 0x30-0x3F `988 + v / 4`; the legacy
/// types 0x10-0x1F first rescale `(5v >> 2) - 430` (Betaflight `ghst.c`). Centre 1984 (legacy)
/// or 2048 → 1500 µs.
pub fn primary_us100(v: u16, legacy: bool) -> i64 {
    let v = i64::from(v);
    let v = if legacy { ((5 * v) >> 2) - 430 } else { v };
    98_800 + v * 25
}

/// The µs of an 8-bit aux channel: `988 + 4a`, legacy `880 + 5a`. Centre 128 (124 legacy) →
/// 1500 µs.
pub fn aux_us(a: u8, legacy: bool) -> i64 {
    let a = i64::from(a);
    if legacy { 880 + 5 * a } else { 988 + 4 * a }
}

/// Describes a GHST frame whose CRC passed.
pub(crate) fn describe(addr: u8, ty: u8, payload: &[u8], sc: &mut Scratch) -> Described {
    let kind = names::frame_type(addr, ty).unwrap_or("Unknown");
    let mut d = Described::plain(kind);
    let mut r = Reader::new(payload);
    match kind {
        "RC" | "RCLink" => rc(ty, payload, sc, &mut d),
        "MenuCtrl" => push_hex(&mut sc.data, payload),
        "Sync" => {
            if let Some(v) = r.be_u32() {
                sc.nums.fixed("Intv", "us", v.into(), 1);
            }
            if let Some(v) = r.be_i32() {
                sc.nums.fixed("Offs", "us", v.into(), 1);
            }
            sc.note().push_str("timing correction");
        }
        "MSPReq" | "MSPWrite" | "MSPResp" => msp(payload, sc),
        "LinkStats" => {
            let n = &mut sc.nums;
            if let Some(v) = r.u8() {
                n.int("RSSI", "dBm", -i64::from(v));
            }
            if let Some(v) = r.u8() {
                n.int("RQly", "%", v.into());
                d.lq = Some(v);
            }
            if let Some(v) = r.u8() {
                n.int("RSNR", "dB", v.into());
            }
            if let Some(v) = r.be_u16() {
                n.int("TPWR", "mW", v.into());
            }
            if let Some(v) = r.be_u16() {
                n.int("FRat", "Hz", v.into());
            }
            if let Some(v) = r.be_u16() {
                n.int("TLat", "us", v.into());
            }
            if let Some(m) = r.u8() {
                n.int("RFMD", "", m.into());
                let note = sc.note();
                note.push_str("RF mode ");
                note.push_str(names::rf_mode(m));
            }
            note_length(sc, &r, 10);
        }
        "VTXStats" => {
            let _flags = r.u8();
            let n = &mut sc.nums;
            if let Some(v) = r.be_u16() {
                n.int("VFrq", "MHz", v.into());
            }
            if let Some(v) = r.be_u16() {
                n.int("VPwr", "mW", v.into());
            }
            let band = r.u8();
            if let Some(c) = r.u8() {
                sc.nums.int("VChn", "", c.into());
            }
            if let Some(b) = band {
                let note = sc.note();
                note.push_str("band ");
                note.push_str(names::vtx_band(b));
            }
        }
        "Battery" => {
            let n = &mut sc.nums;
            if let Some(v) = r.le_u16() {
                n.fixed("RxBt", "V", v.into(), 2);
            }
            if let Some(v) = r.le_u16() {
                n.fixed("Curr", "A", v.into(), 2);
            }
            if let Some(v) = r.le_u16() {
                n.int("Capa", "mAh", i64::from(v) * 10);
            }
            if let Some(v) = r.u8() {
                n.fixed("RxV", "V", v.into(), 1);
            }
        }
        "Menu" => {
            if let (Some(status), Some(flags), Some(line)) = (r.u8(), r.u8(), r.u8()) {
                let t = r.rest();
                let end = t.iter().position(|&b| b == 0).unwrap_or(t.len());
                let data = &mut sc.data;
                data.push_str("line ");
                push_u64(data, line.into());
                data.push_str(" \"");
                push_text(data, &t[..end]);
                data.push('"');
                let note = sc.note();
                note.push_str("menu status ");
                push_u64(note, status.into());
                note.push_str(", flags ");
                push_0x(note, flags);
            }
        }
        "GPS" => {
            sc.sensor.push_str("GPS");
            let n = &mut sc.nums;
            if let Some(v) = r.le_i32() {
                n.fixed("Lat", "deg", v.into(), 7);
            }
            if let Some(v) = r.le_i32() {
                n.fixed("Lon", "deg", v.into(), 7);
            }
            if let Some(v) = r.le_i16() {
                n.int("Alt", "m", v.into());
            }
        }
        "GPS2" => {
            let n = &mut sc.nums;
            if let Some(v) = r.le_u16() {
                // cm/s to km/h in tenths, rounded as EdgeTX does.
                n.fixed("GSpd", "km/h", (i64::from(v) * 36 + 50) / 100, 1);
            }
            if let Some(v) = r.le_u16() {
                n.fixed("Hdg", "deg", v.into(), 1);
            }
            if let Some(v) = r.u8() {
                n.int("Sats", "", v.into());
            }
            if let Some(v) = r.le_u16() {
                n.int("Dist", "m", i64::from(v) * 10);
            }
            if let Some(v) = r.le_u16() {
                n.fixed("HDir", "deg", v.into(), 1);
            }
            if let Some(f) = r.u8() {
                let note = sc.note();
                note.push_str(if f & 1 != 0 { "fix" } else { "no fix" });
                note.push_str(if f & 2 != 0 {
                    ", home set"
                } else {
                    ", no home"
                });
            }
        }
        "MagBaro" => {
            let (head, alt, vario) = (r.le_i16(), r.le_i16(), r.i8());
            let _reserved = (r.le_u16(), r.le_u16());
            let flags = r.u8().unwrap_or(0);
            let n = &mut sc.nums;
            if let (Some(v), true) = (head, flags & 1 != 0) {
                n.fixed("MHdg", "deg", v.into(), 1);
            }
            if let (Some(v), true) = (alt, flags & 2 != 0) {
                n.int("BAlt", "m", v.into());
            }
            if let (Some(v), true) = (vario, flags & 4 != 0) {
                n.fixed("VSpd", "m/s", v.into(), 2);
            }
            if flags & 7 != 7 {
                let note = sc.note();
                note.push_str("flags ");
                push_0x(note, flags);
                note.push_str(": only the fields flagged valid are shown");
            }
        }
        _ => {
            push_hex(&mut sc.data, payload);
            d.class = Class::Warning;
            let note = sc.note();
            note.push_str("unknown frame type ");
            push_0x(note, ty);
        }
    }
    d
}

/// An RC frame: channels 1-4 (12 bits each, packed little-endian) in every frame, then four aux
/// channels of 8 bits (0x10/0x30: CH5-8, 0x11/0x31: CH9-12, 0x12/0x32: CH13-16) or, in 0x13/0x33,
/// link quality, RSSI, RF protocol and transmit power.
fn rc(ty: u8, payload: &[u8], sc: &mut Scratch, d: &mut Described) {
    let legacy = ty < 0x30;
    let mut raw = [0u16; 4];
    unpack_bits(payload, 12, 4, &mut raw);
    channels(sc, 0, &raw, "raw", |v| (primary_us100(v, legacy), 2));
    let rest = payload.get(6..).unwrap_or(&[]);
    let start = match ty & 0x0F {
        0 => Some(4),
        1 => Some(8),
        2 => Some(12),
        _ => None,
    };
    match (ty & 0x0F, start) {
        (_, Some(first)) => {
            let aux: Vec<u16> = rest.iter().take(4).map(|&a| u16::from(a)).collect();
            channels(sc, first, &aux, "aux raw", |a| (aux_us(a as u8, legacy), 0));
        }
        (3, None) => {
            let mut r = Reader::new(rest);
            let n = &mut sc.nums;
            if let Some(v) = r.u8() {
                n.int("RQly", "%", v.into());
                d.lq = Some(v);
            }
            if let Some(v) = r.u8() {
                n.int("RSSI", "dBm", -i64::from(v));
            }
            let proto = r.u8();
            if let Some(p) = proto {
                n.int("RFMD", "", p.into());
            }
            if let Some(v) = r.i8() {
                sc.nums.int("TPWR", "dBm", v.into());
            }
            if let Some(p) = proto {
                let note = sc.note();
                note.push_str("RF protocol ");
                note.push_str(names::rf_protocol(p));
            }
        }
        _ => {
            let note = sc.note();
            note.push_str("frame type ");
            push_0x(note, ty);
            note.push_str(" not known: only CH1-4 read");
        }
    }
    let note = sc.note();
    note.push_str(if legacy {
        "legacy scale"
    } else {
        "12-bit scale"
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn betaflight_scales() {
        // ghst.c's table: legacy 344/1984/3622 (the 11-bit 172/992/1811 doubled) and 12-bit
        // 0/2048/4096; aux legacy 22/124/226, 12-bit 0/128/255.
        assert_eq!(primary_us100(1984, true), 150_050);
        assert_eq!(primary_us100(344, true), 98_800);
        assert_eq!(primary_us100(2048, false), 150_000);
        assert_eq!(primary_us100(0, false), 98_800);
        assert_eq!(primary_us100(4095, false), 201_175);
        assert_eq!([22, 124, 226].map(|a| aux_us(a, true)), [990, 1500, 2010]);
        assert_eq!([0, 128, 255].map(|a| aux_us(a, false)), [988, 1500, 2008]);
    }
}
