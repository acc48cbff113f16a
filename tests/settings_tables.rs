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

/// The lines that name methods name them all or only give an example: the method table
/// (src/algorithm/method_table.rs) is the list, and the help derives its list from it.
/// `text` names every method (in backticks with `ticks`), or at most one that is not paper.
fn names_every_method_or_one(text: &str, ticks: bool) -> Result<(), String> {
    let quoted = |n: &str| {
        if ticks {
            format!("`{n}`")
        } else {
            n.to_string()
        }
    };
    let named: Vec<&str> = Method::ALL
        .iter()
        .map(|m| m.name())
        .filter(|n| text.contains(&quoted(n)))
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
    names_every_method_or_one(&text, false)
        .unwrap_or_else(|e| panic!("contrastxr.example.toml {e}"));
}

/// The README's rows that list the methods (the CONTRASTXR_METHOD row and the `--method`
/// line) list every method of the table. README.md is the docs owner's to change, so it lags a
/// method added to the table until they add the name: ignored by default, run with --ignored.
#[test]
#[ignore = "README.md lags the method table until its owner adds a new method's name"]
fn the_readme_lists_every_method() {
    let text = read("README.md");
    let row = text
        .lines()
        .find(|l| l.starts_with("| `CONTRASTXR_METHOD`"));
    let row = row.expect("README.md has a CONTRASTXR_METHOD row");
    let options = text
        .split("`--method ")
        .nth(1)
        .expect("README.md has a --method line");
    let options: Vec<&str> = options.split('`').next().unwrap().split('|').collect();
    for m in Method::ALL {
        let n = m.name();
        assert!(
            row.contains(&format!("`{n}`")),
            "README.md: {row} lacks `{n}`"
        );
        assert!(
            options.contains(&n),
            "README.md: --method {options:?} lacks {n}"
        );
    }
}

#[test]
fn a_partial_method_list_is_reported() {
    assert!(names_every_method_or_one("hue-only, other-hue", false).is_err());
    assert!(names_every_method_or_one("paper or hue-only", false).is_ok());
}
