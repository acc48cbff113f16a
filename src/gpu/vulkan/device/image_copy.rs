//! The copies of a view's region between an app's image and a view's pixel buffer, with the
//! layout transitions around them: what the layer records around the enhancement each frame
//! (src/gpu/vulkan/frame/frame_record.rs), shared with the benchmark so that `contrastxr bench` times the
//! same commands.

use super::buffer::GpuBuffer;
use super::gpu_device::GpuDevice;
use ash::vk;
use std::collections::HashSet;

/// One view's region of an image (one array layer, mip 0).
#[derive(Clone, Copy, Debug)]
pub struct ImageRegion {
    pub image: vk::Image,
    pub array_index: u32,
    pub offset: (i32, i32),
    pub extent: (u32, u32),
}

impl ImageRegion {
    /// The image's size up to the region's far corner (what a framebuffer over it needs).
    pub fn far_corner(&self) -> (u32, u32) {
        (
            self.offset.0 as u32 + self.extent.0,
            self.offset.1 as u32 + self.extent.1,
        )
    }

    /// The copy of a rectangle at `(x, y)` inside the region (`size` pixels) from or to a
    /// buffer at `buffer_offset`, rows tightly packed.
    pub fn copy_of(
        &self,
        buffer_offset: u64,
        (x, y): (i32, i32),
        (width, height): (u32, u32),
    ) -> vk::BufferImageCopy {
        vk::BufferImageCopy::default()
            .buffer_offset(buffer_offset)
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .base_array_layer(self.array_index)
                    .layer_count(1),
            )
            .image_offset(vk::Offset3D {
                x: self.offset.0 + x,
                y: self.offset.1 + y,
                z: 0,
            })
            .image_extent(vk::Extent3D {
                width,
                height,
                depth: 1,
            })
    }
}

fn subresource(layer: u32) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .base_array_layer(layer)
        .layer_count(1)
}

/// Moves each region's image layer from COLOR_ATTACHMENT_OPTIMAL (where the app left it) to
/// GENERAL for the copies and the in-place enhancement (`to_general`), or back afterwards; one
/// barrier per layer. The app may have written its image in any way (drawn, copied, computed),
/// and the runtime may use it in any way after: the barrier waits for every earlier access and
/// makes the layer's writes visible to every later one.
pub fn record_layout_barriers(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    regions: &[ImageRegion],
    to_general: bool,
) {
    let mut seen = HashSet::new();
    let any = vk::AccessFlags::MEMORY_WRITE | vk::AccessFlags::MEMORY_READ;
    // The layer's accesses: copies, the in-place passes and the image-copy path's write-back
    // draw (a colour attachment in GENERAL).
    let transfer = vk::AccessFlags::TRANSFER_READ
        | vk::AccessFlags::TRANSFER_WRITE
        | vk::AccessFlags::SHADER_READ
        | vk::AccessFlags::SHADER_WRITE
        | vk::AccessFlags::COLOR_ATTACHMENT_READ
        | vk::AccessFlags::COLOR_ATTACHMENT_WRITE;
    let attachment = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
    let general = vk::ImageLayout::GENERAL;
    let ((old, new), (src, dst)) = if to_general {
        ((attachment, general), (any, transfer))
    } else {
        ((general, attachment), (transfer, any))
    };
    let barriers: Vec<_> = regions
        .iter()
        .filter(|r| seen.insert((r.image, r.array_index)))
        .map(|r| {
            vk::ImageMemoryBarrier::default()
                .old_layout(old)
                .new_layout(new)
                .src_access_mask(src)
                .dst_access_mask(dst)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(r.image)
                .subresource_range(subresource(r.array_index))
        })
        .collect();
    let all = vk::PipelineStageFlags::ALL_COMMANDS;
    let transfer = vk::PipelineStageFlags::TRANSFER
        | vk::PipelineStageFlags::COMPUTE_SHADER
        | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT;
    let (src, dst) = if to_general {
        (all, transfer)
    } else {
        (transfer, all)
    };
    // SAFETY: cmd is recording (the caller's contract); the images are valid and not in use
    // by other queues (the layer holds the app's images until xrEndFrame).
    unsafe {
        gpu.device.cmd_pipeline_barrier(
            cmd,
            src,
            dst,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &barriers,
        )
    };
}

/// Copies a region (image in GENERAL) into `pixels` (`to_buffer`) or back, rows tightly packed.
pub fn record_region_copy(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    region: &ImageRegion,
    pixels: &GpuBuffer,
    to_buffer: bool,
) {
    let copy = [region.copy_of(0, (0, 0), region.extent)];
    let d = &gpu.device;
    // SAFETY: cmd is recording; the image is in GENERAL (record_layout_barriers) and the
    // region lies inside it and fits `pixels` (the caller's contract).
    unsafe {
        if to_buffer {
            d.cmd_copy_image_to_buffer(
                cmd,
                region.image,
                vk::ImageLayout::GENERAL,
                pixels.raw,
                &copy,
            );
        } else {
            d.cmd_copy_buffer_to_image(
                cmd,
                pixels.raw,
                region.image,
                vk::ImageLayout::GENERAL,
                &copy,
            );
        }
    }
}

/// Copies a region (image in GENERAL) into `own`, an image of the engine's own of a
/// size-compatible format in GENERAL, at its origin (`to_own`), or back: the raw bytes, as
/// vkCmdCopyImage copies between size-compatible formats (R8G8B8A8_SRGB into R8G8B8A8_UNORM,
/// B8G8R8A8 into R8G8B8A8, A2B10G10R10 into R32_UINT, ...). Only the region's rectangle of
/// its one array layer.
pub fn record_image_region_copy(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    region: &ImageRegion,
    own: vk::Image,
    to_own: bool,
) {
    let layer = |index: u32| {
        vk::ImageSubresourceLayers::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .base_array_layer(index)
            .layer_count(1)
    };
    let at = vk::Offset3D {
        x: region.offset.0,
        y: region.offset.1,
        z: 0,
    };
    let extent = vk::Extent3D {
        width: region.extent.0,
        height: region.extent.1,
        depth: 1,
    };
    let (app, origin) = (
        (layer(region.array_index), at),
        (layer(0), vk::Offset3D::default()),
    );
    let ((src_layer, src_offset), (dst_layer, dst_offset)) = match to_own {
        true => (app, origin),
        false => (origin, app),
    };
    let copy = [vk::ImageCopy::default()
        .src_subresource(src_layer)
        .src_offset(src_offset)
        .dst_subresource(dst_layer)
        .dst_offset(dst_offset)
        .extent(extent)];
    let (src, dst) = match to_own {
        true => (region.image, own),
        false => (own, region.image),
    };
    let general = vk::ImageLayout::GENERAL;
    // SAFETY: cmd is recording; both images are in GENERAL, the region lies inside the app's
    // image and `own` is at least the region's size, of a size-compatible format (the
    // caller's contract).
    unsafe {
        gpu.device
            .cmd_copy_image(cmd, src, general, dst, general, &copy)
    };
}

/// The layout an image of the engine's own is first used in: from UNDEFINED (its contents
/// discarded) to `layout`, before the accesses of `stage`. One barrier for all `images`.
pub fn record_first_layout(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    images: &[vk::Image],
    layout: vk::ImageLayout,
    (stage, access): (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barriers: Vec<_> = images
        .iter()
        .map(|&image| {
            vk::ImageMemoryBarrier::default()
                .old_layout(vk::ImageLayout::UNDEFINED)
                .new_layout(layout)
                .dst_access_mask(access)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(subresource(0))
        })
        .collect();
    // SAFETY: cmd is recording (the caller's contract); the images are the caller's own and
    // not in use.
    unsafe {
        gpu.device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TOP_OF_PIPE,
            stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &barriers,
        )
    };
}
