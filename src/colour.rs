//! Colour science: sRGB, CIE XYZ, CIELAB and the scaled space (docs/algorithm.md, Colour spaces).
//!
//! Everything here is f64 and pure. The GPU shaders use the same constants in f32; the CPU
//! reference in `algorithm` is built on these functions. Nothing here clips a colour to the
//! sRGB gamut except `quantize` (docs/algorithm.md, Scaled space: nothing projects P onto the
//! gamut).

use glam::DVec3;

/// Linear sRGB -> CIE XYZ (D65), rows of the matrix (docs/algorithm.md, XYZ matrices).
pub const LINEAR_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124564, 0.3575761, 0.1804375],
    [0.2126729, 0.7151522, 0.0721750],
    [0.0193339, 0.1191920, 0.9503041],
];

/// CIE XYZ -> linear sRGB: the exact inverse of [`LINEAR_TO_XYZ`], computed in rational
/// arithmetic and rounded once to f64 (not the separately rounded published matrix).
/// `tests::inverse_matrix_is_exact` checks it against a numerical inverse.
pub const XYZ_TO_LINEAR: [[f64; 3]; 3] = [
    [3.2404548360214083, -1.5371388501025751, -0.4985315468684809],
    [
        -0.9692663898756537,
        1.8760109288424913,
        0.041556082346673524,
    ],
    [
        0.05564341960421366,
        -0.20402585426769815,
        1.0572251624579287,
    ],
];

/// Reference white: [`LINEAR_TO_XYZ`] applied to (1, 1, 1), i.e. its row sums, so that sRGB
/// white is exactly L* = 100 and every grey has a* = b* = 0.
pub const WHITE_XYZ: [f64; 3] = [0.95047, 1.0000001, 1.08883];

/// CIELAB's delta = 6/29: below delta^3 the cube root is replaced by a line.
pub const LAB_DELTA: f64 = 6.0 / 29.0;

/// Scaled space (the paper's [-1, 1] space): L' = (L* - 50) / 50, a' = a* / 128, b' = b* / 128.
pub const SCALED_L_OFFSET: f64 = 50.0;
pub const SCALED_L_SCALE: f64 = 50.0;
pub const SCALED_AB_SCALE: f64 = 128.0;

/// IEC 61966-2-1 sRGB curve constants.
pub const SRGB_DECODE_THRESHOLD: f64 = 0.04045;
pub const SRGB_ENCODE_THRESHOLD: f64 = 0.0031308;
pub const SRGB_SLOPE: f64 = 12.92;
pub const SRGB_GAMMA: f64 = 2.4;
pub const SRGB_OFFSET: f64 = 0.055;

/// sRGB-encoded value in [0, 1] -> linear light.
pub fn srgb_decode(v: f64) -> f64 {
    if v <= SRGB_DECODE_THRESHOLD {
        v / SRGB_SLOPE
    } else {
        ((v + SRGB_OFFSET) / (1.0 + SRGB_OFFSET)).powf(SRGB_GAMMA)
    }
}

/// Linear light in [0, 1] -> sRGB-encoded value.
pub fn srgb_encode(v: f64) -> f64 {
    if v <= SRGB_ENCODE_THRESHOLD {
        v * SRGB_SLOPE
    } else {
        (1.0 + SRGB_OFFSET) * v.powf(1.0 / SRGB_GAMMA) - SRGB_OFFSET
    }
}

/// An 8-bit code value -> linear light.
pub fn code_to_linear(c: u8) -> f64 {
    srgb_decode(f64::from(c) / 255.0)
}

/// An 8-bit sRGB colour -> linear RGB.
pub fn srgb8_to_linear(c: [u8; 3]) -> DVec3 {
    DVec3::new(
        code_to_linear(c[0]),
        code_to_linear(c[1]),
        code_to_linear(c[2]),
    )
}

/// Encoded value -> 8-bit code: clip to [0, 1], then `floor(255 v + 0.5)` (docs/algorithm.md,
/// Output encoding).
pub fn quantize(v: f64) -> u8 {
    (255.0 * v.clamp(0.0, 1.0) + 0.5).floor() as u8
}

/// Linear RGB -> 8-bit sRGB: clip each linear channel to [0, 1], encode, quantise.
pub fn linear_to_srgb8(c: DVec3) -> [u8; 3] {
    let q = |v: f64| quantize(srgb_encode(v.clamp(0.0, 1.0)));
    [q(c.x), q(c.y), q(c.z)]
}

fn mul(m: &[[f64; 3]; 3], v: DVec3) -> DVec3 {
    let row = |r: [f64; 3]| r[0] * v.x + r[1] * v.y + r[2] * v.z;
    DVec3::new(row(m[0]), row(m[1]), row(m[2]))
}

pub fn linear_to_xyz(c: DVec3) -> DVec3 {
    mul(&LINEAR_TO_XYZ, c)
}

pub fn xyz_to_linear(c: DVec3) -> DVec3 {
    mul(&XYZ_TO_LINEAR, c)
}

/// CIELAB's f: cube root above delta^3, a line below (continuous with slope 1/(3 delta^2)).
fn lab_f(t: f64) -> f64 {
    if t > LAB_DELTA * LAB_DELTA * LAB_DELTA {
        t.cbrt()
    } else {
        t / (3.0 * LAB_DELTA * LAB_DELTA) + 4.0 / 29.0
    }
}

fn lab_f_inv(f: f64) -> f64 {
    if f > LAB_DELTA {
        f * f * f
    } else {
        3.0 * LAB_DELTA * LAB_DELTA * (f - 4.0 / 29.0)
    }
}

/// XYZ -> (L*, a*, b*) relative to [`WHITE_XYZ`].
pub fn xyz_to_lab(c: DVec3) -> DVec3 {
    let fx = lab_f(c.x / WHITE_XYZ[0]);
    let fy = lab_f(c.y / WHITE_XYZ[1]);
    let fz = lab_f(c.z / WHITE_XYZ[2]);
    DVec3::new(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))
}

pub fn lab_to_xyz(lab: DVec3) -> DVec3 {
    let fy = (lab.x + 16.0) / 116.0;
    let fx = fy + lab.y / 500.0;
    let fz = fy - lab.z / 200.0;
    DVec3::new(
        WHITE_XYZ[0] * lab_f_inv(fx),
        WHITE_XYZ[1] * lab_f_inv(fy),
        WHITE_XYZ[2] * lab_f_inv(fz),
    )
}

pub fn lab_to_scaled(lab: DVec3) -> DVec3 {
    DVec3::new(
        (lab.x - SCALED_L_OFFSET) / SCALED_L_SCALE,
        lab.y / SCALED_AB_SCALE,
        lab.z / SCALED_AB_SCALE,
    )
}

pub fn scaled_to_lab(s: DVec3) -> DVec3 {
    DVec3::new(
        s.x * SCALED_L_SCALE + SCALED_L_OFFSET,
        s.y * SCALED_AB_SCALE,
        s.z * SCALED_AB_SCALE,
    )
}

pub fn linear_to_lab(c: DVec3) -> DVec3 {
    xyz_to_lab(linear_to_xyz(c))
}

pub fn linear_to_scaled(c: DVec3) -> DVec3 {
    lab_to_scaled(linear_to_lab(c))
}

pub fn scaled_to_linear(s: DVec3) -> DVec3 {
    xyz_to_linear(lab_to_xyz(scaled_to_lab(s)))
}

/// An 8-bit sRGB colour -> (L*, a*, b*).
pub fn srgb8_to_lab(c: [u8; 3]) -> DVec3 {
    linear_to_lab(srgb8_to_linear(c))
}

/// CIE76 colour difference Delta E*ab between two LAB colours (unscaled units).
pub fn delta_e(lab1: DVec3, lab2: DVec3) -> f64 {
    lab1.distance(lab2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).abs().max_element() <= tol
    }

    #[test]
    fn check_value_red() {
        let lab = srgb8_to_lab([255, 0, 0]);
        assert!(
            close(lab, DVec3::new(53.2408, 80.0925, 67.2032), 5e-5),
            "{lab}"
        );
    }

    #[test]
    fn check_value_grey_128() {
        let lab = srgb8_to_lab([128, 128, 128]);
        assert!((lab.x - 53.585).abs() < 5e-4, "{lab}");
    }

    #[test]
    fn white_is_l100_and_greys_are_neutral() {
        let white = srgb8_to_lab([255, 255, 255]);
        assert!(close(white, DVec3::new(100.0, 0.0, 0.0), 1e-9), "{white}");
        for g in 0..=255u8 {
            let lab = srgb8_to_lab([g, g, g]);
            assert!(lab.y.abs() < 1e-9 && lab.z.abs() < 1e-9, "grey {g}: {lab}");
        }
    }

    #[test]
    fn white_point_is_row_sums() {
        for (row, w) in LINEAR_TO_XYZ.iter().zip(WHITE_XYZ) {
            assert!((row.iter().sum::<f64>() - w).abs() < 1e-15);
        }
    }

    #[test]
    fn inverse_matrix_is_exact() {
        let cols = |m: &[[f64; 3]; 3]| {
            glam::DMat3::from_cols_array_2d(&[
                [m[0][0], m[1][0], m[2][0]],
                [m[0][1], m[1][1], m[2][1]],
                [m[0][2], m[1][2], m[2][2]],
            ])
        };
        let numeric = cols(&LINEAR_TO_XYZ).inverse();
        let ours = cols(&XYZ_TO_LINEAR);
        assert!(numeric.abs_diff_eq(ours, 1e-13), "{numeric} vs {ours}");
        let product = cols(&LINEAR_TO_XYZ) * ours;
        assert!(product.abs_diff_eq(glam::DMat3::IDENTITY, 1e-15));
    }

    #[test]
    fn srgb_curve_is_continuous_and_inverse() {
        // The IEC constants make the two pieces meet (to ~1e-7) at the thresholds.
        let lo = SRGB_DECODE_THRESHOLD / SRGB_SLOPE;
        let hi = ((SRGB_DECODE_THRESHOLD + SRGB_OFFSET) / (1.0 + SRGB_OFFSET)).powf(SRGB_GAMMA);
        assert!((lo - hi).abs() < 1e-7);
        for c in 0..=255u8 {
            assert_eq!(quantize(srgb_encode(code_to_linear(c))), c);
        }
    }

    #[test]
    fn quantize_rounds_half_up_and_clips() {
        assert_eq!(quantize(-0.3), 0);
        assert_eq!(quantize(1.7), 255);
        assert_eq!(quantize(0.5 / 255.0), 1);
        assert_eq!(quantize(0.49 / 255.0), 0);
        assert_eq!(quantize(f64::NAN.max(0.0)), 0);
    }

    #[test]
    fn delta_e_is_euclidean() {
        let d = delta_e(DVec3::new(50.0, 3.0, 0.0), DVec3::new(50.0, 0.0, 4.0));
        assert!((d - 5.0).abs() < 1e-12);
    }
}
