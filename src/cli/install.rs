//! `contrastxr install [--user|--system] [--library PATH]` and `contrastxr uninstall`.

use super::args::{Args, Opt};
use super::error::{print, CliError};

pub const SCOPE_OPTIONS: &[Opt] = &[Opt::flag("--user"), Opt::flag("--system")];
pub const OPTIONS: &[Opt] = &[
    Opt::flag("--user"),
    Opt::flag("--system"),
    Opt::value("--library", "PATH"),
];
use contrastxr::layer::installed_files::{self, Scope};

pub fn usage() -> String {
    "usage: contrastxr install [--user|--system] [--library PATH]\n\
     \x20      contrastxr uninstall [--user|--system]\n\n\
     Installs the OpenXR layer: copies the layer library (the libcontrastxr.so built with this\n\
     tool, or --library PATH) to a stable place and writes the implicit layer manifest naming\n\
     that copy, so rebuilding or `cargo clean` does not unload the layer. This tool is copied\n\
     beside the library (its `gl-programs` fills the OpenGL program caches ahead of time).\n\
     Where:\n\
     --user (default): $XDG_DATA_HOME/contrastxr/libcontrastxr.so and\n\
     \x20                 $XDG_DATA_HOME/openxr/1/api_layers/implicit.d/contrastxr.json\n\
     \x20                 ($XDG_DATA_HOME defaults to ~/.local/share);\n\
     --system:         /usr/local/lib/contrastxr/libcontrastxr.so and\n\
     \x20                 /etc/xdg/openxr/1/api_layers/implicit.d/contrastxr.json.\n\
     Run it again after rebuilding to update the copy. The layer then loads into OpenXR apps\n\
     started with CONTRASTXR=1. uninstall removes the manifest and the copies. (The Debian\n\
     package installs the layer system-wide itself; no install step is needed with it.)\n"
        .to_string()
}

fn scope(args: &mut Args) -> Result<Scope, CliError> {
    match (args.flag("--user"), args.flag("--system")) {
        (true, true) => Err(CliError::Usage("choose one of --user and --system".into())),
        (_, true) => Ok(Scope::System),
        _ => Ok(Scope::User),
    }
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let scope = scope(args)?;
    let library = args.value(&["--library"])?;
    args.finish()?;
    let library = match library {
        Some(p) => std::fs::canonicalize(&p)
            .map_err(|e| CliError::Failure(format!("cannot find the library {p}: {e}")))?,
        None => installed_files::find_library().map_err(CliError::Failure)?,
    };
    // A stable copy of this tool beside the library's (its `gl-programs` fills the OpenGL
    // program caches ahead of time); the layer itself never runs it.
    let tool = std::env::current_exe().ok();
    let done =
        installed_files::install(scope, &library, tool.as_deref()).map_err(CliError::Failure)?;
    print(&format!(
        "installed {} (library copied from {} to {}); enable the layer with CONTRASTXR=1\n",
        done.manifest.display(),
        library.display(),
        done.library.display()
    ));
    Ok(())
}

pub fn run_uninstall(args: &mut Args) -> Result<(), CliError> {
    let scope = scope(args)?;
    args.finish()?;
    match installed_files::uninstall(scope).map_err(CliError::Failure)? {
        Some(path) => print(&format!("removed {}\n", path.display())),
        None => print("the layer was not installed\n"),
    }
    Ok(())
}
