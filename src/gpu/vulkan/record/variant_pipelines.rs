//! Which pipeline a view's per-pixel passes take: its `classify` and its `enhance` variant,
//! the shared-fetch one where its mapping allows it, or the benchmark's ablated one.

use super::recorder::Recorder;
use super::resources::ViewTarget;
use crate::algorithm::mapping::CameraMapping;
use crate::gpu::core::shader_ids;
use crate::gpu::core::{no_ablated_variant, shares_fetches, VariantKey};
use crate::gpu::vulkan::device::GpuError;
use ash::vk;

impl Recorder {
    /// The `enhance` pipeline for a view: the shared-fetch variant where the view's mapping
    /// allows it and it is built, else the general one (the same output).
    pub(super) fn enhance_pipeline(
        &self,
        view: &ViewTarget,
        key: VariantKey,
        mapping: &CameraMapping,
    ) -> Result<vk::Pipeline, GpuError> {
        let key = key.with_roots(self.roots);
        let shares = shares_fetches(mapping, view.region, view.camera_size);
        if self.ablate != 0 {
            return self.ablated_pipeline(key, shares);
        }
        let shared = shader_ids::enhance_shared(key).filter(|_| self.shared_fetch && shares);
        match shared.map(|id| self.pipelines.get(id)) {
            Some(Ok(p)) => Ok(p),
            _ => self.pipelines.get(shader_ids::enhance(key)?),
        }
    }

    /// The benchmark's ablated `enhance` for the view's variant, where one is built: with
    /// shared fetches where the view's mapping allows them (`shares`) and they are built (the
    /// paper's), as without an ablation, else with the general sampling; with the cube roots
    /// the device takes.
    fn ablated_pipeline(&self, key: VariantKey, shares: bool) -> Result<vk::Pipeline, GpuError> {
        let shared = shares && self.shared_fetch;
        let pow = key.roots.by_pow();
        let ablated = |shared| {
            shader_ids::enhance_ablated(key.method, key.access, self.ablate, (shared, pow))
        };
        let id = ablated(shared)
            .or_else(|| ablated(false))
            .filter(|_| key.has_ablated_variants())
            .ok_or_else(|| GpuError::Unsupported(no_ablated_variant(self.ablate)))?;
        self.pipelines.get(id)
    }
}
