//! CRSF names: devices by address, frame types, command frames, RF power steps, MSP commands.
//! Sources: the TBS text (`tbs-fpv/tbs-crsf-spec` `crsf.md`), ExpressLRS and Betaflight
//! headers; see `docs/crsf.md`.

/// The Device column for an address byte (the TBS "Device Addresses" list; 0xEF is
/// ExpressLRS's Lua address; 0x20-0x7F is the dynamic NAT range).
pub fn device(addr: u8) -> &'static str {
    match addr {
        0x00 => "Broadcast",
        0x0E => "Cloud",
        0x10 => "USB",
        0x12 => "Bluetooth",
        0x13 => "WiFi RX",
        0x14 => "VRX",
        0x20..=0x7F => "NAT",
        0x80 => "OSD",
        0x8A | 0xCA | 0xF0 | 0xF2 => "Reserved",
        0x90 => "ESC1",
        0x91 => "ESC2",
        0x92 => "ESC3",
        0x93 => "ESC4",
        0x94 => "ESC5",
        0x95 => "ESC6",
        0x96 => "ESC7",
        0x97 => "ESC8",
        0xB0 | 0xB2 => "Crossfire",
        0xC0 => "Current sensor",
        0xC2 => "GPS",
        0xC4 => "Blackbox",
        0xC8 => "FC",
        0xCC => "Race tag",
        0xCE => "VTX",
        0xEA => "Radio",
        0xEC => "Receiver",
        0xEE => "TX module",
        0xEF => "ELRS Lua",
        _ => "",
    }
}

/// The Type column of a frame type, or `None` for a type busnoop does not know.
pub fn frame_type(ty: u8) -> Option<&'static str> {
    Some(match ty {
        0x02 => "GPS",
        0x03 => "GPSTime",
        0x06 => "GPSExt",
        0x07 => "Vario",
        0x08 => "Battery",
        0x09 => "Baro",
        0x0A => "Airspeed",
        0x0B => "Heartbeat",
        0x0C => "RPM",
        0x0D => "Temp",
        0x0E => "Voltages",
        0x10 => "VTX",
        0x14 => "LinkStats",
        0x16 => "RC",
        0x17 => "RCSubset",
        0x18 => "RC11",
        0x1C => "LinkRX",
        0x1D => "LinkTX",
        0x1E => "Attitude",
        0x1F => "MAVLinkFC",
        0x21 => "FlightMode",
        0x22 => "ESPNow",
        0x28 => "Ping",
        0x29 => "DeviceInfo",
        0x2B => "ParamEntry",
        0x2C => "ParamRead",
        0x2D => "ParamWrite",
        0x2E => "ELRSStatus",
        0x32 => "Command",
        0x34 => "Logging",
        0x3A => "Radio",
        0x3C => "Game",
        0x78 | 0x79 => "KISS",
        0x7A => "MSPReq",
        0x7B => "MSPResp",
        0x7C => "MSPWrite",
        0x7F => "APLegacy",
        0x80 => "APPassthru",
        0x81 | 0x82 => "mLRS",
        0xAA => "MAVLink",
        0xAC => "MAVSysStatus",
        _ => return None,
    })
}

/// Whether frames of type `ty` carry `[destination][origin]` after the type ("extended": 0x28
/// and up, except the logging frame 0x34, which the TBS text says has the short header; and
/// the ArduPilot, mLRS and MAVLink broadcast frames 0x7F-0x82, 0xAA and 0xAC).
pub fn extended(ty: u8) -> bool {
    ty >= 0x28 && !matches!(ty, 0x34 | 0x7F..=0x82 | 0xAA | 0xAC)
}

/// Uplink transmit power of link statistics (0x14) in mW by its index (TBS text, EdgeTX).
pub const RF_POWER_MW: [u16; 9] = [0, 10, 25, 100, 500, 1000, 2000, 250, 50];

/// A command frame's (0x32) command and sub-command names.
pub fn command(cmd: u8, sub: u8) -> (&'static str, Option<&'static str>) {
    let (group, name) = match (cmd, sub) {
        (0xFF, _) => ("ACK", None),
        (0x01, 0x01) => ("FC", Some("force disarm")),
        (0x01, 0x02) => ("FC", Some("scale channel")),
        (0x01, _) => ("FC", None),
        (0x03, 0x01) => ("Bluetooth", Some("reset")),
        (0x03, 0x02) => ("Bluetooth", Some("enable")),
        (0x03, 0x64) => ("Bluetooth", Some("echo")),
        (0x03, _) => ("Bluetooth", None),
        (0x05, 0x01) => ("OSD", Some("send buttons")),
        (0x05, _) => ("OSD", None),
        (0x08, 0x01) => ("VTX", Some("change channel")),
        (0x08, 0x02) => ("VTX", Some("set frequency")),
        (0x08, 0x03) => ("VTX", Some("change power")),
        (0x08, 0x04) => ("VTX", Some("pit mode on power up")),
        (0x08, 0x05) => ("VTX", Some("power up from pit mode")),
        (0x08, 0x06) => ("VTX", Some("set dynamic power")),
        (0x08, 0x08) => ("VTX", Some("set power")),
        (0x08, _) => ("VTX", None),
        (0x09, 0x01) => ("LED", Some("set to default")),
        (0x09, 0x02) => ("LED", Some("override colour")),
        (0x09, 0x03) => ("LED", Some("override pulse")),
        (0x09, 0x04) => ("LED", Some("override blink")),
        (0x09, 0x05) => ("LED", Some("override shift")),
        (0x09, _) => ("LED", None),
        (0x0A, 0x70) => ("General", Some("speed proposal")),
        (0x0A, 0x71) => ("General", Some("speed response")),
        (0x0A, _) => ("General", None),
        (0x10, 0x01) => ("Crossfire", Some("bind")),
        (0x10, 0x02) => ("Crossfire", Some("cancel bind")),
        (0x10, 0x03) => ("Crossfire", Some("set bind ID")),
        (0x10, 0x05) => ("Crossfire", Some("model selection")),
        (0x10, 0x06) => ("Crossfire", Some("query model selection")),
        (0x10, 0x07) => ("Crossfire", Some("current model")),
        (0x10, _) => ("Crossfire", None),
        (0x20, 0x01) => ("Flow control", Some("subscribe")),
        (0x20, 0x02) => ("Flow control", Some("unsubscribe")),
        (0x20, _) => ("Flow control", None),
        (0x22, 0x01) => ("Screen", Some("pop-up message")),
        (0x22, 0x02) => ("Screen", Some("selection return value")),
        (0x22, _) => ("Screen", None),
        _ => ("", None),
    };
    (group, name)
}

/// A parameter's data type (0x2B entries), without the hidden bit.
pub fn param_type(t: u8) -> &'static str {
    match t & 0x7F {
        0 => "UINT8",
        1 => "INT8",
        2 => "UINT16",
        3 => "INT16",
        4 => "UINT32",
        5 => "INT32",
        8 => "FLOAT",
        9 => "TEXT_SELECTION",
        10 => "STRING",
        11 => "FOLDER",
        12 => "INFO",
        13 => "COMMAND",
        127 => "OUT_OF_RANGE",
        _ => "unknown type",
    }
}

/// An MSP command's name (MSPv1 ids of Betaflight's `msp_protocol.h`), or `None`.
pub fn msp(cmd: u16) -> Option<&'static str> {
    Some(match cmd {
        1 => "MSP_API_VERSION",
        2 => "MSP_FC_VARIANT",
        3 => "MSP_FC_VERSION",
        4 => "MSP_BOARD_INFO",
        5 => "MSP_BUILD_INFO",
        10 => "MSP_NAME",
        11 => "MSP_SET_NAME",
        32 => "MSP_BATTERY_CONFIG",
        33 => "MSP_SET_BATTERY_CONFIG",
        34 => "MSP_MODE_RANGES",
        35 => "MSP_SET_MODE_RANGE",
        36 => "MSP_FEATURE_CONFIG",
        37 => "MSP_SET_FEATURE_CONFIG",
        42 => "MSP_MIXER_CONFIG",
        43 => "MSP_SET_MIXER_CONFIG",
        44 => "MSP_RX_CONFIG",
        45 => "MSP_SET_RX_CONFIG",
        54 => "MSP_CF_SERIAL_CONFIG",
        55 => "MSP_SET_CF_SERIAL_CONFIG",
        68 => "MSP_REBOOT",
        70 => "MSP_DATAFLASH_SUMMARY",
        84 => "MSP_OSD_CONFIG",
        85 => "MSP_SET_OSD_CONFIG",
        88 => "MSP_VTX_CONFIG",
        89 => "MSP_SET_VTX_CONFIG",
        99 => "MSP_SET_ARMING_DISABLED",
        101 => "MSP_STATUS",
        102 => "MSP_RAW_IMU",
        103 => "MSP_SERVO",
        104 => "MSP_MOTOR",
        105 => "MSP_RC",
        106 => "MSP_RAW_GPS",
        107 => "MSP_COMP_GPS",
        108 => "MSP_ATTITUDE",
        109 => "MSP_ALTITUDE",
        110 => "MSP_ANALOG",
        111 => "MSP_RC_TUNING",
        112 => "MSP_PID",
        116 => "MSP_BOXNAMES",
        119 => "MSP_BOXIDS",
        130 => "MSP_BATTERY_STATE",
        131 => "MSP_MOTOR_CONFIG",
        150 => "MSP_STATUS_EX",
        160 => "MSP_UID",
        200 => "MSP_SET_RAW_RC",
        202 => "MSP_SET_PID",
        204 => "MSP_SET_RC_TUNING",
        205 => "MSP_ACC_CALIBRATION",
        206 => "MSP_MAG_CALIBRATION",
        214 => "MSP_SET_MOTOR",
        246 => "MSP_SET_RTC",
        247 => "MSP_RTC",
        250 => "MSP_EEPROM_WRITE",
        253 => "MSP_DEBUGMSG",
        254 => "MSP_DEBUG",
        255 => "MSP_V2_FRAME",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_known_type_is_in_the_vocabulary() {
        for ty in 0..=255u8 {
            if let Some(n) = frame_type(ty) {
                assert!(super::super::vocab::TYPES.contains(&n), "{n}");
            }
        }
        assert_eq!(frame_type(0x16), Some("RC"));
        assert!(extended(0x29) && extended(0x32) && !extended(0x21) && !extended(0x80));
        assert_eq!(command(0x0A, 0x70), ("General", Some("speed proposal")));
        assert_eq!(device(0xC8), "FC");
        assert_eq!(msp(101), Some("MSP_STATUS"));
    }
}
