//! The layer's log: one startup line, then only changes and warnings, each once. Lines go to
//! stderr and to `$XDG_STATE_HOME/contrastxr/layer.log` (default `~/.local/state`).
//! `CONTRASTXR_LOG=debug` adds debug lines.

use std::collections::HashSet;
use std::io::Write;
use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};

struct Log {
    file: Option<std::fs::File>,
    seen: HashSet<String>,
    debug: bool,
}

fn log_path() -> Option<PathBuf> {
    let state = std::env::var_os("XDG_STATE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/state")))?;
    Some(state.join("contrastxr").join("layer.log"))
}

fn open_file() -> Option<std::fs::File> {
    let path = log_path()?;
    std::fs::create_dir_all(path.parent()?).ok()?;
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .ok()
}

fn log() -> &'static Mutex<Log> {
    static LOG: OnceLock<Mutex<Log>> = OnceLock::new();
    LOG.get_or_init(|| {
        Mutex::new(Log {
            file: open_file(),
            seen: HashSet::new(),
            debug: std::env::var("CONTRASTXR_LOG").is_ok_and(|v| v == "debug"),
        })
    })
}

fn write_line(log: &mut Log, line: &str) {
    eprintln!("contrastxr: {line}");
    if let Some(f) = log.file.as_mut() {
        let _ = writeln!(f, "[pid {}] {line}", std::process::id());
    }
}

/// Logs a line unconditionally (startup, state changes).
pub fn info(line: &str) {
    if let Ok(mut log) = log().lock() {
        write_line(&mut log, line);
    }
}

/// Logs a line the first time `key` is seen in this process; per-frame conditions use this.
pub fn once(key: &str, line: &str) {
    if let Ok(mut log) = log().lock() {
        if log.seen.insert(key.to_string()) {
            write_line(&mut log, line);
        }
    }
}

pub fn debug(line: &str) {
    if let Ok(mut log) = log().lock() {
        if log.debug {
            write_line(&mut log, line);
        }
    }
}
