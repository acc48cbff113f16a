//! The 18 fixed CIELAB directions the perceptual method tries (docs/algorithm.md, *The
//! perceptual method*), unit vectors in (L*, a*, b*).

use glam::DVec3;

const S3: f64 = 0.5773502691896258; // 1 / sqrt 3
const S2: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The 6 axes +-L*, +-a*, +-b*; the 8 diagonals (+-1, +-1, +-1) / sqrt 3; the 4 diagonals
/// (0, +-1, +-1) / sqrt 2 of the a*b* plane.
pub const DIRECTIONS: [DVec3; 18] = [
    DVec3::new(1.0, 0.0, 0.0),
    DVec3::new(-1.0, 0.0, 0.0),
    DVec3::new(0.0, 1.0, 0.0),
    DVec3::new(0.0, -1.0, 0.0),
    DVec3::new(0.0, 0.0, 1.0),
    DVec3::new(0.0, 0.0, -1.0),
    DVec3::new(S3, S3, S3),
    DVec3::new(S3, S3, -S3),
    DVec3::new(S3, -S3, S3),
    DVec3::new(S3, -S3, -S3),
    DVec3::new(-S3, S3, S3),
    DVec3::new(-S3, S3, -S3),
    DVec3::new(-S3, -S3, S3),
    DVec3::new(-S3, -S3, -S3),
    DVec3::new(0.0, S2, S2),
    DVec3::new(0.0, S2, -S2),
    DVec3::new(0.0, -S2, S2),
    DVec3::new(0.0, -S2, -S2),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eighteen_distinct_unit_directions_symmetric_about_the_origin() {
        for (i, u) in DIRECTIONS.iter().enumerate() {
            assert!((u.length() - 1.0).abs() < 1e-15, "{u}");
            assert!(DIRECTIONS.contains(&-*u), "{u} has no opposite");
            for v in &DIRECTIONS[i + 1..] {
                assert!(u.distance(*v) > 0.5, "{u} {v}");
            }
        }
        assert!((S3 * S3 * 3.0 - 1.0).abs() < 1e-15);
        // 6 axes, 8 body diagonals, 4 diagonals of the a*b* plane.
        let count = |nonzero: usize| {
            DIRECTIONS
                .iter()
                .filter(|u| u.to_array().iter().filter(|c| **c != 0.0).count() == nonzero)
                .count()
        };
        assert_eq!((count(1), count(3), count(2)), (6, 8, 4));
        assert!(DIRECTIONS
            .iter()
            .filter(|u| u.to_array().iter().filter(|c| **c != 0.0).count() == 2)
            .all(|u| u.x == 0.0));
    }
}
