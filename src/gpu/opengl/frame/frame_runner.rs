//! The per-view recipe on the app's GL context, called on the app's thread with its context
//! current (inside xrEndFrame for the layer, after the app's rendering). The passes of the
//! method (classify, finish_tiles, enhance over the listed tiles through an indirect dispatch)
//! run on the view's region in one of two ways:
//! - in place, as the Vulkan in-place path runs them: the app's texture is bound to an image
//!   unit and the programs load and store its texels, in the storage texel format of the same
//!   size the shaders take (GL_RGBA8, GL_RGBA16F, GL_RGBA16 as GL_RGBA16UI, GL_RGB10_A2 as
//!   GL_R32UI: image units take any format of the texture's size); an sRGB texture, which no
//!   image unit takes, through a GL_RGBA8 texture view of it, which GL allows over immutable
//!   storage, the kind a runtime imports (the programs apply the sRGB curve themselves). No
//!   copy at all.
//! - through a buffer, for a mutable sRGB texture, on a CPU driver unless `in_place = on` (there image load/store
//!   costs more than the copy, a memcpy), or with `in_place = off`: the region is copied into a buffer object
//!   (glGetTextureSubImage into a pixel pack buffer), the passes run on it as the Vulkan copy
//!   path runs them, and it is copied back (glTextureSubImage from a pixel unpack buffer). The
//!   byte layouts are the Vulkan copy path's, so the same shaders read them.
//!
//! GL's images start at the bottom row: the buffer holds the view's rows bottom first, and the
//! view's camera mapping is turned to take buffer rows (`rows_from_bottom`), so each pixel
//! samples the background behind it with no change to the shaders.
//!
//! Everything the recipe changes of the app's GL state is put back (state_guard.rs), and it calls no
//! glGetError; the only error it can leave to the app is a driver's GL_OUT_OF_MEMORY while it
//! allocates (state_guard.rs says when).

use super::frame_view::GlView;
use super::state_guard::{DebugOutputOff, SavedState};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::{Params, ViewMode};
use crate::gpu::core::interface::in_place_texel;
use crate::gpu::core::perceptual_words::PerceptualWords;
use crate::gpu::core::plan::{view_steps, NoPlan};
use crate::gpu::core::{CameraRect, ClassifyChoice, CubeRoots};
use crate::gpu::opengl::conv::{image_unit_format, GlFormat};
use crate::gpu::opengl::device::caps::Caps;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;
use crate::gpu::opengl::pipelines::{ProgramBinaries, Programs};
use crate::gpu::opengl::texels::TexelBuffers;

/// What a call did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The views are enhanced (or, in mode off, left as they are).
    Enhanced,
    /// Programs the views need are still being built: the frame passed through untouched.
    Compiling,
}

/// The background the views sample: an RGBA32UI texture (the layout of `BlurredTexels`), filled
/// from the mapped upload buffers (texel_buffers.rs).
pub(super) struct Background {
    pub(super) texture: u32,
    pub(super) size: (u32, u32),
    /// The `BlurredTexels::serial` the texture holds, and of which texels.
    pub(super) holds: Option<(u64, CameraRect)>,
}

/// How the programs store into a view's texture in place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreThrough {
    /// The texture itself, bound to the image unit in this format of its size.
    Texture(gl::Enum),
    /// A texture view of it in this format (an sRGB texture as GL_RGBA8).
    View(gl::Enum),
}

/// A view slot's buffers, kept across frames and remade only when a view needs more.
#[derive(Default)]
pub(super) struct ViewBuffers {
    pub(super) pixels: u32,
    pub(super) pixel_capacity: usize,
    pub(super) tiles: u32,
    pub(super) tile_capacity: usize,
    /// The perceptual model of the view's frame (`perceptual` method; 0 until one needs it).
    pub(super) perceptual: u32,
    pub(super) perceptual_words: PerceptualWords,
}

pub struct GlFrameRunner {
    pub(super) gl: Gl,
    pub(super) caps: Caps,
    pub(super) programs: Programs,
    pub(super) background: Option<Background>,
    /// Where the background's texels are uploaded from; a live source writes them there.
    pub(super) texel_buffers: TexelBuffers,
    pub(super) views: Vec<ViewBuffers>,
    /// An empty framebuffer object bound while the recipe runs: with the app's window-system
    /// framebuffer bound, a dispatch makes Mesa's software drivers validate it, after which
    /// the app's next glFinish presents its front buffer (an X error on a GLX pbuffer). Made
    /// with the engine and labelled `label`: framebuffers are never shared between contexts,
    /// so finding it under that label tells that the current context is the engine's own.
    pub(super) framebuffer: u32,
    /// The framebuffer's label, unique to this engine in the process.
    label: String,
    /// Whether views may be enhanced in place: by default on a GPU, not on a CPU driver
    /// (`Caps::software`); the `in_place` setting's `on` and `off` decide otherwise.
    pub(super) in_place: bool,
    /// Which of the last enhanced views were stored in place (the others through a buffer).
    pub(super) last_in_place: Vec<bool>,
    /// The benchmark's ablations (interface.rs ABLATE_*) and `classify` (variant_programs.rs):
    /// 0 and the method's own but for `contrastxr bench --ablate`.
    pub(super) ablate: u32,
    pub(super) classify: ClassifyChoice,
    /// How views take the CIELAB cube roots: `pow` on a GPU (`CubeRoots::for_device`).
    pub(super) roots: CubeRoots,
    /// Each frame's GPU time, from timestamp queries around its work.
    pub(super) times: super::frame_times::FrameTimes,
}

/// The mapping of a view whose rows are stored bottom first: buffer row v' is display row
/// 1 - v, so camera = M (u, 1 - v', 1) = M F (u, v', 1).
pub fn rows_from_bottom(m: &CameraMapping) -> CameraMapping {
    CameraMapping {
        rows: m.rows.map(|r| [r[0], -r[1], r[1] + r[2]]),
    }
}

/// Whether rows of `width` pixels are whole 16-byte groups (the wide access).
pub(in crate::gpu::opengl) fn rows_aligned(width: u32, bytes_per_pixel: u32) -> bool {
    (width * bytes_per_pixel).is_multiple_of(16)
}

pub(super) fn texture_level_int(g: &Gl, texture: u32, pname: gl::Enum) -> i32 {
    let mut v = 0;
    // SAFETY: a texture name of this context (the caller's contract), level 0, a valid pname.
    unsafe { (g.get_texture_level_parameteriv)(texture, 0, pname, &mut v) };
    v
}

impl GlFrameRunner {
    /// An engine on the context current on this thread, or why that context cannot run it.
    /// Builds nothing yet: the programs are built by the frame calls that need them.
    ///
    /// # Safety
    /// A GL context is current on this thread, `gl` was loaded for it (or a context of the same
    /// driver), and every later call is made with that same context current.
    pub unsafe fn new(gl: Gl) -> Result<GlFrameRunner, GlError> {
        let caps = Caps::check(&gl)?;
        // SAFETY: the context is current (this call's contract) and 4.5 (Caps).
        let _quiet = unsafe { DebugOutputOff::new(&gl) };
        static ENGINES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = ENGINES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let label = format!("contrastxr engine {}.{n}", std::process::id());
        let mut framebuffer = 0;
        // SAFETY: the context is current (this call's contract) and 4.5 (Caps): one name into
        // a valid output, deleted in `destroy`; a 1x1 default size makes it complete without
        // attachments, so validating it raises no debug message in the app's callback; the
        // label's length is given.
        unsafe {
            (gl.create_framebuffers)(1, &mut framebuffer);
            for p in [
                gl::FRAMEBUFFER_DEFAULT_WIDTH,
                gl::FRAMEBUFFER_DEFAULT_HEIGHT,
            ] {
                (gl.named_framebuffer_parameteri)(framebuffer, p, 1);
            }
            let text = label.as_bytes();
            (gl.object_label)(
                gl::FRAMEBUFFER,
                framebuffer,
                text.len() as i32,
                text.as_ptr().cast(),
            );
        }
        Ok(GlFrameRunner {
            programs: Programs::new(&caps),
            in_place: !caps.software,
            roots: CubeRoots::for_device(caps.software),
            gl,
            caps,
            background: None,
            texel_buffers: TexelBuffers::default(),
            views: Vec::new(),
            framebuffer,
            label,
            last_in_place: Vec::new(),
            ablate: 0,
            classify: ClassifyChoice::Own,
            times: Default::default(),
        })
    }

    /// Whether the context current on this thread is the one the engine was made in (its
    /// framebuffer is there under its label), so that its names are its objects: a context
    /// destroyed meanwhile, and another made at the same address, fail this. Raises no error.
    ///
    /// # Safety
    /// A context of the engine's driver is current on this thread.
    pub unsafe fn made_in_current_context(&self) -> bool {
        let g = &self.gl;
        // SAFETY: glIsFramebuffer takes any name and raises no error.
        if self.framebuffer == 0 || unsafe { (g.is_framebuffer)(self.framebuffer) } == 0 {
            return false;
        }
        let mut text = vec![0u8; self.label.len() + 2];
        let mut length = 0;
        // SAFETY: a framebuffer of this context (just checked); the output holds text.len()
        // bytes, which GL is told.
        unsafe {
            (g.get_object_label)(
                gl::FRAMEBUFFER,
                self.framebuffer,
                text.len() as i32,
                &mut length,
                text.as_mut_ptr().cast(),
            )
        };
        text.get(..length.max(0) as usize) == Some(self.label.as_bytes())
    }

    /// The source's thread writes no more texels into the engine's mapped buffers (no GL
    /// call): for an engine whose objects are deleted later, in its context.
    pub fn close_to_sources(&mut self) {
        self.texel_buffers.close();
    }

    /// Whether views may be enhanced in place, or always go through a buffer (the default:
    /// in place on a GPU, through a buffer on a CPU driver).
    pub fn set_in_place(&mut self, allowed: bool) {
        self.in_place = allowed;
    }

    /// Whether views may be stored in place (the default or `set_in_place`).
    pub fn in_place(&self) -> bool {
        self.in_place
    }

    /// The programs (their ids) views of `internal_format`, `width` texels wide, need for
    /// `params`, taking the views to be of immutable textures (see `ready_from_cache`).
    pub fn shape_program_ids(
        &self,
        internal_format: u32,
        width: u32,
        params: &Params,
    ) -> Result<[usize; 3], GlError> {
        let code = GlFormat::of(internal_format)?.pixel.shader_code();
        let in_place = self.in_place && in_place_texel(code).is_some();
        self.shape_programs(internal_format, width, params, in_place)
    }

    /// Which views of the last `enhance` call were stored in place (the others went through
    /// a buffer), in their order.
    pub fn last_in_place(&self) -> &[bool] {
        &self.last_in_place
    }

    /// How the programs can store into the view's (checked) texture in place, or None when the
    /// view goes through a buffer.
    pub fn store_through(&self, v: &GlView) -> Option<StoreThrough> {
        let format = GlFormat::of(v.internal_format).ok()?;
        if !self.in_place || in_place_texel(format.pixel.shader_code()).is_none() {
            return None;
        }
        let unit_format = image_unit_format(v.internal_format)?;
        if !format.pixel.srgb {
            return Some(StoreThrough::Texture(unit_format));
        }
        let mut immutable = 0;
        // SAFETY: a checked texture of this context; a valid pname (4.2+).
        unsafe {
            (self.gl.get_texture_parameteriv)(
                v.texture,
                gl::TEXTURE_IMMUTABLE_FORMAT,
                &mut immutable,
            )
        };
        (immutable != 0).then_some(StoreThrough::View(unit_format))
    }

    /// Whether a background frame was set.
    pub(in crate::gpu::opengl) fn has_background(&self) -> bool {
        self.background.is_some()
    }

    /// The context's version and features as the engine read them.
    pub fn caps(&self) -> &Caps {
        &self.caps
    }

    /// The fault point standing for a lost context. The context's reset status is never
    /// queried: a robust context reports a reset once, and that report is the app's (with it
    /// the app recreates its context); the layer's calls on a lost context do nothing.
    pub(super) fn check_lost(&self) -> Result<(), GlError> {
        if crate::fault::hit("gl-context-lost") {
            return Err(GlError::ContextLost);
        }
        Ok(())
    }

    /// Whether the programs views of `internal_format`, `width` texels wide, need for
    /// `params` are linked, linking those the program binary cache holds (as read, or taken
    /// in since); nothing is compiled. Views are taken to be of
    /// immutable textures (a runtime's are), so in place wherever the format allows.
    ///
    /// # Safety
    /// As for `enhance`.
    pub unsafe fn ready_from_cache(
        &mut self,
        internal_format: u32,
        width: u32,
        params: &Params,
    ) -> Result<bool, GlError> {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        self.check_lost()?;
        if params.mode == ViewMode::Off {
            return Ok(true);
        }
        let ids = self.shape_program_ids(internal_format, width, params)?;
        self.programs.ready_from_cache(&self.gl, &ids)
    }

    /// Reads the program binary cache's file again (another process may have written it): on
    /// a helper thread within 1 s, so for loading-time calls, never a frame call.
    pub fn reload_program_cache(&mut self) {
        self.programs.reload_cache();
    }

    /// The binaries of the programs `ids` this engine holds, for another engine of its driver.
    pub fn program_binaries(&self, ids: &[usize]) -> ProgramBinaries {
        self.programs.binaries(ids)
    }

    /// Takes in binaries another engine of the driver built (where this one has none), for
    /// `ready_from_cache` to link.
    pub fn take_program_binaries(&mut self, binaries: ProgramBinaries) {
        self.programs.take_binaries(binaries);
    }

    /// Whether the programs `views` need are built: one more is built (or its parallel build
    /// checked) per call while not. Errors as `enhance` has them, before anything runs.
    ///
    /// # Safety
    /// As for `enhance`.
    pub unsafe fn ready(&mut self, views: &[GlView], params: &Params) -> Result<bool, GlError> {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        self.check_lost()?;
        params.validate().map_err(GlError::Input)?;
        if params.mode == ViewMode::Off || views.is_empty() {
            return Ok(true);
        }
        let mut ids = Vec::new();
        for v in views {
            self.check_view(v)?;
            ids.extend(self.view_programs(v, params)?.0);
        }
        self.programs.ready(&self.gl, &ids)
    }

    /// Enhances `views` against the background set last, on the current context. Passes
    /// through untouched (Ok(Compiling)) while a program they need is being built, and with
    /// an error (the app's frame and GL state unchanged) when one failed, the context is
    /// lost, a format is not one the engine handles or a region lies outside its texture.
    ///
    /// # Safety
    /// The engine's context is current on this thread, and every `texture` names a texture of
    /// it that nothing else writes during the call.
    pub unsafe fn enhance(
        &mut self,
        views: &[GlView],
        params: &Params,
    ) -> Result<Outcome, GlError> {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        // SAFETY: this call's own contract.
        if !unsafe { self.ready(views, params) }? {
            return Ok(Outcome::Compiling);
        }
        if params.mode == ViewMode::Off || views.is_empty() {
            return Ok(Outcome::Enhanced);
        }
        let mut ids = Vec::new();
        let mut steps = Vec::new();
        for v in views {
            let (programs, cover) = self.view_programs(v, params)?;
            ids.extend(programs);
            let passes = params.method.entry().passes;
            let plan = view_steps(passes, (v.rect.2, v.rect.3), cover).map_err(|NoPlan(why)| {
                GlError::Input(format!("{}: {why}", params.method.name()))
            })?;
            steps.push(plan);
        }
        let Some(bg_size) = self.background.as_ref().map(|b| b.size) else {
            return Err(GlError::Input("no background frame was set".into()));
        };
        while self.views.len() < views.len() {
            self.views.push(ViewBuffers::default());
        }
        self.last_in_place = views
            .iter()
            .map(|v| self.store_through(v).is_some())
            .collect();
        for (k, v) in views.iter().enumerate() {
            self.ensure_buffers(k, v, self.last_in_place[k])?;
            self.upload_model(k, v, params, bg_size)?;
        }
        let state = SavedState::guard(&self.gl, &self.caps)?;
        // SAFETY: a framebuffer this engine made; the app's bindings are put back by the guard.
        unsafe { (self.gl.bind_framebuffer)(gl::FRAMEBUFFER, self.framebuffer) };
        if crate::fault::hit("gl-recipe-panic") {
            panic!("fault point gl-recipe-panic");
        }
        if crate::fault::hit("gl-driver-message") {
            let text = c"fault point gl-driver-message: a driver's note on the layer's work";
            // SAFETY: a third party's message, its text NUL-terminated (length -1).
            unsafe {
                (self.gl.debug_message_insert)(
                    gl::DEBUG_SOURCE_THIRD_PARTY,
                    gl::DEBUG_TYPE_OTHER,
                    1,
                    gl::DEBUG_SEVERITY_MEDIUM,
                    -1,
                    text.as_ptr(),
                )
            };
        }
        for (k, v) in views.iter().enumerate() {
            let programs: [usize; 3] = ids[3 * k..3 * k + 3].try_into().expect("3 ids");
            self.run_view(k, v, (params, &steps[k]), bg_size, programs);
        }
        drop(state);
        Ok(Outcome::Enhanced)
    }

    /// Writes the program binaries built since the last save (see binary_cache.rs).
    pub fn save_program_cache(&mut self) {
        self.programs.save_cache();
    }

    /// Deletes every GL object of the engine and saves the program binaries.
    ///
    /// # Safety
    /// The engine's context is current on this thread.
    pub unsafe fn destroy(&mut self) {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        self.save_program_cache();
        self.programs.destroy(&self.gl);
        // SAFETY: the context is current (this call's contract).
        unsafe { self.times.destroy(&self.gl) };
        self.drop_background();
        // SAFETY: the context is current (this call's contract).
        unsafe { self.texel_buffers.destroy(&self.gl) };
        if self.framebuffer != 0 {
            // SAFETY: ours; the context is current (the caller's contract).
            unsafe { (self.gl.delete_framebuffers)(1, &self.framebuffer) };
            self.framebuffer = 0;
        }
        for v in self.views.drain(..) {
            for b in [v.pixels, v.tiles, v.perceptual]
                .into_iter()
                .filter(|&b| b != 0)
            {
                // SAFETY: ours; the context is current (the caller's contract).
                unsafe { (self.gl.delete_buffers)(1, &b) };
            }
        }
    }

    /// The function table (for the offline context's own transfers).
    pub(in crate::gpu::opengl) fn gl(&self) -> &Gl {
        &self.gl
    }
}

impl GlFrameRunner {
    /// Marks the start of a frame's work in the context, before its background upload, and
    /// takes in the earlier frames' GPU times the driver has by now (frame_times.rs).
    ///
    /// # Safety
    /// The engine's context is current on this thread.
    pub unsafe fn frame_started(&mut self) {
        // SAFETY: this call's contract.
        unsafe {
            self.times.collect(&self.gl);
            self.times.start(&self.gl);
        }
    }

    /// Marks the end of the frame's work.
    ///
    /// # Safety
    /// As `frame_started`.
    pub unsafe fn frame_ended(&mut self) {
        // SAFETY: this call's contract.
        unsafe { self.times.end(&self.gl) };
    }

    /// The GPU time of each frame's work read since the last call, oldest first.
    pub fn take_gpu_times(&mut self) -> Vec<std::time::Duration> {
        self.times.take()
    }
}
