//! Edits of the config file for `contrastxr set` and `toggle`: one key changes, comments and
//! everything else stay, and the new file replaces the old in one rename, so a running app's
//! watcher never reads half a file.

use super::keys::{key, Key};
use super::path::Env;
use super::resolve::{resolve, resolve_for, Source, Who};
use super::settings::Settings;
use super::value::Value;
use crate::algorithm::params::ViewMode;
use std::path::Path;
use toml_edit::{DocumentMut, Item};

fn read(path: &Path, seed: Option<&Path>) -> Result<String, String> {
    // A link is read through (a dangling one or a loop is refused, not silently replaced).
    let from = if std::fs::symlink_metadata(path).is_ok() {
        Some(path)
    } else {
        seed
    };
    match from {
        None => Ok(String::new()),
        Some(p) => {
            crate::user_file::read_text(p).map_err(|why| format!("config {} {why}", p.display()))
        }
    }
}

/// The settings the file about to be edited gives `who` now, without the environment: the
/// file, else the seed it will be copied from, else the defaults (a file that cannot be read
/// counts as none). What `toggle`, `set` and `calibrate` start from.
pub fn current(path: &Path, seed: Option<&Path>, who: Who) -> Settings {
    let file = [Some(path), seed]
        .into_iter()
        .flatten()
        .find(|p| p.is_file());
    let text = file.and_then(|p| crate::user_file::read_text(p).ok());
    let source = file
        .zip(text.as_deref())
        .map(|(path, text)| Source { path, text });
    resolve_for(who, source, &Env::default()).settings
}

/// Writes `text` to `path` through a temporary file in the same folder and a rename.
pub fn write_atomically(path: &Path, text: &str) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let tmp = path.with_extension(format!("toml.tmp-{}", std::process::id()));
    std::fs::write(&tmp, text).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("cannot replace {}: {e}", path.display())
    })
}

/// Which table of the file an edit goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Table<'a> {
    /// The top level: every app on every headset.
    Top,
    /// `[app."NAME"]`.
    App(&'a str),
    /// `[device."SYSTEM"]`.
    Device(&'a str),
}

impl<'a> Table<'a> {
    /// `[app."NAME"]` when `app` is given, else the top level.
    pub fn of_app(app: Option<&'a str>) -> Table<'a> {
        app.map_or(Table::Top, Table::App)
    }

    fn kind_and_name(self) -> Option<(&'static str, &'a str)> {
        match self {
            Table::Top => None,
            Table::App(name) => Some(("app", name)),
            Table::Device(name) => Some(("device", name)),
        }
    }
}

fn table<'d>(
    doc: &'d mut DocumentMut,
    which: Table,
) -> Result<&'d mut dyn toml_edit::TableLike, String> {
    let Some((kind, name)) = which.kind_and_name() else {
        return Ok(doc.as_table_mut());
    };
    let all = doc.as_table_mut().entry(kind).or_insert_with(|| {
        let mut t = toml_edit::Table::new();
        t.set_implicit(true);
        Item::Table(t)
    });
    let all = all
        .as_table_like_mut()
        .ok_or_else(|| format!("`{kind}` in the file is not a table"))?;
    all.entry(name)
        .or_insert_with(|| Item::Table(toml_edit::Table::new()))
        .as_table_like_mut()
        .ok_or_else(|| format!("{kind}.{name:?} in the file is not a table"))
}

/// Sets `key` to `value` in the file at `path` (created from `seed`, or empty, if missing), in
/// `[app."NAME"]` when `app` is given. The file must parse: a broken file is not overwritten.
pub fn set(
    path: &Path,
    seed: Option<&Path>,
    app: Option<&str>,
    key: &Key,
    value: &Value,
) -> Result<(), String> {
    set_in(path, seed, Table::of_app(app), key, value)
}

/// [`set`] in any table of the file.
pub fn set_in(
    path: &Path,
    seed: Option<&Path>,
    which: Table,
    key: &Key,
    value: &Value,
) -> Result<(), String> {
    let text = read(path, seed)?;
    let mut doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| {
        format!(
            "{} is not valid TOML ({}); fix it first (contrastxr config check)",
            path.display(),
            e.message().trim()
        )
    })?;
    let t = table(&mut doc, which)?;
    match t.get_mut(key.name) {
        Some(Item::Value(old)) => {
            // Keep the line's comment and spacing.
            let decor = old.decor().clone();
            *old = value.to_toml();
            *old.decor_mut() = decor;
        }
        _ => {
            t.insert(key.name, Item::Value(value.to_toml()));
        }
    }
    write_atomically(path, &doc.to_string())
}

/// The value `key` has in the file itself, in table `which`, if any: what to put back after a
/// temporary change.
pub fn entry(
    path: &Path,
    seed: Option<&Path>,
    which: Table,
    key: &Key,
) -> Result<Option<Value>, String> {
    let text = read(path, seed)?;
    let doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| {
        format!(
            "{} is not valid TOML ({})",
            path.display(),
            e.message().trim()
        )
    })?;
    let table: Option<&dyn toml_edit::TableLike> = match which.kind_and_name() {
        None => Some(doc.as_table()),
        Some((kind, name)) => doc
            .get(kind)
            .and_then(Item::as_table_like)
            .and_then(|all| all.get(name))
            .and_then(Item::as_table_like),
    };
    let value = table.and_then(|t| t.get(key.name)).and_then(Item::as_value);
    value.map(|v| key.kind.from_toml(v)).transpose()
}

/// Removes `key` from table `which` of the file; nothing to do if it is not there.
pub fn unset(path: &Path, which: Table, key: &Key) -> Result<(), String> {
    let text = read(path, None)?;
    let mut doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| {
        format!(
            "{} is not valid TOML ({})",
            path.display(),
            e.message().trim()
        )
    })?;
    let removed = table(&mut doc, which)?.remove(key.name).is_some();
    if removed {
        write_atomically(path, &doc.to_string())?;
    }
    Ok(())
}

/// Flips `mode` between `off` and `on_mode` in the file (for `app` when given) and returns the
/// mode now written.
pub fn toggle(
    path: &Path,
    seed: Option<&Path>,
    app: Option<&str>,
    on_mode: &str,
) -> Result<String, String> {
    let text = read(path, seed)?;
    let source = Source { path, text: &text };
    let current = resolve(app.unwrap_or(""), Some(source), &Env::default());
    let next = if current.settings.params.mode == ViewMode::Off {
        on_mode
    } else {
        "off"
    };
    let mode = key("mode").expect("mode is a key");
    let value = mode.parse_setting(next)?;
    // Check the value before writing it.
    mode.apply(&mut current.settings.clone(), value.clone())?;
    set(path, seed, app, mode, &value)?;
    Ok(next.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A config file's path in a scratch folder of its own (gone with the guard).
    fn temp(name: &str) -> (crate::scratch::ScratchDir, std::path::PathBuf) {
        let dir = crate::scratch::ScratchDir::new(&format!("edit-{name}"));
        let path = dir.join("config.toml");
        (dir, path)
    }

    #[test]
    fn set_keeps_comments_and_adds_app_tables() {
        let (_dir, path) = temp("set");
        write_atomically(&path, "# mine\nlambda_e = 0.4 # why\n").unwrap();
        let k = key("lambda_e").unwrap();
        set(&path, None, None, k, &Value::Float(0.6)).unwrap();
        set(&path, None, Some("hello xr"), k, &Value::Float(0.2)).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("# mine\nlambda_e = 0.6 # why\n"), "{text}");
        assert!(
            text.contains("[app.\"hello xr\"]\nlambda_e = 0.2"),
            "{text}"
        );
    }

    #[test]
    fn toggle_flips_between_off_and_the_mode() {
        let (_dir, path) = temp("toggle");
        assert_eq!(toggle(&path, None, None, "split").unwrap(), "off");
        assert_eq!(toggle(&path, None, None, "split").unwrap(), "split");
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "mode = \"split\"\n"
        );
    }

    #[test]
    fn entry_and_unset_put_a_key_back() {
        let (_dir, path) = temp("entry");
        write_atomically(&path, "mode = \"split\"\n[app.\"a\"]\nlambda_e = 0.5\n").unwrap();
        let mode = key("mode").unwrap();
        let lambda = key("lambda_e").unwrap();
        assert_eq!(
            entry(&path, None, Table::Top, mode).unwrap(),
            Some(Value::Text("split".into()))
        );
        assert_eq!(entry(&path, None, Table::App("a"), mode).unwrap(), None);
        assert_eq!(
            entry(&path, None, Table::App("a"), lambda).unwrap(),
            Some(Value::Float(0.5))
        );
        unset(&path, Table::App("a"), lambda).unwrap();
        unset(&path, Table::Top, lambda).unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "mode = \"split\"\n[app.\"a\"]\n"
        );
        set_in(
            &path,
            None,
            Table::Device("HMD"),
            lambda,
            &Value::Float(0.7),
        )
        .unwrap();
        assert_eq!(
            entry(&path, None, Table::Device("HMD"), lambda).unwrap(),
            Some(Value::Float(0.7))
        );
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("[device.HMD]\nlambda_e = 0.7\n"), "{text}");
    }

    #[test]
    fn a_broken_file_is_not_overwritten() {
        let (_dir, path) = temp("broken");
        write_atomically(&path, "lambda_e = \n").unwrap();
        let k = key("lambda_e").unwrap();
        assert!(set(&path, None, None, k, &Value::Float(0.6)).is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "lambda_e = \n");
    }
}
