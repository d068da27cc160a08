//! The public function codes of the MODBUS Application Protocol Specification V1.1b3: names,
//! which may be broadcast, and the length of a request and of a response as the frame's own
//! bytes give it (fixed, or a byte count field, or a walk through Read Device Identification's
//! objects). Exception codes and diagnostics sub-functions by name.

/// Largest RTU frame (address, PDU of at most 253 bytes, CRC).
pub const MAX_FRAME: usize = 256;
/// Smallest RTU frame: address, function code, CRC.
pub const MIN_FRAME: usize = 4;
/// Highest unicast slave address (248-255 are reserved).
pub const MAX_SLAVE: u8 = 247;
/// MEI type of Read Device Identification (function 43 / 14).
pub const MEI_DEVICE_ID: u8 = 0x0E;

/// Which way a frame goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    Request,
    Response,
}

/// How long a frame is, as far as its first bytes tell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Len {
    /// The whole frame, CRC included.
    Known(usize),
    /// A length field lies beyond the bytes given.
    Need,
    /// No frame of this direction starts with these bytes.
    No,
}

/// The name of a public function code, or "".
pub fn name(fc: u8) -> &'static str {
    match fc {
        1 => "Read Coils",
        2 => "Read Discrete Inputs",
        3 => "Read Holding Registers",
        4 => "Read Input Registers",
        5 => "Write Single Coil",
        6 => "Write Single Register",
        7 => "Read Exception Status",
        8 => "Diagnostics",
        11 => "Get Comm Event Counter",
        12 => "Get Comm Event Log",
        15 => "Write Multiple Coils",
        16 => "Write Multiple Registers",
        17 => "Report Server ID",
        20 => "Read File Record",
        21 => "Write File Record",
        22 => "Mask Write Register",
        23 => "Read/Write Multiple Registers",
        24 => "Read FIFO Queue",
        43 => "Read Device Identification",
        _ => "",
    }
}

/// Every public function code, in order.
pub const PUBLIC: [u8; 19] = [
    1, 2, 3, 4, 5, 6, 7, 8, 11, 12, 15, 16, 17, 20, 21, 22, 23, 24, 43,
];

/// Whether `fc` is a public function code busnoop frames.
pub fn is_public(fc: u8) -> bool {
    !name(fc).is_empty()
}

/// Functions that may be sent to address 0 (every slave, no response): the writes.
pub fn broadcastable(fc: u8) -> bool {
    matches!(fc, 5 | 6 | 15 | 16 | 21 | 22)
}

/// The name of an exception code, or "".
pub fn exception_name(code: u8) -> &'static str {
    match code {
        1 => "Illegal Function",
        2 => "Illegal Data Address",
        3 => "Illegal Data Value",
        4 => "Server Device Failure",
        5 => "Acknowledge",
        6 => "Server Device Busy",
        8 => "Memory Parity Error",
        0x0A => "Gateway Path Unavailable",
        0x0B => "Gateway Target Device Failed to Respond",
        _ => "",
    }
}

/// The name of a Diagnostics (function 8) sub-function, or "".
pub fn diagnostic_name(sub: u16) -> &'static str {
    match sub {
        0 => "Return Query Data",
        1 => "Restart Communications Option",
        2 => "Return Diagnostic Register",
        3 => "Change ASCII Input Delimiter",
        4 => "Force Listen Only Mode",
        10 => "Clear Counters and Diagnostic Register",
        11 => "Return Bus Message Count",
        12 => "Return Bus Communication Error Count",
        13 => "Return Bus Exception Error Count",
        14 => "Return Server Message Count",
        15 => "Return Server No Response Count",
        16 => "Return Server NAK Count",
        17 => "Return Server Busy Count",
        18 => "Return Bus Character Overrun Count",
        20 => "Clear Overrun Counter and Flag",
        _ => "",
    }
}

/// A length read from a byte count at `b[at]`: `extra + count`, when `ok(count)`.
fn counted(b: &[u8], at: usize, extra: usize, ok: impl Fn(usize) -> bool) -> Len {
    match b.get(at) {
        None => Len::Need,
        Some(&n) if ok(n as usize) => within(extra + n as usize),
        Some(_) => Len::No,
    }
}

fn within(n: usize) -> Len {
    if n <= MAX_FRAME {
        Len::Known(n)
    } else {
        Len::No
    }
}

/// The length of the frame that starts with `b` (address, function code, …) read as `dir`.
/// Byte counts must be plausible for their function (register data even and not empty, …): a
/// reading that breaks the specification's own rules is no reading.
pub fn frame_len(b: &[u8], dir: Dir) -> Len {
    let (Some(&addr), Some(&fc)) = (b.first(), b.get(1)) else {
        return Len::Need;
    };
    if addr > MAX_SLAVE {
        return Len::No;
    }
    if fc & 0x80 != 0 {
        // An exception: address, function | 0x80, code, CRC.
        return if dir == Dir::Response && addr != 0 && is_public(fc & 0x7F) {
            Len::Known(5)
        } else {
            Len::No
        };
    }
    if addr == 0 && (dir == Dir::Response || !broadcastable(fc)) {
        return Len::No;
    }
    let even = |n: usize| n >= 2 && n.is_multiple_of(2) && n <= 250;
    match (fc, dir) {
        (1..=6 | 8, Dir::Request) => Len::Known(8),
        (1 | 2, Dir::Response) => counted(b, 2, 5, |n| (1..=250).contains(&n)),
        (3 | 4 | 23, Dir::Response) => counted(b, 2, 5, even),
        (5 | 6 | 8 | 11 | 15 | 16, Dir::Response) => Len::Known(8),
        (7, Dir::Response) => Len::Known(5),
        (7 | 11 | 12 | 17, Dir::Request) => Len::Known(4),
        (12, Dir::Response) => counted(b, 2, 5, |n| (6..=250).contains(&n)),
        (15, Dir::Request) => counted(b, 6, 9, |n| (1..=246).contains(&n)),
        (16, Dir::Request) => counted(b, 6, 9, even),
        (17, Dir::Response) => counted(b, 2, 5, |n| (1..=250).contains(&n)),
        (20, Dir::Request) => counted(b, 2, 5, |n| (7..=245).contains(&n) && n % 7 == 0),
        (20 | 21, Dir::Response) | (21, Dir::Request) => {
            counted(b, 2, 5, |n| (7..=245).contains(&n))
        }
        (22, _) => Len::Known(10),
        (23, Dir::Request) => counted(b, 10, 13, even),
        (24, Dir::Request) => Len::Known(6),
        (24, Dir::Response) => match (b.get(2), b.get(3)) {
            (Some(&hi), Some(&lo)) => {
                let n = u16::from_be_bytes([hi, lo]) as usize;
                if even(n) { within(6 + n) } else { Len::No }
            }
            _ => Len::Need,
        },
        (43, _) => match b.get(2) {
            None => Len::Need,
            Some(&MEI_DEVICE_ID) if dir == Dir::Request => Len::Known(7),
            Some(&MEI_DEVICE_ID) => device_id_len(b),
            Some(_) => Len::No,
        },
        _ => Len::No,
    }
}

/// Whether the whole frame `b` (CRC included) read as `dir` keeps the specification's limits
/// on quantities and values (MODBUS Application Protocol V1.1b3 §6): a read of 1-2000 coils or
/// 1-125 registers, a coil written as 0xFF00 or 0x0000, a byte count that fits the quantity.
/// A slave answers a request outside them with an exception, so a master does not send one:
/// bytes that check only by chance (one place in 65,536) mostly fail this too.
pub fn plausible(b: &[u8], dir: Dir) -> bool {
    let word = |i: usize| match (b.get(i), b.get(i + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]) as usize,
        _ => 0,
    };
    let (Some(&fc), Some(&count_byte)) = (b.get(1), b.get(6)) else {
        return true;
    };
    match (fc, dir) {
        (1 | 2, Dir::Request) => (1..=2000).contains(&word(4)),
        (3 | 4, Dir::Request) => (1..=125).contains(&word(4)),
        (5, _) => matches!(word(4), 0xFF00 | 0x0000),
        (15, Dir::Request) => {
            (1..=1968).contains(&word(4)) && count_byte as usize == word(4).div_ceil(8)
        }
        (16, Dir::Request) => (1..=123).contains(&word(4)) && count_byte as usize == 2 * word(4),
        (15, Dir::Response) => (1..=1968).contains(&word(4)),
        (16, Dir::Response) => (1..=123).contains(&word(4)),
        (23, Dir::Request) => {
            (1..=125).contains(&word(4))
                && (1..=121).contains(&word(8))
                && b.get(10).is_some_and(|&n| n as usize == 2 * word(8))
        }
        _ => true,
    }
}

/// Read Device Identification's response: 8 header bytes (address, 43, 14, read code,
/// conformity, more follows, next object, number of objects), the objects (id, length, value),
/// the CRC.
fn device_id_len(b: &[u8]) -> Len {
    let Some(&objects) = b.get(7) else {
        return Len::Need;
    };
    let mut at = 8;
    for _ in 0..objects {
        let Some(&len) = b.get(at + 1) else {
            return Len::Need;
        };
        at += 2 + len as usize;
        if at + 2 > MAX_FRAME {
            return Len::No;
        }
    }
    within(at + 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_of_every_public_function() {
        use Dir::*;
        let k = Len::Known;
        // requests
        for fc in [1u8, 2, 3, 4, 5, 6, 8] {
            assert_eq!(frame_len(&[1, fc], Request), k(8), "{fc}");
        }
        for fc in [7u8, 11, 12, 17] {
            assert_eq!(frame_len(&[1, fc], Request), k(4), "{fc}");
        }
        assert_eq!(frame_len(&[1, 15, 0, 0, 0, 9, 2], Request), k(11));
        assert_eq!(frame_len(&[1, 16, 0, 0, 0, 2, 4], Request), k(13));
        assert_eq!(frame_len(&[1, 16, 0, 0, 0, 2, 3], Request), Len::No);
        assert_eq!(frame_len(&[1, 20, 14], Request), k(19));
        assert_eq!(frame_len(&[1, 20, 13], Request), Len::No);
        assert_eq!(frame_len(&[1, 21, 13], Request), k(18));
        assert_eq!(frame_len(&[1, 22], Request), k(10));
        assert_eq!(
            frame_len(&[1, 23, 0, 0, 0, 1, 0, 0, 0, 1, 2], Request),
            k(15)
        );
        assert_eq!(frame_len(&[1, 24], Request), k(6));
        assert_eq!(frame_len(&[1, 43, 14], Request), k(7));
        assert_eq!(frame_len(&[1, 43, 13], Request), Len::No);
        // responses
        assert_eq!(frame_len(&[1, 1, 1], Response), k(6));
        assert_eq!(frame_len(&[1, 3, 250], Response), k(255));
        assert_eq!(frame_len(&[1, 3, 3], Response), Len::No);
        assert_eq!(frame_len(&[1, 3, 0], Response), Len::No);
        for fc in [5u8, 6, 8, 11, 15, 16] {
            assert_eq!(frame_len(&[1, fc], Response), k(8), "{fc}");
        }
        assert_eq!(frame_len(&[1, 7], Response), k(5));
        assert_eq!(frame_len(&[1, 12, 8], Response), k(13));
        assert_eq!(frame_len(&[1, 17, 2], Response), k(7));
        assert_eq!(frame_len(&[1, 22], Response), k(10));
        assert_eq!(frame_len(&[1, 23, 4], Response), k(9));
        assert_eq!(frame_len(&[1, 24, 0, 6], Response), k(12));
        // 43/14: two objects of 3 and 1 bytes
        let dev = [1, 43, 14, 1, 1, 0, 0, 2, 0, 3, b'a', b'b', b'c', 1, 1, b'x'];
        assert_eq!(frame_len(&dev[..10], Response), Len::Need);
        assert_eq!(frame_len(&dev, Response), k(18));
        // exceptions
        assert_eq!(frame_len(&[1, 0x83], Response), k(5));
        assert_eq!(frame_len(&[1, 0x83], Request), Len::No);
        assert_eq!(frame_len(&[1, 0xC1], Response), Len::No);
        // broadcast: writes only, never answered
        assert_eq!(frame_len(&[0, 6], Request), k(8));
        assert_eq!(frame_len(&[0, 3], Request), Len::No);
        assert_eq!(frame_len(&[0, 6], Response), Len::No);
        assert_eq!(frame_len(&[248, 3], Request), Len::No);
        assert_eq!(frame_len(&[1], Request), Len::Need);
        assert_eq!(frame_len(&[1, 3], Response), Len::Need);
        assert_eq!(frame_len(&[1, 99], Request), Len::No);
    }

    #[test]
    fn plausible_quantities() {
        use Dir::*;
        assert!(plausible(&[1, 3, 0, 0, 0, 125, 0, 0], Request));
        assert!(!plausible(&[1, 3, 0, 0, 0, 126, 0, 0], Request));
        assert!(!plausible(&[1, 3, 0, 0, 0, 0, 0, 0], Request));
        assert!(plausible(&[1, 1, 0, 0, 0x07, 0xD0, 0, 0], Request));
        assert!(!plausible(&[1, 1, 0, 0, 0x07, 0xD1, 0, 0], Request));
        assert!(plausible(&[1, 5, 0, 3, 0xFF, 0, 0, 0], Response));
        assert!(!plausible(&[1, 5, 0, 3, 0x12, 0x34, 0, 0], Request));
        assert!(plausible(&[1, 15, 0, 0, 0, 9, 2, 0, 0, 0, 0], Request));
        assert!(!plausible(&[1, 15, 0, 0, 0, 9, 1, 0, 0, 0], Request));
        assert!(plausible(&[1, 16, 0, 0, 0, 1, 2, 0, 0, 0, 0], Request));
        assert!(!plausible(&[1, 16, 0, 0, 0, 2, 2, 0, 0, 0, 0], Request));
        let rw = [1, 23, 0, 0, 0, 1, 0, 9, 0, 1, 2, 0, 7, 0, 0];
        assert!(plausible(&rw, Request));
        assert!(plausible(&[1, 8, 0, 0, 0, 0, 0, 0], Request));
    }

    #[test]
    fn every_public_code_has_a_name_and_a_request() {
        for fc in PUBLIC {
            assert!(is_public(fc));
            let mut b = vec![1, fc];
            b.resize(12, 0x0E);
            b[6] = 2;
            b[10] = 2;
            assert!(matches!(frame_len(&b, Dir::Request), Len::Known(_)), "{fc}");
        }
        assert_eq!(exception_name(2), "Illegal Data Address");
        assert_eq!(diagnostic_name(0), "Return Query Data");
    }
}
