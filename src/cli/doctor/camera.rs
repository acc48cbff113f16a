//! The background source the layer would open (the V4L2 cameras and their formats, as
//! `contrastxr camera list` shows them) and whether the camera's profile is described.

use super::finding::{doc, tool, Finding, Status};
use contrastxr::camera::v4l2::{self, Mode};
use contrastxr::camera::{parse_source, SourceSpec};
use contrastxr::config::{self, Env, Who};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A V4L2 capture node with its formats.
struct Camera {
    path: PathBuf,
    card: String,
    /// `FOURCC up to WxH`, usable formats first; empty when none can be read.
    formats: Vec<String>,
    usable: bool,
}

fn formats(modes: &[Mode]) -> (Vec<String>, bool) {
    let mut largest: BTreeMap<(bool, [u8; 4]), (u32, u32)> = BTreeMap::new();
    for m in modes {
        let e = largest.entry((m.format.is_none(), m.fourcc)).or_default();
        if m.width * m.height > e.0 * e.1 {
            *e = (m.width, m.height);
        }
    }
    let usable = modes.iter().any(|m| m.format.is_some());
    let list = largest
        .iter()
        .map(|((unusable, fourcc), (w, h))| {
            let note = if *unusable { " (not usable)" } else { "" };
            format!("{} up to {w}x{h}{note}", String::from_utf8_lossy(fourcc))
        })
        .collect();
    (list, usable)
}

/// The capture nodes of `dir`, as `camera list` finds them.
fn cameras(dir: &Path) -> Vec<Camera> {
    v4l2::device_nodes(dir)
        .iter()
        .filter_map(|path| {
            let (device, info) = v4l2::probe(path).ok()?;
            if !info.capture {
                return None;
            }
            let (formats, usable) = v4l2::modes(&device)
                .map(|m| formats(&m))
                .unwrap_or_default();
            Some(Camera {
                path: path.clone(),
                card: info.card,
                formats,
                usable,
            })
        })
        .collect()
}

fn describe(c: &Camera) -> String {
    format!(
        "{} \"{}\": {}",
        c.path.display(),
        c.card,
        if c.formats.is_empty() {
            "no formats listed".into()
        } else {
            c.formats.join(", ")
        }
    )
}

const NAME: &str = "camera";
/// How to see which camera looks at the world.
fn list() -> String {
    format!(
        "`{0} camera list` shows the cameras, `{0} camera test /dev/videoN -o DIR` saves frames \
         to see which one looks at the world",
        tool()
    )
}

fn v4l2_finding(spec: &str, wanted: Option<&Path>) -> Finding {
    let list = list();
    let dir = v4l2::device_dir();
    let found = cameras(&dir);
    let chosen = match wanted {
        Some(p) => found.iter().find(|c| c.path == p),
        None => found.first(),
    };
    let Some(c) = chosen else {
        let what = wanted.map_or(
            format!("no V4L2 capture device in {}", dir.display()),
            |p| format!("{} is not a V4L2 capture device here", p.display()),
        );
        return Finding::problem(
            NAME,
            format!("background = \"{spec}\", but {what}: the layer passes frames through"),
            format!(
                "connect the headset's camera and `{0} set background v4l2:/dev/videoN` ({list}); \
                 without a camera, `{0} set background image:PATH` (or color:#RRGGBB)",
                tool()
            ),
        );
    };
    if !c.usable {
        return Finding::problem(
            NAME,
            format!(
                "background = \"{spec}\" opens {}, which offers no usable format",
                describe(c)
            ),
            format!("choose another camera ({list})"),
        );
    }
    let others: Vec<String> = found
        .iter()
        .filter(|o| o.path != c.path)
        .map(|o| o.path.display().to_string())
        .collect();
    let detail = format!("background = \"{spec}\" opens {}", describe(c));
    if wanted.is_none() && !others.is_empty() {
        return Finding::warn(
            NAME,
            format!("{detail}; also here: {}", others.join(", ")),
            format!(
                "v4l2:auto took one of several cameras: name the headset's world camera, `{} \
                 set background v4l2:/dev/videoN` ({list}), or list its USB id first in \
                 camera_usb_ids (`lsusb` shows it as VID:PID)",
                tool()
            ),
        );
    }
    Finding::ok(NAME, detail)
}

/// A `v4l2:` background on a headset whose profile says it has no colour camera: with no
/// camera of the user's own connected, the fix is another kind of background.
fn without_colour_camera(spec: &str, found: Finding) -> Finding {
    if found.status != Status::Problem {
        return found;
    }
    Finding::warn(
        NAME,
        format!(
            "background = \"{spec}\", but the headset's profile says it has no colour camera \
             (colour_camera = false) and no camera of your own is connected"
        ),
        format!(
            "`{0} set background image:PATH` (or video:PATH, or color:#RRGGBB: a photo or a \
             colour like the place you wear it in); or connect a USB camera, `{0} set \
             colour_camera true` and describe it (camera_fov)",
            tool()
        ),
    )
}

/// The background source the layer would open with these settings (`colour_camera`: whether
/// the headset has a colour camera of its own).
pub fn camera(spec: &str, colour_camera: bool) -> Finding {
    let v4l2 = |wanted: Option<&Path>| match colour_camera {
        true => v4l2_finding(spec, wanted),
        false => without_colour_camera(spec, v4l2_finding(spec, wanted)),
    };
    match parse_source(spec) {
        Err(e) => Finding::problem(NAME, e, format!("`{} set background SOURCE`, SOURCE one of v4l2:auto, v4l2:/dev/videoN, image:PATH, video:PATH, world:PATH, color:#RRGGBB", tool())),
        Ok(SourceSpec::V4l2Auto) => v4l2(None),
        Ok(SourceSpec::V4l2Device(p)) => v4l2(Some(&p)),
        Ok(SourceSpec::Image(p) | SourceSpec::Video(p) | SourceSpec::World(p)) if !p.exists() => Finding::problem(
            NAME,
            format!("background = \"{spec}\", but {} does not exist", p.display()),
            format!(
                "point the background at a file that exists: `{} set background {}`",
                tool(),
                spec.split_once(':').map_or("image", |(kind, _)| kind).to_string() + ":PATH"
            ),
        ),
        Ok(SourceSpec::Image(_) | SourceSpec::Video(_)) => Finding::ok(
            NAME,
            format!("background = \"{spec}\": a file stands in for the camera"),
        ),
        Ok(SourceSpec::World(_)) => Finding::ok(
            NAME,
            format!("background = \"{spec}\": a simulated camera in a panorama stands in for the camera"),
        ),
        Ok(SourceSpec::Color(_)) => Finding::ok(
            NAME,
            format!("background = \"{spec}\": a flat colour stands in for the camera"),
        ),
    }
}

/// `[device."NAME"]` tables of the config file.
fn device_tables(env: &Env) -> Vec<String> {
    let Some(path) = config::path::find(env) else {
        return Vec::new();
    };
    let text = contrastxr::user_file::read_text(&path).unwrap_or_default();
    config::file::parse(&text)
        .map(|f| f.devices.into_iter().map(|(name, _)| name).collect())
        .unwrap_or_default()
}

/// Whether the settings for `device` (None: the file's top level) place the background: a
/// camera profile, or a manual mapping other than the default.
fn placed(env: &Env, device: Option<&str>) -> Option<&'static str> {
    let s = config::load_for(Who { app: "", device }, env).settings;
    if s.registration.profile().is_some() {
        Some("a camera profile")
    } else if s.manual_mapping_set() {
        Some("a manual fov_scale/fov_offset mapping")
    } else {
        None
    }
}

/// Whether the camera's profile is described, for the headset the last app ran on when the
/// log names it.
pub fn profile(env: &Env, system: Option<&str>) -> Finding {
    const NAME: &str = "camera-profile";
    let tables = device_tables(env);
    let mut places: Vec<Option<String>> = vec![None];
    match system {
        Some(s) => places.push(Some(s.to_string())),
        None => places.extend(tables.iter().cloned().map(Some)),
    }
    for place in &places {
        if let Some(what) = placed(env, place.as_deref()) {
            let table = place.as_ref().map_or("the config's top level".into(), |d| {
                format!("[device.{d:?}]")
            });
            return Finding::ok(NAME, format!("{what} in {table} places the background"));
        }
    }
    let device = system.map_or("<systemName>".to_string(), str::to_string);
    let tool = tool();
    let whose = system.map_or(String::new(), |s| format!(" for {s:?}"));
    Finding::warn(
        NAME,
        format!(
            "no camera profile{whose}: the background is placed with the default mapping (the \
             paper's HoloLens values), which will not line up with what you see"
        ),
        format!(
            "describe the camera in [device.{device:?}] ({}; the name is in `{tool} log` once \
             an app ran), then run `{tool} calibrate --device {device:?}` wearing the headset",
            doc("calibration.md")
        ),
    )
}
