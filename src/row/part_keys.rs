//! JSON Lines: the keys of `parts` members written once per name and kept (what
//! [`super::line::W::json_key_within`] writes from).

use super::line::{json_escape, scan};

/// JSON Lines: the keys of `parts`' members (`,"CH1":`), each written once per name and kept
/// in a table of [`PartKeys::SLOTS`] places, found by the name's address and checked against
/// the name's bytes (so a name is found only when it is the same text). A name whose place is
/// taken by another is written again when it comes. Only names of 1 to [`PartKeys::NAME`]
/// bytes with nothing to escape are kept; the rest are written piece by piece.
pub(crate) struct PartKeys {
    slots: Box<[KeySlot]>,
}

#[derive(Clone, Copy, Default)]
struct KeySlot {
    /// The name's bytes as [`name_words`] gives them, and its length (0: empty).
    words: (u64, u64),
    len: usize,
    /// The address of the `&'static str` it was kept for by [`PartKeys::get_static`] (0: kept
    /// by [`PartKeys::get`], whose names may be anywhere).
    ptr: usize,
    /// `,"name":`, padded with zeros.
    key: [u8; 16],
}

/// A name of 1 to 12 bytes in two words that tell every such name of its length apart (each
/// byte is in them, some twice): `None` for another length.
#[inline(always)]
fn name_words(s: &[u8]) -> Option<(u64, u64)> {
    let n = s.len();
    let load8 = |i: usize| u64::from_le_bytes(s[i..i + 8].try_into().unwrap_or([0; 8]));
    let load4 = |i: usize| u32::from_le_bytes(s[i..i + 4].try_into().unwrap_or([0; 4]));
    match n {
        1..=3 => Some((
            s[0] as u64 | (s[n / 2] as u64) << 8 | (s[n - 1] as u64) << 16,
            0,
        )),
        4..=7 => Some((load4(0) as u64 | (load4(n - 4) as u64) << 32, 0)),
        8..=PartKeys::NAME => Some((load8(0), load8(n - 8))),
        _ => None,
    }
}

impl PartKeys {
    const SLOTS: usize = 256;
    /// The longest name kept: its key fills the 16 bytes.
    pub(crate) const NAME: usize = 12;

    pub(crate) fn new() -> Self {
        PartKeys {
            slots: vec![KeySlot::default(); Self::SLOTS].into_boxed_slice(),
        }
    }

    /// The key of `name` (`,"name":`, `name.len() + 4` bytes of the 16), when it is kept or
    /// can be.
    #[inline(always)]
    pub(crate) fn get(&mut self, name: &str) -> Option<&[u8; 16]> {
        let nb = name.as_bytes();
        let words = name_words(nb)?;
        let p = nb.as_ptr() as usize;
        let h = Self::place(p);
        let hit = self
            .slots
            .get(h)
            .is_some_and(|s| s.words == words && s.len == nb.len());
        if hit {
            return self.slots.get(h).map(|s| &s.key);
        }
        self.fill(h, nb, words, 0)
    }

    /// As [`PartKeys::get`] for a name that lives as long as the program: its text cannot
    /// change, so its place is found by its address and length alone (a slot another name
    /// took, or one kept by [`PartKeys::get`], is filled again).
    #[inline(always)]
    pub(crate) fn get_static(&mut self, name: &'static str) -> Option<&[u8; 16]> {
        let nb = name.as_bytes();
        let p = nb.as_ptr() as usize;
        let h = Self::place(p);
        let hit = self
            .slots
            .get(h)
            .is_some_and(|s| s.ptr == p && s.len == nb.len());
        if hit {
            return self.slots.get(h).map(|s| &s.key);
        }
        self.fill(h, nb, name_words(nb)?, p)
    }

    /// A name's place by its address.
    #[inline(always)]
    fn place(p: usize) -> usize {
        (p.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) % Self::SLOTS
    }

    #[cold]
    #[inline(never)]
    fn fill(&mut self, h: usize, nb: &[u8], words: (u64, u64), ptr: usize) -> Option<&[u8; 16]> {
        if nb.is_empty() || nb.len() > Self::NAME || scan(nb, json_escape) != 0 {
            return None;
        }
        let slot = self.slots.get_mut(h)?;
        let mut key = [0u8; 16];
        key[..2].copy_from_slice(b",\"");
        key[2..2 + nb.len()].copy_from_slice(nb);
        key[2 + nb.len()..4 + nb.len()].copy_from_slice(b"\":");
        *slot = KeySlot {
            words,
            len: nb.len(),
            ptr,
            key,
        };
        Some(&slot.key)
    }
}

/// The names of a fixed list of `parts` members (a row's channels, a frame's fields), with
/// their keys (`,"name":`) made by the compiler: what [`super::Cells::parts_marked`] and
/// [`super::Cells::parts_text`] write a row's members from, without a look-up per member.
/// Names of 1 to `PartKeys::NAME` bytes with nothing JSON escapes have keys; a list with
/// another name is written member by member, as [`super::Cells::part`] writes it.
pub struct PartNames<const N: usize> {
    pub(crate) names: [&'static str; N],
    /// `,"name":`, padded with zeros.
    pub(crate) keys: [[u8; 16]; N],
    /// Each key's length (the name's and 4).
    pub(crate) lens: [u8; N],
    /// Every name has its key.
    pub(crate) kept: bool,
}

impl<const N: usize> PartNames<N> {
    /// The list of `names`, in the order their members are written.
    pub const fn new(names: [&'static str; N]) -> Self {
        let mut keys = [[0u8; 16]; N];
        let mut lens = [0u8; N];
        let mut kept = true;
        let mut i = 0;
        while i < N {
            let nb = names[i].as_bytes();
            if nb.is_empty() || nb.len() > PartKeys::NAME {
                kept = false;
            } else {
                keys[i][0] = b',';
                keys[i][1] = b'"';
                let mut j = 0;
                while j < nb.len() {
                    let b = nb[j];
                    if b < 0x20 || b == b'"' || b == b'\\' {
                        kept = false;
                    }
                    keys[i][2 + j] = b;
                    j += 1;
                }
                keys[i][2 + nb.len()] = b'"';
                keys[i][3 + nb.len()] = b':';
                lens[i] = nb.len() as u8 + 4;
            }
            i += 1;
        }
        PartNames {
            names,
            keys,
            lens,
            kept,
        }
    }

    /// The names.
    pub fn names(&self) -> &[&'static str; N] {
        &self.names
    }
}

#[cfg(test)]
mod tests {
    use super::{PartKeys, PartNames};

    /// A list's keys made by the compiler are the keys [`PartKeys::get`] keeps; a list with a
    /// name that is not kept (empty, too long, to escape) has no keys.
    #[test]
    fn listed_names_have_the_kept_keys() {
        static LIST: PartNames<6> =
            PartNames::new(["CH1", "CH16", "RxBt", "FrameLost", "A", "ABCDEFGHIJKL"]);
        assert!(LIST.kept);
        let mut keys = PartKeys::new();
        for (i, name) in LIST.names().iter().enumerate() {
            let want = keys.get(name).copied();
            assert_eq!(Some(LIST.keys[i]), want, "{name}");
            assert_eq!(usize::from(LIST.lens[i]), name.len() + 4, "{name}");
        }
        for name in ["", "a \"quoted\"", "back\\slash", "tab\t", "thirteen char"] {
            let list = PartNames::new(["CH1", name]);
            assert!(!list.kept, "{name:?}");
            assert_eq!(keys.get(name), None, "{name:?}");
        }
    }

    /// Names found by address give the keys names found by their text give; names that are
    /// not kept are not kept either way.
    #[test]
    fn static_names_give_the_same_keys() {
        static NAMES: [&str; 8] = [
            "CH1",
            "CH16",
            "RxBt",
            "FrameLost",
            "A",
            "Alt",
            "Bat%",
            "Hdg",
        ];
        let (mut by_text, mut by_address) = (PartKeys::new(), PartKeys::new());
        for _ in 0..3 {
            for name in NAMES {
                let owned = name.to_string();
                let want = by_text.get(&owned).copied();
                assert!(want.is_some(), "{name}");
                assert_eq!(by_address.get_static(name).copied(), want, "{name}");
                // Both ways in one table: each finds its own.
                assert_eq!(by_text.get_static(name).copied(), want, "{name}");
                assert_eq!(by_text.get(&owned).copied(), want, "{name}");
            }
        }
        for name in ["", "a \"quoted\"", "thirteen char"] {
            assert_eq!(by_address.get_static(name), None, "{name}");
            assert_eq!(by_text.get(name), None, "{name}");
        }
    }
}
