//! The perceived contrast of a captured view (docs/algorithm.md, *What it reports*): the
//! perceptual model's report over the view's bytes before and after, in whatever format the
//! swapchain holds them, against the camera frame behind it prepared as the CPU reference
//! prepares it (pixel by pixel, for the pixels looked at), at the view's own frequency. Made on
//! the capture thread, never on the app's.

use super::capture_files::CaptureJob;
use crate::algorithm::perception::frame_report::{frame_report, ReportPixel};
use crate::algorithm::perception::frequency::{view_frequencies, BlurGeometry};
use crate::background_preparation::PointBackground;
use crate::colour;
use crate::evaluate::perception_report::{model, PerceptionReport};
use crate::gpu::core::pixel_codec;
use crate::gpu::PixelFormat;
use glam::DVec3;

/// The most pixels a report looks at per view: every pixel of a view up to this size, every
/// k-th row and column of a larger one, so that the capture thread's work per view is bounded
/// (about 10 ms in a debug build) however large the view and however many frames are captured.
pub const REPORT_PIXELS: usize = 1 << 14;

/// The least k for which every k-th row and column of a `width` x `height` view are at most
/// [`REPORT_PIXELS`] pixels (1 for a view no larger).
pub fn report_step(width: u32, height: u32) -> u32 {
    let mut k = 1u32;
    while (width.div_ceil(k) as usize) * (height.div_ceil(k) as usize) > REPORT_PIXELS {
        k += 1;
    }
    k
}

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

/// The report of `job`'s view over every `step`-th row and column ([`report_step`]: every
/// pixel of a view of up to [`REPORT_PIXELS`]).
pub fn view_report(job: &CaptureJob, step: u32) -> PerceptionReport {
    let v = &job.view;
    let (w, h) = job.extent;
    let camera = &job.background;
    let blur = BlurGeometry::of_view(&v.params, &v.mapping, w, camera.width, v.pixels_per_degree);
    let model = model(&v.params, view_frequencies(&v.params, &blur));
    // Only the pixels looked at: a report never blurs a whole camera frame.
    let behind = PointBackground::new(camera, &v.params);
    let bpp = job.format.bytes_per_pixel() as usize;
    let step = step.max(1) as usize;
    let rows = (0..h).step_by(step);
    let looked_at = rows.flat_map(|y| (0..w).step_by(step).map(move |x| (x, y)));
    let pixels = looked_at.filter_map(|(x, y)| {
        let i = (y as usize * w as usize + x as usize) * bpp;
        let at = |bytes: &[u8]| bytes.get(i..i + bpp).map(|px| linear_pixel(job.format, px));
        let ((display, alpha), (output, _)) = (at(&job.display)?, at(&job.output)?);
        Some(ReportPixel {
            display,
            alpha,
            background: behind.at(&v.mapping, (w, h), (x, y)),
            output,
        })
    });
    PerceptionReport::new(&frame_report(pixels, &model), &v.params)
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
    fn a_report_looks_at_a_bounded_number_of_pixels() {
        assert_eq!(report_step(128, 128), 1);
        assert_eq!(report_step(160, 96), 1);
        // 320x240: every 2nd is 160x120 = 19200, every 3rd 107x80 = 8560.
        assert_eq!(report_step(320, 240), 3);
        for (w, h) in [(129, 128), (2048, 2048), (4000, 1), (1, 1 << 20)] {
            let k = report_step(w, h);
            let n = |k: u32| w.div_ceil(k) as usize * h.div_ceil(k) as usize;
            assert!(n(k) <= REPORT_PIXELS, "{w}x{h}: {k}");
            assert!(k == 1 || n(k - 1) > REPORT_PIXELS, "{w}x{h}: {k}");
        }
    }
}
