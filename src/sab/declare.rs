//! `--value CMD=TYPE[*SCALE][:UNIT]` and `[sab2.values]`: how SAB payloads are read as numbers,
//! parsed into the plain [`crate::sab::Declared`] the decoder takes (docs/sab.md, "Values").

use crate::sab::{Declared, Direction, Scale, ValueType};

/// The most decimals and significant digits of a scale (exact decimal arithmetic in an i64).
const SCALE_DIGITS: usize = 9;

/// Parses one declaration; `commands` are the `--command` names (NAME, code) a CMD may name.
pub fn parse_value(arg: &str, commands: &[(String, u8)]) -> Result<Declared, String> {
    let Some((cmd, spec)) = arg.rsplit_once('=') else {
        return Err(format!(
            "`{arg}`: expected CMD=TYPE[*SCALE][:UNIT], for example distance=u16*0.01:m"
        ));
    };
    let (command, direction) = command(cmd.trim(), commands)?;
    let (spec, unit) = match spec.split_once(':') {
        Some((s, u)) => {
            let u = u.trim();
            if u.is_empty() {
                return Err(format!("`{arg}`: the unit after `:` is empty"));
            }
            if u.chars().any(|c| c.is_control() || c == '(' || c == ')') {
                return Err(format!(
                    "`{arg}`: the unit `{u}` has a control character or a parenthesis"
                ));
            }
            (s, u.to_owned())
        }
        None => (spec, String::new()),
    };
    let (ty, scale) = match spec.split_once('*') {
        Some((t, s)) => (t, Some(s)),
        None => (spec, None),
    };
    let ty = ty.trim().to_ascii_lowercase();
    let Some(&(_, ty)) = ValueType::ALL.iter().find(|(n, _)| *n == ty) else {
        let names: Vec<&str> = ValueType::ALL.iter().map(|(n, _)| *n).collect();
        return Err(format!(
            "`{arg}`: unknown type `{ty}` (one of {})",
            names.join(" ")
        ));
    };
    let scale = match scale {
        Some(s) => parse_scale(s.trim()).map_err(|e| format!("`{arg}`: {e}"))?,
        None => Scale::ONE,
    };
    Ok(Declared {
        command,
        direction,
        ty,
        scale,
        unit,
    })
}

/// CMD: a `--command` name or a code (`0x34`, `52`), optionally with `.req` or `.ack`.
fn command(cmd: &str, commands: &[(String, u8)]) -> Result<(u8, Direction), String> {
    if cmd.is_empty() {
        return Err("the command before `=` is empty".into());
    }
    if let Some(c) = lookup(cmd, commands) {
        return Ok((c, Direction::Both));
    }
    for (suffix, direction) in [(".req", Direction::Request), (".ack", Direction::Ack)] {
        if let Some(base) = cmd.strip_suffix(suffix)
            && let Some(c) = lookup(base, commands)
        {
            return Ok((c, direction));
        }
    }
    let names: Vec<&str> = commands.iter().map(|(n, _)| n.as_str()).collect();
    Err(format!(
        "`{cmd}` is neither a command code (0x34 or 52, 0..=255) nor a --command name{}, \
         optionally with .req or .ack",
        if names.is_empty() {
            String::new()
        } else {
            format!(" ({})", names.join(", "))
        }
    ))
}

/// A name from `commands` (the last one given wins, as in the Sensor column) or a code.
fn lookup(cmd: &str, commands: &[(String, u8)]) -> Option<u8> {
    if let Some((_, c)) = commands.iter().rev().find(|(n, _)| n == cmd) {
        return Some(*c);
    }
    let v = match cmd.strip_prefix("0x").or_else(|| cmd.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok()?,
        None => cmd.parse().ok()?,
    };
    u8::try_from(v).ok()
}

/// A plain decimal scale: `0.01`, `2.5`, `-1`, `1000`.
fn parse_scale(s: &str) -> Result<Scale, String> {
    let bad =
        || format!("scale `{s}` is not a plain decimal number (write 0.001, not 1e-3 or 1/1000)");
    let (neg, digits) = match s.strip_prefix('-') {
        Some(d) => (true, d),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    let (int, frac) = digits.split_once('.').unwrap_or((digits, ""));
    if int.is_empty() && frac.is_empty()
        || !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit())
    {
        return Err(bad());
    }
    let frac = frac.trim_end_matches('0');
    if frac.len() > SCALE_DIGITS {
        return Err(format!("scale `{s}` has more than {SCALE_DIGITS} decimals"));
    }
    let all = format!("{int}{frac}");
    let significant = all.trim_start_matches('0');
    if significant.is_empty() {
        return Err(format!("scale `{s}` is zero: every value would be 0"));
    }
    if significant.len() > SCALE_DIGITS {
        return Err(format!(
            "scale `{s}` has more than {SCALE_DIGITS} significant digits"
        ));
    }
    let mantissa: i64 = significant.parse().map_err(|_| bad())?;
    Ok(Scale {
        mantissa: if neg { -mantissa } else { mantissa },
        decimals: frac.len() as u8,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<(String, u8)> {
        vec![("distance".into(), 0x10), ("heading".into(), 0x34)]
    }

    fn ok(arg: &str) -> Declared {
        parse_value(arg, &names()).unwrap()
    }

    fn err(arg: &str) -> String {
        parse_value(arg, &names()).unwrap_err()
    }

    #[test]
    fn declarations() {
        assert_eq!(
            ok("distance=u16*0.01:m"),
            Declared {
                command: 0x10,
                direction: Direction::Both,
                ty: ValueType::U16,
                scale: Scale {
                    mantissa: 1,
                    decimals: 2
                },
                unit: "m".into()
            }
        );
        let d = ok("0x34=F32:deg");
        assert_eq!(
            (d.command, d.ty, d.scale, d.unit.as_str()),
            (0x34, ValueType::F32, Scale::ONE, "deg")
        );
        let d = ok("heading.req=u8");
        assert_eq!((d.command, d.direction), (0x34, Direction::Request));
        let d = ok("52.ack=i32*-2.50");
        assert_eq!(
            (d.command, d.direction, d.scale),
            (
                52,
                Direction::Ack,
                Scale {
                    mantissa: -25,
                    decimals: 1
                }
            )
        );
        assert_eq!(
            ok("7=i8*1000").scale,
            Scale {
                mantissa: 1000,
                decimals: 0
            }
        );
        assert_eq!(
            ok("7=i8*0.000000001").scale,
            Scale {
                mantissa: 1,
                decimals: 9
            }
        );
        assert_eq!(ok("7=u16:m/s²").unit, "m/s²");
    }

    #[test]
    fn mistakes_are_explained() {
        assert!(err("distance").contains("CMD=TYPE"));
        assert!(err("=u8").contains("empty"));
        assert!(err("speed=u8").contains("--command name (distance, heading)"));
        assert!(err("256=u8").contains("0..=255"));
        assert!(err("7=u64").contains("one of u8 i8 u16 i16 u32 i32 f32"));
        assert!(err("7=u8*1e-3").contains("plain decimal"));
        assert!(err("7=u8*").contains("plain decimal"));
        assert!(err("7=u8*0").contains("zero"));
        assert!(err("7=u8*0.0000000001").contains("decimals"));
        assert!(err("7=u8*1234567890").contains("significant"));
        assert!(err("7=u8:").contains("unit"));
        assert!(err("7=u8:V(x)").contains("parenthesis"));
    }
}
