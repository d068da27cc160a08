//! S.Port tables of names: default devices per physical ID and frame types.

/// Default device at each physical ID (0-based), as listed in `docs/sport.md` (EdgeTX
/// `frsky_defs.h` DATA_ID_*, Pawelsky's FrSkySportTelemetry defaults, ArduPilot's and Betaflight's
/// slots). Empty where no device has that ID by default.
pub const DEVICES: [&str; 32] = [
    "Vario",     // 0
    "FLVSS",     // 1
    "FAS-40S",   // 2
    "GPS",       // 3
    "RPM",       // 4
    "SP2UART-H", // 5 SP2UART host
    "SP2UART-R", // 6 SP2UART remote
    "FCS-150A",  // 7 also ArduPilot/Betaflight extra downlink
    "",          // 8
    "ASS-70",    // 9 airspeed
    "",          // 10
    "",          // 11
    "",          // 12
    "Uplink",    // 13 radio -> flight controller (MSP, MAVlite)
    "",          // 14
    "",          // 15
    "ESC",       // 16
    "Config",    // 17 transmit header of configuration tools
    "",          // 18
    "",          // 19
    "Downlink",  // 20 ArduPilot/Betaflight extra downlink
    "",          // 21
    "Gas Suite", // 22
    "IMU",       // 23
    "Receiver",  // 24 the receiver's own RSSI/A1/A2/RxBt/SWR
    "Power Box", // 25
    "Temp",      // 26
    "FC",        // 27 flight controller (Betaflight, INAV, ArduPilot passthrough)
    "",          // 28 never polled
    "",          // 29
    "",          // 30
    "",          // 31
];

/// Device name for a physical ID.
pub fn device(phys: u8) -> &'static str {
    DEVICES[(phys & 0x1F) as usize]
}

/// The `Type` column for a frame type byte (CRC state handled by the caller).
pub fn frame_type(kind: u8) -> Option<&'static str> {
    Some(match kind {
        0x00 => "Null",
        0x10 => "Data",
        0x20 => "MaintOff",
        0x21 => "MaintOn",
        0x30 => "Read",
        0x31 => "Write",
        0x32 => "Reply",
        0x50 => "FwUpdate",
        _ => return None,
    })
}

/// Long description of a frame type, for notes and docs.
pub fn frame_type_long(kind: u8) -> &'static str {
    match kind {
        0x00 => "keep-alive without data",
        0x10 => "data",
        0x20 => "maintenance mode off",
        0x21 => "maintenance mode on",
        0x30 => "read request (config, MSP or MAVlite uplink)",
        0x31 => "write request (config, MSP)",
        0x32 => "reply (config, MSP or MAVlite downlink)",
        0x50 => "firmware update",
        _ => "unknown frame type",
    }
}
