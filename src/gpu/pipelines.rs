//! The compute pipelines built from the embedded SPIR-V, with the one descriptor-set layout and
//! push-constant block they share (see shaders/common.wgsl).

use super::device::GpuDevice;
use super::error::{GpuError, VkResultExt};
use super::shaders::{self, ShaderModule};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::{Params, ViewMode, SUBTRACTION_K_B, SUBTRACTION_K_V};
use ash::vk;
use std::sync::Mutex;

/// Bindings 0..=4 of shaders/common.wgsl, all storage buffers.
pub const BINDING_COUNT: u32 = 5;
/// Binding 5: the blurred camera image, a sampled image.
pub const IMAGE_BINDING: u32 = 5;

/// The push-constant block, laid out as WGSL lays out `Params`: 128 bytes, the least
/// maxPushConstantsSize Vulkan guarantees.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PushConstants {
    pub camera_size: [u32; 2],
    pub region_size: [u32; 2],
    pub lambda_e: f32,
    pub lambda_jnd: f32,
    pub transmittance: f32,
    pub blur_half: u32,
    pub taps: [f32; 8],
    pub k_v: f32,
    pub k_b: f32,
    pub mode: u32,
    pub tile_columns: u32,
    pub achromatic_boost: f32,
    pub luminance_cap: f32,
    /// The view's CameraMapping, row-major.
    pub mapping: [[f32; 3]; 3],
    /// WGSL rounds the struct's size up to its 16-byte alignment (the taps).
    pub pad: u32,
}

const _: () = assert!(std::mem::size_of::<PushConstants>() == 128);

impl PushConstants {
    pub fn new(
        params: &Params,
        camera: (u32, u32),
        region: (u32, u32),
        mapping: &CameraMapping,
    ) -> Self {
        let taps64 = params.blur_taps();
        let half = taps64.len() / 2;
        let mut taps = [0.0f32; 8];
        for (k, t) in taps.iter_mut().enumerate().take(half + 1) {
            *t = taps64[half + k] as f32;
        }
        PushConstants {
            camera_size: [camera.0, camera.1],
            region_size: [region.0, region.1],
            lambda_e: params.lambda_e,
            lambda_jnd: params.lambda_jnd_scaled,
            transmittance: params.transmittance,
            blur_half: half as u32,
            taps,
            k_v: SUBTRACTION_K_V,
            k_b: SUBTRACTION_K_B,
            mode: params.mode.shader_code(),
            tile_columns: region.0.div_ceil(super::engine::TILE),
            achromatic_boost: params.achromatic_boost,
            luminance_cap: params.luminance_cap,
            mapping: mapping.to_f32_rows(),
            pad: 0,
        }
    }

    pub fn bytes(&self) -> &[u8] {
        // SAFETY: PushConstants is repr(C), Copy, made only of 4-byte scalars (no padding).
        unsafe {
            std::slice::from_raw_parts(
                (self as *const Self).cast::<u8>(),
                std::mem::size_of::<Self>(),
            )
        }
    }
}

pub struct Pipelines {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub finish_tiles: vk::Pipeline,
    pub copy_pixels: vk::Pipeline,
    pub copy_rows: vk::Pipeline,
    pub decode_camera: vk::Pipeline,
    /// The `enhance` and `classify` variants (shaders::ENHANCE_VARIANTS, then
    /// shaders::CLASSIFY_VARIANTS, then shaders::DECODE_BLUR), built on first use: each costs
    /// a compile in the driver and a session uses a few.
    variants: Mutex<Vec<vk::Pipeline>>,
}

fn no_variants() -> Mutex<Vec<vk::Pipeline>> {
    let n = shaders::ENHANCE_VARIANTS.len()
        + shaders::CLASSIFY_VARIANTS.len()
        + shaders::DECODE_BLUR.len();
    Mutex::new(vec![vk::Pipeline::null(); n])
}

impl Pipelines {
    /// No objects yet (null handles, which vkDestroy* ignores).
    fn empty() -> Pipelines {
        Pipelines {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            finish_tiles: vk::Pipeline::null(),
            copy_pixels: vk::Pipeline::null(),
            copy_rows: vk::Pipeline::null(),
            decode_camera: vk::Pipeline::null(),
            variants: no_variants(),
        }
    }

    pub fn new(gpu: &GpuDevice) -> Result<Pipelines, GpuError> {
        let mut p = Pipelines::empty();
        // On failure, destroy what was made so far (null handles are ignored by vkDestroy*).
        if let Err(e) = p.build(gpu) {
            p.destroy(gpu);
            return Err(e);
        }
        Ok(p)
    }

    fn build(&mut self, gpu: &GpuDevice) -> Result<(), GpuError> {
        crate::fault::check("pipeline-creation").map_err(GpuError::Unsupported)?;
        let bindings: Vec<_> = (0..=IMAGE_BINDING)
            .map(|b| {
                let ty = if b == IMAGE_BINDING {
                    vk::DescriptorType::SAMPLED_IMAGE
                } else {
                    vk::DescriptorType::STORAGE_BUFFER
                };
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: valid create info on a valid device.
        self.set_layout = unsafe { gpu.device.create_descriptor_set_layout(&info, None) }
            .vk("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(std::mem::size_of::<PushConstants>() as u32)];
        let set_layouts = [self.set_layout];
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(&ranges);
        // SAFETY: valid create info on a valid device.
        self.layout = unsafe { gpu.device.create_pipeline_layout(&info, None) }
            .vk("vkCreatePipelineLayout")?;
        self.finish_tiles = self.compute_pipeline(gpu, &shaders::FINISH_TILES)?;
        self.decode_camera = self.compute_pipeline(gpu, &shaders::DECODE_CAMERA)?;
        self.copy_pixels = self.compute_pipeline(gpu, &shaders::COPY_PIXELS)?;
        self.copy_rows = self.compute_pipeline(gpu, &shaders::COPY_ROWS)?;
        Ok(())
    }

    /// The `enhance` pipeline for a method, view mode and pixel format (shader codes); `wide`
    /// for regions whose rows are 16-byte aligned (see `rows_aligned`); `extras` where the
    /// achromatic boost or the luminance cap is on.
    pub fn enhance(
        &self,
        gpu: &GpuDevice,
        (method, mode, format): (u32, u32, u32),
        wide: bool,
        extras: bool,
    ) -> Result<vk::Pipeline, GpuError> {
        let background = mode == ViewMode::Background.shader_code();
        let (method, extras) = if background {
            (0, false)
        } else {
            (method, extras)
        };
        let k = shaders::ENHANCE_VARIANTS
            .iter()
            .position(|&(m, v, f, w, e, _)| {
                (m, v, f, w, e) == (method, mode, format, wide, extras)
            });
        self.variant(gpu, k, |k| &shaders::ENHANCE_VARIANTS[k].5)
    }

    /// The `classify` pipeline for a pixel format (shader code) and row alignment.
    pub fn classify(
        &self,
        gpu: &GpuDevice,
        format: u32,
        wide: bool,
    ) -> Result<vk::Pipeline, GpuError> {
        let k = shaders::CLASSIFY_VARIANTS
            .iter()
            .position(|&(f, w, _)| f == format && w == wide);
        let offset = shaders::ENHANCE_VARIANTS.len();
        self.variant(gpu, k.map(|k| k + offset), |k| {
            &shaders::CLASSIFY_VARIANTS[k - offset].2
        })
    }

    /// The background pass for a blur half-width (0..=7).
    pub fn decode_blur(&self, gpu: &GpuDevice, half: u32) -> Result<vk::Pipeline, GpuError> {
        let offset = shaders::ENHANCE_VARIANTS.len() + shaders::CLASSIFY_VARIANTS.len();
        let k = (half as usize) < shaders::DECODE_BLUR.len();
        self.variant(gpu, k.then_some(offset + half as usize), |k| {
            &shaders::DECODE_BLUR[k - offset]
        })
    }

    fn variant(
        &self,
        gpu: &GpuDevice,
        k: Option<usize>,
        module: impl Fn(usize) -> &'static ShaderModule,
    ) -> Result<vk::Pipeline, GpuError> {
        let k = k.ok_or_else(|| {
            GpuError::Unsupported("no shader for this method, mode and format".into())
        })?;
        let mut built = self.variants.lock().map_err(|_| {
            GpuError::Unsupported("the pipeline cache was poisoned by an earlier panic".into())
        })?;
        if built[k] == vk::Pipeline::null() {
            built[k] = self.compute_pipeline(gpu, module(k))?;
        }
        Ok(built[k])
    }

    fn compute_pipeline(
        &self,
        gpu: &GpuDevice,
        shader: &ShaderModule,
    ) -> Result<vk::Pipeline, GpuError> {
        let words = shader.words();
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: words is SPIR-V produced and validated by naga at build time.
        let module =
            unsafe { gpu.device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
        let entry = std::ffi::CString::new(shader.entry).expect("entry names have no NUL");
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(&entry);
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(self.layout)];
        // SAFETY: module and layout are valid; the module is destroyed after creation.
        let result = unsafe {
            gpu.device
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
        };
        // SAFETY: a shader module may be destroyed once pipelines using it are created.
        unsafe { gpu.device.destroy_shader_module(module, None) };
        result
            .map(|p| p[0])
            .map_err(|(_, result)| GpuError::Vulkan {
                call: "vkCreateComputePipelines",
                result,
            })
    }

    pub fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: the caller guarantees the GPU no longer uses these objects.
        unsafe {
            let variants = match self.variants.get_mut() {
                Ok(v) => std::mem::take(v),
                Err(poisoned) => std::mem::take(poisoned.into_inner()),
            };
            for p in [
                self.finish_tiles,
                self.copy_pixels,
                self.copy_rows,
                self.decode_camera,
            ]
            .into_iter()
            .chain(variants)
            {
                gpu.device.destroy_pipeline(p, None);
            }
            gpu.device.destroy_pipeline_layout(self.layout, None);
            gpu.device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
        *self = Pipelines::empty();
    }
}
