//! `--churn-swapchains`: a second thread creates and destroys colour swapchains for as long as
//! the frame loop runs, so a layer's xrDestroySwapchain races its xrEndFrame (both are legal at
//! once: xrDestroySwapchain synchronises only on its own swapchain).

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use openxr as xr;

use crate::format::SwapchainFormat;

/// Swapchains alive at once: each lives while the next few are made, so a layer's xrEndFrame
/// finds some of them tracked when one is destroyed.
const ALIVE: usize = 4;

/// Creates, enumerates and destroys swapchains until `stop`; counts them in `churned`.
/// Returns the first error, if any.
pub fn churn(
    session: &xr::Session<xr::Vulkan>,
    format: SwapchainFormat,
    stop: &AtomicBool,
    churned: &AtomicU32,
) -> Option<String> {
    let mut alive = std::collections::VecDeque::new();
    while !stop.load(Ordering::Relaxed) {
        let created = session.create_swapchain(&xr::SwapchainCreateInfo {
            create_flags: xr::SwapchainCreateFlags::EMPTY,
            usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT,
            format: format.vk.as_raw() as _,
            sample_count: 1,
            width: 32,
            height: 32,
            face_count: 1,
            array_size: 1,
            mip_count: 1,
        });
        let swapchain = match created {
            Ok(s) => s,
            Err(e) => return Some(format!("xrCreateSwapchain (churn) failed: {e}")),
        };
        if let Err(e) = swapchain.enumerate_images() {
            return Some(format!("xrEnumerateSwapchainImages (churn) failed: {e}"));
        }
        alive.push_back(swapchain);
        if alive.len() > ALIVE {
            // Dropping it calls xrDestroySwapchain.
            alive.pop_front();
            churned.fetch_add(1, Ordering::Relaxed);
        }
    }
    None
}
