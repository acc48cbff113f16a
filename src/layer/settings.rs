//! The layer's settings, read once from environment variables (`CONTRASTXR_*`). An invalid
//! value is reported once and that setting keeps its default; the app runs on.

use crate::algorithm::params::{Method, Params};
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct Capture {
    pub dir: PathBuf,
    /// How many frames to capture, after `skip` frames have passed.
    pub frames: u64,
    pub skip: u64,
}

#[derive(Clone, Debug)]
pub struct Settings {
    /// False when CONTRASTXR is 0/false/off/empty: everything passes through, no GPU work.
    pub enabled: bool,
    /// Act on any environment blend mode, not only ADDITIVE (`CONTRASTXR_FORCE=1`).
    pub force: bool,
    /// Also enhance quad layers (`CONTRASTXR_QUAD_LAYERS=1`).
    pub quad_layers: bool,
    pub params: Params,
    /// Background source spec (`CONTRASTXR_BACKGROUND`): `v4l2:auto` (default), `v4l2:/dev/videoN`,
    /// `image:PATH`, `video:PATH` or `color:#RRGGBB`.
    pub background: String,
    pub capture: Option<Capture>,
    /// Problems found while reading the variables (each is logged once).
    pub warnings: Vec<String>,
}

/// The loader enables an implicit layer when its variable is merely set: these values mean off.
pub fn is_off(value: &str) -> bool {
    matches!(
        value.trim().to_ascii_lowercase().as_str(),
        "" | "0" | "false" | "off" | "no"
    )
}

fn is_on(value: &str) -> bool {
    matches!(
        value.trim().to_ascii_lowercase().as_str(),
        "1" | "true" | "on" | "yes"
    )
}

struct Reader<'a> {
    get: &'a dyn Fn(&str) -> Option<String>,
    warnings: Vec<String>,
}

impl Reader<'_> {
    fn parsed<T: std::str::FromStr>(&mut self, name: &str, default: T) -> T {
        match (self.get)(name) {
            None => default,
            Some(v) => v.trim().parse().unwrap_or_else(|_| {
                self.warnings.push(format!(
                    "{name}={v:?} is not a valid value; using the default"
                ));
                default
            }),
        }
    }

    fn pair(&mut self, name: &str, default: [f32; 2]) -> [f32; 2] {
        let Some(v) = (self.get)(name) else {
            return default;
        };
        let parts: Vec<Option<f32>> = v.split(',').map(|p| p.trim().parse().ok()).collect();
        match parts.as_slice() {
            [Some(x), Some(y)] => [*x, *y],
            _ => {
                self.warnings
                    .push(format!("{name}={v:?} is not X,Y; using the default"));
                default
            }
        }
    }

    fn flag(&mut self, name: &str) -> bool {
        (self.get)(name).is_some_and(|v| is_on(&v))
    }
}

impl Settings {
    pub fn from_env() -> Settings {
        Self::from_lookup(&|name| std::env::var(name).ok())
    }

    /// Reads settings through `get` (the environment, or a map in tests).
    pub fn from_lookup(get: &dyn Fn(&str) -> Option<String>) -> Settings {
        let mut r = Reader {
            get,
            warnings: Vec::new(),
        };
        let d = Params::default();
        let method_name = (r.get)("CONTRASTXR_METHOD").unwrap_or_else(|| "paper".into());
        let method = Method::parse(method_name.trim()).unwrap_or_else(|| {
            r.warnings.push(format!(
                "CONTRASTXR_METHOD={method_name:?} is not a method; using paper"
            ));
            Method::Paper
        });
        let mut params = Params {
            lambda_e: r.parsed("CONTRASTXR_LAMBDA_E", d.lambda_e),
            lambda_jnd_scaled: r.parsed("CONTRASTXR_LAMBDA_JND_SCALED", d.lambda_jnd_scaled),
            transmittance: r.parsed("CONTRASTXR_TRANSMITTANCE", d.transmittance),
            blur_size: r.parsed("CONTRASTXR_BLUR_SIZE", d.blur_size),
            blur_sigma: r.parsed("CONTRASTXR_BLUR_SIGMA", d.blur_sigma),
            blur: !r.flag("CONTRASTXR_NO_BLUR"),
            fov_scale: r.pair("CONTRASTXR_FOV_SCALE", d.fov_scale),
            fov_offset: r.pair("CONTRASTXR_FOV_OFFSET", d.fov_offset),
            fov: !r.flag("CONTRASTXR_NO_FOV"),
            method,
            mode: d.mode,
            ..Params::default()
        };
        if let Err(e) = params.validate() {
            r.warnings
                .push(format!("invalid engine settings ({e}); using the defaults"));
            params = Params {
                method,
                ..Params::default()
            };
        }
        let capture = (r.get)("CONTRASTXR_CAPTURE_DIR")
            .filter(|d| !d.is_empty())
            .map(|dir| Capture {
                dir: PathBuf::from(dir),
                frames: 0,
                skip: 0,
            });
        let capture = capture.map(|c| Capture {
            frames: r.parsed("CONTRASTXR_CAPTURE_FRAMES", 1),
            skip: r.parsed("CONTRASTXR_CAPTURE_SKIP", 0),
            ..c
        });
        Settings {
            enabled: (r.get)("CONTRASTXR").is_none_or(|v| !is_off(&v)),
            force: r.flag("CONTRASTXR_FORCE"),
            quad_layers: r.flag("CONTRASTXR_QUAD_LAYERS"),
            params,
            background: (r.get)("CONTRASTXR_BACKGROUND").unwrap_or_else(|| "v4l2:auto".into()),
            capture,
            warnings: r.warnings,
        }
    }

    /// The one startup line's parameter part.
    pub fn describe(&self) -> String {
        let p = &self.params;
        format!(
            "method={} lambda_e={} lambda_jnd_scaled={} transmittance={} blur={}x{}/{} fov_scale={:?} fov_offset={:?} fov={} background={} force={} quad_layers={} capture={}",
            p.method.name(),
            p.lambda_e,
            p.lambda_jnd_scaled,
            p.transmittance,
            if p.blur { p.blur_size } else { 1 },
            if p.blur { p.blur_size } else { 1 },
            p.blur_sigma,
            p.fov_scale,
            p.fov_offset,
            p.fov,
            self.background,
            self.force,
            self.quad_layers,
            self.capture.as_ref().map_or("off".into(), |c| c.dir.display().to_string()),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn read(vars: &[(&str, &str)]) -> Settings {
        let map: HashMap<String, String> = vars
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        Settings::from_lookup(&move |k| map.get(k).cloned())
    }

    #[test]
    fn off_values_disable_the_layer() {
        for v in ["0", "false", "off", "", " OFF "] {
            assert!(!read(&[("CONTRASTXR", v)]).enabled, "{v:?}");
        }
        assert!(read(&[("CONTRASTXR", "1")]).enabled);
    }

    #[test]
    fn bad_values_keep_defaults_and_warn() {
        let s = read(&[
            ("CONTRASTXR_LAMBDA_E", "lots"),
            ("CONTRASTXR_FOV_SCALE", "1"),
        ]);
        assert_eq!(s.params, Params::default());
        assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
        let s = read(&[
            ("CONTRASTXR_LAMBDA_E", "0.6"),
            ("CONTRASTXR_METHOD", "hue-only"),
        ]);
        assert_eq!(s.params.lambda_e, 0.6);
        assert_eq!(s.params.method, Method::HueOnly);
        let s = read(&[("CONTRASTXR_TRANSMITTANCE", "7")]);
        assert_eq!(s.params.transmittance, Params::default().transmittance);
        assert_eq!(s.warnings.len(), 1);
    }
}
