//! A region of a view's texture to and from memory: client memory, or the buffer bound to the
//! pixel pack (read) or unpack (write) point, at an offset. The one place that tells a 2D
//! texture from a layer of an array texture in a transfer.

use super::frame_view::{GlTarget, GlView};
use crate::gpu::opengl::conv::GlFormat;
use crate::gpu::opengl::device::functions::Gl;
use std::ffi::c_void;

/// (x, y, width, height) in texels, y counted from the bottom as GL does.
pub(in crate::gpu::opengl) type Rect = (u32, u32, u32, u32);

fn layer(v: &GlView) -> Option<i32> {
    match v.target {
        GlTarget::Texture2D => None,
        GlTarget::Texture2DArray { layer } => Some(layer as i32),
    }
}

/// Reads `rect` of the view's texture, in the format's transfer layout, rows tightly packed.
///
/// # Safety
/// The view's context is current and `rect` lies inside its texture (a checked view); `dst`
/// is `bytes` of client memory when no pixel pack buffer is bound, else an offset into the
/// bound one with `bytes` after it; the pixel store is at its defaults.
pub(in crate::gpu::opengl) unsafe fn read_region(
    g: &Gl,
    v: &GlView,
    format: GlFormat,
    rect: Rect,
    (dst, bytes): (*mut c_void, usize),
) {
    let (fmt, ty) = format.transfer;
    let (x, y, w, h) = rect;
    let z = layer(v).unwrap_or(0);
    // SAFETY: the caller's contract.
    unsafe {
        (g.get_texture_sub_image)(
            v.texture,
            0,
            x as i32,
            y as i32,
            z,
            w as i32,
            h as i32,
            1,
            fmt,
            ty,
            bytes as i32,
            dst,
        )
    };
}

/// Writes `rect` of the view's texture from `src`, in the format's transfer layout, rows
/// tightly packed.
///
/// # Safety
/// As for `read_region`, with `src` in client memory or the bound pixel unpack buffer.
pub(in crate::gpu::opengl) unsafe fn write_region(
    g: &Gl,
    v: &GlView,
    format: GlFormat,
    rect: Rect,
    src: *const c_void,
) {
    let (fmt, ty) = format.transfer;
    let (x, y, w, h) = (rect.0 as i32, rect.1 as i32, rect.2 as i32, rect.3 as i32);
    // SAFETY: the caller's contract.
    unsafe {
        match layer(v) {
            None => (g.texture_sub_image_2d)(v.texture, 0, x, y, w, h, fmt, ty, src),
            Some(z) => (g.texture_sub_image_3d)(v.texture, 0, x, y, z, w, h, 1, fmt, ty, src),
        }
    }
}
