//! The perceptual model's settings (docs/algorithm.md, *The perceptual method*): plain values;
//! reading them from the config, the environment and the command line is not this module's job.

use super::frequency::Frequency;

/// The lowest luminance floor (cd/m^2) the model accepts: the lower end of the GPU's tables
/// (log10 Y = -1), clear of the transient weight's jump at 0.0113 cd/m^2.
pub const LUMINANCE_MIN: f64 = 0.1;

/// The luminance (cd/m^2) above which the sensitivities are held at their value there: the
/// upper end of the GPU's tables (log10 Y = 4.5). Beyond the closed form, which has no upper
/// end; the model and the tables then agree everywhere. Only a world brighter than about
/// 30 000 cd/m^2 at the eye (direct sunlight on snow) reaches it.
pub const LUMINANCE_MAX: f64 = 31622.776601683792;

/// How bright the display and the world are, how much contrast is enough, and at which spatial
/// frequency contrast is judged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerceptualSettings {
    /// P: the luminance (cd/m^2) of display colour (1, 1, 1). > 0.
    pub display_peak_nits: f64,
    /// W: the world luminance (cd/m^2) the camera's linear 1.0 stands for, before the lens. >= 0.
    pub world_nits: f64,
    /// The perceived contrast c' at which content counts as visible enough, in [0, 1]; 1 is
    /// never reached (c' < 1 always), so every pixel spends the paper's whole change.
    pub target_contrast: f64,
    /// The floor (cd/m^2) on the luminance the sensitivities are taken at, in
    /// [`LUMINANCE_MIN`, `LUMINANCE_MAX`]: it keeps the model away from the jump of the
    /// transient channel's weight near 0.0113 cd/m^2.
    pub min_luminance: f64,
    pub frequency: Frequency,
}

impl Default for PerceptualSettings {
    fn default() -> Self {
        PerceptualSettings {
            display_peak_nits: 200.0,
            world_nits: 1000.0,
            target_contrast: 0.05,
            min_luminance: 0.1,
            frequency: Frequency::Blur,
        }
    }
}

impl PerceptualSettings {
    /// Checks ranges; the message names the setting.
    pub fn validate(&self) -> Result<(), String> {
        let finite = [
            ("display_peak_nits", self.display_peak_nits),
            ("world_nits", self.world_nits),
            ("target_contrast", self.target_contrast),
            ("min_luminance", self.min_luminance),
        ];
        for (name, v) in finite {
            if !v.is_finite() {
                return Err(format!("{name} must be a finite number, got {v}"));
            }
        }
        if self.display_peak_nits <= 0.0 {
            return Err(format!(
                "display_peak_nits must be > 0, got {}",
                self.display_peak_nits
            ));
        }
        if self.world_nits < 0.0 {
            return Err(format!("world_nits must be >= 0, got {}", self.world_nits));
        }
        if !(0.0..=1.0).contains(&self.target_contrast) {
            return Err(format!(
                "target_contrast must be in [0, 1], got {}",
                self.target_contrast
            ));
        }
        if !(LUMINANCE_MIN..=LUMINANCE_MAX).contains(&self.min_luminance) {
            return Err(format!(
                "min_luminance must be in [{LUMINANCE_MIN}, {LUMINANCE_MAX:.0}], got {}",
                self.min_luminance
            ));
        }
        if let Frequency::Cpd(f) = self.frequency {
            if !(f.is_finite() && f > 0.0) {
                return Err(format!(
                    "frequency must be blur, ensemble or a number of cpd > 0, got {f}"
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_ranges_are_checked() {
        let ok = PerceptualSettings::default();
        assert_eq!(ok.validate(), Ok(()));
        let bad = [
            PerceptualSettings {
                display_peak_nits: 0.0,
                ..ok
            },
            PerceptualSettings {
                world_nits: -1.0,
                ..ok
            },
            PerceptualSettings {
                target_contrast: 1.5,
                ..ok
            },
            PerceptualSettings {
                min_luminance: 0.01,
                ..ok
            },
            PerceptualSettings {
                frequency: Frequency::Cpd(0.0),
                ..ok
            },
            PerceptualSettings {
                world_nits: f64::NAN,
                ..ok
            },
        ];
        for s in bad {
            assert!(s.validate().is_err(), "{s:?}");
        }
    }
}
