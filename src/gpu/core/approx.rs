//! The per-pixel shader's approximations (no pow, tables or divisions in the hot path), with
//! f32 mirrors of what the shader computes so that their accuracy is checked here against the
//! exact colour science of `crate::colour`. The GPU-vs-CPU conformance tests check the whole.

include!("approx_constants.rs");

/// Horner's rule in f32, coefficients lowest power first (the shader's `fma` chain; lavapipe
/// rounds the product and the sum separately, as here).
fn horner(coefficients: &[f64], x: f32) -> f32 {
    coefficients
        .iter()
        .rev()
        .fold(0.0f32, |r, &c| r * x + c as f32)
}

/// The shader's `srgb_decode` of a stored value in [0, 1].
pub fn srgb_decode(v: f32) -> f32 {
    if v > 0.04045 {
        horner(&SRGB_DECODE_POLY, v)
    } else {
        v * (1.0 / 12.92)
    }
}

/// The shader's `srgb_encode` of a linear value in [0, 1].
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.0031308 {
        return 12.92 * v;
    }
    1.055 * horner(&SRGB_ENCODE_POLY, v.sqrt().sqrt()) - 0.055
}

/// The shader's `cbrt` of a positive value.
pub fn cbrt(x: f32) -> f32 {
    let third_bits = (x.to_bits() as f32 * (1.0 / 3.0)) as u32;
    let mut r = f32::from_bits(CBRT_SEED_MAGIC - third_bits);
    let x3 = x * (1.0 / 3.0);
    for _ in 0..CBRT_NEWTON_STEPS {
        r *= 4.0 / 3.0 - x3 * (r * r * r);
    }
    x * r * r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colour;

    #[test]
    fn decode_is_within_1_5e_5_relative_on_every_8bit_code() {
        for code in 1..=255u8 {
            let v = f32::from(code) / 255.0;
            let exact = colour::srgb_decode(f64::from(code) / 255.0);
            let rel = (f64::from(srgb_decode(v)) / exact - 1.0).abs();
            assert!(rel < 1.5e-5, "code {code}: relative error {rel:e}");
        }
    }

    #[test]
    fn encode_is_within_a_hundredth_of_a_code() {
        for k in 0..=100_000 {
            let v = k as f64 / 100_000.0;
            let err = 255.0 * (f64::from(srgb_encode(v as f32)) - colour::srgb_encode(v)).abs();
            assert!(err < 0.01, "v {v}: {err} codes off");
        }
    }

    #[test]
    fn cbrt_is_within_1e_6_relative_over_the_lab_range() {
        // From CIELAB's threshold (6/29)^3 to beyond white (float formats exceed 1).
        let (lo, hi) = (0.0088f64, 8.0f64);
        for k in 0..=200_000 {
            let x = lo * (hi / lo).powf(k as f64 / 200_000.0);
            let rel = (f64::from(cbrt(x as f32)) / x.cbrt() - 1.0).abs();
            assert!(rel < 1e-6, "x {x}: relative error {rel:e}");
        }
    }
}
