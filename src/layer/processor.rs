//! A session's GPU work at xrEndFrame: for each view region, copy it out of the app's image
//! into the engine's buffer, enhance it, and copy it back, on the app's device and queue.
//! The image is still the app's at that point (its release is held until xrEndFrame).

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::commands::Commands;
use crate::gpu::engine::barrier;
use crate::gpu::{
    BackgroundFrame, Engine, GpuDevice, GpuError, PixelFormat, Placement, ViewTarget,
};
use crate::image::RgbaImage;
use ash::vk;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// Most view regions a session keeps buffers for (2 eyes x a few swapchains and quads).
const MAX_VIEWS: u32 = 16;

/// One region of a swapchain image to enhance.
#[derive(Clone, Debug)]
pub struct WorkItem {
    pub key: ViewKey,
    pub image: vk::Image,
    pub format: PixelFormat,
    pub vk_format: vk::Format,
    /// Where this view's display pixels lie in the camera image.
    pub mapping: CameraMapping,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ViewKey {
    pub swapchain: u64,
    pub offset: (i32, i32),
    pub extent: (u32, u32),
    pub array_index: u32,
}

struct PreparedView {
    target: ViewTarget,
    /// The background sequence its bg buffers were prepared for.
    prepared_for: Option<u64>,
    last_frame: u64,
}

/// Raw bytes of one view read back for a capture.
pub struct CapturedView {
    pub item: WorkItem,
    pub display: Vec<u8>,
    pub output: Vec<u8>,
}

pub struct Processor {
    engine: Engine,
    commands: Commands,
    background: Option<BackgroundFrame>,
    background_sequence: u64,
    views: HashMap<ViewKey, PreparedView>,
    frame: u64,
    /// The in-headset indicator drawn after the enhancement (its timer is set by the session).
    pub indicator: super::indicator::Indicator,
    // Last: dropped after everything above was destroyed in Drop.
    pub gpu: GpuDevice,
}

fn subresource(layer: u32) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .base_array_layer(layer)
        .layer_count(1)
}

impl Processor {
    pub fn new(gpu: GpuDevice) -> Result<Processor, GpuError> {
        let mut engine = Engine::new(&gpu, MAX_VIEWS)?;
        let commands = match Commands::new(&gpu) {
            Ok(c) => c,
            Err(e) => {
                engine.destroy(&gpu);
                return Err(e);
            }
        };
        Ok(Processor {
            engine,
            commands,
            background: None,
            background_sequence: 0,
            views: HashMap::new(),
            frame: 0,
            indicator: Default::default(),
            gpu,
        })
    }

    /// Waits for the previous submission (normally long done) so its buffers can be reused.
    fn wait_idle(&mut self) -> Result<(), GpuError> {
        self.commands.wait(&self.gpu, 5_000_000_000)
    }

    /// Makes the GPU background frame hold `image` (sequence identifies a new camera frame).
    fn update_background(&mut self, image: &RgbaImage, sequence: u64) -> Result<(), GpuError> {
        if self.background.is_some() && self.background_sequence == sequence {
            return Ok(());
        }
        let size = (image.width, image.height);
        if self.background.as_ref().is_none_or(|b| b.size != size) {
            if let Some(mut old) = self.background.take() {
                old.destroy(&self.gpu);
            }
            let bg = self
                .engine
                .create_background(&self.gpu, size, Placement::DEVICE)?;
            for v in self.views.values_mut() {
                self.engine.bind(&self.gpu, &mut v.target, &bg);
                v.prepared_for = None;
            }
            self.background = Some(bg);
        }
        let bg = self.background.as_mut().expect("created above");
        bg.upload(&image.pixels)?;
        self.background_sequence = sequence;
        Ok(())
    }

    fn ensure_view(&mut self, item: &WorkItem) -> Result<(), GpuError> {
        if self
            .views
            .get(&item.key)
            .is_some_and(|v| v.target.format == item.format)
        {
            return Ok(());
        }
        if let Some(mut old) = self.views.remove(&item.key) {
            self.engine.destroy_view(&self.gpu, &mut old.target);
        }
        if self.views.len() as u32 >= MAX_VIEWS {
            self.evict_oldest();
        }
        let bg = self
            .background
            .as_ref()
            .expect("background is set before views");
        let target = self.engine.create_view(
            &self.gpu,
            item.key.extent,
            item.format,
            bg,
            Placement::DEVICE,
        )?;
        self.views.insert(
            item.key,
            PreparedView {
                target,
                prepared_for: None,
                last_frame: self.frame,
            },
        );
        Ok(())
    }

    fn evict_oldest(&mut self) {
        let oldest = self
            .views
            .iter()
            .min_by_key(|(_, v)| v.last_frame)
            .map(|(k, _)| *k);
        if let Some(mut v) = oldest.and_then(|k| self.views.remove(&k)) {
            self.engine.destroy_view(&self.gpu, &mut v.target);
        }
    }

    /// Drops the buffers of a destroyed swapchain's views.
    pub fn forget_swapchain(&mut self, swapchain: u64) {
        if self.wait_idle().is_err() {
            return;
        }
        let keys: Vec<ViewKey> = self
            .views
            .keys()
            .filter(|k| k.swapchain == swapchain)
            .copied()
            .collect();
        for k in keys {
            if let Some(mut v) = self.views.remove(&k) {
                self.engine.destroy_view(&self.gpu, &mut v.target);
            }
        }
    }

    /// Enhances every item's region in place. With `capture`, also reads back each region
    /// before and after (waiting for the GPU).
    pub fn process(
        &mut self,
        items: &[WorkItem],
        background: &Arc<RgbaImage>,
        sequence: u64,
        params: &Params,
        capture: bool,
    ) -> Result<Vec<CapturedView>, GpuError> {
        crate::fault::check("image-capture").map_err(GpuError::Unsupported)?;
        self.frame += 1;
        self.wait_idle()?;
        self.update_background(background, sequence)?;
        for item in items {
            self.ensure_view(item)?;
        }
        let mut staging = Vec::new();
        if capture {
            for item in items {
                let bytes = self.views[&item.key].target.pixel_bytes();
                let usage = vk::BufferUsageFlags::TRANSFER_DST;
                let loc = gpu_allocator::MemoryLocation::GpuToCpu;
                let before =
                    crate::gpu::buffer::GpuBuffer::new(&self.gpu, bytes, usage, loc, "capture")?;
                let after =
                    crate::gpu::buffer::GpuBuffer::new(&self.gpu, bytes, usage, loc, "capture")?;
                staging.push((before, after));
            }
        }
        let recorded = self.record(items, params, &staging);
        let submitted = recorded.and_then(|_| self.submit());
        let result = submitted.and_then(|_| {
            if capture {
                self.wait_idle()?;
            }
            Ok(())
        });
        let mut captured = Vec::new();
        for (item, (mut before, mut after)) in items.iter().zip(staging) {
            if result.is_ok() {
                captured.push(CapturedView {
                    item: item.clone(),
                    display: before.mapped().unwrap_or_default().to_vec(),
                    output: after.mapped().unwrap_or_default().to_vec(),
                });
            }
            // Capture buffers are only used when we waited above (or the submit failed).
            let _ = self.wait_idle();
            before.destroy(&self.gpu);
            after.destroy(&self.gpu);
        }
        result.map(|_| captured)
    }

    fn submit(&mut self) -> Result<(), GpuError> {
        // Inside xrEndFrame: the OpenXR spec gives the runtime, and so its layers, the app's
        // queue during this call.
        self.commands.submit(&self.gpu)
    }

    fn image_barriers(&self, items: &[WorkItem], to_general: bool) {
        let mut seen = HashSet::new();
        let barriers: Vec<_> = items
            .iter()
            .filter(|i| seen.insert((i.image, i.key.array_index)))
            .map(|i| {
                let (old, new) = if to_general {
                    (
                        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                        vk::ImageLayout::GENERAL,
                    )
                } else {
                    (
                        vk::ImageLayout::GENERAL,
                        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    )
                };
                let colour = vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                    | vk::AccessFlags::COLOR_ATTACHMENT_READ;
                let transfer = vk::AccessFlags::TRANSFER_READ | vk::AccessFlags::TRANSFER_WRITE;
                let (src, dst) = if to_general {
                    (colour, transfer)
                } else {
                    (transfer, colour)
                };
                vk::ImageMemoryBarrier::default()
                    .old_layout(old)
                    .new_layout(new)
                    .src_access_mask(src)
                    .dst_access_mask(dst)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .image(i.image)
                    .subresource_range(subresource(i.key.array_index))
            })
            .collect();
        let colour = vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT;
        let transfer = vk::PipelineStageFlags::TRANSFER;
        let (src, dst) = if to_general {
            (colour, transfer)
        } else {
            (transfer, colour)
        };
        // SAFETY: cmd is recording; the images are the app's, held by the layer until release.
        unsafe {
            self.gpu.device.cmd_pipeline_barrier(
                self.commands.cmd,
                src,
                dst,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &barriers,
            )
        };
    }

    fn copy_region(&self, item: &WorkItem, to_buffer: bool) {
        let target = &self.views[&item.key].target;
        let region = [vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .base_array_layer(item.key.array_index)
                    .layer_count(1),
            )
            .image_offset(vk::Offset3D {
                x: item.key.offset.0,
                y: item.key.offset.1,
                z: 0,
            })
            .image_extent(vk::Extent3D {
                width: item.key.extent.0,
                height: item.key.extent.1,
                depth: 1,
            })];
        let d = &self.gpu.device;
        // SAFETY: cmd is recording; the image is in GENERAL (see image_barriers) and the
        // region lies inside it (checked against the swapchain size when the item was made).
        unsafe {
            if to_buffer {
                d.cmd_copy_image_to_buffer(
                    self.commands.cmd,
                    item.image,
                    vk::ImageLayout::GENERAL,
                    target.pixels.raw,
                    &region,
                );
            } else {
                d.cmd_copy_buffer_to_image(
                    self.commands.cmd,
                    target.pixels.raw,
                    item.image,
                    vk::ImageLayout::GENERAL,
                    &region,
                );
            }
        }
    }

    fn copy_to_capture(&self, item: &WorkItem, dst: &crate::gpu::buffer::GpuBuffer) {
        let src = &self.views[&item.key].target.pixels;
        let region = [vk::BufferCopy::default().size(self.views[&item.key].target.pixel_bytes())];
        // SAFETY: cmd is recording; both buffers are ours and large enough.
        unsafe {
            self.gpu
                .device
                .cmd_copy_buffer(self.commands.cmd, src.raw, dst.raw, &region)
        };
    }

    fn record(
        &mut self,
        items: &[WorkItem],
        params: &Params,
        staging: &[(crate::gpu::buffer::GpuBuffer, crate::gpu::buffer::GpuBuffer)],
    ) -> Result<(), GpuError> {
        self.commands.begin(&self.gpu)?;
        let seq = self.background_sequence;
        let stale: Vec<ViewKey> = {
            let mut seen = HashSet::new();
            items
                .iter()
                .map(|i| i.key)
                .filter(|k| seen.insert(*k) && self.views[k].prepared_for != Some(seq))
                .collect()
        };
        if !stale.is_empty() {
            let bg = self.background.as_ref().expect("set in process");
            let targets: Vec<&ViewTarget> = stale.iter().map(|k| &self.views[k].target).collect();
            self.engine
                .record_background(&self.gpu, self.commands.cmd, bg, &targets, params)?;
        }
        for k in &stale {
            if let Some(v) = self.views.get_mut(k) {
                v.prepared_for = Some(seq);
            }
        }
        let frame = self.frame;
        for i in items {
            if let Some(v) = self.views.get_mut(&i.key) {
                v.last_frame = frame;
            }
        }
        use vk::PipelineStageFlags as S;
        self.image_barriers(items, true);
        items.iter().for_each(|i| self.copy_region(i, true));
        barrier(
            &self.gpu,
            self.commands.cmd,
            S::TRANSFER,
            S::COMPUTE_SHADER | S::TRANSFER,
        );
        for (i, (before, _)) in items.iter().zip(staging) {
            self.copy_to_capture(i, before);
        }
        if !staging.is_empty() {
            // The capture copies read `pixels` before the enhancement writes it.
            barrier(&self.gpu, self.commands.cmd, S::TRANSFER, S::COMPUTE_SHADER);
        }
        for i in items {
            self.engine.record_enhance(
                &self.gpu,
                self.commands.cmd,
                &self.views[&i.key].target,
                params,
            )?;
        }
        barrier(&self.gpu, self.commands.cmd, S::COMPUTE_SHADER, S::TRANSFER);
        let views = items.iter().map(|i| (i.key, &self.views[&i.key].target));
        let now = std::time::Instant::now();
        if self
            .indicator
            .record(&self.gpu, self.commands.cmd, views, now)?
        {
            // The capture and the copy back read what the indicator wrote.
            barrier(&self.gpu, self.commands.cmd, S::TRANSFER, S::TRANSFER);
        }
        for (i, (_, after)) in items.iter().zip(staging) {
            self.copy_to_capture(i, after);
        }
        items.iter().for_each(|i| self.copy_region(i, false));
        self.image_barriers(items, false);
        barrier(&self.gpu, self.commands.cmd, S::TRANSFER, S::HOST);
        Ok(())
    }
}

impl Drop for Processor {
    fn drop(&mut self) {
        let _ = self.wait_idle();
        for (_, mut v) in self.views.drain() {
            self.engine.destroy_view(&self.gpu, &mut v.target);
        }
        if let Some(mut bg) = self.background.take() {
            bg.destroy(&self.gpu);
        }
        self.indicator.destroy(&self.gpu);
        self.engine.destroy(&self.gpu);
        self.commands.destroy(&self.gpu);
    }
}
