//! Programs built ahead of the frames: when the app makes a swapchain the layer will enhance
//! (a loading-time call, in the app's context), the programs its views need are built, and run
//! once on a small texture of the layer's own. A driver that compiles a program's machine code
//! at its first dispatch (Mesa's llvmpipe: most of a cold start) then does it there, not inside
//! a frame call, where a late frame makes a runtime lengthen its display period.

use super::frame_runner::{rows_aligned, GlFrameRunner, Outcome};
use super::frame_view::{GlTarget, GlView};
use super::state_guard::DebugOutputOff;
use crate::algorithm::params::{Params, ViewMode};
use crate::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use crate::gpu::core::blurred_texels::{BlurTaps, BlurredTexels};
use crate::gpu::core::process_exit;
use crate::gpu::opengl::conv::GlFormat;
use crate::gpu::opengl::device::functions::{self as gl};
use crate::gpu::opengl::device::GlError;
use crate::image::RgbaImage;
use std::time::{Duration, Instant};

/// The warm-up texture's height; its width is 16 or 17 texels, so that its rows are whole
/// 16-byte groups exactly when the app's views' rows are (the same pixel access variant).
const WARM_UP_HEIGHT: u32 = 8;

/// The background frame a warm-up samples when none was set yet.
const WARM_UP_BACKGROUND: (u32, u32) = (6, 3);

impl GlFrameRunner {
    /// Builds the programs views of `internal_format`, `width` texels wide, need for `params`,
    /// waiting up to `limit`, and runs them once on a texture of the layer's own (deleted
    /// after). Ok(false) when they were not ready within `limit` (the frame calls go on with
    /// the build) or the process began to exit. The app's GL state is put back as by `enhance`.
    ///
    /// # Safety
    /// The engine's context is current on this thread.
    pub unsafe fn warm_up(
        &mut self,
        internal_format: u32,
        width: u32,
        params: &Params,
        limit: Duration,
    ) -> Result<bool, GlError> {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        let format = GlFormat::of(internal_format)?;
        if params.mode == ViewMode::Off {
            return Ok(true);
        }
        let w = match rows_aligned(width, format.pixel.bytes_per_pixel()) {
            true => 16,
            false => 17,
        };
        let g = self.gl();
        let mut texture = 0;
        // SAFETY: a new 2D texture of one level in a format the engine handles (GL 4.5 DSA):
        // no binding of the app's changes.
        unsafe {
            (g.create_textures)(gl::TEXTURE_2D, 1, &mut texture);
            (g.texture_storage_2d)(texture, 1, internal_format, w as i32, WARM_UP_HEIGHT as i32);
        }
        let view = GlView {
            texture,
            target: GlTarget::Texture2D,
            internal_format,
            rect: (0, 0, w, WARM_UP_HEIGHT),
            mapping: params.camera_mapping(),
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
        };
        // SAFETY: the context is current (this call's contract); the texture is ours.
        let result = unsafe { self.warm_up_view(&view, params, limit) };
        // SAFETY: ours, bound nowhere.
        unsafe { (self.gl().delete_textures)(1, &texture) };
        result
    }

    /// # Safety
    /// As for `warm_up`; `view` names a texture of the engine's own.
    unsafe fn warm_up_view(
        &mut self,
        view: &GlView,
        params: &Params,
        limit: Duration,
    ) -> Result<bool, GlError> {
        let views = std::slice::from_ref(view);
        let since = Instant::now();
        // Each step builds one program: the process's exit (process_exit.rs) waits for the step
        // under way, never for the rest of the set.
        loop {
            if process_exit::exiting() || since.elapsed() > limit {
                return Ok(false);
            }
            // SAFETY: the context is current (the caller's contract).
            if unsafe { self.ready(views, params) }? {
                break;
            }
        }
        if !self.has_background() {
            // Not a power of two either way, as cameras' frames are: llvmpipe compiles
            // another variant for a texture whose sides are powers of two.
            let black = RgbaImage::new(WARM_UP_BACKGROUND.0, WARM_UP_BACKGROUND.1, [0, 0, 0, 255]);
            let texels = BlurredTexels::prepare(&black, BlurTaps::of(params));
            // SAFETY: as above.
            unsafe { self.set_background(&texels) }?;
        }
        if process_exit::exiting() {
            return Ok(false);
        }
        // SAFETY: as above; the view's texture is ours, written by nothing else.
        let outcome = unsafe { self.enhance(views, params) }?;
        Ok(outcome == Outcome::Enhanced)
    }
}
