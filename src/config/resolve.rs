//! Effective settings for one app on one device: the defaults, then the shipped profiles'
//! `[device."SYSTEM"]` table, then the file's top-level keys,
//! then its `[device."SYSTEM"]` table (once the system is known), then its `[app."NAME"]`
//! table, then the environment. An invalid value gets one message naming its
//! file, line and key (or its variable), and is ignored: the key keeps the value it had
//! without it (its default, unless an earlier source set it).

use super::file::{self, Entry};
use super::keys::{Key, KEYS};
use super::origin::{Origin, Table};
use super::path::Env;
use super::settings::Settings;
use std::path::{Path, PathBuf};

pub struct Resolved {
    pub settings: Settings,
    /// One per entry of [`KEYS`], in that order.
    pub origins: Vec<Origin>,
    /// One sentence per problem, each naming file and line (or variable) and key.
    pub problems: Vec<String>,
    /// The file that was read, if any.
    pub file: Option<PathBuf>,
    /// The file could not be read or parsed, so none of it applies.
    pub file_failed: bool,
}

/// A config file's path and text.
#[derive(Clone, Copy)]
pub struct Source<'a> {
    pub path: &'a Path,
    pub text: &'a str,
}

/// The loader enables an implicit layer when its variable is merely set: these values mean off.
pub fn is_off(value: &str) -> bool {
    matches!(
        value.trim().to_ascii_lowercase().as_str(),
        "" | "0" | "false" | "off" | "no"
    )
}

impl Resolved {
    fn new() -> Resolved {
        Resolved {
            settings: Settings::default(),
            origins: vec![Origin::Default; KEYS.len()],
            problems: Vec::new(),
            file: None,
            file_failed: false,
        }
    }

    /// `key = value  # origin` for the key at `index` in [`KEYS`].
    pub fn line(&self, index: usize) -> String {
        let k = &KEYS[index];
        format!(
            "{} = {}  # {}",
            k.name,
            k.get(&self.settings),
            self.origins[index]
        )
    }

    /// Applies `value` to key `index`, or records why not.
    fn offer(&mut self, index: usize, value: Result<super::value::Value, String>, from: Origin) {
        let key: &Key = &KEYS[index];
        let applied = value.and_then(|v| key.apply(&mut self.settings, v));
        match applied {
            Ok(()) => self.origins[index] = from,
            Err(why) => {
                let place = match &from {
                    Origin::File { path, line, .. } => format!("config {}:{line}", path.display()),
                    Origin::Env(var) => format!("environment variable {var}"),
                    Origin::Default => "default".into(),
                };
                self.problems.push(format!(
                    "{place}: {}: {why}; {} stays {} ({})",
                    key.name,
                    key.name,
                    key.get(&self.settings),
                    self.origins[index]
                ));
            }
        }
    }

    fn apply_entries(&mut self, path: &Path, table: &Table, entries: &[Entry]) {
        for e in entries
            .iter()
            .filter(|e| super::keys::key(&e.key).is_none())
        {
            let known: Vec<&str> = KEYS.iter().map(|k| k.name).collect();
            self.problems.push(format!(
                "config {}:{}: unknown key {:?} (known keys: {})",
                path.display(),
                e.line,
                e.key,
                known.join(", ")
            ));
        }
        for (index, key) in KEYS.iter().enumerate() {
            for e in entries.iter().filter(|e| e.key == key.name) {
                let value = match &e.value {
                    Ok(v) => key.kind.from_toml(v),
                    Err(found) => Err(format!("expected {}, found a {found}", key.kind.describe())),
                };
                let from = Origin::File {
                    path: path.to_path_buf(),
                    table: table.clone(),
                    line: e.line,
                };
                self.offer(index, value, from);
            }
        }
    }

    fn apply_file(&mut self, who: Who, source: Source) {
        self.file = Some(source.path.to_path_buf());
        let parsed = match file::parse(source.text) {
            Ok(parsed) => parsed,
            Err(e) => {
                self.file_failed = true;
                self.problems.push(format!(
                    "config {}:{}: not valid TOML ({}); the whole file is ignored",
                    source.path.display(),
                    e.line,
                    e.message.lines().next().unwrap_or("syntax error")
                ));
                return;
            }
        };
        for (line, problem) in &parsed.problems {
            let p = source.path.display();
            self.problems.push(format!("config {p}:{line}: {problem}"));
        }
        self.apply_entries(source.path, &Table::Top, &parsed.defaults);
        for (name, entries) in &parsed.devices {
            if Some(name.as_str()) == who.device {
                self.apply_entries(source.path, &Table::Device(name.clone()), entries);
            }
        }
        for (name, entries) in &parsed.apps {
            if name == who.app {
                self.apply_entries(source.path, &Table::App(name.clone()), entries);
            }
        }
    }

    /// The shipped profiles' table for `who`'s device only (problems within its tables are the
    /// package's, and reported by `contrastxr doctor`, not at every start).
    fn apply_shipped(&mut self, who: Who, source: Source) {
        let parsed = match file::parse(source.text) {
            Ok(parsed) => parsed,
            Err(e) => {
                // A file that is not TOML at all is named: it may be a wrong CONTRASTXR_DEVICES.
                self.problems.push(format!(
                    "device profiles {}:{}: not valid TOML; none are used",
                    source.path.display(),
                    e.line
                ));
                return;
            }
        };
        for (name, entries) in &parsed.devices {
            if Some(name.as_str()) == who.device {
                let before = self.problems.len();
                self.apply_entries(source.path, &Table::Device(name.clone()), entries);
                self.problems.truncate(before);
            }
        }
    }

    fn apply_env(&mut self, env: &Env) {
        for (index, key) in KEYS.iter().enumerate() {
            if let Some(text) = env.get(key.env) {
                let value = key
                    .parse_text(&text)
                    .map_err(|e| format!("{}={text:?}: {e}", key.env));
                self.offer(index, value, Origin::Env(key.env));
            }
        }
        self.settings.enabled = !env.get("CONTRASTXR").is_some_and(|v| is_off(&v));
    }
}

/// Whose settings: an app (XrApplicationInfo.applicationName) on a device
/// (XrSystemProperties.systemName; None before the app has chosen a system).
#[derive(Clone, Copy, Debug, Default)]
pub struct Who<'a> {
    pub app: &'a str,
    pub device: Option<&'a str>,
}

/// The effective settings for `app` from a file (if any) and the environment.
pub fn resolve(app: &str, file: Option<Source>, env: &Env) -> Resolved {
    resolve_for(Who { app, device: None }, file, env)
}

/// The effective settings for an app on a device from a file (if any) and the environment.
pub fn resolve_for(who: Who, file: Option<Source>, env: &Env) -> Resolved {
    resolve_with(who, None, file, env)
}

/// [`resolve_for`] with the shipped device profiles below the file.
pub fn resolve_with(
    who: Who,
    shipped: Option<Source>,
    file: Option<Source>,
    env: &Env,
) -> Resolved {
    let mut r = Resolved::new();
    if let Some(source) = shipped {
        r.apply_shipped(who, source);
    }
    if let Some(source) = file {
        r.apply_file(who, source);
    }
    r.apply_env(env);
    r
}

/// Every problem of a file: its top level and each `[device."SYSTEM"]` and `[app."NAME"]`
/// table (no environment).
pub fn check(source: Source) -> Vec<String> {
    let env = Env::default();
    let mut all: Vec<String> = resolve("", Some(source), &env).problems;
    let (devices, apps): (Vec<String>, Vec<String>) = file::parse(source.text)
        .map(|f| {
            let names = |t: Vec<(String, Vec<Entry>)>| t.into_iter().map(|(n, _)| n).collect();
            (names(f.devices), names(f.apps))
        })
        .unwrap_or_default();
    let devices = devices.iter().map(|d| Who {
        app: "",
        device: Some(d.as_str()),
    });
    let apps = apps.iter().map(|a| Who {
        app: a.as_str(),
        device: None,
    });
    for who in devices.chain(apps) {
        for p in resolve_for(who, Some(source), &env).problems {
            if !all.contains(&p) {
                all.push(p);
            }
        }
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::params::{Method, ViewMode};

    fn with(text: &str, app: &str, env: &[(&str, &str)]) -> Resolved {
        let source = Source {
            path: Path::new("/c.toml"),
            text,
        };
        resolve(app, Some(source), &Env::from_pairs(env.iter().copied()))
    }

    fn origin(r: &Resolved, key: &str) -> String {
        let i = KEYS.iter().position(|k| k.name == key).unwrap();
        r.origins[i].to_string()
    }

    #[test]
    fn precedence_default_file_app_env() {
        let text = "lambda_e = 0.5\ntransmittance = 0.3\n[app.\"game\"]\nlambda_e = 0.6\nmode = \"split\"\n";
        let r = with(text, "other", &[]);
        assert_eq!(r.settings.params.lambda_e, 0.5);
        assert_eq!(r.settings.params.mode, ViewMode::Enhance);
        assert_eq!(origin(&r, "lambda_e"), "/c.toml:1");
        let r = with(text, "game", &[("CONTRASTXR_TRANSMITTANCE", "0.2")]);
        assert_eq!(r.settings.params.lambda_e, 0.6);
        assert_eq!(origin(&r, "lambda_e"), "/c.toml [app.\"game\"]:4");
        assert_eq!(r.settings.params.mode, ViewMode::Split);
        assert_eq!(r.settings.params.transmittance, 0.2);
        assert_eq!(origin(&r, "transmittance"), "env CONTRASTXR_TRANSMITTANCE");
        assert_eq!(origin(&r, "blur_sigma"), "default");
        assert!(r.problems.is_empty(), "{:?}", r.problems);
    }

    #[test]
    fn wrong_types_name_file_line_and_key_and_keep_the_default() {
        let r = with("\n\nlambda_e = \"high\"\nmethod = 3\n", "", &[]);
        assert_eq!(r.settings, Settings::default());
        assert_eq!(r.problems.len(), 2, "{:?}", r.problems);
        assert!(
            r.problems[1]
                .starts_with("config /c.toml:3: lambda_e: expected a number, found a string"),
            "{:?}",
            r.problems
        );
        assert!(
            r.problems[0].contains("/c.toml:4: method:"),
            "{:?}",
            r.problems
        );
    }

    #[test]
    fn a_syntax_error_ignores_the_file_and_names_the_line() {
        let r = with(
            "lambda_e = 0.6\n[app.\"x\"\n",
            "",
            &[("CONTRASTXR_METHOD", "hue-only")],
        );
        assert!(r.file_failed);
        assert_eq!(r.settings.params.lambda_e, 0.4);
        assert_eq!(r.settings.params.method, Method::HueOnly);
        assert_eq!(r.problems.len(), 1);
        assert!(
            r.problems[0].starts_with("config /c.toml:2: not valid TOML"),
            "{:?}",
            r.problems
        );
    }

    #[test]
    fn bad_environment_values_keep_the_file_value() {
        let r = with(
            "lambda_e = 0.6\n",
            "",
            &[
                ("CONTRASTXR_LAMBDA_E", "lots"),
                ("CONTRASTXR_FOV_SCALE", "1"),
            ],
        );
        assert_eq!(r.settings.params.lambda_e, 0.6);
        assert_eq!(r.problems.len(), 2, "{:?}", r.problems);
        assert!(
            r.problems[0].contains("CONTRASTXR_LAMBDA_E=\"lots\""),
            "{:?}",
            r.problems
        );
    }

    #[test]
    fn unknown_keys_and_off_values() {
        let r = with("lamda_e = 1\n", "", &[("CONTRASTXR", "0")]);
        assert!(!r.settings.enabled);
        assert!(r.problems[0].contains("/c.toml:1: unknown key \"lamda_e\""));
        for v in ["0", "false", "off", "", " OFF "] {
            assert!(is_off(v), "{v:?}");
        }
    }

    #[test]
    fn check_covers_every_app_and_device_table() {
        let text = "lambda_e = -1\n[app.\"a\"]\nblur_size = 4\n[app.\"b\"]\nfov = 2\n[device.\"d\"]\nscene_distance = 0\n";
        let problems = check(Source {
            path: Path::new("/c.toml"),
            text,
        });
        assert_eq!(problems.len(), 4, "{problems:?}");
    }

    #[test]
    fn device_tables_sit_between_the_top_level_and_app_tables() {
        let text = "camera_fov = [80, 60]\nlambda_e = 0.5\n\
                    [device.\"HMD\"]\ncamera_fov = [100, 75]\nlambda_e = 0.6\nscene_distance = 3\n\
                    [app.\"game\"]\nlambda_e = 0.7\n";
        let source = Source {
            path: Path::new("/c.toml"),
            text,
        };
        let env = Env::default();
        let on = |app, device| resolve_for(Who { app, device }, Some(source), &env);
        let r = on("game", Some("HMD"));
        assert_eq!(r.settings.registration.camera_fov, [100.0, 75.0]);
        assert_eq!(r.settings.registration.scene_distance, 3.0);
        assert_eq!(r.settings.params.lambda_e, 0.7);
        assert_eq!(origin(&r, "camera_fov"), "/c.toml [device.\"HMD\"]:4");
        assert_eq!(origin(&r, "scene_distance"), "/c.toml [device.\"HMD\"]:6");
        assert_eq!(origin(&r, "lambda_e"), "/c.toml [app.\"game\"]:8");
        let r = on("other", Some("HMD"));
        assert_eq!(r.settings.params.lambda_e, 0.6);
        let r = on("other", Some("another HMD"));
        assert_eq!(r.settings.registration.camera_fov, [80.0, 60.0]);
        assert_eq!(r.settings.params.lambda_e, 0.5);
        let r = on("other", None);
        assert_eq!(r.settings.registration.scene_distance, 2.0);
    }

    #[test]
    fn camera_usb_ids_are_a_list_of_vid_pid() {
        let r = with("camera_usb_ids = \"0c45:636b, 0c45:6368\"\n", "", &[]);
        assert_eq!(r.settings.camera.usb_ids.len(), 2);
        assert_eq!(
            r.line(
                KEYS.iter()
                    .position(|k| k.name == "camera_usb_ids")
                    .unwrap()
            ),
            "camera_usb_ids = \"0c45:636b,0c45:6368\"  # /c.toml:1"
        );
        let r = with("", "", &[("CONTRASTXR_CAMERA_USB_IDS", "0c45:636b,webcam")]);
        assert!(r.settings.camera.usb_ids.is_empty());
        assert!(
            r.problems[0].contains("\"webcam\" is not VID:PID"),
            "{:?}",
            r.problems
        );
        let r = with("camera_usb_ids = [\"0c45:636b\"]\n", "", &[]);
        assert!(
            r.problems[0].contains("expected a string"),
            "{:?}",
            r.problems
        );
    }

    #[test]
    fn a_huge_camera_size_is_refused_by_name_and_the_default_kept() {
        let r = with(
            "camera_width = 100000\n",
            "",
            &[("CONTRASTXR_CAMERA_HEIGHT", "4294967296")],
        );
        assert_eq!(r.settings.camera, crate::camera::CaptureConfig::default());
        assert_eq!(
            r.problems,
            [
                "config /c.toml:1: camera_width: 100000 is not in [0, 8192]; camera_width stays 640 (default)",
                "environment variable CONTRASTXR_CAMERA_HEIGHT: camera_height: 4294967296 is not in [0, 8192]; camera_height stays 480 (default)",
            ]
        );
    }

    #[test]
    fn a_set_manual_mapping_overrides_the_profile() {
        let r = with("camera_fov = [90, 70]\nfov_scale = [0.65, 0.65]\n", "", &[]);
        assert!(!r.settings.manual_mapping_set());
        assert!(r.settings.registration.profile().is_some());
        let r = with("camera_fov = [90, 70]\nfov_offset = [0.1, 0.1]\n", "", &[]);
        assert!(r.settings.manual_mapping_set());
        let r = with("", "", &[("CONTRASTXR_FOV_SCALE", "0.7,0.7")]);
        assert!(r.settings.manual_mapping_set());
    }

    #[test]
    fn camera_profile_values_are_checked() {
        let r = with(
            "camera_fov = [190, 70]\ncamera_intrinsics = [500, 500, 320, 240, 0, 480]\n\
             camera_position = [0, 0]\nleft_eye_scale = [0, 1]\nscene_distance = -1\n",
            "",
            &[],
        );
        assert_eq!(r.problems.len(), 5, "{:#?}", r.problems);
        assert_eq!(r.settings, Settings::default());
        let r = with(
            "camera_intrinsics = [500, 510, 319.5, 239.5, 640, 480]\ncamera_position = [0, 0.02, -0.05]\n",
            "",
            &[("CONTRASTXR_CAMERA_ROTATION", "-10,0,0")],
        );
        assert!(r.problems.is_empty(), "{:?}", r.problems);
        let profile = r.settings.registration.profile().unwrap();
        assert!(matches!(
            profile.lens,
            crate::algorithm::registration::Lens::Pixels { fx, .. } if fx == 500.0
        ));
    }
}
