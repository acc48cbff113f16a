//! The seam between the layer and the app's graphics API. One folder per API owns what only
//! that API knows: its graphics binding (read at xrCreateSession), its swapchain images (what
//! xrEnumerateSwapchainImages gives), the pixel format of a swapchain's format, and how a
//! view's region of an image is enhanced. The rest of the layer (sessions, swapchains, the
//! frame's views and their camera mappings, the background, the indicator, captures) speaks
//! only [`SessionGraphics`]. The method's recipe (passes, parameters, shader interface) is
//! shared below this seam, in `gpu/`.
//!
//! A new API is a new folder here with a `bind` function, listed in [`BINDINGS`].

pub mod opengl;
pub mod vulkan;

use super::live_settings::Settings;
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::frame::{FrameBackground, OverlayPixels};
use crate::gpu::{PixelFormat, ViewKey};
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
    /// Display uv (v from the view's top edge) to camera uv.
    pub mapping: CameraMapping,
}

/// A view read back for a capture: its bytes before and after the enhancement, rows top first
/// as the view is seen, tightly packed.
pub struct CapturedImage {
    pub view: ViewImage,
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
    /// The image handles of an enumeration the runtime filled (None: not this API's structs).
    ///
    /// # Safety
    /// `images` points to `count` structs of the type its first one names.
    unsafe fn images(
        &self,
        images: *const xr::SwapchainImageBaseHeader,
        count: usize,
    ) -> Option<Vec<u64>>;
    /// Starts building what views of this shape will need, where the API builds ahead.
    fn request_shaders(&self, params: &Params, format: PixelFormat, width: u32, in_place: bool);
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
        background: FrameBackground,
        params: &Params,
        overlay: Option<&OverlayPixels>,
        capture: bool,
    ) -> Result<Vec<CapturedImage>, NotDone>;
    /// The log's line while frames pass through because shaders are still being built.
    fn pending_line(&self) -> &'static str;
    /// What the shaders took to build, for the log's line on when enhancement began.
    fn build_summary(&self) -> Option<String>;
    /// Lines the log says once (by key), checked at each enhanced frame: (key, line).
    fn frame_lines(&self, views: &[ViewImage], prepared: bool) -> Vec<(&'static str, String)>;
    /// The session passes through from now on: stop building, without waiting.
    fn stop_building(&self);
    /// Ends the engine on the app's thread (xrDestroySession): its last work, its objects.
    fn finish(self: Box<Self>) -> Result<(), String>;
}

/// What xrCreateSession's graphics binding gives the layer.
pub enum Bound {
    /// The session is enhanced with these graphics.
    Enhanced(Box<dyn SessionGraphics>),
    /// The session passes through, and why (one sentence).
    PassThrough(String),
}

/// The APIs of the sessions the layer enhances, as its `graphics API of this session:` line
/// names them (what `contrastxr doctor` reads).
pub const ENHANCED_APIS: [&str; 3] = ["Vulkan", "OpenGL (Xlib)", "OpenGL (EGL)"];

/// A binding reader: None when the structure is not its API's binding.
type Bind = unsafe fn(&xr::BaseInStructure, &Settings) -> Option<Bound>;

/// Every API the layer enhances, by its binding.
const BINDINGS: [Bind; 3] = [vulkan::bind, opengl::bind_xlib, opengl::bind_egl];

/// The graphics API a session's create-info chain binds, in words ("OpenGL (Xlib)"), for the
/// line that says why a session is passed through; None when no binding is known.
///
/// # Safety
/// `next` must be null or a valid OpenXR `next` chain (each element an XrBaseInStructure).
pub unsafe fn api_name(mut next: *const std::ffi::c_void) -> Option<&'static str> {
    use xr::StructureType as T;
    while !next.is_null() {
        // SAFETY: the caller guarantees every element starts with XrBaseInStructure.
        let base = unsafe { &*(next as *const xr::BaseInStructure) };
        let api = match base.ty {
            T::GRAPHICS_BINDING_VULKAN_KHR => Some("Vulkan"),
            T::GRAPHICS_BINDING_OPENGL_XLIB_KHR => Some("OpenGL (Xlib)"),
            T::GRAPHICS_BINDING_OPENGL_XCB_KHR => Some("OpenGL (XCB)"),
            T::GRAPHICS_BINDING_OPENGL_WAYLAND_KHR => Some("OpenGL (Wayland)"),
            T::GRAPHICS_BINDING_EGL_MNDX => Some("OpenGL (EGL)"),
            T::GRAPHICS_BINDING_OPENGL_ES_ANDROID_KHR => Some("OpenGL ES"),
            T::GRAPHICS_BINDING_D3D11_KHR | T::GRAPHICS_BINDING_D3D12_KHR => Some("Direct3D"),
            _ => None,
        };
        if api.is_some() {
            return api;
        }
        next = base.next as *const std::ffi::c_void;
    }
    None
}

/// The API-specific OpenXR functions the layer intercepts (the app's Vulkan instance creation).
pub fn intercepted(name: &str) -> Option<xr::pfn::VoidFunction> {
    vulkan::intercepted(name)
}

/// Forgets what the APIs kept for an instance the app destroys.
pub fn forget_instance(instance: xr::Instance) {
    vulkan::app_vulkan::forget(instance);
}

/// The session's graphics from its create info's `next` chain, with the binding's API name.
///
/// # Safety
/// `next` is the next chain of a session create info the runtime accepted.
pub unsafe fn bind(next: *const std::ffi::c_void, settings: &Settings) -> (&'static str, Bound) {
    // SAFETY: the caller's contract.
    let api = unsafe { api_name(next) }.unwrap_or("no known graphics binding");
    let mut at = next;
    while !at.is_null() {
        // SAFETY: every element of an accepted chain starts with XrBaseInStructure.
        let base = unsafe { &*(at as *const xr::BaseInStructure) };
        // SAFETY: each reader casts only a structure of its own type.
        if let Some(bound) = BINDINGS.iter().find_map(|b| unsafe { b(base, settings) }) {
            return (api, bound);
        }
        at = base.next as *const std::ffi::c_void;
    }
    let why = format!(
        "contrastxr enhances Vulkan and OpenGL sessions, not {api}: passing its frames through untouched"
    );
    (api, Bound::PassThrough(why))
}
