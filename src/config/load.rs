//! Finding and reading the config file (and the shipped device profiles) for an environment,
//! then resolving them ([`mod@super::resolve`]). Reads never hang the caller, which may be the
//! app's thread; a file that cannot be read is one problem line, never an error.

use super::path::{self, Env};
use super::resolve::{resolve_with, Resolved, Source, Who};

/// Finds and reads the config file for `env`, then resolves.
pub fn load(app: &str, env: &Env) -> Resolved {
    load_for(Who { app, device: None }, env)
}

/// [`load`] for an app on a device. Files are read through `user_file` on a helper thread
/// within `user_file::APP_THREAD_READ` (the caller may be the app's thread); one that cannot be
/// read is one problem line, and its settings are left out.
pub fn load_for(who: Who, env: &Env) -> Resolved {
    let mut problems = env.unreadable_problems();
    let shipped_path = who.device.and_then(|_| super::shipped::find(env));
    let shipped_text = shipped_path.as_ref().and_then(|p| {
        read_setting_file(p)
            .map_err(|why| problems.push(profiles_problem(p, env, &why)))
            .ok()
    });
    let shipped = shipped_path
        .as_deref()
        .zip(shipped_text.as_deref())
        .map(|(path, text)| Source { path, text });
    let mut r = match path::find(env) {
        None => resolve_with(who, shipped, None, env),
        Some(path) => match read_setting_file(&path) {
            Ok(text) => resolve_with(
                who,
                shipped,
                Some(Source {
                    path: &path,
                    text: &text,
                }),
                env,
            ),
            Err(why) => {
                let mut r = resolve_with(who, shipped, None, env);
                r.file = Some(path.clone());
                r.file_failed = true;
                problems.push(config_problem(&path, env, &why));
                r
            }
        },
    };
    r.problems.splice(0..0, problems);
    r
}

fn read_setting_file(path: &std::path::Path) -> Result<String, String> {
    crate::user_file::read_text_within(path, crate::user_file::APP_THREAD_READ)
}

/// `(CONTRASTXR_X)` when `path` is that variable's value: which setting named it.
fn named_by(env: &Env, var: &str, path: &std::path::Path) -> String {
    let named = env
        .get(var)
        .is_some_and(|v| std::path::Path::new(&v) == path);
    if named {
        format!(" ({var})")
    } else {
        String::new()
    }
}

fn config_problem(path: &std::path::Path, env: &Env, why: &str) -> String {
    let by = named_by(env, "CONTRASTXR_CONFIG", path);
    format!("config {}{by} {why}; using defaults", path.display())
}

fn profiles_problem(path: &std::path::Path, env: &Env, why: &str) -> String {
    let by = named_by(env, "CONTRASTXR_DEVICES", path);
    format!("device profiles {}{by} {why}; using none", path.display())
}
