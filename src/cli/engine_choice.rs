//! The one place the CLI chooses between the GPU engine (Vulkan, or OpenGL on an offline EGL
//! context) and the CPU reference.

use contrastxr::algorithm::Params;
use contrastxr::gpu::opengl::GlOffline;
use contrastxr::gpu::OfflineEngine;
use contrastxr::image::RgbaImage;
use contrastxr::reference;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    Gpu,
    Cpu,
    /// The OpenGL backend, as the layer runs it for OpenGL apps.
    OpenGl,
}

impl Engine {
    pub fn parse(name: &str) -> Option<Engine> {
        match name {
            "gpu" => Some(Engine::Gpu),
            "cpu" => Some(Engine::Cpu),
            "opengl" => Some(Engine::OpenGl),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Engine::Gpu => "gpu",
            Engine::Cpu => "cpu",
            Engine::OpenGl => "opengl",
        }
    }
}

/// Enhances `display` against the camera frame `camera` (any size) with the chosen engine.
pub fn run(
    engine: Engine,
    display: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
) -> Result<RgbaImage, String> {
    match engine {
        Engine::Cpu => Ok(reference::enhance_with_camera(display, camera, params)),
        Engine::Gpu => OfflineEngine::new()
            .and_then(|mut gpu| gpu.enhance(display, camera, params))
            .map_err(|e| e.to_string()),
        Engine::OpenGl => GlOffline::new()
            .and_then(|mut gl| gl.enhance(display, camera, params))
            .map_err(|e| e.to_string()),
    }
}
