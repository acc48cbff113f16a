//! The background's texels on their way into its texture: pixel buffer objects mapped for
//! good (GL 4.4 buffer storage, persistent and coherent), used as gpu/texels' slots. A live
//! source's thread writes each new frame's texels into a free one before it publishes the
//! frame, with memory writes only (no GL call on its thread); the frame call then uploads from
//! that buffer into the texture with one glTextureSubImage2D, of the texels the views sample
//! (as the Vulkan ring, the source writes those of the last frame with a margin). Texels that come without the
//! source's write (a static background, the first live frame) are written into a free buffer
//! by the frame call. A fence after each upload tells when its buffer may be written again.

use crate::gpu::core::blurred_texels::{BlurredTexels, TexelSink, TEXEL_BYTES};
use crate::gpu::core::texels::{MappedRows, RingSink, Taken, TexelSlots};
use crate::gpu::core::CameraRect;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;
use std::collections::VecDeque;
use std::sync::Arc;

/// Buffers in the ring: the one the last upload read, the newest the source wrote, one free.
const SLOTS: usize = 3;

/// How long an upload waits at most for an earlier upload from the buffer it needs (ns).
const SLOT_WAIT_NS: u64 = 1_000_000_000;

#[derive(Default)]
pub struct TexelBuffers {
    buffers: Vec<u32>,
    /// What the buffers hold and who may write them; shared with the source's thread.
    slots: Option<Arc<TexelSlots>>,
    /// The source's way in, the same for the engine's life.
    sink: Arc<RingSink>,
    size: (u32, u32),
    /// Uploads made so far (an upload's number is its `submission` for the slots).
    uploads: u64,
    /// Fences of uploads not yet seen finished, oldest first.
    fences: VecDeque<(u64, gl::Sync)>,
    /// Uploads of texels the source's thread wrote, and all uploads.
    from_source: u64,
}

// SAFETY: the fences are used only with the engine's context current, on the app's threads
// that call into the layer one at a time (the session's lock).
unsafe impl Send for TexelBuffers {}

impl TexelBuffers {
    /// Where a live source writes its frames' texels: one sink for the engine's life, which
    /// takes them while buffers of their size are mapped.
    pub fn sink(&self) -> Arc<dyn TexelSink> {
        self.sink.clone()
    }

    /// Uploads of texels the source's thread wrote, and all uploads.
    pub fn texels_from_source(&self) -> (u64, u64) {
        (self.from_source, self.uploads)
    }

    /// Uploads `rect` of `texels` into `texture` (RGBA32UI, the texels' size) from a buffer
    /// holding them: the source's, else one written now. The unpack buffer binding and row
    /// length are left changed (the caller's SavedState puts them back); the rest of the pixel
    /// store must be at its defaults.
    ///
    /// # Safety
    /// The engine's context is current on this thread; `texture` is its background texture.
    pub unsafe fn upload(
        &mut self,
        g: &Gl,
        texels: &BlurredTexels,
        texture: u32,
        rect: &CameraRect,
    ) -> Result<(), GlError> {
        let size = (texels.width, texels.height);
        if self.size != size || self.slots.is_none() {
            // SAFETY: the caller's contract.
            unsafe { self.make(g, size) }?;
        }
        // SAFETY: the caller's contract.
        unsafe { self.retire(g, 0) };
        let Taken { slot, by_source } = match self.take(texels, rect) {
            Some(t) => t,
            None => {
                // Every free buffer may still be read by an upload: wait for the oldest.
                // SAFETY: the caller's contract.
                unsafe { self.retire(g, SLOT_WAIT_NS) };
                self.take(texels, rect)
                    .ok_or(GlError::Allocation("a free background upload buffer"))?
            }
        };
        let first = (rect.y as usize * size.0 as usize + rect.x as usize) * TEXEL_BYTES;
        // SAFETY: the buffer holds `rect` of the texels (the slot's write) in rows of the
        // frame's width from offset 0, and `rect` lies inside the frame; bound as the unpack
        // buffer, with that row length, it is the upload's source from `first`.
        unsafe {
            (g.bind_buffer)(gl::PIXEL_UNPACK_BUFFER, self.buffers[slot]);
            (g.pixel_storei)(gl::UNPACK_ROW_LENGTH, size.0 as i32);
            (g.texture_sub_image_2d)(
                texture,
                0,
                rect.x as i32,
                rect.y as i32,
                rect.width as i32,
                rect.height as i32,
                gl::RGBA_INTEGER,
                gl::UNSIGNED_INT,
                first as *const std::ffi::c_void,
            );
            let fence = (g.fence_sync)(gl::SYNC_GPU_COMMANDS_COMPLETE, 0);
            self.uploads += 1;
            if !fence.is_null() {
                self.fences.push_back((self.uploads, fence));
            }
        }
        self.from_source += u64::from(by_source);
        Ok(())
    }

    /// The slot holding `rect` of `texels` for the next upload: the source's, else one
    /// written now.
    fn take(&self, texels: &BlurredTexels, rect: &CameraRect) -> Option<Taken> {
        let slots = self.slots.as_ref()?;
        let next = self.uploads + 1;
        slots
            .take(texels.serial, rect, next)
            .or_else(|| slots.write_for_frame(texels, rect, next))
    }

    /// Tells the slots which uploads have finished: those whose fences have signalled, waiting
    /// up to `wait_ns` for the oldest.
    unsafe fn retire(&mut self, g: &Gl, wait_ns: u64) {
        let mut wait = wait_ns;
        while let Some(&(n, fence)) = self.fences.front() {
            // A wait flushes first, so that the fence can signal at all.
            let flags = if wait > 0 {
                gl::SYNC_FLUSH_COMMANDS_BIT
            } else {
                0
            };
            // SAFETY: a fence of this context, not yet deleted.
            let status = unsafe { (g.client_wait_sync)(fence, flags, wait) };
            if status != gl::ALREADY_SIGNALED && status != gl::CONDITION_SATISFIED {
                break;
            }
            wait = 0;
            // SAFETY: signalled; deleted once.
            unsafe { (g.delete_sync)(fence) };
            self.fences.pop_front();
            if let Some(slots) = &self.slots {
                slots.finished_through(n);
            }
        }
    }

    /// SLOTS buffers of a `size` frame's texels, mapped for good, as the slots.
    unsafe fn make(&mut self, g: &Gl, size: (u32, u32)) -> Result<(), GlError> {
        // SAFETY: the caller's contract.
        unsafe { self.destroy(g) };
        let bytes = size.0 as usize * size.1 as usize * TEXEL_BYTES;
        let flags = gl::MAP_WRITE_BIT | gl::MAP_PERSISTENT_BIT | gl::MAP_COHERENT_BIT;
        let mut rows = Vec::new();
        for _ in 0..SLOTS {
            let mut buffer = 0;
            // SAFETY: one name into a valid output; immutable storage of `bytes`, mapped whole
            // for writing with the flags it was made with (GL 4.5, checked by Caps).
            let ptr = unsafe {
                (g.create_buffers)(1, &mut buffer);
                (g.named_buffer_storage)(buffer, bytes as isize, std::ptr::null(), flags);
                (g.map_named_buffer_range)(buffer, 0, bytes as isize, flags)
            };
            if ptr.is_null() {
                // SAFETY: ours, not mapped; then the mapped ones (the caller's contract).
                unsafe {
                    (g.delete_buffers)(1, &buffer);
                    self.destroy(g);
                }
                return Err(GlError::Allocation("background upload buffer"));
            }
            self.buffers.push(buffer);
            rows.push(MappedRows::packed(ptr.cast(), bytes, size.0));
        }
        let slots = Arc::new(TexelSlots::new(size, rows));
        self.sink.connect(Some(slots.clone()));
        self.slots = Some(slots);
        self.size = size;
        Ok(())
    }

    /// The source's thread writes no more (a write under way ends first); no GL call.
    pub fn close(&mut self) {
        self.sink.connect(None);
        if let Some(slots) = self.slots.take() {
            slots.close();
        }
    }

    /// Closes the slots to the source, then unmaps and deletes the buffers and fences.
    ///
    /// # Safety
    /// The engine's context is current on this thread.
    pub unsafe fn destroy(&mut self, g: &Gl) {
        self.close();
        for (_, fence) in self.fences.drain(..) {
            // SAFETY: ours, deleted once.
            unsafe { (g.delete_sync)(fence) };
        }
        for buffer in self.buffers.drain(..) {
            // SAFETY: ours and mapped (only mapped buffers are kept), unmapped once.
            unsafe {
                (g.unmap_named_buffer)(buffer);
                (g.delete_buffers)(1, &buffer);
            }
        }
        self.size = (0, 0);
    }
}

impl Drop for TexelBuffers {
    /// Without the context (a session that cannot make it current again) the buffers stay
    /// with it, but the source's thread must never write them again.
    fn drop(&mut self) {
        self.close();
    }
}
