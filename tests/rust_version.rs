//! The Rust the crate says it needs (`rust-version` in Cargo.toml, and the README's
//! requirements) is at least what every locked dependency needs, build and test dependencies
//! included: with an older toolchain cargo refuses the build with the dependency's name, not
//! ours. `cargo metadata` reads each package's own `rust-version` from the lock file's versions.
//! The toolchain rustup picks for the checks (`rust-toolchain.toml`) meets that too.

use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// A file of the checkout.
fn read(name: &str) -> String {
    std::fs::read_to_string(format!("{ROOT}/{name}")).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// `1.88` or `1.88.0` as (major, minor): patch releases never raise a crate's needs.
fn version(text: &str) -> (u32, u32) {
    let mut parts = text.split('.').map(|p| p.parse::<u32>().unwrap());
    (parts.next().unwrap(), parts.next().unwrap_or(0))
}

/// Every package of the locked build for this machine's target, with its `rust-version`.
fn locked_packages() -> Vec<(String, String, Option<String>)> {
    // The rustc beside the cargo that builds the tests (a rustup toolchain or /usr/bin).
    let rustc = std::path::Path::new(env!("CARGO")).with_file_name("rustc");
    let host = Command::new(rustc).arg("-vV").output().unwrap();
    let host = String::from_utf8(host.stdout).unwrap();
    let triple = host.lines().find_map(|l| l.strip_prefix("host: ")).unwrap();
    let out = Command::new(env!("CARGO"))
        .args(["metadata", "--format-version", "1", "--locked", "--offline"])
        .args(["--filter-platform", triple])
        .current_dir(ROOT)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let metadata: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let in_build: Vec<&str> = metadata["resolve"]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["id"].as_str().unwrap())
        .collect();
    metadata["packages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| in_build.contains(&p["id"].as_str().unwrap()))
        .map(|p| {
            let field = |k: &str| p[k].as_str().map(str::to_owned);
            (
                field("name").unwrap(),
                field("version").unwrap(),
                field("rust_version"),
            )
        })
        .collect()
}

#[test]
fn the_declared_rust_covers_every_locked_dependency_and_the_readme_says_it() {
    let packages = locked_packages();
    let ours = packages
        .iter()
        .find(|(name, ..)| name == "contrastxr")
        .and_then(|(.., v)| v.clone())
        .expect("Cargo.toml declares rust-version");
    let needs_more: Vec<String> = packages
        .iter()
        .filter_map(|(name, v, needs)| {
            let needs = needs.as_deref()?;
            (version(needs) > version(&ours)).then(|| format!("{name} {v} needs {needs}"))
        })
        .collect();
    assert!(
        needs_more.is_empty(),
        "rust-version {ours} in Cargo.toml is below what these need: {needs_more:?}"
    );
    assert!(
        packages.len() > 50,
        "the locked build has only {} packages: metadata misread",
        packages.len()
    );
    let readme = read("README.md");
    assert!(
        readme.contains(&format!("**Rust {ours}** or newer")),
        "README's requirements should name **Rust {ours}** or newer"
    );
}

/// `rust-toolchain.toml`'s `[toolchain]` table.
fn pinned_toolchain() -> toml_edit::Table {
    let text = read("rust-toolchain.toml");
    let doc: toml_edit::DocumentMut = text.parse().expect("rust-toolchain.toml parses");
    doc["toolchain"]
        .as_table()
        .expect("a [toolchain] table")
        .clone()
}

#[test]
fn the_pinned_toolchain_meets_rust_version_and_carries_the_checks() {
    let toolchain = pinned_toolchain();
    let channel = toolchain["channel"].as_str().expect("channel is a string");
    // A release number (1.95.0), not `stable`: a moving channel brings new lints unannounced.
    assert_eq!(
        channel.split('.').count(),
        3,
        "channel {channel:?} is not a release"
    );
    let cargo_toml = read("Cargo.toml");
    let doc: toml_edit::DocumentMut = cargo_toml.parse().unwrap();
    let declared = doc["package"]["rust-version"].as_str().unwrap();
    assert!(
        version(channel) >= version(declared),
        "rust-toolchain.toml's {channel} is older than rust-version {declared}"
    );
    let components: Vec<&str> = toolchain["components"]
        .as_array()
        .expect("components listed")
        .iter()
        .filter_map(|c| c.as_str())
        .collect();
    for needed in ["rustfmt", "clippy"] {
        assert!(
            components.contains(&needed),
            "scripts/test runs {needed}: {components:?}"
        );
    }
    let readme = read("README.md");
    assert!(
        readme.contains(&format!("Rust {channel}")),
        "README's requirements should name the pinned Rust {channel}"
    );
}

#[test]
fn versions_compare_by_major_then_minor() {
    assert!(version("1.88") > version("1.85.1"));
    assert!(version("1.100") > version("1.99"));
    assert_eq!(version("1.88.0"), version("1.88"));
}
