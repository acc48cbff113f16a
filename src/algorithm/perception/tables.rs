//! What the GPU needs per frame to evaluate c' (docs/algorithm.md, *The method, per pixel*, on
//! the GPU): the three channel sensitivities at each of the frame's frequencies, tabulated in f32
//! over log10 Y in [-1, 4.5] and interpolated linearly in log Y, with the frame's lights and the
//! colour matrices rounded to f32; and c' evaluated from them in f32, as a shader would, so that
//! a GPU implementation can be checked against it. Pure.
use glam::Vec3;

use super::castle_csf::{self, Sensitivities};
use super::light::XYZ_TO_LMS;
use super::perceived_contrast::{kulikowski, rms_cone_contrast, Model};
use crate::algorithm::perceptual_settings::{LUMINANCE_MAX, LUMINANCE_MIN};
use crate::colour::LINEAR_TO_XYZ;

/// Entries per channel and frequency.
pub const TABLE_LEN: usize = 256;

/// The tabulated range of log10 Y (Y in cd/m^2): [`LUMINANCE_MIN`] to [`LUMINANCE_MAX`].
pub const LOG_LUMINANCE_MIN: f64 = -1.0;
pub const LOG_LUMINANCE_MAX: f64 = 4.5;

/// log10 Y between two entries.
pub const LOG_LUMINANCE_STEP: f64 =
    (LOG_LUMINANCE_MAX - LOG_LUMINANCE_MIN) / (TABLE_LEN - 1) as f64;

/// The three channels' sensitivities at one frequency; entry i at log10 Y =
/// `LOG_LUMINANCE_MIN + i LOG_LUMINANCE_STEP`.
#[derive(Clone, Debug, PartialEq)]
pub struct SensitivityTable {
    pub cpd: f32,
    pub achromatic: [f32; TABLE_LEN],
    pub red_green: [f32; TABLE_LEN],
    pub yellow_violet: [f32; TABLE_LEN],
}

impl SensitivityTable {
    /// The closed form (f64) at frequency `cpd`, each entry rounded to f32.
    pub fn new(cpd: f64) -> SensitivityTable {
        let mut t = SensitivityTable {
            cpd: cpd as f32,
            achromatic: [0.0; TABLE_LEN],
            red_green: [0.0; TABLE_LEN],
            yellow_violet: [0.0; TABLE_LEN],
        };
        for i in 0..TABLE_LEN {
            let y = 10f64.powf(LOG_LUMINANCE_MIN + i as f64 * LOG_LUMINANCE_STEP);
            let s = castle_csf::sensitivities(y, cpd);
            t.achromatic[i] = s.achromatic as f32;
            t.red_green[i] = s.red_green as f32;
            t.yellow_violet[i] = s.yellow_violet as f32;
        }
        t
    }

    /// The sensitivities at `log_y`, linear in log Y between entries, held at the ends.
    pub fn lookup(&self, log_y: f32) -> Sensitivities<f32> {
        let x = ((log_y - LOG_LUMINANCE_MIN as f32) / LOG_LUMINANCE_STEP as f32)
            .clamp(0.0, (TABLE_LEN - 1) as f32);
        let i = (x as usize).min(TABLE_LEN - 2);
        let t = x - i as f32;
        let lerp = |a: &[f32; TABLE_LEN]| a[i] + t * (a[i + 1] - a[i]);
        Sensitivities {
            achromatic: lerp(&self.achromatic),
            red_green: lerp(&self.red_green),
            yellow_violet: lerp(&self.yellow_violet),
        }
    }
}

/// Everything a frame's evaluation of c' needs, in f32.
#[derive(Clone, Debug, PartialEq)]
pub struct PerceptualTables {
    /// Linear RGB -> CIE 2006 LMS (the XYZ matrices' product, rounded once).
    pub rgb_to_lms: [[f32; 3]; 3],
    /// Linear RGB -> luminance Y (the XYZ matrix's middle row).
    pub rgb_to_luminance: [f32; 3],
    /// P and t W (cd/m^2).
    pub display_peak_nits: f32,
    pub world_nits_at_eye: f32,
    /// log10 of the luminance floor.
    pub log_min_luminance: f32,
    pub target_contrast: f32,
    /// One table per frequency of the frame; c' is the mean over them.
    pub frequencies: Vec<SensitivityTable>,
}

fn mul3(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

fn apply(m: &[[f32; 3]; 3], v: Vec3) -> [f32; 3] {
    m.map(|r| r[0] * v.x + r[1] * v.y + r[2] * v.z)
}

impl PerceptualTables {
    /// The tables of a frame's model.
    pub fn new(model: &Model) -> PerceptualTables {
        let rgb_to_lms = mul3(&XYZ_TO_LMS, &LINEAR_TO_XYZ).map(|r| r.map(|v| v as f32));
        PerceptualTables {
            rgb_to_lms,
            rgb_to_luminance: LINEAR_TO_XYZ[1].map(|v| v as f32),
            display_peak_nits: model.light.display_peak_nits as f32,
            world_nits_at_eye: model.light.world_nits_at_eye as f32,
            log_min_luminance: model
                .min_luminance
                .clamp(LUMINANCE_MIN, LUMINANCE_MAX)
                .log10() as f32,
            target_contrast: model.target_contrast as f32,
            frequencies: model
                .frequencies
                .cpd()
                .iter()
                .map(|&f| SensitivityTable::new(f))
                .collect(),
        }
    }

    /// The pattern linear display colour `display` makes over the linear, unattenuated
    /// background `background`: its cone responses' mean and amplitude, and its mean luminance Y.
    pub fn pattern(&self, display: Vec3, background: Vec3) -> ([f32; 3], [f32; 3], f32) {
        let lms_d = apply(&self.rgb_to_lms, display);
        let lms_b = apply(&self.rgb_to_lms, background);
        let amplitude = lms_d.map(|v| 0.5 * self.display_peak_nits * v);
        let mean: [f32; 3] =
            std::array::from_fn(|i| self.world_nits_at_eye * lms_b[i] + amplitude[i]);
        let lum = Vec3::from(self.rgb_to_luminance);
        let y = self.world_nits_at_eye * lum.dot(background)
            + 0.5 * self.display_peak_nits * lum.dot(display);
        (mean, amplitude, y)
    }

    /// c' of linear display colour `display` over the linear, unattenuated background
    /// `background`, in f32: 3 lookups per frequency and a few dozen operations.
    pub fn perceived_contrast(&self, display: Vec3, background: Vec3) -> f32 {
        let (mean, amplitude, y) = self.pattern(display, background);
        let log_y = y.log10().max(self.log_min_luminance);
        let c = rms_cone_contrast(mean, amplitude);
        let sum: f32 = self
            .frequencies
            .iter()
            .map(|t| {
                kulikowski(
                    c,
                    castle_csf::threshold_multiple(mean, amplitude, t.lookup(log_y)),
                )
            })
            .sum();
        sum / self.frequencies.len() as f32
    }
}
