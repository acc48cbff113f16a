//! The logical device an engine creates for itself: one queue of the first compute family,
//! and, where asked and the driver has it, VK_KHR_pipeline_executable_properties (the
//! compiler's statistics of each pipeline, for `contrastxr bench --shader-stats`).

use super::error::{GpuError, VkResultExt};
use ash::vk;

fn compute_family(instance: &ash::Instance, physical: vk::PhysicalDevice) -> Option<u32> {
    // SAFETY: physical is a handle enumerated from this instance.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
    families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
        .map(|i| i as u32)
}

/// Whether `physical` offers the pipeline executables' statistics.
fn has_executable_statistics(instance: &ash::Instance, physical: vk::PhysicalDevice) -> bool {
    let name = ash::khr::pipeline_executable_properties::NAME;
    // SAFETY: physical is a handle enumerated from this instance.
    let extensions = unsafe { instance.enumerate_device_extension_properties(physical) };
    let listed = extensions
        .unwrap_or_default()
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(name));
    if !listed {
        return false;
    }
    let mut feature = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut feature);
    // SAFETY: physical belongs to the live instance (Vulkan 1.1, checked by the caller).
    unsafe { instance.get_physical_device_features2(physical, &mut features) };
    feature.pipeline_executable_info == vk::TRUE
}

/// A device with one queue of the first compute family of `physical` (a device of
/// `instance`), with the pipeline executables' statistics where `statistics` asks for them and
/// the driver has them; the bool says whether it does.
pub(super) fn create_compute_device(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    statistics: bool,
) -> Result<(ash::Device, u32, bool), GpuError> {
    let family = compute_family(instance, physical)
        .ok_or_else(|| GpuError::NoDevice("the device has no compute queue".into()))?;
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&priorities)];
    let statistics = statistics && has_executable_statistics(instance, physical);
    let extensions = [ash::khr::pipeline_executable_properties::NAME.as_ptr()];
    let mut feature = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
        .pipeline_executable_info(true);
    let mut info = vk::DeviceCreateInfo::default().queue_create_infos(&queues);
    if statistics {
        info = info
            .enabled_extension_names(&extensions)
            .push_next(&mut feature);
    }
    // SAFETY: physical belongs to the live instance; info and its arrays live until the call
    // returns.
    let device = unsafe { instance.create_device(physical, &info, None) }.vk("vkCreateDevice")?;
    Ok((device, family, statistics))
}
