//! Whether the OpenXR loader finds the layer: its manifests in the loader's search paths, and
//! which one's library apps get (checked in `library.rs`).
//!
//! The paths are the Khronos loader's on Linux (`src/loader/manifest_file.cpp`,
//! `ReadDataFilesInSearchPaths`): `$XDG_CONFIG_DIRS` (default `/etc/xdg`), `/etc`,
//! `$XDG_DATA_DIRS` (default `/usr/local/share:/usr/share`) and `$XDG_DATA_HOME` (default
//! `~/.local/share`), each with `openxr/1/api_layers/implicit.d` or `explicit.d`; for explicit
//! layers `XR_API_LAYER_PATH`, when set, replaces them all. `$XDG_CONFIG_HOME` is searched only
//! for the active runtime, never for layers, so a manifest there is reported as not seen.

use super::finding::{tool, tool_as_root, var, Finding};
use super::library::library_finding;
use contrastxr::layer::LAYER_NAME;
use std::path::{Path, PathBuf};

/// One manifest that names this layer.
pub struct Manifest {
    pub path: PathBuf,
    pub implicit: bool,
    /// `library_path` as written.
    pub library: Option<String>,
    /// Why the loader would reject it (missing fields, invalid JSON).
    pub problems: Vec<String>,
}

/// Every manifest of the layer, by where it was found.
pub struct Search {
    pub implicit: Vec<Manifest>,
    pub explicit: Vec<Manifest>,
    /// In `$XDG_CONFIG_HOME/openxr/1/api_layers/*.d`, where the loader does not look.
    pub unseen: Vec<Manifest>,
    /// The implicit directories searched, for the report.
    pub searched: Vec<PathBuf>,
}

fn split(list: &str) -> Vec<PathBuf> {
    list.split(':')
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .collect()
}

fn home() -> Option<PathBuf> {
    var("HOME").map(PathBuf::from)
}

/// The loader's base directories for layer manifests, in its order.
fn bases() -> Vec<PathBuf> {
    let mut dirs = split(&var("XDG_CONFIG_DIRS").unwrap_or_else(|| "/etc/xdg".into()));
    dirs.push(PathBuf::from("/etc"));
    dirs.extend(split(
        &var("XDG_DATA_DIRS").unwrap_or_else(|| "/usr/local/share:/usr/share".into()),
    ));
    let data_home = var("XDG_DATA_HOME")
        .map(PathBuf::from)
        .or_else(|| home().map(|h| h.join(".local/share")));
    dirs.extend(data_home);
    dirs
}

fn sub(kind: &str) -> PathBuf {
    Path::new("openxr/1/api_layers").join(format!("{kind}.d"))
}

/// The directories the loader reads for `kind` ("implicit" or "explicit"), without repeats.
fn search_dirs(kind: &str) -> Vec<PathBuf> {
    let dirs = match var("XR_API_LAYER_PATH") {
        Some(list) if kind == "explicit" => split(&list),
        _ => bases().into_iter().map(|b| b.join(sub(kind))).collect(),
    };
    let mut seen = Vec::new();
    let mut out = Vec::new();
    for d in dirs {
        let key = d.canonicalize().unwrap_or_else(|_| d.clone());
        if !seen.contains(&key) {
            seen.push(key);
            out.push(d);
        }
    }
    out
}

fn string_at<'a>(v: &'a serde_json::Value, key: &str) -> Option<&'a str> {
    v.get(key).and_then(|x| x.as_str())
}

/// The manifest at `path` if it names this layer (or looks like ours but cannot be read).
fn read(path: &Path, implicit: bool) -> Option<Manifest> {
    let ours_by_name = path.file_name()?.to_string_lossy().contains("contrastxr");
    let text = contrastxr::user_file::read_text(path).ok()?;
    let mut m = Manifest {
        path: path.to_path_buf(),
        implicit,
        library: None,
        problems: Vec::new(),
    };
    let v: serde_json::Value = match serde_json::from_str(&text) {
        Ok(v) => v,
        Err(e) if ours_by_name => {
            m.problems.push(format!("not valid JSON ({e})"));
            return Some(m);
        }
        Err(_) => return None,
    };
    let layer = &v["api_layer"];
    if string_at(layer, "name") != Some(LAYER_NAME) {
        return None;
    }
    m.library = string_at(layer, "library_path").map(str::to_string);
    let mut required = vec!["library_path", "api_version", "implementation_version"];
    if implicit {
        required.push("disable_environment");
    }
    for key in required
        .into_iter()
        .filter(|k| string_at(layer, k).is_none())
    {
        m.problems.push(format!("api_layer.{key} is missing"));
    }
    if string_at(&v, "file_format_version").is_none() {
        m.problems.push("file_format_version is missing".into());
    }
    Some(m)
}

/// The manifests of this layer among the `*.json` files of `dirs`.
fn scan(dirs: &[PathBuf], implicit: bool) -> Vec<Manifest> {
    let mut found = Vec::new();
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.filter_map(|e| Some(e.ok()?.path())).collect();
        files.sort();
        let json = files
            .iter()
            .filter(|p| p.extension().is_some_and(|e| e == "json"));
        found.extend(json.filter_map(|p| read(p, implicit)));
    }
    found
}

fn list(manifests: &[Manifest]) -> String {
    let paths: Vec<String> = manifests
        .iter()
        .map(|m| m.path.display().to_string())
        .collect();
    paths.join(", ")
}

impl Search {
    pub fn run() -> Search {
        let searched = search_dirs("implicit");
        let unseen_dirs: Vec<PathBuf> = var("XDG_CONFIG_HOME")
            .map(PathBuf::from)
            .or_else(|| home().map(|h| h.join(".config")))
            .map(|base| vec![base.join(sub("implicit")), base.join(sub("explicit"))])
            .unwrap_or_default()
            .into_iter()
            .filter(|d| !searched.contains(d))
            .collect();
        Search {
            implicit: scan(&searched, true),
            explicit: scan(&search_dirs("explicit"), false),
            unseen: scan(&unseen_dirs, true),
            searched,
        }
    }

    /// The manifest whose library apps get: the first implicit one, else the first explicit.
    fn chosen(&self) -> Option<&Manifest> {
        self.implicit.first().or(self.explicit.first())
    }

    pub fn manifest_finding(&self) -> Finding {
        const NAME: &str = "manifest";
        let Some(m) = self.chosen() else {
            return self.none_found();
        };
        if let Some(p) = m.problems.first() {
            return Finding::problem(
                NAME,
                format!("{}: {p}, so the loader skips it", m.path.display()),
                format!(
                    "write it again: `{} install --user` (or `{} install --system`)",
                    tool(),
                    tool_as_root()
                ),
            );
        }
        let library = m.library.as_deref().unwrap_or("?");
        let names = format!("{} names {library}", m.path.display());
        if !m.implicit {
            let enabled = var("XR_ENABLE_API_LAYERS").is_some_and(|v| v.contains(LAYER_NAME));
            let detail = format!("explicit manifest {names}");
            if enabled {
                return Finding::ok(NAME, detail + ", enabled by XR_ENABLE_API_LAYERS here");
            }
            return Finding::warn(
                NAME,
                detail + "; apps load it only when asked to",
                format!(
                    "start apps with XR_ENABLE_API_LAYERS={LAYER_NAME}, or install the \
                     implicit manifest: `{} install --user`",
                    tool()
                ),
            );
        }
        if self.implicit.len() > 1 {
            return Finding::warn(
                NAME,
                format!(
                    "{} implicit manifests name the layer ({}): the loader loads it once for each",
                    self.implicit.len(),
                    list(&self.implicit)
                ),
                format!(
                    "keep one: `{} uninstall --user` (or `{} uninstall --system`) removes an \
                     installed copy",
                    tool(),
                    tool_as_root()
                ),
            );
        }
        // The loader leaves an implicit layer out when its disable variable is set at all.
        if std::env::var_os("CONTRASTXR_DISABLE").is_some() {
            return Finding::warn(
                NAME,
                format!("implicit manifest {names}, but CONTRASTXR_DISABLE is set here"),
                "unset CONTRASTXR_DISABLE: while it is set the loader leaves the layer out",
            );
        }
        Finding::ok(
            NAME,
            format!("implicit manifest {names}; loaded into apps started with CONTRASTXR=1"),
        )
    }

    fn none_found(&self) -> Finding {
        const NAME: &str = "manifest";
        if let Some(m) = self.unseen.first() {
            return Finding::problem(
                NAME,
                format!(
                    "{} names the layer, but the OpenXR loader does not look for layers under \
                     $XDG_CONFIG_HOME",
                    m.path.display()
                ),
                format!(
                    "remove it and run `{} install --user`, which writes \
                     $XDG_DATA_HOME/openxr/1/api_layers/implicit.d/contrastxr.json",
                    tool()
                ),
            );
        }
        let dirs: Vec<String> = self
            .searched
            .iter()
            .map(|d| d.display().to_string())
            .collect();
        Finding::problem(
            NAME,
            format!(
                "no manifest names {LAYER_NAME} in the loader's paths ({}{})",
                dirs.join(", "),
                var("XR_API_LAYER_PATH").map_or(String::new(), |p| format!("; explicit: {p}"))
            ),
            format!(
                "install the layer: `{} install --user` (or `{} install --system`, or the \
                 Debian package)",
                tool(),
                tool_as_root()
            ),
        )
    }

    pub fn library_finding(&self) -> Finding {
        match self.chosen() {
            Some(m) => match &m.library {
                Some(library) => library_finding(&m.path, library),
                None => Finding::problem(
                    "library",
                    format!("{} names no library_path", m.path.display()),
                    format!("write the manifest again: `{} install --user`", tool()),
                ),
            },
            None => Finding::warn(
                "library",
                "not checked: no manifest of the layer was found",
                "see the manifest finding",
            ),
        }
    }
}
