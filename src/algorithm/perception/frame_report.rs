//! What a frame's enhancement is worth to the eye (docs/algorithm.md, *What it reports*): c'
//! before and after, its gain, the share of content left alone, brought to the target and out
//! of reach, the colour change and the world's luminance behind the content. For the output of
//! any method, not only the perceptual one. Pure; f64.

use glam::DVec3;

use super::frequency::Frequencies;
use super::perceived_contrast::Model;
use super::perceptual_pixel::Class;
use crate::colour;

/// The floor on the mean c' before that the gain divides by.
pub const GAIN_FLOOR: f64 = 1e-4;

/// One pixel of a frame: linear colours, the background unattenuated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReportPixel {
    pub display: DVec3,
    pub alpha: f64,
    pub background: DVec3,
    /// The method's output for it, linear.
    pub output: DVec3,
}

/// A frame's statistics over its content pixels (neither exactly black nor alpha 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameReport {
    pub content_pixels: usize,
    /// Mean c' of the display colours and of the outputs.
    pub perceived_before: f64,
    pub perceived_after: f64,
    /// `perceived_after / max(perceived_before, GAIN_FLOOR)`; 1 for a frame without content.
    pub gain: f64,
    pub log2_gain: f64,
    /// Fractions of the content pixels in each class ([`Class::of`]); they sum to 1 (0 without
    /// content).
    pub left_alone: f64,
    pub brought_to_target: f64,
    pub out_of_reach: f64,
    /// Mean and largest CIE76 Delta E*ab between display colour and output (0 without
    /// content).
    pub mean_delta_e: f64,
    pub max_delta_e: f64,
    /// Mean luminance (cd/m^2) of the world behind the content, as it reaches the eye (t W Y_B).
    pub mean_world_luminance: f64,
    pub frequencies: Frequencies,
}

/// The report of a frame's pixels under `model`.
pub fn frame_report(pixels: impl IntoIterator<Item = ReportPixel>, model: &Model) -> FrameReport {
    let (mut n, mut before, mut after, mut delta_e, mut world) = (0usize, 0.0, 0.0, 0.0, 0.0);
    let mut max_delta_e: f64 = 0.0;
    let (mut alone, mut brought, mut out) = (0usize, 0usize, 0usize);
    for p in pixels {
        if p.alpha == 0.0 || p.display == DVec3::ZERO {
            continue;
        }
        n += 1;
        let b = model.perceived_contrast(p.display, p.background);
        let a = model.perceived_contrast(p.output, p.background);
        before += b;
        after += a;
        match Class::of(b, a, model.target_contrast) {
            Class::LeftAlone => alone += 1,
            Class::BroughtToTarget => brought += 1,
            _ => out += 1,
        }
        let change = colour::delta_e(
            colour::linear_to_lab(p.display),
            colour::linear_to_lab(p.output),
        );
        delta_e += change;
        max_delta_e = max_delta_e.max(change);
        world += model.light.world_xyz(p.background).y;
    }
    let mean = |sum: f64| if n == 0 { 0.0 } else { sum / n as f64 };
    let share = |k: usize| mean(k as f64);
    let (perceived_before, perceived_after) = (mean(before), mean(after));
    let gain = if n == 0 {
        1.0
    } else {
        perceived_after / perceived_before.max(GAIN_FLOOR)
    };
    FrameReport {
        content_pixels: n,
        perceived_before,
        perceived_after,
        gain,
        log2_gain: gain.log2(),
        left_alone: share(alone),
        brought_to_target: share(brought),
        out_of_reach: share(out),
        mean_delta_e: mean(delta_e),
        max_delta_e,
        mean_world_luminance: mean(world),
        frequencies: model.frequencies,
    }
}
