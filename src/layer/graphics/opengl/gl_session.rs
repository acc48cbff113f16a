//! An OpenGL session's graphics: the GL engine, made on the app's context at the first frame
//! the layer acts on, every call inside that context (made current when it is not), and the
//! background texels uploaded once per new frame: a live source writes them into the engine's
//! mapped upload buffer on its own thread; a frame its source did not prepare, such as a
//! static one, is prepared once ([`super::gl_frame_call`], which does a frame call's work).

use super::app_context::{AppContext, Entered};
use super::gl_frame_call::{failed, gl_view, Frame};
use super::left_engines;
use super::program_builder::ProgramBuilder;
use crate::algorithm::params::Params;
use crate::config::InPlace;
use crate::gpu::core::blurred_texels::BlurredTexels;
use crate::gpu::core::{BackgroundInput, OverlayPixels};
use crate::gpu::opengl::{GlFormat, GlFrameRunner, GlView, ProgramBinaries};
use crate::gpu::PixelFormat;
use crate::layer::graphics::session_graphics::{
    image_handles, CapturedImage, NotDone, SessionGraphics, ViewImage,
};
use crate::layer::live_settings::Settings;
use crate::layer::log;
use openxr_sys as xr;
use std::cell::Cell;
use std::time::{Duration, Instant};

/// How long a frame with `wait_for_pipelines` waits for its programs.
const PROGRAM_WAIT: Duration = Duration::from_secs(60);

#[path = "session_programs.rs"]
mod programs;
use programs::Prepared;

pub struct GlSession {
    api: &'static str,
    context: Box<dyn AppContext>,
    /// Made at the first frame the layer acts on, with the app's context current.
    engine: Option<GlFrameRunner>,
    /// Texels prepared here for a frame that came without them, by its background sequence.
    texels: Option<(u64, BlurredTexels)>,
    /// When the first program build began, and when all were ready.
    build: (Option<Instant>, Option<Duration>),
    /// The view shapes (internal format, width, settings) whose programs swapchain creation
    /// asked for.
    warmed: Vec<(u32, u32, Params)>,
    /// Builds running on threads of the layer's own, one per set of programs the caches lacked.
    builders: Vec<ProgramBuilder>,
    /// Binaries of ended builds not yet handed to the engine (the app's context could not be
    /// made current when they ended): handed at the next call in it.
    unlinked: Vec<ProgramBinaries>,
    /// The time the longest build off the app's threads took (they run side by side).
    beside_time: Duration,
    /// The time swapchain creation spent building (or linking from the caches) and running
    /// the programs in the app's context.
    warm_up_time: Duration,
    /// The time frame calls spent on it after a build off the app's threads ended.
    after_builds_time: Duration,
    /// The `in_place` setting as the last swapchain creation saw it; GL needs no usage flag
    /// for it, so it is applied to the engine at each frame call.
    in_place: Cell<InPlace>,
}

// SAFETY: the binding's display and context pointers are used only on the app's threads that
// call into the layer, under the session's lock, as the runtime uses them.
unsafe impl Send for GlSession {}

impl GlSession {
    pub fn new(api: &'static str, context: Box<dyn AppContext>) -> GlSession {
        GlSession {
            api,
            context,
            engine: None,
            texels: None,
            build: (None, None),
            warmed: Vec::new(),
            builders: Vec::new(),
            unlinked: Vec::new(),
            beside_time: Duration::ZERO,
            warm_up_time: Duration::ZERO,
            after_builds_time: Duration::ZERO,
            in_place: Cell::new(InPlace::Auto),
        }
    }

    /// Runs `f` with the app's context current on this thread (and the engine made).
    fn in_context<R>(
        &mut self,
        f: impl FnOnce(&mut GlFrameRunner, &mut Option<(u64, BlurredTexels)>) -> Result<R, NotDone>,
    ) -> Result<R, NotDone> {
        // Current on another thread now is not for good: later frames try again.
        let entered = Entered::enter(&*self.context).map_err(NotDone::Unreachable)?;
        // SAFETY: the app's context is current on this thread.
        unsafe { left_engines::delete_left_on(self.context.key()) };
        let engine = match self.engine.take() {
            Some(engine) => Ok(engine),
            // SAFETY: the app's context is current on this thread; the engine's later calls
            // all happen inside `in_context`, with it current again.
            None => self
                .context
                .gl()
                .and_then(|gl| unsafe { GlFrameRunner::new(gl) }),
        };
        let result = match engine {
            Ok(mut engine) => {
                match self.in_place.get() {
                    InPlace::On => engine.set_in_place(true),
                    InPlace::Off => engine.set_in_place(false),
                    InPlace::Auto => engine.set_in_place(!engine.caps().software),
                }
                for binaries in self.unlinked.drain(..) {
                    engine.take_program_binaries(binaries);
                }
                if self.build.0.is_none() {
                    log::info(&format!(
                        "the app's OpenGL context: {} (OpenGL {}.{})",
                        engine.caps().driver,
                        engine.caps().version.0,
                        engine.caps().version.1
                    ));
                    self.build.0 = Some(Instant::now());
                }
                let r = f(&mut engine, &mut self.texels);
                self.engine = Some(engine);
                r
            }
            Err(e) => Err(failed(e)),
        };
        drop(entered);
        result
    }
}

impl SessionGraphics for GlSession {
    fn api(&self) -> &'static str {
        self.api
    }

    fn graphics(&self) -> &'static str {
        "opengl"
    }

    fn pixel_format(&self, api_format: i64) -> Option<PixelFormat> {
        let internal = u32::try_from(api_format).ok()?;
        GlFormat::of(internal).ok().map(|f| f.pixel)
    }

    fn format_name(&self, api_format: i64) -> String {
        match api_format as u32 {
            0x8058 => "GL_RGBA8".into(),
            0x8C43 => "GL_SRGB8_ALPHA8".into(),
            0x805B => "GL_RGBA16".into(),
            0x881A => "GL_RGBA16F".into(),
            0x8059 => "GL_RGB10_A2".into(),
            other => format!("GL format {other:#06x}"),
        }
    }

    fn needed_usage(&self) -> xr::SwapchainUsageFlags {
        // GL reads and writes a texture without usage flags.
        xr::SwapchainUsageFlags::EMPTY
    }

    fn in_place_usage(
        &self,
        _: PixelFormat,
        _: &xr::SwapchainCreateInfo,
        settings: &Settings,
    ) -> Option<xr::SwapchainUsageFlags> {
        // GL stores into a texture without usage flags: whether a view is stored in place is
        // the engine's choice at each frame (its format, the texture, the driver, this).
        self.in_place.set(settings.in_place);
        None
    }

    fn path_chosen_per_frame(&self) -> bool {
        true
    }

    unsafe fn images(
        &self,
        images: *const xr::SwapchainImageBaseHeader,
        count: usize,
    ) -> Option<Vec<u64>> {
        let ty = xr::StructureType::SWAPCHAIN_IMAGE_OPENGL_KHR;
        // SAFETY: the caller's contract, passed on.
        unsafe {
            image_handles(images, count, ty, |i: &xr::SwapchainImageOpenGLKHR| {
                u64::from(i.image)
            })
        }
    }

    fn request_shaders(
        &mut self,
        params: &Params,
        format: PixelFormat,
        width: u32,
        _: bool,
        wait: bool,
    ) {
        // At a loading-time call: programs the caches hold are linked and run once here, in
        // the app's context; the rest are built on a thread of the layer's own while the frames
        // pass through (or the first frame waits for them), or, where it cannot run, here.
        // What fails is met again, and said, by the frame calls.
        let Some(internal) = GlFormat::ALL
            .into_iter()
            .find(|&f| GlFormat::of(f).is_ok_and(|g| g.pixel == format))
        else {
            return;
        };
        match self.prepare_shape((internal, width), params, (true, wait)) {
            Prepared::Cached => {}
            Prepared::NoBuilder(why) => log::debug(&format!(
                "OpenGL programs built in the app's context: {why}"
            )),
            Prepared::Seen | Prepared::Building | Prepared::InContext | Prepared::Failed => return,
        }
        let took = self.warm_up(internal, width, params, "at swapchain creation");
        self.warm_up_time += took;
    }

    fn forget_swapchain(&mut self, _: u64) -> Result<(), String> {
        // The engine keeps buffers per view slot, none per swapchain.
        Ok(())
    }

    fn take_live_texels(&self, background: &crate::camera::Background) {
        // The engine's sink is one for its life (from the frame after the engine is made): the
        // source's thread writes each frame's texels into a mapped upload buffer.
        if let Some(engine) = &self.engine {
            background.deliver_texels_to(Some(engine.texel_sink()));
        }
    }

    fn ready(&mut self, views: &[ViewImage], params: &Params, wait: bool) -> Result<(), NotDone> {
        // A shape swapchain creation did not see (another width, changed settings) is built
        // off the app's threads too where it can be.
        for v in views {
            let (internal, width) = (v.api_format as u32, v.key.extent.0);
            let prepared = self.prepare_shape((internal, width), params, (false, wait));
            if let Prepared::NoBuilder(why) = prepared {
                log::debug(&format!(
                    "OpenGL programs built in frame calls on the app's context: {why}"
                ));
            }
        }
        self.await_builders(wait)?;
        let views: Vec<GlView> = views.iter().map(gl_view).collect();
        let since = Instant::now();
        let ready = self.in_context(|engine, _| loop {
            // SAFETY: inside `in_context`: the engine's context is current; the views name the
            // app's swapchain textures, which nothing else writes while the layer holds them.
            let ready = unsafe { engine.ready(&views, params) }.map_err(failed)?;
            if ready || !wait || since.elapsed() > PROGRAM_WAIT {
                return Ok(ready);
            }
        })?;
        if !ready {
            return Err(NotDone::Pending);
        }
        if self.build.1.is_none() {
            self.build.1 = self.build.0.map(|t| t.elapsed());
        }
        Ok(())
    }

    fn enhance(
        &mut self,
        views: &[ViewImage],
        background: BackgroundInput,
        params: &Params,
        overlay: Option<&OverlayPixels>,
        capture: bool,
    ) -> Result<Vec<CapturedImage>, NotDone> {
        let gl_views: Vec<GlView> = views.iter().map(gl_view).collect();
        self.in_context(|engine, prepared_here| {
            let frame = Frame {
                views,
                gl_views: &gl_views,
                background: &background,
                params,
            };
            // SAFETY: inside `in_context`: the app's context is current on this thread.
            unsafe { frame.enhance(engine, prepared_here, overlay, capture) }
        })
    }

    fn take_gpu_times(&mut self) -> Vec<Duration> {
        self.engine
            .as_mut()
            .map_or_else(Vec::new, GlFrameRunner::take_gpu_times)
    }

    fn pending_line(&self) -> &'static str {
        if !self.builders.is_empty() {
            return "building the OpenGL programs on a thread of the layer's own, in an OpenGL context of its own: frames go through untouched until they are ready";
        }
        "building the OpenGL programs from the frame calls on the app's context (started and polled where the driver compiles off the calling thread, else one per call, or from the program cache): frames go through untouched until they are ready"
    }

    fn build_summary(&self) -> Option<String> {
        let took = self.build.1?;
        let seconds = |d: Duration| d.as_secs_f64();
        let how = if !self.beside_time.is_zero() {
            format!(
                "built on a thread of the layer's own in {:.3} s while its frames passed through, then linked from the caches and run once in its context in {:.3} s",
                seconds(self.beside_time),
                seconds(self.after_builds_time)
            )
        } else if !self.warm_up_time.is_zero() {
            format!(
                "built and run once in the app's context as it made its swapchains ({:.3} s of xrCreateSwapchain)",
                seconds(self.warm_up_time)
            )
        } else {
            "built inside frame calls on the app's context".to_string()
        };
        Some(format!(
            "OpenGL programs ready {:.3} s after the layer first used the app's context, {how}",
            took.as_secs_f64()
        ))
    }

    fn frame_lines(&self, _: &[ViewImage], _: bool) -> Vec<(&'static str, String)> {
        let mut lines = Vec::new();
        if self
            .engine
            .as_ref()
            .is_some_and(|e| e.texels_from_source().0 > 0)
        {
            lines.push(("source-texels", "live frames' texels are written into a mapped pixel buffer on the camera's thread, before the frame call; the frame call uploads them to the background texture".to_string()));
        }
        let stored = self.engine.as_ref().map_or(&[][..], |e| e.last_in_place());
        let in_place = stored.iter().filter(|&&s| s).count();
        lines.push((
            "first-frame-path",
            format!(
                "views enhanced in the app's OpenGL context: {in_place} of {} in place through an image unit (an sRGB texture through a GL_RGBA8 view), the others through a buffer copy (a mutable sRGB texture, a CPU driver unless in_place = on, or in_place = off)",
                stored.len()
            ),
        ));
        lines
    }

    fn stop_building(&self) {
        // A build thread cannot be stopped midway (it is inside the driver's compiler): it
        // ends on its own, and its programs wait in the caches for the next session.
    }

    fn finish(mut self: Box<Self>) -> Result<(), String> {
        // A build still running goes on alone and ends by itself (its thread is detached).
        self.builders.clear();
        let Some(mut engine) = self.engine.take() else {
            return Ok(());
        };
        match self.context.enter() {
            Ok(previous) => {
                // SAFETY: the app's context is current on this thread.
                unsafe { engine.destroy() };
                self.context.leave(previous);
                Ok(())
            }
            Err(why) => {
                engine.save_program_cache();
                left_engines::keep(self.context.key(), engine);
                Err(format!(
                    "{why}: its OpenGL objects are deleted when the layer next has that context current"
                ))
            }
        }
    }
}

#[cfg(test)]
#[path = "gl_session_tests.rs"]
mod tests;
