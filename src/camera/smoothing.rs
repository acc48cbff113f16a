//! Optional temporal smoothing: an exponential moving average of the background, to calm
//! sensor noise and flicker beyond what the paper's blur does. Off unless configured.

use crate::image::RgbaImage;

pub(crate) struct Smoother {
    /// Weight of the newest frame, in (0, 1].
    alpha: f32,
    /// The running average in sRGB code values; empty until the first frame or a size change.
    average: Vec<[f32; 3]>,
}

impl Smoother {
    pub(crate) fn new(alpha: f32) -> Self {
        Smoother {
            alpha: alpha.clamp(f32::EPSILON, 1.0),
            average: Vec::new(),
        }
    }

    /// Folds `frame` into the average and returns the smoothed frame.
    pub(crate) fn apply(&mut self, mut frame: RgbaImage) -> RgbaImage {
        if self.average.len() != frame.pixels.len() {
            self.average = frame
                .pixels
                .iter()
                .map(|p| p.map(f32::from)[..3].try_into().unwrap())
                .collect();
            return frame;
        }
        for (avg, px) in self.average.iter_mut().zip(frame.pixels.iter_mut()) {
            for c in 0..3 {
                avg[c] += self.alpha * (f32::from(px[c]) - avg[c]);
                px[c] = avg[c].round() as u8;
            }
        }
        frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn average_moves_by_alpha_towards_each_new_frame() {
        let mut s = Smoother::new(0.25);
        let first = s.apply(RgbaImage::new(1, 1, [0, 100, 200, 255]));
        assert_eq!(first.pixels[0], [0, 100, 200, 255]);
        // 0 + 0.25 * (200 - 0) = 50; 100 + 0.25 * 0 = 100; 200 + 0.25 * (0 - 200) = 150.
        let second = s.apply(RgbaImage::new(1, 1, [200, 100, 0, 255]));
        assert_eq!(second.pixels[0], [50, 100, 150, 255]);
        // 50 + 0.25 * 150 = 87.5 -> 88.
        let third = s.apply(RgbaImage::new(1, 1, [200, 100, 0, 255]));
        assert_eq!(third.pixels[0][0], 88);
    }

    #[test]
    fn alpha_one_is_no_smoothing() {
        let mut s = Smoother::new(1.0);
        s.apply(RgbaImage::new(1, 1, [0, 0, 0, 255]));
        assert_eq!(
            s.apply(RgbaImage::new(1, 1, [9, 8, 7, 255])).pixels[0],
            [9, 8, 7, 255]
        );
    }
}
