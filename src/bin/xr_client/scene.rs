//! What the frame loop and the scripted calls draw with: the session, its space, the GPU and
//! the swapchains.

use openxr as xr;

use crate::gpu::Gpu;
use crate::pattern_swapchain::PatternSwapchain;

/// What the frame loop draws with.
pub struct Scene<'a> {
    pub session: &'a xr::Session<xr::Vulkan>,
    pub space: &'a xr::Space,
    pub gpu: &'a Gpu,
    pub projection: PatternSwapchain,
    pub quad: Option<PatternSwapchain>,
    pub view_size: (u32, u32),
    pub blend_mode: xr::EnvironmentBlendMode,
    pub format: crate::swapchain_format::SwapchainFormat,
    /// With --pipelined: the projection image already acquired and waited for the next frame.
    pub ahead: Option<u32>,
}
