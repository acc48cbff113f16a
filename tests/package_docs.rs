//! The Debian package ships what the installed README links to: every relative link of
//! README.md resolves under /usr/share/doc/contrastxr/ through Cargo.toml's
//! `[package.metadata.deb]` assets (without building the package; tests/package.rs builds and
//! installs it in the sandbox).

use std::path::Path;

const DOC_DIR: &str = "usr/share/doc/contrastxr/";

/// The `[source, destination]` pairs of the package's assets.
fn assets() -> Vec<(String, String)> {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml")).unwrap();
    let doc: toml_edit::DocumentMut = text.parse().unwrap();
    let list = doc["package"]["metadata"]["deb"]["assets"]
        .as_array()
        .expect("assets");
    list.iter()
        .map(|a| {
            let a = a.as_array().expect("an asset is an array");
            let s = |i: usize| a.get(i).and_then(|v| v.as_str()).unwrap().to_string();
            (s(0), s(1))
        })
        .collect()
}

/// Where the package installs `file` (a path in the source tree), if it does.
fn installed(assets: &[(String, String)], file: &str) -> Option<String> {
    assets.iter().find_map(|(src, dst)| {
        let name = Path::new(file).file_name()?.to_str()?;
        let in_glob = src
            .strip_suffix('*')
            .is_some_and(|dir| file.strip_prefix(dir).is_some_and(|r| !r.contains('/')));
        (src == file || in_glob).then(|| format!("{dst}{name}"))
    })
}

/// The relative link targets of `text` (`](target)` without an anchor).
fn links(text: &str) -> Vec<String> {
    text.split("](")
        .skip(1)
        .filter_map(|rest| rest.split(')').next())
        .map(|t| t.split('#').next().unwrap_or(t).to_string())
        .filter(|t| !t.is_empty() && !t.contains("://"))
        .collect()
}

#[test]
fn the_installed_readmes_links_resolve() {
    let assets = assets();
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let links = links(&readme);
    assert!(
        links.iter().any(|l| l == "docs/calibration.md"),
        "{links:?}"
    );
    let dead: Vec<String> = links
        .iter()
        .filter(|l| installed(&assets, l) != Some(format!("{DOC_DIR}{l}")))
        .cloned()
        .collect();
    assert!(dead.is_empty(), "not installed beside the README: {dead:?}");
    assert_eq!(
        installed(&assets, "README.md").as_deref(),
        Some("usr/share/doc/contrastxr/README.md")
    );
}

/// The check can fail: a file no asset names is not installed.
#[test]
fn a_file_no_asset_names_is_not_installed() {
    let assets = assets();
    assert_eq!(installed(&assets, "docs/sub/x.md"), None);
    assert_eq!(installed(&assets, "nothing.md"), None);
}
