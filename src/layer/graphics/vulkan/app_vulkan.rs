//! The app's own Vulkan. With XR_KHR_vulkan_enable2 the app hands the runtime (through the
//! layer) its `vkGetInstanceProcAddr` in xrCreateVulkanInstanceKHR: the layer keeps it by the
//! VkInstance made, and its session's device functions come from there. Otherwise they come
//! from the Vulkan loader already loaded in the process; the layer never loads another.

use crate::layer::ffi::{guard, LayerError};
use ash::vk::{self, Handle};
use openxr_sys as xr;
use std::collections::HashMap;
use std::sync::{Mutex, MutexGuard, OnceLock};

/// The app's vkGetInstanceProcAddr by the VkInstance it was given for, with the XrInstance
/// it came through.
type Given = HashMap<u64, (u64, vk::PFN_vkGetInstanceProcAddr)>;

/// The next layer's xrGetInstanceProcAddr by the XrInstance it serves: what the layer's
/// xrCreateVulkanInstanceKHR forwards through.
type Next = HashMap<u64, xr::pfn::GetInstanceProcAddr>;

fn next_fns() -> MutexGuard<'static, Next> {
    static NEXT: OnceLock<Mutex<Next>> = OnceLock::new();
    // Only map operations happen under this lock.
    NEXT.get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|p| p.into_inner())
}

/// Keeps the next layer's xrGetInstanceProcAddr for an XrInstance the layer serves.
pub fn instance_created(instance: xr::Instance, next: xr::pfn::GetInstanceProcAddr) {
    next_fns().insert(instance.into_raw(), next);
}

fn given() -> MutexGuard<'static, Given> {
    static GIVEN: OnceLock<Mutex<Given>> = OnceLock::new();
    // Only map operations happen under this lock.
    GIVEN
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|p| p.into_inner())
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrCreateVulkanInstanceKHR.
pub unsafe extern "system" fn create_vulkan_instance(
    instance: xr::Instance,
    info: *const xr::VulkanInstanceCreateInfoKHR,
    vk_instance: *mut xr::platform::VkInstance,
    vk_result: *mut xr::platform::VkResult,
) -> xr::Result {
    guard(
        "xrCreateVulkanInstanceKHR",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let lookup = next_fns().get(&instance.into_raw()).copied();
            let lookup = lookup.ok_or(LayerError::UnknownHandle("XrInstance"))?;
            let mut next = None;
            let name = c"xrCreateVulkanInstanceKHR";
            // SAFETY: the next layer's lookup, with a NUL-terminated name and a valid out pointer.
            let found = unsafe { lookup(instance, name.as_ptr(), &mut next) };
            let Some(next) = next.filter(|_| found == xr::Result::SUCCESS) else {
                return Ok(found);
            };
            // SAFETY: the next layer's xrCreateVulkanInstanceKHR has this signature.
            let next: xr::pfn::CreateVulkanInstanceKHR = unsafe { std::mem::transmute(next) };
            // SAFETY: forwarding the app's arguments.
            let result = unsafe { next(instance, info, vk_instance, vk_result) };
            // SAFETY: on success the runtime wrote the instance; info is the app's valid struct.
            let made = unsafe { (vk_instance.as_ref(), info.as_ref()) };
            if let (true, Some(&raw), Some(info)) = (result == xr::Result::SUCCESS, made.0, made.1)
            {
                if let Some(gipa) = info.pfn_get_instance_proc_addr {
                    // SAFETY: the app's vkGetInstanceProcAddr, passed as the spec's void function.
                    let gipa: vk::PFN_vkGetInstanceProcAddr = unsafe { std::mem::transmute(gipa) };
                    given().insert(raw as u64, (instance.into_raw(), gipa));
                }
            }
            Ok(result)
        },
    )
}

/// The Vulkan entry points for the app's instance `raw`: the app's own vkGetInstanceProcAddr
/// when it gave one, else the process's Vulkan loader (an error when none is loaded).
pub fn entry_for(raw: vk::Instance) -> Result<ash::Entry, String> {
    let given = given().get(&raw.as_raw()).map(|(_, gipa)| *gipa);
    let gipa = given.or_else(loaded_loader);
    let gipa = gipa.ok_or("no Vulkan loader is loaded in the app's process")?;
    let static_fn = ash::StaticFn {
        get_instance_proc_addr: gipa,
    };
    // SAFETY: gipa is a vkGetInstanceProcAddr of the loader the app's instance was made with.
    Ok(unsafe { ash::Entry::from_static_fn(static_fn) })
}

/// vkGetInstanceProcAddr of the libvulkan.so.1 already loaded in the process (RTLD_NOLOAD:
/// never loaded here).
fn loaded_loader() -> Option<vk::PFN_vkGetInstanceProcAddr> {
    let flags = libc::RTLD_NOW | libc::RTLD_NOLOAD;
    // SAFETY: RTLD_NOLOAD only looks the library up; the reference it takes is kept.
    let handle = unsafe { libc::dlopen(c"libvulkan.so.1".as_ptr(), flags) };
    if handle.is_null() {
        return None;
    }
    // SAFETY: a valid handle and a NUL-terminated name.
    let sym = unsafe { libc::dlsym(handle, c"vkGetInstanceProcAddr".as_ptr()) };
    // SAFETY: the loader's vkGetInstanceProcAddr has this signature.
    (!sym.is_null()).then(|| unsafe {
        std::mem::transmute::<*mut libc::c_void, vk::PFN_vkGetInstanceProcAddr>(sym)
    })
}

/// Forgets what the app gave through the XrInstance it destroys.
pub fn forget(instance: xr::Instance) {
    next_fns().remove(&instance.into_raw());
    given().retain(|_, (of, _)| *of != instance.into_raw());
}

/// The layer's xrCreateVulkanInstanceKHR for the loader, by name.
pub fn intercepted(name: &str) -> Option<xr::pfn::VoidFunction> {
    (name == "xrCreateVulkanInstanceKHR").then(|| {
        // SAFETY: the loader calls it through the signature the OpenXR specification gives the
        // name, which is the one it is declared with.
        unsafe {
            std::mem::transmute::<xr::pfn::CreateVulkanInstanceKHR, xr::pfn::VoidFunction>(
                create_vulkan_instance,
            )
        }
    })
}
