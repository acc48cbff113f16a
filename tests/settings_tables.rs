//! Every setting of the one key table (`config::KEYS`) is in the lists a user reads: the
//! README's environment-variable table and the commented example config (docs/control.md
//! explains groups of keys and points to the example). A key added to KEYS but missing from either
//! fails here.

use contrastxr::config::KEYS;

fn read(path: &str) -> String {
    let full = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{}: {e}", full.display()))
}

/// The keys whose `needle(key)` is missing from `text`.
fn missing(text: &str, needle: impl Fn(&contrastxr::config::Key) -> String) -> Vec<String> {
    KEYS.iter()
        .map(needle)
        .filter(|n| !text.contains(n.as_str()))
        .collect()
}

#[test]
fn the_readme_names_every_environment_variable() {
    let gone = missing(&read("README.md"), |k| format!("`{}`", k.env));
    assert!(gone.is_empty(), "README.md lacks {gone:?}");
}

#[test]
fn the_example_config_names_every_key() {
    let gone = missing(&read("contrastxr.example.toml"), |k| {
        format!("{} =", k.name)
    });
    assert!(gone.is_empty(), "contrastxr.example.toml lacks {gone:?}");
}

/// The checks can fail: a key that no text names is reported.
#[test]
fn a_missing_key_is_reported() {
    let gone = missing("nothing here", |k| format!("`{}`", k.name));
    assert_eq!(gone.len(), KEYS.len());
}
