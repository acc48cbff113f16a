//! `contrastxr bench --shader-stats`: the driver compiler's statistics of the shaders a frame
//! on the bench's format runs, by pixel access, for the method the bench times.

use super::offline_engine::VkOffline;
use crate::algorithm::params::Params;
use crate::gpu::core::interface::{ACCESS_IN_PLACE, ACCESS_SAMPLED, ACCESS_WIDE};
use crate::gpu::core::modules::MODULES;
use crate::gpu::core::shader_ids::{self, ShaderId};
use crate::gpu::core::{ClassifyChoice, CubeRoots, PixelFormat, VariantKey};
use crate::gpu::vulkan::device::{DeviceOptions, GpuDevice, GpuError};
use crate::gpu::vulkan::pipelines::{create_layouts, shader_statistics, ExecutableStatistics};

/// One shader (its SPIR-V file's name) and what the driver's compiler says of it.
#[derive(Clone, Debug)]
pub struct ShaderStatistics {
    pub shader: &'static str,
    pub executables: Vec<ExecutableStatistics>,
}

impl VkOffline {
    /// The statistics of the per-pixel shaders of RGBA8 sRGB views (the bench's format) under
    /// `params`: `finish_tiles`, and for the buffer path's 16-byte access, in place and the
    /// sampled read, `classify` and `enhance` (the general and the shared-fetch variant, with
    /// the cube roots by pow too where built). An error where the device was not made with `DeviceOptions::shader_statistics` or its
    /// driver does not report them.
    pub fn bench_shader_statistics(
        &self,
        params: &Params,
    ) -> Result<Vec<ShaderStatistics>, GpuError> {
        statistics_of(&self.gpu, self.engine.pipelines().layout(), params)
    }
}

/// The same statistics on a device made only to compile: no memory, queue work or engine, so
/// that a compiler without a GPU (RADV's, with RADV_FORCE_FAMILY naming the GPU it compiles
/// for) reports them too. The device's name and the statistics.
pub fn compiled_shader_statistics(
    options: &DeviceOptions,
    params: &Params,
) -> Result<(String, Vec<ShaderStatistics>), GpuError> {
    let options = DeviceOptions {
        shader_statistics: true,
        ..options.clone()
    };
    let gpu = GpuDevice::create(&options)?;
    let (set_layout, layout) = create_layouts(&gpu)?;
    let all = statistics_of(&gpu, layout, params);
    // SAFETY: the layouts are ours; every pipeline made with them is destroyed.
    unsafe {
        gpu.device.destroy_pipeline_layout(layout, None);
        gpu.device.destroy_descriptor_set_layout(set_layout, None);
    }
    Ok((gpu.name.clone(), all?))
}

fn statistics_of(
    gpu: &GpuDevice,
    layout: ash::vk::PipelineLayout,
    params: &Params,
) -> Result<Vec<ShaderStatistics>, GpuError> {
    bench_shaders(params)
        .into_iter()
        .map(|ShaderId(k)| {
            let module = &MODULES[k];
            Ok(ShaderStatistics {
                shader: module.name,
                executables: shader_statistics(gpu, layout, module)?,
            })
        })
        .collect()
}

/// The shaders of a frame of RGBA8 sRGB views under `params`, each once, in pass order.
fn bench_shaders(params: &Params) -> Vec<ShaderId> {
    let mut ids = Vec::new();
    for access in [ACCESS_WIDE, ACCESS_IN_PLACE, ACCESS_SAMPLED] {
        let key = VariantKey::of(params, PixelFormat::SRGB8, access);
        // The method's own classify, and by tile rows (`--ablate classify-rows`) where it has one.
        let [classify, by_rows] = [ClassifyChoice::Own, ClassifyChoice::OwnByRows]
            .map(|c| shader_ids::classify(key.format, access, key.classify_taken(c)).ok());
        ids.extend([classify, by_rows, Some(shader_ids::FINISH_TILES)]);
        // The general and the shared-fetch variant, with each way of taking the cube roots
        // where it is built.
        for roots in [CubeRoots::Newton, CubeRoots::Pow] {
            let key = key.with_roots(roots);
            ids.extend([
                shader_ids::enhance(key).ok(),
                shader_ids::enhance_shared(key),
            ]);
        }
    }
    let mut unique: Vec<ShaderId> = Vec::new();
    for id in ids.into_iter().flatten() {
        if !unique.contains(&id) {
            unique.push(id);
        }
    }
    unique
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bench_shaders_are_the_frames_per_pixel_passes() {
        let names: Vec<&str> = bench_shaders(&Params::default())
            .into_iter()
            .map(|ShaderId(k)| MODULES[k].name)
            .collect();
        // Three accesses, each a classify and two enhance variants (the general and the
        // shared-fetch one), in place and the sampled read also with the cube roots by pow;
        // and one finish_tiles.
        assert_eq!(names.len(), 14, "{names:?}");
        assert_eq!(
            names
                .iter()
                .filter(|n| n.starts_with("finish_tiles"))
                .count(),
            1
        );
        assert_eq!(
            names.iter().filter(|n| n.starts_with("classify")).count(),
            3
        );
        assert_eq!(
            names.iter().filter(|n| n.starts_with("enhance")).count(),
            10
        );
        assert_eq!(names.iter().filter(|n| n.ends_with("_p")).count(), 4);
    }
}
