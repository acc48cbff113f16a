//! Which shipped device profile matched the headset the last app ran on, and whether the camera
//! its settings name by USB id (`camera_usb_ids`) is connected.

use super::finding::Finding;
use contrastxr::camera::v4l2::{device_dir, usb};
use contrastxr::config::{file, load_for, shipped, Env, Who, KEYS};

const NAME: &str = "device-profile";

/// The shipped profiles' file and its `[device."..."]` table names.
fn shipped_tables(env: &Env) -> Option<(String, Vec<String>)> {
    let path = shipped::find(env)?;
    let text = std::fs::read_to_string(&path).ok()?;
    let parsed = file::parse(&text).ok()?;
    let names = parsed.devices.into_iter().map(|(n, _)| n).collect();
    Some((path.display().to_string(), names))
}

/// The headset's camera by USB id, where its settings name one: whether it is connected.
fn camera(env: &Env, system: &str, matched: String) -> Finding {
    let r = load_for(
        Who {
            app: "",
            device: Some(system),
        },
        env,
    );
    let ids = &r.settings.camera.usb_ids;
    if ids.is_empty() {
        return Finding::ok(NAME, matched);
    }
    let index = KEYS.iter().position(|k| k.name == "camera_usb_ids");
    let origin = index.map_or(String::new(), |i| format!(" ({})", r.origins[i]));
    let named = format!("camera_usb_ids = {:?}{origin}", usb::UsbId::list_text(ids));
    let here: Vec<String> = usb::usb_video_nodes(&usb::sysfs_root())
        .into_iter()
        .filter(|(_, id)| ids.contains(id))
        .map(|(node, id)| format!("{} ({id})", device_dir().join(node).display()))
        .collect();
    if here.is_empty() {
        Finding::warn(
            NAME,
            format!("{matched}; its camera, {named}, is not connected"),
            format!(
                "connect the headset's camera (`lsusb` lists it as {}); until then v4l2:auto \
                 takes another camera, if any",
                usb::UsbId::list_text(ids).replace(',', " or ")
            ),
        )
    } else {
        let detail = format!(
            "{matched}; its camera, {named}, is connected: {}",
            here.join(", ")
        );
        Finding::ok(NAME, detail)
    }
}

pub fn device_profile(env: &Env, system: Option<&str>) -> Finding {
    let Some((path, names)) = shipped_tables(env) else {
        let detail = format!(
            "no shipped device profiles found ({}, beside the layer library, or \
             $CONTRASTXR_DEVICES)",
            shipped::PACKAGED_PATH
        );
        return match system {
            Some(system) => camera(env, system, detail),
            None => Finding::ok(NAME, detail),
        };
    };
    let Some(system) = system else {
        return Finding::ok(
            NAME,
            format!(
                "{path}: {} profiles; no app has named its headset yet",
                names.len()
            ),
        );
    };
    let matched = if names.iter().any(|n| n == system) {
        format!("the headset {system:?} matched the shipped profile [device.{system:?}] in {path}")
    } else {
        format!(
            "no shipped profile for {system:?} in {path}: your own [device.{system:?}] table \
             describes it"
        )
    };
    camera(env, system, matched)
}
