//! Where the config file is: `$CONTRASTXR_CONFIG`, else `$XDG_CONFIG_HOME/contrastxr/config.toml`
//! (`~/.config` when unset), else `/etc/xdg/contrastxr/config.toml`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub const SYSTEM_PATH: &str = "/etc/xdg/contrastxr/config.toml";

/// The variables the config depends on, captured once: the layer's watcher thread re-reads the
/// file, but a process's environment does not change under it.
#[derive(Clone, Debug, Default)]
pub struct Env {
    vars: HashMap<String, String>,
    /// Wanted variables whose value is not UTF-8 (a path from another encoding): left out, and
    /// said once as a problem rather than silently ignored.
    not_utf8: Vec<String>,
}

impl Env {
    pub fn capture() -> Env {
        let wanted = |k: &str| {
            k.starts_with("CONTRASTXR") || ["XDG_CONFIG_HOME", "XDG_DATA_HOME", "HOME"].contains(&k)
        };
        let mut env = Env::default();
        for (k, v) in std::env::vars_os() {
            let Some(k) = k.into_string().ok().filter(|k| wanted(k)) else {
                continue;
            };
            match v.into_string() {
                Ok(v) => drop(env.vars.insert(k, v)),
                Err(_) => env.not_utf8.push(k),
            }
        }
        env.not_utf8.sort();
        env
    }

    /// One problem line per wanted variable whose value is not UTF-8.
    pub fn unreadable_problems(&self) -> Vec<String> {
        self.not_utf8
            .iter()
            .map(|k| format!("{k} is not UTF-8 text; ignored"))
            .collect()
    }

    pub fn from_pairs<'a>(pairs: impl IntoIterator<Item = (&'a str, &'a str)>) -> Env {
        Env {
            vars: pairs
                .into_iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            not_utf8: Vec::new(),
        }
    }

    pub fn get(&self, name: &str) -> Option<String> {
        self.vars.get(name).cloned()
    }

    fn non_empty(&self, name: &str) -> Option<String> {
        self.get(name).filter(|v| !v.is_empty())
    }
}

/// The per-user file, whether or not it exists.
pub fn user_path(env: &Env) -> Option<PathBuf> {
    let base = env
        .non_empty("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .or_else(|| env.non_empty("HOME").map(|h| Path::new(&h).join(".config")))?;
    Some(base.join("contrastxr").join("config.toml"))
}

/// The file to read: `$CONTRASTXR_CONFIG` (even if missing: it was asked for), else the first of
/// the user and system files that exists; None when there is none. Each look-up is bounded
/// (`user_file::APP_THREAD_READ`, the caller may be the app's thread): a file whose look-up
/// takes longer (a hung mount) is the one found, and its read then says why it is not used.
pub fn find(env: &Env) -> Option<PathBuf> {
    let limit = crate::user_file::APP_THREAD_READ;
    find_by(env, |p| {
        crate::user_file::is_file_within(p, limit).unwrap_or(true)
    })
}

/// [`find`] with look-ups that may wait for the file system: for a thread of the layer's own.
pub fn find_waiting(env: &Env) -> Option<PathBuf> {
    find_by(env, |p| {
        crate::user_file::metadata(p).is_ok_and(|m| m.is_file())
    })
}

fn find_by(env: &Env, is_file: impl Fn(&Path) -> bool) -> Option<PathBuf> {
    if let Some(p) = env.non_empty("CONTRASTXR_CONFIG") {
        return Some(PathBuf::from(p));
    }
    [user_path(env), Some(PathBuf::from(SYSTEM_PATH))]
        .into_iter()
        .flatten()
        .find(|p| is_file(p))
}

/// The file `contrastxr set` and `toggle` write: the one apps read, except that the system
/// file is not edited in place: its content is the start of a new user file.
pub fn for_writing(env: &Env) -> Result<(PathBuf, Option<PathBuf>), String> {
    if env.not_utf8.iter().any(|k| k == "CONTRASTXR_CONFIG") {
        return Err(
            "CONTRASTXR_CONFIG is not UTF-8 text: give the config file a UTF-8 path".into(),
        );
    }
    if let Some(p) = env.non_empty("CONTRASTXR_CONFIG") {
        return Ok((PathBuf::from(p), None));
    }
    let user = user_path(env).ok_or("neither XDG_CONFIG_HOME nor HOME is set")?;
    let seed = (!user.is_file())
        .then(|| PathBuf::from(SYSTEM_PATH))
        .filter(|p| p.is_file());
    Ok((user, seed))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn explicit_path_wins_even_when_missing() {
        let env = Env::from_pairs([("CONTRASTXR_CONFIG", "/nowhere/c.toml"), ("HOME", "/h")]);
        assert_eq!(find(&env), Some(PathBuf::from("/nowhere/c.toml")));
    }

    #[test]
    fn user_path_follows_xdg() {
        let env = Env::from_pairs([("HOME", "/h")]);
        assert_eq!(
            user_path(&env),
            Some(PathBuf::from("/h/.config/contrastxr/config.toml"))
        );
        let env = Env::from_pairs([("HOME", "/h"), ("XDG_CONFIG_HOME", "/x")]);
        assert_eq!(
            user_path(&env),
            Some(PathBuf::from("/x/contrastxr/config.toml"))
        );
    }
}
