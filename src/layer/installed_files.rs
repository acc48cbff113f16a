//! The layer library's files: where it was loaded from, and
//! `contrastxr install` / `uninstall`: a copy of the layer library in a stable place and the
//! implicit layer manifest naming it, in the XDG OpenXR layer directory. The copy is what keeps
//! the layer loadable after `cargo clean` or a rebuild of the tree it came from. The template is
//! `layer-manifest/contrastxr-implicit.json` (enabled by `CONTRASTXR`, disabled by
//! `CONTRASTXR_DISABLE`); the Debian package ships the same manifest naming
//! [`PACKAGED_LIBRARY`].

use std::path::{Path, PathBuf};

const TEMPLATE: &str = include_str!("../../layer-manifest/contrastxr-implicit.json");
pub const MANIFEST_NAME: &str = "contrastxr.json";
const LIBRARY_NAME: &str = "libcontrastxr.so";
/// The tool's name beside the library copy (`install` copies it there as a stable
/// `contrastxr gl-programs`; the layer itself never runs it).
const TOOL_NAME: &str = "contrastxr";
/// Where the Debian package puts the library (its manifest, `layer-manifest/deb/`, names it).
pub const PACKAGED_LIBRARY: &str = "/usr/lib/contrastxr/libcontrastxr.so";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scope {
    /// `$XDG_DATA_HOME/openxr/1/api_layers/implicit.d` (default `~/.local/share`).
    User,
    /// `/etc/xdg/openxr/1/api_layers/implicit.d`.
    System,
}

/// The implicit manifest naming `library` (JSON-escaped).
pub fn manifest_json(library: &Path) -> String {
    let escaped = serde_json::to_string(&library.display().to_string()).expect("a string");
    TEMPLATE.replace("\"@LIBRARY_PATH@\"", &escaped)
}

fn data_home() -> Result<PathBuf, String> {
    std::env::var_os("XDG_DATA_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/share")))
        .ok_or_else(|| "neither XDG_DATA_HOME nor HOME is set".into())
}

pub fn layer_dir(scope: Scope) -> Result<PathBuf, String> {
    let tail = "openxr/1/api_layers/implicit.d";
    match scope {
        Scope::System => Ok(PathBuf::from("/etc/xdg").join(tail)),
        Scope::User => Ok(data_home()?.join(tail)),
    }
}

/// The layer's library file, as the dynamic linker loaded it (dladdr of its own code; in the
/// command-line tool, the tool itself).
pub(crate) fn library_file() -> Option<std::ffi::CString> {
    // SAFETY: Dl_info is plain C data; all-zero is a valid value for dladdr to fill.
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    let here = library_file as *const std::ffi::c_void;
    // SAFETY: dladdr on an address of this library's code, with a valid out pointer.
    if unsafe { libc::dladdr(here, &mut info) } == 0 || info.dli_fname.is_null() {
        return None;
    }
    // SAFETY: dli_fname is a NUL-terminated path owned by the dynamic linker.
    Some(unsafe { std::ffi::CStr::from_ptr(info.dli_fname) }.to_owned())
}

/// Where `install` keeps its copy of the library: `$XDG_DATA_HOME/contrastxr/` for the user,
/// `/usr/local/lib/contrastxr/` for the system.
pub fn library_copy(scope: Scope) -> Result<PathBuf, String> {
    let dir = match scope {
        Scope::System => PathBuf::from("/usr/local/lib/contrastxr"),
        Scope::User => data_home()?.join("contrastxr"),
    };
    Ok(dir.join(LIBRARY_NAME))
}

/// Copies `from` to `to` through a temporary file and a rename: an app that has the old
/// library loaded keeps its (unlinked) file intact instead of having it rewritten under it.
fn copy_library(from: &Path, to: &Path) -> Result<(), String> {
    let dir = to.parent().ok_or("the library copy has no folder")?;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let tmp = dir.join(format!(".{LIBRARY_NAME}.{}", std::process::id()));
    let copied = std::fs::copy(from, &tmp)
        .map_err(|e| format!("cannot copy {} to {}: {e}", from.display(), tmp.display()))
        .and_then(|_| {
            std::fs::rename(&tmp, to).map_err(|e| format!("cannot write {}: {e}", to.display()))
        });
    if copied.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    copied
}

/// The layer library that came with this executable: beside it (cargo's output folder), or
/// where the Debian package puts it.
pub fn find_library() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this executable: {e}"))?;
    let dir = exe.parent().ok_or("this executable has no folder")?;
    [
        dir.join(LIBRARY_NAME),
        dir.join("..").join(LIBRARY_NAME),
        dir.join("../lib/contrastxr").join(LIBRARY_NAME),
    ]
    .into_iter()
    .find(|p| p.is_file())
    .map(|p| p.canonicalize().unwrap_or(p))
    .ok_or_else(|| {
        format!(
            "{LIBRARY_NAME} is not next to {} (`cargo install` installs no libraries): build \
             it with `cargo build --release` in the source tree and run `contrastxr install \
             --library target/release/{LIBRARY_NAME}`, or install the Debian package \
             (scripts/package)",
            exe.display()
        )
    })
}

/// What `install` wrote.
pub struct Installed {
    pub manifest: PathBuf,
    pub library: PathBuf,
}

/// Copies `library` to [`library_copy`] and `tool` (the running `contrastxr`) beside it, writes
/// the shipped device profiles beside it and the manifest naming the copy.
pub fn install(scope: Scope, library: &Path, tool: Option<&Path>) -> Result<Installed, String> {
    if !library.is_absolute() || !library.is_file() {
        return Err(format!(
            "{} is not an existing absolute library path",
            library.display()
        ));
    }
    let copy = library_copy(scope)?;
    if library.canonicalize().ok() != copy.canonicalize().ok() {
        copy_library(library, &copy)?;
    }
    if let Some(tool) = tool {
        let tool_copy = copy.with_file_name(TOOL_NAME);
        if tool.canonicalize().ok() != tool_copy.canonicalize().ok() {
            copy_library(tool, &tool_copy)?;
        }
    }
    // The shipped device profiles beside the library, where the layer looks for them.
    let profiles = copy.with_file_name(crate::config::shipped::FILE_NAME);
    std::fs::write(&profiles, crate::config::shipped::TEXT)
        .map_err(|e| format!("cannot write {}: {e}", profiles.display()))?;
    let dir = layer_dir(scope)?;
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let path = dir.join(MANIFEST_NAME);
    std::fs::write(&path, manifest_json(&copy))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(Installed {
        manifest: path,
        library: copy,
    })
}

fn remove(path: &Path) -> Result<bool, String> {
    match std::fs::remove_file(path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(format!("cannot remove {}: {e}", path.display())),
    }
}

/// Removes the manifest, the library copy and the tool beside it; Ok(None) when the manifest was not installed.
pub fn uninstall(scope: Scope) -> Result<Option<PathBuf>, String> {
    let path = layer_dir(scope)?.join(MANIFEST_NAME);
    let removed = remove(&path)?;
    let copy = library_copy(scope)?;
    remove(&copy.with_file_name(crate::config::shipped::FILE_NAME))?;
    remove(&copy.with_file_name(TOOL_NAME))?;
    remove(&copy)?;
    Ok(removed.then_some(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifest_is_valid_json_with_the_contract_names() {
        let text = manifest_json(Path::new("/opt/a \"b\"/libcontrastxr.so"));
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let layer = &v["api_layer"];
        assert_eq!(layer["name"], "XR_APILAYER_CONTRASTXR_color_contrast");
        assert_eq!(layer["library_path"], "/opt/a \"b\"/libcontrastxr.so");
        assert_eq!(layer["enable_environment"], "CONTRASTXR");
        assert_eq!(layer["disable_environment"], "CONTRASTXR_DISABLE");
    }

    #[test]
    fn packaged_manifest_is_the_template_with_the_packaged_library() {
        let packaged = include_str!("../../layer-manifest/deb/contrastxr.json");
        let expected: serde_json::Value =
            serde_json::from_str(&manifest_json(Path::new(PACKAGED_LIBRARY))).unwrap();
        let v: serde_json::Value = serde_json::from_str(packaged).unwrap();
        assert_eq!(v, expected);
    }

    #[test]
    fn explicit_manifest_names_the_same_layer() {
        let text = include_str!("../../layer-manifest/contrastxr-explicit.json");
        let v: serde_json::Value = serde_json::from_str(text).unwrap();
        assert_eq!(v["api_layer"]["name"], crate::layer::LAYER_NAME);
    }
}
