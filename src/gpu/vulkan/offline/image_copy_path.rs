//! The offline engine's image-copy path: a view's region of an app-like image that has no
//! storage usage (as a swapchain whose runtime refused it), copied with vkCmdCopyImage into an
//! image of the engine's own in the format's storage texel format, enhanced there by the
//! in-place shaders and copied back, as the layer does (gpu/vulkan/frame/frame_record.rs); beside
//! `enhance_raw` (through a buffer) and `enhance_raw_in_place` so that tests can hold the
//! paths to each other, on any sub-rectangle and array layer.

use super::offline_engine::VkOffline;
use crate::algorithm::params::Params;
use crate::gpu::core::interface::sampled_read;
use crate::gpu::core::CameraRect;
use crate::gpu::core::PixelFormat;
use crate::gpu::vulkan::conv::VkFormat;
use crate::gpu::vulkan::device::{
    barrier, layer_view, record_first_layout, record_image_region_copy, record_layout_barriers,
    DeviceImage, GpuBuffer, GpuError, ImageRegion, StorageImage,
};
use crate::gpu::vulkan::frame::{copy_path, ViewPath};
use crate::gpu::vulkan::pipelines::{WriteBackAttachment, WriteBackPipelines};
use crate::gpu::vulkan::record::{
    record_write_back, record_write_back_barrier, PixelsIn, ViewShape, ViewTarget, WriteBackDraw,
};
use crate::image::RgbaImage;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// An app-like image and where the view's region lies in it.
#[derive(Clone, Copy, Debug)]
pub struct AppImage {
    pub size: (u32, u32),
    pub layers: u32,
    /// The region: its offset, size and array layer.
    pub offset: (i32, i32),
    pub extent: (u32, u32),
    pub layer: u32,
}

/// Every layer of `image` from `old` to `new` layout, after `src` accesses, before `dst`.
fn all_layers(
    image: vk::Image,
    (old, new): (vk::ImageLayout, vk::ImageLayout),
    (src, dst): (vk::AccessFlags, vk::AccessFlags),
) -> vk::ImageMemoryBarrier<'static> {
    vk::ImageMemoryBarrier::default()
        .old_layout(old)
        .new_layout(new)
        .src_access_mask(src)
        .dst_access_mask(dst)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(vk::REMAINING_ARRAY_LAYERS),
        )
}

/// The image-copy path's run: the image, its formats, the write-back's pipelines (None: the
/// region is copied back whole) and the sampled view of the image's layer the sampled read
/// reads (None: the region is copied in).
type RunImageCopy<'a> = (
    AppImage,
    (vk::Format, PixelFormat),
    Option<&'a mut WriteBackPipelines>,
    Option<vk::ImageView>,
);

impl VkOffline {
    /// The image-copy path on `app`, an image of `vk_format`: `image_words` is the whole image's raw words (layer after
    /// layer, rows tightly packed); the region is enhanced through an image of the engine's
    /// own, copied back whole, and the whole image is read back, every layer.
    pub fn enhance_raw_image_copy(
        &mut self,
        image_words: &[u32],
        (vk_format, app): (vk::Format, AppImage),
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<Vec<u32>, GpuError> {
        let image = (vk_format, app);
        self.enhance_raw_image_copy_back(image_words, image, (camera, params), ViewPath::ImageCopy)
    }

    /// `enhance_raw_image_copy` with the enhanced pixels brought in and back as `path` says:
    /// the region copied back (`ViewPath::ImageCopy`) or its listed tiles drawn back
    /// (`ViewPath::ImageCopyTiles`), or the region read through a sampled view instead of
    /// copied in, and its listed tiles drawn back (`ViewPath::SampledTiles`, 8-bit sRGB
    /// formats); any other path is refused.
    pub fn enhance_raw_image_copy_back(
        &mut self,
        image_words: &[u32],
        (vk_format, app): (vk::Format, AppImage),
        (camera, params): (&RgbaImage, &Params),
        path: ViewPath,
    ) -> Result<Vec<u32>, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        if !path.writes_own_image() {
            return Err(GpuError::Unsupported(format!(
                "{} is not the image-copy path",
                path.name()
            )));
        }
        let format = PixelFormat::from_vk(vk_format)
            .ok_or_else(|| GpuError::Unsupported(format!("{vk_format:?}")))?;
        if path.reads_sampled() && !sampled_read(format.shader_code()) {
            return Err(GpuError::Unsupported(format!(
                "{vk_format:?} is not read through a sampled view"
            )));
        }
        if copy_path(&self.gpu, format) != ViewPath::ImageCopy {
            return Err(GpuError::Unsupported(format!(
                "{vk_format:?} is not enhanced through an image copy on this device"
            )));
        }
        let (w, h) = app.size;
        let bytes = u64::from(w * h * app.layers * format.bytes_per_pixel());
        if image_words.len() as u64 * 4 != bytes {
            return Err(GpuError::Unsupported(
                "pixel data does not match the image".into(),
            ));
        }
        let own_format = format.image_copy_format().expect("checked by copy_path");
        let usage = vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::SAMPLED;
        let mut image = DeviceImage::layered(&self.gpu, app.size, app.layers, vk_format, usage)?;
        let own = StorageImage::for_copies(&self.gpu, app.extent, own_format);
        let write_back = match path.draws_tiles_back() {
            true => WriteBackPipelines::new(&self.gpu).map(Some),
            false => Ok(None),
        };
        let own = own.and_then(|o| write_back.map(|w| (o, w)));
        let (mut own, mut write_back) = match own {
            Ok(o) => o,
            Err(e) => {
                image.destroy(&self.gpu);
                return Err(e);
            }
        };
        let sampled = match path.reads_sampled() {
            true => layer_view(&self.gpu, image.raw, app.layer, vk_format).map(Some),
            false => Ok(None),
        };
        let sampled = match sampled {
            Ok(v) => v,
            Err(e) => {
                write_back.iter_mut().for_each(|w| w.destroy(&self.gpu));
                own.destroy(&self.gpu);
                image.destroy(&self.gpu);
                return Err(e);
            }
        };
        let staging = GpuBuffer::new(
            &self.gpu,
            bytes,
            vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
            "staging",
        );
        let result = staging.and_then(|mut staging| {
            let bytes: Vec<u8> = image_words.iter().flat_map(|w| w.to_le_bytes()).collect();
            let run = staging.write(&bytes).and_then(|_| {
                let run = (app, (vk_format, format), write_back.as_mut(), sampled);
                self.run_image_copy(&image, &own, &staging, run, (camera, params))
            });
            let out = run.and_then(|_| {
                let mapped = staging.mapped().ok_or_else(|| {
                    GpuError::Unsupported("staging buffer is not host-visible".into())
                })?;
                Ok(mapped
                    .as_chunks::<4>()
                    .0
                    .iter()
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect())
            });
            staging.destroy(&self.gpu);
            out
        });
        if let Some(w) = write_back.as_mut() {
            w.destroy(&self.gpu);
        }
        if let Some(v) = sampled {
            // SAFETY: made above; the submission that used it has finished.
            unsafe { self.gpu.device.destroy_image_view(v, None) };
        }
        own.destroy(&self.gpu);
        image.destroy(&self.gpu);
        result
    }

    /// Uploads every layer, prepares the background, runs the image-copy path on the region
    /// (copied in, or read through `sampled`; copied back whole, or its tiles drawn back with
    /// `write_back`) and reads every layer back, in one submission.
    fn run_image_copy(
        &self,
        image: &DeviceImage,
        own: &StorageImage,
        staging: &GpuBuffer,
        (app, (vk_format, format), write_back, sampled): RunImageCopy,
        (camera, params): (&RgbaImage, &Params),
    ) -> Result<(), GpuError> {
        let gpu = &self.gpu;
        let shape = ViewShape {
            format,
            width: app.extent.0,
            pixels_in: match sampled {
                Some(_) => PixelsIn::SampledImage,
                None => PixelsIn::Image,
            },
        };
        let (mut bg, mut view) = self.stage_shaped(camera, (shape, app.extent.1))?;
        self.engine.bind_app_image(gpu, &view, own.view);
        if let Some(texels) = sampled {
            self.engine.bind_app_texels(gpu, &view, texels);
            // The shaders read the app's image at the region's place, and write the engine's
            // image at the pixel's place in the region.
            view.origin = (app.offset.0 as u32, app.offset.1 as u32);
        }
        let mapping = params.camera_mapping();
        let region = ImageRegion {
            image: image.raw,
            array_index: app.layer,
            offset: app.offset,
            extent: app.extent,
        };
        let drawn = match write_back {
            Some(w) => match self.write_back_draw(w, (vk_format, format), region, (&view, own)) {
                Ok(d) => Some((&*w, d)),
                Err(e) => {
                    self.engine.destroy_view(gpu, &mut view);
                    bg.destroy(gpu);
                    return Err(e);
                }
            },
            None => None,
        };
        let whole = vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .layer_count(app.layers),
            )
            .image_extent(vk::Extent3D {
                width: app.size.0,
                height: app.size.1,
                depth: 1,
            });
        let done = self.submit(|cmd| {
            use vk::{AccessFlags as A, ImageLayout as L, PipelineStageFlags as S};
            let d = &gpu.device;
            let layout = |(old, new), access, (src, dst)| {
                let b = [all_layers(image.raw, (old, new), access)];
                // SAFETY: cmd is recording; the image is ours and not in use elsewhere.
                unsafe {
                    d.cmd_pipeline_barrier(
                        cmd,
                        src,
                        dst,
                        vk::DependencyFlags::empty(),
                        &[],
                        &[],
                        &b,
                    )
                };
            };
            let general = L::GENERAL;
            layout(
                (L::UNDEFINED, general),
                (A::empty(), A::TRANSFER_WRITE),
                (S::TOP_OF_PIPE, S::TRANSFER),
            );
            // SAFETY: cmd is recording; the buffer holds every layer, the image is in GENERAL.
            unsafe { d.cmd_copy_buffer_to_image(cmd, staging.raw, image.raw, general, &[whole]) };
            // As an app leaves its images at xrEndFrame.
            layout(
                (general, L::COLOR_ATTACHMENT_OPTIMAL),
                (A::TRANSFER_WRITE, A::COLOR_ATTACHMENT_WRITE),
                (S::TRANSFER, S::COLOR_ATTACHMENT_OUTPUT),
            );
            // What the layer records for a view through the image-copy path.
            record_layout_barriers(gpu, cmd, &[region], true);
            match sampled {
                Some(_) => {
                    let write = (S::COMPUTE_SHADER, A::SHADER_READ | A::SHADER_WRITE);
                    record_first_layout(gpu, cmd, &[own.image.raw], general, write);
                }
                None => {
                    let write = (S::TRANSFER, A::TRANSFER_WRITE);
                    record_first_layout(gpu, cmd, &[own.image.raw], general, write);
                    record_image_region_copy(gpu, cmd, &region, own.image.raw, true);
                    barrier(gpu, cmd, S::TRANSFER, S::COMPUTE_SHADER | S::TRANSFER);
                }
            }
            let rect = CameraRect::sampled_by(&[mapping], bg.size);
            self.engine
                .record_background(gpu, cmd, &bg, params, &rect)?;
            self.engine
                .record_enhance(gpu, cmd, &view, params, &mapping)?;
            match &drawn {
                Some((w, (draw, _))) => {
                    record_write_back_barrier(gpu, cmd);
                    record_write_back(gpu, cmd, w, draw);
                }
                None => {
                    barrier(gpu, cmd, S::COMPUTE_SHADER, S::TRANSFER);
                    record_image_region_copy(gpu, cmd, &region, own.image.raw, false);
                }
            }
            record_layout_barriers(gpu, cmd, &[region], false);
            // Read every layer back.
            layout(
                (L::COLOR_ATTACHMENT_OPTIMAL, general),
                (A::MEMORY_WRITE, A::TRANSFER_READ),
                (S::ALL_COMMANDS, S::TRANSFER),
            );
            // SAFETY: as above, the other way.
            unsafe { d.cmd_copy_image_to_buffer(cmd, image.raw, general, staging.raw, &[whole]) };
            Ok(())
        });
        if let Some((w, (draw, mut attachment))) = drawn {
            w.free_set(gpu, draw.set());
            attachment.destroy(gpu);
        }
        self.engine.destroy_view(gpu, &mut view);
        bg.destroy(gpu);
        done
    }

    /// The write-back's draw of `view` (enhanced in `own`) into `region` of an image of
    /// `vk_format`, and the attachment it draws into.
    pub(super) fn write_back_draw(
        &self,
        pipelines: &mut WriteBackPipelines,
        (vk_format, format): (vk::Format, PixelFormat),
        region: ImageRegion,
        (view, own): (&ViewTarget, &StorageImage),
    ) -> Result<(WriteBackDraw, WriteBackAttachment), GpuError> {
        let gpu = &self.gpu;
        let pass = pipelines.pass(gpu, (vk_format, format))?;
        let layer = (region.image, vk_format, region.array_index);
        let far = region.far_corner();
        let mut attachment = WriteBackAttachment::new(gpu, pass.render_pass(), layer, far)?;
        match pipelines.view_set(gpu, view.tiles.raw, own.view) {
            Ok(set) => Ok((
                WriteBackDraw::new(
                    (pass, attachment.framebuffer()),
                    (set, view.tiles.raw),
                    region,
                ),
                attachment,
            )),
            Err(e) => {
                attachment.destroy(gpu);
                Err(e)
            }
        }
    }
}
