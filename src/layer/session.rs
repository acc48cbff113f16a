//! Sessions: read the graphics binding at xrCreateSession and set up the session's graphics
//! ([`graphics`]: Vulkan or OpenGL) and background source ([`sources`]); at xrEndFrame enhance the frame's held
//! images ([`end_frame`](mod@end_frame)) and release them before the runtime composes them.
//! At xrCreateSession the system's `[device."..."]` config table applies ([`headset_settings`]).
//! At xrEndFrame a session also takes newer settings from the config watcher (never waiting);
//! a changed background source is reopened on a helper thread while frames pass through.

use super::ffi::{guard, LayerError};
use super::graphics::{self, Bound};
use super::state::{self, lock, SessionState};
use super::{blend, end_frame, headset_settings, log, sources, swapchain};
use openxr_sys as xr;
use std::sync::{Arc, Mutex};

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrCreateSession.
pub unsafe extern "system" fn create_session(
    instance: xr::Instance,
    info: *const xr::SessionCreateInfo,
    session: *mut xr::Session,
) -> xr::Result {
    guard("xrCreateSession", xr::Result::ERROR_RUNTIME_FAILURE, || {
        let inst = state::instance(instance).ok_or(LayerError::UnknownHandle("XrInstance"))?;
        // SAFETY: forwarding the app's arguments.
        let result = unsafe { (inst.next.create_session)(instance, info, session) };
        if result.into_raw() < 0 {
            return Ok(result);
        }
        // SAFETY: the runtime accepted info, so its system is the app's.
        let system = unsafe { info.as_ref() }.map(|i| i.system_id);
        let settings = headset_settings::settings_on(instance, &inst, system);
        let started = std::time::Instant::now();
        // SAFETY: the runtime accepted info, so it and its next chain are valid.
        let next_chain = unsafe { info.as_ref() }.map_or(std::ptr::null(), |i| i.next);
        // SAFETY: as above.
        let (api, bound) = unsafe { graphics::bind(next_chain, &settings) };
        let engine = match bound {
            Bound::Enhanced(graphics) => Some(graphics),
            Bound::PassThrough(why) => {
                log::info(&format!("session ({api}): {why}"));
                None
            }
        };
        let verdict = if engine.is_some() {
            "enhanced"
        } else {
            "passed through"
        };
        log::info(&format!("{}{api}, {verdict}", log::GRAPHICS_API));
        // SAFETY: session was written by the successful create call.
        let handle = unsafe { *session };
        let motion = super::motion::SessionMotion::create(&inst.next, handle, inst.timespec);
        if let Some(system) = system {
            blend::remember(handle, instance, system);
        }
        let state = SessionState {
            handle,
            instance,
            next: inst.next,
            settings,
            engine,
            retired: Vec::new(),
            indicator: Default::default(),
            started,
            background: None,
            background_requested: false,
            background_delivered: false,
            idle_since: None,
            frames: 0,
            processed: 0,
            last_blend_mode: None,
            regions_seen: false,
            motion,
            frame_in_use: None,
        };
        state::registry()
            .sessions
            .insert(handle.into_raw(), Arc::new(Mutex::new(state)));
        Ok(result)
    })
}

/// How long the session's end waits for its background's thread (a camera restoring its
/// controls and closing).
const CLOSE_WAIT: std::time::Duration = std::time::Duration::from_millis(300);

/// Drops the layer's state of a session (its GPU objects first) and of its swapchains.
pub fn forget(session: xr::Session) {
    let removed = state::registry().sessions.remove(&session.into_raw());
    sources::reopening().remove(&session.into_raw());
    blend::forget(session);
    if let Some(s) = removed {
        let mut s = lock(&s);
        // On the app's thread, inside xrDestroySession or xrDestroyInstance: the pipeline
        // threads end and the warm-up devices are destroyed here.
        s.end_engines();
        // Closes the camera (controls restored) before the app may exit: it is open only
        // while a session runs.
        let closed = s.background.take().map(|bg| bg.close_within(CLOSE_WAIT));
        if closed == Some(false) {
            log::info("the background's thread did not end within 0.3 s of the session's end: it closes its device on its own");
        }
    }
    // Lock order: the registry is never held while a swapchain is locked.
    let all: Vec<(u64, Arc<Mutex<state::SwapchainState>>)> = state::registry()
        .swapchains
        .iter()
        .map(|(k, v)| (*k, v.clone()))
        .collect();
    let gone: Vec<u64> = all
        .into_iter()
        .filter(|(_, sc)| lock(sc).session == session)
        .map(|(k, _)| k)
        .collect();
    let mut reg = state::registry();
    gone.iter().for_each(|k| {
        reg.swapchains.remove(k);
    });
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrDestroySession.
pub unsafe extern "system" fn destroy_session(session: xr::Session) -> xr::Result {
    guard(
        "xrDestroySession",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let s = state::session(session).ok_or(LayerError::UnknownHandle("XrSession"))?;
            let next = lock(&s).next;
            // A panic in the layer's own part is logged; the runtime gets the call regardless.
            guard("xrDestroySession", xr::Result::SUCCESS, || {
                lock(&s).motion.destroy(&next);
                let t = std::time::Instant::now();
                forget(session);
                if crate::fault::hit("destroy-bookkeeping") {
                    panic!("fault injected at destroy-bookkeeping (CONTRASTXR_FAULT)");
                }
                log::debug(&format!(
                    "session state released in {:.3} s",
                    t.elapsed().as_secs_f64()
                ));
                Ok(xr::Result::SUCCESS)
            });
            // SAFETY: forwarding the app's call after releasing everything the layer made.
            Ok(unsafe { (next.destroy_session)(session) })
        },
    )
}

/// The layer's part of xrEndFrame: new settings, the enhancement of the held images, and
/// their release. The caller holds no lock.
fn layer_end_frame(session: xr::Session, s: &Mutex<SessionState>, info: *const xr::FrameEndInfo) {
    let mut s = lock(s);
    s.frames += 1;
    sources::pick_up_settings(session, &mut s);
    // SAFETY: the app's frame end info (null is left for the runtime to reject).
    if let Some(info) = unsafe { info.as_ref() } {
        let done = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            end_frame::enhance_frame(&mut s, info)
        }));
        if done.is_err() {
            log::info(
                "internal error while enhancing: passing this session's frames through from now on",
            );
            s.retire_engine();
        }
    }
    if let Err(e) = crate::fault::check("end-frame") {
        panic!("{e}");
    }
    // The runtime composes only released images: hand over every image we held.
    swapchain::release_held(session);
}

/// After a panic in the layer's part of xrEndFrame: the session passes through from now on,
/// and every image still held is released, so the app's frame reaches the runtime whole.
fn recover_end_frame(session: xr::Session, s: &Mutex<SessionState>) {
    log::once(
        "end-frame-panic",
        "internal error in xrEndFrame: passing this session's frames through from now on",
    );
    lock(s).retire_engine();
    let released = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        swapchain::release_held(session)
    }));
    if released.is_err() {
        log::once("release-failed", "internal error releasing held images");
    }
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrEndFrame.
pub unsafe extern "system" fn end_frame(
    session: xr::Session,
    info: *const xr::FrameEndInfo,
) -> xr::Result {
    guard("xrEndFrame", xr::Result::ERROR_RUNTIME_FAILURE, || {
        let s = state::session(session).ok_or(LayerError::UnknownHandle("XrSession"))?;
        let next = lock(&s).next;
        // A panic anywhere in the layer's part still forwards the app's frame.
        let done = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            layer_end_frame(session, &s, info)
        }));
        if done.is_err() {
            recover_end_frame(session, &s);
        }
        // An app's ADDITIVE frame on a display set additive: the runtime gets a mode it has.
        let additive = lock(&s).settings.additive_display;
        let shown = blend::for_runtime(session, &next, additive, info);
        let info = shown
            .as_ref()
            .map_or(info, |f| f as *const xr::FrameEndInfo);
        // SAFETY: forwarding the app's call (no layer lock is held while the runtime works).
        Ok(unsafe { (next.end_frame)(session, info) })
    })
}
