//! The engine: records the background preparation (once per camera frame, on the camera grid)
//! and the per-pixel enhancement (per view, sampling that image through the view's
//! CameraMapping) into a command buffer that the caller owns and submits. It works the same on a device it created (the CLI)
//! and on someone else's device and queue (the app's, in the layer): it never submits, waits or
//! touches images itself. Data lives in storage buffers, so the swapchain's format never has to
//! be a storage-image format: the caller copies a view's region into `ViewTarget::pixels` and back.

use super::app_image::AppImage;
use super::buffer::GpuBuffer;
use super::codes::{method_code, mode_code};
use super::device::GpuDevice;
use super::error::{GpuError, VkResultExt};
use super::format::PixelFormat;
use super::interface::{
    BindingKind, BINDING_BLURRED, BINDING_BLURRED_TEXELS, BINDING_CAMERA, BINDING_PIXELS,
    BINDING_SOURCE, BINDING_TILES, CLASSIFY_WORKGROUP, DECODE_ROWS, TILE_LIST_DISPATCH_OFFSET,
    TILE_LIST_HEADER_WORDS,
};
use super::pipelines::{
    self, binding_count, BuildMode, BuildReport, Pipelines, PushConstants, ShaderId, WarmUpHook,
};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::{Params, ViewMode};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// The per-pixel passes' workgroups are TILE x TILE (src/gpu/interface.rs, WORKGROUPS).
const WORKGROUP: u32 = TILE;
pub use super::pipelines::TILE;

/// Background frames that may exist at once besides the views (their descriptor sets).
const MAX_BACKGROUNDS: u32 = 2;

/// One camera frame on the GPU and its blurred linear-light copy (camera grid).
pub struct BackgroundFrame {
    pub size: (u32, u32),
    /// RGBA8 sRGB, one u32 per pixel, rows padded to a multiple of 4 pixels (the shader reads
    /// 16 bytes at a time); host-visible, written with `upload`.
    pub camera: GpuBuffer,
    /// Decoded and blurred, linear light, not attenuated: two texels per 16 bytes (see
    /// `blurred` in shaders/common.wgsl). What every view's enhancement samples. Followed by
    /// the decoded camera texels the blur reads (shaders/background.wgsl).
    pub blurred: GpuBuffer,
    /// `blurred` as an image (R32G32B32A32_UINT, kept in GENERAL), which the enhancement reads.
    texels: AppImage,
    texels_view: vk::ImageView,
    /// The preparation pass's descriptor set (camera, blurred).
    set: vk::DescriptorSet,
    pool: vk::DescriptorPool,
}

impl BackgroundFrame {
    /// Copies a camera frame (RGBA8 sRGB, row-major) into the host-visible camera buffer.
    pub fn upload(&mut self, rgba: &[[u8; 4]]) -> Result<(), GpuError> {
        let (w, h) = (self.size.0 as usize, self.size.1 as usize);
        if rgba.len() != w * h {
            return Err(GpuError::Unsupported("camera frame size changed".into()));
        }
        let stride = camera_stride(self.size.0) as usize;
        if stride == w {
            return self.camera.write(rgba.as_flattened());
        }
        let dst = self
            .camera
            .mapped_mut()
            .ok_or_else(|| GpuError::Unsupported("buffer is not host-visible".into()))?;
        for (row, src) in rgba.chunks_exact(w).enumerate() {
            let at = row * stride * 4;
            dst[at..at + w * 4].copy_from_slice(src.as_flattened());
        }
        Ok(())
    }

    pub fn destroy(&mut self, gpu: &GpuDevice) {
        free_set(gpu, self.pool, &mut self.set);
        // SAFETY: the view is ours (null is ignored) and the GPU no longer uses it.
        unsafe { gpu.device.destroy_image_view(self.texels_view, None) };
        self.texels_view = vk::ImageView::null();
        self.texels.destroy(gpu);
        for b in [&mut self.camera, &mut self.blurred] {
            b.destroy(gpu);
        }
    }
}

/// Bytes after the decoded camera texels in `blurred`: a row window at the last row reads up to
/// 5 entries past them (blur half-width 7).
const DECODED_SLACK: u64 = 16 * 8;

/// The camera texels a background preparation makes: those the views' mappings sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraRect {
    /// First texel; x is a multiple of 4 (the pass makes 4 texels per invocation).
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl CameraRect {
    pub fn full(size: (u32, u32)) -> CameraRect {
        CameraRect {
            x: 0,
            y: 0,
            width: size.0,
            height: size.1,
        }
    }

    /// The texels whose entries bilinear sampling reads for any display pixel of views at
    /// `mappings` (the bounding box of each view's mapped corners: where the mapping's z is
    /// positive at all four corners it is positive inside, and the view's image is the convex
    /// quadrilateral of its corners), with a margin for rounding. The whole image where a
    /// mapping is degenerate.
    pub fn sampled_by(mappings: &[CameraMapping], size: (u32, u32)) -> CameraRect {
        let (w, h) = (f64::from(size.0), f64::from(size.1));
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for m in mappings {
            for corner in [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]] {
                let r = &m.rows;
                let z = r[2][0] * corner[0] + r[2][1] * corner[1] + r[2][2];
                let uv = m.apply(glam::DVec2::from(corner));
                if !(z > 0.0 && uv.is_finite()) {
                    return CameraRect::full(size);
                }
                let t = [uv.x * w - 0.5, uv.y * h - 0.5];
                for k in 0..2 {
                    lo[k] = lo[k].min(t[k]);
                    hi[k] = hi[k].max(t[k]);
                }
            }
        }
        if mappings.is_empty() {
            return CameraRect::full(size);
        }
        // Entries floor(t) - 1 ..= floor(t) + 1 in x, rows floor(t) - 1 ..= floor(t) + 2 in y.
        let span = |lo: f64, hi: f64, extra: f64, n: f64| {
            let a = (lo.floor() - 1.0).clamp(0.0, n - 1.0);
            let b = (hi.floor() + extra).clamp(0.0, n - 1.0);
            (a as u32, b as u32)
        };
        let (x0, x1) = span(lo[0], hi[0], 1.0, w);
        let (y0, y1) = span(lo[1], hi[1], 2.0, h);
        let x0 = x0 / 4 * 4;
        CameraRect {
            x: x0,
            y: y0,
            width: x1 - x0 + 1,
            height: y1 - y0 + 1,
        }
    }

    /// Whether every texel of `other` is in this rectangle.
    pub fn contains(&self, other: &CameraRect) -> bool {
        other.x >= self.x
            && other.y >= self.y
            && other.x + other.width <= self.x + self.width
            && other.y + other.height <= self.y + self.height
    }

    /// The smallest rectangle holding both.
    pub fn union(&self, other: &CameraRect) -> CameraRect {
        let (x, y) = (self.x.min(other.x), self.y.min(other.y));
        let right = (self.x + self.width).max(other.x + other.width);
        let bottom = (self.y + self.height).max(other.y + other.height);
        CameraRect {
            x,
            y,
            width: right - x,
            height: bottom - y,
        }
    }
}

/// The blurred camera image's texel format: one 16-byte entry (two packed texels) per texel.
const TEXELS_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

fn colour_layer() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .layer_count(1)
}

/// Pixels per camera buffer row: the width rounded up to whole 16-byte entries.
fn camera_stride(width: u32) -> u32 {
    width.next_multiple_of(4)
}

fn free_set(gpu: &GpuDevice, pool: vk::DescriptorPool, set: &mut vk::DescriptorSet) {
    if *set != vk::DescriptorSet::null() {
        // SAFETY: the set came from this pool and the GPU no longer uses it.
        let _ = unsafe { gpu.device.free_descriptor_sets(pool, &[*set]) };
        *set = vk::DescriptorSet::null();
    }
}

/// One display region (a view): its pixels and tile list, bound to a background frame.
pub struct ViewTarget {
    pub region: (u32, u32),
    pub format: PixelFormat,
    /// The region's raw pixels in `format`, rows tightly packed.
    pub pixels: GpuBuffer,
    /// Indirect dispatch arguments and the list of non-empty tiles (TileList in shaders/common.wgsl).
    pub tiles: GpuBuffer,
    set: vk::DescriptorSet,
    camera_size: (u32, u32),
}

/// Whether every row of a region `width` pixels wide starts on a 16-byte boundary, so the
/// per-pixel passes may read and write 16 bytes at a time (shaders/access_wide.wgsl). True for
/// most widths in use.
pub fn rows_aligned(width: u32, format: PixelFormat) -> bool {
    (width * format.bytes_per_pixel()) % 16 == 0
}

impl ViewTarget {
    /// [`rows_aligned`] for this view.
    pub fn rows_aligned(&self) -> bool {
        rows_aligned(self.region.0, self.format)
    }

    /// Whether the benchmark's 16-byte copy (`record_copy_wide`) can run on this view:
    /// aligned rows of 4-byte pixels.
    pub fn copies_wide(&self) -> bool {
        self.rows_aligned() && self.format.bytes_per_pixel() == 4
    }

    pub fn pixel_bytes(&self) -> u64 {
        u64::from(self.region.0)
            * u64::from(self.region.1)
            * u64::from(self.format.bytes_per_pixel())
    }
}

pub struct Engine {
    pub(super) pipelines: Pipelines,
    pool: vk::DescriptorPool,
}

/// Where the engine's working buffers live: device-local inside the layer, host-visible for the
/// offline tool (which reads results back directly).
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub camera: MemoryLocation,
    pub working: MemoryLocation,
}

impl Placement {
    pub const OFFLINE: Placement = Placement {
        camera: MemoryLocation::CpuToGpu,
        working: MemoryLocation::GpuToCpu,
    };
    pub const DEVICE: Placement = Placement {
        camera: MemoryLocation::CpuToGpu,
        working: MemoryLocation::GpuOnly,
    };
}

const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::STORAGE_BUFFER;

fn transfer_storage() -> vk::BufferUsageFlags {
    STORAGE | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST
}

/// The memory accesses a set of stages can make (only those, or validation objects).
fn accesses(stages: vk::PipelineStageFlags) -> vk::AccessFlags {
    use vk::{AccessFlags as A, PipelineStageFlags as S};
    if stages.contains(S::ALL_COMMANDS) {
        return A::MEMORY_READ | A::MEMORY_WRITE;
    }
    let mut access = A::empty();
    if stages.contains(S::COMPUTE_SHADER) {
        access |= A::SHADER_READ | A::SHADER_WRITE;
    }
    if stages.contains(S::TRANSFER) {
        access |= A::TRANSFER_READ | A::TRANSFER_WRITE;
    }
    if stages.contains(S::HOST) {
        access |= A::HOST_READ | A::HOST_WRITE;
    }
    if stages.contains(S::DRAW_INDIRECT) {
        access |= A::INDIRECT_COMMAND_READ;
    }
    access
}

/// A memory dependency between passes of this engine and the copies around them.
pub fn barrier(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    src: vk::PipelineStageFlags,
    dst: vk::PipelineStageFlags,
) {
    let memory = [vk::MemoryBarrier::default()
        .src_access_mask(accesses(src))
        .dst_access_mask(accesses(dst))];
    // SAFETY: cmd is in the recording state (the caller's contract for every record_* call).
    unsafe {
        gpu.device.cmd_pipeline_barrier(
            cmd,
            src,
            dst,
            vk::DependencyFlags::empty(),
            &memory,
            &[],
            &[],
        )
    };
}

/// Allocates several buffers; on failure frees the ones already made.
fn alloc_all<const N: usize>(
    gpu: &GpuDevice,
    specs: [(u64, vk::BufferUsageFlags, MemoryLocation, &str); N],
) -> Result<[GpuBuffer; N], GpuError> {
    let mut made = Vec::with_capacity(N);
    for (size, usage, location, name) in specs {
        match GpuBuffer::new(gpu, size, usage, location, name) {
            Ok(b) => made.push(b),
            Err(e) => {
                made.iter_mut().for_each(|b: &mut GpuBuffer| b.destroy(gpu));
                return Err(e);
            }
        }
    }
    Ok(made
        .try_into()
        .unwrap_or_else(|_| unreachable!("N buffers were made")))
}

const COMPUTE: vk::PipelineStageFlags = vk::PipelineStageFlags::COMPUTE_SHADER;

impl Engine {
    /// Sets up the pipelines, built as `mode` says; `max_views` bounds how many ViewTargets
    /// may exist at once.
    pub fn new(
        gpu: &GpuDevice,
        max_views: u32,
        mode: BuildMode,
        warm_up: Option<WarmUpHook>,
    ) -> Result<Engine, GpuError> {
        let mut pipelines = Pipelines::new(gpu, mode, warm_up)?;
        let max_sets = max_views + MAX_BACKGROUNDS;
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(max_sets * binding_count(BindingKind::StorageBuffer)),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::SAMPLED_IMAGE)
                .descriptor_count(max_sets * binding_count(BindingKind::SampledImage)),
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET)
            .max_sets(max_sets)
            .pool_sizes(&sizes);
        // SAFETY: valid create info on a valid device.
        match unsafe { gpu.device.create_descriptor_pool(&info, None) } {
            Ok(pool) => Ok(Engine { pipelines, pool }),
            Err(result) => {
                pipelines.destroy(gpu);
                Err(GpuError::Vulkan {
                    call: "vkCreateDescriptorPool",
                    result,
                })
            }
        }
    }

    pub fn create_background(
        &self,
        gpu: &GpuDevice,
        size: (u32, u32),
        placement: Placement,
    ) -> Result<BackgroundFrame, GpuError> {
        if size.0 == 0 || size.1 == 0 {
            return Err(GpuError::Unsupported("empty camera frame".into()));
        }
        let px = u64::from(size.0) * u64::from(size.1);
        let padded = u64::from(camera_stride(size.0)) * u64::from(size.1);
        let blurred_usage = STORAGE | vk::BufferUsageFlags::TRANSFER_SRC;
        let [camera, blurred] = alloc_all(
            gpu,
            [
                (padded * 4, STORAGE, placement.camera, "camera"),
                // The final texels, then the decoded ones (8 bytes each, padded rows), then
                // slack for the entries a row window reads past the last row.
                (
                    px * 16 + padded * 8 + DECODED_SLACK,
                    blurred_usage,
                    placement.working,
                    "blurred",
                ),
            ],
        )?;
        let mut bg = BackgroundFrame {
            size,
            camera,
            blurred,
            texels: AppImage {
                raw: vk::Image::null(),
                allocation: None,
            },
            texels_view: vk::ImageView::null(),
            set: vk::DescriptorSet::null(),
            pool: self.pool,
        };
        if let Err(e) = self.make_texels(gpu, &mut bg) {
            bg.destroy(gpu);
            return Err(e);
        }
        self.write_set(gpu, bg.set, 0, &[&bg.camera, &bg.blurred]);
        Ok(bg)
    }

    /// The background frame's descriptor set and the image the enhancement samples (for the
    /// warm-up, which binds them itself).
    pub(super) fn background_parts(bg: &BackgroundFrame) -> (vk::DescriptorSet, vk::Image) {
        (bg.set, bg.texels.raw)
    }

    pub(super) fn view_set(view: &ViewTarget) -> vk::DescriptorSet {
        view.set
    }

    /// The image the enhancement samples, its view, and the preparation's descriptor set.
    fn make_texels(&self, gpu: &GpuDevice, bg: &mut BackgroundFrame) -> Result<(), GpuError> {
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        bg.texels = AppImage::with_usage(gpu, bg.size, TEXELS_FORMAT, usage)?;
        let info = vk::ImageViewCreateInfo::default()
            .image(bg.texels.raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(TEXELS_FORMAT)
            .subresource_range(colour_layer());
        // SAFETY: a view of our own image, with its format, on a valid device.
        bg.texels_view =
            unsafe { gpu.device.create_image_view(&info, None) }.vk("vkCreateImageView")?;
        bg.set = self.allocate_set(gpu)?;
        Ok(())
    }

    fn allocate_set(&self, gpu: &GpuDevice) -> Result<vk::DescriptorSet, GpuError> {
        let layouts = [self.pipelines.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pool)
            .set_layouts(&layouts);
        // SAFETY: pool and layout are valid; the pool was sized for max_views views plus
        // MAX_BACKGROUNDS background frames.
        match unsafe { gpu.device.allocate_descriptor_sets(&info) } {
            Ok(sets) => Ok(sets[0]),
            Err(result) => Err(GpuError::Vulkan {
                call: "vkAllocateDescriptorSets",
                result,
            }),
        }
    }

    pub fn create_view(
        &self,
        gpu: &GpuDevice,
        region: (u32, u32),
        format: PixelFormat,
        background: &BackgroundFrame,
        placement: Placement,
    ) -> Result<ViewTarget, GpuError> {
        if region.0 == 0 || region.1 == 0 {
            return Err(GpuError::Unsupported("empty display region".into()));
        }
        let px = u64::from(region.0) * u64::from(region.1);
        let usage = transfer_storage();
        let bpp = u64::from(format.bytes_per_pixel());
        let at = placement.working;
        let tile_count = u64::from(region.0.div_ceil(TILE)) * u64::from(region.1.div_ceil(TILE));
        let tile_usage =
            STORAGE | vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let gpu_only = MemoryLocation::GpuOnly;
        let [pixels, tiles] = alloc_all(
            gpu,
            [
                (px * bpp, usage, at, "pixels"),
                (
                    (TILE_LIST_HEADER_WORDS + tile_count) * 4,
                    tile_usage,
                    gpu_only,
                    "tiles",
                ),
            ],
        )?;
        let mut view = ViewTarget {
            region,
            format,
            pixels,
            tiles,
            set: vk::DescriptorSet::null(),
            camera_size: background.size,
        };
        match self.allocate_set(gpu) {
            Ok(set) => view.set = set,
            Err(e) => {
                self.destroy_view(gpu, &mut view);
                return Err(e);
            }
        }
        self.bind(gpu, &mut view, background);
        Ok(view)
    }

    /// Points a view's descriptor set at a (new) background frame. The set must not be in use.
    pub fn bind(&self, gpu: &GpuDevice, view: &mut ViewTarget, background: &BackgroundFrame) {
        let buffers = [
            (BINDING_CAMERA, &background.camera),
            (BINDING_BLURRED, &background.blurred),
            (BINDING_PIXELS, &view.pixels),
            (BINDING_TILES, &view.tiles),
            // The copy passes read the pixels in place unless a source is bound.
            (BINDING_SOURCE, &view.pixels),
        ];
        for (binding, buffer) in buffers {
            self.write_set(gpu, view.set, binding, &[buffer]);
        }
        let image = [vk::DescriptorImageInfo::default()
            .image_view(background.texels_view)
            .image_layout(vk::ImageLayout::GENERAL)];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(view.set)
            .dst_binding(BINDING_BLURRED_TEXELS)
            .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
            .image_info(&image);
        // SAFETY: the set and the view are valid; the caller guarantees the set is not in use.
        unsafe { gpu.device.update_descriptor_sets(&[write], &[]) };
        view.camera_size = background.size;
    }

    /// Points a view's copy source (used only by `record_copy`) at `source`.
    pub fn bind_source(&self, gpu: &GpuDevice, view: &ViewTarget, source: &GpuBuffer) {
        self.write_set(gpu, view.set, BINDING_SOURCE, &[source]);
    }

    fn write_set(
        &self,
        gpu: &GpuDevice,
        set: vk::DescriptorSet,
        first: u32,
        buffers: &[&GpuBuffer],
    ) {
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|b| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(b.raw)
                    .range(vk::WHOLE_SIZE)]
            })
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(first + i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set and buffers are valid; the caller guarantees the set is not in use.
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
    }

    pub fn destroy_view(&self, gpu: &GpuDevice, view: &mut ViewTarget) {
        free_set(gpu, self.pool, &mut view.set);
        for b in [&mut view.pixels, &mut view.tiles] {
            b.destroy(gpu);
        }
    }

    /// Dispatches `pipeline` over `grid` invocations (in WORKGROUP x WORKGROUP groups).
    pub(super) fn dispatch(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        pipeline: vk::Pipeline,
        set: vk::DescriptorSet,
        push: &PushConstants,
        grid: (u32, u32),
    ) {
        let workgroup = (WORKGROUP, WORKGROUP);
        self.dispatch_in(gpu, cmd, (pipeline, workgroup), set, push, grid);
    }

    /// Dispatches `pipeline`, whose workgroup size is given, over `grid` invocations.
    fn dispatch_in(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        (pipeline, workgroup): (vk::Pipeline, (u32, u32)),
        set: vk::DescriptorSet,
        push: &PushConstants,
        grid: (u32, u32),
    ) {
        self.bind_pipeline(gpu, cmd, pipeline, set, push);
        let groups = (grid.0.div_ceil(workgroup.0), grid.1.div_ceil(workgroup.1));
        // SAFETY: cmd is recording with the pipeline, set and push constants bound.
        unsafe { gpu.device.cmd_dispatch(cmd, groups.0, groups.1, 1) };
    }

    fn bind_pipeline(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        pipeline: vk::Pipeline,
        set: vk::DescriptorSet,
        push: &PushConstants,
    ) {
        let d = &gpu.device;
        // SAFETY: cmd is recording; pipeline, layout and set belong to this engine.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.pipelines.layout,
                0,
                &[set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                self.pipelines.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                push.bytes(),
            );
        }
    }

    /// Records the background preparation (docs/algorithm.md, Background preparation) for a camera frame already
    /// uploaded: decode and blur on the camera grid, once per camera frame whatever the number
    /// of views (each view's enhancement samples the result through its own mapping), for the
    /// texels in `rect` (`CameraRect::sampled_by` the views' mappings).
    pub fn record_background(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        background: &BackgroundFrame,
        params: &Params,
        rect: &CameraRect,
    ) -> Result<(), GpuError> {
        let all = vk::PipelineStageFlags::ALL_COMMANDS;
        barrier(gpu, cmd, all, COMPUTE);
        let identity = CameraMapping::IDENTITY;
        // The pass reads the rectangle's first texel from region_size (shaders/background.wgsl).
        let origin = (rect.x / 4 * 4, rect.y);
        let push = PushConstants::new(params, background.size, origin, &identity);
        let pipeline = self
            .pipelines
            .get(pipelines::decode_blur(push.blur_half)?)?;
        let right = (rect.x + rect.width).min(background.size.0);
        self.record_decode(gpu, cmd, background, &push, (origin.0, right), rect)?;
        barrier(gpu, cmd, COMPUTE, COMPUTE);
        // 4 x DECODE_ROWS texels per invocation.
        let grid = (
            (right - origin.0).div_ceil(4),
            rect.height.div_ceil(DECODE_ROWS),
        );
        self.dispatch(gpu, cmd, pipeline, background.set, &push, grid);
        self.record_texels_copy(gpu, cmd, background, (origin.0, rect.y, right, rect.height));
        barrier(gpu, cmd, vk::PipelineStageFlags::TRANSFER, all);
        Ok(())
    }

    /// Decodes the camera texels the blur of `rect` reads: its blocks' windows reach
    /// blur_half texels beyond it on each side, and 4 + blur_half right of a block's start.
    fn record_decode(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        bg: &BackgroundFrame,
        push: &PushConstants,
        (x0, right): (u32, u32),
        rect: &CameraRect,
    ) -> Result<(), GpuError> {
        let (w, h) = bg.size;
        let half = push.blur_half;
        let left = x0.saturating_sub(half) / 4 * 4;
        let end = (right.div_ceil(4) * 4 + 4 + half).min(w);
        let top = rect.y.saturating_sub(half);
        let rows = rect.height.div_ceil(DECODE_ROWS) * DECODE_ROWS;
        let bottom = (rect.y + rows + half).min(h);
        let mut push = *push;
        push.region_size = [left, top];
        let grid = ((end - left).div_ceil(4), bottom - top);
        let pipeline = self.pipelines.get(pipelines::DECODE_CAMERA)?;
        self.dispatch(gpu, cmd, pipeline, bg.set, &push, grid);
        Ok(())
    }

    /// Copies the prepared rows x0..right of rows y..y + height of `blurred` into the image the
    /// enhancement samples (GENERAL; its earlier contents are not needed: every texel a view
    /// reads is in the rectangle just prepared).
    fn record_texels_copy(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        bg: &BackgroundFrame,
        (x0, y0, right, height): (u32, u32, u32, u32),
    ) {
        let to_general = [vk::ImageMemoryBarrier::default()
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::GENERAL)
            .src_access_mask(vk::AccessFlags::SHADER_READ)
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(bg.texels.raw)
            .subresource_range(colour_layer())];
        let written = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE)
            .dst_access_mask(vk::AccessFlags::TRANSFER_READ)];
        let copy = [vk::BufferImageCopy::default()
            .buffer_offset((u64::from(y0) * u64::from(bg.size.0) + u64::from(x0)) * 16)
            .buffer_row_length(bg.size.0)
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .layer_count(1),
            )
            .image_offset(vk::Offset3D {
                x: x0 as i32,
                y: y0 as i32,
                z: 0,
            })
            .image_extent(vk::Extent3D {
                width: right - x0,
                height,
                depth: 1,
            })];
        let d = &gpu.device;
        // SAFETY: cmd is recording; the image and buffer are ours, the region lies in both.
        unsafe {
            d.cmd_pipeline_barrier(
                cmd,
                COMPUTE,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &written,
                &[],
                &to_general,
            );
            d.cmd_copy_buffer_to_image(
                cmd,
                bg.blurred.raw,
                bg.texels.raw,
                vk::ImageLayout::GENERAL,
                &copy,
            );
        }
    }

    /// Records the per-pixel enhancement of one view's `pixels`, in place: the tile
    /// classification, then the enhancement over the listed tiles only (indirect dispatch),
    /// which samples the view's background through `mapping` (display uv -> camera uv).
    /// Nothing in `ViewMode::Off`. The caller orders its copy into `pixels` before this and its
    /// copy out after it (see `barrier`), and the background's preparation before it.
    pub fn record_enhance(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        view: &ViewTarget,
        params: &Params,
        mapping: &CameraMapping,
    ) -> Result<(), GpuError> {
        if params.mode == ViewMode::Off {
            return Ok(());
        }
        let format = view.format.shader_code();
        let wide = view.rows_aligned();
        let extras = params.achromatic_boost > 0.0 || params.luminance_cap > 0.0;
        let codes = (method_code(params.method), mode_code(params.mode), format);
        let pipeline = self
            .pipelines
            .get(pipelines::enhance(codes, wide, extras)?)?;
        let classify = self.pipelines.get(pipelines::classify(format, wide)?)?;
        let finish_tiles = self.pipelines.get(pipelines::FINISH_TILES)?;
        let push = PushConstants::new(params, view.camera_size, view.region, mapping);
        let tiles = (view.region.0.div_ceil(TILE), view.region.1.div_ceil(TILE));
        use vk::PipelineStageFlags as S;
        barrier(gpu, cmd, COMPUTE | S::DRAW_INDIRECT, S::TRANSFER);
        // SAFETY: cmd is recording; the tile buffer is ours, TRANSFER_DST, at least 4 bytes.
        unsafe { gpu.device.cmd_fill_buffer(cmd, view.tiles.raw, 0, 4, 0) };
        barrier(gpu, cmd, S::TRANSFER, COMPUTE);
        let classify = (classify, (CLASSIFY_WORKGROUP[0], CLASSIFY_WORKGROUP[1]));
        self.dispatch_in(gpu, cmd, classify, view.set, &push, tiles);
        barrier(gpu, cmd, COMPUTE, COMPUTE);
        // A 1x1 grid is one workgroup of one invocation.
        self.dispatch(gpu, cmd, finish_tiles, view.set, &push, (1, 1));
        barrier(gpu, cmd, COMPUTE, COMPUTE | S::DRAW_INDIRECT);
        self.bind_pipeline(gpu, cmd, pipeline, view.set, &push);
        // SAFETY: cmd is recording with the pipeline bound above; the tile buffer has
        // INDIRECT_BUFFER usage and its arguments were written by finish_tiles.
        unsafe {
            gpu.device
                .cmd_dispatch_indirect(cmd, view.tiles.raw, TILE_LIST_DISPATCH_OFFSET)
        };
        Ok(())
    }

    /// Records the benchmark's floor: a plain per-pixel copy of the view's bound source
    /// (`bind_source`) into its `pixels` (4-byte formats), with the enhancement's dispatch shape.
    pub fn record_copy(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        view: &ViewTarget,
    ) -> Result<(), GpuError> {
        let pipeline = self.pipelines.get(pipelines::COPY_PIXELS)?;
        let push = PushConstants::new(
            &Params::default(),
            view.camera_size,
            view.region,
            &CameraMapping::IDENTITY,
        );
        self.dispatch(gpu, cmd, pipeline, view.set, &push, view.region);
        Ok(())
    }

    /// Records the benchmark's second floor: the same copy with the enhancement's memory access
    /// shape (a tile row per invocation, 16-byte accesses). None where the view does not allow
    /// it (`ViewTarget::copies_wide`).
    pub fn record_copy_wide(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        view: &ViewTarget,
    ) -> Option<()> {
        if !view.copies_wide() {
            return None;
        }
        let pipeline = self.pipelines.get(pipelines::COPY_ROWS).ok()?;
        let push = PushConstants::new(
            &Params::default(),
            view.camera_size,
            view.region,
            &CameraMapping::IDENTITY,
        );
        let grid = (view.region.0.div_ceil(TILE), view.region.1);
        self.dispatch(gpu, cmd, pipeline, view.set, &push, grid);
        Some(())
    }

    /// The shaders a frame's work needs: the background preparation for `params` and the
    /// enhancement of views of these pixel formats and widths (None for Mode off).
    pub fn shaders_for(
        params: &Params,
        views: impl IntoIterator<Item = (PixelFormat, u32)>,
    ) -> Result<Vec<ShaderId>, GpuError> {
        if params.mode == ViewMode::Off {
            return Ok(Vec::new());
        }
        let half = params.blur_taps().len() as u32 / 2;
        let mut ids = vec![
            pipelines::DECODE_CAMERA,
            pipelines::decode_blur(half)?,
            pipelines::FINISH_TILES,
        ];
        let extras = params.achromatic_boost > 0.0 || params.luminance_cap > 0.0;
        for (format, width) in views {
            let code = format.shader_code();
            let wide = rows_aligned(width, format);
            let codes = (method_code(params.method), mode_code(params.mode), code);
            for id in [
                pipelines::classify(code, wide)?,
                pipelines::enhance(codes, wide, extras)?,
            ] {
                if !ids.contains(&id) {
                    ids.push(id);
                }
            }
        }
        Ok(ids)
    }

    /// Whether the shaders are built (requesting those that are not); an error if one failed.
    pub fn ready(&self, ids: &[ShaderId]) -> Result<bool, GpuError> {
        self.pipelines.ready(ids)
    }

    /// Queues shaders to build ahead of earlier requests (BuildMode::Background).
    pub fn request(&self, ids: &[ShaderId]) {
        self.pipelines.request(ids)
    }

    /// Waits until the shaders are built (at most `timeout`).
    pub fn wait_for(&self, ids: &[ShaderId], timeout: std::time::Duration) -> Result<(), GpuError> {
        self.pipelines.wait_for(ids, timeout)
    }

    /// What building the pipelines took so far.
    pub fn build_report(&self) -> Option<BuildReport> {
        self.pipelines.report()
    }

    /// Tells the pipeline thread to stop, without waiting for it.
    pub fn stop_building(&self) {
        self.pipelines.stop();
    }

    /// Stops the pipeline thread and waits for it: nothing of the engine then touches the
    /// device on another thread (what the GPU uses is left alive).
    pub fn join_building(&mut self) {
        self.pipelines.join();
    }

    pub fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: the caller guarantees the GPU no longer uses the pool's sets.
        unsafe { gpu.device.destroy_descriptor_pool(self.pool, None) };
        self.pool = vk::DescriptorPool::null();
        self.pipelines.destroy(gpu);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    /// Every entry (x, row) and (x, row + 1) that bilinear sampling reads for a grid of display
    /// pixels lies in the rectangle, and its x is a multiple of 4.
    #[test]
    fn the_sampled_rect_holds_every_entry_the_views_read() {
        let size = (640, 480);
        let projective = CameraMapping {
            rows: [[0.8, 0.06, 0.05], [-0.04, 0.7, 0.12], [0.12, -0.09, 0.98]],
        };
        let manual = Params::default().camera_mapping();
        for mappings in [vec![manual], vec![projective], vec![manual, projective]] {
            let rect = CameraRect::sampled_by(&mappings, size);
            assert_eq!(rect.x % 4, 0);
            assert!(rect.width * rect.height < size.0 * size.1, "{rect:?}");
            for m in &mappings {
                for (i, j) in (0..=64).flat_map(|i| (0..=64).map(move |j| (i, j))) {
                    let uv = m.apply(DVec2::new(f64::from(i) / 64.0, f64::from(j) / 64.0));
                    let t = uv * DVec2::new(640.0, 480.0) - 0.5;
                    let x = t.x.floor().clamp(0.0, 639.0) as u32;
                    for y in [t.y.floor(), t.y.floor() + 1.0] {
                        let y = y.clamp(0.0, 479.0) as u32;
                        let texel = CameraRect {
                            x,
                            y,
                            width: 1,
                            height: 1,
                        };
                        assert!(rect.contains(&texel), "{rect:?} misses {texel:?}");
                    }
                }
            }
        }
        let degenerate = CameraMapping {
            rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-2.0, 0.0, 1.0]],
        };
        assert_eq!(
            CameraRect::sampled_by(&[degenerate], size),
            CameraRect::full(size)
        );
    }
}
