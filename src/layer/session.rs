//! Sessions: read the Vulkan graphics binding at xrCreateSession and set up the session's
//! frame engine and background source ([`sources`]); at xrEndFrame enhance the frame's held
//! images ([`end_frame`]) and release them before the runtime composes them.
//! At xrCreateSession the system's `[device."..."]` config table applies ([`headset_settings`]).
//! At xrEndFrame a session also takes newer settings from the config watcher (never waiting);
//! a changed background source is reopened on a helper thread while frames pass through.

use super::ffi::{find_in_chain, guard, LayerError};
use super::live_settings::Settings;
use super::state::{self, lock, SessionState};
use super::{blend, end_frame, headset_settings, log, sources, swapchain};
use crate::gpu::frame::FrameEngine;
use crate::gpu::{Engine, GpuDevice, GpuError};
use ash::vk::{self, Handle};
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
        // SAFETY: the runtime accepted info, so its next chain is valid.
        let binding = unsafe { info.as_ref() }.and_then(|i| unsafe {
            find_in_chain::<xr::GraphicsBindingVulkanKHR>(
                i.next,
                xr::StructureType::GRAPHICS_BINDING_VULKAN_KHR,
            )
        });
        // SAFETY: the runtime accepted info, so its systemId is the app's system.
        let system = unsafe { info.as_ref() }.map(|i| i.system_id);
        let settings = headset_settings::settings_on(instance, &inst, system);
        let started = std::time::Instant::now();
        let engine = match binding {
            // SAFETY: a Vulkan binding the runtime accepted holds valid handles.
            Some(b) => set_up(unsafe { &*b }, &settings),
            None => {
                // SAFETY: the runtime accepted info, so it and its next chain are valid.
                let api = unsafe { info.as_ref().and_then(|i| super::ffi::graphics_api(i.next)) };
                let api = api.unwrap_or("no known graphics binding");
                log::info(&format!(
                    "session is not a Vulkan session ({api}): contrastxr enhances Vulkan sessions only; passing its frames through untouched"
                ));
                None
            }
        };
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

/// The session's frame engine on the app's device (its pipelines start building at once, on
/// its own thread). The background is not opened here: a camera opens only when a frame is to
/// be enhanced.
fn set_up(b: &xr::GraphicsBindingVulkanKHR, settings: &Settings) -> Option<FrameEngine> {
    let raw_instance = vk::Instance::from_raw(b.instance as u64);
    let entry = super::app_vulkan::entry_for(raw_instance).map_err(GpuError::NoLoader);
    // SAFETY: the handles come from a Vulkan binding the runtime accepted; the app keeps them
    // alive until after xrDestroySession, where the engine is ended first.
    let gpu = entry.and_then(|entry| unsafe {
        GpuDevice::borrow(
            entry,
            raw_instance,
            vk::PhysicalDevice::from_raw(b.physical_device as u64),
            vk::Device::from_raw(b.device as u64),
            b.queue_family_index,
            b.queue_index,
        )
    });
    // The background preparation's shaders first: the views' ones need a swapchain's format.
    let first = Engine::shaders_for(&settings.params, []).unwrap_or_default();
    let gpu = gpu.and_then(|gpu| gpu.queue_has_compute().map(|_| gpu));
    let engine = match gpu.and_then(|gpu| FrameEngine::new(gpu, &[])) {
        Ok(engine) => engine,
        Err(e) => {
            log::info(&format!(
                "GPU set-up failed ({e}): passing frames through untouched"
            ));
            return None;
        }
    };
    // Through request_shaders: a warm-up device that cannot be made is said here.
    state::request_shaders(&engine, &first);
    log::info(&format!(
        "session on Vulkan device {:?}, background {}: enhancing",
        engine.gpu.name, settings.background
    ));
    Some(engine)
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
