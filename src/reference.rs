//! The CPU reference on whole images: background preprocessing plus the per-pixel method.
//! Slow and exact (f64); the GPU engine is tested against it.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::perception::frequency::{
    view_params, ViewGeometry, DEFAULT_PIXELS_PER_DEGREE,
};
use crate::algorithm::{enhance_srgb8, Params};
use crate::background_preparation::{self, PreparedBackground};
use crate::image::RgbaImage;

/// Enhances every display pixel against an already prepared background of the same size.
pub fn enhance_image(
    display: &RgbaImage,
    background: &PreparedBackground,
    params: &Params,
) -> RgbaImage {
    assert_eq!(
        (display.width, display.height),
        (background.width, background.height),
        "the background must be prepared for the display's size"
    );
    let pixels = display
        .pixels
        .iter()
        .zip(background.linear.iter().zip(&background.scaled))
        .map(|(&d, (&bg_linear, &bg_scaled))| enhance_srgb8(d, bg_linear, bg_scaled, params))
        .collect();
    RgbaImage {
        width: display.width,
        height: display.height,
        pixels,
        has_alpha: display.has_alpha,
    }
}

/// Preprocesses the camera frame (any size) for the display, then enhances (the manual FoV
/// mapping of `params`).
pub fn enhance_with_camera(display: &RgbaImage, camera: &RgbaImage, params: &Params) -> RgbaImage {
    enhance_with_camera_mapped(display, camera, &params.camera_mapping(), params)
}

/// `enhance_with_camera` for a view at `mapping` in the camera image.
pub fn enhance_with_camera_mapped(
    display: &RgbaImage,
    camera: &RgbaImage,
    mapping: &CameraMapping,
    params: &Params,
) -> RgbaImage {
    let (w, h) = (display.width, display.height);
    let bg = background_preparation::prepare_mapped(camera, w, h, mapping, params);
    // The perceptual method's `blur` frequency, resolved for the view as the engines do.
    let view = ViewGeometry {
        mapping,
        display_width: w,
        camera_width: camera.width,
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    enhance_image(display, &bg, &view_params(params, &view))
}
