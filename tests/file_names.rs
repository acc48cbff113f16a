//! A file's name says its job: no two files under `src/` share a name unless they play the same
//! role in their folders. The roles that repeat: a folder's front door (`mod.rs`), its error
//! type (`error.rs`), a binary's root (`main.rs`, where Cargo looks for it), and a subcommand's
//! file in `src/cli/`, named after the command it runs (`cli/log.rs` runs `contrastxr log`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src");

/// Names every folder may have, each for the same role.
const SAME_ROLE: &[&str] = &["mod.rs", "error.rs", "main.rs"];

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
        .filter(|(_, files)| files.len() > 1)
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
