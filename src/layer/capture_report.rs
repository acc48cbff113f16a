//! The perceived contrast of a captured view (docs/algorithm.md, *What it reports*): the
//! perceptual model's report over the view's bytes before and after, in whatever format the
//! swapchain holds them, against the camera frame behind it prepared as the CPU reference
//! prepares it (pixel by pixel, for the pixels looked at), at the view's own frequency. Made on
//! the capture thread, never on the app's.

use super::capture_files::CaptureJob;
use crate::algorithm::perception::frame_report::{frame_report, ReportPixel};
use crate::algorithm::perception::frequency::BlurGeometry;
use crate::background_preparation::PointBackground;
use crate::colour;
use crate::evaluate::perception_report::{model, PerceptionReport};
use crate::gpu::core::pixel_codec;
use crate::gpu::PixelFormat;
use glam::DVec3;

/// The most pixels the out-of-reach check looks at per view: it takes every n-th pixel of a
/// larger view, which says as much about the share of content out of reach.
pub const CHECK_PIXELS: usize = 1 << 16;

/// One raw pixel as linear light and alpha: an sRGB format's codes through the sRGB curve
/// exactly as an 8-bit image's, a linear one's values clipped to [0, 1] (anything not finite
/// counts as 0).
pub fn linear_pixel(format: PixelFormat, px: &[u8]) -> (DVec3, f64) {
    let c = pixel_codec::decode(format, px).map(f64::from);
    let unit = |v: f64| {
        if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let light = |v: f64| {
        if format.srgb {
            colour::code_to_linear((unit(v) * 255.0).round() as u8)
        } else {
            unit(v)
        }
    };
    (
        DVec3::new(light(c[0]), light(c[1]), light(c[2])),
        unit(c[3]),
    )
}

/// The report of `job`'s view over every `every`-th pixel (1: all of them, as a capture's JSON
/// has it).
pub fn view_report(job: &CaptureJob, every: usize) -> PerceptionReport {
    let v = &job.view;
    let (w, h) = job.extent;
    let camera = &job.background;
    let blur = BlurGeometry::of_view(&v.params, &v.mapping, w, camera.width, v.pixels_per_degree);
    let model = model(&v.params, v.params.perceptual.frequency.resolve(&blur));
    // Only the pixels looked at: the check never blurs a whole camera frame.
    let behind = PointBackground::new(camera, &v.params);
    let bpp = job.format.bytes_per_pixel() as usize;
    let count = (w as usize * h as usize)
        .min(job.display.len() / bpp)
        .min(job.output.len() / bpp);
    let pixels = (0..count).step_by(every.max(1)).map(|i| {
        let at = |bytes: &[u8]| linear_pixel(job.format, &bytes[i * bpp..(i + 1) * bpp]);
        let ((display, alpha), (output, _)) = (at(&job.display), at(&job.output));
        let xy = ((i % w as usize) as u32, (i / w as usize) as u32);
        ReportPixel {
            display,
            alpha,
            background: behind.at(&v.mapping, (w, h), xy),
            output,
        }
    });
    PerceptionReport::new(&frame_report(pixels, &model), &v.params)
}

/// The step the out-of-reach check takes through a view of `pixels` pixels.
pub fn check_step(pixels: usize) -> usize {
    pixels.div_ceil(CHECK_PIXELS).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::PixelLayout;

    #[test]
    fn every_format_decodes_to_the_same_light() {
        // sRGB code 188 is linear 0.502886; a linear format holds that value itself.
        let want = colour::code_to_linear(188);
        let srgb = PixelFormat {
            layout: PixelLayout::Bgra8,
            srgb: true,
        };
        let (c, a) = linear_pixel(srgb, &[0, 0, 188, 255]);
        assert_eq!((c.x, c.y, a), (want, 0.0, 1.0));
        let half = pixel_codec::half_from_f32(want as f32).to_le_bytes();
        let float = PixelFormat {
            layout: PixelLayout::Rgba16Float,
            srgb: false,
        };
        let px = [
            half,
            half,
            half,
            pixel_codec::half_from_f32(1.0).to_le_bytes(),
        ]
        .concat();
        let (c, a) = linear_pixel(float, &px);
        assert!((c.x - want).abs() < 5e-4 && a == 1.0, "{c} {a}");
        // Out of [0, 1] and not finite: clipped, and 0.
        let odd = [
            pixel_codec::half_from_f32(3.0).to_le_bytes(),
            0x7e00u16.to_le_bytes(), // a NaN (the codec reads it as infinity)
            pixel_codec::half_from_f32(-1.0).to_le_bytes(),
            pixel_codec::half_from_f32(0.5).to_le_bytes(),
        ]
        .concat();
        assert_eq!(linear_pixel(float, &odd), (DVec3::new(1.0, 0.0, 0.0), 0.5));
        let ten = PixelFormat {
            layout: PixelLayout::A2b10g10r10,
            srgb: false,
        };
        let word: u32 = 1023 | (3 << 30);
        let (c, a) = linear_pixel(ten, &word.to_le_bytes());
        assert_eq!((c, a), (DVec3::new(1.0, 0.0, 0.0), 1.0));
    }

    #[test]
    fn the_check_looks_at_a_bounded_number_of_pixels() {
        assert_eq!(check_step(100), 1);
        assert_eq!(check_step(CHECK_PIXELS), 1);
        assert_eq!(check_step(CHECK_PIXELS + 1), 2);
        let big: usize = 2048 * 2048;
        assert!(big.div_ceil(check_step(big)) <= CHECK_PIXELS);
    }
}
