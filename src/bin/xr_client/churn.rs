//! `--churn-swapchains`: a second thread creates and destroys swapchains for as long as the
//! session runs, so a layer's xrDestroySwapchain races its xrEndFrame (both are legal at once:
//! xrDestroySwapchain synchronises only on its own swapchain). With `--churn-formats` it cycles
//! through every format the runtime offers, colour and depth, small and large: the runtime then
//! calls Vulkan on the app's device from this thread while a layer sets up.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use ash::vk;
use openxr as xr;

use crate::swapchain_format::SwapchainFormat;

/// Swapchains alive at once: each lives while the next few are made, so a layer's xrEndFrame
/// finds some of them tracked when one is destroyed.
const ALIVE: usize = 4;

/// Sizes the format churn cycles through: the smallest, and a full-HD eye (what the
/// conformance suite creates).
const SIZES: [(u32, u32); 2] = [(32, 32), (1920, 1080)];

/// One swapchain the churn thread makes.
#[derive(Clone, Copy, Debug)]
pub struct Churn {
    format: u32,
    usage: xr::SwapchainUsageFlags,
    size: (u32, u32),
}

/// What the churn thread makes, in turn: the session's format at 32x32, or with `all` every
/// offered format at each of SIZES.
pub fn plan(format: SwapchainFormat, offered: &[u32], all: bool) -> Vec<Churn> {
    if !all {
        let usage = xr::SwapchainUsageFlags::COLOR_ATTACHMENT;
        let format = format.vk.as_raw() as u32;
        return vec![Churn {
            format,
            usage,
            size: SIZES[0],
        }];
    }
    let mut plan = Vec::new();
    for &size in &SIZES {
        for &format in offered {
            let usage = match is_depth(format) {
                true => xr::SwapchainUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                false => xr::SwapchainUsageFlags::COLOR_ATTACHMENT,
            };
            plan.push(Churn {
                format,
                usage,
                size,
            });
        }
    }
    plan
}

fn is_depth(format: u32) -> bool {
    let f = vk::Format::from_raw(format as i32);
    (vk::Format::D16_UNORM.as_raw()..=vk::Format::D32_SFLOAT_S8_UINT.as_raw()).contains(&f.as_raw())
}

/// Creates, enumerates and destroys the plan's swapchains in turn until `stop`; counts them in
/// `churned`. Returns the first error, if any.
pub fn churn(
    session: &xr::Session<xr::Vulkan>,
    plan: &[Churn],
    stop: &AtomicBool,
    churned: &AtomicU32,
) -> Option<String> {
    let mut alive = std::collections::VecDeque::new();
    for c in plan.iter().cycle() {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        let created = session.create_swapchain(&xr::SwapchainCreateInfo {
            create_flags: xr::SwapchainCreateFlags::EMPTY,
            usage_flags: c.usage,
            format: c.format as _,
            sample_count: 1,
            width: c.size.0,
            height: c.size.1,
            face_count: 1,
            array_size: 1,
            mip_count: 1,
        });
        let swapchain = match created {
            Ok(s) => s,
            Err(e) => {
                return Some(format!(
                    "xrCreateSwapchain (churn, VkFormat {} {}x{}) failed: {e}",
                    c.format, c.size.0, c.size.1
                ))
            }
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
