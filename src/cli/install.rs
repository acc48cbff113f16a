//! `contrastxr install [--user|--system] [--library PATH]` and `contrastxr uninstall`.

use super::{print, Args, CliError, Opt};

pub const SCOPE_OPTIONS: &[Opt] = &[Opt::flag("--user"), Opt::flag("--system")];
pub const OPTIONS: &[Opt] = &[
    Opt::flag("--user"),
    Opt::flag("--system"),
    Opt::value("--library", "PATH"),
];
use contrastxr::layer::install::{self, Scope};

pub fn usage() -> String {
    "usage: contrastxr install [--user|--system] [--library PATH]\n\
     \x20      contrastxr uninstall [--user|--system]\n\n\
     Writes (or removes) the implicit OpenXR layer manifest for the built libcontrastxr.so:\n\
     --user (default) into $XDG_DATA_HOME/openxr/1/api_layers/implicit.d,\n\
     --system into /etc/xdg/openxr/1/api_layers/implicit.d.\n\
     The layer then loads into OpenXR apps started with CONTRASTXR=1.\n"
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
        None => install::find_library().map_err(CliError::Failure)?,
    };
    let path = install::install(scope, &library).map_err(CliError::Failure)?;
    print(&format!(
        "installed {} (library {}); enable the layer with CONTRASTXR=1\n",
        path.display(),
        library.display()
    ));
    Ok(())
}

pub fn run_uninstall(args: &mut Args) -> Result<(), CliError> {
    let scope = scope(args)?;
    args.finish()?;
    match install::uninstall(scope).map_err(CliError::Failure)? {
        Some(path) => print(&format!("removed {}\n", path.display())),
        None => print("the layer was not installed\n"),
    }
    Ok(())
}
