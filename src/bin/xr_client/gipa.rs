//! The vkGetInstanceProcAddr the client gives the runtime in XR_KHR_vulkan_enable2's calls
//! (and so the API layers between): the loader's own, counting its calls, so a test can see
//! who uses the app's Vulkan (`vk_gipa_calls_in_create_session`).

use ash::vk;
use std::ffi::c_char;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::OnceLock;

static LOADER_GIPA: OnceLock<vk::PFN_vkGetInstanceProcAddr> = OnceLock::new();
static CALLS: AtomicU32 = AtomicU32::new(0);

unsafe extern "system" fn counting_gipa(
    instance: vk::Instance,
    name: *const c_char,
) -> vk::PFN_vkVoidFunction {
    CALLS.fetch_add(1, Ordering::Relaxed);
    let gipa = LOADER_GIPA.get().expect("set before it is handed out");
    // SAFETY: the caller's arguments, to the loader's function of the same signature.
    unsafe { gipa(instance, name) }
}

/// The counting vkGetInstanceProcAddr in front of `entry`'s loader.
pub fn counting(entry: &ash::Entry) -> vk::PFN_vkGetInstanceProcAddr {
    LOADER_GIPA.get_or_init(|| entry.static_fn().get_instance_proc_addr);
    counting_gipa
}

/// Calls of the counting vkGetInstanceProcAddr so far.
pub fn calls() -> u32 {
    CALLS.load(Ordering::Relaxed)
}
