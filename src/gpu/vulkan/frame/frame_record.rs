//! The recipe of a frame's command buffer (gpu/vulkan/frame/frame_runner.rs): background preparation, layout
//! barriers, copies out of the app's images (into a buffer, or an image of the engine's own),
//! enhancement, overlay, captures, copies back.

use super::frame_runner::FrameRunner;
use super::frame_view::{FrameView, ViewPath};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::core::CameraRect;
use crate::gpu::core::OverlayPixels;
use crate::gpu::vulkan::device::{
    barrier, record_buffer_copy, record_first_layout, record_image_region_copy,
    record_layout_barriers, record_region_copy, GpuBuffer, GpuError, ImageRegion,
};
use crate::gpu::vulkan::record::{record_write_back, record_write_back_barrier};
use ash::vk;

impl FrameRunner {
    pub(super) fn submit(&mut self) -> Result<(), GpuError> {
        // Inside xrEndFrame: the OpenXR spec gives the runtime, and so its layers, the app's
        // queue during this call.
        self.times.record_end(&self.gpu, self.commands.cmd);
        self.commands.submit(&self.gpu)
    }

    fn image_barriers(&self, items: &[FrameView], to_general: bool) {
        let regions: Vec<ImageRegion> = items.iter().map(FrameView::region).collect();
        record_layout_barriers(&self.gpu, self.commands.cmd, &regions, to_general);
    }

    /// Copies the region into its view's buffer or image, or back (`out` false; views
    /// through a copy only, and a sampled read's only while its tiles cannot be drawn back:
    /// it then takes the image-copy path).
    fn copy_region(&self, item: &FrameView, out: bool) {
        let view = &self.views[&item.key];
        let cmd = self.commands.cmd;
        match (item.path, &view.own) {
            (ViewPath::InPlace, _) => {}
            (ViewPath::SampledTiles, _) if self.drawn_back(item) => {}
            (p, Some(own)) if p.writes_own_image() => {
                record_image_region_copy(&self.gpu, cmd, &item.region(), own.image.raw, out)
            }
            _ => record_region_copy(&self.gpu, cmd, &item.region(), &view.target.pixels, out),
        }
    }

    /// Where the view's pixels are while its passes run, for the images among them: the
    /// app's image in place, the engine's own image on the image-copy path and the sampled
    /// read (the region at its origin); None for a view through a buffer.
    fn work_region(&self, item: &FrameView) -> Option<ImageRegion> {
        match (item.path, &self.views[&item.key].own) {
            (ViewPath::InPlace, _) => Some(item.region()),
            (p, Some(own)) if p.writes_own_image() => Some(ImageRegion {
                image: own.image.raw,
                array_index: 0,
                offset: (0, 0),
                extent: item.key.extent,
            }),
            _ => None,
        }
    }

    /// Copies the view's current pixels (the image its passes run on, else the view's
    /// buffer) into a capture buffer; before the enhancement (`before`), a sampled read's
    /// from the app's image, which its passes read.
    fn copy_to_capture(&self, item: &FrameView, dst: &GpuBuffer, before: bool) {
        let cmd = self.commands.cmd;
        let sampled = item.path == ViewPath::SampledTiles && self.drawn_back(item);
        let region = match before && sampled {
            true => Some(item.region()),
            false => self.work_region(item),
        };
        if let Some(region) = region {
            record_region_copy(&self.gpu, cmd, &region, dst, true);
            return;
        }
        let src = &self.views[&item.key].target.pixels;
        let region = [vk::BufferCopy::default().size(self.views[&item.key].target.pixel_bytes())];
        record_buffer_copy(&self.gpu, cmd, (src, dst), &region);
    }

    /// The image-copy path's images to GENERAL (their contents discarded: the copy out
    /// writes them), before the copies out.
    fn own_image_barriers(&self, items: &[FrameView]) {
        let images: Vec<vk::Image> = items
            .iter()
            .filter(|i| i.path.writes_own_image())
            .filter_map(|i| self.views[&i.key].own.as_ref().map(|o| o.image.raw))
            .collect();
        if images.is_empty() {
            return;
        }
        let write = (
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
        );
        let general = vk::ImageLayout::GENERAL;
        record_first_layout(&self.gpu, self.commands.cmd, &images, general, write);
    }

    pub(super) fn record(
        &mut self,
        items: &[FrameView],
        params: &Params,
        overlay: Option<&OverlayPixels>,
        staging: &[(GpuBuffer, GpuBuffer)],
    ) -> Result<(), GpuError> {
        self.commands.begin(&self.gpu)?;
        self.times.record_start(&self.gpu, self.commands.cmd);
        self.record_prepared_copy();
        let next = self.commands.next_submission();
        self.ring.record_use(&self.gpu, self.commands.cmd, next);
        let seq = self.background_sequence;
        let bg = self.background.as_ref().expect("set in process");
        let mappings: Vec<CameraMapping> = items.iter().map(|i| i.mapping).collect();
        let needed = CameraRect::sampled_by(&mappings, bg.size);
        let rect = match self.prepared_for {
            // The views sample a mapped image that holds the frame's texels.
            _ if self.ring.active() => None,
            Some((s, done)) if s == seq && done.contains(&needed) => None,
            // A view the frame's preparation did not cover: prepare both again.
            Some((s, done)) if s == seq => Some(done.union(&needed)),
            _ => Some(needed),
        };
        if let Some(rect) = rect {
            self.engine
                .record_background(&self.gpu, self.commands.cmd, bg, params, &rect)?;
            self.prepared_for = Some((seq, rect));
        }
        let frame = self.frame;
        for i in items {
            if let Some(v) = self.views.get_mut(&i.key) {
                v.last_frame = frame;
            }
        }
        use vk::PipelineStageFlags as S;
        self.image_barriers(items, true);
        self.own_image_barriers(items);
        items.iter().for_each(|i| self.copy_region(i, true));
        barrier(
            &self.gpu,
            self.commands.cmd,
            S::TRANSFER,
            S::COMPUTE_SHADER | S::TRANSFER,
        );
        for (i, (before, _)) in items.iter().zip(staging) {
            self.copy_to_capture(i, before, true);
        }
        if !staging.is_empty() {
            // The capture copies read `pixels` before the enhancement writes it.
            barrier(&self.gpu, self.commands.cmd, S::TRANSFER, S::COMPUTE_SHADER);
        }
        for i in items {
            if let Some(view) = self.views.get_mut(&i.key) {
                view.target.pixels_per_degree = i.pixels_per_degree;
            }
            self.engine.record_enhance(
                &self.gpu,
                self.commands.cmd,
                &self.views[&i.key].target,
                params,
                &i.mapping,
            )?;
        }
        barrier(&self.gpu, self.commands.cmd, S::COMPUTE_SHADER, S::TRANSFER);
        let regions: Vec<ImageRegion> = items
            .iter()
            .map(|i| self.work_region(i).unwrap_or_else(|| i.region()))
            .collect();
        let views = items
            .iter()
            .zip(regions)
            .map(|(i, region)| (i.key, &self.views[&i.key].target, region));
        if self
            .overlays
            .record(&self.gpu, self.commands.cmd, overlay, views)?
        {
            // The capture and the copy back read what the indicator wrote.
            barrier(&self.gpu, self.commands.cmd, S::TRANSFER, S::TRANSFER);
        }
        // A view whose tiles are drawn back is captured after its draw, from the app's image.
        let mut later = Vec::new();
        for (i, (_, after)) in items.iter().zip(staging) {
            let drawn = self.drawn_back(i);
            if !drawn {
                self.copy_to_capture(i, after, false);
            }
            later.push(drawn.then_some(after));
        }
        items
            .iter()
            .filter(|i| !self.drawn_back(i))
            .for_each(|i| self.copy_region(i, false));
        self.record_tile_write_backs(items, overlay, &later)?;
        self.image_barriers(items, false);
        barrier(&self.gpu, self.commands.cmd, S::TRANSFER, S::HOST);
        Ok(())
    }
}

impl FrameRunner {
    /// Whether `item`'s tiles are drawn back this frame (its copy back is then left out).
    pub(super) fn drawn_back(&self, item: &FrameView) -> bool {
        self.tiles.draws.contains_key(&item.key)
    }

    /// `item` with the path this frame took: a view whose tiles are to be drawn back was
    /// copied back whole (a sampled read's also copied in) while the draw's pipeline was
    /// being built.
    pub(super) fn as_taken(&self, item: &FrameView) -> FrameView {
        let mut view = item.clone();
        if view.path.draws_tiles_back() && !self.drawn_back(item) {
            view.path = ViewPath::ImageCopy;
        }
        view
    }

    /// Draws the listed tiles of the views drawn back into the app's images, then copies the
    /// overlay into those regions and, for a capture, reads them back from the app's image
    /// (`after`, by item): what reached the app. After the enhancement and the other views'
    /// copies back; the images are in GENERAL.
    pub(super) fn record_tile_write_backs(
        &mut self,
        items: &[FrameView],
        overlay: Option<&OverlayPixels>,
        after: &[Option<&GpuBuffer>],
    ) -> Result<(), GpuError> {
        use vk::PipelineStageFlags as S;
        let drawn: Vec<(usize, &FrameView)> = items
            .iter()
            .enumerate()
            .filter(|(_, i)| self.drawn_back(i))
            .collect();
        if drawn.is_empty() {
            return Ok(());
        }
        let (gpu, cmd) = (&self.gpu, self.commands.cmd);
        record_write_back_barrier(gpu, cmd);
        let pipelines = self.tiles.pipelines.as_ref().expect("made with the draws");
        for (_, i) in &drawn {
            record_write_back(gpu, cmd, pipelines, &self.tiles.draws[&i.key]);
        }
        barrier(gpu, cmd, S::COLOR_ATTACHMENT_OUTPUT, S::TRANSFER);
        // The draw wrote only the listed tiles: the overlay also goes into the app's image.
        let in_app = drawn
            .iter()
            .map(|(_, i)| (i.key, &self.views[&i.key].target, i.region()));
        if self.overlays.record(gpu, cmd, overlay, in_app)? {
            barrier(gpu, cmd, S::TRANSFER, S::TRANSFER);
        }
        for (k, i) in &drawn {
            if let Some(dst) = after.get(*k).copied().flatten() {
                let region = i.region();
                record_region_copy(gpu, cmd, &region, dst, true);
            }
        }
        Ok(())
    }
}
