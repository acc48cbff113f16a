//! `contrastxr install` / `uninstall`: the implicit layer manifest, with the built library's
//! absolute path, in the XDG OpenXR layer directory. The template is
//! `layer-manifest/contrastxr-implicit.json` (enabled by `CONTRASTXR`, disabled by
//! `CONTRASTXR_DISABLE`).

use std::path::{Path, PathBuf};

const TEMPLATE: &str = include_str!("../../layer-manifest/contrastxr-implicit.json");
pub const MANIFEST_NAME: &str = "contrastxr.json";
const LIBRARY_NAME: &str = "libcontrastxr.so";

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

pub fn layer_dir(scope: Scope) -> Result<PathBuf, String> {
    let tail = "openxr/1/api_layers/implicit.d";
    match scope {
        Scope::System => Ok(PathBuf::from("/etc/xdg").join(tail)),
        Scope::User => {
            let data = std::env::var_os("XDG_DATA_HOME")
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/share")))
                .ok_or("neither XDG_DATA_HOME nor HOME is set")?;
            Ok(data.join(tail))
        }
    }
}

/// The layer library built with this executable (they share cargo's output folder).
pub fn find_library() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this executable: {e}"))?;
    let dir = exe.parent().ok_or("this executable has no folder")?;
    [dir.join(LIBRARY_NAME), dir.join("..").join(LIBRARY_NAME)]
        .into_iter()
        .find(|p| p.is_file())
        .map(|p| p.canonicalize().unwrap_or(p))
        .ok_or_else(|| {
            format!(
                "{LIBRARY_NAME} is not next to {}: build it with `cargo build --release`",
                exe.display()
            )
        })
}

pub fn install(scope: Scope, library: &Path) -> Result<PathBuf, String> {
    if !library.is_absolute() || !library.is_file() {
        return Err(format!(
            "{} is not an existing absolute library path",
            library.display()
        ));
    }
    let dir = layer_dir(scope)?;
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let path = dir.join(MANIFEST_NAME);
    std::fs::write(&path, manifest_json(library))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path)
}

/// Removes the manifest; Ok(None) when it was not installed.
pub fn uninstall(scope: Scope) -> Result<Option<PathBuf>, String> {
    let path = layer_dir(scope)?.join(MANIFEST_NAME);
    match std::fs::remove_file(&path) {
        Ok(()) => Ok(Some(path)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(format!("cannot remove {}: {e}", path.display())),
    }
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
    fn explicit_manifest_names_the_same_layer() {
        let text = include_str!("../../layer-manifest/contrastxr-explicit.json");
        let v: serde_json::Value = serde_json::from_str(text).unwrap();
        assert_eq!(v["api_layer"]["name"], crate::layer::LAYER_NAME);
    }
}
