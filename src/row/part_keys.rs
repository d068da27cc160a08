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

#[cfg(test)]
mod tests {
    use super::PartKeys;

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
