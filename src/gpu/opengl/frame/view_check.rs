//! A view checked before anything runs on it: its texture is there, of the target and internal
//! format the view says, and the region lies inside it; asked with queries that raise no error.

use super::frame_runner::{texture_level_int, GlFrameRunner};
use super::frame_view::{GlTarget, GlView};
use crate::gpu::opengl::device::functions as gl;
use crate::gpu::opengl::device::GlError;

impl GlFrameRunner {
    /// The view's texture is there with its format, and the region lies inside it.
    pub(in crate::gpu::opengl) fn check_view(&self, v: &GlView) -> Result<(), GlError> {
        let g = &self.gl;
        let (x, y, w, h) = v.rect;
        let width = texture_level_int(g, v.texture, gl::TEXTURE_WIDTH);
        let height = texture_level_int(g, v.texture, gl::TEXTURE_HEIGHT);
        let depth = texture_level_int(g, v.texture, gl::TEXTURE_DEPTH);
        let internal = texture_level_int(g, v.texture, gl::TEXTURE_INTERNAL_FORMAT) as u32;
        let (layer, target) = match v.target {
            GlTarget::Texture2D => (0, gl::TEXTURE_2D),
            GlTarget::Texture2DArray { layer } => (layer, gl::TEXTURE_2D_ARRAY),
        };
        // Mesa answers GL_TEXTURE_TARGET in a core context only (in a compatibility context
        // it raises GL_INVALID_ENUM into the app's flag): there a 2D texture is told by its
        // depth of 1, and the view's kind is the swapchain's (its array size).
        let actual = if self.caps.compatibility {
            match v.target {
                GlTarget::Texture2D if depth != 1 => gl::TEXTURE_2D_ARRAY as i32,
                _ => target as i32,
            }
        } else {
            let mut actual = 0;
            // SAFETY: a texture name of this context (the caller's contract); GL_TEXTURE_TARGET
            // is a valid glGetTextureParameteriv query in a 4.5 core context.
            unsafe { (g.get_texture_parameteriv)(v.texture, gl::TEXTURE_TARGET, &mut actual) };
            actual
        };
        if actual as u32 != target {
            return Err(GlError::Input(format!(
                "a view's texture has target {actual:#06x}, not the {target:#06x} the view says"
            )));
        }
        let inside = w > 0
            && h > 0
            && u64::from(x) + u64::from(w) <= width.max(0) as u64
            && u64::from(y) + u64::from(h) <= height.max(0) as u64
            && i64::from(layer) < i64::from(depth);
        if !inside {
            return Err(GlError::Input(format!(
                "a view's region {w}x{h} at ({x}, {y}) layer {layer} is not inside its {width}x{height}x{depth} texture"
            )));
        }
        if internal != v.internal_format {
            return Err(GlError::Input(format!(
                "a view's texture is {internal:#06x}, not the {:#06x} the view says",
                v.internal_format
            )));
        }
        Ok(())
    }
}
