//! Additive presentation for see-through displays whose runtime reports another blend mode
//! (`environment_blend_mode = "additive"`): the app is offered ADDITIVE first in
//! xrEnumerateEnvironmentBlendModes, so it renders black where it has no content, and its
//! ADDITIVE frames reach the runtime in a mode the runtime supports (OPAQUE where it has it:
//! black there is no light on an additive display). Everything else is the runtime's answer.

use super::dispatch::NextFns;
use super::ffi::{guard, LayerError};
use super::headset_settings;
use super::{live_settings, log, state};
use openxr_sys as xr;
use std::collections::HashMap;
use std::sync::{Mutex, MutexGuard, OnceLock};

const ADDITIVE: xr::EnvironmentBlendMode = xr::EnvironmentBlendMode::ADDITIVE;

/// Per session: its instance and system, and (once an ADDITIVE frame came) the mode the
/// runtime is handed instead (None: the runtime has ADDITIVE itself).
struct Presented {
    instance: xr::Instance,
    system: xr::SystemId,
    replacement: Option<Option<xr::EnvironmentBlendMode>>,
}

fn sessions() -> MutexGuard<'static, HashMap<u64, Presented>> {
    static SESSIONS: OnceLock<Mutex<HashMap<u64, Presented>>> = OnceLock::new();
    let m = SESSIONS.get_or_init(Default::default);
    // Only map operations happen under this lock: a panic cannot leave it inconsistent.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Remembers a new session's system (its blend modes are the system's).
pub fn remember(session: xr::Session, instance: xr::Instance, system: xr::SystemId) {
    let p = Presented {
        instance,
        system,
        replacement: None,
    };
    sessions().insert(session.into_raw(), p);
}

pub fn forget(session: xr::Session) {
    sessions().remove(&session.into_raw());
}

/// The runtime's blend modes for a system and view configuration, or its error.
fn runtime_modes(
    next: &NextFns,
    instance: xr::Instance,
    system: xr::SystemId,
    view: xr::ViewConfigurationType,
) -> Result<Vec<xr::EnvironmentBlendMode>, xr::Result> {
    let mut n = 0u32;
    // SAFETY: the next layer's function with a count query (capacity 0, no array).
    let r = unsafe {
        (next.enumerate_environment_blend_modes)(
            instance,
            system,
            view,
            0,
            &mut n,
            std::ptr::null_mut(),
        )
    };
    if r != xr::Result::SUCCESS {
        return Err(r);
    }
    let mut modes = vec![xr::EnvironmentBlendMode::OPAQUE; n as usize];
    // SAFETY: the array holds n modes, as its capacity says.
    let r = unsafe {
        (next.enumerate_environment_blend_modes)(
            instance,
            system,
            view,
            n,
            &mut n,
            modes.as_mut_ptr(),
        )
    };
    if r != xr::Result::SUCCESS {
        return Err(r);
    }
    modes.truncate(n as usize);
    Ok(modes)
}

/// Whether `session`'s frames may come ADDITIVE: the settings make its display additive, or
/// the runtime offers ADDITIVE for a stereo or mono view (true for a session unknown here).
pub fn additive_possible(session: xr::Session, next: &NextFns) -> bool {
    let known = sessions()
        .get(&session.into_raw())
        .map(|p| (p.instance, p.system));
    let Some((instance, system)) = known else {
        return true;
    };
    if additive_display(instance, next, system) {
        return true;
    }
    [
        xr::ViewConfigurationType::PRIMARY_STEREO,
        xr::ViewConfigurationType::PRIMARY_MONO,
    ]
    .into_iter()
    .any(|view| runtime_modes(next, instance, system, view).is_ok_and(|m| m.contains(&ADDITIVE)))
}

/// Whether the settings for `system` (its `[device."..."]` table applied) say the display is
/// additive.
fn additive_display(instance: xr::Instance, next: &NextFns, system: xr::SystemId) -> bool {
    let Some(live) = live_settings::live(instance.into_raw()) else {
        return false;
    };
    match headset_settings::system_name(next, instance, system) {
        Some(name) => live.on_device(&name).additive_display,
        None => live.current().additive_display,
    }
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed.
pub unsafe extern "system" fn enumerate_environment_blend_modes(
    instance: xr::Instance,
    system: xr::SystemId,
    view: xr::ViewConfigurationType,
    capacity: u32,
    count: *mut u32,
    modes: *mut xr::EnvironmentBlendMode,
) -> xr::Result {
    guard(
        "xrEnumerateEnvironmentBlendModes",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let inst = state::instance(instance).ok_or(LayerError::UnknownHandle("XrInstance"))?;
            let next = inst.next;
            // SAFETY: forwarding the app's own arguments.
            let forward = || unsafe {
                (next.enumerate_environment_blend_modes)(
                    instance, system, view, capacity, count, modes,
                )
            };
            // Invalid arguments, and displays the runtime describes rightly: the runtime answers.
            if count.is_null() || (capacity > 0 && modes.is_null()) {
                return Ok(forward());
            }
            if !additive_display(instance, &next, system) {
                return Ok(forward());
            }
            let Ok(runtime) = runtime_modes(&next, instance, system, view) else {
                return Ok(forward());
            };
            if runtime.contains(&ADDITIVE) {
                return Ok(forward());
            }
            let ours: Vec<_> = std::iter::once(ADDITIVE).chain(runtime).collect();
            // The two-call idiom, as the runtime keeps it: the count always, then the array
            // if it fits.
            // SAFETY: count is the app's non-null out pointer.
            unsafe { *count = ours.len() as u32 };
            if capacity == 0 {
                return Ok(xr::Result::SUCCESS);
            }
            if (capacity as usize) < ours.len() {
                return Ok(xr::Result::ERROR_SIZE_INSUFFICIENT);
            }
            // SAFETY: modes holds capacity >= ours.len() entries (the app's array).
            unsafe { std::ptr::copy_nonoverlapping(ours.as_ptr(), modes, ours.len()) };
            Ok(xr::Result::SUCCESS)
        },
    )
}

/// The mode the runtime is handed for an app's ADDITIVE frame: OPAQUE where it has it, else
/// its first; None where the runtime has ADDITIVE (or says nothing).
fn replacement_for(
    next: &NextFns,
    instance: xr::Instance,
    system: xr::SystemId,
) -> Option<xr::EnvironmentBlendMode> {
    let views = [
        xr::ViewConfigurationType::PRIMARY_STEREO,
        xr::ViewConfigurationType::PRIMARY_MONO,
    ];
    let runtime = views
        .iter()
        .find_map(|v| runtime_modes(next, instance, system, *v).ok())?;
    if runtime.contains(&ADDITIVE) {
        return None;
    }
    let mode = if runtime.contains(&xr::EnvironmentBlendMode::OPAQUE) {
        xr::EnvironmentBlendMode::OPAQUE
    } else {
        *runtime.first()?
    };
    log::info(&format!(
        "the app presents ADDITIVE frames on an additive display: the runtime is handed {mode:?}"
    ));
    Some(mode)
}

/// The frame end info the runtime gets instead of the app's, if any: an app's ADDITIVE frame
/// on a display set additive whose runtime lacks ADDITIVE.
pub fn for_runtime(
    session: xr::Session,
    next: &NextFns,
    additive: bool,
    info: *const xr::FrameEndInfo,
) -> Option<xr::FrameEndInfo> {
    // SAFETY: the app's frame end info (null is left for the runtime to reject).
    let info = unsafe { info.as_ref() }?;
    if !additive || info.environment_blend_mode != ADDITIVE {
        return None;
    }
    let (instance, system, known) = {
        let all = sessions();
        let p = all.get(&session.into_raw())?;
        (p.instance, p.system, p.replacement)
    };
    // No lock is held while the runtime answers.
    let mode = known.unwrap_or_else(|| {
        let mode = replacement_for(next, instance, system);
        if let Some(p) = sessions().get_mut(&session.into_raw()) {
            p.replacement = Some(mode);
        }
        mode
    })?;
    Some(xr::FrameEndInfo {
        environment_blend_mode: mode,
        ..*info
    })
}
