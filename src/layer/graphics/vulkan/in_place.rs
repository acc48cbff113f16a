//! Whether a swapchain's views are enhanced in place: the layer asks the runtime for storage
//! usage (and, for sRGB formats, mutable format, to reach them through a UNORM view) on the
//! app's colour swapchains, invisibly to the app. A runtime that refuses gets the app's own
//! create info again and the views go through a copy: of the region into an image of the
//! layer's own that the same shaders enhance (the image-copy path), or into a buffer where the
//! device cannot store to that image's format. `in_place = "auto"` leaves CPU drivers on the
//! buffer path: there a copy is a memcpy and storage-image access costs more.

use crate::config::{CopyBack, CopyIn, InPlace};
use crate::gpu::core::interface::sampled_read;
use crate::gpu::vulkan::frame::can_store;
use crate::gpu::{GpuDevice, PixelFormat, ViewPath};
use crate::layer::ffi::find_in_chain;
use crate::layer::live_settings::Settings;
use openxr_sys as xr;

/// Whether the settings want views enhanced with the in-place shaders on this device: in the
/// app's image where the runtime grants storage usage, else in an image of the layer's own
/// (the image-copy path). `in_place = "auto"` leaves CPU drivers on the buffer path, and
/// `off` every device.
pub fn wanted(gpu: &GpuDevice, settings: &Settings) -> bool {
    match settings.in_place {
        InPlace::On => true,
        InPlace::Off => false,
        InPlace::Auto => !gpu.is_cpu(),
    }
}

/// The path of the views of a swapchain of `format` that are not enhanced in place: through
/// an image of the layer's own where the settings want the in-place shaders and the device
/// can store to the format's image-copy format, else through a buffer.
pub fn copy_path(gpu: &GpuDevice, settings: &Settings, format: PixelFormat) -> ViewPath {
    match wanted(gpu, settings) {
        true => {
            let path = crate::gpu::vulkan::frame::copy_path(gpu, format);
            image_copy_way(path, format, ways(gpu, settings), (true, true))
        }
        false => ViewPath::BufferCopy,
    }
}

/// The ways the settings ask of the image-copy path on this device: the listed tiles drawn
/// back (`copy_back = "tiles"`), the region read through a sampled view (`copy_in =
/// "sampled"`, or `auto` on a GPU).
pub fn ways(gpu: &GpuDevice, settings: &Settings) -> (bool, bool) {
    (
        settings.copy_back == CopyBack::Tiles,
        sampled_wanted(settings.copy_in, gpu.is_cpu()),
    )
}

/// Whether `copy_in` asks for the sampled read on a device that is (`cpu`) a CPU driver or not:
/// on a GPU it reads the app's image once, through the texture unit, where the region copy
/// moves it twice through the copy path; on a CPU driver a sampled texel costs more than the
/// memcpy it saves (docs/performance.md).
pub fn sampled_wanted(copy_in: CopyIn, cpu: bool) -> bool {
    match copy_in {
        CopyIn::Auto => !cpu,
        CopyIn::Region => false,
        CopyIn::Sampled => true,
    }
}

/// `path` (a view's copy path) with the way `ways` asks of the image-copy path, where the
/// swapchain allows it (`usage`: colour-attachment usage, sampled usage): the sampled read
/// (8-bit sRGB formats), else the tiles drawn back, else the region copied back.
pub fn image_copy_way(
    path: ViewPath,
    format: PixelFormat,
    (tiles, sampled): (bool, bool),
    (attachment, sampled_usage): (bool, bool),
) -> ViewPath {
    let sampled = sampled && sampled_usage && sampled_read(format.shader_code());
    match path {
        ViewPath::ImageCopy if attachment && sampled => ViewPath::SampledTiles,
        ViewPath::ImageCopy if attachment && tiles => ViewPath::ImageCopyTiles,
        path => path,
    }
}

/// The usage bits to add for in place on a swapchain of `format`, if the session's settings,
/// its device and the app's create info allow it.
pub fn added_usage(
    gpu: &GpuDevice,
    settings: &Settings,
    format: PixelFormat,
    info: &xr::SwapchainCreateInfo,
) -> Option<xr::SwapchainUsageFlags> {
    if !wanted(gpu, settings) || !can_store(gpu, format) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `auto` takes the sampled read on a GPU only; the two named ways hold on any device.
    #[test]
    fn copy_in_auto_samples_on_a_gpu_and_copies_on_a_cpu_driver() {
        assert!(sampled_wanted(CopyIn::Auto, false));
        assert!(!sampled_wanted(CopyIn::Auto, true));
        for cpu in [false, true] {
            assert!(sampled_wanted(CopyIn::Sampled, cpu));
            assert!(!sampled_wanted(CopyIn::Region, cpu));
        }
    }
}
