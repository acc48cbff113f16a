//! The next layer's (or the runtime's) functions for one instance, resolved once through its
//! xrGetInstanceProcAddr.

use openxr_sys as xr;
use openxr_sys::pfn;
use std::ffi::CStr;

#[derive(Clone, Copy)]
pub struct NextFns {
    pub get_instance_proc_addr: pfn::GetInstanceProcAddr,
    pub destroy_instance: pfn::DestroyInstance,
    pub create_session: pfn::CreateSession,
    pub destroy_session: pfn::DestroySession,
    pub create_swapchain: pfn::CreateSwapchain,
    pub destroy_swapchain: pfn::DestroySwapchain,
    pub enumerate_swapchain_images: pfn::EnumerateSwapchainImages,
    pub acquire_swapchain_image: pfn::AcquireSwapchainImage,
    pub wait_swapchain_image: pfn::WaitSwapchainImage,
    pub release_swapchain_image: pfn::ReleaseSwapchainImage,
    pub end_frame: pfn::EndFrame,
    pub get_system_properties: pfn::GetSystemProperties,
    pub create_reference_space: pfn::CreateReferenceSpace,
    pub destroy_space: pfn::DestroySpace,
    pub locate_space: pfn::LocateSpace,
    pub enumerate_environment_blend_modes: pfn::EnumerateEnvironmentBlendModes,
}

/// Looks up `name` in the next layer.
///
/// # Safety
/// `gipa` must be the next layer's xrGetInstanceProcAddr and `instance` a handle it created.
pub unsafe fn lookup(
    gipa: pfn::GetInstanceProcAddr,
    instance: xr::Instance,
    name: &CStr,
) -> Option<pfn::VoidFunction> {
    let mut f = None;
    // SAFETY: guaranteed by the caller; name is NUL-terminated.
    let r = unsafe { gipa(instance, name.as_ptr(), &mut f) };
    if r == xr::Result::SUCCESS {
        f
    } else {
        None
    }
}

macro_rules! resolve {
    ($gipa:expr, $inst:expr, $name:literal, $ty:ty) => {{
        // SAFETY: guaranteed by the caller of `NextFns::load`.
        let f = unsafe { lookup($gipa, $inst, $name) }
            .ok_or(concat!("the next layer has no ", stringify!($name)))?;
        // SAFETY: the loader returns the function registered under this name, whose
        // signature is $ty by the OpenXR specification.
        unsafe { std::mem::transmute::<pfn::VoidFunction, $ty>(f) }
    }};
}

impl NextFns {
    /// # Safety
    /// `gipa` must be the next layer's xrGetInstanceProcAddr and `instance` a handle it created.
    pub unsafe fn load(
        gipa: pfn::GetInstanceProcAddr,
        instance: xr::Instance,
    ) -> Result<NextFns, &'static str> {
        Ok(NextFns {
            get_instance_proc_addr: gipa,
            destroy_instance: resolve!(gipa, instance, c"xrDestroyInstance", pfn::DestroyInstance),
            create_session: resolve!(gipa, instance, c"xrCreateSession", pfn::CreateSession),
            destroy_session: resolve!(gipa, instance, c"xrDestroySession", pfn::DestroySession),
            create_swapchain: resolve!(gipa, instance, c"xrCreateSwapchain", pfn::CreateSwapchain),
            destroy_swapchain: resolve!(
                gipa,
                instance,
                c"xrDestroySwapchain",
                pfn::DestroySwapchain
            ),
            enumerate_swapchain_images: resolve!(
                gipa,
                instance,
                c"xrEnumerateSwapchainImages",
                pfn::EnumerateSwapchainImages
            ),
            acquire_swapchain_image: resolve!(
                gipa,
                instance,
                c"xrAcquireSwapchainImage",
                pfn::AcquireSwapchainImage
            ),
            wait_swapchain_image: resolve!(
                gipa,
                instance,
                c"xrWaitSwapchainImage",
                pfn::WaitSwapchainImage
            ),
            release_swapchain_image: resolve!(
                gipa,
                instance,
                c"xrReleaseSwapchainImage",
                pfn::ReleaseSwapchainImage
            ),
            end_frame: resolve!(gipa, instance, c"xrEndFrame", pfn::EndFrame),
            get_system_properties: resolve!(
                gipa,
                instance,
                c"xrGetSystemProperties",
                pfn::GetSystemProperties
            ),
            create_reference_space: resolve!(
                gipa,
                instance,
                c"xrCreateReferenceSpace",
                pfn::CreateReferenceSpace
            ),
            destroy_space: resolve!(gipa, instance, c"xrDestroySpace", pfn::DestroySpace),
            locate_space: resolve!(gipa, instance, c"xrLocateSpace", pfn::LocateSpace),
            enumerate_environment_blend_modes: resolve!(
                gipa,
                instance,
                c"xrEnumerateEnvironmentBlendModes",
                pfn::EnumerateEnvironmentBlendModes
            ),
        })
    }
}
