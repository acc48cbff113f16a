//! `--graphics opengl`: the run with an OpenGL session (XR_KHR_opengl_enable, the Xlib binding
//! on a GLX context, or with --gl-binding egl XR_MNDX_egl_enable's binding on an EGL context),
//! as OpenGL apps make one: the projection swapchain in the layout asked for
//! (an array of two layers, or one texture twice as wide with each view an imageRect half) and
//! with --quad a quad swapchain, the test pattern uploaded into each every frame (rows bottom
//! first: GL's image origin is the bottom left), and with --check-untouched each image read back
//! at its next acquire. The session's life, the views' placement, the quad's geometry and the
//! scripted calls are the Vulkan path's (frame_loop, script); only the images are GL's here.

use crate::churn::{self, Churner};
use crate::cli::{Layout, Options};
use crate::egl::{EsBound, GlSessionParts};
use crate::error::{fail, Context, Result};
use crate::frame_loop::{self, projection_views_on, quad_layer_on, Stats};
use crate::gl_binding::GlBinding;
use crate::gl_state::GlStateCheck;
use crate::gl_swapchain::{choose, gl_name, is_gl_depth, GlFormat, GlSwapchain};
use crate::glx::GlContext;
use crate::pattern::{LayerContent, Rows, Target};
use crate::run_report::Report;
use crate::script::ScriptApi;
use crate::x_errors::XErrors;
use openxr as xr;
use openxr::sys;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;

/// One instance with one OpenGL session (or --sessions of them) on this thread's context.
pub fn run(
    entry: &xr::Entry,
    options: &Options,
    report: &mut Report,
    stats: &mut Stats,
) -> Result<()> {
    let available = entry
        .enumerate_extensions()
        .ctx("xrEnumerateInstanceExtensionProperties")?;
    if !available.khr_opengl_enable {
        return fail("the runtime does not offer XR_KHR_opengl_enable");
    }
    let mut extensions = xr::ExtensionSet::default();
    extensions.khr_opengl_enable = true;
    if options.gl_binding == GlBinding::Egl {
        if !available.mndx_egl_enable {
            return fail("the runtime does not offer XR_MNDX_egl_enable (--gl-binding egl)");
        }
        extensions.mndx_egl_enable = true;
    }
    let instance = stats.create_calls.time("xrCreateInstance", || {
        crate::create_instance(entry, &extensions, report)
    })?;
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
    let gl = match options.gl_binding {
        GlBinding::Xlib => GlContext::new()?,
        GlBinding::Egl => crate::egl::context()?,
    };
    report.gl = Some(gl.describe());
    report.gl_binding = Some(gl.binding.name().to_string());
    let mut state = match options.check_gl_state {
        true => Some(GlStateCheck::new(&gl, &options.disturb_gl_state)?),
        false => None,
    };
    let mut egl_api = match options.egl_bind_es {
        true => Some(EsBound::bind(&gl)?),
        false => None,
    };
    let x_errors = match options.x_errors_elsewhere {
        true => Some(XErrors::start(&gl)?),
        false => None,
    };
    let mut result = Ok(());
    for _ in 0..options.sessions.max(1) {
        let session = (&gl, (&mut state, &mut egl_api), x_errors.as_ref());
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
    if let Some(x_errors) = x_errors {
        let (made, seen) = x_errors.finish();
        (report.x_errors_made, report.x_errors_seen) = (Some(made), Some(seen));
    }
    if let Some(state) = state {
        report.gl_state_checked = state.checked;
        report.gl_state_changed = state.changed;
    }
    if let Some(api) = egl_api {
        (report.egl_api_checked, report.egl_api_changed) = (Some(api.checked), Some(api.changed));
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
    (gl, (state, egl_api), x_errors): (&GlContext, Checks<'_>, Option<&XErrors>),
    options: &Options,
    report: &mut Report,
    stats: &mut Stats,
) -> Result<()> {
    let (session, mut waiter, mut stream) = stats
        .create_calls
        .time("xrCreateSession", || create_session(instance, system, gl))?;
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
    let view_size = match options.size {
        Some(size) => size,
        None => crate::recommended_size(instance, system)?,
    };
    report.view_size = [view_size.0, view_size.1];
    let space = session
        .create_reference_space(xr::ReferenceSpaceType::LOCAL, xr::Posef::IDENTITY)
        .ctx("xrCreateReferenceSpace")?;
    let (projection, quad) = stats.create_calls.time(
        "xrCreateSwapchain (projection and quad, with their images' set-up)",
        || layer_swapchains(&session, &format, view_size, options),
    )?;
    let churn = options.churn_swapchains.then(|| GlChurn {
        churner: Churner::default(),
        plan: churn::plan(
            format.internal,
            &offered,
            options.churn_formats,
            is_gl_depth,
        ),
        next: 0,
        churned: AtomicU32::new(0),
    });
    let mut frames = GlFrames {
        session: &session,
        space: &space,
        waiter: &mut waiter,
        stream: &mut stream,
        gl,
        format: &format,
        projection,
        quad,
        view_size,
        blend_mode,
        state,
        egl_api,
        churn,
        x_errors,
    };
    let result = frame_loop::run(instance, &mut frames, options, stats);
    report_checks(&frames, report);
    drop(frames);
    std::thread::sleep(Duration::from_millis(options.idle_ms));
    let t = Instant::now();
    drop((space, session, waiter, stream));
    report.teardown_ms.session(t.elapsed());
    result
}

/// The projection swapchain in the layout asked for (an array of two layers, or one texture
/// twice as wide), and with --quad the quad's, half the view's size.
fn layer_swapchains(
    session: &xr::Session<xr::OpenGL>,
    format: &GlFormat,
    (w, h): (u32, u32),
    options: &Options,
) -> Result<(GlSwapchain, Option<GlSwapchain>)> {
    let check = options.check_untouched;
    let projection = match options.layout {
        Layout::Array => {
            let views = [
                LayerContent::Whole(Target::View(0)),
                LayerContent::Whole(Target::View(1)),
            ];
            GlSwapchain::new(session, format, (w, h), &views, check)?
        }
        Layout::SideBySide => GlSwapchain::new(
            session,
            format,
            (2 * w, h),
            &[LayerContent::SideBySide],
            check,
        )?,
    };
    let quad = options
        .quad
        .then(|| {
            let content = [LayerContent::Whole(Target::Quad)];
            GlSwapchain::new(session, format, (w / 2, h / 2), &content, check)
        })
        .transpose()?;
    Ok((projection, quad))
}

/// What the session's frames found: swapchains churned, and with --check-untouched each
/// image's fate after its release.
fn report_checks(frames: &GlFrames, report: &mut Report) {
    if let Some(churn) = &frames.churn {
        report.swapchains_churned += churn.churned.load(Ordering::Relaxed);
    }
    for swapchain in std::iter::once(&frames.projection).chain(frames.quad.as_ref()) {
        if let Some(log) = &swapchain.check {
            report.frames_checked += log.checked;
            report.frames_modified.extend(&log.modified);
        }
    }
}

/// The session on `gl`, through the binding it was made for.
fn create_session(
    instance: &xr::Instance,
    system: xr::SystemId,
    gl: &GlContext,
) -> Result<GlSessionParts> {
    if gl.binding == GlBinding::Xlib {
        let info = xr::opengl::SessionCreateInfo::Xlib {
            x_display: gl.display.cast(),
            visualid: gl.visual_id,
            glx_fb_config: gl.fb_config.cast(),
            glx_drawable: gl.drawable,
            glx_context: gl.context.cast(),
        };
        // SAFETY: the GLX objects are this thread's current context and outlive the session.
        return unsafe { instance.create_session::<xr::OpenGL>(system, &info) }
            .ctx("xrCreateSession");
    }
    crate::egl::create_session(instance, system, gl)
}

/// An OpenGL session's frames, on the thread whose context the session was made with.
struct GlFrames<'s> {
    session: &'s xr::Session<xr::OpenGL>,
    space: &'s xr::Space,
    waiter: &'s mut xr::FrameWaiter,
    stream: &'s mut xr::FrameStream<xr::OpenGL>,
    gl: &'s GlContext,
    format: &'s GlFormat,
    projection: GlSwapchain,
    quad: Option<GlSwapchain>,
    view_size: (u32, u32),
    blend_mode: xr::EnvironmentBlendMode,
    /// With --check-gl-state: the state set right before xrEndFrame, checked right after.
    state: &'s mut Option<GlStateCheck>,
    /// With --egl-bind-es: the API bound on the thread, checked after xrEndFrame.
    egl_api: &'s mut Option<EsBound>,
    /// With --churn-swapchains: the swapchains made and destroyed between frames.
    churn: Option<GlChurn>,
    /// With --x-errors-elsewhere: the context is released around xrEndFrame.
    x_errors: Option<&'s XErrors>,
}

/// --churn-swapchains in an OpenGL session: one swapchain of the plan made (and the oldest
/// destroyed) before each frame, on the frame thread (churn.rs says why).
struct GlChurn {
    churner: Churner<xr::OpenGL>,
    plan: Vec<churn::Churn>,
    next: usize,
    churned: AtomicU32,
}

/// xrEndFrame with `layers`, inside --check-gl-state's set and check (and with
/// --x-errors-elsewhere with the context released).
fn end_frame(
    (stream, (state, egl_api), x_errors): EndFrame<'_>,
    (time, mode): (xr::Time, xr::EnvironmentBlendMode),
    layers: &[&xr::CompositionLayerBase<'_, xr::OpenGL>],
    frame: u32,
) -> Result<()> {
    if let Some(check) = state.as_mut() {
        check.before_end_frame(frame)?;
    }
    if let Some(api) = egl_api.as_ref() {
        api.bind_again();
    }
    if let Some(x) = x_errors {
        x.release_context();
    }
    let ended = stream.end(time, mode, layers).ctx("xrEndFrame");
    if let Some(x) = x_errors {
        x.take_context()?;
    }
    ended?;
    if let Some(check) = state.as_mut() {
        check.after_end_frame()?;
    }
    if let Some(api) = egl_api.as_mut() {
        api.check(frame);
    }
    Ok(())
}

/// What xrEndFrame goes through: the stream, --check-gl-state's check, --x-errors-elsewhere.
type EndFrame<'a> = (
    &'a mut xr::FrameStream<xr::OpenGL>,
    Checks<'a>,
    Option<&'a XErrors>,
);

/// What the app checks around each xrEndFrame: --check-gl-state's state, --egl-bind-es's API.
type Checks<'a> = (&'a mut Option<GlStateCheck>, &'a mut Option<EsBound>);

impl frame_loop::Frames for GlFrames<'_> {
    type Api = xr::OpenGL;

    fn session(&self) -> &xr::Session<xr::OpenGL> {
        self.session
    }

    fn script(&mut self, ops: &[crate::script::Op]) -> Result<Vec<String>> {
        crate::script::run(&*self, ops)
    }

    fn modified(&self) -> usize {
        let swapchains = std::iter::once(&self.projection).chain(&self.quad);
        swapchains
            .filter_map(|s| s.check.as_ref())
            .map(|c| c.modified.len())
            .sum()
    }

    fn frame(&mut self, options: &Options, stats: &mut Stats) -> Result<()> {
        if let Some(churn) = &mut self.churn {
            let c = &churn.plan[churn.next % churn.plan.len()];
            churn.next += 1;
            let step = churn.churner.step(self.session, c, &churn.churned);
            step.map_err(crate::error::ClientError)?;
        }
        let frame_state = stats
            .calls
            .time("xrWaitFrame", || self.waiter.wait())
            .ctx("xrWaitFrame")?;
        stats
            .calls
            .time("xrBeginFrame", || self.stream.begin())
            .ctx("xrBeginFrame")?;
        stats.frames_ended += 1;
        stats.display_period_ns = frame_state.predicted_display_period.as_nanos();
        let (time, frame) = (frame_state.predicted_display_time, stats.frames_ended - 1);
        if !frame_state.should_render || options.script.is_some() {
            let end = (
                &mut *self.stream,
                (&mut *self.state, &mut *self.egl_api),
                self.x_errors,
            );
            return end_frame(end, (time, self.blend_mode), &[], frame);
        }
        let (_, located) = self
            .session
            .locate_views(VIEW_TYPE, time, self.space)
            .ctx("xrLocateViews")?;
        self.projection.draw(self.gl, stats.frames_submitted)?;
        if let Some(quad) = &mut self.quad {
            quad.draw(self.gl, stats.frames_submitted)?;
        }
        let (projection, quad) = (&self.projection, self.quad.as_ref());
        let views =
            projection_views_on(&projection.handle, &located, options.layout, self.view_size);
        let projection = xr::CompositionLayerProjection::new()
            .space(self.space)
            .views(&views);
        let strips = quad.map_or(Vec::new(), |q| {
            (0..options.quad_strips)
                .map(|k| {
                    let size = q.texture.size;
                    let strip = (k, options.quad_strips);
                    quad_layer_on(&q.handle, size, Rows::BottomFirst, self.space, strip)
                })
                .collect()
        });
        let mut layers: Vec<&xr::CompositionLayerBase<'_, xr::OpenGL>> = vec![&projection];
        layers.extend(
            strips
                .iter()
                .map(|q| -> &xr::CompositionLayerBase<'_, xr::OpenGL> { q }),
        );
        let start = Instant::now();
        let end = (
            &mut *self.stream,
            (&mut *self.state, &mut *self.egl_api),
            self.x_errors,
        );
        end_frame(end, (time, self.blend_mode), &layers, frame)?;
        let ended = Instant::now();
        let ms = (ended - start).as_secs_f64() * 1e3;
        stats.calls.record("xrEndFrame", ms);
        stats.end_frame_ms.push(ms);
        if options.timing {
            // The GL work still queued after xrEndFrame (Monado finishes its own inside it).
            // SAFETY: glFinish of the current context, loaded by name with its C type.
            let finish: unsafe extern "C" fn() = unsafe { self.gl.function(c"glFinish") }?;
            // SAFETY: the context is current on this thread.
            unsafe { finish() };
            stats.drain_ms.push(ended.elapsed().as_secs_f64() * 1e3);
        }
        stats.startup.frame_ended(ended);
        stats.frames_submitted += 1;
        Ok(())
    }
}

/// An OpenGL session's script: swapchains in the session's format, cleared with
/// glClearTexImage in the client's context.
impl ScriptApi for GlFrames<'_> {
    type Api = xr::OpenGL;

    fn session(&self) -> &xr::Session<xr::OpenGL> {
        self.session
    }

    fn space(&self) -> &xr::Space {
        self.space
    }

    fn view_size(&self) -> (u32, u32) {
        self.view_size
    }

    fn blend_mode(&self) -> xr::EnvironmentBlendMode {
        self.blend_mode
    }

    fn swapchain_format(&self) -> (i64, sys::SwapchainUsageFlags) {
        let usage = sys::SwapchainUsageFlags::COLOR_ATTACHMENT | sys::SwapchainUsageFlags::SAMPLED;
        (i64::from(self.format.internal), usage)
    }

    fn images(&self, raw: sys::Swapchain) -> Result<Vec<u64>> {
        let blank = sys::SwapchainImageOpenGLKHR {
            ty: sys::SwapchainImageOpenGLKHR::TYPE,
            next: std::ptr::null_mut(),
            image: 0,
        };
        let images = crate::script::enumerate_images(self, raw, blank)?;
        Ok(images.iter().map(|i| u64::from(i.image)).collect())
    }

    fn clear(&self, image: u64) -> Result<()> {
        self.gl.clear(image as u32, crate::script::CLEAR_COLOUR)
    }
}
