//! What the layer asks of a session's graphics, whichever API they are ([`SessionGraphics`]),
//! and what it hands them: a frame's views, and what comes back.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::core::{BackgroundInput, OverlayPixels};
use crate::gpu::{PixelFormat, ViewKey};
use crate::layer::live_settings::Settings;
use openxr_sys as xr;

/// One view region of one of the app's swapchain images, as the layer hands it to the API's
/// engine.
#[derive(Clone, Debug)]
pub struct ViewImage {
    pub key: ViewKey,
    /// The API's handle of the image (a VkImage, a GL texture name), as enumerated.
    pub image: u64,
    /// The swapchain's format as the app named it (a VkFormat, a GL internal format).
    pub api_format: i64,
    pub format: PixelFormat,
    /// The swapchain has more than one array layer (a GL array texture).
    pub layered: bool,
    /// Enhanced in place in the app's image, else through a copy of the region.
    pub in_place: bool,
    /// The image has colour-attachment usage (the image-copy path may draw into it).
    pub attachment: bool,
    /// The image has sampled usage (the image-copy path may read it through a sampled view).
    pub sampled: bool,
    /// Display uv (v from the view's top edge) to camera uv.
    pub mapping: CameraMapping,
    /// The view's display pixels per degree, from its field of view and width
    /// (`perception::frequency::view_pixels_per_degree`); the default for a quad, and for a
    /// whole image before the first xrEndFrame.
    pub pixels_per_degree: f64,
}

/// A view read back for a capture: its bytes before and after the enhancement, rows top first
/// as the view is seen, tightly packed.
pub struct CapturedImage {
    pub view: ViewImage,
    /// How the view was enhanced (a capture's `"path"`): `in-place` in the app's image,
    /// `image-copy` (through an image of the layer's own), `copy` (through a buffer).
    pub path: &'static str,
    pub display: Vec<u8>,
    pub output: Vec<u8>,
}

/// Why a frame was not enhanced.
#[derive(Debug)]
pub enum NotDone {
    /// Shaders the views need are still being built: the frame passes through.
    Pending,
    /// The session passes through from now on, for this reason (one sentence).
    Failed(String),
    /// This frame passes through untouched, for this reason (one sentence); the next is tried.
    Skipped(String),
    /// What the frame needs cannot be reached now, for this reason (one sentence), and may be
    /// later (the app's OpenGL context current on another thread): the frame passes through,
    /// the engine stays, and later frames try again ever less often (layer/frame_retry.rs).
    Unreachable(String),
}

/// A session's graphics, as the layer uses them.
pub trait SessionGraphics: Send {
    /// The binding's name for the log ("Vulkan", "OpenGL (Xlib)").
    fn api(&self) -> &'static str;
    /// The API in captures' JSON ("vulkan", "opengl").
    fn graphics(&self) -> &'static str;
    /// The pixel format the engine reads a swapchain of `api_format` as (None: not handled).
    fn pixel_format(&self, api_format: i64) -> Option<PixelFormat>;
    /// The format's name in captures (`R8G8B8A8_SRGB`, `GL_SRGB8_ALPHA8`).
    fn format_name(&self, api_format: i64) -> String;
    /// The usage a swapchain must have for the layer to touch its images.
    fn needed_usage(&self) -> xr::SwapchainUsageFlags;
    /// Usage to add so views of a swapchain are enhanced in place (None: through a copy).
    fn in_place_usage(
        &self,
        format: PixelFormat,
        info: &xr::SwapchainCreateInfo,
        settings: &Settings,
    ) -> Option<xr::SwapchainUsageFlags>;
    /// Usage to add, where in place is refused, so views of a swapchain are read through a
    /// sampled view (Vulkan, `copy_in = "sampled"`; None: not wanted).
    fn sampled_usage(
        &self,
        _format: PixelFormat,
        _settings: &Settings,
    ) -> Option<xr::SwapchainUsageFlags> {
        None
    }
    /// How views of a swapchain of `format` that is not enhanced in place are enhanced, by
    /// the name of its path (`copy`: through a buffer; `image-copy`: through an image of the
    /// layer's own), with `settings` as at the swapchain's creation.
    fn copy_path(&self, _format: PixelFormat, _settings: &Settings) -> &'static str {
        "copy"
    }
    /// Whether the engine chooses the path of a swapchain's views at each frame (OpenGL: in
    /// place through an image unit where the texture and the driver allow it), not the usage.
    fn path_chosen_per_frame(&self) -> bool {
        false
    }
    /// The image handles of an enumeration the runtime filled (None: not this API's structs).
    ///
    /// # Safety
    /// `images` points to `count` structs of the type its first one names.
    unsafe fn images(
        &self,
        images: *const xr::SwapchainImageBaseHeader,
        count: usize,
    ) -> Option<Vec<u64>>;
    /// Starts building what views of this shape will need, where the API builds ahead (called
    /// when the app makes a swapchain the layer will enhance); `wait`: the first frame will
    /// wait for the build (`pipelines = "wait"`), so it runs at the app's priority.
    fn request_shaders(
        &mut self,
        params: &Params,
        format: PixelFormat,
        width: u32,
        in_place: bool,
        wait: bool,
    );
    /// Drops what the engine keeps for a swapchain the app destroys.
    fn forget_swapchain(&mut self, swapchain: u64) -> Result<(), String>;
    /// Connects a live source's prepared texels straight to the engine, where it can take them.
    fn take_live_texels(&self, background: &crate::camera::Background);
    /// Whether everything `views` need is built (waited for with `wait`).
    fn ready(&mut self, views: &[ViewImage], params: &Params, wait: bool) -> Result<(), NotDone>;
    /// Enhances `views` in the app's images (after `ready`), draws `overlay` over them, and with
    /// `capture` reads each back before and after.
    fn enhance(
        &mut self,
        views: &[ViewImage],
        background: BackgroundInput,
        params: &Params,
        overlay: Option<&OverlayPixels>,
        capture: bool,
    ) -> Result<Vec<CapturedImage>, NotDone>;
    /// The GPU time of each enhanced frame's work measured since the last call (timestamps
    /// on the app's queue or context, read without waiting, so normally a frame or more
    /// behind), oldest first; empty where the device or context writes none.
    fn take_gpu_times(&mut self) -> Vec<std::time::Duration>;
    /// The log's line while frames pass through because shaders are still being built.
    fn pending_line(&self) -> &'static str;
    /// What the shaders took to build, for the log's line on when enhancement began.
    fn build_summary(&self) -> Option<String>;
    /// Lines the log says once (by key), checked at each enhanced frame: (key, line).
    fn frame_lines(&self, views: &[ViewImage], prepared: bool) -> Vec<(&'static str, String)>;
    /// The session passes through from now on: stop building, without waiting.
    fn stop_building(&self);
    /// Ends the engine on the app's thread (xrDestroySession): its last work, its objects; Err is
    /// the one line the log says when they could not all be ended now.
    fn finish(self: Box<Self>) -> Result<(), String>;
}

/// What xrCreateSession's graphics binding gives the layer.
pub enum Bound {
    /// The session is enhanced with these graphics.
    Enhanced(Box<dyn SessionGraphics>),
    /// The session passes through, and why (one sentence).
    PassThrough(String),
}

/// The handles of an enumeration the runtime filled with `count` structs of type `T`, the
/// graphics API's image struct, which `ty` names (None: the first struct names another type).
///
/// # Safety
/// `images` points to `count` structs of the type its first one names.
pub unsafe fn image_handles<T>(
    images: *const xr::SwapchainImageBaseHeader,
    count: usize,
    ty: xr::StructureType,
    handle: impl Fn(&T) -> u64,
) -> Option<Vec<u64>> {
    // SAFETY: images holds at least one struct (the caller's contract).
    if unsafe { (*images).ty } != ty {
        return None;
    }
    let typed = images as *const T;
    // SAFETY: the first struct names T, so all `count` are T (the caller's contract).
    Some(
        (0..count)
            .map(|i| handle(unsafe { &*typed.add(i) }))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_handles_reads_every_struct_of_its_type_only() {
        let structs: Vec<xr::SwapchainImageVulkanKHR> = (1..=3)
            .map(|k| xr::SwapchainImageVulkanKHR {
                ty: xr::StructureType::SWAPCHAIN_IMAGE_VULKAN_KHR,
                next: std::ptr::null_mut(),
                image: 100 + k,
            })
            .collect();
        let base = structs.as_ptr() as *const xr::SwapchainImageBaseHeader;
        let vulkan = xr::StructureType::SWAPCHAIN_IMAGE_VULKAN_KHR;
        let opengl = xr::StructureType::SWAPCHAIN_IMAGE_OPENGL_KHR;
        // SAFETY: base points to three Vulkan image structs.
        let read =
            unsafe { image_handles(base, 3, vulkan, |i: &xr::SwapchainImageVulkanKHR| i.image) };
        assert_eq!(read, Some(vec![101, 102, 103]));
        // SAFETY: as above; the type does not match, so nothing is read as OpenGL's.
        let other = unsafe {
            image_handles(base, 3, opengl, |i: &xr::SwapchainImageOpenGLKHR| {
                u64::from(i.image)
            })
        };
        assert_eq!(other, None);
    }
}
