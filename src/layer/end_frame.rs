//! A frame's work: which sub-images of the app's layers are enhanced (views and, when
//! configured, quads), with which camera mapping, and their enhancement on the app's queue,
//! at xrEndFrame or, for an image an app released ahead of its xrEndFrame, at that release.

use super::capture_files::{self, CaptureJob};
use super::capture_writer;
use super::ffi;
use super::graphics::{CapturedImage, NotDone, SessionGraphics, ViewImage};
use super::indicator;
use super::live_settings::Settings;
use super::log;
use super::motion::{self, FrameMotion};
use super::reach_advice;
use super::sources;
use super::state::{self, lock, SessionState, SwapchainState, ViewRegion};
use super::view_mappings::{self, ViewGeometry};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::ViewMode;
use crate::algorithm::perception::frequency::{view_pixels_per_degree, DEFAULT_PIXELS_PER_DEGREE};
use crate::camera;
use crate::gpu::core::blurred_texels::BlurTaps;
use crate::gpu::core::{BackgroundInput, OverlayPixels};
use crate::gpu::ViewKey;
use crate::image::RgbaImage;
use openxr_sys as xr;
use std::sync::Arc;
use std::time::Instant;

/// A sub-image a layer names, with its camera mapping when it is a projection view (each
/// view registered from its field of view and pose, see [`view_mappings`]; None for quads).
struct SubImage {
    sub: xr::SwapchainSubImage,
    mapping: Option<CameraMapping>,
    pixels_per_degree: Option<f64>,
}

/// The sub-images of the frame's layers that the layer enhances, with each projection view's
/// mapping and where it came from, for the log once the frame is enhanced (a frame passed
/// through has none to tell).
///
/// # Safety
/// `info` must be a valid XrFrameEndInfo (its layers and views valid structs).
unsafe fn sub_images(
    info: &xr::FrameEndInfo,
    settings: &Settings,
    motion: &mut FrameMotion,
    sources: &mut Vec<(usize, CameraMapping, view_mappings::Source)>,
) -> Vec<SubImage> {
    let mut out = Vec::new();
    if info.layers.is_null() {
        return out;
    }
    for i in 0..info.layer_count as usize {
        // SAFETY: layer_count valid pointers (the caller's contract).
        let layer = unsafe { *info.layers.add(i) };
        // SAFETY: each non-null entry points to a composition layer struct (the caller's contract).
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
            let mappings = motion.mappings(settings, &geometry, proj.space);
            for (k, (view, (mapping, source))) in views.iter().zip(mappings).enumerate() {
                sources.push((k, mapping, source));
                let (fov, width) = (view.fov, view.sub_image.image_rect.extent.width);
                out.push(SubImage {
                    sub: view.sub_image,
                    mapping: Some(mapping),
                    pixels_per_degree: Some(view_pixels_per_degree(
                        f64::from(fov.angle_left),
                        f64::from(fov.angle_right),
                        width.max(0) as u32,
                    )),
                });
            }
        } else if settings.quad_layers && base.ty == xr::StructureType::COMPOSITION_LAYER_QUAD {
            // SAFETY: the type tag says this is a quad layer.
            let sub = unsafe { (*(layer as *const xr::CompositionLayerQuad)).sub_image };
            out.push(SubImage {
                sub,
                mapping: None,
                pixels_per_degree: None,
            });
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
) -> Option<ViewImage> {
    let format = sc.info.pixel.filter(|_| sc.info.processable())?;
    let handle = sc.image(image as usize)?;
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
    let key = ViewKey {
        swapchain: swapchain.into_raw(),
        offset: (r.offset.x, r.offset.y),
        extent: (r.extent.width as u32, r.extent.height as u32),
        array_index: region.array_index,
    };
    // Quads, and whole images before the first xrEndFrame, take the manual mapping.
    let mapping = region
        .mapping
        .unwrap_or_else(|| view_mappings::quad_mapping(settings));
    Some(ViewImage {
        key,
        image: handle,
        api_format: sc.info.api_format,
        format,
        layered: sc.info.array_size > 1,
        in_place: sc.info.in_place,
        attachment: sc.info.attachment,
        sampled: sc.info.sampled,
        mapping,
        pixels_per_degree: region
            .pixels_per_degree
            .unwrap_or(DEFAULT_PIXELS_PER_DEGREE),
    })
}

/// Each enhanced sub-image's swapchain with its regions in this frame, in submission order.
fn regions_by_swapchain(subs: &[SubImage]) -> Vec<(xr::Swapchain, Vec<ViewRegion>)> {
    let mut out: Vec<(xr::Swapchain, Vec<ViewRegion>)> = Vec::new();
    for s in subs {
        let sub = &s.sub;
        let region = ViewRegion {
            rect: sub.image_rect,
            array_index: sub.image_array_index,
            mapping: s.mapping,
            pixels_per_degree: s.pixels_per_degree,
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
fn frame_items(subs: &[SubImage], settings: &Settings) -> Vec<ViewImage> {
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
            pixels_per_degree: None,
        })
        .collect()
}

/// Enhances image `image` of a swapchain now, before the app's xrEndFrame for it (a pipelined
/// app released it and took its next image first). The caller holds the session's lock, then
/// the swapchain's.
pub(super) fn enhance_ahead(
    s: &mut SessionState,
    sc: &SwapchainState,
    swapchain: xr::Swapchain,
    image: u32,
) {
    let items: Vec<ViewImage> = regions_ahead(s, sc)
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
        "environment blend mode {mode:?} is not ADDITIVE: passing frames through (see-through glasses whose runtime says opaque: set environment_blend_mode = \"additive\")"
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
fn background_frame(s: &mut SessionState) -> Option<camera::Frame> {
    // No source at all: why was logged when it failed to open.
    let bg = s.background.as_ref()?;
    // The frame this xrEndFrame's mappings were computed for, if any.
    let frame = s.frame_in_use.clone().or_else(|| bg.latest());
    let delivered = std::mem::replace(&mut s.background_delivered, frame.is_some());
    if frame.is_none() && (s.processed > 0 || delivered) {
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

/// The background's identity for the engine: a new camera frame, or new settings (the
/// background is preprocessed with the settings' blur and FoV mapping), count as new.
fn background_sequence(frame_sequence: u64, s: &Settings) -> u64 {
    frame_sequence.wrapping_add(s.generation << 40)
}

/// Enhances the held images of this frame and remembers its regions; any failure turns the
/// session into pass-through.
pub(super) fn enhance_frame(s: &mut SessionState, info: &xr::FrameEndInfo) {
    s.gpu_time.display_time(info.display_time.as_nanos());
    s.frame_in_use = s.background.as_ref().and_then(|bg| bg.latest());
    let captured_at = s.frame_in_use.as_ref().and_then(|f| f.captured_at);
    let mut moving = motion::at_end_frame(s, info.display_time, captured_at);
    let mut sources = Vec::new();
    // SAFETY: the app's frame end info, valid for this call.
    let subs = unsafe { sub_images(info, &s.settings, &mut moving, &mut sources) };
    moving.finish(s);
    let items = frame_items(&subs, &s.settings);
    s.regions_seen |= !subs.is_empty();
    s.last_blend_mode = Some(info.environment_blend_mode);
    let processed = s.processed;
    process(s, items, Some(info.environment_blend_mode));
    if s.processed > processed {
        for (k, mapping, source) in &sources {
            view_mappings::log_mapping(&s.settings, *k, mapping, source);
        }
    }
    s.frame_in_use = None;
}

/// `process` with panics contained: a panic turns the session into pass-through.
fn guarded_process(
    s: &mut SessionState,
    items: Vec<ViewImage>,
    blend: Option<xr::EnvironmentBlendMode>,
) {
    if let Err(panic) = ffi::contain("while enhancing", || process(s, items, blend)) {
        s.pass_through(&panic.to_string());
    }
}

/// Enhances `items` in place on the app's queue; any failure turns the session into pass-through.
fn process(s: &mut SessionState, items: Vec<ViewImage>, blend: Option<xr::EnvironmentBlendMode>) {
    // Mode off: the app's frames untouched, no GPU work at all.
    if items.is_empty()
        || s.settings.params.mode == ViewMode::Off
        || s.graphics.is_none()
        || !acts_on(s, blend)
    {
        sources::close_when_idle(s);
        return;
    }
    // After a try that could not reach the graphics, some frames pass through without one.
    if !s.retry.due() {
        return;
    }
    sources::open_when_needed(s);
    if let (Some(bg), Some(graphics)) = (&s.background, &s.graphics) {
        // Live frames come prepared for these settings from the source's thread (and, where
        // the graphics can take them, written straight into what the views sample).
        bg.prepare_with(BlurTaps::of(&s.settings.params));
        graphics.take_live_texels(bg);
    }
    let Some(frame) = background_frame(s) else {
        return;
    };
    // Captures make their report anyway; otherwise, once a minute from the first enhanced
    // frame, a read-back for the check of how much content is out of reach (reach_advice).
    let files = capturing(s);
    let check = !files && s.processed > 0 && reach_advice::read_back_due(&s.settings.params);
    let options = FrameOptions {
        capture: files || check,
        wait_for_pipelines: s.settings.wait_for_pipelines,
    };
    let sequence = background_sequence(frame.sequence, &s.settings);
    let prepared = frame.prepared.as_deref();
    let background = BackgroundInput {
        image: &frame.image,
        prepared,
        sequence,
    };
    let done = enhance(s, &items, background, options);
    let times = s.graphics.as_mut().expect("checked above").take_gpu_times();
    if let Some(line) = s.gpu_time.add(&times, Instant::now()) {
        log::info(&line);
    }
    let graphics = s.graphics.as_ref().expect("checked above");
    let lines = graphics.frame_lines(&items, prepared.is_some());
    match done {
        Ok(views) => {
            if s.processed == 0 {
                log_began(s.started, graphics.as_ref());
            }
            if files {
                write_capture(s, views, &frame.image);
            } else if check {
                log::debug(reach_advice::READ_BACK_LINE);
                for v in views {
                    let job = CaptureJob::check(v, frame.image.clone(), &s.settings.params);
                    capture_writer::write(job);
                }
            }
            s.processed += 1;
            s.retry.enhanced();
            log::once(
                "first-frame",
                &format!("processing frames ({} views per frame)", items.len()),
            );
            for (key, line) in lines {
                log::once(key, &line);
            }
        }
        Err(NotDone::Pending) => log::once("pipelines-pending", graphics.pending_line()),
        Err(NotDone::Skipped(why)) => log::once(&format!("skipped: {why}"), &why),
        Err(NotDone::Failed(e)) => s.pass_through(&e),
        Err(NotDone::Unreachable(why)) => s.retry.failed(&why),
    }
}

/// What a frame asks for besides the enhancement.
#[derive(Clone, Copy)]
struct FrameOptions {
    /// Read each view back before and after.
    capture: bool,
    /// Wait for shaders still being built instead of passing the frame through.
    wait_for_pipelines: bool,
}

/// Enhances the views with the newest background, and draws the indicator while it shows.
/// [`NotDone::Pending`] while a shader is still being built (frames pass through).
fn enhance(
    s: &mut SessionState,
    views: &[ViewImage],
    background: BackgroundInput,
    options: FrameOptions,
) -> Result<Vec<CapturedImage>, NotDone> {
    let graphics = s.graphics.as_mut().expect("checked by the caller");
    let params = &s.settings.params;
    graphics.ready(views, params, options.wait_for_pipelines)?;
    // The indicator's time starts with the first enhanced frame, not while shaders build.
    s.indicator.update(&s.settings, Instant::now());
    let text = s.indicator.showing(Instant::now()).map(str::to_string);
    let runs = |region| {
        text.as_deref()
            .map_or(Vec::new(), |t| indicator::runs(t, region))
    };
    let overlay = text.as_deref().map(|key| OverlayPixels {
        key,
        colour: indicator::COLOUR,
        runs: &runs,
    });
    graphics.enhance(views, background, params, overlay.as_ref(), options.capture)
}

/// The session's start-up in one line: when enhancement began and what its shaders took.
fn log_began(started: Instant, graphics: &dyn SessionGraphics) {
    let after = started.elapsed().as_secs_f64();
    let Some(built) = graphics.build_summary() else {
        return;
    };
    log::info(&format!(
        "enhancement began {after:.3} s after the session started ({built})"
    ));
}

/// Hands the frame's captured views to the capture thread: no file is touched here.
fn write_capture(s: &SessionState, views: Vec<CapturedImage>, bg: &Arc<RgbaImage>) {
    let Some(c) = s.settings.capture() else {
        return;
    };
    for (k, v) in views.into_iter().enumerate() {
        let mut extra = motion::capture_json(s.motion.views.get(k));
        if let Some(gpu) = s.gpu_time.session_json() {
            extra.insert("layer_gpu_ms".into(), gpu);
        }
        let Some(graphics) = s.graphics.as_ref() else {
            return;
        };
        let api = capture_files::Api {
            graphics: graphics.graphics(),
            format: graphics.format_name(v.view.api_format),
        };
        let job = CaptureJob::new(
            &c.dir,
            s.processed,
            k,
            v,
            &api,
            bg.clone(),
            &s.settings,
            extra,
        );
        capture_writer::write(job);
    }
}
