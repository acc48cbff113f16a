//! No stale paths: every repository path that the code's comments and the docs name exists.
//!
//! Read: `src/`, `shaders/`, `build.rs`, `build/`, `docs/` and README.md. Checked there:
//! - every path rooted in `src/`, `shaders/`, `tests/`, `docs/` or `scripts/`, in backticks or
//!   in plain text, exists (a glob such as `src/**` or `tests/common/*.rs`, or a `{name}` of a
//!   format string, matches at least one);
//! - every path relative to the file that names one of those folders or a Rust, WGSL or
//!   Markdown file (`../src/gpu/shaders/interface.rs`) exists;
//! - every partial path of a Rust, WGSL or Markdown file (`gpu/pipelines/warm_up.rs`) is the
//!   end of a file's path in the repository.
//!
//! A placeholder (`src/gpu/...`, `src/…`) names its folder, which must exist. What looks like
//! such a path but is none is listed in `NOT_PATHS`, each with why.

use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The folders whose paths are checked.
const ROOTED: &[&str] = &["src", "shaders", "tests", "docs", "scripts"];

/// Text that looks like a checked path but names none, and why.
const NOT_PATHS: &[(&str, &str)] = &[(
    "src/loader/manifest_file.cpp",
    "the Khronos OpenXR loader's source (OpenXR-SDK), not this repository's",
)];

/// The characters a path is made of (with `*` of a glob and `{}` of a format string).
fn path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || "_./-*{}…".contains(c)
}

/// Every path-like word of `text` with its line number: a maximal run of path characters,
/// trailing sentence punctuation removed.
fn words(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(start) = rest.find(path_char) {
            let run = &rest[start..];
            let end = run.find(|c| !path_char(c)).unwrap_or(run.len());
            let word = &run[..end];
            rest = &run[end..];
            // A placeholder keeps its dots; other words lose a sentence's full stop.
            let word = if word.contains("...") || word.contains('…') {
                word.trim_end_matches([',', ':', ';'])
            } else {
                word.trim_end_matches(['.', ',', ':', ';'])
            };
            if word.contains('/') {
                out.push((n + 1, word.to_string()));
            }
        }
    }
    out
}

/// What a word is, for the check.
#[derive(Debug, PartialEq)]
enum Kind {
    /// Rooted in one of ROOTED, from the repository's root.
    Rooted,
    /// `./` or `../`: from the file's folder.
    Relative,
    /// `folder/file.rs`: the end of some file's path.
    Partial,
    /// Not a path this test checks.
    Other,
}

fn kind(word: &str) -> Kind {
    if ROOTED.iter().any(|r| {
        word.strip_prefix(r)
            .is_some_and(|rest| rest.starts_with('/'))
    }) {
        Kind::Rooted
    } else if word.starts_with("./") || word.starts_with("../") {
        // Only one naming the repository's files: `../src/...`, `../build/parts.rs`; not a
        // build output (`./target`) or an installed layout (`../lib/contrastxr`).
        let named = word.trim_start_matches(['.', '/']);
        match kind(named) {
            Kind::Rooted | Kind::Partial => Kind::Relative,
            _ => Kind::Other,
        }
    } else if !word.starts_with('/')
        && !word.contains("//")
        && [".rs", ".wgsl", ".md"].iter().any(|e| word.ends_with(e))
    {
        Kind::Partial
    } else {
        Kind::Other
    }
}

/// Whether `name` matches the glob component `pattern` (`*`: any characters).
fn component_matches(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((head, tail)) => {
            let Some(rest) = name.strip_prefix(head) else {
                return false;
            };
            (0..=rest.len())
                .filter(|&i| rest.is_char_boundary(i))
                .any(|i| component_matches(tail, &rest[i..]))
        }
    }
}

/// Whether the glob `pattern` (components; `**`: any number of folders) matches `path`.
fn glob_matches(pattern: &[&str], path: &[&str]) -> bool {
    match (pattern.first(), path.first()) {
        (None, None) => true,
        (Some(&"**"), _) => {
            glob_matches(&pattern[1..], path)
                || (!path.is_empty() && glob_matches(pattern, &path[1..]))
        }
        (Some(p), Some(n)) => component_matches(p, n) && glob_matches(&pattern[1..], &path[1..]),
        _ => false,
    }
}

/// A format string's `{name}` as a glob's `*`.
fn as_glob(word: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in word.chars() {
        match c {
            '{' => {
                if depth == 0 {
                    out.push('*');
                }
                depth += 1;
            }
            '}' => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

/// Whether a rooted `word` names something in `entries` (every file and folder, relative to
/// the root).
fn exists(word: &str, entries: &[String]) -> bool {
    let glob = as_glob(word);
    let pattern: Vec<&str> = glob.trim_end_matches('/').split('/').collect();
    entries
        .iter()
        .any(|e| glob_matches(&pattern, &e.split('/').collect::<Vec<_>>()))
}

/// The stale paths of one file's `text` (`file` relative to the root), as `file:line: word`.
fn stale(file: &str, text: &str, entries: &[String]) -> Vec<String> {
    let folder = Path::new(file).parent().unwrap_or(Path::new(""));
    let mut out = Vec::new();
    for (line, word) in words(text) {
        if NOT_PATHS.iter().any(|(p, _)| *p == word) {
            continue;
        }
        let found = match kind(&word) {
            Kind::Rooted => {
                // A placeholder: its folder.
                let folder = ["/...", "/…"]
                    .iter()
                    .find_map(|p| word.strip_suffix(p))
                    .unwrap_or(&word);
                exists(folder, entries)
            }
            Kind::Relative => {
                let mut path = folder.to_path_buf();
                for part in word.split('/') {
                    match part {
                        "." | "" => {}
                        ".." => {
                            path.pop();
                        }
                        _ => path.push(part),
                    }
                }
                let path = path.to_string_lossy().replace('\\', "/");
                exists(&path, entries)
            }
            Kind::Partial => {
                let word = as_glob(&word);
                let pattern: Vec<&str> = word.split('/').collect();
                entries.iter().any(|e| {
                    let parts: Vec<&str> = e.split('/').collect();
                    parts.len() >= pattern.len()
                        && glob_matches(&pattern, &parts[parts.len() - pattern.len()..])
                })
            }
            Kind::Other => true,
        };
        if !found {
            out.push(format!("{file}:{line}: {word}"));
        }
    }
    out
}

/// Every file and folder of the repository but `.git` and `target`, relative to the root.
fn entries(dir: &Path, root: &Path, out: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        let name = entry.file_name();
        if dir == root && (name == ".git" || name == "target") {
            continue;
        }
        let relative = path
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        out.push(relative);
        if path.is_dir() {
            entries(&path, root, out);
        }
    }
}

/// The text files the test reads.
fn read_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            read_files(&path, out);
        } else if path
            .extension()
            .is_some_and(|e| e == "rs" || e == "wgsl" || e == "md")
        {
            out.push(path);
        }
    }
}

#[test]
fn every_path_the_code_and_docs_name_exists() {
    let root = Path::new(ROOT);
    let mut all = Vec::new();
    entries(root, root, &mut all);
    let mut files = vec![root.join("build.rs"), root.join("README.md")];
    for dir in ["src", "shaders", "build", "docs"] {
        read_files(&root.join(dir), &mut files);
    }
    let mut checked = 0;
    let mut found = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let name = file.strip_prefix(root).unwrap().to_string_lossy();
        checked += words(&text)
            .iter()
            .filter(|(_, w)| kind(w) != Kind::Other)
            .count();
        found.extend(stale(&name, &text, &all));
    }
    assert!(
        checked > 300,
        "only {checked} paths found: is the scan broken?"
    );
    assert!(
        found.is_empty(),
        "{} paths name nothing in the repository:\n{}",
        found.len(),
        found.join("\n")
    );
}

#[test]
fn the_exceptions_are_still_needed() {
    // Each NOT_PATHS entry appears somewhere, or it goes.
    let root = Path::new(ROOT);
    let mut files = vec![root.join("build.rs"), root.join("README.md")];
    for dir in ["src", "shaders", "build", "docs"] {
        read_files(&root.join(dir), &mut files);
    }
    let text: String = files
        .iter()
        .map(|f| std::fs::read_to_string(f).unwrap())
        .collect();
    for (p, why) in NOT_PATHS {
        assert!(text.contains(p), "`{p}` ({why}) is named nowhere now");
    }
}

#[test]
fn stale_paths_are_found_in_every_form() {
    let entries: Vec<String> = [
        "src",
        "src/gpu",
        "src/gpu/pipelines",
        "src/gpu/pipelines/warm_up.rs",
        "shaders",
        "shaders/access_wide.wgsl",
        "tests",
        "tests/common",
        "tests/common/mod.rs",
        "build",
        "build/wgsl.rs",
    ]
    .map(String::from)
    .to_vec();
    let text = "\
// See src/gpu/pipelines/warm_up.rs, and src/gpu/warm_up.rs.
/// (`src/gpu/interface.rs`): gone; `src/gpu/` and src/** and `tests/common/*.rs` are there.
let p = format!(\"shaders/access_{name}.wgsl\"); let q = \"shaders/copy_{n}.wgsl\";
include!(\"../src/gpu/pipelines/warm_up.rs\"); include!(\"../src/gone.rs\");
(gpu/pipelines/warm_up.rs) (gpu/warm_up.rs) https://github.com/x/y/blob/main/src/z.rs
`src/...` and src/gpu/… are placeholders, src/gone/... one of nothing; `docs/*.md` matches nothing.";
    assert_eq!(
        stale("build/wgsl.rs", text, &entries),
        [
            "build/wgsl.rs:1: src/gpu/warm_up.rs",
            "build/wgsl.rs:2: src/gpu/interface.rs",
            "build/wgsl.rs:3: shaders/copy_{n}.wgsl",
            "build/wgsl.rs:4: ../src/gone.rs",
            "build/wgsl.rs:5: gpu/warm_up.rs",
            "build/wgsl.rs:6: src/gone/...",
            "build/wgsl.rs:6: docs/*.md",
        ]
    );
}

/// The room table of docs/architecture.md names, in each room's row, every public module of
/// that room (`pub mod` in its `mod.rs` under `src/gpu/`): a room's surface grows in the code
/// and the table says so.
#[test]
fn the_room_table_names_every_public_module() {
    let root = Path::new(ROOT);
    let table = std::fs::read_to_string(root.join("docs/architecture.md")).unwrap();
    let mut rows = 0;
    let mut missing = Vec::new();
    for row in table.lines().filter(|l| l.starts_with("| `")) {
        let Some(room) = row[3..].split('`').next().filter(|r| r.ends_with('/')) else {
            continue;
        };
        let Ok(code) = std::fs::read_to_string(root.join("src/gpu").join(room).join("mod.rs"))
        else {
            continue;
        };
        rows += 1;
        let public = code.lines().filter_map(|l| l.strip_prefix("pub mod "));
        for module in public.map(|m| m.trim_end_matches(';')) {
            if !row.contains(&format!("`{module}`")) {
                missing.push(format!("{room}: `{module}`"));
            }
        }
    }
    assert!(
        rows >= 10,
        "only {rows} rooms found: is the table's form changed?"
    );
    assert!(missing.is_empty(), "not in the room table: {missing:?}");
}
