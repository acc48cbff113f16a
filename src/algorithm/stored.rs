//! How an image stores the method's output: what a linear colour reads back as once written
//! (docs/algorithm.md, Output encoding). The perceptual method judges the colour as stored,
//! so that a pixel it brings to the target is still at the target after the image's rounding.

use glam::DVec3;

use crate::colour;

/// The stored encoding of an image's colour channels, as the GPU engine's `quantised()` in
/// shaders/enhance.wgsl reads them back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Stored {
    /// 8-bit sRGB codes (sRGB swapchains, PNG images): the default.
    #[default]
    Srgb8,
    /// Linear values in `levels + 1` steps (255 for UNORM8, 1023 for RGB10A2, 65535 for RGBA16).
    Unorm(u32),
    /// Kept as computed (float16 is taken as exact, as the engine does).
    Exact,
}

impl Stored {
    /// The encoded value of each channel of linear `c` (clipped to [0, 1]) in code values,
    /// before rounding; None where nothing is rounded.
    fn codes(self, c: DVec3) -> Option<DVec3> {
        let c = c.clamp(DVec3::ZERO, DVec3::ONE);
        match self {
            Stored::Srgb8 => Some(255.0 * DVec3::from_array(c.to_array().map(colour::srgb_encode))),
            Stored::Unorm(levels) => Some(f64::from(levels) * c),
            Stored::Exact => None,
        }
    }

    /// Linear `c` (each channel in [0, 1]) as it reads back once stored.
    pub fn read_back(self, c: DVec3) -> DVec3 {
        match self {
            Stored::Srgb8 => {
                DVec3::from_array(colour::linear_to_srgb8(c).map(colour::code_to_linear))
            }
            Stored::Unorm(levels) => {
                let levels = f64::from(levels);
                (levels * c.clamp(DVec3::ZERO, DVec3::ONE) + 0.5).floor() / levels
            }
            Stored::Exact => c,
        }
    }

    /// How far (in code values) the closest channel of `c` is from a rounding boundary
    /// (k + 0.5): near one, float32 may round the other way. Infinite where nothing is rounded.
    pub fn rounding_margin(self, c: DVec3) -> f64 {
        self.codes(c).map_or(f64::INFINITY, |codes| {
            codes
                .to_array()
                .iter()
                .map(|v| (v - v.floor() - 0.5).abs())
                .fold(f64::INFINITY, f64::min)
        })
    }
}
