//! The paper's "enhanced pixel" metric (its Evaluation section; docs/algorithm.md, Evaluation
//! metric).

use glam::DVec3;
use serde::Serialize;

use crate::background_preparation::PreparedBackground;
use crate::colour;
use crate::image::RgbaImage;

/// The just noticeable difference of the metric, Delta E*ab in unscaled units (Mahy 1994).
pub const JND_DELTA_E: f64 = 2.3;

/// Minimum, mean and maximum over the foreground pixels (all 0 when there are none).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stats {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

impl Stats {
    fn of(values: impl Iterator<Item = f64>) -> Stats {
        let (mut min, mut max, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0u64);
        for v in values {
            min = min.min(v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
        if n == 0 {
            return Stats {
                min: 0.0,
                mean: 0.0,
                max: 0.0,
            };
        }
        Stats {
            min,
            mean: sum / n as f64,
            max,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// Display pixels that are neither exactly black nor alpha 0.
    pub foreground_pixels: u64,
    /// Foreground pixels with dE(B, out) > dE(B, D) and dE(out, D) >= 2.3.
    pub enhanced_pixels: u64,
    /// 100 * enhanced / foreground (0 without foreground).
    pub enhanced_percent: f64,
    pub delta_e_out_display: Stats,
    pub delta_e_bg_display: Stats,
    pub delta_e_bg_out: Stats,
}

/// The three colour differences of one foreground pixel.
#[derive(Clone, Copy, Debug)]
struct PixelDifferences {
    out_display: f64,
    bg_display: f64,
    bg_out: f64,
}

impl PixelDifferences {
    fn enhanced(&self) -> bool {
        self.bg_out > self.bg_display && self.out_display >= JND_DELTA_E
    }
}

fn is_foreground(p: [u8; 4]) -> bool {
    p[3] != 0 && p[..3] != [0, 0, 0]
}

fn rgb(p: [u8; 4]) -> [u8; 3] {
    [p[0], p[1], p[2]]
}

/// Per display pixel: None for background (transparent) pixels.
fn differences(
    display: &RgbaImage,
    output: &RgbaImage,
    background: &PreparedBackground,
) -> Vec<Option<PixelDifferences>> {
    assert_eq!(
        (display.width, display.height),
        (output.width, output.height)
    );
    assert_eq!(
        (display.width, display.height),
        (background.width, background.height)
    );
    display
        .pixels
        .iter()
        .zip(&output.pixels)
        .zip(&background.scaled)
        .map(|((&d, &o), &b)| {
            if !is_foreground(d) {
                return None;
            }
            let (d, o): (DVec3, DVec3) =
                (colour::srgb8_to_lab(rgb(d)), colour::srgb8_to_lab(rgb(o)));
            let b = colour::scaled_to_lab(b);
            Some(PixelDifferences {
                out_display: colour::delta_e(o, d),
                bg_display: colour::delta_e(b, d),
                bg_out: colour::delta_e(b, o),
            })
        })
        .collect()
}

/// Which display pixels count as enhanced (false for background pixels).
pub fn enhanced_mask(
    display: &RgbaImage,
    output: &RgbaImage,
    background: &PreparedBackground,
) -> Vec<bool> {
    differences(display, output, background)
        .iter()
        .map(|d| d.is_some_and(|d| d.enhanced()))
        .collect()
}

/// The metric (docs/algorithm.md, Evaluation metric) for an output image against its display
/// image, with B the same preprocessed background the optimiser used.
pub fn metrics(
    display: &RgbaImage,
    output: &RgbaImage,
    background: &PreparedBackground,
) -> Metrics {
    let diffs: Vec<PixelDifferences> = differences(display, output, background)
        .into_iter()
        .flatten()
        .collect();
    let foreground = diffs.len() as u64;
    let enhanced = diffs.iter().filter(|d| d.enhanced()).count() as u64;
    let percent = if foreground == 0 {
        0.0
    } else {
        100.0 * enhanced as f64 / foreground as f64
    };
    Metrics {
        foreground_pixels: foreground,
        enhanced_pixels: enhanced,
        enhanced_percent: percent,
        delta_e_out_display: Stats::of(diffs.iter().map(|d| d.out_display)),
        delta_e_bg_display: Stats::of(diffs.iter().map(|d| d.bg_display)),
        delta_e_bg_out: Stats::of(diffs.iter().map(|d| d.bg_out)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3x1: black (not foreground), white turned red, grey 128 left alone; B = mid grey
    /// (scaled origin, LAB (50, 0, 0)). Expected values from the check values of
    /// docs/algorithm.md, CIELAB: white (100, 0, 0), red (53.2408, 80.0925, 67.2032), grey 128
    /// L* 53.585.
    #[test]
    fn hand_computed_case() {
        let mut display = RgbaImage::new(3, 1, [0, 0, 0, 255]);
        display.set(1, 0, [255, 255, 255, 255]);
        display.set(2, 0, [128, 128, 128, 255]);
        let mut output = display.clone();
        output.set(1, 0, [255, 0, 0, 255]);
        let bg = PreparedBackground {
            width: 3,
            height: 1,
            linear: vec![DVec3::splat(0.5); 3],
            scaled: vec![DVec3::ZERO; 3],
        };
        let m = metrics(&display, &output, &bg);
        assert_eq!((m.foreground_pixels, m.enhanced_pixels), (2, 1));
        assert!((m.enhanced_percent - 50.0).abs() < 1e-12);
        let near = |a: f64, b: f64| (a - b).abs() < 2e-4;
        let s = m.delta_e_out_display;
        assert!(
            near(s.min, 0.0) && near(s.max, 114.531661) && near(s.mean, 114.531661 / 2.0),
            "{s:?}"
        );
        let s = m.delta_e_bg_display;
        assert!(
            near(s.min, 3.585) && near(s.max, 50.0) && near(s.mean, 26.7925),
            "{s:?}"
        );
        let s = m.delta_e_bg_out;
        assert!(near(s.min, 3.585) && near(s.max, 104.602014), "{s:?}");
        assert_eq!(enhanced_mask(&display, &output, &bg), [false, true, false]);
    }

    #[test]
    fn change_below_jnd_is_not_enhanced() {
        // Grey 128 -> 129 moves away from a black background by ~0.37 Delta E only.
        let display = RgbaImage::new(1, 1, [128, 128, 128, 255]);
        let output = RgbaImage::new(1, 1, [129, 129, 129, 255]);
        let bg = PreparedBackground {
            width: 1,
            height: 1,
            linear: vec![DVec3::ZERO],
            scaled: vec![DVec3::new(-1.0, 0.0, 0.0)],
        };
        let m = metrics(&display, &output, &bg);
        assert_eq!((m.foreground_pixels, m.enhanced_pixels), (1, 0));
        assert!(m.delta_e_bg_out.max > m.delta_e_bg_display.max);
    }

    #[test]
    fn empty_foreground_reports_zeros() {
        let black = RgbaImage::new(2, 1, [0, 0, 0, 255]);
        let bg = PreparedBackground {
            width: 2,
            height: 1,
            linear: vec![DVec3::ZERO; 2],
            scaled: vec![DVec3::ZERO; 2],
        };
        let m = metrics(&black, &black, &bg);
        assert_eq!((m.foreground_pixels, m.enhanced_percent), (0, 0.0));
        assert_eq!(
            m.delta_e_bg_out,
            Stats {
                min: 0.0,
                mean: 0.0,
                max: 0.0
            }
        );
    }
}
