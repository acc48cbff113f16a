//! The machine's Vulkan devices, as `contrastxr doctor` lists them.

use super::error::{GpuError, VkResultExt};
use super::gpu_device::{create_instance, load_entry};
use ash::vk;

/// One physical device as the loader lists it (what `contrastxr doctor` reports).
#[derive(Clone, Debug)]
pub struct PhysicalDeviceInfo {
    pub name: String,
    /// "discrete GPU", "integrated GPU", "virtual GPU", "CPU, software" or "other".
    pub kind: &'static str,
    /// The Vulkan version it supports, (major, minor).
    pub version: (u32, u32),
    /// A CPU driver (lavapipe, SwiftShader): too slow for a headset.
    pub cpu: bool,
}

fn device_type(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU, software",
        _ => "other",
    }
}

/// The physical devices, found the way `GpuDevice::create` finds them: the loader
/// (libvulkan.so.1), a Vulkan 1.1 instance without validation, vkEnumeratePhysicalDevices, in
/// the order that `DeviceOptions::index` counts.
pub fn physical_devices() -> Result<Vec<PhysicalDeviceInfo>, GpuError> {
    let entry = load_entry()?;
    let instance = create_instance(&entry, false)?;
    // SAFETY: a valid instance.
    let listed = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices");
    let devices = listed.map(|physicals| {
        physicals
            .iter()
            .map(|&p| {
                // SAFETY: p was enumerated from this instance.
                let props = unsafe { instance.get_physical_device_properties(p) };
                let v = props.api_version;
                PhysicalDeviceInfo {
                    name: props
                        .device_name_as_c_str()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_else(|_| "unknown device".into()),
                    kind: device_type(props.device_type),
                    version: (vk::api_version_major(v), vk::api_version_minor(v)),
                    cpu: props.device_type == vk::PhysicalDeviceType::CPU,
                }
            })
            .collect()
    });
    // SAFETY: the instance has no children.
    unsafe { instance.destroy_instance(None) };
    devices
}
