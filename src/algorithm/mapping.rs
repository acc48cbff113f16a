//! The FoV calibration (docs/algorithm.md, FoV calibration), generalised: where a display
//! pixel's background lies in the camera image. The paper's manual mapping, `camera_uv =
//! fov_scale * display_uv + fov_offset`, is the affine case; a camera registered to a view from
//! its pose and field of view gives a homography (docs/algorithm.md, Per-view registration).
//! Texture coordinates as docs/algorithm.md, FoV calibration, states them: origin top-left,
//! u right, v down, texel centres at (i + 0.5) / W.

use glam::{DMat3, DVec2, DVec3};

/// `camera_uv = (m * (display_uv, 1)).xy / (m * (display_uv, 1)).z`, per view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMapping {
    /// Row-major 3x3: `rows[r][c]`.
    pub rows: [[f64; 3]; 3],
}

impl CameraMapping {
    pub const IDENTITY: CameraMapping = CameraMapping {
        rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    };

    /// The paper's manual mapping: `camera_uv = scale * display_uv + offset`.
    pub fn affine(scale: [f64; 2], offset: [f64; 2]) -> CameraMapping {
        CameraMapping {
            rows: [
                [scale[0], 0.0, offset[0]],
                [0.0, scale[1], offset[1]],
                [0.0, 0.0, 1.0],
            ],
        }
    }

    pub fn from_mat3(m: DMat3) -> CameraMapping {
        let r = m.transpose().to_cols_array_2d();
        CameraMapping { rows: r }
    }

    pub fn to_mat3(self) -> DMat3 {
        DMat3::from_cols_array_2d(&self.rows).transpose()
    }

    /// Whether the last row is (0, 0, 1): no projective divide needed.
    pub fn is_affine(&self) -> bool {
        self.rows[2] == [0.0, 0.0, 1.0]
    }

    /// The camera texture coordinate of a display texture coordinate.
    pub fn apply(&self, display_uv: DVec2) -> DVec2 {
        let h = self.to_mat3() * DVec3::new(display_uv.x, display_uv.y, 1.0);
        DVec2::new(h.x, h.y) / h.z
    }

    /// Row-major f32 values, for the GPU's push constants.
    pub fn to_f32_rows(&self) -> [[f32; 3]; 3] {
        self.rows.map(|r| r.map(|v| v as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn affine_is_scale_then_offset() {
        let m = CameraMapping::affine([0.65, 0.5], [0.13, 0.17]);
        let uv = m.apply(DVec2::new(1.0, 0.5));
        assert!((uv - DVec2::new(0.78, 0.42)).length() < 1e-12);
        assert!(m.is_affine());
    }

    #[test]
    fn mat3_round_trip_keeps_rows() {
        let m = CameraMapping {
            rows: [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]],
        };
        assert_eq!(CameraMapping::from_mat3(m.to_mat3()), m);
        assert_eq!(m.to_mat3().row(0), DVec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn projective_divide_applies() {
        let m = CameraMapping {
            rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]],
        };
        assert_eq!(m.apply(DVec2::new(1.0, 1.0)), DVec2::new(0.5, 0.5));
        assert!(!m.is_affine());
    }
}
