//! A camera frame whose texels its source prepared on the CPU (crate::blurred_texels, on the
//! source's own thread), instead of the camera upload and the decode and blur passes
//! (gpu/record.rs, record_background): the texels the views sample are in a slot of the texel
//! ring (gpu/texel_ring.rs), written by the source's thread before the frame or else by the
//! frame: a mapped image the views then sample where the device allows it, else a host-visible
//! staging buffer, copied into the background frame's image with one vkCmdCopyBufferToImage.
//! The passes remain for frames that come without prepared texels, or with texels made for
//! other blur settings, and for the offline engine.

use super::barrier::layout_change;
use super::buffer::GpuBuffer;
use super::device::GpuDevice;
use super::engine::{barrier, BackgroundFrame, CameraRect, Engine};
use super::error::GpuError;
use super::frame::{FrameBackground, FrameEngine};
use super::frame_view::FrameView;
use super::prepared_staging::new_staging;
use super::texel_ring::TexelRing;
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::blurred_texels::{BlurredTexels, TexelSink, TEXEL_BYTES};
use ash::vk;
use std::sync::Arc;

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
    /// them (the default), off forces the staging buffers and the image copy.
    pub fn set_direct_texels(&mut self, on: bool) {
        self.direct_texels = on && TexelRing::supported(&self.gpu);
    }

    /// Whether prepared texels go straight into mapped images (see `set_direct_texels`;
    /// false from the first failure to make them on).
    pub fn direct_texels(&self) -> bool {
        self.direct_texels
    }

    /// Where a live source should write its frames' texels, on its own thread, for the next
    /// frames to use without a write of their own: the texel ring, once made (the first frame
    /// with prepared texels makes it).
    pub fn texel_sink(&self) -> Option<Arc<dyn TexelSink>> {
        self.ring.sink()
    }

    /// Frames whose texels the source's thread had written, of the frames that used the ring.
    pub fn texels_from_source(&self) -> (u64, u64) {
        (self.ring.from_source, self.ring.frames)
    }

    /// Makes the frame's background its prepared texels, when they were made for `params`, from
    /// a slot of the texel ring: sampled there (mapped images), or copied from there into the
    /// background frame's image, unless that holds them already. Ok(false), with nothing done,
    /// when the frame takes another path, or before the wait for the previous frame (not
    /// `idle`) when the slots must be (re)made or are all in use; an error when the staging
    /// buffers cannot be made.
    pub(super) fn write_direct(
        &mut self,
        background: &FrameBackground,
        views: &[FrameView],
        params: &Params,
        idle: bool,
    ) -> Result<bool, GpuError> {
        let image = background.image;
        let size = (image.width, image.height);
        let Some(texels) = background.prepared.filter(|t| t.made_for(size, params)) else {
            return Ok(false);
        };
        if self.background.as_ref().is_none_or(|b| b.size != size) {
            return Ok(false);
        }
        let mappings: Vec<CameraMapping> = views.iter().map(|v| v.mapping).collect();
        let needed = CameraRect::sampled_by(&mappings, size);
        let seq = background.sequence;
        let sampled = self.direct_texels;
        let rect = match self.prepared_for {
            _ if sampled => needed,
            // The background frame's image holds them: nothing to copy.
            Some((s, done)) if s == seq && done.contains(&needed) => {
                self.ring.active = false;
                self.uses_prepared(seq);
                return Ok(true);
            }
            Some((s, done)) if s == seq => done.union(&needed),
            _ => needed,
        };
        let submission = self.commands.next_submission();
        match self
            .ring
            .write(&self.gpu, texels, &rect, (submission, sampled), idle)
        {
            Ok(true) => {
                self.uses_prepared(seq);
                if !sampled {
                    self.prepared_for = Some((seq, rect));
                }
                Ok(true)
            }
            Ok(false) => Ok(false),
            // From now on through the staging buffers (made by the next call with `idle`).
            Err(_) if sampled => {
                self.direct_texels = false;
                self.ring.close_to_source();
                Ok(false)
            }
            Err(e) => Err(e),
        }
    }

    /// The frame's background is camera frame `seq`, whose texels came prepared.
    fn uses_prepared(&mut self, seq: u64) {
        self.background_sequence = seq;
        self.camera_behind = true;
    }

    /// `write_direct` with no submission in flight: the background frame made, and the slots
    /// made or remade as needed. False, with nothing done, when the frame must be prepared on
    /// the GPU.
    pub(super) fn stage_prepared(
        &mut self,
        background: &FrameBackground,
        views: &[FrameView],
        params: &Params,
    ) -> Result<bool, GpuError> {
        let image = background.image;
        let size = (image.width, image.height);
        self.ring.active = false;
        if background
            .prepared
            .is_none_or(|t| !t.made_for(size, params))
        {
            return Ok(false);
        }
        self.ensure_background(size)?;
        // A second try takes the staging buffers when the mapped images could not be made.
        for _ in 0..2 {
            if self.write_direct(background, views, params, true)? {
                return Ok(true);
            }
        }
        Err(GpuError::Unsupported(
            "no slot of the texel ring is free with the GPU idle".into(),
        ))
    }

    /// The GPU path for a frame whose texels came unprepared: the camera buffer must hold it,
    /// also when an earlier call used prepared texels for the same frame.
    pub(super) fn upload_unprepared(
        &mut self,
        background: &FrameBackground,
    ) -> Result<(), GpuError> {
        self.ring.active = false;
        let behind = std::mem::take(&mut self.camera_behind);
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

    /// Records the copy of the frame's staged texels, once, at the start of its commands.
    pub(super) fn record_prepared_copy(&mut self) {
        let Some(bg) = &self.background else {
            return;
        };
        let Some((staging, rect)) = self.ring.take_copy() else {
            return;
        };
        let cmd = self.commands.cmd;
        self.engine
            .record_texels_upload(&self.gpu, cmd, bg, staging, &rect);
    }
}
