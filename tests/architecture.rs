//! The layering docs/architecture.md promises, checked on the source: no import circle between
//! the top-level modules of `src/`, nor between the files of one module's folder. Every
//! `crate::NAME` (and, inside a folder, `super::NAME`) path outside comments and unit-test
//! modules counts, wherever it stands (`use` lines, types, calls), so a circle closed by an
//! inline path is found too. `.ci/run` runs it with the rest of the tests.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The text of a source file without comments and without its unit-test module.
fn code(path: &Path) -> String {
    strip(&std::fs::read_to_string(path).unwrap())
}

/// `text` without comments and without its unit-test module.
fn strip(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .map(|l| match l.find("//") {
            // A `//` inside a string (an address) is rare in paths' lines; cutting there only
            // loses text after it.
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every `.rs` file below `dir`, test files left out.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n != "tests") {
                files(&p, out);
            }
        } else if p.extension().is_some_and(|x| x == "rs")
            && p.file_name().is_some_and(|n| n != "tests.rs")
        {
            out.push(p);
        }
    }
}

/// The modules named after `prefix` (`crate::`, `super::`) in `text`: a name followed by `::`,
/// or imported by a `use` (`use super::hdlc;`, `use super::{hdlc, sync};`). A function of the
/// parent called as `super::decoder(…)` is no module, even where a file has its name.
fn paths<'a>(text: &'a str, prefix: &str) -> BTreeSet<&'a str> {
    let ident = |s: &str| {
        s.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(s.len())
    };
    let mut out = BTreeSet::new();
    for (i, _) in text.match_indices(prefix) {
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        let rest = &text[i + prefix.len()..];
        let in_use = text[..i].trim_end().ends_with("use");
        if let Some(list) = rest.strip_prefix('{').filter(|_| in_use) {
            let list = &list[..list.find('}').unwrap_or(list.len())];
            for item in list.split(',') {
                let item = item.trim();
                out.insert(&item[..ident(item)]);
            }
            continue;
        }
        let end = ident(rest);
        let after = &rest[end..];
        if after.starts_with("::") || (in_use && after.starts_with(';')) {
            out.insert(&rest[..end]);
        }
    }
    out
}

/// The circles of a graph (strongly connected parts of more than one node), each with the
/// edges inside it and the file that makes each edge.
fn circles(edges: &BTreeMap<String, BTreeMap<String, PathBuf>>) -> Vec<String> {
    // Reachability by a depth-first walk from each node: small graphs.
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.to_owned()];
        while let Some(n) = todo.pop() {
            for m in edges.get(&n).into_iter().flat_map(|e| e.keys()) {
                if seen.insert(m.clone()) {
                    todo.push(m.clone());
                }
            }
        }
        seen
    };
    let mut out = Vec::new();
    for (a, targets) in edges {
        for (b, file) in targets {
            if a < b && reach(b).contains(a) {
                out.push(format!("{a} -> {b} ({}) and back", file.display()));
            }
        }
    }
    out
}

#[test]
fn no_import_circle_between_top_level_modules() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut modules: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    for e in std::fs::read_dir(&src).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        if name == "lib" || name == "main" {
            continue;
        }
        let list = modules.entry(name).or_default();
        if p.is_dir() {
            files(&p, list);
        } else {
            list.push(p);
        }
    }
    let mut edges: BTreeMap<String, BTreeMap<String, PathBuf>> = BTreeMap::new();
    for (name, list) in &modules {
        let e = edges.entry(name.clone()).or_default();
        for f in list {
            for target in paths(&code(f), "crate::") {
                if target != name && modules.contains_key(target) {
                    e.entry(target.to_owned()).or_insert_with(|| f.clone());
                }
            }
        }
    }
    let found = circles(&edges);
    assert!(found.is_empty(), "import circles:\n{}", found.join("\n"));
}

#[test]
fn no_import_circle_between_the_files_of_a_folder() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = Vec::new();
    for e in std::fs::read_dir(&src).unwrap() {
        let dir = e.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let folder = dir.file_name().unwrap().to_string_lossy().into_owned();
        // The folder's own files (mod.rs aside: it is the folder), and each file's subfolder.
        let mut members: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            if name == "mod" || name == "tests" {
                continue;
            }
            let list = members.entry(name).or_default();
            if p.is_dir() {
                files(&p, list);
            } else if p.extension().is_some_and(|x| x == "rs") {
                list.push(p);
            }
        }
        let mut edges: BTreeMap<String, BTreeMap<String, PathBuf>> = BTreeMap::new();
        for (name, list) in &members {
            let e = edges.entry(name.clone()).or_default();
            for f in list {
                let text = code(f);
                // Only a file directly in the folder reaches its siblings with `super::`.
                let mut targets = paths(&text, &format!("crate::{folder}::"));
                if f.parent() == Some(dir.as_path()) {
                    targets.extend(paths(&text, "super::"));
                }
                for t in targets {
                    if t != name && members.contains_key(t) {
                        e.entry(t.to_owned()).or_insert_with(|| f.clone());
                    }
                }
            }
        }
        found.extend(
            circles(&edges)
                .into_iter()
                .map(|c| format!("{folder}: {c}")),
        );
    }
    assert!(found.is_empty(), "import circles:\n{}", found.join("\n"));
}

/// The checker finds a circle closed by an inline path, and none in a chain.
#[test]
fn the_checker_finds_circles() {
    let text = "use crate::a::X;\nfn f() { crate::b::g(); } // crate::c::h\nlet s = super::d::y;\n\
                use super::e;\nuse super::{f, g::H};\nsuper::h(1);";
    let text = strip(text);
    let found: Vec<&str> = paths(&text, "crate::").into_iter().collect();
    assert_eq!(found, ["a", "b"]);
    let found: Vec<&str> = paths(&text, "super::").into_iter().collect();
    assert_eq!(found, ["d", "e", "f", "g"]);
    let mut edges: BTreeMap<String, BTreeMap<String, PathBuf>> = BTreeMap::new();
    fn add(edges: &mut BTreeMap<String, BTreeMap<String, PathBuf>>, a: &str, b: &str) {
        edges
            .entry(a.into())
            .or_default()
            .insert(b.into(), PathBuf::from(format!("{a}.rs")));
    }
    add(&mut edges, "a", "b");
    add(&mut edges, "b", "c");
    assert!(circles(&edges).is_empty());
    add(&mut edges, "c", "a");
    assert_eq!(circles(&edges).len(), 2, "{:?}", circles(&edges));
}
