//! GHST names: devices by address, frame types (some type codes mean one thing uplink, another
//! downlink: the address tells which), RF modes and VTX bands. Sources: Betaflight
//! `rx/ghst_protocol.h`, EdgeTX `telemetry/ghost.h` and `ghost.cpp`; see `docs/ghst.md`.

/// The flight controller's address: uplink frames to it (RC, MSP requests).
pub const FC: u8 = 0x82;

/// The Device column for an address byte.
pub fn device(addr: u8) -> &'static str {
    match addr {
        0x80 => "Radio",
        0x81 => "TX module",
        0x82 => "FC",
        0x83 => "Goggles",
        0x84 => "Tee 1",
        0x85 => "Tee 2",
        0x86 => "Gateway",
        0x87 => "5G clock",
        0x88 => "TX module 115k",
        0x89 => "Receiver",
        _ => "",
    }
}

/// The Type column of frame type `ty` sent to `addr`, or `None` for a type busnoop does not
/// know. 0x13 is the channels-and-link frame to the flight controller, the menu control frame
/// to the TX module; 0x21 and 0x22 are MSP request and write to the flight controller, link
/// and VTX statistics to the radio.
pub fn frame_type(addr: u8, ty: u8) -> Option<&'static str> {
    Some(match ty {
        0x13 if addr != FC => "MenuCtrl",
        0x13 | 0x33 => "RCLink",
        0x10..=0x1F | 0x30..=0x3F => "RC",
        0x20 => "Sync",
        0x21 if addr == FC => "MSPReq",
        0x21 => "LinkStats",
        0x22 if addr == FC => "MSPWrite",
        0x22 => "VTXStats",
        0x23 => "Battery",
        0x24 => "Menu",
        0x25 => "GPS",
        0x26 => "GPS2",
        0x27 => "MagBaro",
        0x28 => "MSPResp",
        _ => return None,
    })
}

/// EdgeTX's names of the link statistics' RF modes.
pub fn rf_mode(m: u8) -> &'static str {
    [
        "Auto", "Norm", "Race", "Pure", "Long", "Unused", "Race2", "Pure2",
    ]
    .get(usize::from(m))
    .copied()
    .unwrap_or("unknown")
}

/// EdgeTX's names of the VTX bands.
pub fn vtx_band(b: u8) -> &'static str {
    ["- - -", "IRC", "Race", "BandE", "BandB", "BandA"]
        .get(usize::from(b))
        .copied()
        .unwrap_or("unknown")
}

/// Betaflight's names of the RF protocols in the channels-and-link frame (0x13/0x33).
pub fn rf_protocol(p: u8) -> &'static str {
    match p {
        0x00 => "undefined",
        0x05 => "Normal",
        0x06 => "Race",
        0x07 => "PureRace",
        0x08 => "LongRange",
        0x0A => "Race250",
        0x0B => "Race500",
        0x0C => "Solid150",
        0x0D => "Solid250",
        _ => "unknown",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn types_by_direction() {
        assert_eq!(frame_type(0x82, 0x21), Some("MSPReq"));
        assert_eq!(frame_type(0x80, 0x21), Some("LinkStats"));
        assert_eq!(frame_type(0x81, 0x13), Some("MenuCtrl"));
        assert_eq!(frame_type(0x82, 0x13), Some("RCLink"));
        assert_eq!(frame_type(0x82, 0x31), Some("RC"));
        assert_eq!(frame_type(0x82, 0x29), None);
        for a in 0..=255u8 {
            for t in 0..=255u8 {
                if let Some(n) = frame_type(a, t) {
                    assert!(super::super::vocab::TYPES.contains(&n));
                }
            }
        }
    }
}
