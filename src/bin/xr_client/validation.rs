//! Counts what VK_LAYER_KHRONOS_validation reports through a debug messenger.

use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU32, Ordering};

use ash::vk;

/// Counts since start-up; the callback has no context pointer to a struct that could move.
static ERRORS: AtomicU32 = AtomicU32::new(0);
static WARNINGS: AtomicU32 = AtomicU32::new(0);

pub fn errors() -> u32 {
    ERRORS.load(Ordering::Relaxed)
}

pub fn warnings() -> u32 {
    WARNINGS.load(Ordering::Relaxed)
}

/// The messenger to chain into VkInstanceCreateInfo (so instance creation is covered) and to
/// create afterwards for the instance's lifetime.
pub fn messenger_info() -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE
                | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
        )
        .pfn_user_callback(Some(on_message))
}

/// # Safety
/// Called by the Vulkan loader with a valid callback data pointer.
unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    let (counter, label) = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        (&ERRORS, "error")
    } else {
        (&WARNINGS, "warning")
    };
    counter.fetch_add(1, Ordering::Relaxed);
    // SAFETY: the layer passes valid callback data for the duration of the call; p_message is a
    // NUL-terminated string or null.
    let message = unsafe {
        data.as_ref()
            .filter(|d| !d.p_message.is_null())
            .map(|d| CStr::from_ptr(d.p_message).to_string_lossy().into_owned())
    };
    eprintln!("vulkan validation {label}: {}", message.unwrap_or_default());
    vk::FALSE
}
