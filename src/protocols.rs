//! The table of protocols. It names every protocol module, so it lives above them: a protocol
//! imports [`crate::protocol`] (the trait and the descriptor), never this table.

use crate::protocol::Protocol;

/// Every protocol busnoop decodes, in the order of the command line's subcommands.
pub const PROTOCOLS: &[&Protocol] = &[
    &crate::sport::PROTOCOL,
    &crate::sbus::PROTOCOL,
    &crate::sab::PROTOCOL,
];

/// The protocols' subcommands for a message: `sport|sbus|sab2`.
pub fn commands() -> String {
    let names: Vec<&str> = PROTOCOLS.iter().map(|p| p.command).collect();
    names.join("|")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::InputKind;

    #[test]
    fn every_protocol_reads_raw_bytes_and_live_lines_and_has_its_own_command() {
        let mut commands: Vec<&str> = PROTOCOLS.iter().map(|p| p.command).collect();
        commands.sort_unstable();
        commands.dedup();
        assert_eq!(commands.len(), PROTOCOLS.len());
        for p in PROTOCOLS {
            assert!(
                p.reads(InputKind::Raw) && p.reads(InputKind::Serial),
                "{}",
                p.name
            );
        }
    }
}
