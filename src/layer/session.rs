//! Sessions: read the graphics binding at xrCreateSession and set up the session's graphics
//! ([`graphics`]: Vulkan or OpenGL) and background source ([`sources`]); at xrEndFrame enhance the frame's held
//! images ([`end_frame`](mod@end_frame)) and release them before the runtime composes them.
//! At xrCreateSession the system's `[device."..."]` config table applies ([`headset_settings`]).
//! At xrEndFrame a session also takes newer settings from the config watcher (never waiting);
//! a changed background source is reopened on a helper thread while frames pass through.

use super::ffi::{contain, guard, Contained, LayerError};
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
            graphics: engine,
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
            retry: Default::default(),
            gpu_time: Default::default(),
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
        // threads end here (a CPU driver's warm-up device is the process's and stays).
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
        let enhanced = contain("while enhancing", || end_frame::enhance_frame(&mut s, info));
        if let Err(panic) = enhanced {
            s.pass_through(&panic.to_string());
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
fn recover_end_frame(session: xr::Session, s: &Mutex<SessionState>, panic: Contained) {
    lock(s).pass_through(&panic.to_string());
    let released = contain("releasing held images", || swapchain::release_held(session));
    if let Err(panic) = released {
        log::once("release-failed", &panic.to_string());
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
        if let Err(panic) = contain("in xrEndFrame", || layer_end_frame(session, &s, info)) {
            recover_end_frame(session, &s, panic);
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

#[cfg(test)]
mod tests {
    use super::super::fake_runtime::Rig;
    use super::super::graphics::fake_graphics::Outcome;
    use super::*;

    const FRAME: [&str; 4] = ["acquire", "wait", "release", "end_frame"];

    /// The app's release is held (the runtime does not see it) until xrEndFrame, where the
    /// image is enhanced and then released, before the runtime's xrEndFrame.
    #[test]
    fn a_held_release_reaches_the_runtime_after_the_enhancement_and_before_the_frame() {
        let rig = Rig::new();
        assert_eq!(rig.render(), [xr::Result::SUCCESS; 3]);
        assert_eq!(rig.runtime_calls(), ["acquire", "wait"]);
        assert!(rig.fake.calls().enhanced.is_empty());
        assert_eq!(rig.end_frame(), xr::Result::SUCCESS);
        assert_eq!(rig.runtime_calls(), FRAME);
        assert_eq!(rig.fake.calls().enhanced, [[rig.swapchain.into_raw()]]);
        assert_eq!(lock(&rig.state()).processed, 1);
    }

    /// A frame the graphics fail: the session passes through from then on (its engine retired,
    /// told to stop building, and never asked again), and every frame still reaches the
    /// runtime whole.
    #[test]
    fn a_failed_frame_passes_the_session_through_and_the_frames_still_reach_the_runtime() {
        let rig = Rig::new();
        rig.fake.answer(Outcome::Fail("the fake failed".into()));
        for _ in 0..2 {
            rig.render();
            assert_eq!(rig.end_frame(), xr::Result::SUCCESS);
        }
        assert_eq!(rig.runtime_calls(), [FRAME, FRAME].concat());
        assert_eq!(rig.fake.calls().enhanced.len(), 1);
        assert_eq!(rig.fake.calls().stopped_building, 1);
        let state = rig.state();
        let s = lock(&state);
        assert!(s.graphics.is_none());
        assert_eq!((s.retired.len(), s.processed), (1, 0));
    }

    /// A panic in the graphics while enhancing costs the app nothing: xrEndFrame succeeds, the
    /// held image and the frame reach the runtime, and the session passes through.
    #[test]
    fn a_panic_while_enhancing_passes_the_session_through() {
        let rig = Rig::new();
        rig.fake.answer(Outcome::Panic);
        rig.render();
        assert_eq!(rig.end_frame(), xr::Result::SUCCESS);
        assert_eq!(rig.runtime_calls(), FRAME);
        assert_eq!(rig.fake.calls().stopped_building, 1);
        assert!(lock(&rig.state()).graphics.is_none());
    }

    /// A panic at a release ahead of xrEndFrame (a pipelined app, enhanced at its next
    /// acquire) is contained the same way: the acquire succeeds and the release reaches the
    /// runtime before it.
    #[test]
    fn a_panic_while_enhancing_ahead_passes_the_session_through() {
        let rig = Rig::new();
        rig.render();
        rig.fake.answer(Outcome::Panic);
        let mut index = 0;
        // SAFETY: the layer's entry point with valid arguments.
        let acquired = unsafe {
            swapchain::acquire_swapchain_image(rig.swapchain, std::ptr::null(), &mut index)
        };
        assert_eq!(acquired, xr::Result::SUCCESS);
        assert_eq!(
            rig.runtime_calls(),
            ["acquire", "wait", "release", "acquire"]
        );
        assert!(lock(&rig.state()).graphics.is_none());
    }

    /// A panic in the graphics while the app makes a swapchain (the shaders it will need are
    /// requested): the app gets its swapchain, and the session passes through.
    #[test]
    fn a_panic_while_requesting_shaders_passes_the_session_through() {
        let rig = Rig::new();
        rig.fake.answer(Outcome::Panic);
        let mut made = xr::Swapchain::NULL;
        let info = super::super::fake_runtime::colour_swapchain();
        // SAFETY: the layer's entry point with valid arguments.
        let created = unsafe { swapchain::create_swapchain(rig.session, &info, &mut made) };
        assert_eq!(created, xr::Result::SUCCESS);
        assert_ne!(made, xr::Swapchain::NULL);
        assert_eq!(rig.runtime_calls(), ["create_swapchain"]);
        assert_eq!(rig.fake.calls().requested_shaders, 1);
        assert!(lock(&rig.state()).graphics.is_none());
    }

    /// A runtime that fails xrCreateSwapchain whatever the usage (out of memory, say): the
    /// app gets the runtime's error after the layer's request and then the app's own, and the
    /// log says the runtime failed, not that it refused the layer's usage.
    #[test]
    fn a_create_the_runtime_fails_with_any_usage_is_not_logged_as_a_refusal() {
        let rig = Rig::new();
        rig.fail_swapchain_creates();
        let mut made = xr::Swapchain::NULL;
        let info = super::super::fake_runtime::colour_swapchain();
        // SAFETY: the layer's entry point with valid arguments.
        let created = unsafe { swapchain::create_swapchain(rig.session, &info, &mut made) };
        assert_eq!(created, xr::Result::ERROR_RUNTIME_FAILURE);
        assert_eq!(rig.runtime_calls(), ["create_swapchain, failed"; 2]);
        assert!(log::said_once("create-failed-0-ERROR_RUNTIME_FAILURE"));
        assert!(!log::said_once("no-transfer-0"));
    }

    /// Frames whose graphics cannot be reached now (the app's OpenGL context current on
    /// another thread) pass through whole and keep the engine; the layer tries at the next
    /// frame, then ever less often, and enhances again once a try succeeds.
    #[test]
    fn unreachable_graphics_pass_frames_through_and_are_tried_again_ever_less_often() {
        let rig = Rig::new();
        rig.fake
            .answer(Outcome::Unreachable("the fake is out of reach".into()));
        let mut tried = Vec::new();
        for frame in 0..8 {
            let before = rig.fake.calls().enhanced.len();
            rig.render();
            assert_eq!(rig.end_frame(), xr::Result::SUCCESS);
            if rig.fake.calls().enhanced.len() > before {
                tried.push(frame);
            }
        }
        assert_eq!(tried, [0, 1, 3, 7]);
        assert_eq!(rig.runtime_calls(), FRAME.repeat(8));
        assert_eq!(rig.fake.calls().stopped_building, 0);
        assert!(lock(&rig.state()).graphics.is_some());
        rig.fake.answer(Outcome::Enhance);
        for _ in 0..8 {
            rig.render();
            rig.end_frame();
        }
        // Frame 15 is the next try; it and every frame after it are enhanced.
        assert_eq!(lock(&rig.state()).processed, 1);
        rig.render();
        rig.end_frame();
        assert_eq!(lock(&rig.state()).processed, 2);
    }

    /// Frames whose shaders are still being built pass through, and the engine stays.
    #[test]
    fn pending_frames_pass_through_and_keep_the_engine() {
        let rig = Rig::new();
        rig.fake.answer(Outcome::Pending);
        rig.render();
        rig.end_frame();
        assert!(lock(&rig.state()).graphics.is_some());
        rig.fake.answer(Outcome::Enhance);
        rig.render();
        rig.end_frame();
        assert_eq!(rig.runtime_calls(), [FRAME, FRAME].concat());
        assert_eq!(lock(&rig.state()).processed, 1);
        assert_eq!(rig.fake.calls().stopped_building, 0);
    }

    /// A swapchain whose views the graphics cannot release: the session passes through (its
    /// views stay under handles the runtime may give out again), and the destroy reaches the
    /// runtime.
    #[test]
    fn a_swapchain_the_graphics_cannot_forget_passes_the_session_through() {
        let rig = Rig::new();
        rig.fake.fail_forget();
        // SAFETY: the layer's entry point with the rig's swapchain.
        let destroyed = unsafe { swapchain::destroy_swapchain(rig.swapchain) };
        assert_eq!(destroyed, xr::Result::SUCCESS);
        assert_eq!(rig.runtime_calls(), ["destroy_swapchain"]);
        assert!(lock(&rig.state()).graphics.is_none());
    }

    /// Passing through twice retires the engine once; the session's end finishes every
    /// engine, retired or not.
    #[test]
    fn a_retired_engine_is_stopped_once_and_finished_at_the_session_end() {
        let rig = Rig::new();
        let state = rig.state();
        lock(&state).pass_through("the first failure");
        lock(&state).pass_through("a second failure");
        assert_eq!(lock(&state).retired.len(), 1);
        assert_eq!(rig.fake.calls().stopped_building, 1);
        assert_eq!(rig.fake.calls().finished, 0);
        forget(rig.session);
        assert_eq!(rig.fake.calls().finished, 1);
    }
}
