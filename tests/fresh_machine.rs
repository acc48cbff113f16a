//! `scripts/test`'s preamble (everything it runs before installing, building and testing) passes
//! on a fresh machine: a HOME with no `.local/state`, `.cache/contrastxr` or `.config/contrastxr`,
//! and XDG folders that are new and empty or not there at all. `.ci/run` runs the whole test
//! command against new empty XDG folders too; this test keeps the class covered for a plain
//! `cargo test`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn fresh_home(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("fresh-machine")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `scripts/test --preamble` with `home` as HOME, the XDG variables removed, then `env` added.
fn preamble(home: &Path, env: &[(&str, &Path)]) -> Output {
    let mut cmd = Command::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/test"));
    cmd.arg("--preamble").env("HOME", home);
    for var in [
        "XDG_STATE_HOME",
        "XDG_CONFIG_HOME",
        "XDG_CACHE_HOME",
        "SUDO_USER",
        "SUDO_UID",
    ] {
        cmd.env_remove(var);
    }
    cmd.envs(env.iter().copied()).output().unwrap()
}

#[track_caller]
fn assert_passes(o: &Output, log_folder: &Path) {
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{}\n{out}\n{err}", o.status);
    let says = format!("the layer log folder is {}", log_folder.display());
    assert!(out.contains(&says), "{says:?} not in {out}");
}

#[test]
fn the_preamble_passes_with_no_state_folder() {
    let home = fresh_home("no-state");
    let o = preamble(&home, &[]);
    assert_passes(&o, &home.join(".local/state/contrastxr"));
    assert!(!home.join(".local").exists(), "the preamble made folders");
}

#[test]
fn the_preamble_passes_with_new_empty_xdg_folders() {
    let home = fresh_home("empty-xdg");
    let (state, config) = (home.join("state"), home.join("config"));
    std::fs::create_dir_all(&state).unwrap();
    std::fs::create_dir_all(&config).unwrap();
    let o = preamble(
        &home,
        &[("XDG_STATE_HOME", &state), ("XDG_CONFIG_HOME", &config)],
    );
    assert_passes(&o, &state.join("contrastxr"));
}

#[test]
fn the_preamble_reads_a_log_folder_that_exists() {
    let home = fresh_home("with-log");
    let log = home.join(".local/state/contrastxr");
    std::fs::create_dir_all(&log).unwrap();
    std::fs::write(log.join("layer.log"), "a line\n").unwrap();
    assert_passes(&preamble(&home, &[]), &log);
}
