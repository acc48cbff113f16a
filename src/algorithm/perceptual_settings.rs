//! The perceptual model's settings (docs/algorithm.md, *The perceptual method*): plain values,
//! which `Params` holds like every other setting. Below the model (`perception/`), which reads
//! them; reading them from the config, the environment and the command line is not this
//! module's job.

/// The `frequency` setting: at which spatial frequency contrast is judged (docs/algorithm.md,
/// *Which frequency*; `perception::frequency` resolves it for a frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Frequency {
    /// The frequency the background's Gaussian blur halves, from the blur's size in degrees of
    /// view (the default).
    Blur,
    /// The mean of c' over the four frequencies of an image ensemble
    /// (`perception::frequency::ENSEMBLE_CPD`).
    Ensemble,
    /// A fixed frequency in cycles per degree, used as given.
    Cpd(f64),
}

impl Frequency {
    /// The setting's text: `blur`, `ensemble` or a number of cpd.
    pub fn parse(text: &str) -> Result<Frequency, String> {
        match text.trim() {
            "blur" => Ok(Frequency::Blur),
            "ensemble" => Ok(Frequency::Ensemble),
            t => match t.parse::<f64>() {
                Ok(f) => Ok(Frequency::Cpd(f)),
                Err(_) => Err(format!(
                    "{t:?} is not blur, ensemble or a number of cycles per degree"
                )),
            },
        }
    }

    /// The text [`Frequency::parse`] reads back.
    pub fn name(&self) -> String {
        match self {
            Frequency::Blur => "blur".into(),
            Frequency::Ensemble => "ensemble".into(),
            Frequency::Cpd(f) => f.to_string(),
        }
    }
}

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
    /// The perceived contrast c' at which content counts as visible enough, in (0, 1]; 1 is
    /// never reached (c' < 1 always), so every pixel spends the paper's whole change. (0 would
    /// count every pixel as visible enough: the method would change nothing.)
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
        if !(self.target_contrast > 0.0 && self.target_contrast <= 1.0) {
            return Err(format!(
                "target_contrast must be in (0, 1], got {}",
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
                target_contrast: 0.0,
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
        let edges = [
            PerceptualSettings {
                target_contrast: 1.0,
                world_nits: 0.0,
                min_luminance: LUMINANCE_MIN,
                ..ok
            },
            PerceptualSettings {
                min_luminance: LUMINANCE_MAX,
                frequency: Frequency::Cpd(0.5),
                ..ok
            },
        ];
        for s in edges {
            assert_eq!(s.validate(), Ok(()), "{s:?}");
        }
    }

    #[test]
    fn frequency_text_round_trips() {
        for f in [
            Frequency::Blur,
            Frequency::Ensemble,
            Frequency::Cpd(4.0),
            Frequency::Cpd(2.5),
        ] {
            assert_eq!(Frequency::parse(&f.name()), Ok(f));
        }
        assert_eq!(Frequency::parse(" 8 "), Ok(Frequency::Cpd(8.0)));
        assert_eq!(Frequency::Cpd(4.0).name(), "4");
        assert!(Frequency::parse("sharp").is_err());
        assert!(Frequency::parse("").is_err());
    }
}
