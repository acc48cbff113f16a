//! What "the GPU agrees with the CPU reference" means (docs/algorithm.md, Conformance), in one
//! place.
//!
//! The shader computes in f32, the reference in f64. Away from branch thresholds the f32 noise
//! (about 1e-6 in scaled units, far below a code value after encoding) can move a result by at
//! most one code value across a rounding boundary. Near a branch threshold f32 may take the
//! other branch, and then any difference is legitimate.

use crate::colour;

/// A branch quantity within this distance of its threshold (scaled units) may flip in f32.
/// Generous on purpose: f32 LAB of a grey has |a'|, |b'| around 1e-7 and the direction of a
/// nearly grey D' or a nearly mid-grey B is unreliable well above 1e-6; below 1e-4 a float32
/// direction error stays under a few milliradians.
pub const NEAR_THRESHOLD: f64 = 1e-4;

/// Distance to a rounding boundary, or to the linear [0, 1] clip, counted as "near".
/// Rounding distance is measured in code values: measured in encoded [0, 1] units, 0.002 is
/// half a code value (boundaries are 1/255 = 0.0039 apart), so every value would be "near".
pub const NEAR_ROUNDING: f64 = 0.002;

/// One pixel of the CPU reference with what a conformance test needs to judge a difference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelTrace {
    /// The reference output (RGBA, alpha passed through).
    pub out: [u8; 4],
    /// The encoded value of each channel in [0, 1] before quantisation.
    pub exact: [f64; 3],
    /// The linear value of each channel before the [0, 1] clip.
    pub linear: [f64; 3],
    /// Some branch condition (|B| <= 1e-6, |D'| <= 1e-6, E'.D' >= 0, |I - D| vs lambda_e,
    /// I == D, |P - B| < r, |D - B| >= r, |D| <= 1e-6) was within [`NEAR_THRESHOLD`] of its
    /// threshold. The black/alpha skip is an exact integer test and never counts.
    pub near_threshold: bool,
}

impl PixelTrace {
    /// Some channel's exact value is within [`NEAR_ROUNDING`] code values of a rounding
    /// boundary (k + 0.5), or its linear value within [`NEAR_ROUNDING`] of 0 or 1.
    pub fn near_rounding(&self) -> bool {
        let near_boundary = |v: f64| {
            let code = 255.0 * v;
            (code - code.floor() - 0.5).abs() < NEAR_ROUNDING
        };
        let near_clip = |l: f64| l.abs() < NEAR_ROUNDING || (l - 1.0).abs() < NEAR_ROUNDING;
        self.exact.iter().any(|&v| near_boundary(v)) || self.linear.iter().any(|&l| near_clip(l))
    }
}

/// Whether a GPU output pixel conforms to the reference: alpha identical and every colour
/// channel within +-1 code value, or any colour where a branch was near its threshold.
/// A rounding-boundary case is already covered by +-1: f32 noise moves the exact value by far
/// less than a code value, so it can only cross one boundary.
pub fn conformant(trace: &PixelTrace, gpu: [u8; 4]) -> bool {
    if gpu[3] != trace.out[3] {
        return false;
    }
    if trace.near_threshold {
        return true;
    }
    (0..3).all(|i| trace.out[i].abs_diff(gpu[i]) <= 1)
}

const PRIMARIES_AND_SECONDARIES: [[u8; 3]; 8] = [
    [0, 0, 0],
    [255, 255, 255],
    [255, 0, 0],
    [0, 255, 0],
    [0, 0, 255],
    [0, 255, 255],
    [255, 0, 255],
    [255, 255, 0],
];

const GREYS: [u8; 9] = [1, 32, 64, 100, 119, 128, 181, 220, 255];

/// Backgrounds whose attenuated (x0.4) colour is close to mid grey (L* = 50, |B| near 0).
const NEAR_MID_GREY_BACKGROUNDS: [[u8; 3]; 5] = [
    [181, 181, 181],
    [182, 181, 181],
    [181, 181, 183],
    [180, 182, 181],
    [170, 185, 190],
];

const NEARLY_GREY_DISPLAYS: [[u8; 3]; 8] = [
    [128, 128, 129],
    [128, 129, 128],
    [127, 128, 128],
    [200, 201, 200],
    [50, 50, 51],
    [2, 1, 1],
    [254, 255, 255],
    [90, 91, 92],
];

/// Colourful backgrounds for the relational cases (D == B, complement, near attenuated B).
const BACKGROUND_SAMPLES: [[u8; 3]; 8] = [
    [230, 210, 40],
    [70, 130, 220],
    [128, 128, 128],
    [40, 160, 60],
    [200, 60, 50],
    [250, 250, 250],
    [20, 20, 30],
    [181, 181, 181],
];

/// The corner cases of docs/algorithm.md, Conformance, as (display, background) 8-bit colour
/// pairs. The background is a uniform camera frame of that colour; "near the attenuated B"
/// assumes the default transmittance 0.4.
pub fn corner_cases() -> Vec<([u8; 3], [u8; 3])> {
    let mut cases = Vec::new();
    for d in PRIMARIES_AND_SECONDARIES {
        cases.extend(PRIMARIES_AND_SECONDARIES.map(|b| (d, b)));
    }
    for g in GREYS {
        cases.extend(GREYS.map(|h| ([g; 3], [h; 3])));
        cases.extend(PRIMARIES_AND_SECONDARIES[2..].iter().map(|&b| ([g; 3], b)));
    }
    let backgrounds = BACKGROUND_SAMPLES.iter().chain(&NEAR_MID_GREY_BACKGROUNDS);
    for &b in backgrounds.clone() {
        cases.extend(NEARLY_GREY_DISPLAYS.map(|d| (d, b)));
        cases.push((b, b));
        cases.push((b.map(|c| 255 - c), b));
        cases.extend(near_attenuated(b).into_iter().map(|d| (d, b)));
    }
    for &b in &NEAR_MID_GREY_BACKGROUNDS {
        cases.extend(PRIMARIES_AND_SECONDARIES.map(|d| (d, b)));
        cases.extend(GREYS.map(|g| ([g; 3], b)));
    }
    cases
}

/// Display colours at and around the background as it reaches the eye (x0.4 in linear light),
/// i.e. inside or at the edge of the JND sphere.
fn near_attenuated(background: [u8; 3]) -> Vec<[u8; 3]> {
    let attenuated = colour::linear_to_srgb8(0.4 * colour::srgb8_to_linear(background));
    let nudge = |d: i16| attenuated.map(|c| (i16::from(c) + d).clamp(0, 255) as u8);
    let mut out = vec![attenuated, nudge(1), nudge(-1), nudge(3)];
    out.push([
        attenuated[0],
        attenuated[1],
        attenuated[2].saturating_add(2),
    ]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trace(out: [u8; 4], exact: [f64; 3], near_threshold: bool) -> PixelTrace {
        PixelTrace {
            out,
            exact,
            linear: [0.5; 3],
            near_threshold,
        }
    }

    #[test]
    fn tolerance_is_one_code_value() {
        let t = trace([10, 20, 30, 255], [0.04; 3], false);
        assert!(conformant(&t, [11, 19, 30, 255]));
        assert!(!conformant(&t, [12, 20, 30, 255]));
        assert!(
            !conformant(&t, [10, 20, 30, 254]),
            "alpha must be identical"
        );
        assert!(conformant(
            &trace([10, 20, 30, 255], [0.04; 3], true),
            [90, 20, 30, 255]
        ));
    }

    #[test]
    fn near_rounding_is_not_vacuous() {
        let at = |code: f64| trace([0; 4], [code / 255.0; 3], false);
        assert!(at(100.5005).near_rounding());
        assert!(!at(100.49).near_rounding());
        assert!(!at(100.0).near_rounding());
        let mut t = at(100.0);
        t.linear = [0.2, 0.9995, 0.3];
        assert!(t.near_rounding());
    }

    #[test]
    fn corner_cases_cover_the_spec_list() {
        let cases = corner_cases();
        assert!(cases.contains(&([255, 0, 0], [0, 255, 255])));
        assert!(cases.contains(&([128, 128, 128], [255, 255, 0])));
        assert!(cases.contains(&([70, 130, 220], [70, 130, 220])), "D == B");
        assert!(
            cases.contains(&([185, 125, 35], [70, 130, 220])),
            "complement"
        );
        assert!(cases
            .iter()
            .any(|(d, b)| d == &[128, 128, 129] && b == &[181, 181, 181]));
        assert!(cases.len() > 300);
    }
}
