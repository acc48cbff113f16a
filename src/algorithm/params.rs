//! The method's settings, shared by the CPU reference, the GPU engine, the CLI and the layer.

pub use super::method::Method;
use super::perceptual_settings::PerceptualSettings;
use super::stored::Stored;

/// What the layer shows (docs/control.md, Modes). `Enhance` is the product; the others are for
/// comparison and calibration while wearing the headset. Comparison methods are `Method`s.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewMode {
    /// The method's output (default).
    Enhance,
    /// The app's frames untouched (no GPU work).
    Off,
    /// Left half of each view original, right half enhanced, with a thin divider.
    Split,
    /// The paper's cyan on enhanced pixels.
    Heatmap,
    /// The preprocessed background as the layer sees it (FoV calibration).
    Background,
}

impl ViewMode {
    pub const ALL: [ViewMode; 5] = [
        ViewMode::Enhance,
        ViewMode::Off,
        ViewMode::Split,
        ViewMode::Heatmap,
        ViewMode::Background,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ViewMode::Enhance => "enhance",
            ViewMode::Off => "off",
            ViewMode::Split => "split",
            ViewMode::Heatmap => "heatmap",
            ViewMode::Background => "background",
        }
    }

    pub fn parse(name: &str) -> Option<ViewMode> {
        ViewMode::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// Subtraction method gains (docs/algorithm.md, Comparison methods): k_v on the display, k_b on
/// the background.
pub const SUBTRACTION_K_V: f32 = 1.0;
pub const SUBTRACTION_K_B: f32 = 0.4;

/// Every setting of the method. Defaults are the paper's (docs/algorithm.md, Defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Maximum colour change in the scaled space (the paper's lambda'_E).
    pub lambda_e: f32,
    /// JND sphere radius in the scaled space (2.3 / 50).
    pub lambda_jnd_scaled: f32,
    /// Lens transmittance applied to the background in linear light (0.4 = 60% attenuation).
    pub transmittance: f32,
    /// Gaussian kernel size in camera pixels (odd; 1 = no blur).
    pub blur_size: u32,
    pub blur_sigma: f32,
    /// False: no blur (`--no-blur`), whatever `blur_size` says.
    pub blur: bool,
    /// camera_uv = fov_scale * display_uv + fov_offset.
    pub fov_scale: [f32; 2],
    pub fov_offset: [f32; 2],
    /// False: camera_uv = display_uv (`--no-fov`).
    pub fov: bool,
    pub method: Method,
    /// What the layer shows; the CPU reference and the CLI implement `Enhance` only.
    pub mode: ViewMode,
    /// Beyond the paper (its first limitation): on a near-grey background the complementary
    /// direction is mostly luminance, which the luminance constraint suppresses. With a boost
    /// in (0, 1], the paper method also raises the display colour's own chroma there, by up to
    /// this fraction of the room left under lambda_e. 0 = off (the paper's method exactly).
    pub achromatic_boost: f32,
    /// Beyond the paper (its second limitation): the output's luminance Y is at most
    /// (1 + luminance_cap) times the input's, scaling the colour down if needed. 0 = off.
    pub luminance_cap: f32,
    /// Beyond the paper: how bright the display and the world are, the contrast that is
    /// enough and the frequency it is judged at, for the perceptual model
    /// (docs/algorithm.md, *The perceptual method*). f64, as the model's CPU reference takes
    /// them.
    pub perceptual: PerceptualSettings,
    /// How the image stores the output: the perceptual method judges the colour as stored. The
    /// GPU engine takes it from the image's format; the CPU reference from here.
    pub stored: Stored,
}

/// Background chroma (scaled a'b' length, ~10 a*b* units) below which it counts as near grey.
pub const ACHROMATIC_CHROMA: f64 = 0.08;

impl Default for Params {
    fn default() -> Self {
        Params {
            lambda_e: 0.4,
            lambda_jnd_scaled: 0.046,
            transmittance: 0.4,
            blur_size: 3,
            blur_sigma: 1.5,
            blur: true,
            fov_scale: [0.65, 0.65],
            fov_offset: [0.13, 0.17],
            fov: true,
            method: Method::Paper,
            mode: ViewMode::Enhance,
            achromatic_boost: 0.0,
            luminance_cap: 0.0,
            perceptual: PerceptualSettings::default(),
            stored: Stored::Srgb8,
        }
    }
}

/// Largest supported blur kernel (taps); the shaders hold this many weights.
pub const MAX_BLUR_SIZE: u32 = 15;

impl Params {
    /// The normalised 1-D Gaussian taps at offsets -(n/2)..=(n/2); `[1.0]` without blur.
    /// The 2-D kernel exp(-(x^2+y^2)/(2 sigma^2)) is separable, so the product of two of these
    /// equals the renormalised 2-D kernel of docs/algorithm.md, Gaussian blur.
    pub fn blur_taps(&self) -> Vec<f64> {
        if !self.blur || self.blur_size <= 1 {
            return vec![1.0];
        }
        let half = (self.blur_size.min(MAX_BLUR_SIZE) / 2) as i32;
        let sigma = f64::from(self.blur_sigma);
        let raw: Vec<f64> = (-half..=half)
            .map(|x| (-(f64::from(x * x)) / (2.0 * sigma * sigma)).exp())
            .collect();
        let sum: f64 = raw.iter().sum();
        raw.into_iter().map(|w| w / sum).collect()
    }

    /// The FoV mapping actually applied: identity with `--no-fov`.
    pub fn fov_mapping(&self) -> ([f32; 2], [f32; 2]) {
        if self.fov {
            (self.fov_scale, self.fov_offset)
        } else {
            ([1.0, 1.0], [0.0, 0.0])
        }
    }

    /// The manual FoV mapping as a `CameraMapping` (identity with `--no-fov`).
    pub fn camera_mapping(&self) -> super::mapping::CameraMapping {
        let (scale, offset) = self.fov_mapping();
        super::mapping::CameraMapping::affine(scale.map(f64::from), offset.map(f64::from))
    }

    /// Checks ranges; the message names the setting.
    pub fn validate(&self) -> Result<(), String> {
        let finite = [
            ("lambda_e", self.lambda_e),
            ("lambda_jnd_scaled", self.lambda_jnd_scaled),
            ("transmittance", self.transmittance),
            ("blur_sigma", self.blur_sigma),
            ("fov_scale.x", self.fov_scale[0]),
            ("fov_scale.y", self.fov_scale[1]),
            ("fov_offset.x", self.fov_offset[0]),
            ("fov_offset.y", self.fov_offset[1]),
            ("achromatic_boost", self.achromatic_boost),
            ("luminance_cap", self.luminance_cap),
        ];
        for (name, v) in finite {
            if !v.is_finite() {
                return Err(format!("{name} must be a finite number, got {v}"));
            }
        }
        if self.lambda_e < 0.0 {
            return Err(format!("lambda_e must be >= 0, got {}", self.lambda_e));
        }
        if self.lambda_jnd_scaled < 0.0 {
            return Err(format!(
                "lambda_jnd_scaled must be >= 0, got {}",
                self.lambda_jnd_scaled
            ));
        }
        if !(0.0..=1.0).contains(&self.achromatic_boost) {
            return Err(format!(
                "achromatic_boost must be in [0, 1], got {}",
                self.achromatic_boost
            ));
        }
        if self.luminance_cap < 0.0 {
            return Err(format!(
                "luminance_cap must be >= 0 (0 = off), got {}",
                self.luminance_cap
            ));
        }
        if !(0.0..=1.0).contains(&self.transmittance) {
            return Err(format!(
                "transmittance must be in [0, 1], got {}",
                self.transmittance
            ));
        }
        if self.blur && (self.blur_size.is_multiple_of(2) || self.blur_size > MAX_BLUR_SIZE) {
            return Err(format!(
                "blur_size must be odd and at most {MAX_BLUR_SIZE}, got {}",
                self.blur_size
            ));
        }
        if self.blur && self.blur_size > 1 && self.blur_sigma <= 0.0 {
            return Err(format!("blur_sigma must be > 0, got {}", self.blur_sigma));
        }
        self.perceptual.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_taps_match_spec() {
        let taps = Params::default().blur_taps();
        let want = [0.307801, 0.384397, 0.307801];
        for (t, w) in taps.iter().zip(want) {
            assert!((t - w).abs() < 1e-6, "{taps:?}");
        }
    }

    #[test]
    fn method_names_round_trip() {
        for m in Method::ALL {
            assert_eq!(Method::parse(m.name()), Some(m));
        }
        assert_eq!(Method::parse("nope"), None);
    }
}
