//! Every setting, once: its TOML key, its environment variable, its kind and how it reads and
//! writes [`Settings`]. The file, the environment, `config print` and `contrastxr set` all go
//! through this table.

use super::settings::{CopyBack, CopyIn, InPlace, Settings};
use super::value::{short_f64, Kind, Value};
use crate::algorithm::params::{Method, ViewMode};
use crate::algorithm::perceptual_settings::Frequency;
use crate::algorithm::registration::Lens;
use crate::camera::source::MAX_CAMERA_SIDE;
use crate::camera::usb_id::UsbId;
use std::path::PathBuf;

pub struct Key {
    /// The TOML key (and the name `contrastxr set` takes).
    pub name: &'static str,
    /// The environment variable that overrides the file.
    pub env: &'static str,
    /// The variable is a `NO_` switch: on means the setting is false.
    pub env_negated: bool,
    pub kind: Kind,
    /// The option the offline commands that run the method take for it (enhance, evaluate,
    /// bench, animate, gl-programs): its spelling and its value's name in their help, or ""
    /// for a `--no-` switch that turns the setting off; None: a setting of the layer only.
    pub option: Option<(&'static str, &'static str)>,
    pub doc: &'static str,
    set: fn(&mut Settings, Value) -> Result<(), String>,
    get: fn(&Settings) -> Value,
}

/// The values of `mode`: the view modes, and the comparison methods (shown in mode enhance),
/// from the method table (src/algorithm/method/table.rs).
pub use crate::algorithm::method::MODES;

fn float(v: Value) -> Result<f32, String> {
    match v {
        Value::Float(x) if x.is_finite() => Ok(x),
        Value::Float(x) => Err(format!("{x} is not a finite number")),
        other => Err(format!("{other} is not a number")),
    }
}

/// A number for an f64 setting: the shortest decimal of the f32 a value holds (0.05, not
/// 0.0500000007), so that a value read back is the one written.
fn float64(v: Value) -> Result<f64, String> {
    float(v).map(short_f64)
}

fn set_frequency(s: &mut Settings, v: Value) -> Result<(), String> {
    s.params.perceptual.frequency = Frequency::parse(&text(v)?)?;
    Ok(())
}

fn non_negative(v: Value) -> Result<f32, String> {
    match float(v)? {
        x if x >= 0.0 => Ok(x),
        x => Err(format!("{x} is negative")),
    }
}

fn count(v: Value) -> Result<u64, String> {
    match v {
        Value::Count(n) => Ok(n),
        other => Err(format!("{other} is not a whole number")),
    }
}

/// A wanted camera width or height, at most [`MAX_CAMERA_SIDE`]: file backgrounds are made at
/// this size, so a larger one would cost memory for nothing (100000 x 100000 RGBA is 37 GiB).
fn camera_side(v: Value) -> Result<u32, String> {
    match count(v)? {
        n if n <= u64::from(MAX_CAMERA_SIDE) => Ok(n as u32),
        n => Err(format!("{n} is not in [0, {MAX_CAMERA_SIDE}]")),
    }
}

fn boolean(v: Value) -> Result<bool, String> {
    match v {
        Value::Bool(b) => Ok(b),
        other => Err(format!("{other} is not true or false")),
    }
}

/// `auto` (None) or a whole number, for a camera control.
fn auto_or_count(v: Value) -> Result<Option<u32>, String> {
    let text = match v {
        Value::Text(t) => t,
        Value::Count(n) => n.to_string(),
        other => return Err(format!("{other} is not auto or a whole number")),
    };
    if text.trim() == "auto" {
        return Ok(None);
    }
    text.trim()
        .parse()
        .map(Some)
        .map_err(|_| format!("{text:?} is not auto or a whole number"))
}

fn auto_text(v: Option<u32>) -> Value {
    Value::Text(v.map_or("auto".into(), |n| n.to_string()))
}

fn pair(v: Value) -> Result<[f32; 2], String> {
    match v {
        Value::Pair(p) if p.iter().all(|x| x.is_finite()) => Ok(p),
        other => Err(format!("{other} is not two finite numbers")),
    }
}

fn numbers<const N: usize>(v: Value) -> Result<[f32; N], String> {
    let list = match v {
        Value::Numbers(list) => list,
        Value::Pair(p) => p.to_vec(),
        other => return Err(format!("{other} is not {N} numbers")),
    };
    let array: [f32; N] = list
        .try_into()
        .map_err(|l: Vec<f32>| format!("{} numbers, not {N}", l.len()))?;
    if array.iter().all(|x| x.is_finite()) {
        Ok(array)
    } else {
        Err(format!("{array:?} are not {N} finite numbers"))
    }
}

fn set_camera_fov(s: &mut Settings, v: Value) -> Result<(), String> {
    let fov = pair(v)?;
    let zero = fov == [0.0, 0.0];
    if !zero && !fov.iter().all(|a| *a > 0.0 && *a < 180.0) {
        return Err(format!(
            "{fov:?}: both angles must be in (0, 180) degrees, or [0, 0] for none"
        ));
    }
    s.registration.camera_fov = fov;
    Ok(())
}

fn set_camera_intrinsics(s: &mut Settings, v: Value) -> Result<(), String> {
    let k: [f32; 6] = numbers(v)?;
    if Lens::from_intrinsics(k).is_some_and(|lens| lens.check().is_err()) {
        return Err(format!(
            "{k:?}: fx, fy, width and height must be > 0, or all six 0 for none"
        ));
    }
    s.registration.camera_intrinsics = k;
    Ok(())
}

fn set_scene_distance(s: &mut Settings, v: Value) -> Result<(), String> {
    let d = float(v)?;
    if d <= 0.0 {
        return Err(format!("{d} is not a distance > 0 (metres)"));
    }
    s.registration.scene_distance = d;
    Ok(())
}

fn eye_scale(v: Value) -> Result<[f32; 2], String> {
    let scale = pair(v)?;
    if scale.iter().all(|x| *x > 0.0) {
        Ok(scale)
    } else {
        Err(format!("{scale:?}: both scales must be > 0"))
    }
}

fn text(v: Value) -> Result<String, String> {
    match v {
        Value::Text(t) => Ok(t),
        other => Err(format!("{other} is not a string")),
    }
}

fn set_mode(s: &mut Settings, v: Value) -> Result<(), String> {
    let name = text(v)?;
    if let Some(mode) = ViewMode::parse(&name) {
        s.params.mode = mode;
    } else if let Some(method) = Method::parse(&name).filter(|m| m.entry().comparison) {
        // A comparison method is shown like the paper's: mode enhance with that method.
        s.params.mode = ViewMode::Enhance;
        s.params.method = method;
    } else {
        return Err(format!(
            "{name:?} is not a mode: use one of {}",
            MODES.join(", ")
        ));
    }
    Ok(())
}

fn set_method(s: &mut Settings, v: Value) -> Result<(), String> {
    let name = text(v)?;
    s.params.method = Method::parse(&name).ok_or_else(|| {
        let all: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        format!("{name:?} is not a method: use one of {}", all.join(", "))
    })?;
    Ok(())
}

fn set_background(s: &mut Settings, v: Value) -> Result<(), String> {
    let spec = text(v)?;
    crate::camera::parse_source(&spec)?;
    s.background = spec.trim().to_string();
    Ok(())
}

fn set_capture_dir(s: &mut Settings, v: Value) -> Result<(), String> {
    let dir = text(v)?;
    s.capture_dir = (!dir.trim().is_empty()).then(|| PathBuf::from(dir.trim()));
    Ok(())
}

/// Every setting, in the order they are applied and printed. `method` comes before `mode`
/// (a comparison mode sets the method) and `blur` before `blur_size` (an even size is valid
/// only without blur).
pub const KEYS: &[Key] = &[
    Key {
        name: "method",
        env: "CONTRASTXR_METHOD",
        env_negated: false,
        kind: Kind::Text,
        option: Some(("--method", "M")),
        doc: crate::algorithm::method::METHOD_DOC,
        set: set_method,
        get: |s| Value::Text(s.params.method.name().into()),
    },
    Key {
        name: "mode",
        env: "CONTRASTXR_MODE",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: crate::algorithm::method::MODE_DOC,
        set: set_mode,
        get: |s| Value::Text(s.params.mode.name().into()),
    },
    Key {
        name: "lambda_e",
        env: "CONTRASTXR_LAMBDA_E",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--lambda-e", "F")),
        doc: "largest colour change in the scaled space (the paper's lambda'_E)",
        set: |s, v| {
            s.params.lambda_e = float(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.lambda_e),
    },
    Key {
        name: "lambda_jnd_scaled",
        env: "CONTRASTXR_LAMBDA_JND_SCALED",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--lambda-jnd-scaled", "F")),
        doc: "JND radius in the scaled space",
        set: |s, v| {
            s.params.lambda_jnd_scaled = float(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.lambda_jnd_scaled),
    },
    Key {
        name: "transmittance",
        env: "CONTRASTXR_TRANSMITTANCE",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--transmittance", "F")),
        doc: "lens transmittance applied to the background, in [0, 1]",
        set: |s, v| {
            s.params.transmittance = float(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.transmittance),
    },
    Key {
        name: "camera_width",
        env: "CONTRASTXR_CAMERA_WIDTH",
        env_negated: false,
        kind: Kind::Count,
        option: None,
        doc: "wanted camera width: the smallest offered size at least this wide (at most 8192)",
        set: |s, v| {
            s.camera.width = camera_side(v)?;
            Ok(())
        },
        get: |s| Value::Count(u64::from(s.camera.width)),
    },
    Key {
        name: "camera_height",
        env: "CONTRASTXR_CAMERA_HEIGHT",
        env_negated: false,
        kind: Kind::Count,
        option: None,
        doc: "wanted camera height (at most 8192)",
        set: |s, v| {
            s.camera.height = camera_side(v)?;
            Ok(())
        },
        get: |s| Value::Count(u64::from(s.camera.height)),
    },
    Key {
        name: "camera_fps",
        env: "CONTRASTXR_CAMERA_FPS",
        env_negated: false,
        kind: Kind::Count,
        option: None,
        doc: "wanted camera rate: the lowest offered rate at least this high",
        set: |s, v| {
            s.camera.fps = u32::try_from(count(v)?).map_err(|_| "too large")?;
            Ok(())
        },
        get: |s| Value::Count(u64::from(s.camera.fps)),
    },
    Key {
        name: "camera_exposure",
        env: "CONTRASTXR_CAMERA_EXPOSURE",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "auto (the camera's automatic exposure) or a fixed exposure time in microseconds",
        set: |s, v| {
            s.camera.controls.exposure_us = auto_or_count(v)?;
            Ok(())
        },
        get: |s| auto_text(s.camera.controls.exposure_us),
    },
    Key {
        name: "camera_white_balance",
        env: "CONTRASTXR_CAMERA_WHITE_BALANCE",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "auto (the camera's automatic white balance) or a fixed colour temperature in kelvin",
        set: |s, v| {
            s.camera.controls.white_balance_k = auto_or_count(v)?;
            Ok(())
        },
        get: |s| auto_text(s.camera.controls.white_balance_k),
    },
    Key {
        name: "camera_gain",
        env: "CONTRASTXR_CAMERA_GAIN",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "auto (the camera's automatic gain) or a fixed gain in the camera's units",
        set: |s, v| {
            s.camera.controls.gain = auto_or_count(v)?;
            Ok(())
        },
        get: |s| auto_text(s.camera.controls.gain),
    },
    Key {
        name: "background_smoothing",
        env: "CONTRASTXR_BACKGROUND_SMOOTHING",
        env_negated: false,
        kind: Kind::Float,
        option: None,
        doc: "temporal smoothing: weight of the newest camera frame in a moving average, in (0, 1]; 0 = off",
        set: |s, v| {
            let w = float(v)?;
            if !(0.0..=1.0).contains(&w) {
                return Err(format!("{w} is not in [0, 1]"));
            }
            s.camera.smoothing = (w > 0.0 && w < 1.0).then_some(w);
            Ok(())
        },
        get: |s| Value::Float(s.camera.smoothing.unwrap_or(0.0)),
    },
    Key {
        name: "achromatic_boost",
        env: "CONTRASTXR_ACHROMATIC_BOOST",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--achromatic-boost", "F")),
        doc: "beyond the paper: raise chroma on near-grey backgrounds, in [0, 1] (0 = off)",
        set: |s, v| {
            s.params.achromatic_boost = float(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.achromatic_boost),
    },
    Key {
        name: "luminance_cap",
        env: "CONTRASTXR_LUMINANCE_CAP",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--luminance-cap", "F")),
        doc: "beyond the paper: output luminance at most (1 + cap) x input (0 = off)",
        set: |s, v| {
            s.params.luminance_cap = float(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.luminance_cap),
    },
    Key {
        name: "display_peak_nits",
        env: "CONTRASTXR_DISPLAY_PEAK_NITS",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--display-peak-nits", "NITS")),
        doc: "perceptual model: the display's luminance at full white, in cd/m^2 (> 0)",
        set: |s, v| {
            s.params.perceptual.display_peak_nits = float64(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.perceptual.display_peak_nits as f32),
    },
    Key {
        name: "world_nits",
        env: "CONTRASTXR_WORLD_NITS",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--world-nits", "NITS")),
        doc: "perceptual model: the world's luminance, in cd/m^2 before the lens, that the camera's full white stands for (>= 0)",
        set: |s, v| {
            s.params.perceptual.world_nits = float64(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.perceptual.world_nits as f32),
    },
    Key {
        name: "target_contrast",
        env: "CONTRASTXR_TARGET_CONTRAST",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--target-contrast", "F")),
        doc: "perceptual model: the perceived contrast c' at which content counts as visible enough, in (0, 1] (1 is never reached)",
        set: |s, v| {
            s.params.perceptual.target_contrast = float64(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.perceptual.target_contrast as f32),
    },
    Key {
        name: "min_luminance",
        env: "CONTRASTXR_MIN_LUMINANCE",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--min-luminance", "NITS")),
        doc: "perceptual model: the floor, in cd/m^2, on the luminance contrast sensitivity is taken at (0.1 to 31623)",
        set: |s, v| {
            s.params.perceptual.min_luminance = float64(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.perceptual.min_luminance as f32),
    },
    Key {
        name: "frequency",
        env: "CONTRASTXR_FREQUENCY",
        env_negated: false,
        kind: Kind::Text,
        option: Some(("--frequency", "FREQ")),
        doc: "perceptual model: the spatial frequency contrast is judged at: blur (the one the background's blur halves), ensemble (four frequencies of images) or a number of cycles per degree",
        set: set_frequency,
        get: |s| Value::Text(s.params.perceptual.frequency.name()),
    },
    Key {
        name: "blur",
        env: "CONTRASTXR_NO_BLUR",
        env_negated: true,
        kind: Kind::Bool,
        option: Some(("--no-blur", "")),
        doc: "blur the background before use",
        set: |s, v| {
            s.params.blur = boolean(v)?;
            Ok(())
        },
        get: |s| Value::Bool(s.params.blur),
    },
    Key {
        name: "blur_size",
        env: "CONTRASTXR_BLUR_SIZE",
        env_negated: false,
        kind: Kind::Count,
        option: Some(("--blur-size", "N")),
        doc: "Gaussian kernel size in camera pixels (odd, at most 15)",
        set: |s, v| {
            s.params.blur_size = u32::try_from(count(v)?).map_err(|_| "too large")?;
            Ok(())
        },
        get: |s| Value::Count(u64::from(s.params.blur_size)),
    },
    Key {
        name: "blur_sigma",
        env: "CONTRASTXR_BLUR_SIGMA",
        env_negated: false,
        kind: Kind::Float,
        option: Some(("--blur-sigma", "F")),
        doc: "Gaussian sigma in camera pixels",
        set: |s, v| {
            s.params.blur_sigma = float(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.params.blur_sigma),
    },
    Key {
        name: "fov",
        env: "CONTRASTXR_NO_FOV",
        env_negated: true,
        kind: Kind::Bool,
        option: Some(("--no-fov", "")),
        doc: "map display to camera coordinates (false: camera_uv = display_uv, no registration)",
        set: |s, v| {
            s.params.fov = boolean(v)?;
            Ok(())
        },
        get: |s| Value::Bool(s.params.fov),
    },
    Key {
        name: "fov_scale",
        env: "CONTRASTXR_FOV_SCALE",
        env_negated: false,
        kind: Kind::Pair,
        option: Some(("--fov-scale", "X,Y")),
        doc: "manual mapping camera_uv = fov_scale * display_uv + fov_offset, for both eyes; other than the default (or fov_offset other than its default), it overrides the camera profile",
        set: |s, v| {
            s.params.fov_scale = pair(v)?;
            Ok(())
        },
        get: |s| Value::Pair(s.params.fov_scale),
    },
    Key {
        name: "fov_offset",
        env: "CONTRASTXR_FOV_OFFSET",
        env_negated: false,
        kind: Kind::Pair,
        option: Some(("--fov-offset", "X,Y")),
        doc: "see fov_scale",
        set: |s, v| {
            s.params.fov_offset = pair(v)?;
            Ok(())
        },
        get: |s| Value::Pair(s.params.fov_offset),
    },
    Key {
        name: "camera_fov",
        env: "CONTRASTXR_CAMERA_FOV",
        env_negated: false,
        kind: Kind::Pair,
        option: None,
        doc: "camera profile: the camera's full field of view [horizontal, vertical] in degrees ([0, 0] = not given)",
        set: set_camera_fov,
        get: |s| Value::Pair(s.registration.camera_fov),
    },
    Key {
        name: "camera_intrinsics",
        env: "CONTRASTXR_CAMERA_INTRINSICS",
        env_negated: false,
        kind: Kind::Numbers(6),
        option: None,
        doc: "camera profile: [fx, fy, cx, cy, width, height] in pixels as OpenCV calibrates them (all 0 = not given; used instead of camera_fov)",
        set: set_camera_intrinsics,
        get: |s| Value::Numbers(s.registration.camera_intrinsics.to_vec()),
    },
    Key {
        name: "camera_position",
        env: "CONTRASTXR_CAMERA_POSITION",
        env_negated: false,
        kind: Kind::Numbers(3),
        option: None,
        doc: "camera profile: [x, y, z] metres from the point between the eyes (+x right, +y up, -z forward)",
        set: |s, v| {
            s.registration.camera_position = numbers(v)?;
            Ok(())
        },
        get: |s| Value::Numbers(s.registration.camera_position.to_vec()),
    },
    Key {
        name: "camera_rotation",
        env: "CONTRASTXR_CAMERA_ROTATION",
        env_negated: false,
        kind: Kind::Numbers(3),
        option: None,
        doc: "camera profile: [pitch, yaw, roll] degrees relative to the head (pitch > 0 tilts it up, yaw > 0 turns it left)",
        set: |s, v| {
            s.registration.camera_rotation = numbers(v)?;
            Ok(())
        },
        get: |s| Value::Numbers(s.registration.camera_rotation.to_vec()),
    },
    Key {
        name: "scene_distance",
        env: "CONTRASTXR_SCENE_DISTANCE",
        env_negated: false,
        kind: Kind::Float,
        option: None,
        doc: "camera profile: the distance in metres at which camera and eyes line up exactly",
        set: set_scene_distance,
        get: |s| Value::Float(s.registration.scene_distance),
    },
    Key {
        name: "motion_compensation",
        env: "CONTRASTXR_MOTION_COMPENSATION",
        env_negated: false,
        kind: Kind::Bool,
        option: None,
        doc: "map each view from the camera at the frame's capture time to the eye at display time (false: head-fixed)",
        set: |s, v| {
            s.motion.compensation = boolean(v)?;
            Ok(())
        },
        get: |s| Value::Bool(s.motion.compensation),
    },
    Key {
        name: "camera_latency_ms",
        env: "CONTRASTXR_CAMERA_LATENCY_MS",
        env_negated: false,
        kind: Kind::Float,
        option: None,
        doc: "milliseconds by which the camera's frames are older than their timestamps say",
        set: |s, v| {
            s.motion.camera_latency_ms = non_negative(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.motion.camera_latency_ms),
    },
    Key {
        name: "world_latency_ms",
        env: "CONTRASTXR_WORLD_LATENCY_MS",
        env_negated: false,
        kind: Kind::Float,
        option: None,
        doc: "background world: milliseconds between a simulated frame's capture and its delivery",
        set: |s, v| {
            s.camera.world_latency_ms = non_negative(v)?;
            Ok(())
        },
        get: |s| Value::Float(s.camera.world_latency_ms),
    },
    Key {
        name: "left_eye_offset",
        env: "CONTRASTXR_LEFT_EYE_OFFSET",
        env_negated: false,
        kind: Kind::Pair,
        option: None,
        doc: "left eye's correction: move the background picture by [x, y] (fractions of the view, +y down); written by contrastxr calibrate",
        set: |s, v| {
            s.registration.eye_offset[0] = pair(v)?;
            Ok(())
        },
        get: |s| Value::Pair(s.registration.eye_offset[0]),
    },
    Key {
        name: "left_eye_scale",
        env: "CONTRASTXR_LEFT_EYE_SCALE",
        env_negated: false,
        kind: Kind::Pair,
        option: None,
        doc: "left eye's correction: scale the background picture by [x, y] about the view's centre",
        set: |s, v| {
            s.registration.eye_scale[0] = eye_scale(v)?;
            Ok(())
        },
        get: |s| Value::Pair(s.registration.eye_scale[0]),
    },
    Key {
        name: "right_eye_offset",
        env: "CONTRASTXR_RIGHT_EYE_OFFSET",
        env_negated: false,
        kind: Kind::Pair,
        option: None,
        doc: "right eye's correction, as left_eye_offset",
        set: |s, v| {
            s.registration.eye_offset[1] = pair(v)?;
            Ok(())
        },
        get: |s| Value::Pair(s.registration.eye_offset[1]),
    },
    Key {
        name: "right_eye_scale",
        env: "CONTRASTXR_RIGHT_EYE_SCALE",
        env_negated: false,
        kind: Kind::Pair,
        option: None,
        doc: "right eye's correction, as left_eye_scale",
        set: |s, v| {
            s.registration.eye_scale[1] = eye_scale(v)?;
            Ok(())
        },
        get: |s| Value::Pair(s.registration.eye_scale[1]),
    },
    Key {
        name: "background",
        env: "CONTRASTXR_BACKGROUND",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "v4l2:auto, v4l2:/dev/videoN, image:PATH, video:PATH, world:PATH or color:#RRGGBB",
        set: set_background,
        get: |s| Value::Text(s.background.clone()),
    },
    Key {
        name: "colour_camera",
        env: "CONTRASTXR_COLOUR_CAMERA",
        env_negated: false,
        kind: Kind::Bool,
        option: None,
        doc: "the headset has a colour camera for the background (false: use image:, video: or color:, or a camera of your own)",
        set: |s, v| {
            s.colour_camera = boolean(v)?;
            Ok(())
        },
        get: |s| Value::Bool(s.colour_camera),
    },
    Key {
        name: "camera_usb_ids",
        env: "CONTRASTXR_CAMERA_USB_IDS",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "the headset's own camera, as comma-separated USB ids VID:PID (as lsusb prints them): v4l2:auto takes it before any other camera, and doctor says whether it is connected; \"\" = none",
        set: |s, v| {
            let Value::Text(text) = v else {
                return Err(format!("{v} is not a string of VID:PID ids"));
            };
            s.camera.usb_ids = UsbId::parse_list(&text)?;
            Ok(())
        },
        get: |s| Value::Text(UsbId::list_text(&s.camera.usb_ids)),
    },
    Key {
        name: "force",
        env: "CONTRASTXR_FORCE",
        env_negated: false,
        kind: Kind::Bool,
        option: None,
        doc: "act on any environment blend mode, not only ADDITIVE",
        set: |s, v| {
            s.force = boolean(v)?;
            Ok(())
        },
        get: |s| Value::Bool(s.force),
    },
    Key {
        name: "environment_blend_mode",
        env: "CONTRASTXR_ENVIRONMENT_BLEND_MODE",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "the display's true blend mode: additive (apps are offered ADDITIVE, and its frames are enhanced, even where the runtime reports only OPAQUE), or \"\" to trust the runtime",
        set: |s, v| {
            s.additive_display = match v {
                Value::Text(t) if t == "additive" => true,
                Value::Text(t) if t.is_empty() => false,
                other => return Err(format!("{other} is not additive or \"\"")),
            };
            Ok(())
        },
        get: |s| Value::Text(if s.additive_display { "additive" } else { "" }.into()),
    },
    Key {
        name: "pipelines",
        env: "CONTRASTXR_PIPELINES",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "background: frames pass through untouched until the shader pipelines are built on the layer's thread; wait: the first frame waits for them (every frame enhanced, as captures and tests that count frames need)",
        set: |s, v| {
            s.wait_for_pipelines = match v {
                Value::Text(t) if t == "background" => false,
                Value::Text(t) if t == "wait" => true,
                other => return Err(format!("{other} is not background or wait")),
            };
            Ok(())
        },
        get: |s| Value::Text(if s.wait_for_pipelines { "wait" } else { "background" }.into()),
    },
    Key {
        name: "quad_layers",
        env: "CONTRASTXR_QUAD_LAYERS",
        env_negated: false,
        kind: Kind::Bool,
        option: None,
        doc: "also enhance quad layers",
        set: |s, v| {
            s.quad_layers = boolean(v)?;
            Ok(())
        },
        get: |s| Value::Bool(s.quad_layers),
    },
    Key {
        name: "in_place",
        env: "CONTRASTXR_IN_PLACE",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "on: enhance the app's images in place (Vulkan: storage usage added to its swapchains; OpenGL: through an image unit), and where the runtime refuses storage (Vulkan) through an image of the layer's own, copied image to image; off: always through a buffer copy of each view; auto: on, except on CPU drivers (lavapipe, llvmpipe), where the buffer copies are cheaper than storage-image access",
        set: |s, v| {
            s.in_place = match v {
                Value::Text(t) => InPlace::parse(&t).ok_or(format!("{t:?} is not auto, on or off"))?,
                other => return Err(format!("{other} is not auto, on or off")),
            };
            Ok(())
        },
        get: |s| Value::Text(s.in_place.name().into()),
    },
    Key {
        name: "copy_back",
        env: "CONTRASTXR_COPY_BACK",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "Vulkan, for a view enhanced through an image of the layer's own (the runtime refused storage usage, as on sRGB swapchains): region: the whole region copied back into the app's image; tiles: only the tiles the enhancement listed drawn back (a render pass), the rest of the image left as the app rendered it",
        set: |s, v| {
            s.copy_back = match v {
                Value::Text(t) => CopyBack::parse(&t).ok_or(format!("{t:?} is not region or tiles"))?,
                other => return Err(format!("{other} is not region or tiles")),
            };
            Ok(())
        },
        get: |s| Value::Text(s.copy_back.name().into()),
    },
    Key {
        name: "copy_in",
        env: "CONTRASTXR_COPY_IN",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "Vulkan, for a view enhanced through an image of the layer's own: region: the region copied into it first; sampled: on 8-bit sRGB swapchains (sampled usage added to them), the region read through a sampled view of the app's image instead, and only the tiles the enhancement listed drawn back, whatever copy_back says; auto: sampled on a GPU, region on CPU drivers (lavapipe, llvmpipe), where a sampled texel costs more than the copy it saves",
        set: |s, v| {
            s.copy_in = match v {
                Value::Text(t) => CopyIn::parse(&t).ok_or(format!("{t:?} is not auto, region or sampled"))?,
                other => return Err(format!("{other} is not auto, region or sampled")),
            };
            Ok(())
        },
        get: |s| Value::Text(s.copy_in.name().into()),
    },
    Key {
        name: "capture_dir",
        env: "CONTRASTXR_CAPTURE_DIR",
        env_negated: false,
        kind: Kind::Text,
        option: None,
        doc: "write display/output/background PNGs of processed frames here (\"\" = off)",
        set: set_capture_dir,
        get: |s| {
            Value::Text(
                s.capture_dir
                    .as_ref()
                    .map_or(String::new(), |d| d.display().to_string()),
            )
        },
    },
    Key {
        name: "capture_frames",
        env: "CONTRASTXR_CAPTURE_FRAMES",
        env_negated: false,
        kind: Kind::Count,
        option: None,
        doc: "how many processed frames to capture",
        set: |s, v| {
            s.capture_frames = count(v)?;
            Ok(())
        },
        get: |s| Value::Count(s.capture_frames),
    },
    Key {
        name: "capture_skip",
        env: "CONTRASTXR_CAPTURE_SKIP",
        env_negated: false,
        kind: Kind::Count,
        option: None,
        doc: "processed frames to let pass before capturing",
        set: |s, v| {
            s.capture_skip = count(v)?;
            Ok(())
        },
        get: |s| Value::Count(s.capture_skip),
    },
    Key {
        name: "indicator",
        env: "CONTRASTXR_INDICATOR",
        env_negated: false,
        kind: Kind::Bool,
        option: None,
        doc: "show the mode and lambda_e in the eye image for a few seconds after start and after each change",
        set: |s, v| {
            s.indicator = boolean(v)?;
            Ok(())
        },
        get: |s| Value::Bool(s.indicator),
    },
    Key {
        name: "indicator_seconds",
        env: "CONTRASTXR_INDICATOR_SECONDS",
        env_negated: false,
        kind: Kind::Float,
        option: None,
        doc: "how long the indicator shows, in seconds (0 to 60)",
        set: |s, v| {
            let seconds = float(v)?;
            if !(0.0..=60.0).contains(&seconds) {
                return Err(format!("{seconds} is not in [0, 60]"));
            }
            s.indicator_seconds = seconds;
            Ok(())
        },
        get: |s| Value::Float(s.indicator_seconds),
    },
];

pub fn key(name: &str) -> Option<&'static Key> {
    KEYS.iter().find(|k| k.name == name)
}

impl Key {
    /// Sets this key on `settings` if the value is valid for it and leaves the method's
    /// settings valid as a whole; otherwise `settings` is unchanged and the error says why.
    pub fn apply(&self, settings: &mut Settings, value: Value) -> Result<(), String> {
        let mut candidate = settings.clone();
        (self.set)(&mut candidate, value)?;
        candidate.params.validate()?;
        *settings = candidate;
        Ok(())
    }

    pub fn get(&self, settings: &Settings) -> Value {
        (self.get)(settings)
    }

    /// Parses this key's text form (environment variable or command line).
    pub fn parse_text(&self, text: &str) -> Result<Value, String> {
        match (self.kind.from_text(text)?, self.env_negated) {
            (Value::Bool(b), true) => Ok(Value::Bool(!b)),
            (v, _) => Ok(v),
        }
    }

    /// Parses the text form of the value itself (`contrastxr set blur false`), never negated.
    pub fn parse_setting(&self, text: &str) -> Result<Value, String> {
        self.kind.from_text(text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_round_trips_its_default() {
        let defaults = Settings::default();
        for k in KEYS {
            let mut s = defaults.clone();
            k.apply(&mut s, k.get(&defaults))
                .unwrap_or_else(|e| panic!("{}: {e}", k.name));
            assert_eq!(s, defaults, "{}", k.name);
        }
    }

    #[test]
    fn camera_controls_take_auto_or_a_whole_number() {
        let mut s = Settings::default();
        let k = key("camera_exposure").unwrap();
        k.apply(&mut s, Value::Text("8000".into())).unwrap();
        assert_eq!(s.camera.controls.exposure_us, Some(8000));
        k.apply(&mut s, Value::Text("auto".into())).unwrap();
        assert_eq!(s.camera.controls.exposure_us, None);
        assert!(k.apply(&mut s, Value::Text("bright".into())).is_err());
        assert!(k.apply(&mut s, Value::Float(1.5)).is_err());
    }

    #[test]
    fn comparison_modes_set_the_method() {
        let mut s = Settings::default();
        key("mode")
            .unwrap()
            .apply(&mut s, Value::Text("hue-only".into()))
            .unwrap();
        assert_eq!(
            (s.params.mode, s.params.method),
            (ViewMode::Enhance, Method::HueOnly)
        );
        for bad in ["paper", "fancy", ""] {
            assert!(key("mode")
                .unwrap()
                .apply(&mut s, Value::Text(bad.into()))
                .is_err());
        }
    }

    #[test]
    fn invalid_values_leave_settings_unchanged() {
        let mut s = Settings::default();
        let k = key("transmittance").unwrap();
        assert!(k.apply(&mut s, Value::Float(7.0)).is_err());
        assert!(key("blur_size")
            .unwrap()
            .apply(&mut s, Value::Count(4))
            .is_err());
        assert!(key("background")
            .unwrap()
            .apply(&mut s, Value::Text("webcam".into()))
            .is_err());
        assert_eq!(s, Settings::default());
    }

    #[test]
    fn perceptual_settings_read_back_as_written_and_are_range_checked() {
        let mut s = Settings::default();
        let set = |s: &mut Settings, name: &str, text: &str| {
            let k = key(name).unwrap();
            k.apply(s, k.parse_setting(text)?)
        };
        set(&mut s, "target_contrast", "0.07").unwrap();
        set(&mut s, "world_nits", "5000").unwrap();
        set(&mut s, "display_peak_nits", "600").unwrap();
        set(&mut s, "min_luminance", "0.3").unwrap();
        set(&mut s, "frequency", "ensemble").unwrap();
        let p = &s.params.perceptual;
        assert_eq!(
            (
                p.target_contrast,
                p.world_nits,
                p.display_peak_nits,
                p.min_luminance
            ),
            (0.07, 5000.0, 600.0, 0.3)
        );
        assert_eq!(p.frequency, Frequency::Ensemble);
        set(&mut s, "frequency", "4").unwrap();
        assert_eq!(s.params.perceptual.frequency, Frequency::Cpd(4.0));
        assert_eq!(key("frequency").unwrap().get(&s), Value::Text("4".into()));
        let before = s.clone();
        for (name, text, says) in [
            ("display_peak_nits", "0", "display_peak_nits must be > 0"),
            ("world_nits", "-1", "world_nits must be >= 0"),
            ("target_contrast", "0", "target_contrast must be in (0, 1]"),
            (
                "target_contrast",
                "1.5",
                "target_contrast must be in (0, 1]",
            ),
            (
                "min_luminance",
                "0.01",
                "min_luminance must be in [0.1, 31623]",
            ),
            (
                "frequency",
                "-2",
                "frequency must be blur, ensemble or a number",
            ),
            ("frequency", "sharp", "is not blur, ensemble or a number"),
        ] {
            let e = set(&mut s, name, text).unwrap_err();
            assert!(e.contains(says), "{name} = {text}: {e}");
        }
        assert_eq!(s, before, "a refused value leaves the settings unchanged");
    }

    #[test]
    fn camera_sizes_are_bounded() {
        let mut s = Settings::default();
        for name in ["camera_width", "camera_height"] {
            let k = key(name).unwrap();
            // The doc states the bound the setter checks.
            assert!(
                k.doc.contains(&format!("at most {MAX_CAMERA_SIDE}")),
                "{name}"
            );
            k.apply(&mut s, Value::Count(u64::from(MAX_CAMERA_SIDE)))
                .unwrap();
            for n in [u64::from(MAX_CAMERA_SIDE) + 1, 100_000, 1 << 32] {
                let e = k.apply(&mut s, Value::Count(n)).unwrap_err();
                assert_eq!(e, format!("{n} is not in [0, 8192]"), "{name}");
            }
        }
        assert_eq!((s.camera.width, s.camera.height), (8192, 8192));
    }

    #[test]
    fn no_switches_are_negated() {
        let k = key("blur").unwrap();
        assert_eq!(k.parse_text("1"), Ok(Value::Bool(false)));
        assert_eq!(k.parse_setting("false"), Ok(Value::Bool(false)));
    }
}
