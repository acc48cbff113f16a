//! The options shared by `enhance` and `evaluate`: method, preprocessing, engine, images.

use contrastxr::algorithm::{Method, Params};
use contrastxr::image::RgbaImage;

use super::args::{parse_f32, parse_pair, Opt};
use super::engine::Engine;
use super::{Args, CliError};

pub const METHOD_USAGE: &str = "\
method and preprocessing options (defaults are the paper's):
  --lambda-e F             maximum colour change, scaled LAB units (0.4; 0 = no change)
  --lambda-jnd-scaled F    JND sphere radius, scaled units (0.046 = Delta E 2.3)
  --transmittance F        lens transmittance applied to the background (0.4)
  --achromatic-boost F     beyond the paper: raise chroma on near-grey backgrounds (0 = off, <= 1)
  --luminance-cap F        beyond the paper: output luminance <= (1 + F) x input (0 = off)
  --blur-size N            Gaussian kernel size on the camera grid, odd (3)
  --blur-sigma F           Gaussian sigma in camera pixels (1.5)
  --no-blur                no background blur
  --fov-scale X,Y          camera_uv = scale * display_uv + offset (0.65,0.65)
  --fov-offset X,Y         (0.13,0.17)
  --no-fov                 camera_uv = display_uv
  --method M               paper|hue-only|other-hue|lum-chroma|subtraction (paper)
";

/// The help of [`ENGINE_OPTIONS`], for the commands that run the method.
pub const ENGINE_USAGE: &str = "\
  --engine E               gpu|cpu (gpu; cpu is the exact, slower reference)
";

/// The options [`params`] reads.
pub const METHOD_OPTIONS: &[Opt] = &[
    Opt::value("--lambda-e", "F"),
    Opt::value("--lambda-jnd-scaled", "F"),
    Opt::value("--transmittance", "F"),
    Opt::value("--achromatic-boost", "F"),
    Opt::value("--luminance-cap", "F"),
    Opt::value("--blur-size", "N"),
    Opt::value("--blur-sigma", "F"),
    Opt::flag("--no-blur"),
    Opt::value("--fov-scale", "X,Y"),
    Opt::value("--fov-offset", "X,Y"),
    Opt::flag("--no-fov"),
    Opt::value("--method", "M"),
];

/// The option [`engine`] reads.
pub const ENGINE_OPTIONS: &[Opt] = &[Opt::value("--engine", "E")];

/// Takes the method and preprocessing options out of `args`, starting from the defaults.
pub fn params(args: &mut Args) -> Result<Params, CliError> {
    let mut p = Params::default();
    let number = |args: &mut Args, name: &str, slot: &mut f32| -> Result<(), CliError> {
        if let Some(v) = args.value(&[name])? {
            *slot = parse_f32(name, &v)?;
        }
        Ok(())
    };
    number(args, "--lambda-e", &mut p.lambda_e)?;
    number(args, "--lambda-jnd-scaled", &mut p.lambda_jnd_scaled)?;
    number(args, "--transmittance", &mut p.transmittance)?;
    number(args, "--achromatic-boost", &mut p.achromatic_boost)?;
    number(args, "--luminance-cap", &mut p.luminance_cap)?;
    number(args, "--blur-sigma", &mut p.blur_sigma)?;
    if let Some(v) = args.value(&["--blur-size"])? {
        p.blur_size = v.trim().parse().map_err(|_| {
            CliError::Failure(format!(
                "--blur-size must be a positive odd integer, got '{v}'"
            ))
        })?;
    }
    if let Some(v) = args.value(&["--fov-scale"])? {
        p.fov_scale = parse_pair("--fov-scale", &v)?;
    }
    if let Some(v) = args.value(&["--fov-offset"])? {
        p.fov_offset = parse_pair("--fov-offset", &v)?;
    }
    p.blur = !args.flag("--no-blur");
    p.fov = !args.flag("--no-fov");
    if let Some(v) = args.value(&["--method"])? {
        p.method = Method::parse(&v).ok_or_else(|| {
            let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
            CliError::Failure(format!(
                "--method must be one of {}, got '{v}'",
                names.join(", ")
            ))
        })?;
    }
    p.validate().map_err(CliError::Failure)?;
    Ok(p)
}

pub fn engine(args: &mut Args) -> Result<Engine, CliError> {
    match args.value(&["--engine"])? {
        None => Ok(Engine::Gpu),
        Some(v) => Engine::parse(&v)
            .ok_or_else(|| CliError::Failure(format!("--engine must be gpu or cpu, got '{v}'"))),
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
