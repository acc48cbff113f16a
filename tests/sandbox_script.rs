//! `scripts/xr-sandbox run` refuses a missing or stale default layer library, which would make
//! the app run without the layer, or with an old one, and names `CONTRASTXR_LAYER_LIB` (root
//! only: the script's `run` needs it; the sandbox root itself is never reached, its folder is a
//! scratch one). A library named by `CONTRASTXR_LAYER_LIB` is taken as given
//! (tests/xr_runtime.rs names a missing one to see the loader's message).

use std::path::{Path, PathBuf};
use std::process::Output;

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("sandbox-script")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("debug")).unwrap();
    dir
}

/// Makes `path` last modified `seconds` ago.
fn set_age(path: &Path, seconds: u64) {
    let when = std::time::SystemTime::now() - std::time::Duration::from_secs(seconds);
    let file = std::fs::File::options().write(true).open(path).unwrap();
    file.set_modified(when).unwrap();
}

/// `xr-sandbox run -- true` with `target` as the target folder and `env` added.
fn run(target: &Path, env: &[(&str, &str)]) -> Output {
    std::process::Command::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/xr-sandbox"))
        .args(["run", "--", "true"])
        .env_remove("CONTRASTXR_LAYER_LIB")
        .env("CARGO_TARGET_DIR", target)
        .env("CONTRASTXR_SANDBOX_DIR", target.join("sandbox"))
        .envs(env.iter().copied())
        .output()
        .expect("run scripts/xr-sandbox")
}

fn refused(o: &Output, says: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(125), "{err}");
    assert!(err.contains(says), "{says:?} not in {err}");
    assert!(err.contains("CONTRASTXR_LAYER_LIB"), "{err}");
}

#[test]
fn a_missing_or_stale_layer_library_is_refused() {
    if !is_root() {
        eprintln!("skipped: scripts/xr-sandbox run needs root");
        return;
    }
    let target = scratch("refused");
    let lib = target.join("debug/libcontrastxr.so");
    refused(
        &run(&target, &[]),
        &format!("no layer library at {}", lib.display()),
    );
    // Built, then a source of it changed: cargo's dep-info beside it names the source.
    let source = target.join("lib.rs");
    std::fs::write(&lib, b"\x7fELF").unwrap();
    let deps = format!("{}: {}\n", lib.display(), source.display());
    std::fs::write(target.join("debug/libcontrastxr.d"), deps).unwrap();
    std::fs::write(&source, "// changed").unwrap();
    set_age(&lib, 60);
    refused(
        &run(&target, &[]),
        &format!("{} is older than {}", lib.display(), source.display()),
    );
    // A fresh library, or one named (even a missing one), passes this check and meets the
    // next: the (scratch) root.
    set_age(&source, 120);
    let missing = target.join("nothing.so");
    for env in [
        vec![],
        vec![("CONTRASTXR_LAYER_LIB", missing.to_str().unwrap())],
    ] {
        let o = run(&target, &env);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("the sandbox root is not set up"), "{err}");
    }
}
