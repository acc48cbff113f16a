//! One finding of `contrastxr doctor`: a check's status, what it saw and how to fix it.

/// How a finding stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    Ok,
    Warn,
    Problem,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Warn => "warn",
            Status::Problem => "problem",
        }
    }
}

/// One line of the report: what was checked, how it stands, and what to do when it is not ok.
#[derive(Clone, Debug)]
pub struct Finding {
    pub name: &'static str,
    pub status: Status,
    pub detail: String,
    pub fix: Option<String>,
}

impl Finding {
    pub fn ok(name: &'static str, detail: impl Into<String>) -> Finding {
        Finding {
            name,
            status: Status::Ok,
            detail: detail.into(),
            fix: None,
        }
    }

    pub fn warn(name: &'static str, detail: impl Into<String>, fix: impl Into<String>) -> Finding {
        Finding {
            name,
            status: Status::Warn,
            detail: detail.into(),
            fix: Some(fix.into()),
        }
    }

    pub fn problem(
        name: &'static str,
        detail: impl Into<String>,
        fix: impl Into<String>,
    ) -> Finding {
        Finding {
            name,
            status: Status::Problem,
            detail: detail.into(),
            fix: Some(fix.into()),
        }
    }
}

/// A non-empty environment variable.
pub fn var(name: &str) -> Option<String> {
    std::env::var(name).ok().filter(|v| !v.is_empty())
}

/// Where the package installs the documentation (README.md, and docs/ beside it).
const DOCS: &str = "/usr/share/doc/contrastxr";

/// A document of docs/, named where the reader has it: the package's installed copy, else the
/// checkout this tool was built in (`<checkout>/target/<profile>/contrastxr`), else by its
/// place in the source.
pub fn doc(name: &str) -> String {
    let installed = std::path::Path::new(DOCS).join("docs").join(name);
    let checkout = std::env::current_exe()
        .ok()
        .and_then(|exe| Some(exe.parent()?.parent()?.parent()?.join("docs").join(name)));
    [Some(installed), checkout]
        .into_iter()
        .flatten()
        .find(|p| p.is_file())
        .map_or(format!("docs/{name}"), |p| p.display().to_string())
}

/// The folders sudo's `secure_path` searches (Debian's default): a tool elsewhere (a source
/// build, ~/.cargo/bin) is named by its path after `sudo`.
const SUDO_PATH: &[&str] = &["/usr/local/sbin", "/usr/local/bin", "/usr/sbin", "/usr/bin"];

/// This tool as the user can run it: `contrastxr` when that finds this executable on PATH,
/// else its path (a source build's `target/release/contrastxr`).
pub fn tool() -> String {
    let Ok(exe) = std::env::current_exe() else {
        return "contrastxr".into();
    };
    let on_path = var("PATH").is_some_and(|path| {
        std::env::split_paths(&path)
            .map(|d| d.join("contrastxr"))
            .find(|p| p.is_file())
            .and_then(|p| p.canonicalize().ok())
            .is_some_and(|p| p == exe)
    });
    match on_path {
        true => "contrastxr".into(),
        false => exe.display().to_string(),
    }
}

/// `sudo` and this tool, as root can find it.
pub fn tool_as_root() -> String {
    let exe = std::env::current_exe().ok();
    let in_sudo_path = exe
        .as_deref()
        .and_then(std::path::Path::parent)
        .is_some_and(|d| SUDO_PATH.iter().any(|s| d == std::path::Path::new(s)));
    match (in_sudo_path, exe) {
        (false, Some(exe)) => format!("sudo {}", exe.display()),
        _ => "sudo contrastxr".into(),
    }
}
