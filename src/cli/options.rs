//! The options shared by `enhance` and `evaluate`: method, preprocessing, engine, images.

use contrastxr::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use contrastxr::algorithm::Params;
use contrastxr::config::{Key, Settings, Value, KEYS};
use contrastxr::image::RgbaImage;

use super::args::Args;
use super::args::Opt;
use super::backend_choice::Backend;
use super::error::CliError;

/// The settings of the method the offline commands take as options: the keys of
/// [`contrastxr::config::KEYS`] with an `option` (where its meaning, kind and default come
/// from), in KEYS' order, with the option each is parsed by.
fn method_keys() -> impl Iterator<Item = (&'static Key, Opt)> {
    KEYS.iter().filter_map(|k| k.option.map(|o| (k, opt(o))))
}

/// A key's option: a value, or a `--no-` flag where the value's name is "".
const fn opt((long, value): (&'static str, &'static str)) -> Opt {
    match value.is_empty() {
        true => Opt::flag(long),
        false => Opt::value(long, value),
    }
}

const OPTION_COUNT: usize = {
    let mut n = 0;
    let mut i = 0;
    while i < KEYS.len() {
        if KEYS[i].option.is_some() {
            n += 1;
        }
        i += 1;
    }
    n
};

/// The options [`params`] reads.
pub const METHOD_OPTIONS: &[Opt] = &{
    let mut all = [Opt::flag(""); OPTION_COUNT];
    let (mut i, mut j) = (0, 0);
    while i < KEYS.len() {
        if let Some(o) = KEYS[i].option {
            all[j] = opt(o);
            j += 1;
        }
        i += 1;
    }
    all
};

/// The method options' help, from each key's description and default.
pub fn method_usage() -> String {
    let defaults = Settings::default();
    let mut s =
        String::from("method and preprocessing options (defaults as in the config file):\n");
    for (key, option) in method_keys() {
        let left = match option.value {
            Some(v) => format!("{} {v}", option.long),
            None => option.long.to_string(),
        };
        let default = match option.value {
            Some(_) => format!(" ({})", key.get(&defaults)),
            None => String::new(),
        };
        let doc = match option.value {
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
    for (key, option) in method_keys() {
        let long = option.long;
        let value = match option.value {
            None if args.flag(long) => Value::Bool(false),
            None => continue,
            Some(_) => match args.value(&[long])? {
                Some(text) => key.parse_setting(&text).map_err(|_| {
                    let kind = key.kind.describe();
                    CliError::Failure(format!("{long} must be {kind}, got '{text}'"))
                })?,
                None => continue,
            },
        };
        key.apply(&mut settings, value)
            .map_err(|e| CliError::Failure(format!("{long}: {e}")))?;
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
    use contrastxr::config::Kind;

    #[test]
    fn every_option_is_named_after_its_key_and_of_its_kind() {
        for (key, option) in method_keys() {
            let flag = option.value.is_none();
            assert_eq!(flag, key.kind == Kind::Bool, "{}", key.name);
            let long = format!("--{}", key.name.replace('_', "-"));
            let expected = if flag {
                format!("--no-{}", &long[2..])
            } else {
                long
            };
            assert_eq!(option.long, expected);
        }
        assert_eq!(METHOD_OPTIONS.len(), method_keys().count());
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
                    k.option.is_some() || k.name == "mode",
                    "{} changes the method but has no option",
                    k.name
                );
            }
        }
    }

    #[test]
    fn the_help_names_each_option_with_its_default() {
        let usage = method_usage();
        for option in METHOD_OPTIONS {
            assert!(usage.contains(option.long), "{}", option.long);
        }
        assert!(usage.contains("--lambda-e F"), "{usage}");
        assert!(usage.contains("(0.4)"), "{usage}");
    }
}
