//! The members of a JSON row's `parts` written by [`Cells`]: one at a time, a fixed list at
//! once, or a list of `name=value` pairs read back from the Data cell. Nothing in the other
//! formats.

use super::*;

impl<F: Fmt> Cells<'_, '_, F> {
    /// JSON Lines only (nothing in the other formats): a row's numbers as the table writes a
    /// [`crate::row::Row::parts`] (`,"parts":{…}`, nothing when there are none). Not together with
    /// [`Cells::part`].
    #[inline(always)]
    pub fn row_parts(&mut self, parts: crate::row::Parts<'_>) {
        if F::FORMAT == Format::Jsonl && !parts.is_empty() {
            self.p.line.json_parts(parts);
        }
    }

    /// JSON Lines only (nothing in the other formats): a member of `parts`, the number named
    /// `name` marked in the Data cell. After the extra columns.
    #[inline(always)]
    pub fn part(&mut self, name: &str, m: Mark) {
        if F::FORMAT != Format::Jsonl {
            return;
        }
        match self.marked(m) {
            (false, a, b) => {
                let first = self.parts == 0;
                self.parts += 1;
                if let Some(key) = self.t.part_keys.get(name) {
                    self.p
                        .line
                        .json_key_within(first, key, name.len() + 4, a, b);
                    return;
                }
                let pre: &[u8] = if first { b",\"parts\":{" } else { b"," };
                self.p.line.json_member_within(pre, name, a, b);
            }
            (true, ..) => {
                self.part_name(name);
                self.put_marked(m);
            }
        }
    }

    /// As [`Cells::part`], for a name that lives as long as the program (a literal, a name
    /// from a `static` or `const` table): its kept key is found by the name's address alone,
    /// without reading the name.
    #[inline(always)]
    pub fn part_static(&mut self, name: &'static str, m: Mark) {
        if F::FORMAT != Format::Jsonl {
            return;
        }
        if let (false, a, b) = self.marked(m)
            && let Some(key) = self.t.part_keys.get_static(name)
        {
            let first = self.parts == 0;
            self.parts += 1;
            self.p
                .line
                .json_key_within(first, key, name.len() + 4, a, b);
            return;
        }
        self.part(name, m);
    }

    /// JSON Lines only: the members of `parts` for the first `marks.len()` names of `names`
    /// (at most all), each the number marked by its mark in the Data cell: as
    /// [`Cells::part`] for each in order, with the keys made by the compiler and one room
    /// check for all. After the extra columns.
    #[inline(always)]
    pub fn parts_marked<const N: usize>(&mut self, names: &PartNames<N>, marks: &[Mark]) {
        if F::FORMAT != Format::Jsonl {
            return;
        }
        let marks = marks.get(..N).unwrap_or(marks);
        if names.kept
            && self.rewritten.is_none()
            && self
                .p
                .line
                .json_keys_within(self.parts == 0, &names.keys, &names.lens, marks)
        {
            self.parts += marks.len();
            return;
        }
        for (name, &m) in names.names.iter().zip(marks) {
            self.part(name, m);
        }
    }

    /// JSON Lines only: the members of `parts` for the first `texts.len()` names of `names`
    /// (at most all), each with its number's text: as [`Cells::part_text`] for each in order,
    /// with the keys made by the compiler and one room check for all.
    #[inline(always)]
    pub fn parts_text<const N: usize>(&mut self, names: &PartNames<N>, texts: &[&str]) {
        if F::FORMAT != Format::Jsonl {
            return;
        }
        let texts = texts.get(..N).unwrap_or(texts);
        if names.kept
            && self
                .p
                .line
                .json_keys_text(self.parts == 0, &names.keys, &names.lens, texts)
        {
            self.parts += texts.len();
            return;
        }
        for (name, t) in names.names.iter().zip(texts) {
            self.part_text(name, t);
        }
    }

    /// JSON Lines only: a member of `parts` with its number's text.
    #[inline(always)]
    pub fn part_text(&mut self, name: &str, text: &str) {
        if F::FORMAT != Format::Jsonl {
            return;
        }
        if let Some(key) = self.t.part_keys.get(name) {
            let first = self.parts == 0;
            self.parts += 1;
            self.p
                .line
                .json_key_text(first, key, name.len() + 4, text.as_bytes());
            return;
        }
        self.part_name(name);
        self.p.line.put(text.as_bytes());
    }

    #[inline(always)]
    pub(super) fn part_name(&mut self, name: &str) {
        self.open_member();
        let w = &mut *self.p.line;
        w.json_str(name);
        w.byte(b':');
    }

    /// A member of `parts` begins: `,"parts":{` before the first, `,` before the others.
    #[inline(always)]
    fn open_member(&mut self) {
        let first = self.parts == 0;
        self.parts += 1;
        self.p.line.put(if first { b",\"parts\":{" } else { b"," });
    }

    /// JSON Lines only: the `name=number` pairs, separated by blanks, of the marked text in
    /// the Data cell (an S-Bus media list `R57=-8 R58=12`), each a member of `parts`, name and
    /// number cut from the text, as the table writes the [`crate::row::Parts::Spans`] of such a
    /// list. For texts of plain ASCII names and numbers.
    #[inline]
    pub fn pairs(&mut self, list: Mark) {
        if F::FORMAT != Format::Jsonl {
            return;
        }
        let (in_scratch, a, b) = self.marked(list);
        let mut i = a;
        while i < b {
            let src: &[u8] = if in_scratch {
                &self.t.data_copy
            } else {
                self.p.line.bytes()
            };
            let tok = src.get(i..b).unwrap_or_default();
            let end = i + tok.iter().position(|&c| c == b' ').unwrap_or(tok.len());
            let eq = i + tok[..end - i]
                .iter()
                .position(|&c| c == b'=')
                .unwrap_or(end - i);
            let num = (eq + 1).min(end);
            self.open_member();
            let w = &mut *self.p.line;
            if eq == i {
                w.put(b"null");
            } else {
                w.byte(b'"');
                if in_scratch {
                    w.put(&self.t.data_copy[i..eq]);
                } else {
                    w.copy_within(i, eq);
                }
                w.byte(b'"');
            }
            w.byte(b':');
            if in_scratch {
                w.put(&self.t.data_copy[num..end]);
            } else {
                w.copy_within(num, end);
            }
            i = end + 1;
        }
    }
}
