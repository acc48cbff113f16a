//! The vkGetInstanceProcAddr the client gives the runtime in XR_KHR_vulkan_enable2's calls
//! (and so the API layers between): the loader's own, counting its calls, so a test can see
//! who uses the app's Vulkan (`vk_gipa_calls_in_create_session`).

use ash::vk;
use std::ffi::c_char;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

/// The loader's function of the instance being made: set at every `counting`, since each of
/// the client's XrInstances loads libvulkan anew (`--instances`), and the library of an earlier
/// one may have been unloaded since, and its address range reused by another library.
static LOADER_GIPA: Mutex<Option<vk::PFN_vkGetInstanceProcAddr>> = Mutex::new(None);
static CALLS: AtomicU32 = AtomicU32::new(0);

unsafe extern "system" fn counting_gipa(
    instance: vk::Instance,
    name: *const c_char,
) -> vk::PFN_vkVoidFunction {
    CALLS.fetch_add(1, Ordering::Relaxed);
    let gipa = LOADER_GIPA
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .expect("set before it is handed out");
    // SAFETY: the caller's arguments, to the loader's function of the same signature.
    unsafe { gipa(instance, name) }
}

/// The counting vkGetInstanceProcAddr in front of `entry`'s loader.
pub fn counting(entry: &ash::Entry) -> vk::PFN_vkGetInstanceProcAddr {
    *LOADER_GIPA.lock().unwrap_or_else(|p| p.into_inner()) =
        Some(entry.static_fn().get_instance_proc_addr);
    counting_gipa
}

/// Calls of the counting vkGetInstanceProcAddr so far.
pub fn calls() -> u32 {
    CALLS.load(Ordering::Relaxed)
}
