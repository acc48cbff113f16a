//! What the layer asks of a swapchain the app makes: whether its images may be enhanced, the
//! pixel format they are enhanced in, the usage the session's graphics need (and want for in
//! place), and the one log line naming the path its views take.

use super::log;
use super::state::SessionState;
use crate::gpu::PixelFormat;
use openxr_sys as xr;

fn is_colour(info: &xr::SwapchainCreateInfo) -> bool {
    let usage = info.usage_flags;
    usage.contains(xr::SwapchainUsageFlags::COLOR_ATTACHMENT)
        && !usage.contains(xr::SwapchainUsageFlags::DEPTH_STENCIL_ATTACHMENT)
}

/// Whether a swapchain of this create info may be enhanced at all: single-sampled colour
/// images (a multisampled image cannot be copied out: the runtime resolves it itself).
fn enhanceable(info: &xr::SwapchainCreateInfo) -> bool {
    if !is_colour(info) {
        return false;
    }
    if info.sample_count > 1 {
        log::once(
            &format!("msaa-{}", info.sample_count),
            &format!(
                "a multisampled swapchain ({} samples per pixel): its images pass through untouched",
                info.sample_count
            ),
        );
        return false;
    }
    true
}

/// What the session's graphics need of a swapchain: the pixel format its images are enhanced
/// in (None: they pass through), the usage the layer must have, and usage for in place.
pub(super) fn plan(s: &SessionState, info: &xr::SwapchainCreateInfo) -> Option<Plan> {
    let graphics = s.graphics.as_ref()?;
    let pixel = graphics
        .pixel_format(info.format)
        .filter(|_| enhanceable(info))?;
    Some(Plan {
        pixel,
        needed: graphics.needed_usage(),
        in_place: graphics.in_place_usage(pixel, info, &s.settings),
        copy_path: graphics.copy_path(pixel, &s.settings),
        format_name: graphics.format_name(info.format),
    })
}

pub(super) struct Plan {
    pub(super) pixel: PixelFormat,
    pub(super) needed: xr::SwapchainUsageFlags,
    pub(super) in_place: Option<xr::SwapchainUsageFlags>,
    /// The path's name for views not enhanced in place (`SessionGraphics::copy_path`).
    pub(super) copy_path: &'static str,
    pub(super) format_name: String,
}

/// The one line per enhanced swapchain: the path its views take and why.
pub(super) fn path_line(
    info: &xr::SwapchainCreateInfo,
    plan: &Plan,
    in_place: bool,
    refused: Option<xr::Result>,
) -> String {
    let path = match in_place {
        true => "in-place",
        false => plan.copy_path,
    };
    let why = match (in_place, refused, plan.in_place.is_some()) {
        (true, _, _) => "the runtime granted storage usage".to_string(),
        (false, Some(result), _) => format!("the runtime refused storage usage ({result:?})"),
        (false, None, false) => {
            "storage usage not asked for (in_place setting, device or format)".to_string()
        }
        (false, None, true) => "storage usage not granted".to_string(),
    };
    format!(
        "swapchain of format {} ({}x{}, {} layer(s)): views enhanced through path {path}; {why}",
        plan.format_name, info.width, info.height, info.array_size
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GL_SRGB8_ALPHA8: whether a swapchain is enhanceable does not depend on its format.
    const FORMAT: i64 = 0x8C43;

    fn info(format: i64, usage: xr::SwapchainUsageFlags, samples: u32) -> xr::SwapchainCreateInfo {
        xr::SwapchainCreateInfo {
            ty: xr::SwapchainCreateInfo::TYPE,
            next: std::ptr::null(),
            create_flags: xr::SwapchainCreateFlags::EMPTY,
            usage_flags: usage,
            format,
            sample_count: samples,
            width: 64,
            height: 48,
            face_count: 1,
            array_size: 2,
            mip_count: 1,
        }
    }

    #[test]
    fn only_single_sampled_colour_images_are_enhanced() {
        let colour = xr::SwapchainUsageFlags::COLOR_ATTACHMENT;
        let depth = xr::SwapchainUsageFlags::DEPTH_STENCIL_ATTACHMENT;
        let srgb = FORMAT;
        assert!(enhanceable(&info(srgb, colour, 1)));
        assert!(!enhanceable(&info(srgb, colour, 4)));
        assert!(!enhanceable(&info(srgb, depth, 1)));
        assert!(!enhanceable(&info(srgb, colour | depth, 1)));
    }
}
