//! `contrastxr bench --shader-stats`: the driver compiler's statistics of the shaders a frame
//! on the bench's format runs, by pixel access, for the method the bench times.

use super::offline_engine::VkOffline;
use crate::algorithm::params::Params;
use crate::gpu::core::interface::{ACCESS_IN_PLACE, ACCESS_SAMPLED, ACCESS_WIDE};
use crate::gpu::core::modules::MODULES;
use crate::gpu::core::shader_ids::{self, ShaderId};
use crate::gpu::core::{ClassifyChoice, PixelFormat, VariantKey};
use crate::gpu::vulkan::device::GpuError;
use crate::gpu::vulkan::pipelines::{shader_statistics, ExecutableStatistics};

/// One shader (its SPIR-V file's name) and what the driver's compiler says of it.
#[derive(Clone, Debug)]
pub struct ShaderStatistics {
    pub shader: &'static str,
    pub executables: Vec<ExecutableStatistics>,
}

impl VkOffline {
    /// The statistics of the per-pixel shaders of RGBA8 sRGB views (the bench's format) under
    /// `params`: `finish_tiles`, and for the buffer path's 16-byte access, in place and the
    /// sampled read, `classify` and `enhance` (the general and the shared-fetch variant).
    /// An error where the device was not made with `DeviceOptions::shader_statistics` or its
    /// driver does not report them.
    pub fn bench_shader_statistics(
        &self,
        params: &Params,
    ) -> Result<Vec<ShaderStatistics>, GpuError> {
        let layout = self.engine.pipelines().layout();
        bench_shaders(params)
            .into_iter()
            .map(|ShaderId(k)| {
                let module = &MODULES[k];
                Ok(ShaderStatistics {
                    shader: module.name,
                    executables: shader_statistics(&self.gpu, layout, module)?,
                })
            })
            .collect()
    }
}

/// The shaders of a frame of RGBA8 sRGB views under `params`, each once, in pass order.
fn bench_shaders(params: &Params) -> Vec<ShaderId> {
    let mut ids = Vec::new();
    for access in [ACCESS_WIDE, ACCESS_IN_PLACE, ACCESS_SAMPLED] {
        let key = VariantKey::of(params, PixelFormat::SRGB8, access);
        // The method's own classify, and by tile rows (`--ablate classify-rows`) where it has one.
        let [classify, by_rows] = [ClassifyChoice::Own, ClassifyChoice::OwnByRows]
            .map(|c| shader_ids::classify(key.format, access, key.classify_taken(c)).ok());
        let general = shader_ids::enhance(key.codes(), access, key.extras).ok();
        let shared = shader_ids::enhance_shared(key.codes(), access, key.extras);
        ids.extend([
            classify,
            by_rows,
            Some(shader_ids::FINISH_TILES),
            general,
            shared,
        ]);
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
        // Three accesses, each a classify and two enhance variants, and one finish_tiles.
        assert_eq!(names.len(), 10, "{names:?}");
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
        assert_eq!(names.iter().filter(|n| n.starts_with("enhance")).count(), 6);
    }
}
