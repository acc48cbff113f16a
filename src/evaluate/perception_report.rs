//! The perceived contrast of an enhancement (docs/algorithm.md, *What it reports*): the
//! perceptual model's frame report over a display image, its output and the prepared
//! background, for any method's output. Pure CPU, f64; it never runs a method.

use glam::DVec3;
use serde::Serialize;

use crate::algorithm::perception::frame_report::{frame_report, FrameReport, ReportPixel};
use crate::algorithm::perception::frequency::{view_frequencies, BlurGeometry, Frequencies};
use crate::algorithm::perception::perceived_contrast::Model;
use crate::algorithm::Params;
use crate::background_preparation::PreparedBackground;
use crate::colour;
use crate::image::RgbaImage;

/// What `contrastxr evaluate --json` adds to the paper's metric (the colour change itself is
/// the metric's `delta_e_out_display`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PerceptionReport {
    /// Mean c' of the content pixels' display colours, and of their outputs.
    pub perceived_contrast_before: f64,
    pub perceived_contrast_after: f64,
    /// `after / max(before, 1e-4)`, and its log2 (1 and 0 without content).
    pub perceived_contrast_gain: f64,
    pub perceived_contrast_log2_gain: f64,
    /// The c' counted as visible enough (the `target_contrast` setting).
    pub target_contrast: f64,
    /// Fractions of the content pixels whose display colour reaches the target, whose output
    /// reaches it and whose neither does (they sum to 1; 0 without content).
    pub left_alone_fraction: f64,
    pub brought_to_target_fraction: f64,
    pub out_of_reach_fraction: f64,
    /// The `frequency` setting, and the frequencies (cpd) c' was averaged over.
    pub frequency: String,
    pub frequency_cpd: Vec<f64>,
    /// Mean luminance (cd/m^2) of the world behind the content, as it reaches the eye.
    pub mean_world_luminance: f64,
}

/// The frequencies of `params`'s `frequency` setting for a display `display_width` pixels wide
/// at `pixels_per_degree`, over a camera frame `camera_width` pixels wide placed by the manual
/// FoV mapping (as the command line places it).
pub fn offline_frequencies(
    params: &Params,
    display_width: u32,
    camera_width: u32,
    pixels_per_degree: f64,
) -> Frequencies {
    let blur = BlurGeometry::manual(params, display_width, camera_width, pixels_per_degree);
    view_frequencies(params, &blur)
}

/// The model of `params` (its perceptual settings and transmittance) at `frequencies`.
pub fn model(params: &Params, frequencies: Frequencies) -> Model {
    Model::new(
        &params.perceptual,
        f64::from(params.transmittance),
        frequencies,
    )
}

/// The frame report of `output` against `display` over `background` (the same prepared
/// background the method used; its unattenuated linear light) under `model`.
pub fn frame_report_of_images(
    display: &RgbaImage,
    output: &RgbaImage,
    background: &PreparedBackground,
    model: &Model,
) -> FrameReport {
    assert_eq!(
        (display.width, display.height),
        (output.width, output.height)
    );
    assert_eq!(
        (display.width, display.height),
        (background.width, background.height)
    );
    let linear = |p: [u8; 4]| {
        DVec3::new(
            colour::code_to_linear(p[0]),
            colour::code_to_linear(p[1]),
            colour::code_to_linear(p[2]),
        )
    };
    let pixels = display
        .pixels
        .iter()
        .zip(&output.pixels)
        .zip(&background.linear)
        .map(|((&d, &o), &b)| ReportPixel {
            display: linear(d),
            alpha: f64::from(d[3]) / 255.0,
            background: b,
            output: linear(o),
        });
    frame_report(pixels, model)
}

impl PerceptionReport {
    /// The report's keys from a frame report made with `params`.
    pub fn new(report: &FrameReport, params: &Params) -> PerceptionReport {
        PerceptionReport {
            perceived_contrast_before: report.perceived_before,
            perceived_contrast_after: report.perceived_after,
            perceived_contrast_gain: report.gain,
            perceived_contrast_log2_gain: report.log2_gain,
            target_contrast: params.perceptual.target_contrast,
            left_alone_fraction: report.left_alone,
            brought_to_target_fraction: report.brought_to_target,
            out_of_reach_fraction: report.out_of_reach,
            frequency: params.perceptual.frequency.name(),
            frequency_cpd: report.frequencies.cpd().to_vec(),
            mean_world_luminance: report.mean_world_luminance,
        }
    }
}

/// [`PerceptionReport`] of `output` against `display` over `background` with `params` at
/// `frequencies`.
pub fn perception_report(
    display: &RgbaImage,
    output: &RgbaImage,
    background: &PreparedBackground,
    params: &Params,
    frequencies: Frequencies,
) -> PerceptionReport {
    let report = frame_report_of_images(display, output, background, &model(params, frequencies));
    PerceptionReport::new(&report, params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::perceptual_settings::PerceptualSettings;

    /// Two content pixels over a grey 0.8 world at 5000 cd/m^2 behind a lens of 0.3, at 2 cpd,
    /// and a black one; by hand from the second worked example of docs/algorithm.md's model
    /// (grey 0.5 over that world: c 0.04, C 4.298, so C / c = 107.45 there, which hardly moves
    /// between 1200 and 1300 cd/m^2). Grey on grey, c is the Michelson contrast
    /// `Y_D / (Y_D + 2 Y_tB)` and c' = `c (1 - 1 / (107.45 c))`:
    /// - code 188 (linear 0.502886, Y_D 100.577): c 0.0402216, c' 0.030915, below the target;
    /// - turned white (Y_D 200): c 0.0769231, c' 0.067627, above it.
    #[test]
    fn grey_on_grey_follows_the_worked_example() {
        let params = Params {
            transmittance: 0.3,
            perceptual: PerceptualSettings {
                world_nits: 5000.0,
                ..PerceptualSettings::default()
            },
            ..Params::default()
        };
        let mut display = RgbaImage::new(3, 1, [188, 188, 188, 255]);
        display.set(2, 0, [0, 0, 0, 255]);
        let mut output = display.clone();
        output.set(1, 0, [255, 255, 255, 255]);
        let background = PreparedBackground {
            width: 3,
            height: 1,
            linear: vec![DVec3::splat(0.8); 3],
            scaled: vec![DVec3::ZERO; 3],
        };
        let r = perception_report(
            &display,
            &output,
            &background,
            &params,
            Frequencies::One(2.0),
        );
        let near = |a: f64, b: f64, rel: f64| (a - b).abs() <= rel * b.abs();
        assert!(near(r.perceived_contrast_before, 0.030915, 1e-3), "{r:?}");
        let after = (0.030915 + 0.067627) / 2.0;
        assert!(near(r.perceived_contrast_after, after, 2e-3), "{r:?}");
        assert!(near(
            r.perceived_contrast_gain,
            r.perceived_contrast_after / r.perceived_contrast_before,
            1e-12
        ));
        assert_eq!(
            (
                r.left_alone_fraction,
                r.brought_to_target_fraction,
                r.out_of_reach_fraction
            ),
            (0.0, 0.5, 0.5),
            "{r:?}"
        );
        // World behind content: 0.3 * 5000 * 0.8 (the Y row of the crate's matrix sums to 1
        // within 2e-7).
        assert!(near(r.mean_world_luminance, 1200.0, 1e-6), "{r:?}");
        assert_eq!(
            (r.frequency.as_str(), r.frequency_cpd.as_slice()),
            ("blur", &[2.0][..])
        );
    }
}
