//! What the layer asks of a swapchain the app makes: whether its images may be enhanced, the
//! pixel format they are enhanced in, the usage the session's graphics need (and want for in
//! place), and the one log line naming the path its views take.

use super::log;
use super::state::SessionState;
use crate::config::InPlace;
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
        sampled: graphics.sampled_usage(pixel, &s.settings),
        copy_path: graphics.copy_path(pixel, &s.settings),
        per_frame: graphics
            .path_chosen_per_frame()
            .then_some(s.settings.in_place),
        format_name: graphics.format_name(info.format),
    })
}

pub(super) struct Plan {
    pub(super) pixel: PixelFormat,
    pub(super) needed: xr::SwapchainUsageFlags,
    pub(super) in_place: Option<xr::SwapchainUsageFlags>,
    /// Usage to add where in place is refused, for the sampled read.
    pub(super) sampled: Option<xr::SwapchainUsageFlags>,
    /// The path's name for views not enhanced in place (`SessionGraphics::copy_path`).
    pub(super) copy_path: &'static str,
    /// The `in_place` setting where the path is chosen at each frame (OpenGL).
    pub(super) per_frame: Option<InPlace>,
    pub(super) format_name: String,
}

/// The one line per enhanced swapchain: the path its views take and why.
pub(super) fn path_line(
    info: &xr::SwapchainCreateInfo,
    plan: &Plan,
    in_place: bool,
    refused: Option<xr::Result>,
) -> String {
    let swapchain = format!(
        "swapchain of format {} ({}x{}, {} layer(s))",
        plan.format_name, info.width, info.height, info.array_size
    );
    if let Some(setting) = plan.per_frame {
        return format!(
            "{swapchain}: views enhanced in place through an image unit where the texture and the driver allow it, else through a buffer copy, chosen at each frame (in_place = {}; under auto a CPU driver takes the buffer copy; the first enhanced frame's line says which)",
            setting.name()
        );
    }
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
    format!("{swapchain}: views enhanced through path {path}; {why}")
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

    fn srgb_plan(per_frame: Option<InPlace>) -> Plan {
        Plan {
            pixel: PixelFormat {
                layout: crate::gpu::PixelLayout::Rgba8,
                srgb: true,
            },
            needed: xr::SwapchainUsageFlags::TRANSFER_SRC,
            in_place: Some(xr::SwapchainUsageFlags::UNORDERED_ACCESS),
            sampled: None,
            copy_path: "image-copy",
            format_name: "R8G8B8A8_SRGB".into(),
            per_frame,
        }
    }

    /// The line names the path a swapchain's views take: the runtime's answer where usage
    /// decides it (Vulkan), the per-frame choice where nothing at creation does (OpenGL).
    #[test]
    fn the_swapchain_line_names_the_path_taken() {
        let colour = info(FORMAT, xr::SwapchainUsageFlags::COLOR_ATTACHMENT, 1);
        let refused = Some(xr::Result::ERROR_FEATURE_UNSUPPORTED);
        assert_eq!(
            path_line(&colour, &srgb_plan(None), false, refused),
            "swapchain of format R8G8B8A8_SRGB (64x48, 2 layer(s)): views enhanced through path image-copy; the runtime refused storage usage (ERROR_FEATURE_UNSUPPORTED)"
        );
        let granted = path_line(&colour, &srgb_plan(None), true, None);
        assert!(
            granted.ends_with("path in-place; the runtime granted storage usage"),
            "{granted}"
        );
        let gl = path_line(&colour, &srgb_plan(Some(InPlace::Auto)), false, None);
        let per_frame = "swapchain of format R8G8B8A8_SRGB (64x48, 2 layer(s)): views enhanced in place through an image unit where";
        assert!(gl.starts_with(per_frame), "{gl}");
        assert!(
            gl.contains("chosen at each frame (in_place = auto;"),
            "{gl}"
        );
        assert!(!gl.contains("through path"), "{gl}");
    }
}
