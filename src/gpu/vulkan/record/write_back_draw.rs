//! Recording the image-copy path's write-back by drawing (src/gpu/vulkan/pipelines/write_back_pipelines.rs):
//! the tiles the view's enhancement listed, drawn from the engine's image into the app's image,
//! instead of copying the whole region back.

use crate::gpu::core::interface::{TILE, TILE_LIST_DRAW_OFFSET};
use crate::gpu::vulkan::device::{GpuDevice, ImageRegion};
use crate::gpu::vulkan::pipelines::{WriteBackConstants, WriteBackPass, WriteBackPipelines};
use ash::vk;

/// What one view's write-back draws with.
#[derive(Clone, Copy, Debug)]
pub struct WriteBackDraw {
    pass: WriteBackPass,
    framebuffer: vk::Framebuffer,
    /// The view's set: its tile list and the engine's image.
    set: vk::DescriptorSet,
    /// The view's tile list (its draw arguments at TILE_LIST_DRAW_OFFSET).
    tiles: vk::Buffer,
    /// The view's region in the app's image.
    region: ImageRegion,
}

impl WriteBackDraw {
    /// The draw of a view's listed tiles (`tiles`, the view's tile list) with `pass` into
    /// `framebuffer` (the app's image layer), reading through `set`, into `region`.
    pub fn new(
        (pass, framebuffer): (WriteBackPass, vk::Framebuffer),
        (set, tiles): (vk::DescriptorSet, vk::Buffer),
        region: ImageRegion,
    ) -> Self {
        WriteBackDraw {
            pass,
            framebuffer,
            set,
            tiles,
            region,
        }
    }

    pub fn set(&self) -> vk::DescriptorSet {
        self.set
    }
}

/// The barrier between the enhancement (and the copy out) and the draw: the tile list's
/// arguments and indices, the engine's image and the app's image as an attachment.
pub fn record_write_back_barrier(gpu: &GpuDevice, cmd: vk::CommandBuffer) {
    use vk::{AccessFlags as A, PipelineStageFlags as S};
    let memory = [vk::MemoryBarrier::default()
        .src_access_mask(A::SHADER_WRITE | A::TRANSFER_WRITE)
        .dst_access_mask(
            A::INDIRECT_COMMAND_READ
                | A::SHADER_READ
                | A::COLOR_ATTACHMENT_READ
                | A::COLOR_ATTACHMENT_WRITE,
        )];
    let dst = S::DRAW_INDIRECT | S::VERTEX_SHADER | S::FRAGMENT_SHADER | S::COLOR_ATTACHMENT_OUTPUT;
    // SAFETY: cmd is recording (the caller's contract).
    unsafe {
        gpu.device.cmd_pipeline_barrier(
            cmd,
            S::COMPUTE_SHADER | S::TRANSFER,
            dst,
            vk::DependencyFlags::empty(),
            &memory,
            &[],
            &[],
        )
    };
}

/// Draws the view's listed tiles into its region of the app's image (in GENERAL), after
/// `record_write_back_barrier`.
pub fn record_write_back(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    pipelines: &WriteBackPipelines,
    draw: &WriteBackDraw,
) {
    let d = &gpu.device;
    let r = &draw.region;
    let rect = vk::Rect2D {
        offset: vk::Offset2D {
            x: r.offset.0,
            y: r.offset.1,
        },
        extent: vk::Extent2D {
            width: r.extent.0,
            height: r.extent.1,
        },
    };
    let viewport = vk::Viewport {
        x: r.offset.0 as f32,
        y: r.offset.1 as f32,
        width: r.extent.0 as f32,
        height: r.extent.1 as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    let constants = WriteBackConstants {
        region_size: [r.extent.0, r.extent.1],
        tile_columns: r.extent.0.div_ceil(TILE),
        pad: 0,
    };
    let begin = vk::RenderPassBeginInfo::default()
        .render_pass(draw.pass.render_pass())
        .framebuffer(draw.framebuffer)
        .render_area(rect);
    let graphics = vk::PipelineBindPoint::GRAPHICS;
    // SAFETY: cmd is recording outside a render pass; the pass, framebuffer, pipeline and set
    // are valid and agree (WriteBackPipelines made them for this image's format); the draw's
    // arguments lie in the tile list at TILE_LIST_DRAW_OFFSET (finish_tiles wrote them).
    unsafe {
        d.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE);
        d.cmd_bind_pipeline(cmd, graphics, draw.pass.pipeline());
        d.cmd_bind_descriptor_sets(cmd, graphics, pipelines.layout(), 0, &[draw.set], &[]);
        d.cmd_push_constants(
            cmd,
            pipelines.layout(),
            vk::ShaderStageFlags::VERTEX,
            0,
            &constants.bytes(),
        );
        d.cmd_set_viewport(cmd, 0, &[viewport]);
        d.cmd_set_scissor(cmd, 0, &[rect]);
        d.cmd_draw_indirect(cmd, draw.tiles, TILE_LIST_DRAW_OFFSET, 1, 16);
        d.cmd_end_render_pass(cmd);
    }
}
