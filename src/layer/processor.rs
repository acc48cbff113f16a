//! A session's GPU work at xrEndFrame: for each view region, copy it out of the app's image
//! into the engine's buffer, enhance it, and copy it back, on the app's device and queue.
//! The image is still the app's at that point (its release is held until xrEndFrame).

use super::work::{ViewKey, WorkItem};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::buffer::record_buffer_copy;
use crate::gpu::commands::Commands;
use crate::gpu::engine::barrier;
use crate::gpu::image_copy::{record_layout_barriers, record_region_copy, ImageRegion};
use crate::gpu::pipelines::{BuildMode, BuildReport, ShaderId};
use crate::gpu::warm_up::{WarmUp, WarmUpSlot};
use crate::gpu::{BackgroundFrame, CameraRect, Engine, GpuDevice, GpuError, Placement, ViewTarget};
use crate::image::RgbaImage;
use ash::vk;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long a session that waits for its pipelines (`pipelines = "wait"`) waits at most.
const PIPELINE_WAIT: Duration = Duration::from_secs(120);

/// Most view regions a session keeps buffers for (2 eyes x a few swapchains and quads).
const MAX_VIEWS: u32 = 16;

struct PreparedView {
    target: ViewTarget,
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
    /// The background sequence the blurred camera image was prepared for (once per camera
    /// frame, whatever the number of views), and the camera texels prepared.
    prepared_for: Option<(u64, CameraRect)>,
    views: HashMap<ViewKey, PreparedView>,
    frame: u64,
    /// The in-headset indicator drawn after the enhancement (its timer is set by the session).
    pub indicator: super::indicator::Indicator,
    /// When the session started (xrCreateSession).
    pub started: Instant,
    /// The warm-up device (CPU drivers), dropped here on the app's thread after the pipeline
    /// thread that uses it has ended.
    warm_up: Option<WarmUpSlot>,
    // Last: dropped after everything above was destroyed in Drop.
    pub gpu: GpuDevice,
}

impl Processor {
    /// Sets up the engine on the session's device; its pipelines start building at once on
    /// the engine's own thread, `first` first.
    pub fn new(gpu: GpuDevice, first: &[ShaderId]) -> Result<Processor, GpuError> {
        let started = Instant::now();
        let (warm_up, hook) = WarmUp::slot(&gpu).unzip();
        let mut engine = Engine::new(&gpu, MAX_VIEWS, BuildMode::Background, hook)?;
        let commands = match Commands::new(&gpu) {
            Ok(c) => c,
            Err(e) => {
                engine.destroy(&gpu);
                return Err(e);
            }
        };
        let processor = Processor {
            engine,
            commands,
            background: None,
            background_sequence: 0,
            prepared_for: None,
            views: HashMap::new(),
            frame: 0,
            indicator: Default::default(),
            started,
            warm_up,
            gpu,
        };
        processor.request(first);
        Ok(processor)
    }

    /// Tells the pipeline thread to stop, without waiting: the session passes through from now
    /// on, and the processor is dropped only at xrDestroySession.
    pub fn stop_building(&self) {
        self.engine.stop_building();
    }

    /// Queues shaders to build ahead of earlier requests (at xrCreateSession, and when a
    /// swapchain's format becomes known). On the app's thread: a CPU driver's warm-up device
    /// is made here when one of them needs it, never on the pipeline thread (gpu/warm_up.rs).
    pub fn request(&self, ids: &[ShaderId]) {
        self.prepare_warm_up(ids);
        self.engine.request(ids);
    }

    /// Makes the warm-up device (CPU drivers) if one of `ids` needs it and it does not exist.
    fn prepare_warm_up(&self, ids: &[ShaderId]) {
        let Some(slot) = &self.warm_up else { return };
        let t = Instant::now();
        match WarmUp::prepare(slot, &self.gpu, ids) {
            Some(Ok(())) => super::log::debug(&format!(
                "warm-up device made on the app's thread in {:.3} s",
                t.elapsed().as_secs_f64()
            )),
            Some(Err(e)) => super::log::debug(&format!(
                "no warm-up device ({e}): shaders compile at their first dispatch"
            )),
            None => {}
        }
    }

    pub fn build_report(&self) -> Option<BuildReport> {
        self.engine.build_report()
    }

    /// Whether the pipelines these items need are built: if not, they are requested and,
    /// with `wait`, waited for; without it the frame is [`GpuError::Pending`].
    pub fn pipelines_ready(
        &self,
        items: &[WorkItem],
        params: &Params,
        wait: bool,
    ) -> Result<(), GpuError> {
        let views = items.iter().map(|i| (i.format, i.key.extent.0));
        let ids = Engine::shaders_for(params, views)?;
        self.prepare_warm_up(&ids);
        match self.engine.ready(&ids)? {
            true => Ok(()),
            false if wait => self.engine.wait_for(&ids, PIPELINE_WAIT),
            false => Err(GpuError::Pending),
        }
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
            }
            self.background = Some(bg);
            self.prepared_for = None;
        }
        let bg = self.background.as_mut().expect("created above");
        bg.upload(&image.pixels)?;
        self.background_sequence = sequence;
        Ok(())
    }

    /// Makes the view of `item` exist, evicting the least recently used view that is not one
    /// of `in_use` (the items of this submission) when the engine holds MAX_VIEWS already.
    fn ensure_view(&mut self, item: &WorkItem, in_use: &[WorkItem]) -> Result<(), GpuError> {
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
            self.evict_oldest(in_use);
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
                last_frame: self.frame,
            },
        );
        Ok(())
    }

    fn evict_oldest(&mut self, in_use: &[WorkItem]) {
        let oldest = self
            .views
            .iter()
            .filter(|(k, _)| !in_use.iter().any(|i| i.key == **k))
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
    /// before and after (waiting for the GPU). [`GpuError::Pending`], with nothing recorded,
    /// while a pipeline it needs is still being built (unless `wait_for_pipelines`).
    pub fn process(
        &mut self,
        items: &[WorkItem],
        background: &Arc<RgbaImage>,
        sequence: u64,
        params: &Params,
        (capture, wait_for_pipelines): (bool, bool),
    ) -> Result<Vec<CapturedView>, GpuError> {
        self.pipelines_ready(items, params, wait_for_pipelines)?;
        crate::fault::check("image-capture").map_err(GpuError::Unsupported)?;
        // The previous submission read the camera buffer the upload writes.
        self.wait_idle()?;
        self.update_background(background, sequence)?;
        // More regions than the engine holds views for: one submission per MAX_VIEWS.
        let mut captured = Vec::new();
        for part in items.chunks(MAX_VIEWS as usize) {
            captured.extend(self.process_part(part, params, capture)?);
        }
        Ok(captured)
    }

    /// `process` for at most MAX_VIEWS items (their views all exist at once).
    fn process_part(
        &mut self,
        items: &[WorkItem],
        params: &Params,
        capture: bool,
    ) -> Result<Vec<CapturedView>, GpuError> {
        self.frame += 1;
        self.wait_idle()?;
        for item in items {
            self.ensure_view(item, items)?;
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
        // The capture buffers may be freed only once the GPU is done with them; when it is
        // not, they are left alive (the error then ends the session's enhancement).
        let idle = match staging.is_empty() {
            true => Ok(()),
            false => self.wait_idle(),
        };
        for (item, (mut before, mut after)) in items.iter().zip(staging) {
            if result.is_ok() {
                captured.push(CapturedView {
                    item: item.clone(),
                    display: before.mapped().unwrap_or_default().to_vec(),
                    output: after.mapped().unwrap_or_default().to_vec(),
                });
            }
            if idle.is_ok() {
                before.destroy(&self.gpu);
                after.destroy(&self.gpu);
            }
        }
        result.and(idle).map(|_| captured)
    }

    fn submit(&mut self) -> Result<(), GpuError> {
        // Inside xrEndFrame: the OpenXR spec gives the runtime, and so its layers, the app's
        // queue during this call.
        self.commands.submit(&self.gpu)
    }

    fn image_barriers(&self, items: &[WorkItem], to_general: bool) {
        let regions: Vec<ImageRegion> = items.iter().map(WorkItem::region).collect();
        record_layout_barriers(&self.gpu, self.commands.cmd, &regions, to_general);
    }

    fn copy_region(&self, item: &WorkItem, to_buffer: bool) {
        let pixels = &self.views[&item.key].target.pixels;
        let cmd = self.commands.cmd;
        record_region_copy(&self.gpu, cmd, &item.region(), pixels, to_buffer);
    }

    fn copy_to_capture(&self, item: &WorkItem, dst: &crate::gpu::buffer::GpuBuffer) {
        let src = &self.views[&item.key].target.pixels;
        let region = [vk::BufferCopy::default().size(self.views[&item.key].target.pixel_bytes())];
        record_buffer_copy(&self.gpu, self.commands.cmd, (src, dst), &region);
    }

    fn record(
        &mut self,
        items: &[WorkItem],
        params: &Params,
        staging: &[(crate::gpu::buffer::GpuBuffer, crate::gpu::buffer::GpuBuffer)],
    ) -> Result<(), GpuError> {
        self.commands.begin(&self.gpu)?;
        let seq = self.background_sequence;
        let bg = self.background.as_ref().expect("set in process");
        let mappings: Vec<CameraMapping> = items.iter().map(|i| i.mapping).collect();
        let needed = CameraRect::sampled_by(&mappings, bg.size);
        let rect = match self.prepared_for {
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
                &i.mapping,
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
    /// Runs on the app's thread (xrDestroySession, xrDestroyInstance, or a failed set-up).
    fn drop(&mut self) {
        let idle = self.wait_idle();
        // The pipeline thread uses the app's device: it ends before anything is destroyed.
        self.engine.join_building();
        if let Err(e) = idle {
            super::log::info(&format!(
                "the GPU did not finish the layer's last work ({e}): its objects are left alive, not destroyed"
            ));
            self.gpu.abandon();
            return;
        }
        for (_, mut v) in self.views.drain() {
            self.engine.destroy_view(&self.gpu, &mut v.target);
        }
        if let Some(mut bg) = self.background.take() {
            bg.destroy(&self.gpu);
        }
        self.indicator.destroy(&self.gpu);
        self.engine.destroy(&self.gpu);
        // Waited for above: this wait cannot fail.
        let _ = self.commands.destroy(&self.gpu);
        // The pipeline thread that dispatched on it has ended (joined above).
        drop(self.warm_up.take());
    }
}
