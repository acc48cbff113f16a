//! `--graphics opengl`: the run with an OpenGL session (XR_KHR_opengl_enable, the Xlib binding
//! on a GLX context), as OpenGL apps make one: one array swapchain of two layers, the test
//! pattern uploaded into each view's layer every frame (rows bottom first: GL's image origin is
//! the bottom left), and with --check-untouched each image read back at its next acquire.

use crate::cli::{Layout, Options};
use crate::error::{fail, Context, Result};
use crate::frame_loop::Stats;
use crate::gl_state::GlStateCheck;
use crate::glx::{self, GlContext};
use crate::pattern::{self, Target};
use crate::run_report::Report;
use crate::swapchain_format::SwapchainFormat;
use openxr as xr;
use std::time::{Duration, Instant};

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;

/// A swapchain format by its GL internal format, with the client's encoding of it (the same
/// bytes as the Vulkan format of that layout) and the (format, type) of its pixel transfers.
struct GlFormat {
    internal: u32,
    encoding: SwapchainFormat,
    transfer: (u32, u32),
}

/// The GL colour formats the client fills.
fn gl_formats() -> [GlFormat; 5] {
    let by = |name| SwapchainFormat::by_name(name).expect("a known format");
    [
        GlFormat {
            internal: 0x8C43,
            encoding: by("R8G8B8A8_SRGB"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_BYTE),
        },
        GlFormat {
            internal: 0x8058,
            encoding: by("R8G8B8A8_UNORM"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_BYTE),
        },
        GlFormat {
            internal: 0x881A,
            encoding: by("R16G16B16A16_SFLOAT"),
            transfer: (glx::GL_RGBA, glx::GL_HALF_FLOAT),
        },
        GlFormat {
            internal: 0x805B,
            encoding: by("R16G16B16A16_UNORM"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_SHORT),
        },
        GlFormat {
            internal: 0x8059,
            encoding: by("A2B10G10R10_UNORM"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_INT_2_10_10_10_REV),
        },
    ]
}

/// The GL name of a format (for --list-formats and errors).
fn gl_name(internal: u32) -> String {
    match internal {
        0x8C43 => "GL_SRGB8_ALPHA8".into(),
        0x8058 => "GL_RGBA8".into(),
        0x881A => "GL_RGBA16F".into(),
        0x805B => "GL_RGBA16".into(),
        0x8059 => "GL_RGB10_A2".into(),
        0x81A5 => "GL_DEPTH_COMPONENT16".into(),
        0x8CAC => "GL_DEPTH_COMPONENT32F".into(),
        0x88F0 => "GL_DEPTH24_STENCIL8".into(),
        0x8CAD => "GL_DEPTH32F_STENCIL8".into(),
        other => format!("GL format 0x{other:04x}"),
    }
}

/// One instance with one OpenGL session (or --sessions of them) on this thread's context.
pub fn run(
    entry: &xr::Entry,
    options: &Options,
    report: &mut Report,
    stats: &mut Stats,
) -> Result<()> {
    if options.layout != Layout::Array || options.quad {
        return fail("--graphics opengl supports --layout array without --quad");
    }
    let available = entry
        .enumerate_extensions()
        .ctx("xrEnumerateInstanceExtensionProperties")?;
    if !available.khr_opengl_enable {
        return fail("the runtime does not offer XR_KHR_opengl_enable");
    }
    let mut extensions = xr::ExtensionSet::default();
    extensions.khr_opengl_enable = true;
    let instance = crate::create_instance(entry, &extensions, report)?;
    let system = instance
        .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
        .ctx("xrGetSystem")?;
    let blend_mode = *instance
        .enumerate_environment_blend_modes(system, VIEW_TYPE)
        .ctx("xrEnumerateEnvironmentBlendModes")?
        .first()
        .ok_or_else(|| crate::error::ClientError("the runtime offers no blend mode".into()))?;
    report.blend_mode = format!("{blend_mode:?}");
    // The spec asks for the requirements before the session.
    instance
        .graphics_requirements::<xr::OpenGL>(system)
        .ctx("xrGetOpenGLGraphicsRequirementsKHR")?;
    let gl = GlContext::new()?;
    report.gl = Some(gl.describe());
    let mut state = match options.check_gl_state {
        true => Some(GlStateCheck::new(&gl, &options.disturb_gl_state)?),
        false => None,
    };
    let mut result = Ok(());
    for _ in 0..options.sessions.max(1) {
        let session = (&gl, &mut state);
        result = run_session(
            &instance, system, blend_mode, session, options, report, stats,
        );
        if result.is_err() {
            break;
        }
        report.sessions_run += 1;
        report
            .sessions
            .push(crate::run_report::Sample::now(stats.frames_submitted));
        if options.list_formats {
            break;
        }
    }
    if let Some(state) = state {
        report.gl_state_checked = state.checked;
        report.gl_state_changed = state.changed;
    }
    result?;
    let t = Instant::now();
    drop(instance);
    report.teardown_ms.instance(t.elapsed());
    Ok(())
}

fn run_session(
    instance: &xr::Instance,
    system: xr::SystemId,
    blend_mode: xr::EnvironmentBlendMode,
    (gl, state): (&GlContext, &mut Option<GlStateCheck>),
    options: &Options,
    report: &mut Report,
    stats: &mut Stats,
) -> Result<()> {
    let info = xr::opengl::SessionCreateInfo::Xlib {
        x_display: gl.display.cast(),
        visualid: gl.visual_id,
        glx_fb_config: gl.fb_config.cast(),
        glx_drawable: gl.drawable,
        glx_context: gl.context.cast(),
    };
    // SAFETY: the GLX objects are this thread's current context and outlive the session.
    let (session, mut waiter, mut stream) =
        unsafe { instance.create_session::<xr::OpenGL>(system, &info) }.ctx("xrCreateSession")?;
    stats.startup.session_created();
    let offered = session
        .enumerate_swapchain_formats()
        .ctx("xrEnumerateSwapchainFormats")?;
    if options.list_formats {
        offered.iter().for_each(|&f| println!("{}", gl_name(f)));
        return Ok(());
    }
    let format = choose(options.format, &offered)?;
    report.format = gl_name(format.internal);
    let size = match options.size {
        Some(size) => size,
        None => {
            let views = instance
                .enumerate_view_configuration_views(system, VIEW_TYPE)
                .ctx("xrEnumerateViewConfigurationViews")?;
            (
                views[0].recommended_image_rect_width,
                views[0].recommended_image_rect_height,
            )
        }
    };
    report.view_size = [size.0, size.1];
    let space = session
        .create_reference_space(xr::ReferenceSpaceType::LOCAL, xr::Posef::IDENTITY)
        .ctx("xrCreateReferenceSpace")?;
    let mut swapchain = session
        .create_swapchain(&xr::SwapchainCreateInfo {
            create_flags: xr::SwapchainCreateFlags::EMPTY,
            usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT
                | xr::SwapchainUsageFlags::SAMPLED,
            format: format.internal,
            sample_count: 1,
            width: size.0,
            height: size.1,
            face_count: 1,
            array_size: 2,
            mip_count: 1,
        })
        .ctx("xrCreateSwapchain")?;
    let images = swapchain
        .enumerate_images()
        .ctx("xrEnumerateSwapchainImages")?;
    let mut views = Views::new(&format, size, images.len(), options.check_untouched);
    let result = frames(
        &session,
        &space,
        (&mut waiter, &mut stream),
        &mut swapchain,
        (gl, &images, &mut views),
        state,
        blend_mode,
        options,
        stats,
    );
    report.frames_checked += views.checked;
    report.frames_modified.extend(&views.modified);
    drop(swapchain);
    std::thread::sleep(Duration::from_millis(options.idle_ms));
    let t = Instant::now();
    drop((space, session, waiter, stream));
    report.teardown_ms.session(t.elapsed());
    result
}

fn choose(wanted: Option<SwapchainFormat>, offered: &[u32]) -> Result<GlFormat> {
    // In the runtime's order: `auto` takes the first one the client can fill.
    let known = offered
        .iter()
        .filter_map(|&o| gl_formats().into_iter().find(|f| f.internal == o));
    let found = match wanted {
        Some(w) => known.into_iter().find(|f| f.encoding == w),
        None => known.into_iter().next(),
    };
    found.ok_or_else(|| {
        let names: Vec<_> = offered.iter().map(|&f| gl_name(f)).collect();
        crate::error::ClientError(format!(
            "no wanted GL format among those offered: {}",
            names.join(" ")
        ))
    })
}

/// The pattern of each view (rows bottom first) and, with --check-untouched, what each image
/// held when it was released.
struct Views {
    pattern: [Vec<u8>; 2],
    transfer: (u32, u32),
    texel_bytes: usize,
    size: (u32, u32),
    /// Per swapchain image: the frame whose pattern it was released with, if checking.
    released: Vec<Option<u32>>,
    check: bool,
    checked: u32,
    modified: Vec<u32>,
    scratch: Vec<u8>,
}

impl Views {
    fn new(format: &GlFormat, (w, h): (u32, u32), images: usize, check: bool) -> Views {
        let view = |v: u32| {
            let mut bytes =
                Vec::with_capacity((w * h) as usize * format.encoding.bytes_per_texel());
            // Bottom row first: what the app draws at the top of its view is the last row.
            for y in (0..h).rev() {
                for x in 0..w {
                    format
                        .encoding
                        .encode(pattern::texel(Target::View(v), x, y, w, h), &mut bytes);
                }
            }
            bytes
        };
        Views {
            pattern: [view(0), view(1)],
            transfer: format.transfer,
            texel_bytes: format.encoding.bytes_per_texel(),
            size: (w, h),
            released: vec![None; images],
            check,
            checked: 0,
            modified: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// Checks image `index` against what it was released with, then writes this frame's views.
    fn draw(&mut self, gl: &GlContext, image: u32, index: usize, frame: u32) -> Result<()> {
        if let (true, Some(was)) = (self.check, self.released[index]) {
            for layer in 0..2 {
                gl.read(
                    image,
                    layer,
                    self.size,
                    self.transfer,
                    &mut self.scratch,
                    self.texel_bytes,
                )?;
                if self.scratch != self.pattern[layer as usize] && !self.modified.contains(&was) {
                    self.modified.push(was);
                }
            }
            self.checked += 1;
        }
        for layer in 0..2 {
            gl.upload(
                image,
                layer,
                self.size,
                self.transfer,
                &self.pattern[layer as usize],
            )?;
        }
        self.released[index] = Some(frame);
        Ok(())
    }
}

#[allow(clippy::too_many_arguments)]
fn frames(
    session: &xr::Session<xr::OpenGL>,
    space: &xr::Space,
    (waiter, stream): (&mut xr::FrameWaiter, &mut xr::FrameStream<xr::OpenGL>),
    swapchain: &mut xr::Swapchain<xr::OpenGL>,
    (gl, images, views): (&GlContext, &[u32], &mut Views),
    state: &mut Option<GlStateCheck>,
    blend_mode: xr::EnvironmentBlendMode,
    options: &Options,
    stats: &mut Stats,
) -> Result<()> {
    let deadline =
        Instant::now() + Duration::from_secs(30) + Duration::from_millis(200) * options.frames;
    let first = stats.frames_submitted;
    let mut events = xr::EventDataBuffer::new();
    let (mut running, mut exit_requested) = (false, false);
    let instance = session.instance();
    loop {
        while let Some(event) = instance.poll_event(&mut events).ctx("xrPollEvent")? {
            if let xr::Event::SessionStateChanged(change) = event {
                match change.state() {
                    xr::SessionState::READY => {
                        session.begin(VIEW_TYPE).ctx("xrBeginSession")?;
                        running = true;
                    }
                    xr::SessionState::FOCUSED => stats.reached_focused = true,
                    xr::SessionState::STOPPING => {
                        session.end().ctx("xrEndSession")?;
                        running = false;
                    }
                    xr::SessionState::EXITING => return Ok(()),
                    xr::SessionState::LOSS_PENDING => {
                        return fail("the runtime reported session loss")
                    }
                    _ => {}
                }
            }
        }
        if Instant::now() > deadline {
            return fail(format!(
                "timed out after {} frames",
                stats.frames_submitted - first
            ));
        }
        if !running {
            std::thread::sleep(Duration::from_millis(10));
            continue;
        }
        if stats.frames_submitted - first >= options.frames && !exit_requested {
            session.request_exit().ctx("xrRequestExitSession")?;
            exit_requested = true;
        }
        let frame_state = stats
            .calls
            .time("xrWaitFrame", || waiter.wait())
            .ctx("xrWaitFrame")?;
        stats
            .calls
            .time("xrBeginFrame", || stream.begin())
            .ctx("xrBeginFrame")?;
        stats.frames_ended += 1;
        // With --check-gl-state: the state set right before xrEndFrame, checked right after.
        let frame = stats.frames_ended - 1;
        if !frame_state.should_render {
            if let Some(check) = state.as_mut() {
                check.before_end_frame(frame)?;
            }
            stream
                .end(frame_state.predicted_display_time, blend_mode, &[])
                .ctx("xrEndFrame")?;
            if let Some(check) = state.as_mut() {
                check.after_end_frame()?;
            }
            continue;
        }
        let (_, located) = session
            .locate_views(VIEW_TYPE, frame_state.predicted_display_time, space)
            .ctx("xrLocateViews")?;
        let index = swapchain.acquire_image().ctx("xrAcquireSwapchainImage")? as usize;
        swapchain
            .wait_image(xr::Duration::INFINITE)
            .ctx("xrWaitSwapchainImage")?;
        views.draw(gl, images[index], index, stats.frames_submitted)?;
        swapchain.release_image().ctx("xrReleaseSwapchainImage")?;
        let rect = xr::Rect2Di {
            offset: xr::Offset2Di { x: 0, y: 0 },
            extent: xr::Extent2Di {
                width: views.size.0 as i32,
                height: views.size.1 as i32,
            },
        };
        let projection_views: Vec<_> = (0..2)
            .map(|v| {
                xr::CompositionLayerProjectionView::new()
                    .pose(located[v].pose)
                    .fov(located[v].fov)
                    .sub_image(
                        xr::SwapchainSubImage::new()
                            .swapchain(swapchain)
                            .image_array_index(v as u32)
                            .image_rect(rect),
                    )
            })
            .collect();
        let projection = xr::CompositionLayerProjection::new()
            .space(space)
            .views(&projection_views);
        if let Some(check) = state.as_mut() {
            check.before_end_frame(frame)?;
        }
        let start = Instant::now();
        stream
            .end(
                frame_state.predicted_display_time,
                blend_mode,
                &[&projection],
            )
            .ctx("xrEndFrame")?;
        let ended = Instant::now();
        if let Some(check) = state.as_mut() {
            check.after_end_frame()?;
        }
        stats
            .calls
            .record("xrEndFrame", (ended - start).as_secs_f64() * 1e3);
        stats.end_frame_ms.push((ended - start).as_secs_f64() * 1e3);
        if options.timing {
            // The GL work still queued after xrEndFrame (Monado finishes its own inside it).
            // SAFETY: glFinish of the current context, loaded by name with its C type.
            let finish: unsafe extern "C" fn() = unsafe { gl.function(c"glFinish") }?;
            // SAFETY: the context is current on this thread.
            unsafe { finish() };
            stats.drain_ms.push(ended.elapsed().as_secs_f64() * 1e3);
        }
        stats.startup.frame_ended(ended);
        stats.frames_submitted += 1;
    }
}
