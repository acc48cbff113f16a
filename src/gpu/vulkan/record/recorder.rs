//! The engine: records the background preparation (once per camera frame, on the camera grid)
//! and the per-pixel enhancement (per view, sampling that image through the view's
//! CameraMapping) into a command buffer that the caller owns and submits. It works the same on a device it created (the CLI)
//! and on someone else's device and queue (the app's, in the layer): it never submits, waits or
//! touches images itself. Data lives in storage buffers, so the swapchain's format never has to
//! be a storage-image format: the caller copies a view's region into `ViewTarget::pixels` and back.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::method::Pass;
use crate::algorithm::params::{Params, ViewMode};
use crate::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use crate::gpu::core::interface::TILE;
use crate::gpu::core::interface::{
    in_place_texel, BindingKind, BINDING_BLURRED, BINDING_CAMERA, BINDING_PERCEPTUAL,
    BINDING_PIXELS, BINDING_SOURCE, BINDING_TILES, PERCEPTUAL_WORDS, TILE_LIST_HEADER_WORDS,
};
use crate::gpu::core::shader_ids::{self, ShaderId};
use crate::gpu::core::shares_fetches;
use crate::gpu::core::PixelFormat;
use crate::gpu::core::{ClassifyChoice, CubeRoots, VariantKey};
use crate::gpu::vulkan::device::{
    colour_layer, DeviceImage, GpuBuffer, GpuDevice, GpuError, VkResultExt,
};
use crate::gpu::vulkan::pipelines::{binding_count, BuildMode, BuildReport, Pipelines, WarmUpHook};
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::resources::{
    alloc_all, camera_stride, transfer_storage, CameraResources, PixelsIn, Placement, ViewShape,
    ViewTarget, STORAGE, TEXELS_FORMAT,
};
use super::set_pool::SetPool;

/// The per-pixel passes' workgroups are TILE x TILE (src/gpu/core/interface.rs, WORKGROUPS).
pub(super) const WORKGROUP: u32 = TILE;

/// Background frames that may exist at once besides the views (their descriptor sets).
const MAX_BACKGROUNDS: u32 = 2;

/// Bytes after the decoded camera texels in `blurred`: a row window at the last row reads up to
/// 5 entries past them (blur half-width 7).
const DECODED_SLACK: u64 = 16 * 8;

pub struct Recorder {
    pub(super) pipelines: Pipelines,
    pool: SetPool,
    /// Take the shared-fetch variant where a view's mapping allows it (gpu/core/shared_fetch.rs);
    /// off only to compare it with the general one.
    pub(super) shared_fetch: bool,
    /// The benchmark's ablations (interface.rs ABLATE_*): 0, but for `contrastxr bench
    /// --ablate`.
    pub(super) ablate: u32,
    /// Which `classify` views take: their method's own, but for `contrastxr bench --ablate
    /// classify` and `classify-rows`.
    pub(super) classify: ClassifyChoice,
    /// How views take the CIELAB cube roots: the device's way (`CubeRoots::for_device`).
    pub(super) roots: CubeRoots,
}

pub(super) const COMPUTE: vk::PipelineStageFlags = vk::PipelineStageFlags::COMPUTE_SHADER;

impl Recorder {
    /// Sets up the pipelines, built as `mode` says; `max_views` bounds how many ViewTargets
    /// may exist at once.
    pub fn new(
        gpu: &GpuDevice,
        max_views: u32,
        mode: BuildMode,
        warm_up: Option<WarmUpHook>,
    ) -> Result<Recorder, GpuError> {
        let mut pipelines = Pipelines::new(gpu, mode, warm_up)?;
        let max_sets = max_views + MAX_BACKGROUNDS;
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(max_sets * binding_count(BindingKind::StorageBuffer)),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::SAMPLED_IMAGE)
                .descriptor_count(max_sets * binding_count(BindingKind::SampledImage)),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_IMAGE)
                .descriptor_count(max_sets * binding_count(BindingKind::StorageImage)),
        ];
        match SetPool::new(gpu, max_sets, &sizes) {
            Ok(pool) => Ok(Recorder {
                pipelines,
                pool,
                shared_fetch: true,
                ablate: 0,
                classify: ClassifyChoice::Own,
                roots: CubeRoots::for_device(gpu.is_cpu()),
            }),
            Err(e) => {
                pipelines.destroy(gpu);
                Err(e)
            }
        }
    }

    pub fn create_background(
        &self,
        gpu: &GpuDevice,
        size: (u32, u32),
        placement: Placement,
    ) -> Result<CameraResources, GpuError> {
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
        let mut bg = CameraResources {
            size,
            camera,
            blurred,
            texels: DeviceImage::none(),
            texels_view: vk::ImageView::null(),
            set: vk::DescriptorSet::null(),
            pool: self.pool.clone(),
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
    /// The pipelines the engine records with.
    pub(crate) fn pipelines(&self) -> &Pipelines {
        &self.pipelines
    }

    /// Whether views whose mapping allows it take the shared-fetch `enhance` variant (on by
    /// default); off, every view takes the general one, to compare them.
    pub fn set_shared_fetch(&mut self, on: bool) {
        self.shared_fetch = on;
    }

    /// How views take the CIELAB cube roots: the device's way by default
    /// (`CubeRoots::for_device`); the other, to compare them or to test it on this device.
    pub fn set_cube_roots(&mut self, roots: CubeRoots) {
        self.roots = roots;
    }

    /// How views take the CIELAB cube roots (where their variant is built that way).
    pub fn cube_roots(&self) -> CubeRoots {
        self.roots
    }

    /// The benchmark's ablations (interface.rs ABLATE_*; 0, the default, for none): views then
    /// take the ablated `enhance`, built for the paper's and the perceptual method in mode
    /// enhance on RGBA8 sRGB only. Their output is not an enhancement.
    pub fn set_ablation(&mut self, ablate: u32) {
        self.ablate = ablate;
    }

    /// Which `classify` views take (their method's own by default), to compare them.
    pub fn set_classify(&mut self, choice: ClassifyChoice) {
        self.classify = choice;
    }

    pub(crate) fn background_parts(bg: &CameraResources) -> (vk::DescriptorSet, vk::Image) {
        (bg.set, bg.texels.raw)
    }

    pub(crate) fn view_set(view: &ViewTarget) -> vk::DescriptorSet {
        view.set
    }

    /// The image the enhancement samples, its view, and the preparation's descriptor set.
    fn make_texels(&self, gpu: &GpuDevice, bg: &mut CameraResources) -> Result<(), GpuError> {
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        bg.texels = DeviceImage::with_usage(gpu, bg.size, TEXELS_FORMAT, usage)?;
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

    /// A set of the passes' layout; the pool holds max_views views plus MAX_BACKGROUNDS
    /// background frames, and refuses more on every driver.
    fn allocate_set(&self, gpu: &GpuDevice) -> Result<vk::DescriptorSet, GpuError> {
        self.pool.allocate(gpu, self.pipelines.set_layout())
    }

    /// A view enhanced through a copy of its region (`pixels`).
    pub fn create_view(
        &self,
        gpu: &GpuDevice,
        region: (u32, u32),
        format: PixelFormat,
        background: &CameraResources,
        placement: Placement,
    ) -> Result<ViewTarget, GpuError> {
        let shape = ViewShape {
            format,
            width: region.0,
            pixels_in: PixelsIn::Buffer,
        };
        self.create_shaped_view(gpu, (shape, region.1), background, placement)
    }

    /// A view of `shape` and `height`: in place (the app's image bound later with
    /// `bind_app_image`; `pixels` is then a 16-byte stand-in) or through a copy.
    pub fn create_shaped_view(
        &self,
        gpu: &GpuDevice,
        (shape, height): (ViewShape, u32),
        background: &CameraResources,
        placement: Placement,
    ) -> Result<ViewTarget, GpuError> {
        let (region, format) = ((shape.width, height), shape.format);
        if region.0 == 0 || region.1 == 0 {
            return Err(GpuError::Unsupported("empty display region".into()));
        }
        if shape.pixels_in.in_image() && in_place_texel(format.shader_code()).is_none() {
            return Err(GpuError::Unsupported(format!(
                "{format:?} is not enhanced in place"
            )));
        }
        let px = match shape.pixels_in.in_image() {
            true => 16 / u64::from(format.bytes_per_pixel()),
            false => u64::from(region.0) * u64::from(region.1),
        };
        let usage = transfer_storage();
        let bpp = u64::from(format.bytes_per_pixel());
        let at = placement.working;
        let tile_count = u64::from(region.0.div_ceil(TILE)) * u64::from(region.1.div_ceil(TILE));
        let tile_usage =
            STORAGE | vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let gpu_only = MemoryLocation::GpuOnly;
        let model_usage = STORAGE | vk::BufferUsageFlags::TRANSFER_DST;
        let [pixels, tiles, perceptual] = alloc_all(
            gpu,
            [
                (px * bpp, usage, at, "pixels"),
                (
                    (TILE_LIST_HEADER_WORDS + tile_count) * 4,
                    tile_usage,
                    gpu_only,
                    "tiles",
                ),
                (
                    u64::from(PERCEPTUAL_WORDS) * 4,
                    model_usage,
                    gpu_only,
                    "perceptual",
                ),
            ],
        )?;
        let mut view = ViewTarget {
            region,
            format,
            pixels_in: shape.pixels_in,
            origin: (0, 0),
            pixels,
            tiles,
            perceptual,
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
            perceptual_words: Default::default(),
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
    pub fn bind(&self, gpu: &GpuDevice, view: &mut ViewTarget, background: &CameraResources) {
        let buffers = [
            (BINDING_CAMERA, &background.camera),
            (BINDING_BLURRED, &background.blurred),
            (BINDING_PIXELS, &view.pixels),
            (BINDING_TILES, &view.tiles),
            // The copy passes read the pixels in place unless a source is bound.
            (BINDING_SOURCE, &view.pixels),
            (BINDING_PERCEPTUAL, &view.perceptual),
        ];
        for (binding, buffer) in buffers {
            self.write_set(gpu, view.set, binding, &[buffer]);
        }
        self.bind_texels(gpu, view, background.texels_view);
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
        self.pool.free(gpu, &mut view.set);
        for b in [&mut view.pixels, &mut view.tiles, &mut view.perceptual] {
            b.destroy(gpu);
        }
    }

    /// The shaders a frame's work needs: the background preparation for `params` and the
    /// enhancement of views of these pixel formats and widths (None for Mode off), on a device
    /// that takes its cube roots by `roots` (`Recorder::roots`).
    pub fn shaders_for(
        params: &Params,
        views: impl IntoIterator<Item = ViewShape>,
        roots: CubeRoots,
    ) -> Result<Vec<ShaderId>, GpuError> {
        if params.mode == ViewMode::Off {
            return Ok(Vec::new());
        }
        let half = params.blur_taps().len() as u32 / 2;
        let mut ids = vec![shader_ids::DECODE_CAMERA, shader_ids::decode_blur(half)?];
        // The method's passes (its entry in src/algorithm/method/table.rs): the one shader
        // every view shares first, then each view's own.
        let passes = params.method.entry().passes;
        if passes.contains(&Pass::FinishTiles) {
            ids.push(shader_ids::FINISH_TILES);
        }
        for view in views {
            let key = VariantKey::of(params, view.format, view.access()).with_roots(roots);
            for pass in passes {
                let id = match pass {
                    Pass::Classify => {
                        let own = key.classify_taken(ClassifyChoice::Own);
                        shader_ids::classify(key.format, key.access, own)?
                    }
                    Pass::FinishTiles => continue,
                    Pass::Enhance => shader_ids::enhance(key)?,
                };
                if !ids.contains(&id) {
                    ids.push(id);
                }
            }
        }
        Ok(ids)
    }

    /// The shared-fetch variants (gpu/core/shared_fetch.rs) a frame's views can take: those of the
    /// views whose mapping allows them, where `params` has one (build.rs builds them for the
    /// defaults only).
    pub fn shared_fetch_shaders_for<'a>(
        &self,
        params: &Params,
        views: impl IntoIterator<Item = (ViewShape, (u32, u32), &'a CameraMapping)>,
        camera: (u32, u32),
    ) -> Vec<ShaderId> {
        let mut ids = Vec::new();
        for (shape, region, mapping) in views {
            if !self.shared_fetch || !shares_fetches(mapping, region, camera) {
                continue;
            }
            let key = VariantKey::of(params, shape.format, shape.access()).with_roots(self.roots);
            if let Some(id) = shader_ids::enhance_shared(key) {
                if !ids.contains(&id) {
                    ids.push(id);
                }
            }
        }
        ids
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
        self.pool.destroy(gpu);
        self.pipelines.destroy(gpu);
    }
}
