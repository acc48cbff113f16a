//! The simulated perceived image: what the eye gets through an additive display
//! (docs/algorithm.md, Perceived image).

use glam::DVec3;

use crate::algorithm::Params;
use crate::background_preparation;
use crate::colour;
use crate::image::RgbaImage;

/// `encode(clip(linear(display) + transmittance * linear(background)))`, the background
/// FoV-mapped like the optimiser's but sharp (not blurred). Black and alpha-0 display pixels
/// add no light. The result is opaque RGB.
pub fn perceived(display: &RgbaImage, camera: &RgbaImage, params: &Params) -> RgbaImage {
    let sharp = background_preparation::fov_sharp(camera, display.width, display.height, params);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn additive_blend_of_display_and_attenuated_background() {
        // Uniform code-200 background: linear 0.577580; x0.4 = 0.231032 -> code 132.
        let camera = RgbaImage::new(8, 8, [200, 200, 200, 255]);
        let mut display = RgbaImage::new(3, 1, [0, 0, 0, 255]);
        display.set(1, 0, [255, 255, 255, 255]);
        display.set(2, 0, [90, 0, 0, 0]);
        let p = perceived(&display, &camera, &Params::default());
        assert_eq!(p.get(0, 0), [132, 132, 132, 255]);
        assert_eq!(p.get(1, 0), [255, 255, 255, 255], "clipped at white");
        assert_eq!(p.get(2, 0), [132, 132, 132, 255], "alpha 0 adds no light");
        assert!(!p.has_alpha);
    }
}
