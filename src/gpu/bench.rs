//! The benchmark behind `contrastxr bench`: GPU time, from timestamp queries, of the plain copy
//! pass (the floor), the per-frame enhancement, everything the layer records per display frame
//! (the enhancement with the copies from and to the app's image) and the per-camera-frame
//! background preparation, over the same display regions, on the offline engine's device.

use super::app_image::AppImage;
use super::buffer::GpuBuffer;
use super::engine::{barrier, CameraRect, Placement, ViewTarget};
use super::error::{GpuError, VkResultExt};
use super::format::PixelFormat;
use super::image_copy::{record_layout_barriers, record_region_copy, ImageRegion};
use super::offline::OfflineEngine;
use super::BackgroundFrame;
use crate::algorithm::params::Params;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// The camera frame size the background preparation is timed with (a common camera mode).
pub const CAMERA_SIZE: (u32, u32) = (1280, 720);
/// Runs before the timed ones (pipeline warm-up, caches, clocks).
pub const WARM_UP_RUNS: u32 = 3;

/// What the display regions hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    /// A typical mixed-reality frame: black (see-through) with two UI panels and a shaded
    /// object, about 17% of the pixels foreground.
    Typical,
    /// Every pixel foreground (a colourful gradient, never black).
    Full,
}

impl Content {
    pub const ALL: [Content; 2] = [Content::Typical, Content::Full];

    pub fn name(self) -> &'static str {
        match self {
            Content::Typical => "typical",
            Content::Full => "full",
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct BenchCase {
    /// Per view.
    pub region: (u32, u32),
    pub views: u32,
    pub content: Content,
    /// Timed runs; the result is their median.
    pub runs: u32,
}

/// Medians in milliseconds over all views of a case.
#[derive(Clone, Copy, Debug)]
pub struct BenchResult {
    pub case: BenchCase,
    pub copy_ms: f64,
    /// The copy with the enhancement's 16-byte accesses (None where rows are not aligned).
    pub copy_wide_ms: Option<f64>,
    pub enhance_ms: f64,
    /// Everything the layer records per display frame: the layout transitions, the copies of
    /// each view from the app's image into its buffer and back, and the enhancement.
    pub frame_ms: f64,
    /// The same without the enhancement: the layer's image copies alone.
    pub image_copy_ms: f64,
    /// Per camera frame: decode and blur on the camera grid (once, whatever the views).
    pub background_ms: f64,
    /// Fraction of pixels that are foreground (neither black nor alpha 0).
    pub foreground: f64,
}

impl BenchResult {
    /// Enhancement time over copy time.
    pub fn ratio(&self) -> f64 {
        self.enhance_ms / self.copy_ms
    }

    /// Enhancement time over the 16-byte copy's time.
    pub fn ratio_wide(&self) -> Option<f64> {
        self.copy_wide_ms.map(|c| self.enhance_ms / c)
    }

    /// The layer's whole per-frame work over the copy's time.
    pub fn frame_ratio(&self) -> f64 {
        self.frame_ms / self.copy_ms
    }

    /// A display frame that also brings a new camera frame (a live camera at or above the
    /// display's rate): the background preparation then the frame, one after the other on the
    /// queue, so the sum of the two medians.
    pub fn live_frame_ms(&self) -> f64 {
        self.frame_ms + self.background_ms
    }

    pub fn megapixels(&self) -> f64 {
        let (w, h) = self.case.region;
        f64::from(w) * f64::from(h) * f64::from(self.case.views) / 1e6
    }
}

/// One RGBA8 pixel (R in the low byte) of the given content at (x, y) of a w x h region.
pub fn content_pixel(content: Content, x: u32, y: u32, w: u32, h: u32) -> u32 {
    let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
    let rgba = |r: f32, g: f32, b: f32| {
        let q = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u32;
        q(r) | q(g) << 8 | q(b) << 16 | 255 << 24
    };
    if content == Content::Full {
        return rgba(u.max(0.01), v, 0.5 + 0.5 * (u - v));
    }
    let inside =
        |x0: f32, x1: f32, y0: f32, y1: f32| (x0..x1).contains(&u) && (y0..y1).contains(&v);
    if inside(0.10, 0.40, 0.30, 0.60) {
        return rgba(0.78, 0.82, 0.90);
    }
    if inside(0.60, 0.85, 0.15, 0.35) {
        return rgba(0.15, 0.63, 0.31);
    }
    let (dx, dy) = ((u - 0.55) * w as f32, (v - 0.65) * h as f32);
    let r = 0.12 * w.min(h) as f32;
    let d2 = (dx * dx + dy * dy) / (r * r);
    if d2 < 1.0 {
        let shade = 1.0 - 0.6 * d2;
        return rgba(0.9 * shade, 0.45 * shade, 0.1 * shade + 0.02);
    }
    0xff00_0000
}

/// A smooth camera frame with some texture (what the blur and FoV mapping see).
fn camera_frame(size: (u32, u32)) -> Vec<[u8; 4]> {
    let mut out = Vec::with_capacity((size.0 * size.1) as usize);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let t = ((x * 7 + y * 13) % 32) as u8;
            out.push([
                (x * 255 / size.0) as u8 / 2 + t,
                (y * 255 / size.1) as u8 / 2 + 64,
                160 - t,
                255,
            ]);
        }
    }
    out
}

/// Everything one case allocates; `destroy` frees what was made.
struct Rig {
    background: Option<BackgroundFrame>,
    views: Vec<ViewTarget>,
    sources: Vec<GpuBuffer>,
    /// One app-like image per view (R8G8B8A8_SRGB, as the content), kept in
    /// COLOR_ATTACHMENT_OPTIMAL between runs, as an app leaves it at xrEndFrame.
    images: Vec<AppImage>,
    staging: Option<GpuBuffer>,
    queries: vk::QueryPool,
}

impl Rig {
    fn regions(&self, size: (u32, u32)) -> Vec<ImageRegion> {
        let region = |i: &AppImage| ImageRegion {
            image: i.raw,
            array_index: 0,
            offset: (0, 0),
            extent: size,
        };
        self.images.iter().map(region).collect()
    }
}

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
}
const SPANS: usize = 6;
const QUERIES: u32 = 2 * SPANS as u32;

impl OfflineEngine {
    /// Times one case; `params` are the enhancement's settings (method, blur, ...).
    pub fn bench(&mut self, case: &BenchCase, params: &Params) -> Result<BenchResult, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let mut rig = Rig {
            background: None,
            views: Vec::new(),
            sources: Vec::new(),
            images: Vec::new(),
            staging: None,
            queries: vk::QueryPool::null(),
        };
        let result = self.bench_with(&mut rig, case, params);
        self.destroy_rig(rig);
        result
    }

    fn bench_with(
        &mut self,
        rig: &mut Rig,
        case: &BenchCase,
        params: &Params,
    ) -> Result<BenchResult, GpuError> {
        let foreground = self.build_rig(rig, case)?;
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
            background_ms: ms[Span::Background as usize],
            foreground,
        })
    }

    /// Allocates the camera frame, views, pristine sources and query pool; returns the
    /// foreground fraction of the content.
    fn build_rig(&mut self, rig: &mut Rig, case: &BenchCase) -> Result<f64, GpuError> {
        let (w, h) = case.region;
        let gpu = &self.gpu;
        let mut bg = self
            .engine
            .create_background(gpu, CAMERA_SIZE, Placement::DEVICE)?;
        let uploaded = bg.upload(&camera_frame(CAMERA_SIZE));
        rig.background = Some(bg);
        uploaded?;
        let words: Vec<u32> = (0..w * h)
            .map(|i| content_pixel(case.content, i % w, i / w, w, h))
            .collect();
        let foreground = words.iter().filter(|&&p| p & 0xff_ffff != 0).count() as f64;
        let bytes: Vec<u8> = words.iter().flat_map(|p| p.to_le_bytes()).collect();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let mut staging = GpuBuffer::new(
            gpu,
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
            "bench staging",
        )?;
        let written = staging.write(&bytes);
        rig.staging = Some(staging);
        written?;
        let background = rig.background.as_ref().expect("made above");
        for _ in 0..case.views {
            let view = self.engine.create_view(
                gpu,
                case.region,
                PixelFormat::SRGB8,
                background,
                Placement::DEVICE,
            )?;
            rig.views.push(view);
            let source = GpuBuffer::new(
                gpu,
                bytes.len() as u64,
                usage,
                MemoryLocation::GpuOnly,
                "bench source",
            )?;
            let view = rig.views.last().expect("pushed above");
            self.engine.bind_source(gpu, view, &source);
            rig.sources.push(source);
            rig.images
                .push(AppImage::new(gpu, case.region, vk::Format::R8G8B8A8_SRGB)?);
        }
        self.fill_sources(rig, bytes.len() as u64, case.region)?;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(QUERIES);
        // SAFETY: a valid create info on the engine's own device.
        rig.queries =
            unsafe { self.gpu.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        Ok(foreground / f64::from(w * h))
    }

    /// Fills the copy sources with the content and brings the images to the layout an app
    /// leaves them in (their content is written at each run, `restore_images`).
    fn fill_sources(&mut self, rig: &Rig, size: u64, extent: (u32, u32)) -> Result<(), GpuError> {
        let staging = rig.staging.as_ref().expect("made before").raw;
        self.submit(|cmd| {
            for source in &rig.sources {
                let region = [vk::BufferCopy::default().size(size)];
                // SAFETY: cmd is recording; both buffers are ours and `size` bytes long.
                unsafe {
                    self.gpu
                        .device
                        .cmd_copy_buffer(cmd, staging, source.raw, &region)
                };
            }
            let to_attachment: Vec<_> = rig
                .regions(extent)
                .iter()
                .map(|r| {
                    vk::ImageMemoryBarrier::default()
                        .old_layout(vk::ImageLayout::UNDEFINED)
                        .new_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                        .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .image(r.image)
                        .subresource_range(
                            vk::ImageSubresourceRange::default()
                                .aspect_mask(vk::ImageAspectFlags::COLOR)
                                .level_count(1)
                                .layer_count(1),
                        )
                })
                .collect();
            // SAFETY: cmd is recording; the images are ours and unused.
            unsafe {
                self.gpu.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                    vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[],
                    &to_attachment,
                )
            };
            Ok(())
        })
    }

    /// Writes the pristine content into each app image (an app's newly rendered frame).
    fn restore_images(&self, cmd: vk::CommandBuffer, rig: &Rig, regions: &[ImageRegion]) {
        let staging = rig.staging.as_ref().expect("made before");
        record_layout_barriers(&self.gpu, cmd, regions, true);
        for r in regions {
            record_region_copy(&self.gpu, cmd, r, staging, false);
        }
        record_layout_barriers(&self.gpu, cmd, regions, false);
    }

    /// What the layer records per display frame around (and, with `enhance`, including) the
    /// enhancement: src/layer/processor.rs's `record` less the background and captures.
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
    /// frame and its image copies alone. Returns each Span's GPU time in milliseconds (the
    /// 16-byte copy's is 0 where the rows do not allow it).
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

    fn destroy_rig(&mut self, mut rig: Rig) {
        let gpu = &self.gpu;
        // SAFETY: every submission was waited for; the pool is ours (null is ignored).
        unsafe { gpu.device.destroy_query_pool(rig.queries, None) };
        for mut v in rig.views.drain(..) {
            self.engine.destroy_view(gpu, &mut v);
        }
        rig.sources.iter_mut().for_each(|b| b.destroy(gpu));
        rig.images.iter_mut().for_each(|i| i.destroy(gpu));
        if let Some(mut b) = rig.staging.take() {
            b.destroy(gpu);
        }
        if let Some(mut b) = rig.background.take() {
            b.destroy(gpu);
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}
