//! The session's life: wait for READY, begin, submit frames, request exit after N frames, end on
//! STOPPING, leave on EXITING. Every OpenXR or Vulkan failure ends the loop with an error.

use std::path::Path;
use std::time::{Duration, Instant};

use openxr as xr;

use crate::cli::{Layout, Options};
use crate::error::{fail, Context, Result};
use crate::gpu::Gpu;
use crate::pattern::Rows;
use crate::pattern_swapchain::PatternSwapchain;
use crate::scene::Scene;
use crate::timing::{Calls, Startup};

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;
/// A run fails when no frame has ended (xrEndFrame) for this long, the first one included: a
/// hung runtime or layer. Not a bound on the whole run: on a loaded machine a frame that waits
/// for shaders to build (`pipelines = "wait"`, a CPU driver compiling) takes many seconds, and
/// a slow run that keeps submitting frames is not a failure of the client's.
const STALL_TIMEOUT: Duration = Duration::from_secs(60);

#[derive(Default, Debug)]
pub struct Stats {
    /// xrEndFrame calls that carried the projection layer (and the quad layer with --quad).
    pub frames_submitted: u32,
    /// All xrEndFrame calls, including those with no layers when the runtime said not to render.
    pub frames_ended: u32,
    pub reached_focused: bool,
    /// With --timing: milliseconds inside xrEndFrame, and waiting for the queue after it.
    pub end_frame_ms: Vec<f64>,
    pub drain_ms: Vec<f64>,
    /// With --timing: every frame-loop call's wall time (the swapchains' added after each
    /// session).
    pub calls: Calls,
    /// With --timing: the wall time of the calls that create the instance, each session and
    /// its projection swapchain (start-up, kept apart from the frame loop's).
    pub create_calls: Calls,
    /// When the first session was created and its first frames ended (kept with or without
    /// --timing: a few numbers).
    pub startup: Startup,
    /// Resident memory and descriptors every 50 submitted frames.
    pub memory: Vec<crate::memory::Sample>,
    /// With --script: each op's XrResult, and whether the script ran to its end.
    pub script: Vec<String>,
    pub script_ran: bool,
    /// The run ended before --frames because --stop-file's file appeared.
    pub stopped: bool,
    /// A session ended before --frames because --until-modified's count was reached.
    pub reached_modified: bool,
    /// xrWaitFrame's predictedDisplayPeriod at the last frame, in ns.
    pub display_period_ns: i64,
}

/// A session's frames, whatever its graphics API: what [`run`] calls while the session runs.
pub trait Frames {
    type Api: xr::Graphics;
    fn session(&self) -> &xr::Session<Self::Api>;
    /// Runs --script's ops once, on a swapchain of its own; each op's result.
    fn script(&mut self, ops: &[crate::script::Op]) -> Result<Vec<String>>;
    /// One frame: xrWaitFrame, xrBeginFrame, the layers (none with --script), xrEndFrame;
    /// counts it in `stats`.
    fn frame(&mut self, options: &Options, stats: &mut Stats) -> Result<()>;
    /// With --check-untouched: this session's frames found changed so far.
    fn modified(&self) -> usize;
}

pub fn run<F: Frames>(
    instance: &xr::Instance,
    frames: &mut F,
    options: &Options,
    stats: &mut Stats,
) -> Result<()> {
    // Frames of earlier sessions (--sessions) count in `stats`, not towards this one.
    let first_frame = stats.frames_submitted;
    let mut progress = (stats.frames_ended, Instant::now());
    let mut events = xr::EventDataBuffer::new();
    let (mut running, mut exit_requested) = (false, false);
    loop {
        while let Some(event) = instance.poll_event(&mut events).ctx("xrPollEvent")? {
            match event {
                xr::Event::SessionStateChanged(change) => match change.state() {
                    xr::SessionState::READY => {
                        frames.session().begin(VIEW_TYPE).ctx("xrBeginSession")?;
                        running = true;
                    }
                    xr::SessionState::FOCUSED => stats.reached_focused = true,
                    xr::SessionState::STOPPING => {
                        frames.session().end().ctx("xrEndSession")?;
                        running = false;
                    }
                    xr::SessionState::EXITING => return Ok(()),
                    xr::SessionState::LOSS_PENDING => {
                        return fail("the runtime reported session loss")
                    }
                    _ => {}
                },
                xr::Event::InstanceLossPending(_) => {
                    return fail("the runtime reported instance loss")
                }
                _ => {}
            }
        }
        if stats.frames_ended != progress.0 {
            progress = (stats.frames_ended, Instant::now());
        }
        if progress.1.elapsed() > STALL_TIMEOUT {
            return fail(format!(
                "timed out after {} frames (wanted {}): none ended for {} s",
                stats.frames_submitted - first_frame,
                options.frames,
                STALL_TIMEOUT.as_secs()
            ));
        }
        if !running {
            std::thread::sleep(Duration::from_millis(10));
            continue;
        }
        if let (Some(ops), false) = (&options.script, stats.script_ran) {
            stats.script = frames.script(ops)?;
            stats.script_ran = true;
        }
        let done = if options.script.is_some() {
            stats.script_ran
        } else if stats.frames_submitted - first_frame >= options.frames {
            true
        } else if options
            .until_modified
            .is_some_and(|n| frames.modified() >= n as usize)
        {
            stats.reached_modified = true;
            true
        } else {
            let stop = options.stop_file.as_deref().is_some_and(Path::exists);
            stats.stopped |= stop;
            stop
        };
        if done && !exit_requested {
            frames
                .session()
                .request_exit()
                .ctx("xrRequestExitSession")?;
            exit_requested = true;
        }
        // Frames go on until STOPPING arrives, as the spec asks after xrRequestExitSession.
        let submitted = stats.frames_submitted;
        frames.frame(options, stats)?;
        if stats.frames_submitted != submitted && stats.frames_submitted.is_multiple_of(50) {
            stats
                .memory
                .push(crate::memory::Sample::now(stats.frames_submitted));
        }
    }
}

/// A Vulkan session's frames: the scene and the session's frame calls.
pub struct VulkanFrames<'s, 'a> {
    pub scene: &'s mut Scene<'a>,
    pub waiter: &'s mut xr::FrameWaiter,
    pub stream: &'s mut xr::FrameStream<xr::Vulkan>,
}

impl Frames for VulkanFrames<'_, '_> {
    type Api = xr::Vulkan;

    fn session(&self) -> &xr::Session<xr::Vulkan> {
        self.scene.session
    }

    fn script(&mut self, ops: &[crate::script::Op]) -> Result<Vec<String>> {
        crate::script::run(&*self.scene, ops)
    }

    fn frame(&mut self, options: &Options, stats: &mut Stats) -> Result<()> {
        frame(self.scene, self.waiter, self.stream, options, stats)
    }

    fn modified(&self) -> usize {
        let swapchains = std::iter::once(&self.scene.projection).chain(&self.scene.quad);
        swapchains.map(PatternSwapchain::modified).sum()
    }
}

fn frame(
    scene: &mut Scene<'_>,
    frame_waiter: &mut xr::FrameWaiter,
    frame_stream: &mut xr::FrameStream<xr::Vulkan>,
    options: &Options,
    stats: &mut Stats,
) -> Result<()> {
    let calls = &mut stats.calls;
    let state = calls
        .time("xrWaitFrame", || frame_waiter.wait())
        .ctx("xrWaitFrame")?;
    calls
        .time("xrBeginFrame", || frame_stream.begin())
        .ctx("xrBeginFrame")?;
    stats.frames_ended += 1;
    stats.display_period_ns = state.predicted_display_period.as_nanos();
    if !state.should_render || options.script.is_some() {
        // Apart from xrEndFrame: with no layers, a layer has nothing to do in it.
        let (time, mode) = (state.predicted_display_time, scene.blend_mode);
        return calls
            .time("xrEndFrame (no layers)", || {
                frame_stream.end(time, mode, &[])
            })
            .ctx("xrEndFrame (no layers)");
    }
    let (_, views) = scene
        .session
        .locate_views(VIEW_TYPE, state.predicted_display_time, scene.space)
        .ctx("xrLocateViews")?;
    render(scene, stats.frames_submitted)?;
    if options.pipelined {
        // The next frame's image, before this frame's xrEndFrame (a render thread running ahead).
        scene.ahead = Some(scene.projection.acquire()?);
    }
    let projection_views = projection_views(scene, &views, options.layout);
    let projection = xr::CompositionLayerProjection::new()
        .space(scene.space)
        .views(&projection_views);
    let quads = scene.quad.as_ref().map_or(Vec::new(), |q| {
        (0..options.quad_strips)
            .map(|k| quad_layer(q, scene.space, (k, options.quad_strips)))
            .collect()
    });
    let mut layers: Vec<&xr::CompositionLayerBase<'_, xr::Vulkan>> = vec![&projection];
    layers.extend(
        quads
            .iter()
            .map(|q| -> &xr::CompositionLayerBase<'_, xr::Vulkan> { q }),
    );
    let start = Instant::now();
    frame_stream
        .end(state.predicted_display_time, scene.blend_mode, &layers)
        .ctx("xrEndFrame")?;
    let ended = Instant::now();
    stats.startup.frame_ended(ended);
    if options.timing {
        time_end_frame(scene.gpu, stats, start, ended)?;
    }
    stats.frames_submitted += 1;
    Ok(())
}

/// Records the time inside xrEndFrame (`start` to `ended`), then drains the queue and records
/// how long that took: GPU work a layer queued in xrEndFrame and had not waited for.
fn time_end_frame(gpu: &Gpu, stats: &mut Stats, start: Instant, ended: Instant) -> Result<()> {
    gpu.wait_idle()?;
    let end_frame_ms = (ended - start).as_secs_f64() * 1e3;
    stats.end_frame_ms.push(end_frame_ms);
    stats.calls.record("xrEndFrame", end_frame_ms);
    stats.drain_ms.push(ended.elapsed().as_secs_f64() * 1e3);
    Ok(())
}

/// The two views of the projection layer, as laid out in its swapchain.
fn projection_views<'a>(
    scene: &'a Scene<'_>,
    views: &[xr::View],
    layout: Layout,
) -> Vec<xr::CompositionLayerProjectionView<'a, xr::Vulkan>> {
    projection_views_on(&scene.projection.handle, views, layout, scene.view_size)
}

/// The two views of a projection layer on `swapchain`, laid out with `layout`, each view
/// `view_size`.
pub fn projection_views_on<'a, G: xr::Graphics>(
    swapchain: &'a xr::Swapchain<G>,
    views: &[xr::View],
    layout: Layout,
    view_size: (u32, u32),
) -> Vec<xr::CompositionLayerProjectionView<'a, G>> {
    (0..2)
        .map(|i| {
            let (index, rect) = view_placement(layout, view_size, i);
            xr::CompositionLayerProjectionView::new()
                .pose(views[i as usize].pose)
                .fov(views[i as usize].fov)
                .sub_image(
                    xr::SwapchainSubImage::new()
                        .swapchain(swapchain)
                        .image_array_index(index)
                        .image_rect(rect),
                )
        })
        .collect()
}

/// Where view `i` is in the projection swapchain with `layout`: its array layer and its image
/// rect (side by side: the i-th half, the whole height, so the same rect whichever end of the
/// image its rows count from).
pub fn view_placement(layout: Layout, (w, h): (u32, u32), i: u32) -> (u32, xr::Rect2Di) {
    let (index, x) = match layout {
        Layout::Array => (i, 0),
        Layout::SideBySide => (0, (i * w) as i32),
    };
    let rect = xr::Rect2Di {
        offset: xr::Offset2Di { x, y: 0 },
        extent: xr::Extent2Di {
            width: w as i32,
            height: h as i32,
        },
    };
    (index, rect)
}

/// Fills the next image of every swapchain and releases them once the GPU is done.
fn render(scene: &mut Scene<'_>, frame: u32) -> Result<()> {
    let projection_index = match scene.ahead.take() {
        Some(index) => index,
        None => scene.projection.acquire()?,
    };
    let quad_index = scene.quad.as_mut().map(|q| q.acquire()).transpose()?;
    scene.gpu.submit_and_wait(|device, cmd| {
        scene
            .projection
            .record_upload(device, cmd, projection_index);
        if let (Some(quad), Some(index)) = (&scene.quad, quad_index) {
            quad.record_upload(device, cmd, index);
        }
    })?;
    scene.projection.finish_check(projection_index, frame);
    if let (Some(quad), Some(index)) = (scene.quad.as_mut(), quad_index) {
        quad.finish_check(index, frame);
    }
    scene.projection.release()?;
    scene.quad.as_mut().map(|q| q.release()).transpose()?;
    Ok(())
}

/// A quad 1.5 m in front of the viewer, 0.4 m wide, with the swapchain's aspect ratio; with
/// `(k, n)` strips, strip k of n of it (its rows and its part of the quad's height).
fn quad_layer<'a>(
    quad: &'a PatternSwapchain,
    space: &'a xr::Space,
    strip: (u32, u32),
) -> xr::CompositionLayerQuad<'a, xr::Vulkan> {
    let size = (quad.width, quad.height);
    quad_layer_on(&quad.handle, size, Rows::TopFirst, space, strip)
}

/// [`quad_layer`] on `swapchain` of `(width, height)`, whose image rect rows count from the
/// image's top (`Rows::TopFirst`, Vulkan) or its bottom (`Rows::BottomFirst`, OpenGL): strip 0
/// is the image's top rows either way.
pub fn quad_layer_on<'a, G: xr::Graphics>(
    swapchain: &'a xr::Swapchain<G>,
    (width, height): (u32, u32),
    rows: Rows,
    space: &'a xr::Space,
    (k, n): (u32, u32),
) -> xr::CompositionLayerQuad<'a, G> {
    let (top, bottom) = (height * k / n, height * (k + 1) / n);
    let y = match rows {
        Rows::TopFirst => top,
        Rows::BottomFirst => height - bottom,
    };
    let rect = xr::Rect2Di {
        offset: xr::Offset2Di { x: 0, y: y as i32 },
        extent: xr::Extent2Di {
            width: width as i32,
            height: (bottom - top) as i32,
        },
    };
    let metres = 0.4 / width as f32;
    let centre = (top + bottom) as f32 / 2.0 - height as f32 / 2.0;
    let pose = xr::Posef {
        orientation: xr::Quaternionf::IDENTITY,
        position: xr::Vector3f {
            x: 0.0,
            y: -centre * metres,
            z: -1.5,
        },
    };
    xr::CompositionLayerQuad::new()
        .space(space)
        .eye_visibility(xr::EyeVisibility::BOTH)
        .sub_image(
            xr::SwapchainSubImage::new()
                .swapchain(swapchain)
                .image_rect(rect),
        )
        .pose(pose)
        .size(xr::Extent2Df {
            width: 0.4,
            height: (bottom - top) as f32 * metres,
        })
}
