//! The perceived contrast c' of content over the world (docs/algorithm.md, *Light and
//! contrast*): the physical RMS cone contrast c of the pattern a content edge makes, less its
//! detection threshold c / C, with C from castleCSF at the pattern's mean luminance. Pure; the
//! f64 reference (the f32 tables for the GPU are tables.rs).

use glam::DVec3;

use super::castle_csf::{self, Real};
use super::frequency::{BlurGeometry, Frequencies};
use super::light::{Light, Pattern};
use crate::algorithm::params::Params;
use crate::algorithm::perceptual_settings::{PerceptualSettings, LUMINANCE_MAX};

/// The RMS cone contrast `sqrt(((dL/L_m)^2 + (dM/M_m)^2 + (dS/S_m)^2) / 3)`; 0 where there is no
/// light (a mean of 0).
pub fn rms_cone_contrast<R: Real>(mean: [R; 3], amplitude: [R; 3]) -> R {
    let mut sum = R::of(0.0);
    for i in 0..3 {
        if mean[i] > R::of(0.0) {
            let k = amplitude[i] / mean[i];
            sum = sum + k * k;
        }
    }
    (sum / R::of(3.0)).sqrt()
}

/// Kulikowski's rule: the perceived contrast is the physical contrast less the threshold c / C,
/// `c' = c max(1 - 1/C, 0)` (0 for C = 0).
pub fn kulikowski<R: Real>(c: R, threshold_multiple: R) -> R {
    if threshold_multiple <= R::of(0.0) {
        return R::of(0.0);
    }
    c * (R::of(1.0) - R::of(1.0) / threshold_multiple).max(R::of(0.0))
}

/// c, C and c' of one pattern at one frequency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contrast {
    /// The physical (RMS cone) contrast.
    pub physical: f64,
    /// C: how many times its detection threshold the pattern is.
    pub threshold_multiple: f64,
    /// c'.
    pub perceived: f64,
}

/// c, C and c' of `pattern` at frequency `f` (cpd), the sensitivities taken at luminance `y`.
pub fn contrast(pattern: &Pattern, y: f64, f: f64) -> Contrast {
    let physical = rms_cone_contrast(pattern.mean, pattern.amplitude);
    let s = castle_csf::sensitivities(y, f);
    let threshold_multiple = castle_csf::threshold_multiple(pattern.mean, pattern.amplitude, s);
    Contrast {
        physical,
        threshold_multiple,
        perceived: kulikowski(physical, threshold_multiple),
    }
}

/// The model for one frame: the lights, the floor, the target and the frequencies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    pub light: Light,
    /// The floor on the luminance the sensitivities are taken at (cd/m^2).
    pub min_luminance: f64,
    /// The c' at which content counts as visible enough.
    pub target_contrast: f64,
    pub frequencies: Frequencies,
    /// A factor on every threshold multiple C: 1 for the model itself. The conformance trace
    /// varies it by the GPU tables' tolerance to find the pixels whose output they may flip.
    pub threshold_scale: f64,
}

impl Model {
    /// The model of `settings`, behind a lens of `transmittance`, at `frequencies` (from
    /// `settings.frequency` resolved for the frame).
    pub fn new(
        settings: &PerceptualSettings,
        transmittance: f64,
        frequencies: Frequencies,
    ) -> Model {
        Model {
            light: Light {
                display_peak_nits: settings.display_peak_nits,
                world_nits_at_eye: transmittance * settings.world_nits,
            },
            min_luminance: settings.min_luminance,
            target_contrast: settings.target_contrast,
            frequencies,
            threshold_scale: 1.0,
        }
    }

    /// The model of `params`: its perceptual settings behind its lens, the frequency setting
    /// resolved as [`BlurGeometry::unplaced`] says where it is `blur` (a view's engine resolves
    /// it for the view first, `frequency::for_view`).
    pub fn of_params(params: &Params) -> Model {
        let frequencies = params
            .perceptual
            .frequency
            .resolve(&BlurGeometry::unplaced(params));
        Model::new(
            &params.perceptual,
            f64::from(params.transmittance),
            frequencies,
        )
    }

    /// The luminance the sensitivities are taken at for a pattern of mean luminance `y`:
    /// `y` floored at `min_luminance` and held at [`LUMINANCE_MAX`].
    pub fn sensitivity_luminance(&self, y: f64) -> f64 {
        y.max(self.min_luminance).min(LUMINANCE_MAX)
    }

    /// c' of linear display colour `display` over the linear (unattenuated) background
    /// `background`: the mean over the frame's frequencies.
    pub fn perceived_contrast(&self, display: DVec3, background: DVec3) -> f64 {
        let pattern = self.light.pattern(display, background);
        let y = self.sensitivity_luminance(pattern.luminance);
        let cpd = self.frequencies.cpd();
        let sum: f64 = cpd
            .iter()
            .map(|&f| {
                let c = contrast(&pattern, y, f);
                kulikowski(c.physical, self.threshold_scale * c.threshold_multiple)
            })
            .sum();
        sum / cpd.len() as f64
    }
}
