//! One display pixel end to end: 8-bit sRGB -> linear -> scaled -> method -> back
//! (docs/algorithm.md, Per-pixel optimisation and Output encoding).

use glam::DVec3;

use super::conformance::{PixelTrace, NEAR_THRESHOLD};
use super::constraints::Margin;
use super::params::{Params, SUBTRACTION_K_B, SUBTRACTION_K_V};
use super::reference_fn::Reference;
use super::scaled::enhance_scaled_traced;
use crate::colour;

/// Linear result with the smallest branch margin (scaled units; infinite when no branch ran).
struct LinearOutcome {
    /// Before the [0, 1] clip.
    unclipped: DVec3,
    margin: f64,
    /// The luminance cap's factor on the clipped colour (1 when off or not reached).
    cap_scale: f64,
}

impl LinearOutcome {
    fn linear(&self) -> DVec3 {
        self.unclipped.clamp(DVec3::ZERO, DVec3::ONE) * self.cap_scale
    }
}

/// The optional cap beyond the paper: the factor that keeps the clipped output's luminance Y
/// at most (1 + cap) times the display's (display power never rises beyond that fraction).
fn luminance_cap_scale(display_linear: DVec3, unclipped: DVec3, cap: f32) -> f64 {
    if cap <= 0.0 {
        return 1.0;
    }
    let limit = (1.0 + f64::from(cap)) * colour::linear_to_xyz(display_linear).y;
    let y = colour::linear_to_xyz(unclipped.clamp(DVec3::ZERO, DVec3::ONE)).y;
    if y > limit {
        limit / y
    } else {
        1.0
    }
}

/// A pixel that is exactly black or fully transparent is transparent on an additive display.
fn is_skipped(display_linear: DVec3, alpha: f64) -> bool {
    alpha == 0.0 || display_linear == DVec3::ZERO
}

/// The method on one content pixel; `traced`: with the margins the conformance trace needs
/// (otherwise `margin` may be left infinite).
fn enhance_linear_traced(
    display_linear: DVec3,
    bg_linear: DVec3,
    bg_scaled: DVec3,
    params: &Params,
    traced: bool,
) -> LinearOutcome {
    if let Reference::Linear(method) = params.method.entry().reference {
        let unclipped = method(display_linear, bg_linear, params);
        return LinearOutcome {
            unclipped,
            margin: f64::INFINITY,
            cap_scale: luminance_cap_scale(display_linear, unclipped, params.luminance_cap),
        };
    }
    let display = colour::linear_to_scaled(display_linear);
    let out = enhance_scaled_traced(display, bg_scaled, params);
    // P == D (lambda_e = 0, mid grey background, ...) skips the LAB round trip, so that "no
    // change" is bit-exact.
    let unclipped = if out.p == display {
        display_linear
    } else {
        colour::scaled_to_linear(out.p)
    };
    let scaled = LinearOutcome {
        unclipped,
        margin: out.margin,
        cap_scale: luminance_cap_scale(display_linear, unclipped, params.luminance_cap),
    };
    match params.method.entry().reference {
        // The paper's output is this method's budget (enhance_scaled_traced ran the paper).
        Reference::Perceptual(method) => {
            let mut m = Margin(scaled.margin);
            let trace = traced.then_some(&mut m);
            let out = method(display_linear, bg_linear, scaled.linear(), params, trace);
            LinearOutcome {
                unclipped: out,
                margin: m.0,
                cap_scale: 1.0,
            }
        }
        _ => scaled,
    }
}

/// `subtraction` (Weiland et al. 2009), the linear-light reference its entry names: k_v x the
/// display minus k_b x the unattenuated background, before the clip.
pub(super) fn subtraction(display_linear: DVec3, bg_linear: DVec3, _: &Params) -> DVec3 {
    let k_v = f64::from(SUBTRACTION_K_V);
    let k_b = f64::from(SUBTRACTION_K_B);
    k_v * display_linear - k_b * bg_linear
}

/// The method on one pixel in linear light. `bg_linear` is the blurred, FoV-mapped,
/// unattenuated background (for subtraction), `bg_scaled` the paper's B.
/// None: the pixel is skipped (exactly black or alpha 0) and must be left untouched.
/// Otherwise the new linear colour, each channel clipped to [0, 1].
pub fn enhance_linear(
    display_linear: DVec3,
    alpha: f64,
    bg_linear: DVec3,
    bg_scaled: DVec3,
    params: &Params,
) -> Option<DVec3> {
    if is_skipped(display_linear, alpha) {
        return None;
    }
    Some(enhance_linear_traced(display_linear, bg_linear, bg_scaled, params, false).linear())
}

/// The method on one 8-bit RGBA pixel; alpha passes through, a skipped pixel comes back as is.
pub fn enhance_srgb8(
    display: [u8; 4],
    bg_linear: DVec3,
    bg_scaled: DVec3,
    params: &Params,
) -> [u8; 4] {
    srgb8_outcome(display, bg_linear, bg_scaled, params, false).out
}

/// `enhance_srgb8` with what the GPU conformance test needs to judge a difference.
/// `params.stored` should be `Stored::Srgb8` (the default), as the pixel is.
pub fn enhance_srgb8_trace(
    display: [u8; 4],
    bg_linear: DVec3,
    bg_scaled: DVec3,
    params: &Params,
) -> PixelTrace {
    srgb8_outcome(display, bg_linear, bg_scaled, params, true)
}

fn srgb8_outcome(
    display: [u8; 4],
    bg_linear: DVec3,
    bg_scaled: DVec3,
    params: &Params,
    traced: bool,
) -> PixelTrace {
    let display_linear = colour::srgb8_to_linear([display[0], display[1], display[2]]);
    let unchanged = || PixelTrace {
        out: display,
        exact: [0, 1, 2].map(|i| f64::from(display[i]) / 255.0),
        linear: display_linear.to_array(),
        near_threshold: false,
    };
    if is_skipped(display_linear, f64::from(display[3])) {
        return unchanged();
    }
    let out = enhance_linear_traced(display_linear, bg_linear, bg_scaled, params, traced);
    let near_threshold = out.margin < NEAR_THRESHOLD;
    if out.unclipped == display_linear {
        return PixelTrace {
            near_threshold,
            ..unchanged()
        };
    }
    let exact = out.linear().to_array().map(colour::srgb_encode);
    let q = exact.map(colour::quantize);
    PixelTrace {
        out: [q[0], q[1], q[2], display[3]],
        exact,
        linear: out.unclipped.to_array(),
        near_threshold,
    }
}
