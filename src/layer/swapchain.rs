//! Swapchains: track creation info, images and image states, and hold the app's release of a
//! colour image until xrEndFrame, so the layer writes the image while it is still the app's to
//! give. (On Monado a released image is handed to an external queue at once: writing it after
//! the release would be outside the OpenXR specification.) Every call reaches the runtime at once except a
//! release the runtime would accept; anything that needs the runtime to see the app's own state
//! (another acquire, another release) hands a held release over first, enhanced, so each call
//! gets the runtime's own answer. Queue work happens only in calls the spec lets use the app's
//! queue: xrAcquireSwapchainImage, xrReleaseSwapchainImage, xrEndFrame; and never at once with
//! a forwarded xrCreateSwapchain or xrDestroySwapchain, where a runtime may submit on it too
//! (`app_queue`).

use super::ffi::{contain, guard, LayerError};
use super::image_states::{ImageStates, ReleasePlan};
use super::log;
use super::state::{self, lock, SessionState, SwapchainInfo, SwapchainState};
use super::swapchain_plan::{path_line, plan};
use crate::gpu::vulkan::device::app_queue;
use crate::gpu::PixelFormat;
use openxr_sys as xr;
use std::sync::{Arc, Mutex};

/// The runtime's xrCreateSwapchain, never at once with the layer's submits on an app's queue
/// (Monado submits the new images' layout change on it).
///
/// # Safety
/// The arguments of an xrCreateSwapchain call.
unsafe fn create_downstream(
    create: xr::pfn::CreateSwapchain,
    session: xr::Session,
    info: *const xr::SwapchainCreateInfo,
    swapchain: *mut xr::Swapchain,
) -> xr::Result {
    let _queue = app_queue::hold();
    // SAFETY: guaranteed by the caller.
    unsafe { create(session, info, swapchain) }
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrCreateSwapchain.
pub(crate) unsafe extern "system" fn create_swapchain(
    session: xr::Session,
    info: *const xr::SwapchainCreateInfo,
    swapchain: *mut xr::Swapchain,
) -> xr::Result {
    guard(
        "xrCreateSwapchain",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let s = state::session(session).ok_or(LayerError::UnknownHandle("XrSession"))?;
            let next = lock(&s).next;
            // SAFETY: the app's create info (null is left for the runtime to reject).
            let Some(app_info) = (unsafe { info.as_ref() }) else {
                // SAFETY: forwarding the app's arguments.
                return Ok(unsafe {
                    create_downstream(next.create_swapchain, session, info, swapchain)
                });
            };
            let format = app_info.format;
            // Pass-through sessions never have images held or touched.
            let plan = plan(&lock(&s), app_info);
            let pixel = plan.as_ref().map(|p| p.pixel);
            let needed = plan
                .as_ref()
                .map_or(xr::SwapchainUsageFlags::EMPTY, |p| p.needed);
            let mut usage_granted = app_info.usage_flags.contains(needed);
            // The app's create info with more usage bits; whether the runtime made it.
            let mut result = xr::Result::ERROR_RUNTIME_FAILURE;
            let mut create_with = |extra: xr::SwapchainUsageFlags| {
                let mut wanted = *app_info;
                wanted.usage_flags |= needed | extra;
                // SAFETY: the app's create info with more usage bits.
                result = unsafe {
                    create_downstream(next.create_swapchain, session, &wanted, swapchain)
                };
                (result.into_raw() >= 0, result)
            };
            let mut in_place = false;
            let mut refused = None;
            // What the runtime refused: logged only once a create with less usage succeeds
            // (else the runtime failed the app's own request, and said nothing of the usage).
            let mut refusals: Vec<(String, String)> = Vec::new();
            if let Some(extra) = plan.as_ref().and_then(|p| p.in_place) {
                let (made, result) = create_with(extra);
                in_place = made;
                usage_granted |= made;
                if !made {
                    refused = Some(result);
                    let path = plan.as_ref().map_or("copy", |p| p.copy_path);
                    refusals.push((format!("no-storage-{format}"), format!(
                        "the runtime refused storage usage on swapchains of format {format} ({result:?}): their views are enhanced through a copy (path {path})"
                    )));
                }
            }
            let mut sampled = false;
            if let Some(extra) = plan.as_ref().and_then(|p| p.sampled).filter(|_| !in_place) {
                let (made, result) = create_with(extra);
                sampled = made;
                usage_granted |= made;
                if !made {
                    refusals.push((format!("no-sampled-{format}"), format!(
                        "the runtime refused sampled usage on swapchains of format {format} ({result:?}): their views are copied into the layer's image (copy_in = \"sampled\" needs it)"
                    )));
                }
            }
            if pixel.is_some() && !usage_granted {
                let (made, result) = create_with(xr::SwapchainUsageFlags::EMPTY);
                usage_granted = made;
                if !made {
                    refusals.push((format!("no-transfer-{format}"), format!(
                    "the runtime refused transfer usage on swapchains of format {format} ({result:?}): those pass through"
                )));
                }
            }
            if result.into_raw() < 0 {
                // SAFETY: forwarding the app's arguments unchanged.
                result =
                    unsafe { create_downstream(next.create_swapchain, session, info, swapchain) };
            }
            log_refusals(&refusals, format, result);
            // Every swapchain is tracked (with its session's dispatch); only processable ones are touched.
            if result.into_raw() >= 0 {
                let mut info = SwapchainInfo::new(app_info, pixel, usage_granted, in_place);
                info.sampled |= sampled;
                let state = SwapchainState::new(session, next, info);
                // SAFETY: written by the successful create call.
                let handle = unsafe { *swapchain };
                state::registry()
                    .swapchains
                    .insert(handle.into_raw(), Arc::new(Mutex::new(state)));
                if let Some(format) = pixel.filter(|_| usage_granted) {
                    if let Some(plan) = &plan {
                        log::info(&path_line(app_info, plan, in_place, refused));
                    }
                    request_shaders(&s, format, app_info.width, in_place);
                }
            }
            Ok(result)
        },
    )
}

/// Logs each usage the runtime refused, once per kind and format, where the create finally
/// succeeded; where even the app's own request failed, one line saying so instead: the
/// failure was the runtime's (out of memory, say), not a refusal of the layer's usage.
fn log_refusals(refusals: &[(String, String)], format: i64, result: xr::Result) {
    if result.into_raw() >= 0 {
        for (key, line) in refusals {
            log::once(key, line);
        }
    } else if !refusals.is_empty() {
        log::once(&format!("create-failed-{format}-{result:?}"), &format!(
            "the runtime failed xrCreateSwapchain of format {format} ({result:?}) with the app's own usage as well: the app gets that error"
        ));
    }
}

/// Starts building the shaders that views of this swapchain will need (Vulkan: on the
/// engine's own thread; OpenGL: linked from the caches here, or built on a thread of the
/// layer's own), so they are likely ready by the first xrEndFrame. Views usually span the
/// width. A panic in it costs the app nothing: its swapchain was made, and the session passes
/// through from then on.
fn request_shaders(s: &Mutex<SessionState>, format: PixelFormat, width: u32, in_place: bool) {
    let mut s = lock(s);
    // A session whose frames can never be ADDITIVE (and the layer not forced on) is never
    // enhanced: nothing to build for it.
    if !s.settings.force && !super::blend::additive_possible(s.handle, &s.next) {
        return;
    }
    let (params, wait) = (s.settings.params.clone(), s.settings.wait_for_pipelines);
    let Some(graphics) = s.graphics.as_mut() else {
        return;
    };
    let prepared = contain("while preparing the shaders at xrCreateSwapchain", || {
        graphics.request_shaders(&params, format, width, in_place, wait)
    });
    if let Err(panic) = prepared {
        s.pass_through(&panic.to_string());
    }
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrDestroySwapchain.
pub(crate) unsafe extern "system" fn destroy_swapchain(swapchain: xr::Swapchain) -> xr::Result {
    guard(
        "xrDestroySwapchain",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let sc = state::swapchain(swapchain).ok_or(LayerError::UnknownHandle("XrSwapchain"))?;
            let next = lock(&sc).next;
            // A panic in the layer's own part is logged; the runtime gets the call regardless.
            guard("xrDestroySwapchain", xr::Result::SUCCESS, || {
                if crate::fault::hit("destroy-bookkeeping") {
                    panic!("fault injected at destroy-bookkeeping (CONTRASTXR_FAULT)");
                }
                forget(&sc, swapchain);
                Ok(xr::Result::SUCCESS)
            });
            let _queue = app_queue::hold();
            // SAFETY: forwarding the app's call.
            Ok(unsafe { (next.destroy_swapchain)(swapchain) })
        },
    )
}

/// The layer's state of a swapchain the app destroys (the session's views of its images too).
fn forget(sc: &Arc<Mutex<SwapchainState>>, swapchain: xr::Swapchain) {
    with_session(sc, |s, sc| {
        // A held release goes with the swapchain: the image is never composed again.
        sc.states = ImageStates::default();
        let Some(s) = s else { return };
        let forgotten = s
            .graphics
            .as_mut()
            .map(|graphics| graphics.forget_swapchain(swapchain.into_raw()));
        if let Some(Err(e)) = forgotten {
            // Its image views stay alive under handles the runtime may reuse: no more frames.
            s.pass_through(&format!("xrDestroySwapchain: {e}"));
        }
    });
    state::registry().swapchains.remove(&swapchain.into_raw());
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrEnumerateSwapchainImages.
pub(crate) unsafe extern "system" fn enumerate_swapchain_images(
    swapchain: xr::Swapchain,
    capacity: u32,
    count: *mut u32,
    images: *mut xr::SwapchainImageBaseHeader,
) -> xr::Result {
    guard(
        "xrEnumerateSwapchainImages",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let tracked = state::swapchain(swapchain);
            let next = match &tracked {
                Some(sc) => lock(sc).next,
                None => return Err(LayerError::UnknownHandle("XrSwapchain")),
            };
            // SAFETY: forwarding the app's arguments.
            let result =
                unsafe { (next.enumerate_swapchain_images)(swapchain, capacity, count, images) };
            if let (Some(sc), true) = (
                tracked,
                result == xr::Result::SUCCESS && capacity > 0 && !images.is_null(),
            ) {
                // SAFETY: on success the runtime filled *count structs of the type the app chose.
                let n = unsafe { *count } as usize;
                with_session(&sc, |s, sc| {
                    let graphics = s.and_then(|s| s.graphics.as_ref());
                    // SAFETY: n structs of the app's chosen type were written (checked non-null).
                    if let Some(raw) = graphics.and_then(|g| unsafe { g.images(images, n) }) {
                        sc.set_images(raw);
                    }
                });
            }
            Ok(result)
        },
    )
}

/// Runs `f` with the swapchain's session (if the layer tracks it) and the swapchain locked, in
/// the documented lock order: the session first (see `state`).
pub fn with_session<R>(
    sc: &Arc<Mutex<SwapchainState>>,
    f: impl FnOnce(Option<&mut SessionState>, &mut SwapchainState) -> R,
) -> R {
    let session = lock(sc).session;
    let s = state::session(session);
    let mut s = s.as_ref().map(|s| lock(s));
    let mut sc = lock(sc);
    f(s.as_deref_mut(), &mut sc)
}

/// Forwards the held release to the runtime (the image becomes the runtime's).
fn forward_held(sc: &mut SwapchainState, swapchain: xr::Swapchain) {
    if sc.states.held().is_none() {
        return;
    }
    let info = xr::SwapchainImageReleaseInfo {
        ty: xr::SwapchainImageReleaseInfo::TYPE,
        next: std::ptr::null(),
    };
    // SAFETY: releasing the waited image the app released earlier, with a valid release info.
    let result = unsafe { (sc.next.release_swapchain_image)(swapchain, &info) };
    if result.into_raw() < 0 {
        // Not expected: a release is held only while the runtime counts the image as waited.
        log::once(
            "release-failed",
            &format!("forwarding a held image release failed: {result:?}"),
        );
    }
    sc.states.released();
}

/// Forwards every held release of a session's swapchains (at xrEndFrame, before the runtime's).
/// The caller holds the session's lock.
pub fn release_held(session: xr::Session) {
    let all: Vec<(u64, Arc<Mutex<SwapchainState>>)> = state::registry()
        .swapchains
        .iter()
        .map(|(k, v)| (*k, v.clone()))
        .collect();
    for (handle, sc) in all {
        crate::fault::pause("release-held");
        let mut sc = lock(&sc);
        if sc.session == session {
            forward_held(&mut sc, xr::Swapchain::from_raw(handle));
        }
    }
}

/// Enhances a released image now, with the regions last submitted for its swapchain: its
/// xrEndFrame comes after the runtime must have it (a pipelined app).
fn enhance_ahead(
    s: Option<&mut SessionState>,
    sc: &SwapchainState,
    swapchain: xr::Swapchain,
    image: u32,
) {
    log::once(
        "pipelined",
        "the app works ahead of xrEndFrame (a pipelined renderer): its images are enhanced when released, with the view regions it last submitted",
    );
    if let Some(s) = s {
        super::end_frame::enhance_ahead(s, sc, swapchain, image);
    }
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrAcquireSwapchainImage.
pub(crate) unsafe extern "system" fn acquire_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageAcquireInfo,
    index: *mut u32,
) -> xr::Result {
    guard(
        "xrAcquireSwapchainImage",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let sc = state::swapchain(swapchain).ok_or(LayerError::UnknownHandle("XrSwapchain"))?;
            // The app takes its next image before xrEndFrame: the held one goes now, enhanced
            // (acquire may use the app's queue), so the runtime sees what the app sees.
            let next = with_session(&sc, |s, sc| {
                if let Some(i) = sc.states.held() {
                    enhance_ahead(s, sc, swapchain, i);
                    forward_held(sc, swapchain);
                }
                sc.next
            });
            // SAFETY: forwarding the app's arguments.
            let result = unsafe { (next.acquire_swapchain_image)(swapchain, info, index) };
            if result.into_raw() >= 0 {
                // SAFETY: written by the successful call.
                lock(&sc).states.acquired(unsafe { *index });
            }
            Ok(result)
        },
    )
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrWaitSwapchainImage.
pub(crate) unsafe extern "system" fn wait_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageWaitInfo,
) -> xr::Result {
    guard(
        "xrWaitSwapchainImage",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let sc = state::swapchain(swapchain).ok_or(LayerError::UnknownHandle("XrSwapchain"))?;
            // No lock is held while the runtime blocks. A held release here means the app has
            // no acquired image: the runtime answers CALL_ORDER_INVALID either way ("already
            // waited" for the held image, as "nothing acquired" without the layer).
            let next = lock(&sc).next;
            // SAFETY: forwarding the app's arguments.
            let result = unsafe { (next.wait_swapchain_image)(swapchain, info) };
            if result.into_raw() >= 0 && result != xr::Result::TIMEOUT_EXPIRED {
                lock(&sc).states.waited(result == xr::Result::SUCCESS);
            }
            Ok(result)
        },
    )
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrReleaseSwapchainImage.
pub(crate) unsafe extern "system" fn release_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageReleaseInfo,
) -> xr::Result {
    guard(
        "xrReleaseSwapchainImage",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let sc = state::swapchain(swapchain).ok_or(LayerError::UnknownHandle("XrSwapchain"))?;
            let (plan, next) = with_session(&sc, |s, sc| {
                // SAFETY: the app's release info, null or valid (its type is checked here and
                // by the runtime when forwarded).
                let info_ok =
                    info.is_null() || unsafe { (*info).ty } == xr::SwapchainImageReleaseInfo::TYPE;
                let holdable = info_ok && sc.info.processable() && sc.has_images();
                let plan = sc.states.plan_release(holdable);
                match plan {
                    ReleasePlan::Hold(_) => sc.states.hold(),
                    ReleasePlan::EnhanceThenForward(i) => enhance_ahead(s, sc, swapchain, i),
                    ReleasePlan::FlushHeldThenForward(i) => {
                        enhance_ahead(s, sc, swapchain, i);
                        forward_held(sc, swapchain);
                    }
                    ReleasePlan::Forward => {}
                }
                (plan, sc.next)
            });
            if let ReleasePlan::Hold(_) = plan {
                // The runtime would accept this release (an image is waited): it answers the
                // same when the layer forwards it at xrEndFrame.
                return Ok(xr::Result::SUCCESS);
            }
            // SAFETY: forwarding the app's arguments.
            let result = unsafe { (next.release_swapchain_image)(swapchain, info) };
            if result.into_raw() >= 0 {
                lock(&sc).states.released();
            }
            Ok(result)
        },
    )
}
