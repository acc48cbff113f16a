//! The benchmark behind `contrastxr bench`: GPU time, from timestamp queries, of the plain copy
//! pass (the floor), the per-frame enhancement and the per-camera-frame background preparation
//! over the same display regions, on the offline engine's device.

use super::buffer::GpuBuffer;
use super::engine::{barrier, Placement, ViewTarget};
use super::error::{GpuError, VkResultExt};
use super::format::PixelFormat;
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
    staging: Option<GpuBuffer>,
    queries: vk::QueryPool,
}

/// Timestamps per run: copy, enhancement, background and 16-byte copy, start and end each.
const QUERIES: u32 = 8;

impl OfflineEngine {
    /// Times one case; `params` are the enhancement's settings (method, blur, ...).
    pub fn bench(&mut self, case: &BenchCase, params: &Params) -> Result<BenchResult, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let mut rig = Rig {
            background: None,
            views: Vec::new(),
            sources: Vec::new(),
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
        let mut samples: [Vec<f64>; 4] = Default::default();
        for run in 0..WARM_UP_RUNS + case.runs {
            let times = self.timed_run(rig, params)?;
            if run >= WARM_UP_RUNS {
                for (s, t) in samples.iter_mut().zip(times) {
                    s.push(t);
                }
            }
        }
        let [copy_ms, enhance_ms, background_ms, copy_wide_ms] = samples.map(median);
        Ok(BenchResult {
            case: *case,
            copy_ms,
            copy_wide_ms: rig
                .views
                .iter()
                .all(ViewTarget::copies_wide)
                .then_some(copy_wide_ms),
            enhance_ms,
            background_ms,
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
        }
        self.fill_sources(rig, bytes.len() as u64)?;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(QUERIES);
        // SAFETY: a valid create info on the engine's own device.
        rig.queries =
            unsafe { self.gpu.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        Ok(foreground / f64::from(w * h))
    }

    fn fill_sources(&mut self, rig: &Rig, size: u64) -> Result<(), GpuError> {
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
            Ok(())
        })
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

    /// One run: 16-byte copy, copy (which also restores the pristine pixels), enhancement,
    /// background. Returns the GPU times in milliseconds: copy, enhancement, background, 16-byte
    /// copy (0 where the rows do not allow it).
    fn timed_run(&mut self, rig: &Rig, params: &Params) -> Result<[f64; 4], GpuError> {
        let compute = vk::PipelineStageFlags::COMPUTE_SHADER;
        let views: Vec<&ViewTarget> = rig.views.iter().collect();
        let background = rig.background.as_ref().expect("made before");
        self.submit(|cmd| {
            let (gpu, engine, q) = (&self.gpu, &self.engine, rig.queries);
            // SAFETY: cmd is recording; the pool is ours and not in use by pending work.
            unsafe { gpu.device.cmd_reset_query_pool(cmd, q, 0, QUERIES) };
            barrier(gpu, cmd, vk::PipelineStageFlags::ALL_COMMANDS, compute);
            self.timestamp(cmd, q, 6);
            views.iter().for_each(|v| {
                engine.record_copy_wide(gpu, cmd, v);
            });
            self.timestamp(cmd, q, 7);
            barrier(gpu, cmd, compute, compute);
            self.timestamp(cmd, q, 0);
            views.iter().for_each(|v| engine.record_copy(gpu, cmd, v));
            self.timestamp(cmd, q, 1);
            barrier(gpu, cmd, compute, vk::PipelineStageFlags::ALL_COMMANDS);
            self.timestamp(cmd, q, 2);
            for v in &views {
                engine.record_enhance(gpu, cmd, v, params)?;
            }
            self.timestamp(cmd, q, 3);
            barrier(gpu, cmd, compute, vk::PipelineStageFlags::ALL_COMMANDS);
            self.timestamp(cmd, q, 4);
            engine.record_background(gpu, cmd, background, &views, params)?;
            self.timestamp(cmd, q, 5);
            Ok(())
        })?;
        let mut ticks = [0u64; QUERIES as usize];
        // SAFETY: the submission was waited for; the eight queries were written by it.
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
        let span = |a: usize| ticks[a + 1].wrapping_sub(ticks[a]) as f64 * ms;
        Ok([span(0), span(2), span(4), span(6)])
    }

    fn destroy_rig(&mut self, mut rig: Rig) {
        let gpu = &self.gpu;
        // SAFETY: every submission was waited for; the pool is ours (null is ignored).
        unsafe { gpu.device.destroy_query_pool(rig.queries, None) };
        for mut v in rig.views.drain(..) {
            self.engine.destroy_view(gpu, &mut v);
        }
        rig.sources.iter_mut().for_each(|b| b.destroy(gpu));
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
