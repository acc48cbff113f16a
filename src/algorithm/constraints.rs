//! The steps of Algorithm 1 (docs/algorithm.md, Per-pixel optimisation), each in the scaled
//! space, each recording how close its branch condition came to flipping (for the GPU
//! conformance tolerance).

use glam::DVec3;

/// Below this length a scaled vector has no usable direction (|B|, |D'|, |D|; docs/algorithm.md,
/// Ideal colour I, Chroma step, Comparison methods).
pub(super) const DIRECTION_EPSILON: f64 = 1e-6;

/// The smallest distance of any evaluated branch quantity from its threshold, in scaled units.
#[derive(Clone, Copy, Debug)]
pub struct Margin(pub f64);

impl Margin {
    pub fn new() -> Self {
        Margin(f64::INFINITY)
    }

    /// Records that a branch compared `value` with `threshold`.
    pub fn note(&mut self, value: f64, threshold: f64) {
        self.0 = self.0.min((value - threshold).abs());
    }
}

/// Color difference constraint: the change vector E = DE towards I = -B/|B|, at most
/// `lambda_e` long. None when |B| <= 1e-6 (mid grey background: no complementary direction).
pub fn change_vector(
    display: DVec3,
    background: DVec3,
    lambda_e: f64,
    m: &mut Margin,
) -> Option<DVec3> {
    let b_len = background.length();
    m.note(b_len, DIRECTION_EPSILON);
    if b_len <= DIRECTION_EPSILON {
        return None;
    }
    let ideal = -background / b_len;
    let towards_ideal = ideal - display;
    let dist = towards_ideal.length();
    // min() is continuous, but a float32 engine may pick the other argument near equality.
    m.note(dist, lambda_e);
    m.note(dist, 0.0);
    if dist == 0.0 {
        return Some(DVec3::ZERO);
    }
    Some(dist.min(lambda_e) * (towards_ideal / dist))
}

/// E' = (0, E.a, E.b) split into its chroma part (along D' = (0, D.a, D.b)) and its hue part.
/// None when D is achromatic (|D'| <= 1e-6): chroma has no direction there.
pub struct ChromaSplit {
    pub chroma: DVec3,
    pub hue: DVec3,
    /// E'.D' >= 0: the chroma part increases chroma (theta_ch <= 90 degrees).
    pub increases_chroma: bool,
}

pub fn ab_plane(v: DVec3) -> DVec3 {
    DVec3::new(0.0, v.y, v.z)
}

pub fn split_chroma(display: DVec3, e: DVec3, m: &mut Margin) -> Option<ChromaSplit> {
    let e_ab = ab_plane(e);
    let d_ab = ab_plane(display);
    let d_len = d_ab.length();
    m.note(d_len, DIRECTION_EPSILON);
    if d_len <= DIRECTION_EPSILON {
        return None;
    }
    let dot = e_ab.dot(d_ab);
    // The sign test compares the signed length of the chroma part with 0.
    m.note(dot / d_len, 0.0);
    let chroma = (dot / (d_len * d_len)) * d_ab;
    Some(ChromaSplit {
        chroma,
        hue: e_ab - chroma,
        increases_chroma: dot >= 0.0,
    })
}

/// Chroma constraint: dir.ab keeps the hue change and only a chroma increase.
/// An achromatic display colour takes all of E' (docs/algorithm.md, Chroma step).
pub fn chroma_constraint(display: DVec3, e: DVec3, m: &mut Margin) -> DVec3 {
    match split_chroma(display, e, m) {
        None => ab_plane(e),
        Some(s) if s.increases_chroma => s.chroma + s.hue,
        Some(s) => s.hue,
    }
}

/// Luminance constraint: dir.L = (1 - |cos theta_l|) * E.L, cos theta_l = E.L / |E|.
pub fn luminance_constraint(e: DVec3) -> f64 {
    let len = e.length();
    let cos_l = if len == 0.0 { 0.0 } else { e.x / len };
    (1.0 - cos_l.abs()) * e.x
}

/// JND constraint: if P fell strictly inside the sphere |X - B| = r and D is not inside it,
/// move P back along D->P to where the segment first meets the sphere.
pub fn jnd_constraint(
    display: DVec3,
    p: DVec3,
    background: DVec3,
    r: f64,
    m: &mut Margin,
) -> DVec3 {
    let p_dist = (p - background).length();
    m.note(p_dist, r);
    if p_dist >= r {
        return p;
    }
    let d_to_b = display - background;
    let d_dist = d_to_b.length();
    m.note(d_dist, r);
    if d_dist < r || p == display {
        return p;
    }
    let dp = p - display;
    let a = dp.length_squared();
    let h = dp.dot(d_to_b);
    let c = (d_to_b.length_squared() - r * r).max(0.0);
    // The smaller root of a s^2 + 2 h s + c = 0, in the cancellation-free form.
    let denom = -h + (h * h - a * c).max(0.0).sqrt();
    let s = if denom > 0.0 { c / denom } else { 0.0 };
    display + s * dp
}
