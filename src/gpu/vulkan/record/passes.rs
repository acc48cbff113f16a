//! Recording the engine's passes into a command buffer: the background preparation, the
//! enhancement (classification, then the listed tiles only), and the copy passes (the
//! benchmark's floor).

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::{Params, ViewMode};
use crate::algorithm::perception::frequency::ViewGeometry;
use crate::gpu::core::blurred_texels::TEXEL_BYTES;
use crate::gpu::core::interface::{DECODE_ROWS, TILE};
use crate::gpu::core::plan::{encode, view_steps, Encoder, Grid, NoPlan, Reads, Shader};
use crate::gpu::core::push_constants::PushConstants;
use crate::gpu::core::shader_ids;
use crate::gpu::core::VariantKey;
use crate::gpu::vulkan::device::{barrier, layout_change, GpuBuffer, GpuDevice, GpuError};
use ash::vk;

use super::recorder::{Recorder, COMPUTE, WORKGROUP};
use super::resources::{CameraResources, ViewTarget};
use crate::gpu::core::CameraRect;

impl Recorder {
    /// Dispatches `pipeline` over `grid` invocations (in WORKGROUP x WORKGROUP groups).
    pub(crate) fn dispatch(
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
                self.pipelines.layout(),
                0,
                &[set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                self.pipelines.layout(),
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
        background: &CameraResources,
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
            .get(shader_ids::decode_blur(push.blur_half)?)?;
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
        bg: &CameraResources,
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
        let pipeline = self.pipelines.get(shader_ids::DECODE_CAMERA)?;
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
        bg: &CameraResources,
        (x0, y0, right, height): (u32, u32, u32, u32),
    ) {
        let to_general = [layout_change(
            bg.texels.raw,
            (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL),
            (
                vk::AccessFlags::SHADER_READ,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
        )];
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
        let key = VariantKey::of(params, view.format, view.shape().access());
        self.record_model(gpu, cmd, view, params, mapping);
        let mut push = PushConstants::new(params, view.camera_size, view.region, mapping);
        // 16 bits each (interface.rs, region_origin): swapchain images are far smaller.
        push.region_origin = (view.origin.0 & 0xffff) | (view.origin.1 << 16);
        // The method's passes (its entry in src/algorithm/method/table.rs) as steps.
        let classify = key.classify_taken(self.classify);
        let steps = view_steps(params.method.entry().passes, view.region, classify.1).map_err(
            |NoPlan(why)| GpuError::Unsupported(format!("{}: {why}", params.method.name())),
        )?;
        let mut encoder = ViewEncoder {
            engine: self,
            gpu,
            cmd,
            view,
            push: &push,
            pipelines: [
                self.pipelines
                    .get(shader_ids::classify(key.format, key.access, classify)?)?,
                self.pipelines.get(shader_ids::FINISH_TILES)?,
                self.enhance_pipeline(view, key, mapping)?,
            ],
        };
        encode(&steps, &mut encoder).unwrap_or_else(|never| match never {});
        Ok(())
    }

    /// Records the upload of the view's perceptual model (src/gpu/core/perceptual_words.rs)
    /// where its method reads one and the view's buffer does not hold it yet (the caller says
    /// when the submission made it held: `ViewTarget::model_submitted`), ordered after earlier
    /// passes' reads of it and before the enhancement's.
    fn record_model(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        view: &ViewTarget,
        params: &Params,
        mapping: &CameraMapping,
    ) {
        let geometry = ViewGeometry {
            mapping,
            display_width: view.region.0,
            camera_width: view.camera_size.0,
            pixels_per_degree: view.pixels_per_degree,
        };
        let mut words = view
            .perceptual_words
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let Some(words) = words.to_upload(params, &geometry) else {
            return;
        };
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_ne_bytes()).collect();
        let transfer = vk::PipelineStageFlags::TRANSFER;
        barrier(gpu, cmd, COMPUTE, transfer);
        // SAFETY: cmd is recording outside a render pass; the buffer is the view's, made with
        // TRANSFER_DST usage and PERCEPTUAL_WORDS words (at most 65536 bytes, a multiple of 4).
        unsafe {
            gpu.device
                .cmd_update_buffer(cmd, view.perceptual.raw, 0, &bytes)
        };
        barrier(gpu, cmd, transfer, COMPUTE);
    }

    /// Records the benchmark's floor: a plain per-pixel copy of the view's bound source
    /// (`bind_source`) into its `pixels` (4-byte formats), with the enhancement's dispatch shape.
    pub fn record_copy(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        view: &ViewTarget,
    ) -> Result<(), GpuError> {
        let pipeline = self.pipelines.get(shader_ids::COPY_PIXELS)?;
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
        let pipeline = self.pipelines.get(shader_ids::COPY_ROWS).ok()?;
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
}

impl Recorder {
    /// Records the copy of `rect`'s texels from `staging` (laid out as the image, 16 bytes per
    /// texel) into the image the enhancement samples: what `record_background` makes of the
    /// same rectangle, from texels prepared on the CPU.
    pub fn record_texels_upload(
        &self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        background: &CameraResources,
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

/// One view's steps as Vulkan commands, recorded into `cmd` with the view's set and push
/// constants.
struct ViewEncoder<'a> {
    engine: &'a Recorder,
    gpu: &'a GpuDevice,
    cmd: vk::CommandBuffer,
    view: &'a ViewTarget,
    push: &'a PushConstants,
    /// classify, finish_tiles, enhance.
    pipelines: [vk::Pipeline; 3],
}

impl Encoder for ViewEncoder<'_> {
    type Error = std::convert::Infallible;

    fn clear_tiles(&mut self) {
        use vk::PipelineStageFlags as S;
        let (gpu, cmd) = (self.gpu, self.cmd);
        barrier(gpu, cmd, COMPUTE | S::DRAW_INDIRECT, S::TRANSFER);
        // SAFETY: cmd is recording; the tile buffer is ours, TRANSFER_DST, at least 4 bytes.
        unsafe {
            gpu.device
                .cmd_fill_buffer(cmd, self.view.tiles.raw, 0, 4, 0)
        };
        barrier(gpu, cmd, S::TRANSFER, COMPUTE);
    }

    fn dispatch(&mut self, shader: Shader, grid: Grid) -> Result<(), Self::Error> {
        let pipeline = self.pipelines[shader as usize];
        let (gpu, cmd, set) = (self.gpu, self.cmd, self.view.set);
        self.engine
            .bind_pipeline(gpu, cmd, pipeline, set, self.push);
        match grid {
            // SAFETY: cmd is recording with the pipeline, set and push constants bound.
            Grid::Groups(x, y) => unsafe { gpu.device.cmd_dispatch(cmd, x, y, 1) },
            // SAFETY: as above; the tile buffer has INDIRECT_BUFFER usage and its arguments
            // were written by finish_tiles.
            Grid::TileList(offset) => unsafe {
                gpu.device
                    .cmd_dispatch_indirect(cmd, self.view.tiles.raw, offset)
            },
        }
        Ok(())
    }

    fn barrier(&mut self, reads: Reads) {
        use vk::PipelineStageFlags as S;
        match reads {
            Reads::Tiles => barrier(self.gpu, self.cmd, COMPUTE, COMPUTE),
            Reads::TilesAndArguments => {
                barrier(self.gpu, self.cmd, COMPUTE, COMPUTE | S::DRAW_INDIRECT)
            }
            // What reads the pixels next (a copy back, a layout change) records its own.
            Reads::Pixels => {}
        }
    }
}
