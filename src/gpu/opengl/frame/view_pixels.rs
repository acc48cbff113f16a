//! A view's pixels to and from client memory, outside the recipe: read back for a capture, and
//! the indicator's lit runs written over an enhanced view. Both with the app's state saved and
//! put back, no buffer bound to the pixel pack/unpack points and the pixel store at defaults.

use super::frame_runner::GlFrameRunner;
use super::frame_view::GlView;
use super::region::{read_region, write_region};
use super::state_guard::{DebugOutputOff, SavedState};
use crate::gpu::core::Run;
use crate::gpu::opengl::conv::GlFormat;
use crate::gpu::opengl::device::caps::Caps;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;

/// The view's region bytes, rows as GL stores them (bottom first), tightly packed.
///
/// # Safety
/// `g`'s context is current and `v` is a checked view of it; no pack buffer is bound.
unsafe fn read(g: &Gl, v: &GlView, format: GlFormat) -> Vec<u8> {
    let (_, _, w, h) = v.rect;
    let bpp = format.pixel.bytes_per_pixel() as usize;
    let mut out = vec![0u8; w as usize * h as usize * bpp];
    // SAFETY: the region lies in the texture (checked view); `out` holds it with rows tightly
    // packed (pixel store at defaults, 4-byte alignment divides every row of 4- and 8-byte
    // pixels).
    unsafe { read_region(g, v, format, v.rect, (out.as_mut_ptr().cast(), out.len())) };
    out
}

/// Writes `pixel` (one pixel's bytes) over each run; run rows count from the view's top.
///
/// # Safety
/// As for `read`, with no unpack buffer bound.
unsafe fn draw(g: &Gl, v: &GlView, format: GlFormat, runs: &[Run], pixel: &[u8]) {
    let (x, y, w, h) = v.rect;
    for r in runs.iter().filter(|r| r.y < h && r.x < w) {
        let len = r.len.min(w - r.x);
        let row: Vec<u8> = pixel.repeat(len as usize);
        // GL rows count from the bottom.
        let rect = (x + r.x, y + h - 1 - r.y, len, 1);
        // SAFETY: the run lies inside the region (clipped above), `row` holds `len` pixels.
        unsafe { write_region(g, v, format, rect, row.as_ptr().cast()) };
    }
}

/// Runs `f` with the app's state saved, no pixel buffers bound, and puts the state back.
fn with_client_memory<R>(g: &Gl, caps: &Caps, f: impl FnOnce() -> R) -> Result<R, GlError> {
    let state = SavedState::guard(g, caps)?;
    // SAFETY: unbinding the pixel buffer points (put back by the guard).
    unsafe {
        (g.bind_buffer)(gl::PIXEL_PACK_BUFFER, 0);
        (g.bind_buffer)(gl::PIXEL_UNPACK_BUFFER, 0);
    }
    let r = f();
    drop(state);
    Ok(r)
}

impl GlFrameRunner {
    /// The view's pixels, rows top first (as the view is seen), tightly packed.
    ///
    /// # Safety
    /// The engine's context is current, and `v` names one of its textures (checked here).
    pub unsafe fn read_view(&self, v: &GlView) -> Result<Vec<u8>, GlError> {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        self.check_view(v)?;
        let format = GlFormat::of(v.internal_format)?;
        let g = self.gl();
        // SAFETY: the view was checked; the context is current (the caller's contract).
        let bottom_first = with_client_memory(g, &self.caps, || unsafe { read(g, v, format) })?;
        let row = v.rect.2 as usize * format.pixel.bytes_per_pixel() as usize;
        Ok(bottom_first
            .chunks_exact(row.max(1))
            .rev()
            .flatten()
            .copied()
            .collect())
    }

    /// Writes `pixel` (one pixel in the view's format) over the lit `runs` (rows from the
    /// view's top).
    ///
    /// # Safety
    /// As for `read_view`.
    pub unsafe fn draw_runs(&self, v: &GlView, runs: &[Run], pixel: &[u8]) -> Result<(), GlError> {
        // SAFETY: the engine's context is current (this call's contract).
        let _quiet = unsafe { DebugOutputOff::new(&self.gl) };
        self.check_view(v)?;
        let format = GlFormat::of(v.internal_format)?;
        if pixel.len() != format.pixel.bytes_per_pixel() as usize {
            return Err(GlError::Input("an overlay pixel of the wrong size".into()));
        }
        let g = self.gl();
        // SAFETY: as for `read_view`.
        with_client_memory(g, &self.caps, || unsafe { draw(g, v, format, runs, pixel) })
    }
}
