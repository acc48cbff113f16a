//! Swapchains: track creation info and images, and hold the app's release of a colour image
//! until xrEndFrame, so the layer writes the image while it is still the app's to give.
//! (On Monado a released image is handed to an external queue at once: writing it after the
//! release would be outside the spec.)

use super::ffi::guard;
use super::log;
use super::state::{self, lock, SwapchainInfo, SwapchainState};
use crate::gpu::PixelFormat;
use ash::vk::{self, Handle};
use openxr_sys as xr;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

fn transfer() -> xr::SwapchainUsageFlags {
    xr::SwapchainUsageFlags::TRANSFER_SRC | xr::SwapchainUsageFlags::TRANSFER_DST
}

fn is_colour(info: &xr::SwapchainCreateInfo) -> bool {
    let usage = info.usage_flags;
    usage.contains(xr::SwapchainUsageFlags::COLOR_ATTACHMENT)
        && !usage.contains(xr::SwapchainUsageFlags::DEPTH_STENCIL_ATTACHMENT)
}

pub(crate) unsafe extern "system" fn create_swapchain(
    session: xr::Session,
    info: *const xr::SwapchainCreateInfo,
    swapchain: *mut xr::Swapchain,
) -> xr::Result {
    guard(
        "xrCreateSwapchain",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let Some(s) = state::session(session) else {
                return xr::Result::ERROR_HANDLE_INVALID;
            };
            let (next, active) = {
                let s = lock(&s);
                (s.next, s.processor.is_some())
            };
            // SAFETY: the app's create info (null is left for the runtime to reject).
            let Some(app_info) = (unsafe { info.as_ref() }) else {
                // SAFETY: forwarding the app's arguments.
                return unsafe { (next.create_swapchain)(session, info, swapchain) };
            };
            let vk_format = vk::Format::from_raw(app_info.format as i32);
            // Pass-through sessions never have images held or touched.
            let pixel = PixelFormat::from_vk(vk_format).filter(|_| active && is_colour(app_info));
            let mut transfer_usage = app_info.usage_flags.contains(transfer());
            let mut result = xr::Result::ERROR_RUNTIME_FAILURE;
            if active && pixel.is_some() && !transfer_usage {
                let mut wanted = *app_info;
                wanted.usage_flags |= transfer();
                // SAFETY: the app's create info with two more usage bits.
                result = unsafe { (next.create_swapchain)(session, &wanted, swapchain) };
                transfer_usage = result.into_raw() >= 0;
                if !transfer_usage {
                    log::once(&format!("no-transfer-{vk_format:?}"), &format!(
                    "the runtime refused transfer usage on {vk_format:?} swapchains ({result:?}): those pass through"
                ));
                }
            }
            if result.into_raw() < 0 {
                // SAFETY: forwarding the app's arguments unchanged.
                result = unsafe { (next.create_swapchain)(session, info, swapchain) };
            }
            // Every swapchain is tracked (with its session's dispatch); only processable ones are touched.
            if result.into_raw() >= 0 {
                let state = SwapchainState {
                    session,
                    next,
                    info: SwapchainInfo {
                        vk_format,
                        pixel,
                        width: app_info.width,
                        height: app_info.height,
                        array_size: app_info.array_size,
                        transfer_usage,
                    },
                    images: Vec::new(),
                    acquired: VecDeque::new(),
                    held_release: None,
                };
                // SAFETY: written by the successful create call.
                let handle = unsafe { *swapchain };
                state::registry()
                    .swapchains
                    .insert(handle.into_raw(), Arc::new(Mutex::new(state)));
            }
            result
        },
    )
}

pub(crate) unsafe extern "system" fn destroy_swapchain(swapchain: xr::Swapchain) -> xr::Result {
    guard(
        "xrDestroySwapchain",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let removed = state::registry().swapchains.remove(&swapchain.into_raw());
            let next = match &removed {
                Some(sc) => {
                    let sc = lock(sc);
                    if let Some(s) = state::session(sc.session) {
                        if let Some(p) = lock(&s).processor.as_mut() {
                            p.forget_swapchain(swapchain.into_raw());
                        }
                    }
                    sc.next
                }
                None => return xr::Result::ERROR_HANDLE_INVALID,
            };
            // SAFETY: forwarding the app's call.
            unsafe { (next.destroy_swapchain)(swapchain) }
        },
    )
}

pub(crate) unsafe extern "system" fn enumerate_swapchain_images(
    swapchain: xr::Swapchain,
    capacity: u32,
    count: *mut u32,
    images: *mut xr::SwapchainImageBaseHeader,
) -> xr::Result {
    guard(
        "xrEnumerateSwapchainImages",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let tracked = state::swapchain(swapchain);
            let next = match &tracked {
                Some(sc) => lock(sc).next,
                None => return xr::Result::ERROR_HANDLE_INVALID,
            };
            // SAFETY: forwarding the app's arguments.
            let result =
                unsafe { (next.enumerate_swapchain_images)(swapchain, capacity, count, images) };
            if let (Some(sc), true) = (
                tracked,
                result == xr::Result::SUCCESS && capacity > 0 && !images.is_null(),
            ) {
                // SAFETY: on success the runtime filled *count structs of the type the app chose.
                let n = unsafe { *count } as usize;
                if unsafe { (*images).ty } == xr::StructureType::SWAPCHAIN_IMAGE_VULKAN_KHR {
                    let vk_images = images as *const xr::SwapchainImageVulkanKHR;
                    // SAFETY: n Vulkan image structs were written.
                    lock(&sc).images = (0..n)
                        .map(|i| unsafe { vk::Image::from_raw((*vk_images.add(i)).image) })
                        .collect();
                }
            }
            result
        },
    )
}

/// Forwards a held release to the runtime (the image becomes the runtime's).
fn forward_release(sc: &mut SwapchainState, swapchain: xr::Swapchain) -> xr::Result {
    if sc.held_release.take().is_none() {
        return xr::Result::SUCCESS;
    }
    let info = xr::SwapchainImageReleaseInfo {
        ty: xr::SwapchainImageReleaseInfo::TYPE,
        next: std::ptr::null(),
    };
    // SAFETY: releasing an image the app released earlier, with a valid release info.
    let result = unsafe { (sc.next.release_swapchain_image)(swapchain, &info) };
    if result.into_raw() < 0 {
        log::once(
            "release-failed",
            &format!("forwarding a held image release failed: {result:?}"),
        );
    }
    result
}

/// Forwards every held release of a session's swapchains (at xrEndFrame, before the runtime's).
pub fn release_held(session: xr::Session) {
    let held: Vec<(u64, Arc<Mutex<SwapchainState>>)> = state::registry()
        .swapchains
        .iter()
        .map(|(k, v)| (*k, v.clone()))
        .collect();
    for (handle, sc) in held {
        let mut sc = lock(&sc);
        if sc.session == session {
            forward_release(&mut sc, xr::Swapchain::from_raw(handle));
        }
    }
}

pub(crate) unsafe extern "system" fn acquire_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageAcquireInfo,
    index: *mut u32,
) -> xr::Result {
    guard(
        "xrAcquireSwapchainImage",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let Some(sc) = state::swapchain(swapchain) else {
                return xr::Result::ERROR_HANDLE_INVALID;
            };
            let mut sc = lock(&sc);
            if sc.held_release.is_some() {
                // The app wants another image before xrEndFrame: the held one goes as it is.
                log::once(
                    "reacquire",
                    "an app acquired again before xrEndFrame: that image passed through unenhanced",
                );
                forward_release(&mut sc, swapchain);
            }
            // SAFETY: forwarding the app's arguments.
            let result = unsafe { (sc.next.acquire_swapchain_image)(swapchain, info, index) };
            if result.into_raw() >= 0 {
                // SAFETY: written by the successful call.
                let i = unsafe { *index };
                sc.acquired.push_back(i);
            }
            result
        },
    )
}

pub(crate) unsafe extern "system" fn release_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageReleaseInfo,
) -> xr::Result {
    guard(
        "xrReleaseSwapchainImage",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let Some(sc) = state::swapchain(swapchain) else {
                return xr::Result::ERROR_HANDLE_INVALID;
            };
            let mut sc = lock(&sc);
            let holdable =
                sc.info.processable() && !sc.images.is_empty() && sc.held_release.is_none();
            if holdable {
                if let Some(i) = sc.acquired.pop_front() {
                    sc.held_release = Some(i);
                    return xr::Result::SUCCESS;
                }
            }
            // SAFETY: forwarding the app's arguments.
            let result = unsafe { (sc.next.release_swapchain_image)(swapchain, info) };
            if result.into_raw() >= 0 {
                sc.acquired.pop_front();
            }
            result
        },
    )
}
