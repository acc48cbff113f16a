//! The files of `src/` import each other in one direction only: no file reaches, through the
//! modules it names (`use super::x`, `crate::a::b` paths), back to itself. A circle means two
//! files each need the other, so neither can be read, changed or tested alone.
//!
//! A module's front door (`mod.rs`, the crate roots) only declares and re-exports its files: a
//! name taken through it counts as an import of the file that defines it (`super::Thing` with
//! `pub use file::Thing` in the folder's mod.rs is an import of `file.rs`), so a two-way tie
//! through the re-exports is a circle too. Test modules (`mod tests`) are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src");

/// Every .rs file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module path of a file relative to its crate root, and that root's folder.
fn module_of(file: &Path) -> (PathBuf, Vec<String>) {
    let rel = file.strip_prefix(SRC).unwrap();
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    let mut root = PathBuf::from(SRC);
    // The XR client is a crate of its own, rooted at src/bin/xr_client/main.rs.
    if parts.len() >= 2 && parts[0] == "bin" {
        root = root.join("bin").join(&parts[1]);
        parts.drain(..2);
    }
    if parts
        .last()
        .is_some_and(|p| p == "mod" || p == "lib" || p == "main")
    {
        parts.pop();
    }
    (root, parts)
}

/// The file a module path names: the longest prefix that is a file of its own (not a mod.rs).
fn resolve(root: &Path, path: &[String]) -> Option<PathBuf> {
    (1..=path.len()).rev().find_map(|n| {
        let file = root.join(path[..n].join("/")).with_extension("rs");
        file.is_file().then_some(file)
    })
}

/// The code of a file without its test module and comments.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The module paths a file's code names, from `super::`/`crate::` paths and `use` groups.
fn named_paths(code: &str, module: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes: Vec<char> = code.chars().collect();
    let text: String = bytes.iter().collect();
    for start in ["super::", "crate::"] {
        for (at, _) in text.match_indices(start) {
            let before = text[..at].chars().last();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            let mut base: Vec<String> = if start == "crate::" {
                Vec::new()
            } else {
                module[..module.len().saturating_sub(1)].to_vec()
            };
            let rest = &text[at + start.len()..];
            let mut rest = rest;
            // super::super::...
            while let Some(r) = rest.strip_prefix("super::") {
                base.pop();
                rest = r;
            }
            for tail in expand(rest) {
                let mut p = base.clone();
                p.extend(tail);
                out.push(p);
            }
        }
    }
    out
}

/// `a::b::{c, d::e}` -> [a, b, c], [a, b, d, e] (one level of braces), `a::b::X` -> [a, b, X].
fn expand(rest: &str) -> Vec<Vec<String>> {
    let ident = |s: &str| -> (Vec<String>, usize) {
        let mut parts = Vec::new();
        let mut used = 0;
        let mut s2 = s;
        loop {
            let n = s2
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(s2.len());
            if n == 0 {
                break;
            }
            parts.push(s2[..n].to_string());
            used += n;
            s2 = &s2[n..];
            match s2.strip_prefix("::") {
                Some(r) if !r.starts_with('{') => {
                    used += 2;
                    s2 = r;
                }
                _ => break,
            }
        }
        (parts, used)
    };
    let (head, used) = ident(rest);
    let after = &rest[used..];
    let group = match head.is_empty() {
        true => after.strip_prefix('{'),
        false => after.strip_prefix("::{"),
    };
    if let Some(group) = group {
        let end = group.find('}').unwrap_or(group.len());
        return group[..end]
            .split(',')
            .map(|item| {
                let mut p = head.clone();
                p.extend(ident(item.trim()).0);
                p
            })
            .collect();
    }
    vec![head]
}

/// The file that defines `path`'s item when `path` names it through a folder's front door
/// (`super::Thing` where the folder's mod.rs has `pub use file::Thing` or `file::{Thing, ..}`).
fn through_front_door(root: &Path, path: &[String]) -> Option<PathBuf> {
    (1..path.len()).rev().find_map(|n| {
        let door = root.join(path[..n].join("/")).join("mod.rs");
        let door = if n == 0 { root.join("lib.rs") } else { door };
        let text = std::fs::read_to_string(&door).ok()?;
        let item = &path[n];
        let code = code(&text);
        code.split("pub use ").skip(1).find_map(|decl| {
            let decl = &decl[..decl.find(';')?];
            expand(decl)
                .into_iter()
                .find(|p| p.last() == Some(item))
                .and_then(|p| {
                    let mut full = path[..n].to_vec();
                    full.extend(p[..p.len() - 1].iter().cloned());
                    resolve(root, &full)
                })
        })
    })
}

/// Each file's imports of other files, also through a folder's re-exports.
fn import_graph() -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut files = Vec::new();
    rust_files(Path::new(SRC), &mut files);
    let mut graph = BTreeMap::new();
    for file in &files {
        let (root, module) = module_of(file);
        let text = std::fs::read_to_string(file).unwrap();
        let targets: BTreeSet<PathBuf> = named_paths(&code(&text), &module)
            .iter()
            .filter_map(|p| resolve(&root, p).or_else(|| through_front_door(&root, p)))
            .filter(|t| t != file)
            .collect();
        graph.insert(file.clone(), targets);
    }
    graph
}

/// A circle through `from`, if there is one: the files in order.
fn circle(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>, from: &PathBuf) -> Option<Vec<PathBuf>> {
    let mut stack = vec![(from.clone(), vec![from.clone()])];
    let mut seen = BTreeSet::new();
    while let Some((node, path)) = stack.pop() {
        for next in graph.get(&node).into_iter().flatten() {
            if next == from {
                return Some(path);
            }
            if seen.insert(next.clone()) {
                let mut p = path.clone();
                p.push(next.clone());
                stack.push((next.clone(), p));
            }
        }
    }
    None
}

#[test]
fn no_file_of_src_imports_itself_through_others() {
    let graph = import_graph();
    assert!(graph.len() > 50, "found only {} files", graph.len());
    let mut circles = BTreeSet::new();
    for file in graph.keys() {
        if let Some(c) = circle(&graph, file) {
            let mut names: Vec<String> = c
                .iter()
                .map(|f| f.strip_prefix(SRC).unwrap().display().to_string())
                .collect();
            names.sort();
            circles.insert(names.join(" <-> "));
        }
    }
    circles.retain(|c| !KNOWN_TIES.contains(&c.as_str()));
    assert!(circles.is_empty(), "import circles:\n{}", {
        let list: Vec<_> = circles.into_iter().collect();
        list.join("\n")
    });
}

/// Circles that run through a folder's re-exports and are not undone yet: this list may only
/// shrink (it is empty: `Method` has a file of its own, algorithm/method.rs, so methods.rs and
/// params.rs no longer name each other).
const KNOWN_TIES: [&str; 0] = [];

/// Every known tie is still one (a tie undone must leave the list).
#[test]
fn the_known_ties_are_still_ties() {
    let graph = import_graph();
    for tie in KNOWN_TIES {
        let first = PathBuf::from(SRC).join(tie.split(" <-> ").next().unwrap());
        assert!(
            circle(&graph, &first).is_some(),
            "{tie} is undone: take it off KNOWN_TIES"
        );
    }
}

/// The check sees a circle when there is one (two files of a made-up module naming each other).
#[test]
fn a_circle_is_found() {
    let a = PathBuf::from("a.rs");
    let b = PathBuf::from("b.rs");
    let graph = BTreeMap::from([
        (a.clone(), BTreeSet::from([b.clone()])),
        (b.clone(), BTreeSet::from([a.clone()])),
    ]);
    assert_eq!(circle(&graph, &a), Some(vec![a.clone(), b.clone()]));
    let one_way = BTreeMap::from([(a.clone(), BTreeSet::from([b.clone()]))]);
    assert_eq!(circle(&one_way, &a), None);
    let paths = named_paths(
        "use super::{engine::TILE, pipelines};",
        &["gpu".into(), "x".into()],
    );
    assert!(paths.contains(&vec!["gpu".into(), "engine".into(), "TILE".into()]));
    assert!(paths.contains(&vec!["gpu".into(), "pipelines".into()]));
}

/// What a `mod.rs` may hold at its top level: module declarations, re-exports and imports (and
/// their attributes). A definition there (a function, type, constant) is something its own files
/// would import back from their front door.
fn mod_rs_definitions(text: &str) -> Vec<String> {
    const ALLOWED: [&str; 8] = [
        "mod ",
        "pub mod ",
        "pub(crate) mod ",
        "use ",
        "pub use ",
        "pub(crate) use ",
        "pub(super) use ",
        "#",
    ];
    code(text)
        .lines()
        .filter(|l| !l.is_empty() && !l.starts_with([' ', '\t', '}', ')', ']']))
        .filter(|l| !ALLOWED.iter().any(|a| l.starts_with(a)))
        .map(str::to_string)
        .collect()
}

#[test]
fn mod_rs_files_only_declare_and_re_export() {
    let mut files = Vec::new();
    rust_files(Path::new(SRC), &mut files);
    let mut found = Vec::new();
    for file in files.iter().filter(|f| f.ends_with("mod.rs")) {
        let text = std::fs::read_to_string(file).unwrap();
        for line in mod_rs_definitions(&text) {
            found.push(format!(
                "{}: {line}",
                file.strip_prefix(SRC).unwrap().display()
            ));
        }
    }
    assert!(
        found.is_empty(),
        "mod.rs files that define items:\n{}",
        found.join("\n")
    );
}

/// The check can fail: a definition in a front door is found, a declaration is not.
#[test]
fn a_definition_in_a_mod_rs_is_found() {
    let text = "//! Doc.\nmod a;\npub use a::B;\n\n/// Doc.\npub fn c() {\n    d();\n}\n";
    assert_eq!(mod_rs_definitions(text), ["pub fn c() {"]);
}
