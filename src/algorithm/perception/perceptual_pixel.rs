//! The perceptual method on one pixel, the CPU reference in f64 (docs/algorithm.md, *The
//! perceptual method*): leave a pixel that is visible enough; otherwise spend the paper's
//! colour change, in CIELAB, in the most visible of the paper's own colour and 18 fixed
//! directions, then come back toward the original to the least change that reaches the target.
//! It takes the paper method's output as given (`paper_output`, or `perceptual_over_paper`
//! which runs the paper's CPU reference); it knows nothing of images, the GPU or OpenXR.

use glam::DVec3;

use super::directions::DIRECTIONS;
use super::perceived_contrast::Model;
use crate::algorithm::conformance::{NEAR_ROUNDING, NEAR_THRESHOLD};
use crate::algorithm::constraints::Margin;
use crate::algorithm::params::{Method, Params};
use crate::algorithm::pixel::enhance_linear;
use crate::algorithm::stored::Stored;
use crate::colour;

/// Bisection steps from the kept candidate back toward the original colour.
pub const BISECTION_STEPS: u32 = 8;

/// How far (CIE76 Delta E) a candidate's change may exceed the budget and still count as within
/// it: the round trip CIELAB -> linear RGB -> CIELAB of an unclipped candidate is exact only
/// to about 1e-12.
pub const BUDGET_SLACK: f64 = 1e-6;

/// The relative tolerance of the GPU's threshold multiples C: its f32 sensitivity tables are
/// within 5e-4 of the closed form (src/algorithm/perception/tables.rs), and the colour
/// conversions add less. A pixel whose output changes when every C is scaled by 1 -+ this
/// may legitimately come out of the GPU as either (docs/algorithm.md, Conformance).
pub const THRESHOLD_TOLERANCE: f64 = 2e-3;

/// A candidate's CIELAB change closer to the budget than this (Delta E, plus the same
/// fraction of the budget) may be kept or dropped either way in f32.
pub const CHANGE_NEAR: f64 = 1e-3;

/// What the method did with a pixel (docs/algorithm.md, *What it reports*).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Class {
    /// Exactly black or alpha 0: no content, left exactly as it is.
    NoContent,
    /// c' of the original already reaches the target.
    LeftAlone,
    /// Changed to the least change (to 1/256 of the kept candidate's) that reaches the target.
    BroughtToTarget,
    /// The target is out of reach within the paper's change: the most visible candidate (or the
    /// pixel as it is, where the paper changes nothing).
    OutOfReach,
}

impl Class {
    /// The class of a content pixel from its c' before and after and the target: the method's
    /// own classes follow from these, so any method's output can be classed the same way.
    pub fn of(before: f64, after: f64, target: f64) -> Class {
        if before >= target {
            Class::LeftAlone
        } else if after >= target {
            Class::BroughtToTarget
        } else {
            Class::OutOfReach
        }
    }
}

/// The method's result for one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// Linear RGB, each channel in [0, 1] (the display colour itself where unchanged).
    pub output: DVec3,
    pub class: Class,
    /// c' of the display colour and of the output (0 for no content).
    pub perceived_before: f64,
    pub perceived_after: f64,
}

/// Linear RGB of a CIELAB colour, each channel clipped to [0, 1].
fn lab_to_clipped_linear(lab: DVec3) -> DVec3 {
    colour::xyz_to_linear(colour::lab_to_xyz(lab)).clamp(DVec3::ZERO, DVec3::ONE)
}

/// The perceptual method on linear display colour `display` (alpha `alpha`) over the linear,
/// unattenuated background `background`, given the paper method's output for the pixel
/// (`paper_output`, linear, as the paper's reference returns it: clipped to [0, 1]), its output
/// kept exact ([`Stored::Exact`]).
pub fn perceptual(
    display: DVec3,
    alpha: f64,
    background: DVec3,
    paper_output: DVec3,
    model: &Model,
) -> Outcome {
    let pixel = Pixel {
        display,
        alpha,
        background,
        paper_output,
    };
    perceptual_traced(&pixel, model, Stored::Exact, &mut Margin::new())
}

/// One pixel's inputs: the display colour, its alpha, the background and the paper's output.
struct Pixel {
    display: DVec3,
    alpha: f64,
    background: DVec3,
    paper_output: DVec3,
}

/// [`perceptual`] with the output as `stored` reads it back (the bisection judges that colour),
/// recording in `m` how close each of its decisions came to going the other way.
fn perceptual_traced(px: &Pixel, model: &Model, stored: Stored, m: &mut Margin) -> Outcome {
    let Pixel {
        display,
        alpha,
        background,
        paper_output,
    } = *px;
    if alpha == 0.0 || display == DVec3::ZERO {
        return Outcome {
            output: display,
            class: Class::NoContent,
            perceived_before: 0.0,
            perceived_after: 0.0,
        };
    }
    let target = model.target_contrast;
    let before = model.perceived_contrast(display, background);
    let unchanged = |class| Outcome {
        output: display,
        class,
        perceived_before: before,
        perceived_after: before,
    };
    if before >= target {
        return unchanged(Class::LeftAlone);
    }
    let d_lab = colour::linear_to_lab(display);
    let paper = paper_output.clamp(DVec3::ZERO, DVec3::ONE);
    let budget = colour::delta_e(d_lab, colour::linear_to_lab(paper));
    if budget == 0.0 {
        return unchanged(Class::OutOfReach);
    }

    // The paper's colour first, then the 18 directions at the paper's change. Clipping in linear
    // RGB is no projection in CIELAB and can lengthen a change (by up to about 1.9x); such a
    // candidate would change the pixel more than the paper does, so it is not a candidate
    // (docs/algorithm.md, *The method, per pixel*, step 4).
    let mut best = Candidate::new(paper, d_lab, background, model);
    for u in DIRECTIONS {
        let unclipped = colour::xyz_to_linear(colour::lab_to_xyz(d_lab + budget * u));
        let colour = unclipped.clamp(DVec3::ZERO, DVec3::ONE);
        let c = Candidate::new(colour, d_lab, background, model);
        if colour != unclipped {
            // In the scaled units of NEAR_THRESHOLD: a gap of CHANGE_NEAR (1 + budget) is at it.
            m.note(
                (c.change - budget).abs() * NEAR_THRESHOLD / (CHANGE_NEAR * (1.0 + budget)),
                0.0,
            );
        }
        if c.change > budget + BUDGET_SLACK {
            continue;
        }
        // Changes within the slack are equal: unclipped, every candidate's is the budget.
        let smaller = c.change < best.change - BUDGET_SLACK;
        if c.perceived > best.perceived || (c.perceived == best.perceived && smaller) {
            best = c;
        }
    }

    if best.perceived < target {
        return Outcome {
            output: best.colour,
            class: Class::OutOfReach,
            perceived_before: before,
            perceived_after: best.perceived,
        };
    }
    // Back toward D on the straight CIELAB line to the kept candidate: c'(D) < target <= c'(1).
    // Each point is judged as stored, so that the pixel shown reaches the target.
    let (mut lo, mut hi) = (0.0, 1.0);
    let (mut out, mut after) = (best.colour, best.perceived);
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        let colour = lab_to_clipped_linear(d_lab + mid * (best.lab - d_lab));
        // In the scaled units of NEAR_THRESHOLD: NEAR_ROUNDING code values from a rounding
        // boundary is at it (float32 may store the other code, and judge it the other way).
        m.note(
            stored.rounding_margin(colour) * NEAR_THRESHOLD / NEAR_ROUNDING,
            0.0,
        );
        let shown = stored.read_back(colour);
        let c = model.perceived_contrast(shown, background);
        if c >= target {
            (hi, out, after) = (mid, shown, c);
        } else {
            lo = mid;
        }
    }
    Outcome {
        output: out,
        class: Class::BroughtToTarget,
        perceived_before: before,
        perceived_after: after,
    }
}

/// One candidate colour, its CIELAB change from the display colour and its c'.
struct Candidate {
    colour: DVec3,
    lab: DVec3,
    change: f64,
    perceived: f64,
}

impl Candidate {
    fn new(colour: DVec3, d_lab: DVec3, background: DVec3, model: &Model) -> Self {
        let lab = colour::linear_to_lab(colour);
        Candidate {
            colour,
            lab,
            change: colour::delta_e(d_lab, lab),
            perceived: model.perceived_contrast(colour, background),
        }
    }
}

/// [`perceptual`] with the paper method's output computed by its CPU reference
/// (`enhance_linear` with `params`, its method set to the paper's): `display`, `alpha` and
/// `background` as there; `params.transmittance` must be the model's.
pub fn perceptual_over_paper(
    display: DVec3,
    alpha: f64,
    background: DVec3,
    params: &Params,
    model: &Model,
) -> Outcome {
    let paper_params = Params {
        method: Method::Paper,
        ..params.clone()
    };
    let bg_scaled = colour::linear_to_scaled(f64::from(params.transmittance) * background);
    let paper_output =
        enhance_linear(display, alpha, background, bg_scaled, &paper_params).unwrap_or(display);
    let pixel = Pixel {
        display,
        alpha,
        background,
        paper_output,
    };
    perceptual_traced(&pixel, model, params.stored, &mut Margin::new())
}

/// The method's CPU reference as its entry in the method table names it
/// (`Reference::Perceptual`): the output for linear display colour `display` over the linear,
/// unattenuated background `background`, given the paper method's output `paper` (clipped),
/// with the model of `params` ([`Model::of_params`]), as `params.stored` reads it back.
/// Traced (`m` given), records in `m` the candidates' decisions near the budget, bisection
/// points near a rounding boundary and, as at its threshold, a pixel whose output the GPU
/// tables' tolerance may change ([`THRESHOLD_TOLERANCE`]).
pub fn perceptual_step(
    display: DVec3,
    background: DVec3,
    paper: DVec3,
    params: &Params,
    m: Option<&mut Margin>,
) -> DVec3 {
    let model = Model::of_params(params);
    let pixel = Pixel {
        display,
        alpha: 1.0,
        background,
        paper_output: paper,
    };
    let Some(m) = m else {
        return perceptual_traced(&pixel, &model, params.stored, &mut Margin::new()).output;
    };
    let out = perceptual_traced(&pixel, &model, params.stored, m).output;
    for scale in [1.0 - THRESHOLD_TOLERANCE, 1.0 + THRESHOLD_TOLERANCE] {
        let varied = Model {
            threshold_scale: scale,
            ..model
        };
        let other = perceptual_traced(&pixel, &varied, params.stored, &mut Margin::new());
        // Every output is a candidate or a bisection step: any difference is a decision that
        // went the other way.
        if other.output != out {
            m.note(0.0, 0.0);
        }
    }
    out
}
