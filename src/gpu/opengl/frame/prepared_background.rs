//! The background on the app's context: the texels a source prepared (or the frame call
//! prepares), uploaded into the engine's texture from the texel buffers, only the rectangle the
//! views sample.

use super::frame_runner::{texture_level_int, Background, GlFrameRunner};
use super::state_guard::{DebugOutputOff, SavedState};
use crate::algorithm::mapping::CameraMapping;
use crate::gpu::core::blurred_texels::{BlurredTexels, TexelSink, TEXEL_BYTES};
use crate::gpu::core::CameraRect;
use crate::gpu::opengl::device::functions as gl;
use crate::gpu::opengl::device::GlError;

impl GlFrameRunner {
    /// Where a live source writes its frames' texels, on its own thread (memory writes into a
    /// mapped buffer): one sink for the engine's life.
    pub fn texel_sink(&self) -> std::sync::Arc<dyn TexelSink> {
        self.texel_buffers.sink()
    }

    /// Background uploads of texels the source's thread wrote, and all uploads.
    pub fn texels_from_source(&self) -> (u64, u64) {
        self.texel_buffers.texels_from_source()
    }

    /// Makes `texels` the background the views sample: uploaded once (a new frame's texels,
    /// told apart by their serial, from a mapped pixel unpack buffer), nothing when it holds
    /// them already. Prepared on the source's thread (crate::gpu::core::blurred_texels), which for a live
    /// source also writes them into that buffer; only the upload happens here.
    ///
    /// # Safety
    /// The engine's context is current on this thread.
    pub unsafe fn set_background(&mut self, texels: &BlurredTexels) -> Result<(), GlError> {
        // SAFETY: this call's own contract; no mapping: the whole frame.
        unsafe { self.set_background_for(texels, &[]) }
    }

    /// As `set_background`, for views at `mappings` (display uv to camera uv, as `GlView`
    /// has them): only the texels they sample are uploaded (`CameraRect::sampled_by`; all of
    /// them for no mapping).
    ///
    /// # Safety
    /// The engine's context is current on this thread.
    pub unsafe fn set_background_for(
        &mut self,
        texels: &BlurredTexels,
        mappings: &[CameraMapping],
    ) -> Result<(), GlError> {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        self.check_lost()?;
        let size = (texels.width, texels.height);
        if size.0 == 0
            || size.1 == 0
            || texels.bytes.len() != size.0 as usize * size.1 as usize * TEXEL_BYTES
        {
            return Err(GlError::Input(
                "the background frame is empty or damaged".into(),
            ));
        }
        let needed = CameraRect::sampled_by(mappings, size);
        let held = |b: &Background| {
            b.size == size
                && b.holds
                    .is_some_and(|(n, r)| n == texels.serial && r.contains(&needed))
        };
        if self.background.as_ref().is_some_and(held) {
            return Ok(());
        }
        if self.background.as_ref().is_some_and(|b| b.size != size) {
            self.drop_background();
        }
        let g = &self.gl;
        if self.background.is_none() {
            let mut texture = 0;
            // SAFETY: a new 2D texture of one level, RGBA32UI (4.2+), the background's size
            // (checked against GL_TEXTURE_WIDTH below); nearest filtering, so that it is
            // complete for texelFetch whatever the sampler state.
            unsafe {
                (g.create_textures)(gl::TEXTURE_2D, 1, &mut texture);
                (g.texture_parameteri)(texture, gl::TEXTURE_MIN_FILTER, gl::NEAREST);
                (g.texture_parameteri)(texture, gl::TEXTURE_MAG_FILTER, gl::NEAREST);
                (g.texture_storage_2d)(texture, 1, gl::RGBA32UI, size.0 as i32, size.1 as i32);
            }
            let made = texture_level_int(g, texture, gl::TEXTURE_WIDTH) == size.0 as i32;
            if !made {
                // SAFETY: ours.
                unsafe { (g.delete_textures)(1, &texture) };
                return Err(GlError::Allocation("background texture"));
            }
            self.background = Some(Background {
                texture,
                size,
                holds: None,
            });
        }
        let bg = self.background.as_mut().expect("made above");
        let state = SavedState::guard(g, &self.caps)?;
        // SAFETY: the context is current (this call's contract); the texture is the
        // background's, of the texels' size; the unpack binding is put back by the guard.
        let uploaded = unsafe { self.texel_buffers.upload(g, texels, bg.texture, &needed) };
        drop(state);
        uploaded?;
        bg.holds = Some((texels.serial, needed));
        Ok(())
    }

    pub(super) fn drop_background(&mut self) {
        if let Some(bg) = self.background.take() {
            // SAFETY: ours; the context is current (every caller's contract).
            unsafe { (self.gl.delete_textures)(1, &bg.texture) };
        }
    }
}
