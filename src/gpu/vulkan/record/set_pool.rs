//! The engine's descriptor pool, counting its sets: past `max_sets` a driver may refuse a set
//! (NVIDIA's does, ERROR_OUT_OF_POOL_MEMORY) or hand it out anyway (lavapipe's does). Counting
//! makes every driver refuse at the same point, so a caller that asks for too many fails here
//! as it would on a GPU.

use crate::gpu::vulkan::device::{GpuDevice, GpuError, VkResultExt};
use ash::vk;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

#[derive(Clone)]
pub(crate) struct SetPool {
    raw: vk::DescriptorPool,
    /// Sets allocated and not freed, shared by every handle of the pool.
    live: Arc<AtomicU32>,
    max_sets: u32,
}

impl SetPool {
    /// A FREE_DESCRIPTOR_SET pool of `max_sets` sets with `sizes`.
    pub(super) fn new(
        gpu: &GpuDevice,
        max_sets: u32,
        sizes: &[vk::DescriptorPoolSize],
    ) -> Result<SetPool, GpuError> {
        let info = vk::DescriptorPoolCreateInfo::default()
            .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET)
            .max_sets(max_sets)
            .pool_sizes(sizes);
        // SAFETY: valid create info on a valid device.
        let raw = unsafe { gpu.device.create_descriptor_pool(&info, None) }
            .vk("vkCreateDescriptorPool")?;
        Ok(SetPool {
            raw,
            live: Arc::default(),
            max_sets,
        })
    }

    /// A set of `layout`, or ERROR_OUT_OF_POOL_MEMORY once `max_sets` are out.
    pub(super) fn allocate(
        &self,
        gpu: &GpuDevice,
        layout: vk::DescriptorSetLayout,
    ) -> Result<vk::DescriptorSet, GpuError> {
        let taken = self
            .live
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < self.max_sets).then_some(n + 1)
            });
        if taken.is_err() {
            return Err(out_of_pool());
        }
        let layouts = [layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.raw)
            .set_layouts(&layouts);
        // SAFETY: pool and layout are valid, and the pool has a set left (counted above).
        match unsafe { gpu.device.allocate_descriptor_sets(&info) } {
            Ok(sets) => Ok(sets[0]),
            Err(result) => {
                self.live.fetch_sub(1, Ordering::AcqRel);
                Err(GpuError::Vulkan {
                    call: "vkAllocateDescriptorSets",
                    result,
                })
            }
        }
    }

    /// Frees `set` (null: nothing) and nulls it.
    pub(super) fn free(&self, gpu: &GpuDevice, set: &mut vk::DescriptorSet) {
        if *set == vk::DescriptorSet::null() {
            return;
        }
        // SAFETY: the set came from this pool and the GPU no longer uses it.
        let _ = unsafe { gpu.device.free_descriptor_sets(self.raw, &[*set]) };
        self.live.fetch_sub(1, Ordering::AcqRel);
        *set = vk::DescriptorSet::null();
    }

    /// Destroys the pool with every set still out.
    pub(super) fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: the caller guarantees the GPU no longer uses the pool's sets.
        unsafe { gpu.device.destroy_descriptor_pool(self.raw, None) };
        self.raw = vk::DescriptorPool::null();
        self.live.store(0, Ordering::Release);
    }
}

fn out_of_pool() -> GpuError {
    GpuError::Vulkan {
        call: "vkAllocateDescriptorSets",
        result: vk::Result::ERROR_OUT_OF_POOL_MEMORY,
    }
}
