//! Vulkan sessions (XR_KHR_vulkan_enable2, and the first version's binding): the frame engine
//! on the app's own device and queue, its swapchain images as VkImages.

pub mod app_vulkan;
mod in_place;
mod vulkan_session;

pub use app_vulkan::intercepted;
pub use vulkan_session::bind;
