//! The paper's "enhanced pixel" metric (eq. test_diff, spec section 4).

use glam::DVec3;
use serde::Serialize;

use crate::background::PreparedBackground;
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

/// The metric of spec section 4 for an output image against its display image, with B the
/// same preprocessed background the optimiser used.
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
