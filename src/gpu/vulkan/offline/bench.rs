//! The benchmark behind `contrastxr bench`: GPU time, from timestamp queries, of the plain copy
//! pass (the floor), the per-frame enhancement, everything the layer records per display frame
//! (the enhancement with the copies from and to the app's image: through buffers, in place,
//! through images of the engine's own) and the per-camera-frame
//! background preparation, over the same display regions, on the offline engine's device.

use super::bench_rig::Rig;
use super::offline_engine::VkOffline;
use crate::algorithm::params::Params;
use crate::gpu::core::bench::{median, Ablation, BenchCase, BenchResult, WARM_UP_RUNS};
use crate::gpu::core::{CameraRect, ClassifyChoice};
use crate::gpu::vulkan::device::{
    barrier, record_first_layout, record_image_region_copy, record_layout_barriers,
    record_region_copy, GpuError, ImageRegion, VkResultExt,
};
use crate::gpu::vulkan::record::{record_write_back, record_write_back_barrier, ViewTarget};
use ash::vk;

/// The spans timed in each run, in `timed_run`'s order of recording (a start and an end
/// timestamp each).
#[derive(Clone, Copy)]
enum Span {
    Background,
    CopyWide,
    Copy,
    Enhance,
    Frame,
    ImageCopy,
    FrameInPlace,
    FrameImageCopy,
    ImageCopyCopies,
    FrameImageCopyTiles,
    FrameSampledTiles,
}
const SPANS: usize = 11;
const QUERIES: u32 = 2 * SPANS as u32;

impl VkOffline {
    /// Times one case; `params` are the enhancement's settings (method, blur, ...).
    pub fn bench(&mut self, case: &BenchCase, params: &Params) -> Result<BenchResult, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let mut rig = Rig {
            background: None,
            views: Vec::new(),
            sources: Vec::new(),
            images: Vec::new(),
            staging: None,
            in_place: Vec::new(),
            storage_views: Vec::new(),
            image_copy: Vec::new(),
            own_images: Vec::new(),
            write_back: None,
            write_back_draws: Vec::new(),
            sampled: Vec::new(),
            sampled_views: Vec::new(),
            sampled_draws: Vec::new(),
            queries: vk::QueryPool::null(),
        };
        let ablation = case.ablation;
        self.set_ablation(ablation.bits());
        self.set_shared_fetch(ablation != Ablation::SharedFetch);
        self.set_classify(ablation.classify());
        let result = self.bench_with(&mut rig, case, params);
        self.set_ablation(0);
        self.set_shared_fetch(true);
        self.set_classify(ClassifyChoice::Own);
        self.destroy_rig(rig);
        result
    }

    fn bench_with(
        &mut self,
        rig: &mut Rig,
        case: &BenchCase,
        params: &Params,
    ) -> Result<BenchResult, GpuError> {
        let foreground = self.build_rig(rig, case, QUERIES)?;
        let mut samples: [Vec<f64>; SPANS] = Default::default();
        for run in 0..WARM_UP_RUNS + case.runs {
            let times = self.timed_run(rig, params)?;
            if run >= WARM_UP_RUNS {
                for (s, t) in samples.iter_mut().zip(times) {
                    s.push(t);
                }
            }
        }
        let ms = samples.map(median);
        Ok(BenchResult {
            case: *case,
            copy_ms: ms[Span::Copy as usize],
            copy_wide_ms: rig
                .views
                .iter()
                .all(ViewTarget::copies_wide)
                .then_some(ms[Span::CopyWide as usize]),
            enhance_ms: ms[Span::Enhance as usize],
            frame_ms: ms[Span::Frame as usize],
            image_copy_ms: ms[Span::ImageCopy as usize],
            frame_in_place_ms: (!rig.in_place.is_empty())
                .then_some(ms[Span::FrameInPlace as usize]),
            frame_image_copy_ms: (!rig.image_copy.is_empty())
                .then_some(ms[Span::FrameImageCopy as usize]),
            image_copy_copies_ms: (!rig.image_copy.is_empty())
                .then_some(ms[Span::ImageCopyCopies as usize]),
            frame_image_copy_tiles_ms: (!rig.write_back_draws.is_empty())
                .then_some(ms[Span::FrameImageCopyTiles as usize]),
            frame_sampled_tiles_ms: (!rig.sampled_draws.is_empty())
                .then_some(ms[Span::FrameSampledTiles as usize]),
            background_ms: ms[Span::Background as usize],
            foreground,
        })
    }

    /// What the layer records per display frame around (and, with `enhance`, including) the
    /// enhancement: src/gpu/vulkan/frame/frame_record.rs's `record` less the background and captures.
    fn record_frame(
        &self,
        cmd: vk::CommandBuffer,
        (views, regions): (&[&ViewTarget], &[ImageRegion]),
        params: &Params,
        enhance: bool,
    ) -> Result<(), GpuError> {
        use vk::PipelineStageFlags as S;
        let gpu = &self.gpu;
        record_layout_barriers(gpu, cmd, regions, true);
        for (r, v) in regions.iter().zip(views) {
            record_region_copy(gpu, cmd, r, &v.pixels, true);
        }
        barrier(gpu, cmd, S::TRANSFER, S::COMPUTE_SHADER | S::TRANSFER);
        if enhance {
            let mapping = params.camera_mapping();
            for v in views {
                self.engine.record_enhance(gpu, cmd, v, params, &mapping)?;
            }
            barrier(gpu, cmd, S::COMPUTE_SHADER, S::TRANSFER);
        }
        for (r, v) in regions.iter().zip(views) {
            record_region_copy(gpu, cmd, r, &v.pixels, false);
        }
        record_layout_barriers(gpu, cmd, regions, false);
        Ok(())
    }

    /// What the layer records per display frame in place: gpu/vulkan/frame/frame_record.rs's `record` for
    /// in-place views, less the background and captures. Nothing without in-place views.
    fn record_frame_in_place(
        &self,
        cmd: vk::CommandBuffer,
        rig: &Rig,
        regions: &[ImageRegion],
        params: &Params,
    ) -> Result<(), GpuError> {
        if rig.in_place.is_empty() {
            return Ok(());
        }
        let gpu = &self.gpu;
        record_layout_barriers(gpu, cmd, regions, true);
        let mapping = params.camera_mapping();
        for v in &rig.in_place {
            self.engine.record_enhance(gpu, cmd, v, params, &mapping)?;
        }
        record_layout_barriers(gpu, cmd, regions, false);
        Ok(())
    }

    /// What the layer records per display frame through the image-copy path
    /// (gpu/vulkan/frame/frame_record.rs's `record` for such views, less the background and captures):
    /// with `enhance`, the passes between the copies; with `tiles` (and `enhance`), the listed
    /// tiles drawn back instead of the regions copied back. Nothing without image-copy views.
    fn record_frame_image_copy(
        &self,
        cmd: vk::CommandBuffer,
        rig: &Rig,
        (regions, params): (&[ImageRegion], &Params),
        (enhance, tiles): (bool, bool),
    ) -> Result<(), GpuError> {
        if rig.image_copy.is_empty() || (tiles && rig.write_back_draws.is_empty()) {
            return Ok(());
        }
        use vk::PipelineStageFlags as S;
        let gpu = &self.gpu;
        record_layout_barriers(gpu, cmd, regions, true);
        let own: Vec<vk::Image> = rig.own_images.iter().map(|i| i.image.raw).collect();
        let write = (S::TRANSFER, vk::AccessFlags::TRANSFER_WRITE);
        record_first_layout(gpu, cmd, &own, vk::ImageLayout::GENERAL, write);
        for (r, o) in regions.iter().zip(&own) {
            record_image_region_copy(gpu, cmd, r, *o, true);
        }
        barrier(gpu, cmd, S::TRANSFER, S::COMPUTE_SHADER | S::TRANSFER);
        if enhance {
            let mapping = params.camera_mapping();
            for v in &rig.image_copy {
                self.engine.record_enhance(gpu, cmd, v, params, &mapping)?;
            }
        }
        if enhance && tiles {
            let pipelines = rig.write_back.as_ref().expect("made with the draws");
            record_write_back_barrier(gpu, cmd);
            for (draw, _) in &rig.write_back_draws {
                record_write_back(gpu, cmd, pipelines, draw);
            }
        } else {
            if enhance {
                barrier(gpu, cmd, S::COMPUTE_SHADER, S::TRANSFER);
            }
            for (r, o) in regions.iter().zip(&own) {
                record_image_region_copy(gpu, cmd, r, *o, false);
            }
        }
        record_layout_barriers(gpu, cmd, regions, false);
        Ok(())
    }

    /// What the layer records per display frame through the sampled read: each region read
    /// through a sampled view of its app image, enhanced into the engine's image and its listed
    /// tiles drawn back. Nothing without such views.
    fn record_frame_sampled(
        &self,
        cmd: vk::CommandBuffer,
        rig: &Rig,
        (regions, params): (&[ImageRegion], &Params),
    ) -> Result<(), GpuError> {
        if rig.sampled_draws.is_empty() {
            return Ok(());
        }
        use vk::{AccessFlags as A, PipelineStageFlags as S};
        let gpu = &self.gpu;
        record_layout_barriers(gpu, cmd, regions, true);
        let own: Vec<vk::Image> = rig.own_images.iter().map(|i| i.image.raw).collect();
        let write = (S::COMPUTE_SHADER, A::SHADER_READ | A::SHADER_WRITE);
        record_first_layout(gpu, cmd, &own, vk::ImageLayout::GENERAL, write);
        let mapping = params.camera_mapping();
        for v in &rig.sampled {
            self.engine.record_enhance(gpu, cmd, v, params, &mapping)?;
        }
        let pipelines = rig.write_back.as_ref().expect("made with the draws");
        record_write_back_barrier(gpu, cmd);
        for (draw, _) in &rig.sampled_draws {
            record_write_back(gpu, cmd, pipelines, draw);
        }
        record_layout_barriers(gpu, cmd, regions, false);
        Ok(())
    }

    fn timestamp(&self, cmd: vk::CommandBuffer, pool: vk::QueryPool, query: u32) {
        // SAFETY: cmd is recording; the query was reset in this command buffer. BOTTOM_OF_PIPE:
        // written once all earlier commands are complete.
        unsafe {
            self.gpu.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                pool,
                query,
            )
        };
    }

    /// One run: background, 16-byte copy, copy (which also restores the pristine pixels),
    /// enhancement, then (after restoring the app images' content, untimed) the layer's whole
    /// frame and its image copies alone, in place, through the image-copy path (with its
    /// copies alone), through the image-copy path with the tiles drawn back and through the
    /// sampled read. Returns each Span's GPU time in milliseconds (the 16-byte copy's is 0
    /// where the rows do not allow it).
    fn timed_run(&mut self, rig: &Rig, params: &Params) -> Result<[f64; SPANS], GpuError> {
        let all = vk::PipelineStageFlags::ALL_COMMANDS;
        let views: Vec<&ViewTarget> = rig.views.iter().collect();
        let regions = rig.regions(views[0].region);
        let background = rig.background.as_ref().expect("made before");
        let mapping = params.camera_mapping();
        self.submit(|cmd| {
            let (gpu, engine, q) = (&self.gpu, &self.engine, rig.queries);
            // SAFETY: cmd is recording; the pool is ours and not in use by pending work.
            unsafe { gpu.device.cmd_reset_query_pool(cmd, q, 0, QUERIES) };
            let timed = |span: Span, record: &mut dyn FnMut() -> Result<(), GpuError>| {
                barrier(gpu, cmd, all, all);
                self.timestamp(cmd, q, 2 * span as u32);
                let done = record();
                self.timestamp(cmd, q, 2 * span as u32 + 1);
                done
            };
            let rect = CameraRect::sampled_by(&vec![mapping; views.len()], background.size);
            timed(Span::Background, &mut || {
                engine.record_background(gpu, cmd, background, params, &rect)
            })?;
            timed(Span::CopyWide, &mut || {
                views.iter().for_each(|v| {
                    engine.record_copy_wide(gpu, cmd, v);
                });
                Ok(())
            })?;
            timed(Span::Copy, &mut || {
                views
                    .iter()
                    .try_for_each(|v| engine.record_copy(gpu, cmd, v))
            })?;
            timed(Span::Enhance, &mut || {
                for v in &views {
                    engine.record_enhance(gpu, cmd, v, params, &mapping)?;
                }
                Ok(())
            })?;
            barrier(gpu, cmd, all, all);
            self.restore_images(cmd, rig, &regions);
            let both = (views.as_slice(), regions.as_slice());
            timed(Span::Frame, &mut || {
                self.record_frame(cmd, both, params, true)
            })?;
            timed(Span::ImageCopy, &mut || {
                self.record_frame(cmd, both, params, false)
            })?;
            barrier(gpu, cmd, all, all);
            self.restore_images(cmd, rig, &regions);
            timed(Span::FrameInPlace, &mut || {
                self.record_frame_in_place(cmd, rig, &regions, params)
            })?;
            barrier(gpu, cmd, all, all);
            self.restore_images(cmd, rig, &regions);
            let image_copy = (regions.as_slice(), params);
            timed(Span::FrameImageCopy, &mut || {
                self.record_frame_image_copy(cmd, rig, image_copy, (true, false))
            })?;
            timed(Span::ImageCopyCopies, &mut || {
                self.record_frame_image_copy(cmd, rig, image_copy, (false, false))
            })?;
            barrier(gpu, cmd, all, all);
            self.restore_images(cmd, rig, &regions);
            timed(Span::FrameImageCopyTiles, &mut || {
                self.record_frame_image_copy(cmd, rig, image_copy, (true, true))
            })?;
            barrier(gpu, cmd, all, all);
            self.restore_images(cmd, rig, &regions);
            timed(Span::FrameSampledTiles, &mut || {
                self.record_frame_sampled(cmd, rig, image_copy)
            })
        })?;
        let mut ticks = [0u64; QUERIES as usize];
        // SAFETY: the submission was waited for; every query was written by it.
        unsafe {
            self.gpu.device.get_query_pool_results(
                rig.queries,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let ms = f64::from(self.gpu.timestamp_period()) / 1e6;
        Ok(std::array::from_fn(|k| {
            ticks[2 * k + 1].wrapping_sub(ticks[2 * k]) as f64 * ms
        }))
    }
}
