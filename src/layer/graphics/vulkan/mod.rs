//! Vulkan sessions (XR_KHR_vulkan_enable2, and the first version's binding): the frame engine
//! on the app's own device and queue, its swapchain images as VkImages.

pub mod app_vulkan;
mod in_place;
mod vulkan_session;

pub use vulkan_session::bind;

/// The layer's xrCreateVulkanInstanceKHR for the loader, by name.
pub fn intercepted(name: &str) -> Option<openxr_sys::pfn::VoidFunction> {
    (name == "xrCreateVulkanInstanceKHR").then(|| {
        // SAFETY: the loader calls it through the signature the OpenXR specification gives the
        // name, which is the one it is declared with.
        unsafe {
            std::mem::transmute::<
                openxr_sys::pfn::CreateVulkanInstanceKHR,
                openxr_sys::pfn::VoidFunction,
            >(app_vulkan::create_vulkan_instance)
        }
    })
}
