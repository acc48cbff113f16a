//! The camera texels a background preparation makes: those the views' mappings sample (with
//! the bilinear neighbours each sample reads), rounded out to whole 16-byte camera entries.

use crate::algorithm::mapping::CameraMapping;

/// The camera texels a background preparation makes: those the views' mappings sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraRect {
    /// First texel; x is a multiple of 4 (the pass makes 4 texels per invocation).
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl CameraRect {
    pub fn full(size: (u32, u32)) -> CameraRect {
        CameraRect {
            x: 0,
            y: 0,
            width: size.0,
            height: size.1,
        }
    }

    /// The texels whose entries bilinear sampling reads for any display pixel of views at
    /// `mappings` (the bounding box of each view's mapped corners: where the mapping's z is
    /// positive at all four corners it is positive inside, and the view's image is the convex
    /// quadrilateral of its corners), with a margin for rounding. The whole image where a
    /// mapping is degenerate.
    pub fn sampled_by(mappings: &[CameraMapping], size: (u32, u32)) -> CameraRect {
        let (w, h) = (f64::from(size.0), f64::from(size.1));
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for m in mappings {
            for corner in [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]] {
                let r = &m.rows;
                let z = r[2][0] * corner[0] + r[2][1] * corner[1] + r[2][2];
                let uv = m.apply(glam::DVec2::from(corner));
                if !(z > 0.0 && uv.is_finite()) {
                    return CameraRect::full(size);
                }
                let t = [uv.x * w - 0.5, uv.y * h - 0.5];
                for k in 0..2 {
                    lo[k] = lo[k].min(t[k]);
                    hi[k] = hi[k].max(t[k]);
                }
            }
        }
        if mappings.is_empty() {
            return CameraRect::full(size);
        }
        // Entries floor(t) - 1 ..= floor(t) + 1 in x, rows floor(t) - 1 ..= floor(t) + 2 in y.
        let span = |lo: f64, hi: f64, extra: f64, n: f64| {
            let a = (lo.floor() - 1.0).clamp(0.0, n - 1.0);
            let b = (hi.floor() + extra).clamp(0.0, n - 1.0);
            (a as u32, b as u32)
        };
        let (x0, x1) = span(lo[0], hi[0], 1.0, w);
        let (y0, y1) = span(lo[1], hi[1], 2.0, h);
        let x0 = x0 / 4 * 4;
        CameraRect {
            x: x0,
            y: y0,
            width: x1 - x0 + 1,
            height: y1 - y0 + 1,
        }
    }

    /// Whether every texel of `other` is in this rectangle.
    pub fn contains(&self, other: &CameraRect) -> bool {
        other.x >= self.x
            && other.y >= self.y
            && other.x + other.width <= self.x + self.width
            && other.y + other.height <= self.y + self.height
    }

    /// This rectangle grown by `margin` texels on each side within a `size` frame (x kept a
    /// multiple of 4).
    pub fn grown(&self, margin: u32, size: (u32, u32)) -> CameraRect {
        let x = self.x.saturating_sub(margin) / 4 * 4;
        let y = self.y.saturating_sub(margin);
        let right = (self.x + self.width + margin).min(size.0);
        let bottom = (self.y + self.height + margin).min(size.1);
        CameraRect {
            x,
            y,
            width: right.saturating_sub(x),
            height: bottom.saturating_sub(y),
        }
    }

    /// The smallest rectangle holding both.
    pub fn union(&self, other: &CameraRect) -> CameraRect {
        let (x, y) = (self.x.min(other.x), self.y.min(other.y));
        let right = (self.x + self.width).max(other.x + other.width);
        let bottom = (self.y + self.height).max(other.y + other.height);
        CameraRect {
            x,
            y,
            width: right - x,
            height: bottom - y,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::params::Params;
    use glam::DVec2;

    /// Every entry (x, row) and (x, row + 1) that bilinear sampling reads for a grid of display
    /// pixels lies in the rectangle, and its x is a multiple of 4.
    #[test]
    fn the_sampled_rect_holds_every_entry_the_views_read() {
        let size = (640, 480);
        let projective = CameraMapping {
            rows: [[0.8, 0.06, 0.05], [-0.04, 0.7, 0.12], [0.12, -0.09, 0.98]],
        };
        let manual = Params::default().camera_mapping();
        for mappings in [vec![manual], vec![projective], vec![manual, projective]] {
            let rect = CameraRect::sampled_by(&mappings, size);
            assert_eq!(rect.x % 4, 0);
            assert!(rect.width * rect.height < size.0 * size.1, "{rect:?}");
            for m in &mappings {
                for (i, j) in (0..=64).flat_map(|i| (0..=64).map(move |j| (i, j))) {
                    let uv = m.apply(DVec2::new(f64::from(i) / 64.0, f64::from(j) / 64.0));
                    let t = uv * DVec2::new(640.0, 480.0) - 0.5;
                    let x = t.x.floor().clamp(0.0, 639.0) as u32;
                    for y in [t.y.floor(), t.y.floor() + 1.0] {
                        let y = y.clamp(0.0, 479.0) as u32;
                        let texel = CameraRect {
                            x,
                            y,
                            width: 1,
                            height: 1,
                        };
                        assert!(rect.contains(&texel), "{rect:?} misses {texel:?}");
                    }
                }
            }
        }
        let degenerate = CameraMapping {
            rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-2.0, 0.0, 1.0]],
        };
        assert_eq!(
            CameraRect::sampled_by(&[degenerate], size),
            CameraRect::full(size)
        );
    }
}
