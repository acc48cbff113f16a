//! Which shipped device profile matched the headset the last app ran on (or where profiles were
//! looked for, when none were found), and whether the camera the settings name by USB id
//! (`camera_usb_ids`) is connected, whether or not an app has run.

use super::finding::{tool, tool_as_root, Finding, Status};
use contrastxr::camera::usb_id::UsbId;
use contrastxr::camera::v4l2::{device_dir, usb};
use contrastxr::config::{file, load_for, shipped, Env, Who, KEYS};

const NAME: &str = "device-profile";

/// The shipped profiles' file and its `[device."..."]` table names.
fn shipped_tables(env: &Env) -> Option<(String, Vec<String>)> {
    let path = shipped::find(env)?;
    let text = contrastxr::user_file::read_text(&path).ok()?;
    let parsed = file::parse(&text).ok()?;
    let names = parsed.devices.into_iter().map(|(n, _)| n).collect();
    Some((path.display().to_string(), names))
}

/// The headset's camera by USB id, where the settings (for `system`, when an app named it) name
/// one: whether it is connected, added to `found`.
fn with_camera(env: &Env, system: Option<&str>, found: Finding) -> Finding {
    let r = load_for(
        Who {
            app: "",
            device: system,
        },
        env,
    );
    let ids = &r.settings.camera.usb_ids;
    if ids.is_empty() {
        return found;
    }
    let index = KEYS.iter().position(|k| k.name == "camera_usb_ids");
    let origin = index.map_or(String::new(), |i| format!(" ({})", r.origins[i]));
    let named = format!("camera_usb_ids = {:?}{origin}", UsbId::list_text(ids));
    let here: Vec<String> = usb::usb_video_nodes(&usb::sysfs_root())
        .into_iter()
        .filter(|(_, id)| ids.contains(id))
        .map(|(node, id)| format!("{} ({id})", device_dir().join(node).display()))
        .collect();
    if !here.is_empty() {
        let detail = format!(
            "{}; its camera, {named}, is connected: {}",
            found.detail,
            here.join(", ")
        );
        return Finding { detail, ..found };
    }
    let fix = format!(
        "connect the headset's camera (`lsusb` lists it as {}); until then v4l2:auto takes \
         another camera, if any",
        UsbId::list_text(ids).replace(',', " or ")
    );
    Finding {
        status: found.status.max(Status::Warn),
        detail: format!("{}; its camera, {named}, is not connected", found.detail),
        fix: Some(found.fix.map_or(fix.clone(), |f| format!("{f}; {fix}"))),
        ..found
    }
}

/// No profiles file: where it was looked for.
fn none_found(env: &Env) -> Finding {
    let detail = match env.get("CONTRASTXR_DEVICES").filter(|p| !p.is_empty()) {
        Some(p) => {
            format!("no device profiles found: CONTRASTXR_DEVICES names {p}, which cannot be read")
        }
        None => {
            let searched: Vec<String> = shipped::searched(env)
                .iter()
                .map(|p| p.display().to_string())
                .collect();
            format!(
                "no device profiles found (searched {})",
                searched.join(", ")
            )
        }
    };
    Finding::warn(
        NAME,
        detail,
        format!(
            "`{} install --user` (or `{} install --system`) writes them beside the layer \
             library; the Debian package installs {}; or set CONTRASTXR_DEVICES to a \
             profiles file",
            tool(),
            tool_as_root(),
            shipped::PACKAGED_PATH
        ),
    )
}

pub fn device_profile(env: &Env, system: Option<&str>) -> Finding {
    let found = match (shipped_tables(env), system) {
        (None, _) => none_found(env),
        (Some((path, names)), None) => Finding::ok(
            NAME,
            format!(
                "{path}: {} profiles; no app has named its headset yet",
                names.len()
            ),
        ),
        (Some((path, names)), Some(system)) if names.iter().any(|n| n == system) => Finding::ok(
            NAME,
            format!(
                "the headset {system:?} matched the shipped profile [device.{system:?}] in {path}"
            ),
        ),
        (Some((path, _)), Some(system)) => Finding::ok(
            NAME,
            format!(
                "no shipped profile for {system:?} in {path}: your own [device.{system:?}] \
                 table describes it"
            ),
        ),
    };
    with_camera(env, system, found)
}
