//! The one place the CLI chooses between the GPU engine (Vulkan, or OpenGL on an offline EGL
//! context) and the CPU reference.

use contrastxr::algorithm::perception::frequency::{view_params, ViewGeometry};
use contrastxr::algorithm::Params;
use contrastxr::gpu::opengl::GlOffline;
use contrastxr::gpu::{OfflineBackend, VkOffline};
use contrastxr::image::RgbaImage;
use contrastxr::reference;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The Vulkan backend (`--engine gpu`), on the first Vulkan device or `CONTRASTXR_VK_DEVICE`.
    Vulkan,
    /// The CPU reference.
    Cpu,
    /// The OpenGL backend, as the layer runs it for OpenGL apps.
    OpenGl,
}

impl Backend {
    pub fn parse(name: &str) -> Option<Backend> {
        match name {
            "gpu" => Some(Backend::Vulkan),
            "cpu" => Some(Backend::Cpu),
            "opengl" => Some(Backend::OpenGl),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Backend::Vulkan => "gpu",
            Backend::Cpu => "cpu",
            Backend::OpenGl => "opengl",
        }
    }
}

/// Enhances `display` against the camera frame `camera` (any size) with the chosen engine, the
/// view at `pixels_per_degree` (its perceptual model's `blur` frequency resolved for it, placed
/// by the manual mapping, so that every engine judges it alike).
pub fn run(
    engine: Backend,
    display: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
    pixels_per_degree: f64,
) -> Result<RgbaImage, String> {
    let mapping = params.camera_mapping();
    let view = ViewGeometry {
        mapping: &mapping,
        display_width: display.width,
        camera_width: camera.width,
        pixels_per_degree,
    };
    let params = &view_params(params, &view);
    match engine {
        Backend::Cpu => Ok(reference::enhance_with_camera(display, camera, params)),
        Backend::Vulkan => {
            let mut vulkan = VkOffline::new().map_err(|e| e.to_string())?;
            vulkan.enhance(display, camera, params)
        }
        Backend::OpenGl => {
            let mut opengl = GlOffline::new().map_err(|e| e.to_string())?;
            opengl.enhance(display, camera, params)
        }
    }
}
