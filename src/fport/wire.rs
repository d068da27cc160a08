//! F.Port wire format shared by both framings: the FrSky checksum, the 11-bit channel packing,
//! the frame bytes and encoders (for tests, the fuzz seeds and detection checks).
//!
//! F.Port v1: `7E [len][type][data][crc] 7E`, byte-stuffed (`7E -> 7D 5E`, `7D -> 7D 5D`),
//! the checksum over `len..data` (unstuffed). F.Port 2 and FBUS: `[len][type][data][crc]`, no
//! delimiters and no stuffing, the checksum over `type..data`. See `docs/fport.md`.

use crate::sport::wire::carry_sum;

/// F.Port v1 frame delimiter.
pub const START: u8 = 0x7E;
/// F.Port v1 escape byte (the next byte is XORed with 0x20).
pub const ESCAPE: u8 = 0x7D;

/// F.Port v1 control frame: length 0x19 (type, 22 channel bytes, flags, RSSI), type 0x00.
pub const V1_CONTROL_LEN: u8 = 0x19;
/// F.Port v1 telemetry frame length (type and the 7-byte S.Port payload).
pub const V1_TELEMETRY_LEN: u8 = 0x08;
/// F.Port v1 frame types: control (RX -> FC), downlink (RX -> FC: poll or request), uplink
/// (FC -> RX: answer).
pub const V1_CONTROL: u8 = 0x00;
pub const V1_DOWNLINK: u8 = 0x01;
pub const V1_UPLINK: u8 = 0x81;
/// Longest length byte an F.Port v1 frame is read with (longer ones are not frames).
pub const V1_MAX_LEN: u8 = 0x40;

/// F.Port 2 control frame lengths (channel bytes, flags, RSSI after the type byte) for 8, 16
/// and 24 channels (ArduPilot `AP_RCProtocol_FPort2.cpp`: 0x0D, 0x18, 0x23).
pub const V2_CONTROL_8: u8 = 0x0D;
pub const V2_CONTROL_16: u8 = 0x18;
pub const V2_CONTROL_24: u8 = 0x23;
/// F.Port 2 control frame type carrying channels.
pub const V2_CHANNELS: u8 = 0xFF;
/// F.Port 2 over-the-air firmware update control types (INAV `fport2.c` CFT_OTA_*).
pub const OTA_START: u8 = 0xF0;
pub const OTA_DATA: u8 = 0xF1;
pub const OTA_STOP: u8 = 0xF2;
/// Length byte of an OTA data frame (32 data bytes after the type); start and stop frames
/// use [`V2_CONTROL_16`] (24 bytes).
pub const V2_OTA_LEN: u8 = 0x20;
/// F.Port 2 telemetry frames (downlink and uplink): length 0x08, the physical ID byte and
/// the 7-byte S.Port payload.
pub const V2_TELEMETRY_LEN: u8 = 0x08;
/// Longest F.Port 2 frame on the wire: 24 channels (`23 FF` + 33 + flags + RSSI + checksum).
pub const V2_MAX_FRAME: usize = V2_CONTROL_24 as usize + 3;

/// Control flags (the SBUS flags byte).
pub const FLAG_CH17: u8 = 0x01;
pub const FLAG_CH18: u8 = 0x02;
pub const FLAG_FRAME_LOST: u8 = 0x04;
pub const FLAG_FAILSAFE: u8 = 0x08;

/// The S.Port payload inside a telemetry frame: `[frame type][app ID LE16][value LE32]`.
pub const PAYLOAD_LEN: usize = 7;

/// The FrSky checksum byte of `bytes`: `0xFF` minus their sum with end-around carry.
pub fn checksum(bytes: &[u8]) -> u8 {
    0xFF - carry_sum(bytes)
}

/// True when `bytes` (the covered bytes followed by the checksum byte) pass the check: their
/// sum with end-around carry is 0xFF.
pub fn check_ok(bytes: &[u8]) -> bool {
    carry_sum(bytes) == 0xFF
}

/// Number of bytes `n` 11-bit channels take.
pub const fn channel_bytes(n: usize) -> usize {
    (n * 11).div_ceil(8)
}

/// Unpacks `out.len()` 11-bit channels, least significant bit first (the SBUS packing), from
/// `data` (at least [`channel_bytes`] long; missing bytes read as 0).
pub fn unpack_channels(data: &[u8], out: &mut [u16]) {
    for (i, ch) in out.iter_mut().enumerate() {
        let bit = i * 11;
        let byte = bit / 8;
        let at = |k: usize| u32::from(data.get(byte + k).copied().unwrap_or(0));
        let word = at(0) | at(1) << 8 | at(2) << 16;
        *ch = ((word >> (bit % 8)) & 0x7FF) as u16;
    }
}

/// Packs 11-bit channels (higher bits dropped) into `out` (cleared first).
pub fn pack_channels(channels: &[u16], out: &mut Vec<u8>) {
    out.clear();
    out.resize(channel_bytes(channels.len()), 0);
    for (i, &ch) in channels.iter().enumerate() {
        let v = u32::from(ch & 0x7FF) << ((i * 11) % 8);
        let byte = i * 11 / 8;
        for k in 0..3 {
            if let Some(b) = out.get_mut(byte + k) {
                *b |= (v >> (8 * k)) as u8;
            }
        }
    }
}

/// Appends `byte`, stuffed as F.Port v1 (and S.Port) require.
pub fn push_stuffed(out: &mut Vec<u8>, byte: u8) {
    if byte == START || byte == ESCAPE {
        out.push(ESCAPE);
        out.push(byte ^ 0x20);
    } else {
        out.push(byte);
    }
}

/// Encodes an F.Port v1 frame `7E [len][kind][data][crc] 7E` (len = 1 + data length),
/// stuffed.
pub fn encode_v1(out: &mut Vec<u8>, kind: u8, data: &[u8]) {
    let mut body = Vec::with_capacity(data.len() + 2);
    body.push((data.len() + 1) as u8);
    body.push(kind);
    body.extend_from_slice(data);
    let crc = checksum(&body);
    body.push(crc);
    out.push(START);
    for &b in &body {
        push_stuffed(out, b);
    }
    out.push(START);
}

/// The data of a control frame: the packed channels, the flags and the RSSI byte.
pub fn control_data(channels: &[u16], flags: u8, rssi: u8) -> Vec<u8> {
    let mut data = Vec::new();
    pack_channels(channels, &mut data);
    data.push(flags);
    data.push(rssi);
    data
}

/// An F.Port v1 control frame with 16 channels.
pub fn encode_v1_control(out: &mut Vec<u8>, channels: &[u16; 16], flags: u8, rssi: u8) {
    encode_v1(out, V1_CONTROL, &control_data(channels, flags, rssi));
}

/// An F.Port v1 telemetry frame: `kind` [`V1_DOWNLINK`] or [`V1_UPLINK`].
pub fn encode_v1_telemetry(out: &mut Vec<u8>, kind: u8, payload: &[u8; PAYLOAD_LEN]) {
    encode_v1(out, kind, payload);
}

/// Encodes an F.Port 2 frame `[len][kind][data][crc]`, the checksum over `kind..data`.
pub fn encode_v2(out: &mut Vec<u8>, len: u8, kind: u8, data: &[u8]) {
    out.push(len);
    let start = out.len();
    out.push(kind);
    out.extend_from_slice(data);
    let crc = checksum(&out[start..]);
    out.push(crc);
}

/// An F.Port 2 control frame with 8, 16 or 24 channels (other counts are padded to the next).
pub fn encode_v2_control(out: &mut Vec<u8>, channels: &[u16], flags: u8, rssi: u8) {
    let (len, n) = match channels.len() {
        0..=8 => (V2_CONTROL_8, 8),
        9..=16 => (V2_CONTROL_16, 16),
        _ => (V2_CONTROL_24, 24),
    };
    let mut all = channels.to_vec();
    all.resize(n, 0);
    encode_v2(out, len, V2_CHANNELS, &control_data(&all, flags, rssi));
}

/// An F.Port 2 telemetry frame (downlink or uplink: the same bytes) for the physical ID byte
/// `phys` (the S.Port header byte with its check bits, 0x1B for the flight controller).
pub fn encode_v2_telemetry(out: &mut Vec<u8>, phys: u8, payload: &[u8; PAYLOAD_LEN]) {
    encode_v2(out, V2_TELEMETRY_LEN, phys, payload);
}

/// An S.Port payload `[kind][app ID LE16][value LE32]`.
pub fn payload(kind: u8, app_id: u16, value: u32) -> [u8; PAYLOAD_LEN] {
    let mut p = [0u8; PAYLOAD_LEN];
    p[0] = kind;
    p[1..3].copy_from_slice(&app_id.to_le_bytes());
    p[3..].copy_from_slice(&value.to_le_bytes());
    p
}

/// Betaflight's channel scale in thousandths of a µs: `5/8 * x + 880` exactly (Betaflight's
/// integer arithmetic drops the fraction).
pub fn micros_milli(raw: u16) -> i64 {
    i64::from(raw) * 625 + 880_000
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The word-wise check agrees with the byte-by-byte end-around-carry sum at every length
    /// and on the edge bytes 0x00 and 0xFF.
    #[test]
    fn check_ok_is_the_carry_sum_check() {
        let mut x = 0x2545_F491u32;
        for len in 0..70usize {
            for _ in 0..300 {
                let mut bytes: Vec<u8> = (0..len)
                    .map(|_| {
                        x ^= x << 13;
                        x ^= x >> 17;
                        x ^= x << 5;
                        match x % 4 {
                            0 => 0,
                            1 => 0xFF,
                            _ => (x >> 8) as u8,
                        }
                    })
                    .collect();
                assert_eq!(check_ok(&bytes), carry_sum(&bytes) == 0xFF, "{bytes:02X?}");
                if let Some(n) = len.checked_sub(1) {
                    // The checksum that makes them pass.
                    bytes[n] = 0xFF - carry_sum(&bytes[..n]);
                    assert!(check_ok(&bytes), "{bytes:02X?}");
                }
            }
        }
    }

    /// The v1 null poll from the F.Port documents and other drivers' tests.
    #[test]
    fn the_null_poll_checks() {
        let mut out = Vec::new();
        encode_v1_telemetry(&mut out, V1_DOWNLINK, &[0; 7]);
        assert_eq!(
            out,
            [
                0x7E, 0x08, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF6, 0x7E
            ]
        );
        assert!(check_ok(&out[1..11]));
        assert!(!check_ok(&[0x08, 0x01, 0, 0, 0, 0, 0, 0, 0, 0xF5]));
    }

    #[test]
    fn channels_pack_and_unpack() {
        let ch: Vec<u16> = (0..24).map(|i| (i * 89 + 172) as u16 & 0x7FF).collect();
        for n in [8, 16, 24] {
            let mut data = Vec::new();
            pack_channels(&ch[..n], &mut data);
            assert_eq!(data.len(), channel_bytes(n));
            let mut back = vec![0u16; n];
            unpack_channels(&data, &mut back);
            assert_eq!(back, ch[..n]);
        }
        // SBUS packing: channel 1 = 0x7FF fills byte 0 and the low 3 bits of byte 1.
        let mut data = Vec::new();
        pack_channels(&[0x7FF, 0], &mut data);
        assert_eq!(data, [0xFF, 0x07, 0x00]);
    }

    #[test]
    fn betaflight_scale() {
        assert_eq!(micros_milli(200), 1_005_000);
        assert_eq!(micros_milli(1000), 1_505_000);
        assert_eq!(micros_milli(1800), 2_005_000);
        assert_eq!(micros_milli(993), 1_500_625);
    }

    #[test]
    fn v2_checksum_leaves_out_the_length() {
        let mut out = Vec::new();
        encode_v2_telemetry(&mut out, 0x1B, &[0; 7]);
        assert_eq!(out.len(), 10);
        assert_eq!(out[9], 0xFF - 0x1B);
        assert!(check_ok(&out[1..]));
        let mut c = Vec::new();
        encode_v2_control(&mut c, &[992; 16], 0, 100);
        assert_eq!(c.len(), 27);
        assert_eq!(&c[..2], &[0x18, 0xFF]);
        assert!(check_ok(&c[1..]));
    }
}
