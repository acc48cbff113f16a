//! Whether a view may take the shared-fetch `enhance` variant (shaders/sample_shared.wgsl),
//! in which the four pixels of a group read the two texel entries of each of their two camera
//! rows once (4 reads) instead of per pixel (8 reads). Its output is the general variant's, bit
//! for bit, where, in the shader's f32 arithmetic:
//! - the four pixels sample the same camera rows: their `ty` is equal when the mapping's
//!   u -> v term (row 1, column 0) and its projective terms are zero and its bottom row is
//!   (0, 0, 1), so that the divide is by exactly 1;
//! - their texel columns floor(tx) lie within 2 of each other (the four texels of the two
//!   entries hold every pixel's pair): tx = cu * W - 0.5 moves by |map_00| * W / width per
//!   display pixel, so three steps plus two pixels' rounding must stay under 2 texels.
//!
//! The v -> u term (row 0, column 1) only shifts a whole row, and a mirrored mapping
//! (map_00 < 0) only reverses the group: both are allowed.

use crate::algorithm::mapping::CameraMapping;

/// Bound on the rounding of one pixel's tx, relative to the largest magnitude its terms reach:
/// about ten roundings of 2^-24 each (Vulkan allows 2.5 ulp for the divide), taken as 32.
const TX_ROUNDING: f64 = 32.0 / (1u64 << 24) as f64;

/// Whether a view of `region` pixels, sampling a camera frame of `camera` texels through
/// `mapping`, gets the same output from the shared-fetch variant as from the general one.
pub fn shares_fetches(mapping: &CameraMapping, region: (u32, u32), camera: (u32, u32)) -> bool {
    // What the shader sees: the push constants' f32 values.
    let m = mapping.to_f32_rows().map(|r| r.map(f64::from));
    if region.0 == 0 || camera.0 == 0 || !m.iter().flatten().all(|v| v.is_finite()) {
        return false;
    }
    if m[1][0] != 0.0 || m[2] != [0.0, 0.0, 1.0] {
        return false;
    }
    let (width, texels) = (f64::from(region.0), f64::from(camera.0));
    let step = m[0][0].abs() * texels / width;
    // u reaches (width + 2.5) / width in the last group (pixels past the row are computed and
    // not stored), v stays in [0, 1].
    let u_max = (width + 2.5) / width;
    let largest = (m[0][0].abs() * u_max + m[0][1].abs() + m[0][2].abs()) * texels + 1.0;
    3.0 * step + 2.0 * TX_ROUNDING * largest < 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAMERA: (u32, u32) = (1280, 720);

    /// The default manual mapping (fov_scale 0.65, fov_offset 0.13, 0.17).
    fn default_mapping() -> CameraMapping {
        CameraMapping::affine([0.65, 0.65], [0.13, 0.17])
    }

    #[test]
    fn the_default_mapping_shares_at_the_usual_sizes() {
        for region in [(1268, 720), (2064, 2208), (1440, 1600), (3000, 3000)] {
            assert!(
                shares_fetches(&default_mapping(), region, CAMERA),
                "{region:?}"
            );
        }
    }

    #[test]
    fn three_steps_must_stay_under_two_texels_with_room_for_rounding() {
        // 0.65 x 1280 / 1248 = 2/3 texel per pixel exactly: three steps reach two texels.
        assert!(!shares_fetches(&default_mapping(), (1248, 720), CAMERA));
        // Just under 2/3: 1.9968 texels over three steps, inside the rounding margin (about
        // 0.0038 texels here).
        assert!(!shares_fetches(&default_mapping(), (1250, 720), CAMERA));
        // 1.9952 texels: outside it.
        assert!(shares_fetches(&default_mapping(), (1251, 720), CAMERA));
        // Smaller views and a wider camera frame both step further.
        assert!(!shares_fetches(&default_mapping(), (640, 360), CAMERA));
        assert!(!shares_fetches(
            &default_mapping(),
            (1268, 720),
            (2560, 1440)
        ));
    }

    #[test]
    fn rotation_and_vertical_shear_do_not_share() {
        let a = 0.05f64;
        let (c, s) = (a.cos() * 0.5, a.sin() * 0.5);
        let rotated = CameraMapping {
            rows: [[c, -s, 0.25], [s, c, 0.25], [0.0, 0.0, 1.0]],
        };
        assert!(!shares_fetches(&rotated, (2064, 2208), CAMERA));
        let mut sheared = default_mapping();
        sheared.rows[1][0] = 1e-6;
        assert!(!shares_fetches(&sheared, (2064, 2208), CAMERA));
        // A term that f32 rounds to zero is zero for the shader.
        sheared.rows[1][0] = 1e-50;
        assert!(shares_fetches(&sheared, (2064, 2208), CAMERA));
    }

    #[test]
    fn projective_mappings_do_not_share() {
        for bottom in [[1e-4, 0.0, 1.0], [0.0, 1e-4, 1.0], [0.0, 0.0, 2.0]] {
            let mut m = default_mapping();
            m.rows[2] = bottom;
            assert!(!shares_fetches(&m, (2064, 2208), CAMERA), "{bottom:?}");
        }
    }

    #[test]
    fn mirrored_and_row_shifted_mappings_share() {
        let mirrored = CameraMapping::affine([-0.65, 0.65], [0.78, 0.17]);
        assert!(shares_fetches(&mirrored, (1268, 720), CAMERA));
        assert!(!shares_fetches(&mirrored, (1248, 720), CAMERA));
        let flipped = CameraMapping::affine([0.65, -0.65], [0.13, 0.82]);
        assert!(shares_fetches(&flipped, (1268, 720), CAMERA));
        let mut shifted = default_mapping();
        shifted.rows[0][1] = 0.1;
        assert!(shares_fetches(&shifted, (1268, 720), CAMERA));
    }

    #[test]
    fn degenerate_inputs_do_not_share() {
        let mut m = default_mapping();
        assert!(!shares_fetches(&m, (0, 720), CAMERA));
        assert!(!shares_fetches(&m, (1268, 720), (0, 720)));
        m.rows[0][2] = f64::NAN;
        assert!(!shares_fetches(&m, (1268, 720), CAMERA));
        m.rows[0][2] = 1e300;
        assert!(!shares_fetches(&m, (1268, 720), CAMERA));
    }
}
