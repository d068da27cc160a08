//! The SAB header byte (flags and address) and the NACK error codes. Both framings use the
//! same header (`docs/sab.md`, "Header").
//!
//! ```text
//!   7   6   5   4   3   2   1   0
//! +---+---+---+---+---+---+---+---+
//! | flags |        address        |
//! +---+---+---+---+---+---+---+---+
//! ```
//!
//! modm tests bit 7 for "is a response" and bit 6 for "is an acknowledge". The address has six
//! bits: modm's prose says "up to 32 slaves", but its code masks `0x3F` and its unit tests use
//! address 0x3F.

/// Mask of the address bits.
pub const ADDRESS_MASK: u8 = 0x3F;

/// Number of distinct addresses.
pub const ADDRESSES: usize = 64;

/// The two flag bits of a header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Flags {
    /// `00`: a request from the master.
    Request,
    /// `01`: reserved, never sent by modm (modm would treat it as a request).
    Reserved,
    /// `10`: a negative response; the payload is one error code.
    Nack,
    /// `11`: a positive response, may carry a payload.
    Ack,
}

impl Flags {
    /// The flags of a header byte.
    pub const fn of(header: u8) -> Flags {
        match header >> 6 {
            0 => Flags::Request,
            1 => Flags::Reserved,
            2 => Flags::Nack,
            _ => Flags::Ack,
        }
    }

    /// The flag bits in place (bits 7..6).
    pub const fn bits(self) -> u8 {
        match self {
            Flags::Request => 0x00,
            Flags::Reserved => 0x40,
            Flags::Nack => 0x80,
            Flags::Ack => 0xC0,
        }
    }

    /// Bit 7: sent by a slave. Requests and the reserved combination are not responses.
    pub const fn is_response(self) -> bool {
        matches!(self, Flags::Nack | Flags::Ack)
    }

    /// The `Type` column.
    pub const fn type_name(self) -> &'static str {
        match self {
            Flags::Request => "Request",
            Flags::Reserved => "Reserved",
            Flags::Nack => "NACK",
            Flags::Ack => "ACK",
        }
    }
}

/// The address of a header byte (6 bits).
pub const fn address(header: u8) -> u8 {
    header & ADDRESS_MASK
}

/// A header byte from flags and an address (the address is masked to 6 bits).
pub const fn header(flags: Flags, address: u8) -> u8 {
    flags.bits() | (address & ADDRESS_MASK)
}

/// First user-defined NACK code; the codes below are reserved for the system.
pub const FIRST_USER_CODE: u8 = 0x20;

/// What a NACK error code means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NackCode {
    /// One of modm's four system codes: name and meaning.
    System {
        code: u8,
        name: &'static str,
        meaning: &'static str,
    },
    /// 0x04..0x1F: reserved for the system, not defined by modm.
    ReservedSystem(u8),
    /// 0x20 and up: defined by the application.
    User(u8),
}

impl NackCode {
    pub const fn of(code: u8) -> NackCode {
        match code {
            0x00 => NackCode::System {
                code,
                name: "GENERAL_ERROR",
                meaning: "general error",
            },
            0x01 => NackCode::System {
                code,
                name: "NO_ACTION",
                meaning: "no action registered for the command",
            },
            0x02 => NackCode::System {
                code,
                name: "WRONG_PAYLOAD_LENGTH",
                meaning: "request payload length differs from what the action expects",
            },
            0x03 => NackCode::System {
                code,
                name: "NO_RESPONSE",
                meaning: "the action returned without answering",
            },
            c if c < FIRST_USER_CODE => NackCode::ReservedSystem(c),
            c => NackCode::User(c),
        }
    }

    pub const fn code(self) -> u8 {
        match self {
            NackCode::System { code, .. } => code,
            NackCode::ReservedSystem(c) | NackCode::User(c) => c,
        }
    }

    /// Appends a short name: `NO_ACTION`, `reserved 0x05`, `user 0x21`.
    pub fn push_name(self, out: &mut String) {
        match self {
            NackCode::System { name, .. } => out.push_str(name),
            NackCode::ReservedSystem(c) => {
                out.push_str("reserved 0x");
                crate::fmt::push_hex_u8(out, c);
            }
            NackCode::User(c) => {
                out.push_str("user 0x");
                crate::fmt::push_hex_u8(out, c);
            }
        }
    }

    /// Appends the name and what it means (for the Note column).
    pub fn push_description(self, out: &mut String) {
        self.push_name(out);
        match self {
            NackCode::System { meaning, .. } => {
                out.push_str(" (");
                out.push_str(meaning);
                out.push(')');
            }
            NackCode::ReservedSystem(_) => out.push_str(" (system code not defined by modm)"),
            NackCode::User(_) => out.push_str(" (user-defined error)"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_and_address() {
        // Headers of the modm unit tests (sab.md §2) and the SAB2 vectors.
        assert_eq!(Flags::of(0x12), Flags::Request);
        assert_eq!(address(0x12), 0x12);
        assert_eq!(Flags::of(0xFF), Flags::Ack);
        assert_eq!(address(0xFF), 0x3F);
        assert_eq!(Flags::of(0x86), Flags::Nack);
        assert_eq!(address(0x86), 0x06);
        assert_eq!(Flags::of(0x54), Flags::Reserved);
        assert_eq!(header(Flags::Ack, 0x12), 0xD2);
        assert_eq!(header(Flags::Nack, 0x3F), 0xBF);
        assert_eq!(header(Flags::Request, 0x41), 0x01);
        for h in 0..=255u8 {
            assert_eq!(header(Flags::of(h), address(h)), h);
            assert_eq!(Flags::of(h).is_response(), h & 0x80 != 0);
        }
    }

    #[test]
    fn nack_names() {
        let name = |c| {
            let mut s = String::new();
            NackCode::of(c).push_name(&mut s);
            s
        };
        assert_eq!(name(0), "GENERAL_ERROR");
        assert_eq!(name(1), "NO_ACTION");
        assert_eq!(name(2), "WRONG_PAYLOAD_LENGTH");
        assert_eq!(name(3), "NO_RESPONSE");
        assert_eq!(name(4), "reserved 0x04");
        assert_eq!(name(0x1F), "reserved 0x1F");
        assert_eq!(name(0x20), "user 0x20");
        assert_eq!(name(0xFF), "user 0xFF");
        let mut s = String::new();
        NackCode::of(1).push_description(&mut s);
        assert_eq!(s, "NO_ACTION (no action registered for the command)");
        assert_eq!(NackCode::of(0x33).code(), 0x33);
    }
}
