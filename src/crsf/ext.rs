//! CRSF extended frames (type 0x28 and up: `[destination][origin]` first) and the envelopes of
//! other protocols: device ping and information, parameters, command frames with their inner
//! CRC (a baud-rate change is announced in the Note), the radio's timing frame, MSP requests
//! and responses (the MSP command named), ArduPilot passthrough, MAVLink.

use super::link::{Described, Scratch};
use super::names;
use super::read::{Reader, push_text};
use super::wire::{COMMAND, command_crc8};
use crate::fmt::{push_0x, push_0x16, push_hex, push_i64, push_u64};
use crate::numbers::push_uint;
use crate::row::Class;

/// What the extended frames remember between frames (bounded: one entry per address or port).
pub(crate) struct State {
    /// Per origin address: the parameter number and chunks remaining of its last entry frame
    /// (0x2B), to tell a continuation chunk from a first one.
    chunks: Box<[Option<(u8, u8)>; 256]>,
    /// Per port: the baud rate last proposed (command 0x0A.0x70).
    proposals: Box<[Option<u32>; 256]>,
}

impl Default for State {
    fn default() -> Self {
        State {
            chunks: Box::new([None; 256]),
            proposals: Box::new([None; 256]),
        }
    }
}

/// `name (0xNN)` of an address.
fn push_device(out: &mut String, addr: u8) {
    let name = names::device(addr);
    if !name.is_empty() {
        out.push_str(name);
        out.push(' ');
    }
    out.push('(');
    push_0x(out, addr);
    out.push(')');
}

/// Describes an extended frame of type `ty`; the payload starts with destination and origin.
pub(crate) fn extended(ty: u8, payload: &[u8], sc: &mut Scratch, st: &mut State) -> Described {
    let kind = names::frame_type(ty).unwrap_or("Unknown");
    let mut d = Described::plain(kind);
    let mut r = Reader::new(payload);
    let (Some(dest), Some(origin)) = (r.u8(), r.u8()) else {
        sc.note().push_str("no destination and origin");
        push_hex(&mut sc.data, payload);
        return d;
    };
    {
        let note = sc.note();
        note.push_str("from ");
        push_device(note, origin);
        note.push_str(" to ");
        push_device(note, dest);
    }
    match ty {
        0x28 => sc.data.push_str("ping"),
        0x29 => device_info(&mut r, sc),
        0x2B => param_entry(&mut r, origin, sc, st),
        0x2C => {
            if let (Some(p), Some(c)) = (r.u8(), r.u8()) {
                sc.data.push_str("read parameter ");
                push_u64(&mut sc.data, p.into());
                sc.data.push_str(" chunk ");
                push_u64(&mut sc.data, c.into());
            }
        }
        0x2D => {
            if let Some(p) = r.u8() {
                sc.data.push_str("write parameter ");
                push_u64(&mut sc.data, p.into());
                let v = r.rest();
                sc.data.push_str(" value ");
                match v.len() {
                    1 => push_u64(&mut sc.data, v[0].into()),
                    4 => push_i64(
                        &mut sc.data,
                        i32::from_be_bytes([v[0], v[1], v[2], v[3]]).into(),
                    ),
                    _ => push_hex(&mut sc.data, v),
                }
            }
        }
        COMMAND => return command(payload, sc, st),
        0x3A => radio(&mut r, sc),
        0x3C => match (r.u8(), r.be_u16()) {
            (Some(1), Some(p)) => {
                sc.data.push_str("add points ");
                push_i64(&mut sc.data, (p as i16).into());
            }
            (Some(2), Some(c)) => {
                sc.data.push_str("command code ");
                push_0x16(&mut sc.data, c);
            }
            _ => push_hex(&mut sc.data, &payload[2..]),
        },
        0x7A..=0x7C => msp(r.rest(), sc),
        _ => {
            push_hex(&mut sc.data, r.rest());
            if names::frame_type(ty).is_none() {
                d.class = Class::Warning;
                let note = sc.note();
                note.push_str("unknown frame type ");
                push_0x(note, ty);
            }
        }
    }
    d
}

/// Device information (0x29): name, serial number, hardware and firmware IDs, parameter count
/// and version. ExpressLRS puts "ELRS" as the serial number and its version in the firmware
/// ID's last three bytes (as EdgeTX reads it).
fn device_info(r: &mut Reader<'_>, sc: &mut Scratch) {
    let (name, _) = r.cstr();
    let data = &mut sc.data;
    data.push('"');
    push_text(data, name);
    data.push('"');
    let serial = r.bytes(4);
    let hw = r.be_u32();
    let fw = r.bytes(4);
    if let Some(s) = serial {
        data.push_str(" serial ");
        if s == b"ELRS" {
            data.push_str("ELRS");
        } else {
            push_hex(data, s);
        }
    }
    if let Some(h) = hw {
        data.push_str(" hw 0x");
        for b in h.to_be_bytes() {
            crate::fmt::push_hex_u8(data, b);
        }
    }
    if let Some(f) = fw {
        data.push_str(" fw ");
        if serial == Some(b"ELRS") {
            push_u64(data, f[1].into());
            data.push('.');
            push_u64(data, f[2].into());
            data.push('.');
            push_u64(data, f[3].into());
        } else {
            push_hex(data, f);
        }
    }
    if let Some(n) = r.u8() {
        data.push_str(", ");
        push_u64(data, n.into());
        data.push_str(" parameters");
    }
    if let Some(v) = r.u8() {
        data.push_str(", version ");
        push_u64(data, v.into());
    }
}

/// A parameter entry (0x2B): number, chunks remaining, and for a first chunk the parent
/// folder, data type (bit 7: hidden) and name; the value of a FLOAT, TEXT_SELECTION, STRING or
/// INFO entry when it is in this chunk.
fn param_entry(r: &mut Reader<'_>, origin: u8, sc: &mut Scratch, st: &mut State) {
    let (Some(param), Some(left)) = (r.u8(), r.u8()) else {
        sc.note().push_str("short parameter entry");
        return;
    };
    let prev = st.chunks[origin as usize];
    st.chunks[origin as usize] = Some((param, left));
    let data = &mut sc.data;
    data.push_str("parameter ");
    push_u64(data, param.into());
    let continuation = matches!(prev, Some((p, l)) if p == param && l > 0 && l == left + 1);
    if continuation {
        data.push_str(" continued: ");
        push_hex(data, r.rest());
    } else if let (Some(parent), Some(t)) = (r.u8(), r.u8()) {
        let (name, _) = r.cstr();
        data.push_str(" \"");
        push_text(data, name);
        data.push_str("\" ");
        data.push_str(names::param_type(t));
        if t & 0x80 != 0 {
            data.push_str(" hidden");
        }
        data.push_str(" in folder ");
        push_u64(data, parent.into());
        if left == 0 {
            param_value(t & 0x7F, r, data);
        }
    }
    if left > 0 {
        let note = sc.note();
        push_u64(note, left.into());
        note.push_str(" chunks to come");
    }
}

/// The value part of a one-chunk parameter entry.
fn param_value(t: u8, r: &mut Reader<'_>, data: &mut String) {
    match t {
        8 => {
            if let (Some(v), Some(min), Some(max), Some(_def), Some(point)) =
                (r.be_i32(), r.be_i32(), r.be_i32(), r.be_i32(), r.u8())
            {
                let p = point.min(9);
                data.push_str(" = ");
                crate::fmt::push_fixed(data, v.into(), p);
                data.push_str(" (");
                crate::fmt::push_fixed(data, min.into(), p);
                data.push_str("..");
                crate::fmt::push_fixed(data, max.into(), p);
                data.push(')');
                let _step = r.be_i32();
                let (unit, _) = r.cstr();
                if !unit.is_empty() {
                    data.push(' ');
                    push_text(data, unit);
                }
            }
        }
        9 => {
            let (options, _) = r.cstr();
            if let Some(v) = r.u8() {
                data.push_str(" = ");
                match options.split(|&b| b == b';').nth(v.into()) {
                    Some(o) => {
                        data.push('"');
                        push_text(data, o);
                        data.push('"');
                    }
                    None => push_u64(data, v.into()),
                }
                data.push_str(" of \"");
                push_text(data, options);
                data.push('"');
            }
        }
        10 | 12 => {
            let (v, _) = r.cstr();
            data.push_str(" = \"");
            push_text(data, v);
            data.push('"');
        }
        13 => {
            if let Some(s) = r.u8() {
                data.push_str(" status ");
                data.push_str(match s {
                    0 => "READY",
                    1 => "START",
                    2 => "PROGRESS",
                    3 => "CONFIRMATION_NEEDED",
                    4 => "CONFIRM",
                    5 => "CANCEL",
                    6 => "POLL",
                    _ => "unknown",
                });
                let _timeout = r.u8();
                let (info, _) = r.cstr();
                if !info.is_empty() {
                    data.push_str(" \"");
                    push_text(data, info);
                    data.push('"');
                }
            }
        }
        _ => {}
    }
}

/// A command frame (0x32): `dest origin command sub data inner-crc`; the inner CRC (polynomial
/// 0xBA) covers type … data.
fn command(payload: &[u8], sc: &mut Scratch, st: &mut State) -> Described {
    let mut d = Described::plain("Command");
    if payload.len() < 4 {
        push_hex(&mut sc.data, &payload[2.min(payload.len())..]);
        sc.note().push_str("too short for a command and its CRC");
        d.class = Class::Warning;
        return d;
    }
    let (body, inner) = payload.split_at(payload.len() - 1);
    let mut covered = [0u8; 64];
    covered[0] = COMMAND;
    covered[1..=body.len()].copy_from_slice(body);
    let want = command_crc8(&covered[..=body.len()]);
    let cmd = body[2];
    let sub = body.get(3).copied();
    let (group, name) = names::command(cmd, sub.unwrap_or(0));
    match name {
        Some(n) => sc.sensor.push_str(n),
        None if !group.is_empty() => sc.sensor.push_str(group),
        None => {}
    }
    let data = &mut sc.data;
    push_0x(data, cmd);
    if let Some(s) = sub {
        data.push('.');
        push_0x(data, s);
    }
    if !group.is_empty() {
        data.push(' ');
        data.push_str(group);
    }
    let args = body.get(4..).unwrap_or(&[]);
    if !args.is_empty() {
        data.push_str(": ");
        push_hex(data, args);
    }
    if inner[0] != want {
        d.class = Class::Warning;
        d.inner_crc_error = true;
        let note = sc.note();
        note.push_str("command CRC ");
        push_0x(note, inner[0]);
        note.push_str(", expected ");
        push_0x(note, want);
        return d;
    }
    let mut a = Reader::new(args);
    match (cmd, sub) {
        (0x0A, Some(0x70)) => {
            if let (Some(port), Some(baud)) = (a.u8(), a.be_u32()) {
                st.proposals[port as usize] = Some(baud);
                let note = sc.note();
                note.push_str("baud rate change proposed: port ");
                push_uint(note, port.into());
                note.push_str(" to ");
                push_u64(note, baud.into());
                note.push_str(" baud");
            }
        }
        (0x0A, Some(0x71)) => {
            if let (Some(port), Some(ok)) = (a.u8(), a.u8()) {
                let note = sc.note();
                note.push_str("baud rate change ");
                note.push_str(if ok != 0 { "accepted" } else { "rejected" });
                note.push_str(": port ");
                push_uint(note, port.into());
                if ok != 0 {
                    match st.proposals[port as usize] {
                        Some(b) => {
                            note.push_str(", the line now runs at ");
                            push_u64(note, b.into());
                            note.push_str(
                                " baud (busnoop keeps its rate: start again with --baud ",
                            );
                            push_u64(note, b.into());
                            note.push(')');
                        }
                        None => note.push_str(", the line speed changes"),
                    }
                    // busnoop keeps its rate: what follows will not decode.
                    d.class = Class::Warning;
                }
            }
        }
        (0xFF, _) => {
            if let (Some(c), Some(s), Some(action)) = (sub, a.u8(), a.u8()) {
                let note = sc.note();
                note.push_str("ACK of ");
                push_0x(note, c);
                note.push('.');
                push_0x(note, s);
                note.push_str(if action != 0 { ": done" } else { ": not done" });
                let (info, _) = a.cstr();
                if !info.is_empty() {
                    note.push_str(" \"");
                    push_text(note, info);
                    note.push('"');
                }
            }
        }
        _ => {}
    }
    d
}

/// The radio's frame (0x3A): sub-type 0x10 is the timing correction ("CRSF shot"): update
/// interval and offset in 100 ns units, shown in µs.
fn radio(r: &mut Reader<'_>, sc: &mut Scratch) {
    match r.u8() {
        Some(0x10) => {
            if let Some(v) = r.be_u32() {
                sc.nums.fixed("Intv", "us", v.into(), 1);
            }
            if let Some(v) = r.be_i32() {
                sc.nums.fixed("Offs", "us", v.into(), 1);
            }
            sc.note().push_str("timing correction");
        }
        Some(s) => {
            push_0x(&mut sc.data, s);
            sc.data.push(' ');
            push_hex(&mut sc.data, r.rest());
        }
        None => {}
    }
}

/// MSP over CRSF (0x7A request, 0x7B response, 0x7C write): a status byte (bits 0-3 sequence,
/// bit 4 start of an MSP frame, bits 5-6 MSP version, bit 7 error), then a chunk of the MSP
/// body without `$M<`/`$X<` and checksum. A start chunk names the MSP command.
pub(crate) fn msp(body: &[u8], sc: &mut Scratch) {
    let Some((&status, rest)) = body.split_first() else {
        sc.note().push_str("no MSP status byte");
        return;
    };
    let seq = status & 0x0F;
    let start = status & 0x10 != 0;
    let version = (status >> 5) & 3;
    let mut cmd = None;
    if start {
        let mut r = Reader::new(rest);
        cmd = match version {
            1 => match (r.u8(), r.u8()) {
                (Some(_size), Some(c)) => Some(u16::from(c)),
                _ => None,
            },
            2 => match (r.u8(), r.le_u16()) {
                (Some(_flags), Some(c)) => Some(c),
                _ => None,
            },
            _ => None,
        };
    }
    if let Some(c) = cmd {
        match names::msp(c) {
            Some(n) => sc.sensor.push_str(n),
            None => {
                sc.sensor.push_str("MSP ");
                push_uint(&mut sc.sensor, c.into());
            }
        }
    }
    let data = &mut sc.data;
    data.push_str("MSPv");
    push_uint(data, version.into());
    data.push_str(" seq ");
    push_uint(data, seq.into());
    if start {
        data.push_str(" start");
    }
    if status & 0x80 != 0 {
        data.push_str(" error");
    }
    if let Some(c) = cmd {
        data.push_str(" cmd ");
        push_uint(data, c.into());
    }
    if !rest.is_empty() {
        data.push_str(": ");
        push_hex(data, rest);
    }
}

/// ArduPilot's passthrough frame (0x80): sub-type 0xF0 one S.Port passthrough packet, 0xF2 up
/// to nine, 0xF1 a status text. ArduPilot writes these packed structures in the flight
/// controller's byte order (little-endian), unlike the rest of CRSF.
pub(crate) fn ardupilot(payload: &[u8], sc: &mut Scratch) {
    let mut r = Reader::new(payload);
    let data = &mut sc.data;
    match r.u8() {
        Some(0xF0) => {
            data.push_str("single");
            if let (Some(app), Some(v)) = (r.le_u16(), r.le_u32()) {
                data.push_str(" app ");
                push_0x16(data, app);
                data.push_str(" value ");
                push_u64(data, v.into());
            }
        }
        Some(0xF2) => {
            let n = r.u8().unwrap_or(0);
            data.push_str("multi ");
            push_uint(data, n.into());
            for _ in 0..n {
                let (Some(app), Some(v)) = (r.le_u16(), r.le_u32()) else {
                    break;
                };
                data.push_str(", app ");
                push_0x16(data, app);
                data.push_str(" value ");
                push_u64(data, v.into());
            }
        }
        Some(0xF1) => {
            data.push_str("status text");
            if let Some(sev) = r.u8() {
                data.push_str(" severity ");
                push_uint(data, sev.into());
            }
            let (t, _) = r.cstr();
            data.push_str(" \"");
            push_text(data, t);
            data.push('"');
        }
        Some(s) => {
            push_0x(data, s);
            data.push(' ');
            push_hex(data, r.rest());
        }
        None => {}
    }
}

/// The MAVLink envelope (0xAA): total chunks (high nibble) and this chunk (low nibble), the data
/// size, the data (payload kept in the Data cell).
pub(crate) fn mavlink(payload: &[u8], sc: &mut Scratch) {
    let mut r = Reader::new(payload);
    let (Some(chunks), Some(size)) = (r.u8(), r.u8()) else {
        push_hex(&mut sc.data, payload);
        sc.note().push_str("too short for a MAVLink envelope");
        return;
    };
    let data = &mut sc.data;
    data.push_str("chunk ");
    push_uint(data, u64::from(chunks & 0x0F));
    data.push_str(" of ");
    push_uint(data, u64::from(chunks >> 4));
    data.push_str(", ");
    push_uint(data, size.into());
    data.push_str(" bytes: ");
    let bytes = r.rest();
    push_hex(data, &bytes[..usize::from(size).min(bytes.len())]);
    if usize::from(size) > bytes.len() {
        let note = sc.note();
        note.push_str("data size ");
        push_uint(note, size.into());
        note.push_str(" but ");
        push_uint(note, bytes.len() as u64);
        note.push_str(" bytes in the frame");
    }
    match bytes {
        [0xFD, _, _, _, _, sys, comp, a, b, c, ..] => {
            let id = u32::from_le_bytes([*a, *b, *c, 0]);
            mav_note(sc, 2, id.into(), *sys, *comp);
        }
        [0xFE, _, _, sys, comp, id, ..] => mav_note(sc, 1, (*id).into(), *sys, *comp),
        _ => {}
    }
}

fn mav_note(sc: &mut Scratch, v: u8, id: u64, sys: u8, comp: u8) {
    let note = sc.note();
    note.push_str("MAVLink ");
    push_uint(note, v.into());
    note.push_str(" message ");
    push_u64(note, id);
    note.push_str(" from system ");
    push_uint(note, sys.into());
    note.push_str(" component ");
    push_uint(note, comp.into());
}
