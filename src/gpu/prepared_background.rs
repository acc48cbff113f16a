//! A camera frame whose texels its source prepared on the CPU (crate::blurred_texels, on the
//! source's own thread), instead of the camera upload and the decode and blur passes
//! (gpu/record.rs, record_background): the frame writes the texels the views sample straight
//! into a mapped image the views then sample (gpu/texel_ring.rs) where the device allows it,
//! else into a host-visible staging buffer, copied into the background frame's image with one
//! vkCmdCopyBufferToImage. The passes remain for frames that come without prepared texels, or
//! with texels made for other blur settings, and for the offline engine.

use super::barrier::layout_change;
use super::buffer::GpuBuffer;
use super::device::GpuDevice;
use super::engine::{barrier, BackgroundFrame, CameraRect, Engine};
use super::error::GpuError;
use super::frame::{FrameBackground, FrameEngine};
use super::frame_view::FrameView;
use super::interface::LINEAR_BITS;
use super::prepared_staging::new_staging;
use super::texel_ring::TexelRing;
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::blurred_texels::{BlurredTexels, TexelSink, TEXEL_BYTES};
use ash::vk;
use std::sync::Arc;

// The CPU packs texels as the shaders do.
const _: () = assert!(crate::blurred_texels::LINEAR_BITS == LINEAR_BITS);

/// A host-visible buffer holding all of `texels`, laid out as the image (for `record_texels_upload`).
pub fn staging_buffer(gpu: &GpuDevice, texels: &BlurredTexels) -> Result<GpuBuffer, GpuError> {
    let mut buffer = new_staging(gpu, texels.bytes.len() as u64)?;
    buffer
        .write(&texels.bytes)
        .inspect_err(|_| buffer.destroy(gpu))?;
    Ok(buffer)
}

impl Engine {
    /// Records the copy of `rect`'s texels from `staging` (laid out as the image, 16 bytes per
    /// texel) into the image the enhancement samples: what `record_background` makes of the
    /// same rectangle, from texels prepared on the CPU.
    pub fn record_texels_upload(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        background: &BackgroundFrame,
        staging: &GpuBuffer,
        rect: &CameraRect,
    ) {
        let all = vk::PipelineStageFlags::ALL_COMMANDS;
        let transfer = vk::PipelineStageFlags::TRANSFER;
        let width = background.size.0;
        let right = (rect.x + rect.width).min(width);
        let to_general = [layout_change(
            background.texels.raw,
            (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL),
            (
                vk::AccessFlags::MEMORY_READ,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
        )];
        let first = u64::from(rect.y) * u64::from(width) + u64::from(rect.x);
        let copy = [vk::BufferImageCopy::default()
            .buffer_offset(first * TEXEL_BYTES as u64)
            .buffer_row_length(width)
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .layer_count(1),
            )
            .image_offset(vk::Offset3D {
                x: rect.x as i32,
                y: rect.y as i32,
                z: 0,
            })
            .image_extent(vk::Extent3D {
                width: right - rect.x,
                height: rect.height,
                depth: 1,
            })];
        let d = &gpu.device;
        // SAFETY: cmd is recording; the image and the buffer are ours, and the region lies in
        // both (the buffer holds the whole frame's texels, the rectangle is inside the frame).
        unsafe {
            d.cmd_pipeline_barrier(
                cmd,
                all,
                transfer,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &to_general,
            );
            d.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                background.texels.raw,
                vk::ImageLayout::GENERAL,
                &copy,
            );
        }
        barrier(gpu, cmd, transfer, all);
    }
}

impl FrameEngine {
    /// Whether prepared texels go straight into mapped images: on where the device samples
    /// them (the default), off forces the staging buffer and the image copy.
    pub fn set_direct_texels(&mut self, on: bool) {
        self.direct_texels = on && TexelRing::supported(&self.gpu);
    }

    /// Whether prepared texels go straight into mapped images (see `set_direct_texels`;
    /// false from the first failure to make them on).
    pub fn direct_texels(&self) -> bool {
        self.direct_texels
    }

    /// Where a live source should write its frames' texels, on its own thread, for the next
    /// frames to sample without a copy: the mapped images, once made (the first frame with
    /// prepared texels makes them). None on the staging path.
    pub fn texel_sink(&self) -> Option<Arc<dyn TexelSink>> {
        self.direct_texels.then(|| self.ring.sink())?
    }

    /// Frames whose texels the source's thread had written, of the frames that sampled the
    /// mapped images.
    pub fn texels_from_source(&self) -> (u64, u64) {
        (self.ring.from_source, self.ring.frames)
    }

    /// Makes the frame sample its prepared texels, written straight into a mapped image no
    /// submitted frame samples, when they were made for `params`. False, with nothing done,
    /// when the frame takes another path, or before the wait for the previous frame (not
    /// `idle`) when the images must be (re)made or are all in use.
    pub(super) fn write_direct(
        &mut self,
        background: &FrameBackground,
        views: &[FrameView],
        params: &Params,
        idle: bool,
    ) -> bool {
        let image = background.image;
        let size = (image.width, image.height);
        let texels = background.prepared.filter(|t| t.made_for(size, params));
        let (true, Some(texels)) = (self.direct_texels, texels) else {
            return false;
        };
        if self.background.as_ref().is_none_or(|b| b.size != size) {
            return false;
        }
        let mappings: Vec<CameraMapping> = views.iter().map(|v| v.mapping).collect();
        let needed = CameraRect::sampled_by(&mappings, size);
        let seq = background.sequence;
        let submission = self.commands.next_submission();
        match self
            .ring
            .write(&self.gpu, texels, &needed, submission, idle)
        {
            Ok(true) => {
                self.background_sequence = seq;
                self.staged.camera_behind = true;
                true
            }
            Ok(false) => false,
            // From now on through the staging buffer; the images are freed at the end (and
            // take no more writes from the source now).
            Err(_) => {
                self.direct_texels = false;
                self.ring.close_to_source();
                false
            }
        }
    }

    /// Makes the frame's background its prepared texels when they were made for `params`:
    /// writes those the views sample into a mapped image (`write_direct`) or the staging buffer
    /// for `record_prepared_copy`. False, with nothing done, when the frame must be prepared
    /// on the GPU. Only with no submission in flight.
    pub(super) fn stage_prepared(
        &mut self,
        background: &FrameBackground,
        views: &[FrameView],
        params: &Params,
    ) -> Result<bool, GpuError> {
        let image = background.image;
        let size = (image.width, image.height);
        self.ring.active = false;
        let Some(texels) = background.prepared.filter(|t| t.made_for(size, params)) else {
            return Ok(false);
        };
        self.ensure_background(size)?;
        if self.write_direct(background, views, params, true) {
            return Ok(true);
        }
        let seq = background.sequence;
        let mappings: Vec<CameraMapping> = views.iter().map(|v| v.mapping).collect();
        let needed = CameraRect::sampled_by(&mappings, size);
        let rect = match self.prepared_for {
            Some((s, done)) if s == seq && done.contains(&needed) => return Ok(true),
            Some((s, done)) if s == seq => done.union(&needed),
            _ => needed,
        };
        self.write_staging(texels, &rect)?;
        self.background_sequence = seq;
        self.prepared_for = Some((seq, rect));
        self.staged.camera_behind = true;
        Ok(true)
    }

    /// Copies the rows of `rect` into the staging buffer (made or remade for the frame's size).
    fn write_staging(&mut self, texels: &BlurredTexels, rect: &CameraRect) -> Result<(), GpuError> {
        let bytes = texels.bytes.len() as u64;
        if self
            .staged
            .buffer
            .as_ref()
            .is_none_or(|b| b.size != bytes.max(16))
        {
            self.staged.destroy(&self.gpu);
            self.staged.buffer = Some(new_staging(&self.gpu, bytes)?);
        }
        let buffer = self.staged.buffer.as_mut().expect("made above");
        let dst = buffer
            .mapped_mut()
            .ok_or_else(|| GpuError::Unsupported("staging buffer is not host-visible".into()))?;
        let row = texels.width as usize * TEXEL_BYTES;
        let right = (rect.x + rect.width).min(texels.width) as usize;
        let span = rect.x as usize * TEXEL_BYTES..right * TEXEL_BYTES;
        for y in rect.y as usize..(rect.y + rect.height) as usize {
            let at = y * row;
            let range = at + span.start..at + span.end;
            dst[range.clone()].copy_from_slice(&texels.bytes[range]);
        }
        self.staged.pending = Some(*rect);
        Ok(())
    }

    /// The GPU path for a frame whose texels came unprepared: the camera buffer must hold it,
    /// also when an earlier call used prepared texels for the same frame.
    pub(super) fn upload_unprepared(
        &mut self,
        background: &FrameBackground,
    ) -> Result<(), GpuError> {
        self.ring.active = false;
        let behind = std::mem::take(&mut self.staged.camera_behind);
        if behind && self.background_sequence == background.sequence {
            if let Some(bg) = self.background.as_mut() {
                bg.upload(&background.image.pixels)?;
            }
        }
        self.update_background(background.image, background.sequence)
    }

    /// Points the views' `blurred_texels` at the image the frame samples (the GPU is idle).
    pub(super) fn bind_texels(&mut self, items: &[FrameView]) {
        let bg = self.background.as_ref().expect("set in process");
        let want = self.ring.sampled_view().unwrap_or(bg.texels_view);
        for item in items {
            let Some(v) = self.views.get_mut(&item.key) else {
                continue;
            };
            if v.texels != want {
                self.engine.bind_texels(&self.gpu, &v.target, want);
                v.texels = want;
            }
        }
    }

    /// Records the copy of the staged texels, once, at the start of the frame's commands.
    pub(super) fn record_prepared_copy(&mut self) {
        let Some(rect) = self.staged.pending.take() else {
            return;
        };
        let (Some(bg), Some(staging)) = (&self.background, &self.staged.buffer) else {
            return;
        };
        let cmd = self.commands.cmd;
        self.engine
            .record_texels_upload(&self.gpu, cmd, bg, staging, &rect);
    }
}
