//! A session's GPU work for one frame, recorded and submitted in one call: the background's
//! upload and preparation, then for each view region of the app's images: copy it out into
//! the engine's buffer, enhance it, draw the overlay, copy it back, on the app's device and
//! queue. Used by the layer inside xrEndFrame, where the images are still the app's (their
//! release is held until then). Knows nothing of OpenXR.

use super::app_views::AppImageViews;
use super::frame_times::FrameTimes;
use super::frame_view::{CapturedView, FrameView, ViewKey, ViewPath};
use super::overlay_copies::Overlays;
use super::prepared_view::PreparedView;
use super::tile_write_back::TileWriteBack;
use super::warm_up::{WarmUp, WarmUpMade};
use crate::algorithm::params::Params;
use crate::gpu::core::shader_ids::ShaderId;
use crate::gpu::core::BackgroundInput;
use crate::gpu::core::CameraRect;
use crate::gpu::core::OverlayPixels;
use crate::gpu::vulkan::conv::VkFormat;
use crate::gpu::vulkan::device::{Commands, GpuDevice, GpuError, StorageImage};
use crate::gpu::vulkan::pipelines::{BuildMode, BuildReport};
use crate::gpu::vulkan::record::{CameraResources, Placement, Recorder, ViewTarget};
use crate::gpu::vulkan::texels::TexelRing;
use crate::image::RgbaImage;
use ash::vk;
use std::collections::HashMap;
use std::time::Duration;

/// How long a session that waits for its pipelines (`pipelines = "wait"`) waits at most.
const PIPELINE_WAIT: Duration = Duration::from_secs(120);

/// How long a frame call waits for the engine's last work before reusing what it used.
const IDLE_WAIT_NS: u64 = 5_000_000_000;
/// How long the engine's end (xrDestroySession, xrDestroyInstance) waits for its last work:
/// a frame's work takes milliseconds; past this the GPU is taken as hung and the objects are
/// left alive rather than destroyed under it.
const END_WAIT_NS: u64 = 250_000_000;

/// Most view regions a session keeps buffers for (2 eyes x a few swapchains and quads).
const MAX_VIEWS: u32 = 16;

/// What a frame asks for besides the enhancement.
#[derive(Clone, Copy, Default)]
pub struct FrameOptions {
    /// Read each view back before and after (waits for the GPU).
    pub capture: bool,
    /// Wait for pipelines still being built instead of returning [`GpuError::Pending`].
    pub wait_for_pipelines: bool,
}

/// The pipelines of a frame's views are built: `pipelines_ready` gives it, `process` takes it,
/// so that a frame checks them once and records nothing before they are.
#[must_use]
#[derive(Debug)]
pub struct PipelinesReady(());

pub struct FrameRunner {
    pub(super) engine: Recorder,
    pub(super) commands: Commands,
    pub(super) background: Option<CameraResources>,
    pub(super) background_sequence: u64,
    /// The background sequence the blurred camera image was prepared for (once per camera
    /// frame, whatever the number of views), and the camera texels prepared.
    pub(super) prepared_for: Option<(u64, CameraRect)>,
    /// The camera buffer does not hold the frame in use (its texels came prepared).
    pub(super) camera_behind: bool,
    /// Where prepared texels are written: mapped images the views sample where the device
    /// allows (`direct_texels`), else staging buffers.
    pub(super) ring: TexelRing,
    pub(super) direct_texels: bool,
    pub(super) views: HashMap<ViewKey, PreparedView>,
    pub(super) frame: u64,
    /// Lit pixels drawn over the views after the enhancement.
    pub(super) overlays: Overlays,
    /// Views of the app's image layers: storage views for in place, sampled views for the
    /// sampled read.
    pub(super) app_views: AppImageViews,
    /// The image-copy path's tiles drawn back: pipelines, attachments, the frame's draws.
    pub(super) tiles: TileWriteBack,
    /// Each frame's GPU time, from timestamps around its submissions.
    pub(super) times: FrameTimes,
    /// Set once the engine's objects were destroyed (or left alive after a GPU failure).
    torn_down: bool,
    /// What making the process's warm-up device (CPU drivers) gave, when this session's
    /// start made or tried to make one; taken by [`FrameRunner::warm_up_made`].
    warm_up_made: Option<WarmUpMade>,
    // Last: dropped after everything above was destroyed in Drop.
    pub gpu: GpuDevice,
}

impl FrameRunner {
    /// Sets up the engine on the session's device; its pipelines start building at once on
    /// the engine's own thread, `first` first.
    pub fn new(gpu: GpuDevice, first: &[ShaderId]) -> Result<FrameRunner, GpuError> {
        // Here, inside the app's xrCreateSession: never in a later call (gpu/vulkan/frame/warm_up.rs).
        let (hook, warm_up_made) = WarmUp::for_session(&gpu);
        let mut engine = Recorder::new(&gpu, MAX_VIEWS, BuildMode::Background, hook)?;
        let commands = match Commands::new(&gpu) {
            Ok(c) => c,
            Err(e) => {
                engine.destroy(&gpu);
                return Err(e);
            }
        };
        let frame_runner = FrameRunner {
            engine,
            commands,
            background: None,
            background_sequence: 0,
            prepared_for: None,
            camera_behind: false,
            ring: TexelRing::default(),
            direct_texels: TexelRing::supported(&gpu),
            views: HashMap::new(),
            frame: 0,
            overlays: Overlays::default(),
            app_views: AppImageViews::default(),
            tiles: TileWriteBack::default(),
            times: FrameTimes::new(&gpu),
            torn_down: false,
            warm_up_made,
            gpu,
        };
        frame_runner.request(first);
        Ok(frame_runner)
    }

    /// Tells the pipeline thread to stop, without waiting: the session passes through from now
    /// on, and the processor is dropped only at xrDestroySession.
    pub fn stop_building(&self) {
        self.engine.stop_building();
    }

    /// Queues shaders to build ahead of earlier requests (at xrCreateSession, and when a
    /// swapchain's format becomes known).
    pub fn request(&self, ids: &[ShaderId]) {
        self.engine.request(ids);
    }

    /// What making the process's warm-up device gave, when the session's start made (or tried
    /// to make) one; None afterwards.
    pub fn warm_up_made(&mut self) -> Option<WarmUpMade> {
        self.warm_up_made.take()
    }

    /// The GPU time of each frame's work measured since the last call, oldest first: from
    /// when the queue's earlier work (the app's frame) finished to when the frame's own did.
    /// Empty where the queue writes no timestamps.
    pub fn take_gpu_times(&mut self) -> Vec<Duration> {
        self.times.take()
    }

    pub fn build_report(&self) -> Option<BuildReport> {
        self.engine.build_report()
    }

    /// Why the tiles of a format cannot be drawn back (`ViewPath::ImageCopyTiles`; its views
    /// copy the region back), if they cannot.
    pub fn write_back_failure(&self) -> Option<String> {
        self.tiles.failure()
    }

    /// Whether the pipelines these items need are built: if not, they are requested and,
    /// with `wait`, waited for; without it the frame is [`GpuError::Pending`]. A frame's one
    /// check: `process` takes what it gives.
    pub fn pipelines_ready(
        &self,
        views: &[FrameView],
        params: &Params,
        wait: bool,
    ) -> Result<PipelinesReady, GpuError> {
        let shapes = views.iter().map(FrameView::shape);
        let ids = Recorder::shaders_for(params, shapes, self.engine.cube_roots())?;
        match self.engine.ready(&ids)? {
            true => Ok(PipelinesReady(())),
            false if wait => self
                .engine
                .wait_for(&ids, PIPELINE_WAIT)
                .map(|()| PipelinesReady(())),
            false => Err(GpuError::Pending),
        }
    }

    /// Queues the shared-fetch variants this frame's views could take (gpu/core/shared_fetch.rs)
    /// and are not built yet, with their warm-up. Never waited for: until one is built, its
    /// views take the general variant, whose output is the same.
    fn request_shared_fetches(&self, views: &[FrameView], params: &Params, camera: &RgbaImage) {
        let shapes = views.iter().map(|v| (v.shape(), v.key.extent, &v.mapping));
        let size = (camera.width, camera.height);
        let ids = self.engine.shared_fetch_shaders_for(params, shapes, size);
        if ids.is_empty() {
            return;
        }
        // A failed build only means the general variant.
        let _ = self.engine.ready(&ids);
    }

    /// Waits for the previous submission (normally long done) so its buffers can be reused.
    pub(super) fn wait_idle(&mut self) -> Result<(), GpuError> {
        self.wait_idle_within(IDLE_WAIT_NS)
    }

    fn wait_idle_within(&mut self, timeout_ns: u64) -> Result<(), GpuError> {
        self.commands.wait(&self.gpu, timeout_ns)?;
        self.ring.finished_through(self.commands.finished_through());
        self.times.read(&self.gpu);
        Ok(())
    }

    /// Makes the GPU background frame hold `image` (sequence identifies a new camera frame).
    pub(super) fn update_background(
        &mut self,
        image: &RgbaImage,
        sequence: u64,
    ) -> Result<(), GpuError> {
        if self.background.is_some() && self.background_sequence == sequence {
            return Ok(());
        }
        self.ensure_background((image.width, image.height))?;
        let bg = self.background.as_mut().expect("made above");
        bg.upload(&image.pixels)?;
        self.background_sequence = sequence;
        Ok(())
    }

    /// Makes the GPU background frame exist at `size` (views are bound to it).
    pub(super) fn ensure_background(&mut self, size: (u32, u32)) -> Result<(), GpuError> {
        if self.background.as_ref().is_none_or(|b| b.size != size) {
            if let Some(mut old) = self.background.take() {
                old.destroy(&self.gpu);
            }
            let bg = self
                .engine
                .create_background(&self.gpu, size, Placement::DEVICE)?;
            for v in self.views.values_mut() {
                self.engine.bind(&self.gpu, &mut v.target, &bg);
                v.texels = bg.texels_view();
            }
            self.background = Some(bg);
            self.prepared_for = None;
        }
        Ok(())
    }

    /// Makes the view of `item` exist, evicting the least recently used view that is not one
    /// of `in_use` (the items of this submission) when the engine holds MAX_VIEWS already.
    fn ensure_view(&mut self, item: &FrameView, in_use: &[FrameView]) -> Result<(), GpuError> {
        let image_copy = item.path.writes_own_image();
        if self
            .views
            .get(&item.key)
            .is_some_and(|v| v.target.shape() == item.shape() && v.own.is_some() == image_copy)
        {
            return Ok(());
        }
        if let Some(mut old) = self.views.remove(&item.key) {
            old.destroy(&self.engine, &self.gpu);
        }
        if self.views.len() as u32 >= MAX_VIEWS {
            self.evict_oldest(in_use);
        }
        let bg = self
            .background
            .as_ref()
            .expect("background is set before views");
        let shape = (item.shape(), item.key.extent.1);
        let mut target = self
            .engine
            .create_shaped_view(&self.gpu, shape, bg, Placement::DEVICE)?;
        let texels = bg.texels_view();
        let own = match image_copy {
            true => match self.own_image(item, &target) {
                Ok(own) => Some(own),
                Err(e) => {
                    self.engine.destroy_view(&self.gpu, &mut target);
                    return Err(e);
                }
            },
            false => None,
        };
        self.views.insert(
            item.key,
            PreparedView {
                target,
                last_frame: self.frame,
                texels,
                own,
                write_back_set: None,
            },
        );
        Ok(())
    }

    /// The image-copy path's image for `item`, bound as `target`'s `app_image` (the region
    /// at its origin).
    fn own_image(&self, item: &FrameView, target: &ViewTarget) -> Result<StorageImage, GpuError> {
        let format = item.format.image_copy_format().ok_or_else(|| {
            GpuError::Unsupported(format!("{:?} has no image-copy format", item.format))
        })?;
        let own = StorageImage::for_copies(&self.gpu, item.key.extent, format)?;
        self.engine.bind_app_image(&self.gpu, target, own.view);
        Ok(own)
    }

    fn evict_oldest(&mut self, in_use: &[FrameView]) {
        let oldest = self
            .views
            .iter()
            .filter(|(k, _)| !in_use.iter().any(|i| i.key == **k))
            .min_by_key(|(_, v)| v.last_frame)
            .map(|(k, _)| *k);
        if let Some(mut v) = oldest.and_then(|k| self.views.remove(&k)) {
            v.destroy(&self.engine, &self.gpu);
        }
    }

    /// Drops the buffers of a destroyed swapchain's views.
    /// An error when the GPU did not finish: the swapchain's views then stay alive (and the
    /// caller must stop using this engine: their handles may be given out again).
    pub fn forget_swapchain(&mut self, swapchain: u64) -> Result<(), GpuError> {
        crate::fault::check("swapchain-wait").map_err(GpuError::Unsupported)?;
        self.wait_idle()?;
        let keys: Vec<ViewKey> = self
            .views
            .keys()
            .filter(|k| k.swapchain == swapchain)
            .copied()
            .collect();
        for k in keys {
            if let Some(mut v) = self.views.remove(&k) {
                v.destroy(&self.engine, &self.gpu);
            }
        }
        self.app_views.forget(&self.gpu, swapchain);
        self.tiles.forget(&self.gpu, swapchain);
        Ok(())
    }

    /// Enhances every view's region of the app's images in place, and draws `overlay` over
    /// them. With `capture`, also reads back each region before and after (waiting for the
    /// GPU). `ready` is `pipelines_ready`'s answer for the same views and parameters.
    pub fn process(
        &mut self,
        ready: PipelinesReady,
        views: &[FrameView],
        background: BackgroundInput,
        params: &Params,
        overlay: Option<&OverlayPixels>,
        options: FrameOptions,
    ) -> Result<Vec<CapturedView>, GpuError> {
        let PipelinesReady(()) = ready;
        self.times.next_frame();
        self.request_shared_fetches(views, params, background.image);
        crate::fault::check("image-capture").map_err(GpuError::Unsupported)?;
        // Before the wait: prepared texels may be in, or go into, a slot no submitted frame reads.
        let written = self.write_direct(&background, views, params, false)?;
        // The previous submission read the camera buffer the upload writes.
        self.wait_idle()?;
        if !written && !self.stage_prepared(&background, views, params)? {
            self.upload_unprepared(&background)?;
        }
        // More regions than the engine holds views for: one submission per MAX_VIEWS.
        let mut captured = Vec::new();
        for part in views.chunks(MAX_VIEWS as usize) {
            captured.extend(self.process_part(part, params, overlay, options)?);
        }
        Ok(captured)
    }

    /// `process` for at most MAX_VIEWS views (their buffers all exist at once).
    fn process_part(
        &mut self,
        items: &[FrameView],
        params: &Params,
        overlay: Option<&OverlayPixels>,
        options: FrameOptions,
    ) -> Result<Vec<CapturedView>, GpuError> {
        let capture = options.capture;
        self.frame += 1;
        self.wait_idle()?;
        for item in items {
            self.ensure_view(item, items)?;
        }
        for item in items.iter().filter(|i| i.path == ViewPath::InPlace) {
            self.bind_app_image(item)?;
        }
        for item in items.iter().filter(|i| i.path.reads_sampled()) {
            self.bind_app_texels(item)?;
        }
        self.bind_texels(items);
        let wait = options.wait_for_pipelines;
        self.tiles
            .prepare(&self.gpu, (items, wait), &mut self.views);
        let mut staging = Vec::new();
        if capture {
            for item in items {
                let bytes = self.views[&item.key].target.pixel_bytes();
                let usage = vk::BufferUsageFlags::TRANSFER_DST;
                let loc = gpu_allocator::MemoryLocation::GpuToCpu;
                let before = crate::gpu::vulkan::device::GpuBuffer::new(
                    &self.gpu, bytes, usage, loc, "capture",
                )?;
                let after = crate::gpu::vulkan::device::GpuBuffer::new(
                    &self.gpu, bytes, usage, loc, "capture",
                )?;
                staging.push((before, after));
            }
        }
        let recorded = self.record(items, params, overlay, &staging);
        let submitted = recorded.and_then(|_| self.submit());
        if submitted.is_ok() {
            items
                .iter()
                .for_each(|i| self.views[&i.key].target.model_submitted());
        }
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
                    view: self.as_taken(item),
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
}

impl FrameRunner {
    /// Ends the engine: waits for its last work and its pipeline thread, then destroys what it
    /// made. An error says the GPU did not finish, and the objects were left alive.
    pub fn finish(mut self) -> Result<(), GpuError> {
        self.tear_down()
    }

    fn tear_down(&mut self) -> Result<(), GpuError> {
        if self.torn_down {
            return Ok(());
        }
        self.torn_down = true;
        // On every path, also when the GPU never finishes: the source's thread writes the
        // mapped images no more (the app may free them with its device right after).
        self.ring.close_to_source();
        let idle = crate::fault::check("device-lost")
            .map_err(|_| GpuError::Vulkan {
                call: "vkWaitForFences",
                result: ash::vk::Result::ERROR_DEVICE_LOST,
            })
            .and_then(|()| self.wait_idle_within(END_WAIT_NS));
        // The pipeline thread uses the app's device: it ends before anything is destroyed. It
        // stops at once unless it is creating a pipeline on the app's device (a warm-up in
        // flight is not waited for: see gpu/vulkan/frame/warm_up.rs).
        self.engine.join_building();
        if let Err(e) = idle {
            self.gpu.abandon();
            return Err(e);
        }
        for (_, mut v) in self.views.drain() {
            v.destroy(&self.engine, &self.gpu);
        }
        if let Some(mut bg) = self.background.take() {
            bg.destroy(&self.gpu);
        }
        self.overlays.destroy(&self.gpu);
        self.ring.destroy(&self.gpu);
        self.app_views.destroy(&self.gpu);
        self.tiles.destroy(&self.gpu);
        self.engine.destroy(&self.gpu);
        self.times.destroy(&self.gpu);
        // Waited for above: this wait cannot fail.
        let _ = self.commands.destroy(&self.gpu);
        Ok(())
    }
}

impl Drop for FrameRunner {
    /// Runs on the app's thread (xrDestroySession, xrDestroyInstance, or a failed set-up),
    /// when [`FrameRunner::finish`] was not called.
    fn drop(&mut self) {
        let _ = self.tear_down();
    }
}
