//! The shipped device profiles (`devices.toml`): `[device."SYSTEM"]` tables for headsets people
//! run on Linux, applied below everything in the user's config file. Found at
//! `$CONTRASTXR_DEVICES`, else beside the running layer library (where `contrastxr install`
//! puts them), else beside `install --user`'s and `install --system`'s copies of the library
//! (for the command-line tool, which has no layer loaded), else
//! `/usr/share/contrastxr/devices.toml` (the package's).

use super::path::Env;
use std::path::PathBuf;

/// The package's copy.
pub const PACKAGED_PATH: &str = "/usr/share/contrastxr/devices.toml";
/// The file's name beside the library.
pub const FILE_NAME: &str = "devices.toml";
/// The shipped profiles themselves (written beside the library by `contrastxr install`).
pub const TEXT: &str = include_str!("../../devices.toml");

/// The folder of the layer library loaded in this process, if any (from /proc/self/maps).
fn library_dir() -> Option<PathBuf> {
    let maps = std::fs::read_to_string("/proc/self/maps").ok()?;
    maps.lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .find(|p| p.ends_with("/libcontrastxr.so"))
        .and_then(|p| PathBuf::from(p).parent().map(PathBuf::from))
}

/// The shipped profiles' file, if one exists.
pub fn find(env: &Env) -> Option<PathBuf> {
    if let Some(p) = env.get("CONTRASTXR_DEVICES").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    // Bounded as `path::find` is: a look-up that stalls finds that file, whose read says why.
    let limit = crate::user_file::APP_THREAD_READ;
    searched(env)
        .into_iter()
        .find(|p| crate::user_file::is_file_within(p, limit).unwrap_or(true))
}

/// The files [`find`] tries in turn when `CONTRASTXR_DEVICES` is unset.
pub fn searched(env: &Env) -> Vec<PathBuf> {
    let data_home = env
        .get("XDG_DATA_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            env.get("HOME")
                .map(|h| PathBuf::from(h).join(".local/share"))
        });
    let beside = library_dir().map(|d| d.join(FILE_NAME));
    let user = data_home.map(|d| d.join("contrastxr").join(FILE_NAME));
    let system = PathBuf::from("/usr/local/lib/contrastxr").join(FILE_NAME);
    beside
        .into_iter()
        .chain(user)
        .chain([system, PathBuf::from(PACKAGED_PATH)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{check, resolve_with, Source, Who, KEYS};
    use std::path::Path;

    #[test]
    fn the_shipped_profiles_are_valid_and_name_monado_systems() {
        let path = Path::new("devices.toml");
        assert_eq!(check(Source { path, text: TEXT }), Vec::<String>::new());
        let parsed = crate::config::file::parse(TEXT).unwrap();
        let names: Vec<&str> = parsed.devices.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "Monado: North Star",
                "Monado: Xreal Air Glasses",
                "Monado: Rokid Max",
                "Monado: Rokid Air"
            ]
        );
        assert!(parsed.defaults.is_empty() && parsed.apps.is_empty());
    }

    fn index(name: &str) -> usize {
        KEYS.iter().position(|k| k.name == name).unwrap()
    }

    #[test]
    fn shipped_below_the_device_table_below_the_app_table_below_the_environment() {
        let shipped = "[device.\"D\"]\nlambda_e = 0.3\nenvironment_blend_mode = \"additive\"\n";
        let shipped = Source {
            path: Path::new("/usr/share/contrastxr/devices.toml"),
            text: shipped,
        };
        let on = |user: &str, env: &[(&str, &str)], device| {
            let file = Source {
                path: Path::new("/c.toml"),
                text: user,
            };
            let env = crate::config::Env::from_pairs(env.iter().copied());
            let who = Who { app: "A", device };
            resolve_with(who, Some(shipped), Some(file), &env)
        };
        let r = on("", &[], Some("D"));
        assert_eq!(r.settings.params.lambda_e, 0.3);
        assert!(r.settings.additive_display);
        let line = r.line(index("environment_blend_mode"));
        assert_eq!(
            line,
            "environment_blend_mode = \"additive\"  # /usr/share/contrastxr/devices.toml [device.\"D\"]:3"
        );
        // Another system: the shipped table does not apply.
        assert!(!on("", &[], Some("E")).settings.additive_display);
        assert!(!on("", &[], None).settings.additive_display);
        let lambda_e = |r: &crate::config::Resolved| {
            let i = index("lambda_e");
            (r.settings.params.lambda_e, r.origins[i].to_string())
        };
        let shipped_origin = "/usr/share/contrastxr/devices.toml [device.\"D\"]:2";
        assert_eq!(
            lambda_e(&on("lambda_e = 0.35\n", &[], Some("D"))),
            (0.35, "/c.toml:1".into()),
            "the user's top level beats the shipped table"
        );
        assert_eq!(
            lambda_e(&on("", &[], Some("D"))),
            (0.3, shipped_origin.into())
        );
        let device = "[device.\"D\"]\nlambda_e = 0.4\n";
        assert_eq!(
            lambda_e(&on(device, &[], Some("D"))),
            (0.4, "/c.toml [device.\"D\"]:2".into())
        );
        let app = format!("{device}[app.\"A\"]\nlambda_e = 0.5\n");
        assert_eq!(
            lambda_e(&on(&app, &[], Some("D"))),
            (0.5, "/c.toml [app.\"A\"]:4".into())
        );
        let env = [("CONTRASTXR_LAMBDA_E", "0.6")];
        assert_eq!(
            lambda_e(&on(&app, &env, Some("D"))),
            (0.6, "env CONTRASTXR_LAMBDA_E".into())
        );
        let env = [("CONTRASTXR_ENVIRONMENT_BLEND_MODE", "")];
        assert!(!on("", &env, Some("D")).settings.additive_display);
    }
}
