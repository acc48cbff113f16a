//! The files of `src/` import each other in one direction only: no file reaches, through the
//! modules it names (`use super::x`, `crate::a::b` paths), back to itself. A circle means two
//! files each need the other, so neither can be read, changed or tested alone.
//!
//! A module's front door (`mod.rs`, the crate roots) only declares and re-exports its files: a
//! name taken through it counts as an import of the file that defines it (`super::Thing` with
//! `pub use file::Thing` in the folder's mod.rs is an import of `file.rs`), so a two-way tie
//! through the re-exports is a circle too; there are 0 such ties. A path inside an inline module
//! (`mod reference { use super::super::pixel::*; }`) is read from that module, as rustc reads
//! it. Siblings name each other by their own modules, not through their folder's re-exports.
//! Test modules (`mod tests`) are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src");

/// The files of a source tree and their text (the real `src/`, or one made up by a test).
type Tree = BTreeMap<PathBuf, String>;

/// Every .rs file of `src/` with its text.
fn src_tree() -> Tree {
    let mut files = Vec::new();
    rust_files(Path::new(SRC), &mut files);
    files
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(&f).unwrap();
            (f, text)
        })
        .collect()
}

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

/// The module path of a file relative to its crate root, and that root's folder (`src` is the
/// tree's `src/` folder).
fn module_of(src: &Path, file: &Path) -> (PathBuf, Vec<String>) {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    let mut root = src.to_path_buf();
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
fn resolve(tree: &Tree, root: &Path, path: &[String]) -> Option<PathBuf> {
    (1..=path.len()).rev().find_map(|n| {
        let file = root.join(path[..n].join("/")).with_extension("rs");
        tree.contains_key(&file).then_some(file)
    })
}

/// The code of a file without its test module and comments.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    // Line comments go; a `//` in a string literal ("https://...") stays.
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < text.len() {
        if let Some(end) = literal_end(text, i) {
            out.push_str(&text[i..end]);
            i = end;
        } else if text[i..].starts_with("//") {
            i += text[i..].find('\n').unwrap_or(text.len() - i);
        } else {
            let c = text[i..].chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// Where the string or character literal that starts at byte `i` of `code` ends (the byte after
/// it), if one starts there: `"..."`, `r"..."`, `r#"..."#`, `'{'`, `'\''`; a lifetime (`'a`)
/// is none.
fn literal_end(code: &str, i: usize) -> Option<usize> {
    let rest = &code[i..];
    if rest.starts_with('"') {
        let hashes = code[..i].chars().rev().take_while(|&c| c == '#').count();
        let raw = code[..i - hashes].ends_with('r');
        let close = format!("\"{}", "#".repeat(hashes));
        let mut j = 1;
        while j < rest.len() {
            if !raw && rest[j..].starts_with('\\') {
                j += 1 + rest[j + 1..].chars().next().map_or(0, char::len_utf8);
            } else if rest[j..].starts_with(&close) {
                return Some(i + j + close.len());
            } else {
                j += rest[j..].chars().next().map_or(1, char::len_utf8);
            }
        }
        return Some(code.len());
    }
    let mut chars = rest.strip_prefix('\'')?.char_indices();
    match chars.next()? {
        (_, '\\') => rest[3..].find('\'').map(|n| i + 3 + n + 1),
        (_, c) => (chars.next()?.1 == '\'').then(|| i + 1 + c.len_utf8() + 1),
    }
}

/// The inline modules (`mod name { .. }`, `pub(super) mod name { .. }`) of a file's code: each
/// one's name and the span of its body, in bytes. Braces in string and character literals do
/// not count.
fn inline_modules(code: &str) -> Vec<(String, std::ops::Range<usize>)> {
    let mut found = Vec::new();
    // The open braces: where each opened, and the inline module it opens, if it does.
    let mut open: Vec<(usize, Option<String>)> = Vec::new();
    let mut i = 0;
    while i < code.len() {
        if let Some(end) = literal_end(code, i) {
            i = end;
            continue;
        }
        let c = code[i..].chars().next().unwrap();
        if c == '{' {
            let head = code[..i].trim_end();
            let name_at = head
                .rfind(|c: char| !(c.is_alphanumeric() || c == '_'))
                .map_or(0, |n| n + 1);
            let keyword = head[..name_at].trim_end();
            let is_mod = keyword
                .strip_suffix("mod")
                .is_some_and(|s| !s.ends_with(|c: char| c.is_alphanumeric() || c == '_'));
            let name = (is_mod && name_at < head.len()).then(|| head[name_at..].to_string());
            open.push((i, name));
        } else if c == '}' {
            if let Some((start, Some(name))) = open.pop() {
                found.push((name, start..i));
            }
        }
        i += c.len_utf8();
    }
    found
}

/// The module paths a file's code names, from `super::`/`crate::` paths and `use` groups. A
/// path inside an inline module (`mod reference { use super::super::pixel::*; }`) starts
/// from that module, not from the file's.
fn named_paths(code: &str, module: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes: Vec<char> = code.chars().collect();
    let text: String = bytes.iter().collect();
    let inline = inline_modules(&text);
    for start in ["super::", "crate::"] {
        for (at, _) in text.match_indices(start) {
            let before = text[..at].chars().last();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            // The module the path is written in: the file's, and the inline ones around it,
            // outermost first.
            let mut here = module.to_vec();
            let mut around: Vec<_> = inline.iter().filter(|(_, s)| s.contains(&at)).collect();
            around.sort_by_key(|(_, s)| s.start);
            here.extend(around.into_iter().map(|(name, _)| name.clone()));
            let mut base: Vec<String> = if start == "crate::" {
                Vec::new()
            } else {
                here[..here.len().saturating_sub(1)].to_vec()
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

/// The re-exports of a front door's code (`pub use`, `pub(crate) use`, `pub(super) use`,
/// `pub(in path) use`): each declaration's text up to its `;`.
fn re_exports(code: &str) -> Vec<&str> {
    code.match_indices("pub")
        .filter_map(|(at, _)| {
            let rest = &code[at + 3..];
            let rest = match rest.strip_prefix('(') {
                Some(r) => &r[r.find(')')? + 1..],
                None => rest,
            };
            let decl = rest.strip_prefix(" use ")?;
            Some(&decl[..decl.find(';')?])
        })
        .collect()
}

/// The file that defines `path`'s item when `path` names it through a folder's front door
/// (`super::Thing` where the folder's mod.rs re-exports `file::Thing` or `file::{Thing, ..}`).
fn through_front_door(tree: &Tree, root: &Path, path: &[String]) -> Option<PathBuf> {
    (1..path.len()).rev().find_map(|n| {
        let door = root.join(path[..n].join("/")).join("mod.rs");
        let door = if n == 0 { root.join("lib.rs") } else { door };
        let text = tree.get(&door)?;
        let item = &path[n];
        let code = code(text);
        re_exports(&code).into_iter().find_map(|decl| {
            expand(decl)
                .into_iter()
                .find(|p| p.last() == Some(item))
                .and_then(|p| {
                    let mut full = path[..n].to_vec();
                    full.extend(p[..p.len() - 1].iter().cloned());
                    resolve(tree, root, &full)
                })
        })
    })
}

/// Each file's imports of other files, also through a folder's re-exports (`src`: the tree's
/// `src/` folder).
fn import_graph(tree: &Tree, src: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut graph = BTreeMap::new();
    for (file, text) in tree {
        let (root, module) = module_of(src, file);
        let targets: BTreeSet<PathBuf> = named_paths(&code(text), &module)
            .iter()
            .filter_map(|p| resolve(tree, &root, p).or_else(|| through_front_door(tree, &root, p)))
            .filter(|t| t != file)
            .collect();
        graph.insert(file.clone(), targets);
    }
    graph
}

/// Every circle of `graph`, each as its files (relative to `src`) sorted and joined by " <-> ".
fn circles(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>, src: &Path) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for file in graph.keys() {
        if let Some(c) = circle(graph, file) {
            let mut names: Vec<String> = c
                .iter()
                .map(|f| f.strip_prefix(src).unwrap().display().to_string())
                .collect();
            names.sort();
            found.insert(names.join(" <-> "));
        }
    }
    found
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

/// Circles, through a folder's re-exports or not, that `src/` has: none. (The last ones,
/// algorithm/methods.rs <-> algorithm/params.rs, then methods.rs <-> pixel.rs and <-> scaled.rs
/// through methods.rs's inline `mod reference`, were undone.)
#[test]
fn no_file_of_src_imports_itself_through_others() {
    let tree = src_tree();
    let graph = import_graph(&tree, Path::new(SRC));
    assert!(graph.len() > 50, "found only {} files", graph.len());
    let found = circles(&graph, Path::new(SRC));
    assert!(found.is_empty(), "import circles:\n{}", {
        let list: Vec<_> = found.into_iter().collect();
        list.join("\n")
    });
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

/// The check follows a path from inside an inline module from that module: `a.rs` of a made-up
/// folder names `b.rs`'s function only from its `mod inner` (`super::super::b`), and `b.rs`
/// names `a.rs`'s type back: a circle. (Taken from the file's module, `super::super::b` would
/// name a `b` beside the folder, and the circle would be missed.)
#[test]
fn a_circle_through_an_inline_module_is_found() {
    let src = Path::new("/made-up/src");
    let file = |p: &str, text: &str| (src.join(p), text.to_string());
    let mut tree = Tree::from([
        file("lib.rs", "pub mod room;\n"),
        file("room/mod.rs", "pub mod a;\nmod b;\n"),
        file(
            "room/a.rs",
            "pub enum R {\n    F(fn()),\n}\nconst S: &str = \"}\";\nconst C: char = '{';\n\
             mod inner {\n    pub(super) use super::super::b::*;\n    \
             fn g<'x>(_: &'x str) {\n        let _ = \"{\";\n    }\n}\n\
             pub static F: R = R::F(inner::f);\n",
        ),
        file(
            "room/b.rs",
            "use super::a::R;\npub fn f() {}\nfn g(_: R) {}\n",
        ),
    ]);
    let module = ["room".to_string(), "a".to_string()];
    let paths = named_paths(&code(&tree[&src.join("room/a.rs")]), &module);
    assert_eq!(paths, [["room", "b"]]);
    let found = circles(&import_graph(&tree, src), src);
    assert_eq!(
        found,
        BTreeSet::from(["room/a.rs <-> room/b.rs".to_string()])
    );
    // `super::` in an inline module names its file: no import of another file.
    tree.insert(
        src.join("room/b.rs"),
        "pub fn f() {}\nmod fake {\n    use super::f;\n}\n".into(),
    );
    assert!(circles(&import_graph(&tree, src), src).is_empty());
    let b = import_graph(&tree, src)[&src.join("room/b.rs")].clone();
    assert!(b.is_empty(), "{b:?}");
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
    // A re-export to a named ancestor only (`pub(in crate::gpu::opengl) use ..`).
    let restricted_use = |l: &str| l.starts_with("pub(in ") && l.contains(") use ");
    code(text)
        .lines()
        .filter(|l| !l.is_empty() && !l.starts_with([' ', '\t', '}', ')', ']']))
        .filter(|l| !ALLOWED.iter().any(|a| l.starts_with(a)) && !restricted_use(l))
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

/// The check sees a two-way tie through a folder's front door: `a.rs` and `b.rs` of a made-up
/// folder each take the other's item from their `mod.rs`, which only re-exports them.
#[test]
fn a_tie_through_a_mod_rs_is_found() {
    let src = Path::new("/made-up/src");
    let file = |p: &str, text: &str| (src.join(p), text.to_string());
    let mut tree = Tree::from([
        file("lib.rs", "pub mod room;\n"),
        file(
            "room/mod.rs",
            "mod a;\nmod b;\npub use a::A;\npub(crate) use b::B;\n",
        ),
        file("room/a.rs", "use super::B;\npub struct A(B);\n"),
        file(
            "room/b.rs",
            "use crate::room::A;\npub struct B;\nfn f(_: A) {}\n",
        ),
    ]);
    let found = circles(&import_graph(&tree, src), src);
    assert_eq!(
        found,
        BTreeSet::from(["room/a.rs <-> room/b.rs".to_string()])
    );
    // One way only: no circle.
    tree.insert(src.join("room/b.rs"), "pub struct B;\n".into());
    assert!(circles(&import_graph(&tree, src), src).is_empty());
}

/// Each file that names `path` through its own folder's front door (a sibling's item taken
/// from the folder's re-exports instead of the sibling's own module), with that path.
fn through_own_door(tree: &Tree, src: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for (file, text) in tree {
        if file.ends_with("mod.rs") || file.ends_with("lib.rs") || file.ends_with("main.rs") {
            continue;
        }
        let (root, module) = module_of(src, file);
        let folder = &module[..module.len() - 1];
        for p in named_paths(&code(text), &module) {
            let via_door = p.len() == folder.len() + 1 && p.starts_with(folder);
            if via_door
                && resolve(tree, &root, &p).is_none()
                && through_front_door(tree, &root, &p).is_some()
            {
                let rel = file.strip_prefix(src).unwrap().display();
                found.push(format!("{rel}: {}", p.join("::")));
            }
        }
    }
    found
}

/// Siblings import each other from their own modules, not through their folder's
/// re-exports, so the picture of who uses whom stays true.
#[test]
fn siblings_import_each_other_by_their_own_names() {
    let found = through_own_door(&src_tree(), Path::new(SRC));
    assert!(
        found.is_empty(),
        "files taking a sibling's item from their folder's re-exports:\n{}",
        found.join("\n")
    );
}

/// The check can fail: `super::B` in a file whose folder re-exports `b::B` is found.
#[test]
fn a_sibling_through_the_front_door_is_found() {
    let src = Path::new("/made-up/src");
    let tree = Tree::from([
        (src.join("lib.rs"), "pub mod room;\n".to_string()),
        (
            src.join("room/mod.rs"),
            "mod a;\nmod b;\npub use b::B;\n".into(),
        ),
        (src.join("room/a.rs"), "use super::B;\n".into()),
        (src.join("room/b.rs"), "pub struct B;\n".into()),
    ]);
    assert_eq!(through_own_door(&tree, src), ["room/a.rs: room::B"]);
}

/// The fields of `text`'s types that are public (`pub`, `pub(crate)`) and of a Vulkan type.
fn public_vulkan_fields(text: &str) -> Vec<String> {
    code(text)
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("pub ") || l.starts_with("pub(crate) "))
        .filter(|l| {
            let field = l.split_once(' ').map_or("", |(_, rest)| rest);
            let is_field = field
                .split_once(':')
                .is_some_and(|(name, _)| name.chars().all(|c| c.is_alphanumeric() || c == '_'));
            is_field && field.contains("vk::")
        })
        .map(str::to_string)
        .collect()
}

/// Each public `vk::` field of `tree` outside the Vulkan device room (`gpu/vulkan/device/`) and
/// the XR test client (`bin/`, a crate of its own), as "file: field".
fn public_handle_fields(tree: &Tree, src: &Path) -> Vec<String> {
    let device = src.join("gpu/vulkan/device");
    let client = src.join("bin");
    let mut found = Vec::new();
    for (file, text) in tree {
        if file.starts_with(&device) || file.starts_with(&client) {
            continue;
        }
        for field in public_vulkan_fields(text) {
            let rel = file.strip_prefix(src).unwrap().display().to_string();
            found.push(format!("{rel}: {field}"));
        }
    }
    found
}

/// Raw Vulkan handles stay in the GPU engine's device room: no type elsewhere in `src/` has a
/// `pub` or `pub(crate)` field of a `vk::` type (the frame's, the pipelines' and the layer's
/// swapchains' keep theirs private, with accessors; `pub(super)`, visible to its own folder
/// only, is allowed). The XR test client (`src/bin/`) is a crate of its own and is left out.
#[test]
fn raw_handles_are_public_only_in_the_device_room() {
    let found = public_handle_fields(&src_tree(), Path::new(SRC));
    assert!(
        found.is_empty(),
        "public Vulkan fields outside gpu/vulkan/device/:\n{}",
        found.join("\n")
    );
}

/// The check can fail: a public handle field is found; a private one, one visible to its room
/// only (`pub(super)`) and a function's argument are not. It looks at every file of `src/` but
/// the device room's and the XR client's.
#[test]
fn a_public_handle_field_is_found() {
    let text =
        "pub struct V {\n    pub image: vk::Image,\n    pub(super) view: vk::ImageView,\n    \
                format: vk::Format,\n}\npub fn f(x: vk::Image) {}\n";
    assert_eq!(public_vulkan_fields(text), ["pub image: vk::Image,"]);
    let src = Path::new("/made-up/src");
    let field = "pub struct S {\n    pub(crate) images: Vec<vk::Image>,\n}\n";
    let tree = Tree::from([
        (src.join("layer/state.rs"), field.to_string()),
        (src.join("gpu/vulkan/frame/view.rs"), field.into()),
        (src.join("gpu/vulkan/device/image.rs"), field.into()),
        (src.join("bin/xr_client/gpu.rs"), field.into()),
    ]);
    assert_eq!(
        public_handle_fields(&tree, src),
        [
            "gpu/vulkan/frame/view.rs: pub(crate) images: Vec<vk::Image>,",
            "layer/state.rs: pub(crate) images: Vec<vk::Image>,",
        ]
    );
}

/// The engine's core (`src/gpu/core/`) is every graphics backend's: it names no graphics API
/// and no backend. Its files are there to be read (the check cannot pass on an empty folder).
#[test]
fn the_core_names_no_graphics_api() {
    let core = Path::new(SRC).join("gpu/core");
    let mut found = Vec::new();
    let mut read = 0;
    for (file, text) in src_tree() {
        if !file.starts_with(&core) {
            continue;
        }
        read += 1;
        let code = code(&text);
        let backend = code
            .match_indices("crate::gpu::")
            .any(|(at, m)| !code[at + m.len()..].starts_with("core::"));
        // A path that starts with `word` (not `std::hash::` for `ash::`).
        let names = |word: &str| {
            code.match_indices(word).any(|(at, _)| {
                let before = code[..at].chars().last();
                !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
            })
        };
        for (bad, named) in [
            ("ash::", names("ash::")),
            ("vk::", names("vk::")),
            ("gpu_allocator", names("gpu_allocator")),
            ("gl::", names("gl::")),
            ("a backend of crate::gpu", backend),
        ] {
            if named {
                let rel = file.strip_prefix(SRC).unwrap().display().to_string();
                found.push(format!("{rel}: {bad}"));
            }
        }
    }
    assert!(read > 10, "read only {read} files of src/gpu/core/");
    assert!(found.is_empty(), "the core names:\n{}", found.join("\n"));
}

/// The two rooms of `src` that `from` and `to` sit in where their paths part: the first
/// differing entry of each under the folder they share (a folder, or a file).
fn rooms_apart(src: &Path, from: &Path, to: &Path) -> Option<(PathBuf, PathBuf)> {
    let (a, b) = (from.strip_prefix(src).ok()?, to.strip_prefix(src).ok()?);
    let mut shared = src.to_path_buf();
    for (x, y) in a.iter().zip(b.iter()) {
        if x != y {
            return Some((shared.join(x), shared.join(y)));
        }
        shared.push(x);
    }
    None
}

/// Every pair of rooms (folders or files, at any depth) that import each other, each as
/// "a <-> b" relative to `src`.
fn room_ties(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>, src: &Path) -> BTreeSet<String> {
    let mut edges = BTreeSet::new();
    for (from, targets) in graph {
        for to in targets {
            edges.extend(rooms_apart(src, from, to));
        }
    }
    edges
        .iter()
        .filter(|(a, b)| a < b && edges.contains(&(b.clone(), a.clone())))
        .map(|(a, b)| {
            let rel = |p: &Path| p.strip_prefix(src).unwrap().display().to_string();
            format!("{} <-> {}", rel(a), rel(b))
        })
        .collect()
}

/// Rooms import each other in one direction too, not only files: no folder reaches into a
/// neighbour (a folder or a file beside it) that reaches back, even where no file is on a
/// circle. (The last three: `blurred_texels.rs` <-> `gpu/`, the Vulkan pipelines' warm-up <->
/// the recorder, `layer/state.rs` <-> `layer/graphics/`.)
#[test]
fn no_two_rooms_import_each_other() {
    let graph = import_graph(&src_tree(), Path::new(SRC));
    let ties = room_ties(&graph, Path::new(SRC));
    assert!(ties.is_empty(), "rooms that import each other:\n{}", {
        let list: Vec<_> = ties.into_iter().collect();
        list.join("\n")
    });
}

/// The check sees a tie between a file and a folder beside it that no file circle shows.
#[test]
fn a_tie_between_rooms_is_found() {
    let src = Path::new("/made-up/src");
    let tree = Tree::from([
        (src.join("lib.rs"), "mod packing;\nmod gpu;\n".to_string()),
        (
            src.join("packing.rs"),
            "use crate::gpu::interface::BITS;\n".into(),
        ),
        (
            src.join("gpu/mod.rs"),
            "pub mod interface;\npub mod slots;\n".into(),
        ),
        (
            src.join("gpu/interface.rs"),
            "pub const BITS: u32 = 10;\n".into(),
        ),
        (
            src.join("gpu/slots.rs"),
            "use crate::packing::pack;\n".into(),
        ),
    ]);
    let graph = import_graph(&tree, src);
    assert!(circles(&graph, src).is_empty());
    assert_eq!(
        room_ties(&graph, src).into_iter().collect::<Vec<_>>(),
        ["gpu <-> packing.rs"]
    );
}

/// The files of one GPU backend that import a file of another, as "from -> to" (relative to
/// `src`).
fn across_backends(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>, src: &Path) -> Vec<String> {
    let backend = |f: &Path| {
        ["gpu/vulkan", "gpu/opengl"]
            .into_iter()
            .find(|b| f.starts_with(src.join(b)))
    };
    let rel = |p: &Path| p.strip_prefix(src).unwrap().display().to_string();
    let mut found = Vec::new();
    for (from, targets) in graph {
        for to in targets {
            if let (Some(a), Some(b)) = (backend(from), backend(to)) {
                if a != b {
                    found.push(format!("{} -> {}", rel(from), rel(to)));
                }
            }
        }
    }
    found
}

/// A backend stands on the core alone: what two backends share lives in `gpu/core/` (the
/// benchmark's cases, the cache files), not in one backend that the other reaches into.
#[test]
fn no_backend_imports_another() {
    let found = across_backends(&import_graph(&src_tree(), Path::new(SRC)), Path::new(SRC));
    assert!(
        found.is_empty(),
        "imports across backends:\n{}",
        found.join("\n")
    );
}

/// The check sees an OpenGL file reaching into Vulkan's rooms.
#[test]
fn an_import_across_backends_is_found() {
    let src = Path::new("/made-up/src");
    let tree = Tree::from([
        (
            src.join("gpu/vulkan/offline/bench.rs"),
            "pub const RUNS: u32 = 3;\n".to_string(),
        ),
        (
            src.join("gpu/opengl/offline/bench.rs"),
            "use crate::gpu::vulkan::offline::bench::RUNS;\n".into(),
        ),
    ]);
    let graph = import_graph(&tree, src);
    assert_eq!(
        across_backends(&graph, src),
        ["gpu/opengl/offline/bench.rs -> gpu/vulkan/offline/bench.rs"]
    );
}
