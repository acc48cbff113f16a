//! The headset's own settings: at xrCreateSession the layer asks the next layer for the
//! system's name (XrSystemProperties.systemName) and applies the config's
//! `[device."<systemName>"]` table, between the file's top level and its `[app."..."]` table.
//! Settings are first resolved at xrCreateInstance, before the app has chosen a system.

use super::dispatch::NextFns;
use super::ffi::c_str;
use super::live_settings::{self, Settings};
use super::log;
use super::state::InstanceState;
use crate::config::{Resolved, KEYS};
use openxr_sys as xr;
use std::sync::Arc;

/// The system's name, or None (logged once) if the runtime does not say.
pub(super) fn system_name(
    next: &NextFns,
    instance: xr::Instance,
    system: xr::SystemId,
) -> Option<String> {
    // SAFETY: an all-zero XrSystemProperties is a valid out struct once its type is set.
    let mut props: xr::SystemProperties = unsafe { std::mem::zeroed() };
    props.ty = xr::SystemProperties::TYPE;
    // SAFETY: the next layer's function, with the app's instance and system and our out struct.
    let result = unsafe { (next.get_system_properties)(instance, system, &mut props) };
    if result != xr::Result::SUCCESS {
        log::once(
            "system-name",
            &format!(
                "xrGetSystemProperties failed ({result:?}): no [device.\"...\"] table applies"
            ),
        );
        return None;
    }
    // The runtime writes a NUL-terminated name; make sure of the terminator anyway.
    props.system_name[xr::MAX_SYSTEM_NAME_SIZE - 1] = 0;
    // SAFETY: a NUL-terminated array that lives until the end of this function.
    unsafe { c_str(props.system_name.as_ptr()) }.map(str::to_string)
}

/// Logs what the device table changed: each changed value with its origin, and its problems.
fn log_device(name: &str, before: &Settings, r: &Resolved) {
    log::info(&format!(
        "system {name:?}: settings in a [device.{name:?}] config table apply to it"
    ));
    for (i, k) in KEYS.iter().enumerate() {
        if k.get(before) != k.get(&r.settings) {
            log::info(&format!("setting {}", r.line(i)));
        }
    }
    for p in &r.problems {
        log::info(p);
    }
}

/// The settings for a new session on `system`: the instance's, with the device's table.
pub fn settings_on(
    instance: xr::Instance,
    inst: &InstanceState,
    system: Option<xr::SystemId>,
) -> Arc<Settings> {
    let live = live_settings::live(instance.into_raw());
    let (Some(live), Some(system)) = (live, system) else {
        return inst.settings.clone();
    };
    let Some(name) = system_name(&inst.next, instance, system) else {
        return live.current();
    };
    let before = live.current();
    if let Some(r) = live.set_device(&name) {
        log_device(&name, &before, &r);
    }
    live.current()
}
