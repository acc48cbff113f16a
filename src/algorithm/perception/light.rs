//! The physical light of a pixel (docs/algorithm.md, *Light and contrast*): the display's and
//! the world's light in cd/m^2 (CIE XYZ, then CIE 2006 cone responses), and the pattern a
//! content edge makes on an additive display, alternating between the world alone and the world
//! plus the display. Pure; f64.

use glam::DVec3;

use crate::colour;

/// CIE XYZ -> CIE 2006 LMS (2 degree) cone responses.
pub const XYZ_TO_LMS: [[f64; 3]; 3] = [
    [0.187596, 0.585169, -0.026384],
    [-0.133397, 0.405506, 0.034502],
    [0.000244, -0.000543, 0.019407],
];

/// Cone responses of an XYZ colour.
pub fn lms(xyz: DVec3) -> [f64; 3] {
    XYZ_TO_LMS.map(|r| r[0] * xyz.x + r[1] * xyz.y + r[2] * xyz.z)
}

/// How bright the two lights are: the display's peak and the world behind the lens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// P: the luminance (cd/m^2) of display colour (1, 1, 1).
    pub display_peak_nits: f64,
    /// t W: the luminance that the camera's linear 1.0 stands for, as it reaches the eye through
    /// a lens of transmittance t.
    pub world_nits_at_eye: f64,
}

impl Light {
    /// The display's light, XYZ in cd/m^2, of linear display colour `display`: P M D.
    pub fn display_xyz(&self, display: DVec3) -> DVec3 {
        self.display_peak_nits * colour::linear_to_xyz(display)
    }

    /// The world's light at the eye, XYZ in cd/m^2, of the linear (unattenuated) background
    /// `background`: t W M B.
    pub fn world_xyz(&self, background: DVec3) -> DVec3 {
        self.world_nits_at_eye * colour::linear_to_xyz(background)
    }

    /// The content's edge as a pattern alternating between tB and tB + D.
    pub fn pattern(&self, display: DVec3, background: DVec3) -> Pattern {
        let d = self.display_xyz(display);
        let b = self.world_xyz(background);
        let (lms_d, lms_b) = (lms(d), lms(b));
        Pattern {
            mean: [0, 1, 2].map(|i| lms_b[i] + lms_d[i] / 2.0),
            amplitude: lms_d.map(|v| v / 2.0),
            luminance: b.y + d.y / 2.0,
        }
    }
}

/// A pattern alternating between two lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pattern {
    /// Cone responses of its mean, LMS_B + LMS_D / 2.
    pub mean: [f64; 3],
    /// Cone responses of its amplitude, LMS_D / 2.
    pub amplitude: [f64; 3],
    /// The luminance of its mean (cd/m^2): Y of the mean's XYZ, Y_tB + Y_D / 2. The contrast
    /// sensitivities are taken at it.
    pub luminance: f64,
}
