//! Every setting of the one key table (`config::KEYS`) is in the lists a user reads: the
//! README's environment-variable table and the commented example config (docs/control.md
//! explains groups of keys and points to the example). A key added to KEYS but missing from either
//! fails here.

use contrastxr::algorithm::Method;
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

/// A text that names methods as values (each within `quote`, as `"hue-only"` in TOML) names
/// them all or only gives an example: the method table (src/algorithm/method/table.rs) is the
/// list, and the help derives its list from it. Quoted, since a method's name may be a word
/// of the prose (`luminance`). Ok where every method is named, or at most one but paper.
fn names_every_method_or_one(text: &str, quote: char) -> Result<(), String> {
    let named: Vec<&str> = Method::ALL
        .iter()
        .map(|m| m.name())
        .filter(|n| text.contains(&format!("{quote}{n}{quote}")))
        .collect();
    let others = named.iter().filter(|n| **n != "paper").count();
    if named.len() == Method::ALL.len() || others <= 1 {
        Ok(())
    } else {
        Err(format!("names {named:?} of {} methods", Method::ALL.len()))
    }
}

#[test]
fn the_example_config_names_the_methods_as_the_table_has_them() {
    let text = read("contrastxr.example.toml");
    names_every_method_or_one(&text, '"').unwrap_or_else(|e| panic!("contrastxr.example.toml {e}"));
}

/// The README's `CONTRASTXR_METHOD` row lists every method of the table.
#[test]
fn the_readme_lists_every_method() {
    let text = read("README.md");
    let row = text
        .lines()
        .find(|l| l.starts_with("| `CONTRASTXR_METHOD`"));
    let row = row.expect("README.md has a CONTRASTXR_METHOD row");
    for m in Method::ALL {
        let n = m.name();
        assert!(
            row.contains(&format!("`{n}`")),
            "README.md: {row} lacks `{n}`"
        );
    }
}

#[test]
fn a_partial_method_list_is_reported() {
    let partial = r#"mode = "hue-only" or "other-hue""#;
    assert!(names_every_method_or_one(partial, '"').is_err());
    assert!(names_every_method_or_one(r#""paper" or "hue-only""#, '"').is_ok());
    assert!(names_every_method_or_one("hue-only, other-hue (unquoted prose)", '"').is_ok());
}
