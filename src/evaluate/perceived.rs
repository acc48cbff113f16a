//! The simulated perceived image: what the eye gets through an additive display (spec section 4).

use glam::DVec3;

use crate::algorithm::Params;
use crate::background;
use crate::colour;
use crate::image::RgbaImage;

/// `encode(clip(linear(display) + transmittance * linear(background)))`, the background
/// FoV-mapped like the optimiser's but sharp (not blurred). Black and alpha-0 display pixels
/// add no light. The result is opaque RGB.
pub fn perceived(display: &RgbaImage, camera: &RgbaImage, params: &Params) -> RgbaImage {
    let sharp = background::fov_sharp(camera, display.width, display.height, params);
    let t = f64::from(params.transmittance);
    let pixels = display
        .pixels
        .iter()
        .zip(sharp)
        .map(|(&d, bg)| {
            let light = if d[3] == 0 {
                DVec3::ZERO
            } else {
                colour::srgb8_to_linear([d[0], d[1], d[2]])
            };
            let [r, g, b] = colour::linear_to_srgb8(light + t * bg);
            [r, g, b, 255]
        })
        .collect();
    RgbaImage {
        width: display.width,
        height: display.height,
        pixels,
        has_alpha: false,
    }
}
