//! The table of protocols. It names every protocol module, so it lives above them: a protocol
//! imports [`crate::protocol`] (the trait and the descriptor), never this table.

use crate::protocol::Protocol;

/// Every protocol busnoop decodes, in the order of the command line's subcommands.
pub const PROTOCOLS: &[&Protocol] = &[
    &crate::sport::PROTOCOL,
    &crate::fport::PROTOCOL,
    &crate::sbus::PROTOCOL,
    &crate::sab::PROTOCOL,
    &crate::crsf::PROTOCOL,
    &crate::ghst::PROTOCOL,
    &crate::futaba::PROTOCOL,
    &crate::ibus::PROTOCOL,
    &crate::logs::PROTOCOL,
    &crate::modbus::PROTOCOL,
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

    /// Two protocols' exports in one link type would be read by the wrong dissector, unless
    /// both wrap their frames in datagrams (raw IPv4/UDP) whose port picks the dissector
    /// (serial S-Bus as Ether-S-Bus on 5050, Modbus as Modbus/UDP on 502).
    #[test]
    fn every_export_has_its_own_link_type() {
        let mut seen: Vec<(crate::protocol::Export, &str)> = Vec::new();
        for p in PROTOCOLS {
            if let Some(e) = p.export {
                for (other, name) in &seen {
                    if other.linktype == e.linktype {
                        assert!(
                            e.wrap.is_some()
                                && other.wrap.is_some()
                                && other.dissector != e.dissector,
                            "{} and {name} both export as link type {}",
                            p.command,
                            e.linktype
                        );
                    }
                }
                seen.push((e, p.command));
            }
        }
    }

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

    /// With several sources the table's first extra column is `Port`: no decoder (of any input
    /// it reads, any variant) names one of its own so.
    #[test]
    fn no_protocol_has_a_column_named_port() {
        use crate::protocol::Probe;
        for p in PROTOCOLS {
            for &input in p.accepts {
                let probe = Probe {
                    input,
                    line: p.line,
                };
                for v in (p.variants)(&probe) {
                    let columns = v.decoder.columns();
                    assert!(
                        !columns.contains(&crate::row::PORT_COLUMN),
                        "{} ({}): {columns:?}",
                        p.name,
                        v.label
                    );
                }
            }
        }
    }
}
