//! Whether a swapchain's views are enhanced in place: the layer asks the runtime for storage
//! usage (and, for sRGB formats, mutable format, to reach them through a UNORM view) on the
//! app's colour swapchains, invisibly to the app. A runtime that refuses gets the app's own
//! create info again and the views go through a copy. `in_place = "auto"` leaves CPU drivers
//! on the copy path: there a copy is a memcpy and storage-image access costs more.

use crate::config::InPlace;
use crate::gpu::frame::can_store;
use crate::gpu::{GpuDevice, PixelFormat};
use crate::layer::ffi::find_in_chain;
use crate::layer::live_settings::Settings;
use openxr_sys as xr;

/// The usage bits to add for in place on a swapchain of `format`, if the session's settings,
/// its device and the app's create info allow it.
pub fn added_usage(
    gpu: &GpuDevice,
    settings: &Settings,
    format: PixelFormat,
    info: &xr::SwapchainCreateInfo,
) -> Option<xr::SwapchainUsageFlags> {
    let wanted = match settings.in_place {
        InPlace::On => true,
        InPlace::Off => false,
        InPlace::Auto => !gpu.is_cpu(),
    };
    if !wanted || !can_store(gpu, format) {
        return None;
    }
    if !format.srgb {
        return Some(xr::SwapchainUsageFlags::UNORDERED_ACCESS);
    }
    // SAFETY: the app's create info chain (the runtime rejects a malformed one; here only
    // its structure types are read).
    let listed = unsafe {
        find_in_chain::<xr::BaseInStructure>(
            info.next,
            xr::StructureType::VULKAN_SWAPCHAIN_FORMAT_LIST_CREATE_INFO_KHR,
        )
    };
    // The app's own format list would not name the UNORM view.
    listed.is_none().then_some(
        xr::SwapchainUsageFlags::UNORDERED_ACCESS | xr::SwapchainUsageFlags::MUTABLE_FORMAT,
    )
}
