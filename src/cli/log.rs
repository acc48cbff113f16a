//! `contrastxr log`: the layer's log lines of the last app that loaded it (from the file the
//! layer writes, `$XDG_STATE_HOME/contrastxr/layer.log`, and its rotated predecessor).

use super::args::{Args, Opt};
use super::error::{print, CliError};
use contrastxr::layer::{log, log_file};

pub const OPTIONS: &[Opt] = &[Opt::flag("--all"), Opt::flag("--path")];

pub fn usage() -> String {
    "usage: contrastxr log [--all | --path]\n\n\
     Prints the layer's log lines of the last app that loaded the layer: its start, the\n\
     settings it ran with, and every change and warning since, each line with its UTC time.\n\
     --all:  every line of the log (layer.log.1, then layer.log).\n\
     --path: the log file's path ($XDG_STATE_HOME/contrastxr/layer.log, default\n\
     \x20       ~/.local/state/contrastxr/layer.log; it is rotated to layer.log.1 at 1 MiB).\n"
        .to_string()
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let (all, path_only) = (args.flag("--all"), args.flag("--path"));
    args.finish()?;
    let path = log::path().ok_or(CliError::Failure(
        "neither XDG_STATE_HOME nor HOME is set, so there is no log file".into(),
    ))?;
    if path_only {
        print(&format!("{}\n", path.display()));
        return Ok(());
    }
    // The layer caps each file at log_file::MAX_BYTES; anything else there is not read whole.
    let read = |p: &std::path::Path| {
        contrastxr::user_file::read(p, 2 * log_file::MAX_BYTES)
            .map(|b| String::from_utf8_lossy(&b).into_owned())
            .unwrap_or_default()
    };
    let text = read(&log_file::rotated(&path)) + &read(&path);
    if text.is_empty() {
        return Err(CliError::Failure(format!(
            "no layer log at {}: no app has run with the layer yet",
            path.display()
        )));
    }
    if all {
        print(&text);
        return Ok(());
    }
    let lines = log::last_app(&text);
    if lines.is_empty() {
        return Err(CliError::Failure(format!(
            "{} has no start of an app in it (written by an older contrastxr?); try --all",
            path.display()
        )));
    }
    print(&(lines.join("\n") + "\n"));
    Ok(())
}
