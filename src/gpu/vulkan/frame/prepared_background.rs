//! A camera frame whose texels its source prepared on the CPU (crate::gpu::core::blurred_texels, on the
//! source's own thread), instead of the camera upload and the decode and blur passes
//! (gpu/vulkan/record/passes.rs, record_background): the texels the views sample are in a slot of the texel
//! ring (gpu/vulkan/texels/texel_ring.rs), written by the source's thread before the frame or else by the
//! frame: a mapped image the views then sample where the device allows it, else a host-visible
//! staging buffer, copied into the background frame's image with one vkCmdCopyBufferToImage.
//! The passes remain for frames that come without prepared texels, or with texels made for
//! other blur settings, and for the offline engine.

use super::frame_runner::FrameRunner;
use super::frame_view::FrameView;
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::core::blurred_texels::TexelSink;
use crate::gpu::core::BackgroundInput;
use crate::gpu::core::CameraRect;
use crate::gpu::vulkan::device::GpuError;
use crate::gpu::vulkan::texels::TexelRing;
use std::sync::Arc;

impl FrameRunner {
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
    /// frames to use without a write of their own: one sink for the engine's life, so a source
    /// is connected to it once. It reaches the texel ring once the ring is made (the first
    /// frame with prepared texels makes it).
    pub fn texel_sink(&self) -> Arc<dyn TexelSink> {
        self.ring.sink()
    }

    /// Frames whose texels the source's thread had written, of the frames that used the ring.
    pub fn texels_from_source(&self) -> (u64, u64) {
        self.ring.texels_from_source()
    }

    /// Makes the frame's background its prepared texels, when they were made for `params`, from
    /// a slot of the texel ring: sampled there (mapped images), or copied from there into the
    /// background frame's image, unless that holds them already. Ok(false), with nothing done,
    /// when the frame takes another path, or before the wait for the previous frame (not
    /// `idle`) when the slots must be (re)made or are all in use; an error when the staging
    /// buffers cannot be made.
    pub(super) fn write_direct(
        &mut self,
        background: &BackgroundInput,
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
                self.ring.set_inactive();
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
        background: &BackgroundInput,
        views: &[FrameView],
        params: &Params,
    ) -> Result<bool, GpuError> {
        let image = background.image;
        let size = (image.width, image.height);
        self.ring.set_inactive();
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
        background: &BackgroundInput,
    ) -> Result<(), GpuError> {
        self.ring.set_inactive();
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
        let want = self.ring.sampled_view().unwrap_or(bg.texels_view());
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
