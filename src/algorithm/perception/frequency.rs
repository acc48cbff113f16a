//! Which spatial frequency the contrast sensitivities are taken at (docs/algorithm.md, *Which
//! frequency*): from the background's blur, an ensemble of image frequencies, or a fixed number
//! of cycles per degree. Pure.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
pub use crate::algorithm::perceptual_settings::Frequency;

/// A view's pixels per degree where nothing says otherwise (the command line's default).
pub const DEFAULT_PIXELS_PER_DEGREE: f64 = 20.0;

/// The midpoints (cpd) of four bands of equal probability of a 1/f^1.8 amplitude spectrum over
/// 1 to 30 cpd: the frequency distribution of images.
pub const ENSEMBLE_CPD: [f64; 4] = [1.1679, 1.7145, 2.9920, 8.3785];

/// The range `Blur` is clamped to (cpd). Below 1 cpd a 1 deg^2 patch makes every contrast
/// invisible, which says nothing useful; 30 cpd is about the eye's resolution limit, and what
/// an unblurred background gives.
pub const BLUR_CPD_MIN: f64 = 1.0;
pub const BLUR_CPD_MAX: f64 = 30.0;

/// The frequency at which a Gaussian of sigma 1 degree halves a grating's amplitude:
/// exp(-2 pi^2 sigma^2 f^2) = 1/2 gives f = sqrt(ln 2 / 2) / (pi sigma).
pub fn blur_halving_cpd_deg() -> f64 {
    (std::f64::consts::LN_2 / 2.0).sqrt() / std::f64::consts::PI
}

/// The background's blur, as the view sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlurGeometry {
    /// The Gaussian's sigma in camera pixels (0 when the background is not blurred).
    pub sigma_camera_px: f64,
    /// How many display pixels one camera pixel covers.
    pub display_px_per_camera_px: f64,
    /// The view's display pixels per degree.
    pub pixels_per_degree: f64,
}

impl BlurGeometry {
    /// The blur of `params` in a view `display_width` pixels wide with `pixels_per_degree`,
    /// over a camera frame `camera_width` pixels wide placed by the manual FoV mapping
    /// (`Params::fov_mapping`, as the command line places it): the view's width covers
    /// `fov_scale.x` of the camera's, so one camera pixel spans `display_width / (fov_scale.x
    /// camera_width)` display pixels. Sigma 0 without blur.
    pub fn manual(
        params: &Params,
        display_width: u32,
        camera_width: u32,
        pixels_per_degree: f64,
    ) -> BlurGeometry {
        let blurred = params.blur && params.blur_size > 1;
        let scale = f64::from(params.fov_mapping().0[0]);
        BlurGeometry {
            sigma_camera_px: if blurred {
                f64::from(params.blur_sigma)
            } else {
                0.0
            },
            display_px_per_camera_px: f64::from(display_width) / (scale * f64::from(camera_width)),
            pixels_per_degree,
        }
    }

    /// The blur of `params` in a view `display_width` pixels wide with `pixels_per_degree`,
    /// over a camera frame `camera_width` pixels wide placed by `mapping`: one camera pixel
    /// spans `display_width / (|d camera_u / d display_u| camera_width)` display pixels, the
    /// derivative taken at the view's centre (a projective mapping's scale varies across the
    /// view). Equal to [`manual`](Self::manual) for the manual mapping.
    pub fn of_view(
        params: &Params,
        mapping: &CameraMapping,
        display_width: u32,
        camera_width: u32,
        pixels_per_degree: f64,
    ) -> BlurGeometry {
        let [a, b, c] = mapping.rows[0];
        let [g, h, i] = mapping.rows[2];
        let (u, v) = (0.5, 0.5);
        let z = g * u + h * v + i;
        let du = (a * z - g * (a * u + b * v + c)) / (z * z);
        BlurGeometry {
            display_px_per_camera_px: f64::from(display_width)
                / (du.abs() * f64::from(camera_width)),
            pixels_per_degree,
            ..BlurGeometry::unplaced(params)
        }
    }

    /// The blur of `params` where no view places it (one pixel's reference): one display
    /// pixel per camera pixel at [`DEFAULT_PIXELS_PER_DEGREE`].
    pub fn unplaced(params: &Params) -> BlurGeometry {
        let blurred = params.blur && params.blur_size > 1;
        BlurGeometry {
            sigma_camera_px: if blurred {
                f64::from(params.blur_sigma)
            } else {
                0.0
            },
            display_px_per_camera_px: 1.0,
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
        }
    }

    /// The blur's sigma in degrees of view.
    pub fn sigma_deg(&self) -> f64 {
        self.sigma_camera_px * self.display_px_per_camera_px / self.pixels_per_degree
    }

    /// `clamp(sqrt(ln 2 / 2) / (pi sigma_deg), 1, 30)`; 30 without blur.
    pub fn halving_cpd(&self) -> f64 {
        let f = blur_halving_cpd_deg() / self.sigma_deg();
        if f.is_nan() {
            BLUR_CPD_MAX
        } else {
            f.clamp(BLUR_CPD_MIN, BLUR_CPD_MAX)
        }
    }
}

/// The frequencies a frame's c' is averaged over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Frequencies {
    One(f64),
    Ensemble,
}

impl Frequencies {
    /// In cpd; c' is their mean.
    pub fn cpd(&self) -> &[f64] {
        match self {
            Frequencies::One(f) => std::slice::from_ref(f),
            Frequencies::Ensemble => &ENSEMBLE_CPD,
        }
    }
}

impl Frequency {
    /// The frequencies for a frame whose background has blur `blur`.
    pub fn resolve(self, blur: &BlurGeometry) -> Frequencies {
        match self {
            Frequency::Blur => Frequencies::One(blur.halving_cpd()),
            Frequency::Ensemble => Frequencies::Ensemble,
            Frequency::Cpd(f) => Frequencies::One(f),
        }
    }
}

/// `params` for one view of blur `blur`: its `frequency` setting, where `blur`, replaced by the
/// number of cycles per degree the view's blur gives, so that every pixel of the view (on the
/// GPU and in the CPU reference) is judged at the same frequency.
/// The frequency is rounded to a step of 2^(1/1024) (0.07 %), far below what moves c', so that
/// a view whose field of view jitters from frame to frame keeps its model (and the GPU tables
/// made from it).
pub fn for_view(params: &Params, blur: &BlurGeometry) -> Params {
    let mut out = params.clone();
    if let Frequency::Blur = params.perceptual.frequency {
        let steps = (blur.halving_cpd().log2() * 1024.0).round();
        out.perceptual.frequency = Frequency::Cpd((steps / 1024.0).exp2());
    }
    out
}

/// Where a view lies and how finely: what resolves the `blur` frequency for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewGeometry<'a> {
    pub mapping: &'a CameraMapping,
    pub display_width: u32,
    pub camera_width: u32,
    pub pixels_per_degree: f64,
}

/// The params of one view for the `perceptual` method: `params` with the `blur` frequency
/// resolved for the view's geometry, what the CPU reference of the view's pixels takes too.
pub fn view_params(params: &Params, view: &ViewGeometry) -> Params {
    let blur = BlurGeometry::of_view(
        params,
        view.mapping,
        view.display_width,
        view.camera_width,
        view.pixels_per_degree,
    );
    for_view(params, &blur)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_halving_constant_is_the_one_stated() {
        // 0.18738 as the docs round it.
        assert!((blur_halving_cpd_deg() - 0.18738).abs() < 2e-5);
        // At that frequency the Gaussian's transfer function is 1/2.
        let (sigma, f) = (0.3, blur_halving_cpd_deg() / 0.3);
        let mtf = (-2.0 * std::f64::consts::PI.powi(2) * sigma * sigma * f * f).exp();
        assert!((mtf - 0.5).abs() < 1e-12, "{mtf}");
    }

    #[test]
    fn blur_frequency_follows_the_blur_in_degrees_and_is_clamped() {
        // sigma 1.5 camera px, 2 display px per camera px, 20 ppd: 0.15 deg -> 1.2493 cpd.
        let g = BlurGeometry {
            sigma_camera_px: 1.5,
            display_px_per_camera_px: 2.0,
            pixels_per_degree: 20.0,
        };
        assert!((g.halving_cpd() - 0.18739 / 0.15).abs() < 1e-3);
        let wide = BlurGeometry {
            sigma_camera_px: 15.0,
            ..g
        };
        assert_eq!(wide.halving_cpd(), 1.0);
        let none = BlurGeometry {
            sigma_camera_px: 0.0,
            ..g
        };
        assert_eq!(none.halving_cpd(), 30.0);
        assert_eq!(Frequency::Cpd(4.0).resolve(&g), Frequencies::One(4.0));
        // The command line's default view: 640 display px over 0.65 of a 960 px camera frame,
        // sigma 1.5, 20 ppd: 1.5 * (640 / 624) / 20 = 0.076923 deg -> 2.4361 cpd.
        let manual = BlurGeometry::manual(&Params::default(), 640, 960, 20.0);
        assert!((manual.sigma_deg() - 0.0769231).abs() < 1e-6, "{manual:?}");
        assert!((manual.halving_cpd() - 2.43608).abs() < 1e-4, "{manual:?}");
        let unblurred = Params {
            blur: false,
            ..Params::default()
        };
        let manual = BlurGeometry::manual(&unblurred, 640, 960, 20.0);
        assert_eq!(manual.halving_cpd(), BLUR_CPD_MAX);
        // The manual mapping as a CameraMapping gives the same: 640 / (0.65 * 960) display px
        // per camera px.
        let p = Params::default();
        let view = BlurGeometry::of_view(&p, &p.camera_mapping(), 640, 960, 20.0);
        assert!(
            (view.display_px_per_camera_px - 640.0 / 624.0).abs() < 1e-6,
            "{view:?}"
        );
        // A projective mapping z = 0.5 u + 0.75 at the centre (z = 1): d cu / du = (2 * 1 -
        // 0.5 * (2 * 0.5 + 0)) / 1 = 1.5, so 600 / (1.5 * 800) = 0.5 display px per camera px.
        let projective = CameraMapping {
            rows: [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.5, 0.0, 0.75]],
        };
        let view = BlurGeometry::of_view(&p, &projective, 600, 800, 20.0);
        assert!(
            (view.display_px_per_camera_px - 0.5).abs() < 1e-12,
            "{view:?}"
        );
        let Frequency::Cpd(f) = for_view(&p, &view).perceptual.frequency else {
            panic!("blur not resolved");
        };
        assert!((f / view.halving_cpd() - 1.0).abs() < 4e-4, "{f}");
        // A view a hair wider keeps the same frequency.
        let wider = BlurGeometry {
            pixels_per_degree: view.pixels_per_degree * (1.0 + 1e-7),
            ..view
        };
        assert_eq!(for_view(&p, &wider).perceptual.frequency, Frequency::Cpd(f));
        assert_eq!(Frequency::Ensemble.resolve(&g).cpd(), &ENSEMBLE_CPD);
    }
}
