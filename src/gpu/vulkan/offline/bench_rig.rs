//! The benchmark's set-up (gpu/vulkan/offline/bench.rs): per case, the camera frame, the views (through a
//! buffer copy and, where the device can store the format, in place and through an image of the
//! engine's own), the pristine content, the
//! app-like images and the timestamp queries; and their release.

use super::offline_engine::VkOffline;
use crate::gpu::core::bench::{camera_frame, content_pixel, BenchCase, CAMERA_SIZE};
use crate::gpu::core::PixelFormat;
use crate::gpu::vulkan::conv::VkFormat;
use crate::gpu::vulkan::device::{layer_view, StorageImage};
use crate::gpu::vulkan::device::{
    record_first_layout, record_layout_barriers, record_region_copy, ImageRegion,
};
use crate::gpu::vulkan::device::{DeviceImage, GpuBuffer, GpuDevice, GpuError, VkResultExt};
use crate::gpu::vulkan::frame::{can_store, copy_path, storage_view, ViewPath};
use crate::gpu::vulkan::pipelines::{WriteBackAttachment, WriteBackPipelines};
use crate::gpu::vulkan::record::{
    CameraResources, PixelsIn, Placement, ViewShape, ViewTarget, WriteBackDraw,
};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// Everything one case allocates; `destroy` frees what was made.
pub(super) struct Rig {
    pub(super) background: Option<CameraResources>,
    pub(super) views: Vec<ViewTarget>,
    pub(super) sources: Vec<GpuBuffer>,
    /// One app-like image per view (R8G8B8A8_SRGB, as the content), kept in
    /// COLOR_ATTACHMENT_OPTIMAL between runs, as an app leaves it at xrEndFrame.
    pub(super) images: Vec<DeviceImage>,
    pub(super) staging: Option<GpuBuffer>,
    /// Views enhanced in place in `images` (one each; empty unless the case asks for them
    /// and the device can store the format), and the images' storage views they are bound to.
    pub(super) in_place: Vec<ViewTarget>,
    pub(super) storage_views: Vec<vk::ImageView>,
    /// Views through the image-copy path (one per app image; empty unless the case asks for
    /// them and the device can store the format), each bound to its image in `own_images`.
    pub(super) image_copy: Vec<ViewTarget>,
    pub(super) own_images: Vec<StorageImage>,
    /// The image-copy views' write-back by drawing (with them), each view's draw and the
    /// attachment of its app image.
    pub(super) write_back: Option<WriteBackPipelines>,
    pub(super) write_back_draws: Vec<(WriteBackDraw, WriteBackAttachment)>,
    /// Views through the sampled read (with the draws: one per app image, reading a sampled
    /// view of it in `sampled_views` and writing its image in `own_images`), and their draws.
    pub(super) sampled: Vec<ViewTarget>,
    pub(super) sampled_views: Vec<vk::ImageView>,
    pub(super) sampled_draws: Vec<(WriteBackDraw, WriteBackAttachment)>,
    pub(super) queries: vk::QueryPool,
}

impl Rig {
    pub(super) fn regions(&self, size: (u32, u32)) -> Vec<ImageRegion> {
        let region = |i: &DeviceImage| ImageRegion {
            image: i.raw,
            array_index: 0,
            offset: (0, 0),
            extent: size,
        };
        self.images.iter().map(region).collect()
    }
}

/// An app-like image of the bench's format (R8G8B8A8_SRGB, as the content); with storage
/// usage and a mutable format when the case times the frame in place, as the layer asks of the
/// runtime for its swapchains, and sampled usage when it times the sampled read.
fn app_image(gpu: &GpuDevice, case: &BenchCase) -> Result<DeviceImage, GpuError> {
    let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
        | vk::ImageUsageFlags::TRANSFER_SRC
        | vk::ImageUsageFlags::TRANSFER_DST;
    let mut flags = vk::ImageCreateFlags::empty();
    if case.tiles {
        usage |= vk::ImageUsageFlags::SAMPLED;
    }
    if case.in_place && can_store(gpu, PixelFormat::SRGB8) {
        usage |= vk::ImageUsageFlags::STORAGE;
        flags |= vk::ImageCreateFlags::MUTABLE_FORMAT | vk::ImageCreateFlags::EXTENDED_USAGE;
    }
    DeviceImage::with_flags(gpu, case.region, vk::Format::R8G8B8A8_SRGB, usage, flags)
}

impl VkOffline {
    /// The engine views a bench case holds per app view at most: the buffer path's, in place,
    /// the image-copy path's and the sampled read's (`with_views` takes this many per view).
    pub const BENCH_TARGETS_PER_VIEW: u32 = 4;

    /// One view through the image-copy path per app image, bound to an image of its own.
    fn add_image_copy_views(&mut self, rig: &mut Rig, case: &BenchCase) -> Result<(), GpuError> {
        let gpu = &self.gpu;
        let background = rig.background.as_ref().expect("made before");
        let format = PixelFormat::SRGB8;
        let own_format = format
            .image_copy_format()
            .ok_or_else(|| GpuError::Unsupported("no image-copy format".into()))?;
        let shape = ViewShape {
            format,
            width: case.region.0,
            pixels_in: PixelsIn::Image,
        };
        for _ in &rig.images {
            rig.own_images
                .push(StorageImage::for_copies(gpu, case.region, own_format)?);
            let target = (shape, case.region.1);
            let target =
                self.engine
                    .create_shaped_view(gpu, target, background, Placement::DEVICE)?;
            let own = rig.own_images.last().expect("pushed above");
            self.engine.bind_app_image(gpu, &target, own.view);
            rig.image_copy.push(target);
        }
        match case.tiles {
            true => self.add_write_back_draws(rig, case),
            false => Ok(()),
        }
    }

    /// The image-copy views' write-back by drawing: a draw per view into its app image; and
    /// the sampled read's views with theirs.
    fn add_write_back_draws(&mut self, rig: &mut Rig, case: &BenchCase) -> Result<(), GpuError> {
        let regions = rig.regions(case.region);
        let pipelines = rig.write_back.insert(WriteBackPipelines::new(&self.gpu)?);
        let formats = (vk::Format::R8G8B8A8_SRGB, PixelFormat::SRGB8);
        let views = rig.image_copy.iter().zip(&rig.own_images);
        for (region, view) in regions.iter().zip(views) {
            let draw = self.write_back_draw(pipelines, formats, *region, view)?;
            rig.write_back_draws.push(draw);
        }
        let background = rig.background.as_ref().expect("made before");
        let shape = ViewShape {
            format: PixelFormat::SRGB8,
            width: case.region.0,
            pixels_in: PixelsIn::SampledImage,
        };
        for (region, own) in regions.into_iter().zip(&rig.own_images) {
            let gpu = &self.gpu;
            let texels = layer_view(gpu, region.image, 0, formats.0)?;
            rig.sampled_views.push(texels);
            let target = (shape, case.region.1);
            let target =
                self.engine
                    .create_shaped_view(gpu, target, background, Placement::DEVICE)?;
            self.engine.bind_app_image(gpu, &target, own.view);
            self.engine.bind_app_texels(gpu, &target, texels);
            rig.sampled.push(target);
            let view = rig.sampled.last().expect("pushed above");
            let draw = self.write_back_draw(pipelines, formats, region, (view, own))?;
            rig.sampled_draws.push(draw);
        }
        Ok(())
    }

    /// One view in place per app image, bound to a storage view of it.
    fn add_in_place_views(&mut self, rig: &mut Rig, case: &BenchCase) -> Result<(), GpuError> {
        let gpu = &self.gpu;
        let background = rig.background.as_ref().expect("made before");
        let shape = ViewShape {
            format: PixelFormat::SRGB8,
            width: case.region.0,
            pixels_in: PixelsIn::Image,
        };
        for image in &rig.images {
            let view = storage_view(gpu, image.raw, 0, PixelFormat::SRGB8)?;
            rig.storage_views.push(view);
            let target = (shape, case.region.1);
            let target =
                self.engine
                    .create_shaped_view(gpu, target, background, Placement::DEVICE)?;
            self.engine.bind_app_image(gpu, &target, view);
            rig.in_place.push(target);
        }
        Ok(())
    }

    /// Allocates the camera frame, views, pristine sources and query pool; returns the
    /// foreground fraction of the content.
    /// `queries`: the timestamp queries a run writes.
    pub(super) fn build_rig(
        &mut self,
        rig: &mut Rig,
        case: &BenchCase,
        queries: u32,
    ) -> Result<f64, GpuError> {
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
            rig.images.push(app_image(gpu, case)?);
        }
        if case.in_place && can_store(gpu, PixelFormat::SRGB8) {
            self.add_in_place_views(rig, case)?;
        }
        if case.image_copy && copy_path(&self.gpu, PixelFormat::SRGB8) == ViewPath::ImageCopy {
            self.add_image_copy_views(rig, case)?;
        }
        self.fill_sources(rig, bytes.len() as u64)?;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(queries);
        // SAFETY: a valid create info on the engine's own device.
        rig.queries =
            unsafe { self.gpu.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        Ok(foreground / f64::from(w * h))
    }

    /// Fills the copy sources with the content and brings the images to the layout an app
    /// leaves them in (their content is written at each run, `restore_images`).
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
            let images: Vec<vk::Image> = rig.images.iter().map(|i| i.raw).collect();
            let attachment = (
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            );
            let layout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
            record_first_layout(&self.gpu, cmd, &images, layout, attachment);
            Ok(())
        })
    }

    /// Writes the pristine content into each app image (an app's newly rendered frame).
    pub(super) fn restore_images(
        &self,
        cmd: vk::CommandBuffer,
        rig: &Rig,
        regions: &[ImageRegion],
    ) {
        let staging = rig.staging.as_ref().expect("made before");
        record_layout_barriers(&self.gpu, cmd, regions, true);
        for r in regions {
            record_region_copy(&self.gpu, cmd, r, staging, false);
        }
        record_layout_barriers(&self.gpu, cmd, regions, false);
    }

    pub(super) fn destroy_rig(&mut self, mut rig: Rig) {
        let gpu = &self.gpu;
        // SAFETY: every submission was waited for; the pool is ours (null is ignored).
        unsafe { gpu.device.destroy_query_pool(rig.queries, None) };
        for mut v in rig.views.drain(..) {
            self.engine.destroy_view(gpu, &mut v);
        }
        rig.sources.iter_mut().for_each(|b| b.destroy(gpu));
        for mut v in rig.in_place.drain(..) {
            self.engine.destroy_view(gpu, &mut v);
        }
        for mut v in rig.image_copy.drain(..).chain(rig.sampled.drain(..)) {
            self.engine.destroy_view(gpu, &mut v);
        }
        if let Some(mut pipelines) = rig.write_back.take() {
            let draws = rig.write_back_draws.drain(..);
            for (_, mut attachment) in draws.chain(rig.sampled_draws.drain(..)) {
                attachment.destroy(gpu);
            }
            // Its pool frees the views' sets.
            pipelines.destroy(gpu);
        }
        rig.own_images.iter_mut().for_each(|i| i.destroy(gpu));
        for v in rig
            .storage_views
            .drain(..)
            .chain(rig.sampled_views.drain(..))
        {
            // SAFETY: made by this rig on this device; every submission was waited for.
            unsafe { gpu.device.destroy_image_view(v, None) };
        }
        rig.images.iter_mut().for_each(|i| i.destroy(gpu));
        if let Some(mut b) = rig.staging.take() {
            b.destroy(gpu);
        }
        if let Some(mut b) = rig.background.take() {
            b.destroy(gpu);
        }
    }
}
