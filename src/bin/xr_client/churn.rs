//! `--churn-swapchains`: a second thread creates and destroys swapchains for as long as the
//! session runs, so a layer's xrDestroySwapchain races its xrEndFrame (both are legal at once:
//! xrDestroySwapchain synchronises only on its own swapchain). With `--churn-formats` it cycles
//! through every format the runtime offers, colour and depth, small and large: the runtime then
//! calls Vulkan on the app's device from this thread while a layer sets up. An OpenGL session
//! churns on its frame thread instead, between frames (gl_run.rs): XR_KHR_opengl_enable lets
//! swapchain calls use the app's context, which must not be current on two threads at once.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::time::{Duration, Instant};

use ash::vk;
use openxr as xr;

/// Swapchains alive at once: each lives while the next few are made, so a layer's xrEndFrame
/// finds some of them tracked when one is destroyed.
const ALIVE: usize = 4;

/// The least time between two of the churn thread's swapchains. Monado destroys a swapchain on
/// its compositor thread, once a frame: unpaced, thousands a second pile up between two of its
/// frames, each image's memory an open file on lavapipe, until the service reaches the usual
/// limit of 1024 open files and the next create fails (VK_ERROR_OUT_OF_DEVICE_MEMORY). Paced,
/// a destroy still lands every few milliseconds, inside every xrEndFrame.
const STEP_MIN: Duration = Duration::from_millis(2);

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

/// What the churn makes, in turn: the session's format (`format`, the API's raw value) at 32x32,
/// or with `all` every offered format at each of SIZES, depth formats (`is_depth`) as depth
/// attachments.
pub fn plan(format: u32, offered: &[u32], all: bool, is_depth: fn(u32) -> bool) -> Vec<Churn> {
    if !all {
        let usage = xr::SwapchainUsageFlags::COLOR_ATTACHMENT;
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

/// Whether a VkFormat is a depth (or depth-stencil) format.
pub fn is_vk_depth(format: u32) -> bool {
    let f = vk::Format::from_raw(format as i32);
    (vk::Format::D16_UNORM.as_raw()..=vk::Format::D32_SFLOAT_S8_UINT.as_raw()).contains(&f.as_raw())
}

/// The swapchains the churn keeps alive, oldest first.
pub struct Churner<G: xr::Graphics> {
    alive: std::collections::VecDeque<xr::Swapchain<G>>,
}

impl<G: xr::Graphics> Default for Churner<G> {
    fn default() -> Self {
        Churner {
            alive: Default::default(),
        }
    }
}

/// Both APIs' swapchain formats are plain numbers (a VkFormat, a GL internal format).
impl<G: xr::Graphics> Churner<G>
where
    G::Format: From<u32>,
{
    /// Creates and enumerates swapchain `c`, and destroys the oldest one once more than ALIVE
    /// are alive (counted in `churned`). Returns the error, if any.
    pub fn step(
        &mut self,
        session: &xr::Session<G>,
        c: &Churn,
        churned: &AtomicU32,
    ) -> Result<(), String> {
        let swapchain = session
            .create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::EMPTY,
                usage_flags: c.usage,
                format: c.format.into(),
                sample_count: 1,
                width: c.size.0,
                height: c.size.1,
                face_count: 1,
                array_size: 1,
                mip_count: 1,
            })
            .map_err(|e| {
                format!(
                    "xrCreateSwapchain (churn, format {} {}x{}) failed: {e}",
                    c.format, c.size.0, c.size.1
                )
            })?;
        if let Err(e) = swapchain.enumerate_images() {
            return Err(format!("xrEnumerateSwapchainImages (churn) failed: {e}"));
        }
        self.alive.push_back(swapchain);
        if self.alive.len() > ALIVE {
            // Dropping it calls xrDestroySwapchain.
            self.alive.pop_front();
            churned.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    }
}

/// Creates, enumerates and destroys the plan's swapchains in turn, at most one per STEP_MIN,
/// until `stop`; counts them in `churned`. Returns the first error, if any.
pub fn churn<G: xr::Graphics>(
    session: &xr::Session<G>,
    plan: &[Churn],
    stop: &AtomicBool,
    churned: &AtomicU32,
) -> Option<String>
where
    G::Format: From<u32>,
{
    let mut churner = Churner::default();
    for c in plan.iter().cycle() {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        let started = Instant::now();
        if let Err(e) = churner.step(session, c, churned) {
            return Some(e);
        }
        std::thread::sleep(STEP_MIN.saturating_sub(started.elapsed()));
    }
    None
}
