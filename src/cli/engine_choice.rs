//! The one place the CLI chooses between the GPU engine and the CPU reference.

use contrastxr::algorithm::Params;
use contrastxr::gpu::OfflineEngine;
use contrastxr::image::RgbaImage;
use contrastxr::reference;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    Gpu,
    Cpu,
}

impl Engine {
    pub fn parse(name: &str) -> Option<Engine> {
        match name {
            "gpu" => Some(Engine::Gpu),
            "cpu" => Some(Engine::Cpu),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Engine::Gpu => "gpu",
            Engine::Cpu => "cpu",
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
    }
}
