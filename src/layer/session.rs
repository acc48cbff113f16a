//! Sessions: read the Vulkan graphics binding at xrCreateSession, and at xrEndFrame enhance
//! every projection view (and quad layers when configured) before the runtime composes it.
//! At xrCreateSession the system's `[device."..."]` config table applies ([`device`]).
//! At xrEndFrame a session also takes newer settings from the config watcher (never waiting);
//! a changed background source is reopened on a helper thread while frames pass through.

use super::capture;
use super::ffi::{find_in_chain, guard};
use super::processor::Processor;
use super::registration::{self, ViewGeometry};
use super::settings::{self, Settings};
use super::state::{self, lock, SessionState, SwapchainState, ViewRegion};
use super::work::{ViewKey, WorkItem};
use super::{device, log, swapchain};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::ViewMode;
use crate::camera::{self, Background, CaptureConfig};
use crate::gpu::pipeline_cache::Origin;
use crate::gpu::{Engine, GpuDevice, GpuError};
use ash::vk::{self, Handle};
use openxr_sys as xr;
use std::collections::HashMap;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrCreateSession.
pub unsafe extern "system" fn create_session(
    instance: xr::Instance,
    info: *const xr::SessionCreateInfo,
    session: *mut xr::Session,
) -> xr::Result {
    guard("xrCreateSession", xr::Result::ERROR_RUNTIME_FAILURE, || {
        let Some(inst) = state::instance(instance) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        // SAFETY: forwarding the app's arguments.
        let result = unsafe { (inst.next.create_session)(instance, info, session) };
        if result.into_raw() < 0 {
            return result;
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
        let settings = device::settings_on(instance, &inst, system);
        let (processor, background) = match binding {
            // SAFETY: a Vulkan binding the runtime accepted holds valid handles.
            Some(b) => set_up(unsafe { &*b }, &settings),
            None => {
                log::info("session is not a Vulkan session: passing its frames through untouched");
                (None, None)
            }
        };
        let state = SessionState {
            instance,
            next: inst.next,
            settings,
            processor,
            background,
            frames: 0,
            processed: 0,
            last_blend_mode: None,
            regions_seen: false,
        };
        // SAFETY: session was written by the successful create call.
        let handle = unsafe { *session };
        state::registry()
            .sessions
            .insert(handle.into_raw(), Arc::new(Mutex::new(state)));
        result
    })
}

fn open_background(spec: &str, camera: &CaptureConfig) -> Result<Background, String> {
    let source = camera::parse_source(spec)?;
    Background::open(&source, camera).map_err(|e| e.to_string())
}

/// Opens the background, logging once why not: the session then passes frames through until
/// the config names a source that opens.
fn open_background_logged(spec: &str, camera: &CaptureConfig) -> Option<Background> {
    match open_background(spec, camera) {
        Ok(bg) => Some(bg),
        Err(e) => {
            log::info(&format!(
                "no background ({e}): passing frames through untouched"
            ));
            None
        }
    }
}

fn set_up(
    b: &xr::GraphicsBindingVulkanKHR,
    settings: &Settings,
) -> (Option<Processor>, Option<Background>) {
    // SAFETY: the handles come from a Vulkan binding the runtime accepted; the app keeps them
    // alive until after xrDestroySession, where the processor is dropped first.
    let gpu = unsafe {
        GpuDevice::borrow(
            vk::Instance::from_raw(b.instance as u64),
            vk::PhysicalDevice::from_raw(b.physical_device as u64),
            vk::Device::from_raw(b.device as u64),
            b.queue_family_index,
            b.queue_index,
        )
    };
    // The background preparation's shaders first: the views' ones need a swapchain's format.
    let first = Engine::shaders_for(&settings.params, []).unwrap_or_default();
    let gpu = gpu.and_then(|gpu| gpu.queue_has_compute().map(|_| gpu));
    let processor = match gpu.and_then(|gpu| Processor::new(gpu, &first)) {
        Ok(p) => p,
        Err(e) => {
            log::info(&format!(
                "GPU set-up failed ({e}): passing frames through untouched"
            ));
            return (None, None);
        }
    };
    // Opened after the GPU set-up: a camera stays closed for a session that cannot use it.
    let background = open_background_logged(&settings.background, &settings.camera);
    if let Some(bg) = &background {
        log::info(&format!(
            "session on Vulkan device {:?}, background {}: enhancing",
            processor.gpu.name,
            bg.description()
        ));
    }
    (Some(processor), background)
}

/// Background sources being reopened after a config change, by session: the helper thread
/// closes the old source, opens the new one and sends it (None if it failed).
fn reopening() -> MutexGuard<'static, HashMap<u64, Receiver<Option<Background>>>> {
    static REOPENING: OnceLock<Mutex<HashMap<u64, Receiver<Option<Background>>>>> = OnceLock::new();
    let m = REOPENING.get_or_init(Default::default);
    // Only map operations happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

fn start_reopen(
    session: xr::Session,
    old: Option<Background>,
    spec: String,
    camera: CaptureConfig,
) {
    let (tx, rx) = mpsc::channel();
    let spawned = std::thread::Builder::new()
        .name("contrastxr-reopen".into())
        .spawn(move || {
            drop(old);
            let _ = tx.send(open_background_logged(&spec, &camera));
        });
    match spawned {
        Ok(_) => {
            reopening().insert(session.into_raw(), rx);
        }
        Err(e) => log::info(&format!("cannot reopen the background ({e})")),
    }
}

/// A reopened background, if the helper thread has finished.
fn take_reopened(session: xr::Session, s: &mut SessionState) {
    let mut pending = reopening();
    let Some(rx) = pending.get(&session.into_raw()) else {
        return;
    };
    match rx.try_recv() {
        Ok(bg) => {
            if let Some(bg) = &bg {
                log::info(&format!("background is now {}", bg.description()));
            }
            s.background = bg;
            pending.remove(&session.into_raw());
        }
        Err(TryRecvError::Empty) => {}
        Err(TryRecvError::Disconnected) => {
            pending.remove(&session.into_raw());
        }
    }
}

/// Takes newer settings from the config watcher, if any, without waiting.
fn pick_up_settings(session: xr::Session, s: &mut SessionState) {
    take_reopened(session, s);
    let Some(live) = settings::live(s.instance.into_raw()) else {
        return;
    };
    let Some(newer) = live.newer(s.settings.generation) else {
        return;
    };
    let source_changed =
        newer.background != s.settings.background || newer.camera != s.settings.camera;
    if source_changed && s.processor.is_some() {
        start_reopen(
            session,
            s.background.take(),
            newer.background.clone(),
            newer.camera.clone(),
        );
    }
    s.settings = newer;
}

/// Drops the layer's state of a session (its GPU objects first) and of its swapchains.
pub fn forget(session: xr::Session) {
    let removed = state::registry().sessions.remove(&session.into_raw());
    reopening().remove(&session.into_raw());
    if let Some(s) = removed {
        let mut s = lock(&s);
        s.processor = None;
        // Closes the camera: it is open only while a session runs.
        s.background = None;
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
            let Some(s) = state::session(session) else {
                return xr::Result::ERROR_HANDLE_INVALID;
            };
            let next = lock(&s).next;
            let t = std::time::Instant::now();
            forget(session);
            log::debug(&format!(
                "session state released in {:.3} s",
                t.elapsed().as_secs_f64()
            ));
            // SAFETY: forwarding the app's call after releasing everything the layer made.
            unsafe { (next.destroy_session)(session) }
        },
    )
}

/// A sub-image a layer names, with its camera mapping when it is a projection view (each
/// view registered from its field of view and pose, see [`registration`]; None for quads).
struct SubImage {
    sub: xr::SwapchainSubImage,
    mapping: Option<CameraMapping>,
}

/// The sub-images of the frame's layers that the layer enhances.
///
/// # Safety
/// `info` must be a valid XrFrameEndInfo (its layers and views valid structs).
unsafe fn sub_images(info: &xr::FrameEndInfo, settings: &Settings) -> Vec<SubImage> {
    let mut out = Vec::new();
    if info.layers.is_null() {
        return out;
    }
    for i in 0..info.layer_count as usize {
        // SAFETY: layer_count valid pointers (the caller's contract).
        let layer = unsafe { *info.layers.add(i) };
        let Some(base) = (unsafe { layer.as_ref() }) else {
            continue;
        };
        if base.ty == xr::StructureType::COMPOSITION_LAYER_PROJECTION {
            // SAFETY: the type tag says this is a projection layer.
            let proj = unsafe { &*(layer as *const xr::CompositionLayerProjection) };
            if proj.views.is_null() {
                continue;
            }
            // SAFETY: view_count valid views.
            let views = unsafe { std::slice::from_raw_parts(proj.views, proj.view_count as usize) };
            let geometry: Vec<_> = views.iter().map(ViewGeometry::from_xr).collect();
            let mappings = registration::projection_mappings(settings, &geometry);
            for (k, (view, (mapping, source))) in views.iter().zip(mappings).enumerate() {
                registration::log_mapping(settings, k, &mapping, &source);
                out.push(SubImage {
                    sub: view.sub_image,
                    mapping: Some(mapping),
                });
            }
        } else if settings.quad_layers && base.ty == xr::StructureType::COMPOSITION_LAYER_QUAD {
            // SAFETY: the type tag says this is a quad layer.
            let sub = unsafe { (*(layer as *const xr::CompositionLayerQuad)).sub_image };
            out.push(SubImage { sub, mapping: None });
        }
    }
    out
}

/// A work item for one view region of image `image` of a swapchain, if the region lies inside it.
fn work_item(
    swapchain: xr::Swapchain,
    sc: &SwapchainState,
    image: u32,
    region: &ViewRegion,
    settings: &Settings,
) -> Option<WorkItem> {
    let format = sc.info.pixel.filter(|_| sc.info.processable())?;
    let vk_image = *sc.images.get(image as usize)?;
    let r = region.rect;
    let fits = r.offset.x >= 0
        && r.offset.y >= 0
        && r.extent.width > 0
        && r.extent.height > 0
        && (r.offset.x + r.extent.width) as u32 <= sc.info.width
        && (r.offset.y + r.extent.height) as u32 <= sc.info.height
        && region.array_index < sc.info.array_size;
    if !fits {
        log::once("bad-rect", "a layer's imageRect/imageArrayIndex lies outside its swapchain: that view passes through");
        return None;
    }
    Some(WorkItem {
        key: ViewKey {
            swapchain: swapchain.into_raw(),
            offset: (r.offset.x, r.offset.y),
            extent: (r.extent.width as u32, r.extent.height as u32),
            array_index: region.array_index,
        },
        image: vk_image,
        format,
        vk_format: sc.info.vk_format,
        // Quads, and whole images before the first xrEndFrame, take the manual mapping.
        mapping: region
            .mapping
            .unwrap_or_else(|| registration::quad_mapping(settings)),
    })
}

/// Each enhanced sub-image's swapchain with its regions in this frame, in submission order.
fn regions_by_swapchain(subs: &[SubImage]) -> Vec<(xr::Swapchain, Vec<ViewRegion>)> {
    let mut out: Vec<(xr::Swapchain, Vec<ViewRegion>)> = Vec::new();
    for SubImage { sub, mapping } in subs {
        let region = ViewRegion {
            rect: sub.image_rect,
            array_index: sub.image_array_index,
            mapping: *mapping,
        };
        match out.iter_mut().find(|(h, _)| *h == sub.swapchain) {
            Some((_, regions)) => regions.push(region),
            None => out.push((sub.swapchain, vec![region])),
        }
    }
    out
}

/// Remembers each swapchain's regions for images released ahead of their xrEndFrame, and
/// returns the work for the images the layer holds now. The caller holds the session's lock.
fn frame_items(subs: &[SubImage], settings: &Settings) -> Vec<WorkItem> {
    let mut items = Vec::new();
    for (handle, regions) in regions_by_swapchain(subs) {
        let Some(sc) = state::swapchain(handle) else {
            continue;
        };
        let mut sc = lock(&sc);
        if let Some(image) = sc.states.held() {
            items.extend(
                regions
                    .iter()
                    .filter_map(|r| work_item(handle, &sc, image, r, settings)),
            );
        }
        sc.last_views = regions;
    }
    items
}

/// The regions to enhance an image released ahead of its xrEndFrame with: the swapchain's
/// last submitted ones; before the session's first xrEndFrame named any, each array layer whole.
fn regions_ahead(s: &SessionState, sc: &SwapchainState) -> Vec<ViewRegion> {
    if s.regions_seen {
        return sc.last_views.clone();
    }
    let rect = xr::Rect2Di {
        offset: xr::Offset2Di { x: 0, y: 0 },
        extent: xr::Extent2Di {
            width: sc.info.width as i32,
            height: sc.info.height as i32,
        },
    };
    (0..sc.info.array_size)
        .map(|array_index| ViewRegion {
            rect,
            array_index,
            mapping: None,
        })
        .collect()
}

/// Enhances image `image` of a swapchain now, before the app's xrEndFrame for it (a pipelined
/// app released it and took its next image first). The caller holds the session's lock, then
/// the swapchain's.
pub fn enhance_ahead(
    s: &mut SessionState,
    sc: &SwapchainState,
    swapchain: xr::Swapchain,
    image: u32,
) {
    let items: Vec<WorkItem> = regions_ahead(s, sc)
        .iter()
        .filter_map(|r| work_item(swapchain, sc, image, r, &s.settings))
        .collect();
    let blend = s.last_blend_mode;
    guarded_process(s, items, blend);
}

/// Whether the layer acts on frames of this blend mode (None: not known yet, before the first
/// xrEndFrame; only a forced layer acts then).
fn acts_on(s: &SessionState, mode: Option<xr::EnvironmentBlendMode>) -> bool {
    if mode == Some(xr::EnvironmentBlendMode::ADDITIVE) || s.settings.force {
        return true;
    }
    let Some(mode) = mode else {
        return false;
    };
    log::once("blend-mode", &format!(
        "environment blend mode {mode:?} is not ADDITIVE: passing frames through (set CONTRASTXR_FORCE=1 to act anyway)"
    ));
    false
}

fn capturing(s: &SessionState) -> bool {
    // Frames are numbered by the layer's processed count: capture [skip, skip + frames).
    s.settings
        .capture()
        .is_some_and(|c| s.processed >= c.skip && s.processed < c.skip + c.frames)
}

/// The newest background frame, or None (logged once: lost after frames came, or not yet).
fn background_frame(s: &SessionState) -> Option<camera::Frame> {
    // No source at all: why was logged when it failed to open.
    let bg = s.background.as_ref()?;
    let frame = bg.latest();
    if frame.is_none() && s.processed > 0 {
        log::once(
            "background-lost",
            &format!(
                "background {} lost: passing frames through untouched until it returns",
                bg.description()
            ),
        );
    } else if frame.is_none() {
        log::debug("no background frame yet: passing this frame through");
    }
    frame
}

/// The background's identity for the processor: a new camera frame, or new settings (the
/// background is preprocessed with the settings' blur and FoV mapping), count as new.
fn background_sequence(frame_sequence: u64, s: &Settings) -> u64 {
    frame_sequence.wrapping_add(s.generation << 40)
}

/// Enhances the held images of this frame and remembers its regions; any failure turns the
/// session into pass-through.
fn enhance_frame(s: &mut SessionState, info: &xr::FrameEndInfo) {
    // SAFETY: the app's frame end info, valid for this call.
    let subs = unsafe { sub_images(info, &s.settings) };
    let items = frame_items(&subs, &s.settings);
    s.regions_seen |= !subs.is_empty();
    s.last_blend_mode = Some(info.environment_blend_mode);
    process(s, items, Some(info.environment_blend_mode));
}

/// `process` with panics caught: a panic turns the session into pass-through.
fn guarded_process(
    s: &mut SessionState,
    items: Vec<WorkItem>,
    blend: Option<xr::EnvironmentBlendMode>,
) {
    let done = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| process(s, items, blend)));
    if done.is_err() {
        log::info(
            "internal error while enhancing: passing this session's frames through from now on",
        );
        s.processor = None;
    }
}

/// Enhances `items` in place on the app's queue; any failure turns the session into pass-through.
fn process(s: &mut SessionState, items: Vec<WorkItem>, blend: Option<xr::EnvironmentBlendMode>) {
    // Mode off: the app's frames untouched, no GPU work at all.
    if items.is_empty()
        || s.settings.params.mode == ViewMode::Off
        || s.processor.is_none()
        || !acts_on(s, blend)
    {
        return;
    }
    let Some(frame) = background_frame(s) else {
        return;
    };
    let capture = capturing(s);
    let params = s.settings.params.clone();
    let sequence = background_sequence(frame.sequence, &s.settings);
    let processor = s.processor.as_mut().expect("checked above");
    let wait = s.settings.wait_for_pipelines;
    // The indicator's time starts with the first enhanced frame, not while pipelines build.
    let ready = processor.pipelines_ready(&items, &params, wait);
    if ready.is_ok() {
        processor
            .indicator
            .timer
            .update(&s.settings, std::time::Instant::now());
    }
    let done = ready
        .and_then(|_| processor.process(&items, &frame.image, sequence, &params, (capture, wait)));
    match done {
        Ok(views) => {
            if s.processed == 0 {
                log_began(processor);
            }
            if capture {
                write_capture(s, &views, &frame.image);
            }
            s.processed += 1;
            log::once(
                "first-frame",
                &format!("processing frames ({} views per frame)", items.len()),
            );
        }
        Err(GpuError::Pending) => log::once(
            "pipelines-pending",
            "building the shader pipelines on the layer's own thread: frames go through untouched until they are ready",
        ),
        Err(e) => {
            log::info(&format!(
                "GPU work failed ({e}): passing this session's frames through from now on"
            ));
            s.processor = None;
        }
    }
}

/// The session's start-up in one line: when enhancement began and what the pipelines took.
fn log_began(processor: &Processor) {
    let after = processor.started.elapsed().as_secs_f64();
    let Some(r) = processor.build_report() else {
        return;
    };
    let cache = match &r.cache {
        Origin::Process => format!(
            "{} bytes from this process's earlier session",
            r.cache_bytes
        ),
        Origin::File(path) => format!("{} bytes from {}", r.cache_bytes, path.display()),
        Origin::Empty(None) => "empty".into(),
        Origin::Empty(Some(why)) => format!("empty ({why})"),
    };
    log::info(&format!(
        "enhancement began {after:.3} s after the session started ({} pipelines built in {:.3} s on the layer's thread; pipeline cache: {cache})",
        r.built,
        r.build_time.as_secs_f64()
    ));
    let each: Vec<String> = r
        .builds
        .iter()
        .map(|(name, t)| format!("{name} {:.0} ms", t.as_secs_f64() * 1e3))
        .collect();
    log::debug(&format!("pipeline builds: {}", each.join(", ")));
}

fn write_capture(
    s: &SessionState,
    views: &[super::processor::CapturedView],
    bg: &crate::image::RgbaImage,
) {
    let Some(c) = s.settings.capture() else {
        return;
    };
    for (k, v) in views.iter().enumerate() {
        let written = capture::write_view(&c.dir, s.processed, k, v, bg, &s.settings);
        if let Err(e) = written {
            log::once("capture-failed", &format!("capture failed: {e}"));
        }
    }
}

/// The layer's part of xrEndFrame: new settings, the enhancement of the held images, and
/// their release. The caller holds no lock.
fn layer_end_frame(session: xr::Session, s: &Mutex<SessionState>, info: *const xr::FrameEndInfo) {
    let mut s = lock(s);
    s.frames += 1;
    pick_up_settings(session, &mut s);
    // SAFETY: the app's frame end info (null is left for the runtime to reject).
    if let Some(info) = unsafe { info.as_ref() } {
        let done =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| enhance_frame(&mut s, info)));
        if done.is_err() {
            log::info(
                "internal error while enhancing: passing this session's frames through from now on",
            );
            s.processor = None;
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
    lock(s).processor = None;
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
        let Some(s) = state::session(session) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        let next = lock(&s).next;
        // A panic anywhere in the layer's part still forwards the app's frame.
        let done = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            layer_end_frame(session, &s, info)
        }));
        if done.is_err() {
            recover_end_frame(session, &s);
        }
        // SAFETY: forwarding the app's call (no layer lock is held while the runtime works).
        unsafe { (next.end_frame)(session, info) }
    })
}
