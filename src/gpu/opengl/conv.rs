//! The app's colour textures as the engine reads them: each internal format GL apps take from
//! an OpenXR runtime, the engine's pixel format for it, and the transfer format and type that
//! copy its texels raw (no conversion: pixel transfers never apply the sRGB curve, so an sRGB
//! texture's bytes arrive as stored and the shaders decode them as on Vulkan).

use crate::gpu::core::{PixelFormat, PixelLayout};
use crate::gpu::opengl::device::functions as gl;
use crate::gpu::opengl::device::GlError;

/// A colour texture format the backend enhances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GlFormat {
    /// The internal format (GL_RGBA8, ...).
    pub internal: u32,
    pub pixel: PixelFormat,
    /// glGetTextureSubImage / glTextureSubImage's format and type for its raw texels.
    pub(super) transfer: (gl::Enum, gl::Enum),
}

impl GlFormat {
    /// The format of an internal format, or the error naming it.
    pub fn of(internal: u32) -> Result<GlFormat, GlError> {
        use PixelLayout::*;
        let (layout, srgb, ty) = match internal {
            gl::RGBA8 => (Rgba8, false, gl::UNSIGNED_BYTE),
            gl::SRGB8_ALPHA8 => (Rgba8, true, gl::UNSIGNED_BYTE),
            gl::RGBA16 => (Rgba16Unorm, false, gl::UNSIGNED_SHORT),
            gl::RGBA16F => (Rgba16Float, false, gl::HALF_FLOAT),
            // R in bits 0..10, alpha in 30..32: the layout of A2B10G10R10_UNORM_PACK32.
            gl::RGB10_A2 => (A2b10g10r10, false, gl::UNSIGNED_INT_2_10_10_10_REV),
            other => return Err(GlError::Format(other)),
        };
        Ok(GlFormat {
            internal,
            pixel: PixelFormat { layout, srgb },
            transfer: (gl::RGBA, ty),
        })
    }

    /// The internal format whose texels are of `pixel`, if the backend enhances one.
    pub fn internal_of(pixel: PixelFormat) -> Option<u32> {
        Self::ALL
            .into_iter()
            .find(|&internal| GlFormat::of(internal).is_ok_and(|f| f.pixel == pixel))
    }

    /// Every format the backend enhances.
    pub const ALL: [u32; 5] = [
        gl::RGBA8,
        gl::SRGB8_ALPHA8,
        gl::RGBA16,
        gl::RGBA16F,
        gl::RGB10_A2,
    ];
}

/// The image unit format the in-place programs take a texture of `internal` as: the storage
/// texel format of their variant (interface.rs, `in_place_texel`), of the texture's size.
pub(in crate::gpu::opengl) fn image_unit_format(internal: u32) -> Option<gl::Enum> {
    match internal {
        gl::RGBA8 | gl::SRGB8_ALPHA8 => Some(gl::RGBA8),
        gl::RGBA16F => Some(gl::RGBA16F),
        gl::RGBA16 => Some(gl::RGBA16UI),
        gl::RGB10_A2 => Some(gl::R32UI),
        _ => None,
    }
}
