//! The engine on a device or context of its own, whole images in and out, the same for every
//! backend: what the command line enhances with and what one conformance suite
//! (tests/engine_conformance.rs) holds each backend to.

use super::pixel_codec;
use super::pixel_format::PixelFormat;
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::image::RgbaImage;

/// A backend's offline engine.
pub trait OfflineBackend {
    /// The graphics API, as the command line names it ("vulkan", "opengl").
    fn api(&self) -> &'static str;

    /// Whether it runs on a CPU driver (lavapipe, llvmpipe).
    fn on_cpu(&self) -> bool;

    /// The pixel formats it enhances (OpenGL has no BGRA internal format).
    fn pixel_formats(&self) -> Vec<PixelFormat>;

    /// Enhances raw pixels of `format` (rows top first; one u32 per pixel, two for the 16-bit
    /// formats) against a camera frame, through `mapping`; an error says why not.
    fn enhance_pixels(
        &mut self,
        pixels: &[u32],
        shape: ((u32, u32), PixelFormat),
        camera: &RgbaImage,
        mapping: &CameraMapping,
        params: &Params,
    ) -> Result<Vec<u32>, String>;

    /// Enhances an 8-bit sRGB image against a camera frame, through `mapping`.
    fn enhance_mapped(
        &mut self,
        display: &RgbaImage,
        camera: &RgbaImage,
        mapping: &CameraMapping,
        params: &Params,
    ) -> Result<RgbaImage, String> {
        let shape = ((display.width, display.height), PixelFormat::SRGB8);
        let words = pixel_codec::srgb8_words(display);
        let out = self.enhance_pixels(&words, shape, camera, mapping, params)?;
        Ok(pixel_codec::srgb8_image(display, &out))
    }

    /// `enhance_mapped` with the manual FoV mapping of `params`.
    fn enhance(
        &mut self,
        display: &RgbaImage,
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<RgbaImage, String> {
        self.enhance_mapped(display, camera, &params.camera_mapping(), params)
    }

    /// Vulkan validation errors so far (0 where the backend has no validation layer).
    fn validation_errors(&self) -> u32 {
        0
    }
}
