//! `contrastxr config check [FILE]`, `config print [--app NAME]` and `config path`.

use super::args::{Args, Opt};
use super::error::{print, CliError};
use contrastxr::config::{self, Env, Source, KEYS};
use std::path::PathBuf;

/// `--device SYSTEM` (with control's `--app NAME`).
pub const OPTIONS: &[Opt] = &[Opt::value("--device", "SYSTEM")];

pub fn usage() -> String {
    "usage: contrastxr config check [FILE]\n\
     \x20      contrastxr config print [--app NAME] [--device SYSTEM]\n\
     \x20      contrastxr config path\n\n\
     check: reads FILE (default: the file the layer reads) and prints every problem with its\n\
     \x20      file, line and key; exit code 1 if there is one.\n\
     print: the settings an app named NAME (its XrApplicationInfo.applicationName) would run\n\
     \x20      with, as TOML, each with where it came from (default, FILE:LINE for the top\n\
     \x20      level, FILE [device.\"SYSTEM\"]:LINE or FILE [app.\"NAME\"]:LINE, or env VAR),\n\
     \x20      including this shell's CONTRASTXR_* variables; with --device, on the headset\n\
     \x20      whose XrSystemProperties.systemName is SYSTEM (its [device.\"SYSTEM\"] table).\n\
     \x20      With --device it also names the device profiles file it read, or the folders\n\
     \x20      searched when there is none.\n\
     path:  the file the layer reads: $CONTRASTXR_CONFIG, else\n\
     \x20      $XDG_CONFIG_HOME/contrastxr/config.toml, else /etc/xdg/contrastxr/config.toml;\n\
     \x20      with none of them, the file `contrastxr set` would create.\n"
        .to_string()
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let app = args.value(&["--app"])?;
    let device = args.value(&["--device"])?;
    let mut pos = args.positional().into_iter();
    args.finish()?;
    let what = pos
        .next()
        .ok_or(CliError::Usage("say check, print or path".into()))?;
    let rest: Vec<String> = pos.collect();
    match (what.as_str(), rest.as_slice()) {
        ("check", [file]) => check(PathBuf::from(file)),
        ("check", []) => check(found()?),
        ("print", []) => {
            print_settings(app.as_deref().unwrap_or(""), device.as_deref());
            Ok(())
        }
        ("path", []) => path(),
        _ => Err(CliError::Usage(format!(
            "unknown or misused config subcommand {what:?}"
        ))),
    }
}

fn found() -> Result<PathBuf, CliError> {
    config::path::find(&Env::capture()).ok_or(CliError::Failure(
        "no config file: none of $CONTRASTXR_CONFIG, $XDG_CONFIG_HOME/contrastxr/config.toml, \
         /etc/xdg/contrastxr/config.toml exists"
            .into(),
    ))
}

/// The file the layer reads, or, when there is none, the one `set` would create (said on
/// stderr, so stdout stays the path alone).
fn path() -> Result<(), CliError> {
    let env = Env::capture();
    if let Some(p) = config::path::find(&env) {
        print(&format!("{}\n", p.display()));
        return Ok(());
    }
    let (p, _) = config::path::for_writing(&env).map_err(CliError::Failure)?;
    eprintln!("contrastxr: no config file yet; `contrastxr set KEY VALUE` creates this one");
    print(&format!("{}\n", p.display()));
    Ok(())
}

/// The comment line naming the device profiles file a `--device` print read, or where none was.
fn profiles_line(env: &Env) -> String {
    match config::shipped::find(env) {
        Some(p) if p.is_file() => format!("# device profiles: {}\n", p.display()),
        Some(p) => format!("# device profiles: none ({} does not exist)\n", p.display()),
        None => {
            let searched: Vec<String> = config::shipped::searched(env)
                .iter()
                .map(|p| p.display().to_string())
                .collect();
            format!(
                "# device profiles: none found (searched {})\n",
                searched.join(", ")
            )
        }
    }
}

fn check(path: PathBuf) -> Result<(), CliError> {
    let text = contrastxr::user_file::read_text(&path)
        .map_err(|why| CliError::Failure(format!("config {} {why}", path.display())))?;
    let problems = config::check(Source {
        path: &path,
        text: &text,
    });
    if problems.is_empty() {
        print(&format!("{}: ok\n", path.display()));
        return Ok(());
    }
    for p in &problems {
        eprintln!("{p}");
    }
    Err(CliError::Failure(format!(
        "{} problem(s) in {}",
        problems.len(),
        path.display()
    )))
}

fn print_settings(app: &str, device: Option<&str>) {
    let env = Env::capture();
    let r = config::load_for(config::Who { app, device }, &env);
    let on = device.map_or(String::new(), |d| format!(" on system {d:?}"));
    let mut out = format!(
        "# contrastxr settings for app {app:?}{on}; config file: {}\n",
        r.file
            .as_ref()
            .map_or("none".into(), |p| p.display().to_string())
    );
    if device.is_some() {
        out += &profiles_line(&env);
    }
    for i in 0..KEYS.len() {
        out += &r.line(i);
        out.push('\n');
    }
    print(&out);
    for p in &r.problems {
        eprintln!("{p}");
    }
}
