//! Where a slot's texels lie in the mapped memory of its image, and the one write into it.

use crate::gpu::core::blurred_texels::{BlurredTexels, TEXEL_BYTES};
use crate::gpu::core::CameraRect;

/// Where one image's (or buffer's) texels lie in its mapped memory.
#[derive(Clone, Copy)]
pub struct MappedRows {
    pub(in crate::gpu) ptr: *mut u8,
    pub(in crate::gpu) len: usize,
    pub(in crate::gpu) offset: usize,
    pub(in crate::gpu) row_pitch: usize,
}

// SAFETY: the memory stays mapped until the ring's `close` has returned, and only the holder
// of the slot's `writing` claim writes it.
unsafe impl Send for MappedRows {}

impl MappedRows {
    /// Rows of `width` texels packed from the start of `len` bytes mapped at `ptr` (a buffer
    /// laid out as the texels are).
    pub(crate) fn packed(ptr: *mut u8, len: usize, width: u32) -> MappedRows {
        MappedRows {
            ptr,
            len,
            offset: 0,
            row_pitch: width as usize * TEXEL_BYTES,
        }
    }

    /// Copies the rows of `rect` from `texels` (16 bytes per texel, rows packed). The caller
    /// holds the slot's writing claim and no submission samples the image.
    pub(in crate::gpu) fn write(&self, texels: &BlurredTexels, rect: &CameraRect) {
        // SAFETY: mapped for `len` bytes until `close` (which waits for this write), and no one
        // else reads or writes it now (the caller's claim; no submission samples it).
        let dst = unsafe { std::slice::from_raw_parts_mut(self.ptr, self.len) };
        let row = texels.width as usize * TEXEL_BYTES;
        let right = (rect.x + rect.width).min(texels.width) as usize;
        let span = rect.x as usize * TEXEL_BYTES..right * TEXEL_BYTES;
        for y in rect.y as usize..(rect.y + rect.height) as usize {
            let (src, at) = (y * row, self.offset + y * self.row_pitch);
            dst[at + span.start..at + span.end]
                .copy_from_slice(&texels.bytes[src + span.start..src + span.end]);
        }
    }
}
