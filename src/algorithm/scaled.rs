//! The per-pixel methods in the scaled space: Algorithm 1 (docs/algorithm.md, Per-pixel
//! optimisation) and the paper's comparison methods (docs/algorithm.md, Comparison methods).

use glam::DVec3;

use super::constraints::DIRECTION_EPSILON;
use super::constraints::{
    ab_plane, change_vector, chroma_constraint, jnd_constraint, luminance_constraint, split_chroma,
    Margin,
};
use super::params::{Params, ACHROMATIC_CHROMA};
use super::reference_fn::Reference;

/// P and how close the computation came to a branch flip.
#[derive(Clone, Copy, Debug)]
pub struct ScaledOutcome {
    /// The optimal displayed colour, scaled space, before any clipping.
    pub p: DVec3,
    /// Smallest |quantity - threshold| over the branch conditions evaluated (scaled units).
    pub margin: f64,
}

/// The method's P for display colour D on background B (both scaled): its entry's scaled
/// reference (src/algorithm/method/table.rs) where there is a change vector E. A method in
/// linear light (subtraction; see `enhance_linear`) returns D unchanged here.
pub fn enhance_scaled(display: DVec3, background: DVec3, params: &Params) -> DVec3 {
    enhance_scaled_traced(display, background, params).p
}

pub fn enhance_scaled_traced(display: DVec3, background: DVec3, params: &Params) -> ScaledOutcome {
    let mut m = Margin::new();
    let lambda_e = f64::from(params.lambda_e);
    let p = match (
        change_vector(display, background, lambda_e, &mut m),
        params.method.entry().reference,
    ) {
        (Some(e), Reference::Scaled(method)) => method(display, background, e, params, &mut m),
        // A perceptual method spends the paper's change (src/algorithm/pixel.rs).
        (Some(e), Reference::Perceptual(_)) => paper(display, background, e, params, &mut m),
        _ => display,
    };
    ScaledOutcome { p, margin: m.0 }
}

// The methods' scaled references, as their entries in method/table.rs name them: P from D, B
// and E.

/// Algorithm 1: the chroma and luminance constraints shape E into dir; P = D + dir; then JND.
pub(super) fn paper(
    display: DVec3,
    background: DVec3,
    e: DVec3,
    params: &Params,
    m: &mut Margin,
) -> DVec3 {
    let dir_ab = chroma_constraint(display, e, m);
    let dir = DVec3::new(luminance_constraint(e), dir_ab.y, dir_ab.z);
    let p = achromatic_boost(display, display + dir, background, params, m);
    let r = f64::from(params.lambda_jnd_scaled);
    jnd_constraint(display, p, background, r, m)
}

/// The optional boost beyond the paper: on a near-grey background, move P further along the
/// display colour's own chroma direction by `achromatic_boost` x (the room left under lambda_e),
/// fading out as the background's chroma reaches ACHROMATIC_CHROMA. |P - D| stays <= lambda_e
/// (triangle inequality) and chroma only grows.
fn achromatic_boost(
    display: DVec3,
    p: DVec3,
    background: DVec3,
    params: &Params,
    m: &mut Margin,
) -> DVec3 {
    let boost = f64::from(params.achromatic_boost);
    if boost <= 0.0 {
        return p;
    }
    let b_chroma = ab_plane(background).length();
    let d_ab = ab_plane(display);
    let d_chroma = d_ab.length();
    m.note(b_chroma, ACHROMATIC_CHROMA);
    m.note(d_chroma, DIRECTION_EPSILON);
    if b_chroma >= ACHROMATIC_CHROMA || d_chroma <= DIRECTION_EPSILON {
        return p;
    }
    let room = (f64::from(params.lambda_e) - (p - display).length()).max(0.0);
    p + boost * (1.0 - b_chroma / ACHROMATIC_CHROMA) * room * (d_ab / d_chroma)
}

/// E'_h, the hue part of E'. For an achromatic D all of E' counts as hue change, as in the
/// paper method's achromatic branch (dir.ab = E'.ab).
fn hue_change(display: DVec3, e: DVec3, m: &mut Margin) -> DVec3 {
    split_chroma(display, e, m).map_or(ab_plane(e), |s| s.hue)
}

/// `hue-only`: P = D + E'_h.
pub(super) fn hue_only(display: DVec3, _: DVec3, e: DVec3, _: &Params, m: &mut Margin) -> DVec3 {
    display + hue_change(display, e, m)
}

/// `other-hue`: P = D - E'_h.
pub(super) fn other_hue(display: DVec3, _: DVec3, e: DVec3, _: &Params, m: &mut Margin) -> DVec3 {
    display - hue_change(display, e, m)
}

/// Luminance and chroma only: |E'_h| along OD (away from mid grey).
pub(super) fn lum_chroma(display: DVec3, _: DVec3, e: DVec3, _: &Params, m: &mut Margin) -> DVec3 {
    let len = display.length();
    m.note(len, DIRECTION_EPSILON);
    if len <= DIRECTION_EPSILON {
        return display;
    }
    display + hue_change(display, e, m).length() * (display / len)
}

/// `luminance`: only L' moves, away from B's L', by lambda_e, and stays in [-1, 1] (L* in
/// [0, 100]); a' and b' (hue and chroma) are kept. Where D's L' equals B's it moves toward the
/// side with more room: up where L'_D <= 0, else down (docs/algorithm.md, Comparison methods).
pub(super) fn luminance(
    display: DVec3,
    background: DVec3,
    _: DVec3,
    params: &Params,
    m: &mut Margin,
) -> DVec3 {
    let above = display.x - background.x;
    m.note(above, 0.0);
    let up = if above == 0.0 {
        display.x <= 0.0
    } else {
        above > 0.0
    };
    let step = f64::from(params.lambda_e);
    let l = display.x + if up { step } else { -step };
    DVec3::new(l.clamp(-1.0, 1.0), display.y, display.z)
}
