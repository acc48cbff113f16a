//! The options shared by `enhance` and `evaluate`: method, preprocessing, engine, images.

use contrastxr::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use contrastxr::algorithm::Params;
use contrastxr::config::{self, Key, Settings, Value};
use contrastxr::image::RgbaImage;

use super::args::Args;
use super::args::Opt;
use super::backend_choice::Backend;
use super::error::CliError;

/// A setting of the method the offline commands take as an option: its name in
/// [`contrastxr::config::KEYS`] (where its meaning, kind and default come from), the option, and
/// the value's name in the help (None: a `--no-` flag that turns a switch off).
pub struct ParamOption {
    pub key: &'static str,
    pub option: Opt,
}

const fn option(key: &'static str, long: &'static str, value: &'static str) -> ParamOption {
    ParamOption {
        key,
        option: Opt::value(long, value),
    }
}

const fn switch_off(key: &'static str, long: &'static str) -> ParamOption {
    ParamOption {
        key,
        option: Opt::flag(long),
    }
}

/// The method's settings as options; each is parsed and checked by its key, as in the config
/// file (a test holds this list to KEYS).
pub const PARAM_OPTIONS: [ParamOption; 17] = [
    option("method", "--method", "M"),
    option("lambda_e", "--lambda-e", "F"),
    option("lambda_jnd_scaled", "--lambda-jnd-scaled", "F"),
    option("transmittance", "--transmittance", "F"),
    option("achromatic_boost", "--achromatic-boost", "F"),
    option("luminance_cap", "--luminance-cap", "F"),
    option("blur_size", "--blur-size", "N"),
    option("blur_sigma", "--blur-sigma", "F"),
    switch_off("blur", "--no-blur"),
    option("fov_scale", "--fov-scale", "X,Y"),
    option("fov_offset", "--fov-offset", "X,Y"),
    switch_off("fov", "--no-fov"),
    option("display_peak_nits", "--display-peak-nits", "NITS"),
    option("world_nits", "--world-nits", "NITS"),
    option("target_contrast", "--target-contrast", "F"),
    option("min_luminance", "--min-luminance", "NITS"),
    option("frequency", "--frequency", "FREQ"),
];

/// The options [`params`] reads.
pub const METHOD_OPTIONS: &[Opt] = &{
    let mut all = [Opt::flag(""); PARAM_OPTIONS.len()];
    let mut i = 0;
    while i < PARAM_OPTIONS.len() {
        all[i] = PARAM_OPTIONS[i].option;
        i += 1;
    }
    all
};

fn key_of(o: &ParamOption) -> &'static Key {
    config::key(o.key).expect("PARAM_OPTIONS names KEYS (tested)")
}

/// The method options' help, from each key's description and default.
pub fn method_usage() -> String {
    let defaults = Settings::default();
    let mut s =
        String::from("method and preprocessing options (defaults as in the config file):\n");
    for o in &PARAM_OPTIONS {
        let key = key_of(o);
        let left = match o.option.value {
            Some(v) => format!("{} {v}", o.option.long),
            None => o.option.long.to_string(),
        };
        let default = match o.option.value {
            Some(_) => format!(" ({})", key.get(&defaults)),
            None => String::new(),
        };
        let doc = match o.option.value {
            Some(_) => key.doc.to_string(),
            None => format!("{} = false", key.name),
        };
        s += &format!("  {left:<24} {doc}{default}\n");
    }
    s
}
/// The help of [`ENGINE_OPTIONS`], for the commands that run the method.
pub const ENGINE_USAGE: &str =
    "  --engine E               gpu|cpu|opengl (gpu; cpu is the exact, slower reference; opengl\n                           the layer's OpenGL backend on an offline EGL context)\n";

/// The help of [`PPD_OPTIONS`], one line.
pub fn ppd_usage() -> String {
    format!(
        "  --ppd N              the display's pixels per degree of view \
         ({DEFAULT_PIXELS_PER_DEGREE}), for frequency = blur\n"
    )
}

/// The option [`pixels_per_degree`] reads.
pub const PPD_OPTIONS: &[Opt] = &[Opt::value("--ppd", "N")];

/// `--ppd`: the view's display pixels per degree, for the perceptual model's `blur` frequency
/// (the layer takes a view's from its field of view); `DEFAULT_PIXELS_PER_DEGREE` without it.
pub fn pixels_per_degree(args: &mut Args) -> Result<f64, CliError> {
    match args.value(&["--ppd"])? {
        None => Ok(DEFAULT_PIXELS_PER_DEGREE),
        Some(t) => match t.trim().parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
            _ => Err(CliError::Failure(format!(
                "--ppd must be a number of pixels per degree > 0, got '{t}'"
            ))),
        },
    }
}

/// The option [`engine`] reads.
pub const ENGINE_OPTIONS: &[Opt] = &[Opt::value("--engine", "E")];

/// Takes the method and preprocessing options out of `args`, starting from the defaults.
pub fn params(args: &mut Args) -> Result<Params, CliError> {
    let mut settings = Settings::default();
    for o in &PARAM_OPTIONS {
        let key = key_of(o);
        let value = match o.option.value {
            None if args.flag(o.option.long) => Value::Bool(false),
            None => continue,
            Some(_) => match args.value(&[o.option.long])? {
                Some(text) => key.parse_setting(&text).map_err(|_| {
                    let kind = key.kind.describe();
                    CliError::Failure(format!("{} must be {kind}, got '{text}'", o.option.long))
                })?,
                None => continue,
            },
        };
        key.apply(&mut settings, value)
            .map_err(|e| CliError::Failure(format!("{}: {e}", o.option.long)))?;
    }
    Ok(settings.params)
}

pub fn engine(args: &mut Args) -> Result<Backend, CliError> {
    match args.value(&["--engine"])? {
        None => Ok(Backend::Vulkan),
        Some(v) => Backend::parse(&v).ok_or_else(|| {
            CliError::Failure(format!("--engine must be gpu, cpu or opengl, got '{v}'"))
        }),
    }
}

pub fn load_path(path: &str, what: &str) -> Result<RgbaImage, CliError> {
    RgbaImage::load(std::path::Path::new(path))
        .map_err(|e| CliError::Failure(format!("cannot read the {what} image: {e}")))
}

pub fn save_image(img: &RgbaImage, path: &str) -> Result<(), CliError> {
    img.save_png(std::path::Path::new(path))
        .map_err(CliError::Failure)
}

#[cfg(test)]
mod tests {
    use super::*;
    use contrastxr::config::{Kind, KEYS};

    #[test]
    fn every_option_is_a_key_of_its_kind() {
        for o in &PARAM_OPTIONS {
            let key = KEYS.iter().find(|k| k.name == o.key);
            let key = key.unwrap_or_else(|| panic!("{} is not in KEYS", o.key));
            let flag = o.option.value.is_none();
            assert_eq!(flag, key.kind == Kind::Bool, "{}", o.key);
            let long = format!("--{}", key.name.replace('_', "-"));
            let expected = if flag {
                format!("--no-{}", &long[2..])
            } else {
                long
            };
            assert_eq!(o.option.long, expected);
        }
    }

    #[test]
    fn every_setting_of_the_method_has_an_option() {
        let defaults = Settings::default();
        for k in KEYS {
            let mut changed = defaults.clone();
            let other = match k.get(&defaults) {
                Value::Bool(b) => Value::Bool(!b),
                Value::Float(f) => Value::Float(f * 0.5 + 0.01),
                Value::Count(n) => Value::Count(n + 2),
                Value::Pair([x, y]) => Value::Pair([x * 0.5, y * 0.5]),
                _ => continue,
            };
            if k.apply(&mut changed, other).is_ok() && changed.params != defaults.params {
                assert!(
                    PARAM_OPTIONS.iter().any(|o| o.key == k.name) || k.name == "mode",
                    "{} changes the method but has no option",
                    k.name
                );
            }
        }
    }

    #[test]
    fn the_help_names_each_option_with_its_default() {
        let usage = method_usage();
        for o in &PARAM_OPTIONS {
            assert!(usage.contains(o.option.long), "{}", o.option.long);
        }
        assert!(usage.contains("--lambda-e F"), "{usage}");
        assert!(usage.contains("(0.4)"), "{usage}");
    }
}
