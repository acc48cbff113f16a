//! Which shipped device profile matched the headset the last app ran on.

use super::finding::Finding;
use contrastxr::config::{file, shipped, Env};

/// The shipped profiles' file and its `[device."..."]` table names.
fn shipped_tables(env: &Env) -> Option<(String, Vec<String>)> {
    let path = shipped::find(env)?;
    let text = std::fs::read_to_string(&path).ok()?;
    let parsed = file::parse(&text).ok()?;
    let names = parsed.devices.into_iter().map(|(n, _)| n).collect();
    Some((path.display().to_string(), names))
}

pub fn device_profile(env: &Env, system: Option<&str>) -> Finding {
    const NAME: &str = "device-profile";
    let Some((path, names)) = shipped_tables(env) else {
        return Finding::ok(
            NAME,
            format!(
                "no shipped device profiles found ({}, beside the layer library, or \
                 $CONTRASTXR_DEVICES)",
                shipped::PACKAGED_PATH
            ),
        );
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
    if names.iter().any(|n| n == system) {
        Finding::ok(
            NAME,
            format!(
                "the headset {system:?} matched the shipped profile [device.{system:?}] in {path}"
            ),
        )
    } else {
        Finding::ok(
            NAME,
            format!("no shipped profile for {system:?} in {path}: your own [device.{system:?}] table describes it"),
        )
    }
}
