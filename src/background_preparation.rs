//! Background preprocessing on the CPU (docs/algorithm.md, Background preparation): decode,
//! Gaussian blur on the camera's own grid, mapping onto the display grid through the view's
//! CameraMapping (bilinear, linear light), then attenuation and conversion to the scaled space.
//! The GPU engine does the same in f32 (the first two once per camera frame, the rest per pixel
//! it enhances).

use glam::{DVec2, DVec3};

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::Params;
use crate::colour;
use crate::image::RgbaImage;

/// The background behind each display pixel, on the display's grid.
#[derive(Clone, Debug)]
pub struct PreparedBackground {
    pub width: u32,
    pub height: u32,
    /// Decoded, blurred, FoV-sampled linear light, NOT attenuated (subtraction needs this).
    /// Row-major, `width * height` entries.
    pub linear: Vec<DVec3>,
    /// transmittance * linear -> XYZ -> LAB -> scaled: the paper's B.
    pub scaled: Vec<DVec3>,
}

/// A linear-light image on the camera's grid, row-major.
#[derive(Clone, Debug)]
pub struct LinearImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<DVec3>,
}

impl LinearImage {
    fn decode(camera: &RgbaImage) -> Self {
        let lut: Vec<f64> = (0..=255u8).map(colour::code_to_linear).collect();
        let pixels = camera
            .pixels
            .iter()
            .map(|p| DVec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect();
        LinearImage {
            width: camera.width,
            height: camera.height,
            pixels,
        }
    }

    /// Pixel with clamp-to-edge addressing.
    fn at(&self, x: i64, y: i64) -> DVec3 {
        let x = x.clamp(0, i64::from(self.width) - 1) as usize;
        let y = y.clamp(0, i64::from(self.height) - 1) as usize;
        self.pixels[y * self.width as usize + x]
    }

    /// One pass of the separable Gaussian, horizontal (`dx = 1`) or vertical.
    fn blur_pass(&self, taps: &[f64], horizontal: bool) -> Self {
        let half = (taps.len() / 2) as i64;
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let mut pixels = Vec::with_capacity(self.pixels.len());
        for y in 0..h {
            for x in 0..w {
                let mut sum = DVec3::ZERO;
                for (k, &t) in taps.iter().enumerate() {
                    let o = k as i64 - half;
                    sum += t * if horizontal {
                        self.at(x + o, y)
                    } else {
                        self.at(x, y + o)
                    };
                }
                pixels.push(sum);
            }
        }
        LinearImage {
            width: self.width,
            height: self.height,
            pixels,
        }
    }

    fn blur(self, taps: &[f64]) -> Self {
        if taps.len() <= 1 {
            return self;
        }
        self.blur_pass(taps, true).blur_pass(taps, false)
    }

    /// Bilinear sample at texture coordinates (u, v): texel centres at (i + 0.5) / W,
    /// clamp-to-edge.
    fn sample(&self, u: f64, v: f64) -> DVec3 {
        bilinear((self.width, self.height), u, v, |x, y| self.at(x, y))
    }

    /// Resamples onto a `width` x `height` display grid: camera_uv = mapping(display_uv).
    fn fov_map(&self, width: u32, height: u32, mapping: &CameraMapping) -> Vec<DVec3> {
        let mut out = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            let v = (f64::from(y) + 0.5) / f64::from(height);
            for x in 0..width {
                let u = (f64::from(x) + 0.5) / f64::from(width);
                let c = mapping.apply(DVec2::new(u, v));
                out.push(self.sample(c.x, c.y));
            }
        }
        out
    }
}

/// Bilinear sample at texture coordinates (u, v) of a `size` image whose texel `(x, y)`
/// (clamped to the image by `at`) is `at(x, y)`.
fn bilinear(size: (u32, u32), u: f64, v: f64, at: impl Fn(i64, i64) -> DVec3) -> DVec3 {
    let x = u * f64::from(size.0) - 0.5;
    let y = v * f64::from(size.1) - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let top = at(x0, y0).lerp(at(x0 + 1, y0), fx);
    let bottom = at(x0, y0 + 1).lerp(at(x0 + 1, y0 + 1), fx);
    top.lerp(bottom, fy)
}

/// The prepared background behind single display pixels, without decoding or blurring the
/// whole camera frame: what [`prepare_mapped`]'s `linear` holds there, to the last bit (the
/// same sums in the same order), for a sample of the pixels of a view over a large frame.
pub struct PointBackground<'a> {
    camera: &'a RgbaImage,
    taps: Vec<f64>,
    /// Linear light of each code, as `LinearImage::decode` takes it.
    lut: Vec<f64>,
}

impl<'a> PointBackground<'a> {
    pub fn new(camera: &'a RgbaImage, params: &Params) -> Self {
        PointBackground {
            camera,
            taps: params.blur_taps(),
            lut: (0..=255u8).map(colour::code_to_linear).collect(),
        }
    }

    fn clamped(&self, x: i64, y: i64) -> (u32, u32) {
        let x = x.clamp(0, i64::from(self.camera.width) - 1) as u32;
        let y = y.clamp(0, i64::from(self.camera.height) - 1) as u32;
        (x, y)
    }

    fn decoded(&self, x: i64, y: i64) -> DVec3 {
        let (x, y) = self.clamped(x, y);
        let p = self.camera.get(x, y);
        DVec3::new(
            self.lut[p[0] as usize],
            self.lut[p[1] as usize],
            self.lut[p[2] as usize],
        )
    }

    /// Texel `(x, y)` of the blurred frame: the vertical pass over the horizontal one, as
    /// `LinearImage::blur` makes it.
    fn blurred(&self, x: i64, y: i64) -> DVec3 {
        if self.taps.len() <= 1 {
            return self.decoded(x, y);
        }
        let (x, y) = self.clamped(x, y);
        let (x, y) = (i64::from(x), i64::from(y));
        let half = (self.taps.len() / 2) as i64;
        let mut sum = DVec3::ZERO;
        for (k, &t) in self.taps.iter().enumerate() {
            let row = i64::from(self.clamped(x, y + k as i64 - half).1);
            let mut across = DVec3::ZERO;
            for (j, &s) in self.taps.iter().enumerate() {
                across += s * self.decoded(x + j as i64 - half, row);
            }
            sum += t * across;
        }
        sum
    }

    /// The background behind display pixel `(x, y)` of a `width` x `height` view at `mapping`.
    pub fn at(
        &self,
        mapping: &CameraMapping,
        (width, height): (u32, u32),
        (x, y): (u32, u32),
    ) -> DVec3 {
        let u = (f64::from(x) + 0.5) / f64::from(width);
        let v = (f64::from(y) + 0.5) / f64::from(height);
        let c = mapping.apply(DVec2::new(u, v));
        let size = (self.camera.width, self.camera.height);
        bilinear(size, c.x, c.y, |x, y| self.blurred(x, y))
    }
}

/// The camera frame decoded and blurred (docs/algorithm.md, Background preparation, steps
/// 1-2): linear light on the
/// camera's grid, not attenuated. The part that depends on the camera frame only.
pub fn blurred_camera(camera: &RgbaImage, params: &Params) -> LinearImage {
    LinearImage::decode(camera).blur(&params.blur_taps())
}

/// Preprocesses a camera frame for a `width` x `height` display (docs/algorithm.md, Background
/// preparation) with the
/// manual FoV mapping of `params` (`Params::camera_mapping`).
pub fn prepare(camera: &RgbaImage, width: u32, height: u32, params: &Params) -> PreparedBackground {
    prepare_mapped(camera, width, height, &params.camera_mapping(), params)
}

/// Preprocesses a camera frame for one view of `width` x `height` whose pixels lie at
/// `mapping` in the camera image (docs/algorithm.md, Per-view registration: the FoV step
/// generalised to a homography).
pub fn prepare_mapped(
    camera: &RgbaImage,
    width: u32,
    height: u32,
    mapping: &CameraMapping,
    params: &Params,
) -> PreparedBackground {
    let linear = blurred_camera(camera, params).fov_map(width, height, mapping);
    let transmittance = f64::from(params.transmittance);
    let scaled = linear
        .iter()
        .map(|&c| colour::linear_to_scaled(transmittance * c))
        .collect();
    PreparedBackground {
        width,
        height,
        linear,
        scaled,
    }
}

/// The camera frame FoV-mapped onto the display grid, linear light, neither blurred nor
/// attenuated: what the eye sees sharp through the lens (before the lens's transmittance).
pub fn fov_sharp(camera: &RgbaImage, width: u32, height: u32, params: &Params) -> Vec<DVec3> {
    fov_sharp_mapped(camera, width, height, &params.camera_mapping())
}

/// `fov_sharp` for a view at `mapping` in the camera image.
pub fn fov_sharp_mapped(
    camera: &RgbaImage,
    width: u32,
    height: u32,
    mapping: &CameraMapping,
) -> Vec<DVec3> {
    LinearImage::decode(camera).fov_map(width, height, mapping)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_fov() -> Params {
        Params {
            fov: false,
            ..Params::default()
        }
    }

    #[test]
    fn uniform_camera_gives_uniform_background() {
        let camera = RgbaImage::new(7, 5, [200, 100, 50, 255]);
        let bg = prepare(&camera, 4, 3, &Params::default());
        let want = colour::srgb8_to_linear([200, 100, 50]);
        for c in &bg.linear {
            assert!((*c - want).abs().max_element() < 1e-12);
        }
        let scaled = colour::linear_to_scaled(f64::from(0.4f32) * want);
        assert!((bg.scaled[5] - scaled).abs().max_element() < 1e-12);
    }

    /// Pixel by pixel, the point background is the prepared background exactly: blurred and
    /// not, under a projective mapping that reaches past the frame's edges.
    #[test]
    fn the_point_background_is_the_prepared_one_to_the_bit() {
        let mut camera = RgbaImage::new(9, 7, [0, 0, 0, 255]);
        for y in 0..7 {
            for x in 0..9 {
                let c = |k: u32| ((x * 37 + y * 91 + k * 53) % 256) as u8;
                camera.set(x, y, [c(0), c(1), c(2), 255]);
            }
        }
        let mapping = CameraMapping {
            rows: [[1.3, 0.1, -0.2], [0.05, 1.2, -0.1], [0.2, 0.1, 1.0]],
        };
        for blur_size in [1, 3, 5] {
            let params = Params {
                blur_size,
                ..Params::default()
            };
            let (w, h) = (11, 6);
            let bg = prepare_mapped(&camera, w, h, &mapping, &params);
            let point = PointBackground::new(&camera, &params);
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    assert_eq!(point.at(&mapping, (w, h), (x, y)), bg.linear[i], "{x} {y}");
                }
            }
        }
    }

    #[test]
    fn blur_uses_spec_taps_with_clamp_to_edge() {
        // A single white column x = 1 on black, 3 wide: after the horizontal pass the middle
        // column keeps 0.384397 and its neighbours get 0.307801 (the edge clamps repeat 0).
        let mut camera = RgbaImage::new(3, 3, [0, 0, 0, 255]);
        for y in 0..3 {
            camera.set(1, y, [255, 255, 255, 255]);
        }
        let bg = prepare(&camera, 3, 3, &no_fov());
        let row: Vec<f64> = (0..3).map(|x| bg.linear[3 + x].x).collect();
        assert!(
            (row[0] - 0.307801).abs() < 1e-6 && (row[1] - 0.384397).abs() < 1e-6,
            "{row:?}"
        );
        assert!((row[2] - 0.307801).abs() < 1e-6);
    }

    #[test]
    fn fov_window_is_cropped_and_bilinear() {
        // Camera 4x1 with linear ramp codes; display 2x1, no blur, scale 0.5 offset 0.25:
        // display u = 0.25 -> camera u = 0.375 -> x = 1.0 exactly (texel 1);
        // display u = 0.75 -> camera u = 0.625 -> x = 2.0 (texel 2).
        let mut camera = RgbaImage::new(4, 1, [0, 0, 0, 255]);
        let codes = [10u8, 60, 120, 250];
        for (x, c) in codes.iter().enumerate() {
            camera.set(x as u32, 0, [*c, *c, *c, 255]);
        }
        let params = Params {
            blur: false,
            fov_scale: [0.5, 1.0],
            fov_offset: [0.25, 0.0],
            ..Params::default()
        };
        let sharp = fov_sharp(&camera, 2, 1, &params);
        assert!((sharp[0].x - colour::code_to_linear(60)).abs() < 1e-6);
        assert!((sharp[1].x - colour::code_to_linear(120)).abs() < 1e-6);
        // Half way between texels 0 and 1 in linear light, not in code values.
        let half = Params {
            fov_scale: [0.25, 1.0],
            fov_offset: [0.125, 0.0],
            ..params
        };
        let s = fov_sharp(&camera, 1, 1, &half);
        let want = 0.5 * (colour::code_to_linear(10) + colour::code_to_linear(60));
        assert!((s[0].x - want).abs() < 1e-6, "{} vs {want}", s[0].x);
    }

    #[test]
    fn a_homography_samples_after_the_projective_divide() {
        // Camera 4x1 ramp as above, display 1x1 (uv 0.5, 0.5). M (0.5, 0.5, 1) = (0.75, 0.5, 2):
        // camera u = 0.375 -> x = 1.0, texel 1 exactly; without the divide it would be texel 2.5.
        let mut camera = RgbaImage::new(4, 1, [0, 0, 0, 255]);
        for (x, c) in [10u8, 60, 120, 250].iter().enumerate() {
            camera.set(x as u32, 0, [*c, *c, *c, 255]);
        }
        let mapping = CameraMapping {
            rows: [[1.0, 0.0, 0.25], [0.0, 1.0, 0.0], [1.0, 1.0, 1.0]],
        };
        let s = fov_sharp_mapped(&camera, 1, 1, &mapping);
        assert!((s[0].x - colour::code_to_linear(60)).abs() < 1e-9);
        let params = Params {
            blur: false,
            ..Params::default()
        };
        let bg = prepare_mapped(&camera, 1, 1, &mapping, &params);
        assert_eq!(bg.linear, s);
    }
}
