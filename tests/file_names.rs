//! A file's name says its job: no two files under `src/` share a name unless they play the same
//! role in their folders. The roles that repeat: a folder's front door (`mod.rs`), its error
//! type (`error.rs`), a binary's root (`main.rs`, where Cargo looks for it), a subcommand's
//! file in `src/cli/`, named after the command it runs (`cli/log.rs` runs `contrastxr log`),
//! and the GPU backends' files: `src/gpu/vulkan/` and `src/gpu/opengl/` hold the same roles
//! under the same names (`conv.rs`, `offline/bench.rs`), so a name repeats there only at the
//! same place in each backend, and every backend has every role.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src");

/// Names every folder may have, each for the same role.
const SAME_ROLE: &[&str] = &["mod.rs", "error.rs", "main.rs"];

/// The GPU backends' folders: the same roles under the same names.
const BACKENDS: &[&str] = &["gpu/vulkan", "gpu/opengl"];

/// The roles every backend has, each a file or a folder of that name in the backend's folder.
const BACKEND_ROLES: &[&str] = &[
    "conv",
    "device",
    "frame",
    "offline",
    "pipelines",
    "record",
    "texels",
];

/// Where `file` sits inside its backend's folder (`offline/bench.rs`), if it is in one.
fn place_in_backend(file: &Path) -> Option<PathBuf> {
    let rel = file.strip_prefix(SRC).ok()?;
    BACKENDS
        .iter()
        .find_map(|b| rel.strip_prefix(b).ok().map(Path::to_path_buf))
}

/// Files sharing a name that play the same role: each at the same place in another backend.
fn same_place_in_each_backend(files: &[PathBuf]) -> bool {
    let places: Vec<Option<PathBuf>> = files.iter().map(|f| place_in_backend(f)).collect();
    places.iter().all(|p| p.is_some() && *p == places[0])
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

/// The subcommands' names, from the tool's command table.
fn commands() -> Vec<String> {
    let table = std::fs::read_to_string(Path::new(SRC).join("cli/command_table.rs")).unwrap();
    table
        .split("name: \"")
        .skip(1)
        .filter_map(|rest| rest.split('"').next())
        .map(str::to_string)
        .collect()
}

/// Whether `file` is a subcommand's own file: `src/cli/<command>.rs`.
fn command_file(file: &Path, commands: &[String]) -> bool {
    file.parent() == Some(&Path::new(SRC).join("cli"))
        && file
            .file_stem()
            .is_some_and(|stem| commands.iter().any(|c| stem == c.as_str()))
}

#[test]
fn no_two_files_under_src_share_a_name_for_different_jobs() {
    let commands = commands();
    assert!(
        commands.iter().any(|c| c == "log"),
        "no command names found in src/cli/command_table.rs: {commands:?}"
    );
    let mut files = Vec::new();
    rust_files(Path::new(SRC), &mut files);
    let mut by_name: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    for file in files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        if SAME_ROLE.contains(&name.as_str()) || command_file(&file, &commands) {
            continue;
        }
        by_name.entry(name).or_default().push(file);
    }
    let clashes: Vec<String> = by_name
        .iter()
        .filter(|(_, files)| files.len() > 1 && !same_place_in_each_backend(files))
        .map(|(name, files)| {
            let paths: Vec<String> = files
                .iter()
                .map(|f| f.strip_prefix(SRC).unwrap().display().to_string())
                .collect();
            format!("{name}: {}", paths.join(", "))
        })
        .collect();
    assert!(
        clashes.is_empty(),
        "files under src/ that share a name (rename one so that each name says its job):\n{}",
        clashes.join("\n")
    );
}

/// The rule's exception is narrow: a name repeated in two backends at different places (or in
/// a backend and elsewhere) is a clash.
#[test]
fn a_backend_name_at_another_place_is_a_clash() {
    let src = Path::new(SRC);
    let same = [
        src.join("gpu/vulkan/offline/bench.rs"),
        src.join("gpu/opengl/offline/bench.rs"),
    ];
    assert!(same_place_in_each_backend(&same));
    let moved = [
        src.join("gpu/vulkan/offline/bench.rs"),
        src.join("gpu/opengl/frame/bench.rs"),
    ];
    assert!(!same_place_in_each_backend(&moved));
    let outside = [src.join("gpu/vulkan/conv.rs"), src.join("cli/conv.rs")];
    assert!(!same_place_in_each_backend(&outside));
}

/// The roles of a backend folder: its files' and folders' names, `mod.rs` aside.
fn roles(backend: &Path) -> Vec<String> {
    let mut found: Vec<String> = std::fs::read_dir(backend)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir() || p.extension().is_some_and(|e| e == "rs"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|name| name != "mod")
        .collect();
    found.sort();
    found
}

/// Every backend holds the same roles under the same names, and no other: a reader who knows
/// where a job is in one backend knows where it is in the other.
#[test]
fn every_backend_has_the_same_roles() {
    for backend in BACKENDS {
        assert_eq!(
            roles(&Path::new(SRC).join(backend)),
            BACKEND_ROLES,
            "the roles of src/{backend}/"
        );
    }
}

/// The files that may be longer than [`MAX_LINES`]: the settings table, one entry per key.
const LONG_FILES: &[&str] = &["config/keys.rs"];

/// Lines a file of `src/` may have: a reader sees a file's job at once.
const MAX_LINES: usize = 500;

/// Each file of `src/` over `max` lines, as "path: lines", but those in `allowed`.
fn long_files(files: &[(PathBuf, usize)], max: usize, allowed: &[&str]) -> Vec<String> {
    files
        .iter()
        .filter(|(path, lines)| {
            let rel = path.strip_prefix(SRC).unwrap_or(path);
            *lines > max && !allowed.iter().any(|a| rel == Path::new(a))
        })
        .map(|(path, lines)| format!("{}: {lines}", path.display()))
        .collect()
}

#[test]
fn no_file_is_over_500_lines_but_the_settings_table() {
    let mut files = Vec::new();
    rust_files(Path::new(SRC), &mut files);
    let counted: Vec<(PathBuf, usize)> = files
        .into_iter()
        .map(|f| {
            let lines = std::fs::read_to_string(&f).unwrap().lines().count();
            (f, lines)
        })
        .collect();
    let long = long_files(&counted, MAX_LINES, LONG_FILES);
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn a_long_file_is_found_and_the_table_allowed() {
    let src = Path::new(SRC);
    let files = [
        (src.join("gpu/a.rs"), 501),
        (src.join("gpu/b.rs"), 500),
        (src.join("config/keys.rs"), 900),
    ];
    assert_eq!(
        long_files(&files, MAX_LINES, LONG_FILES),
        [format!("{}: 501", src.join("gpu/a.rs").display())]
    );
}
