//! `contrastxr toggle` and `contrastxr set`: live control of running apps through the config
//! file, which every running app's layer watches (a change applies within a second).

use super::args::{Args, Opt};
use super::error::{print, CliError};

/// `--app NAME`, also taken by `config`.
pub const OPTIONS: &[Opt] = &[Opt::value("--app", "NAME")];
use contrastxr::config::{self, edit, Env};

pub fn usage() -> String {
    "usage: contrastxr toggle [--app NAME] [MODE]\n\
     \x20      contrastxr set [--app NAME] KEY VALUE   (or KEY=VALUE)\n\n\
     Both edit the config file that running apps watch ($CONTRASTXR_CONFIG, else\n\
     $XDG_CONFIG_HOME/contrastxr/config.toml; a system file is copied there first), so the\n\
     change reaches every running app within a second; with --app, only [app.\"NAME\"].\n\
     toggle: mode off <-> MODE (default enhance), for A/B comparison.\n\
     set:    one setting, checked first, e.g. `contrastxr set lambda_e 0.6`,\n\
     \x20       `contrastxr set mode split`, `contrastxr set lambda_e -0.1` (refused: out of range),\n\
     \x20       `contrastxr set fov_offset=-0.1,0.2` (or `set -- fov_offset -0.1,0.2`).\n\
     An app started with the setting's CONTRASTXR_* variable keeps the variable's value.\n"
        .to_string()
}

fn target() -> Result<(std::path::PathBuf, Option<std::path::PathBuf>), CliError> {
    config::path::for_writing(&Env::capture()).map_err(CliError::Failure)
}

fn warn_if_overridden(key: &config::Key) {
    if std::env::var_os(key.env).is_some() {
        eprintln!(
            "note: {} is set in this shell; an app started with it ignores the file's {}",
            key.env, key.name
        );
    }
}

pub fn run_toggle(args: &mut Args) -> Result<(), CliError> {
    let app = args.value(&["--app"])?;
    let pos = args.positional();
    args.finish()?;
    let on_mode = match pos.as_slice() {
        [] => "enhance",
        [mode] => mode.as_str(),
        _ => return Err(CliError::Usage("toggle takes at most one MODE".into())),
    };
    let (path, seed) = target()?;
    let mode = config::key("mode").expect("mode is a key");
    warn_if_overridden(mode);
    let now =
        edit::toggle(&path, seed.as_deref(), app.as_deref(), on_mode).map_err(CliError::Failure)?;
    print(&format!("mode = {now:?} in {}\n", path.display()));
    Ok(())
}

pub fn run_set(args: &mut Args) -> Result<(), CliError> {
    let app = args.value(&["--app"])?;
    let pos = args.positional();
    args.finish()?;
    let (name, text) = match pos.as_slice() {
        [pair] if pair.contains('=') => pair.split_once('=').expect("checked"),
        [name, value] => (name.as_str(), value.as_str()),
        _ => return Err(CliError::Usage("set takes KEY VALUE".into())),
    };
    let key = config::key(name.trim()).ok_or_else(|| {
        let known: Vec<&str> = config::KEYS.iter().map(|k| k.name).collect();
        CliError::Usage(format!("unknown key {name:?}; keys: {}", known.join(", ")))
    })?;
    let value = key
        .parse_setting(text)
        .map_err(|e| CliError::Failure(format!("{}: {e}", key.name)))?;
    let (path, seed) = target()?;
    // Checked against what the file already says (e.g. an even blur_size needs blur = false).
    let who = config::Who {
        app: app.as_deref().unwrap_or(""),
        device: None,
    };
    let mut current = edit::current(&path, seed.as_deref(), who);
    key.apply(&mut current, value.clone())
        .map_err(|e| CliError::Failure(format!("{}: {e}", key.name)))?;
    warn_if_overridden(key);
    edit::set(&path, seed.as_deref(), app.as_deref(), key, &value).map_err(CliError::Failure)?;
    print(&format!("{} = {value} in {}\n", key.name, path.display()));
    Ok(())
}
