//! A figure comparing methods by the perceptual model (docs/algorithm.md, *What it reports*):
//! per method one row, perceived original | perceived output | the content pixels by class
//! (left alone green, brought to the target cyan, out of reach magenta, as the perceptual
//! method's heatmap paints them), under a title with the method's c' gain and fractions.

use super::figure::{
    blit, label_box, shrink, BACKDROP, GAP, LABEL_SCALE, MAP_EMPTY, MAX_PANEL_WIDTH, TEXT,
};
use super::font::{draw_text, text_height};
use super::perceived::perceived;
use crate::algorithm::perception::perceived_contrast::Model;
use crate::algorithm::perception::perceptual_pixel::Class;
use crate::algorithm::Params;
use crate::background_preparation::PreparedBackground;
use crate::colour;
use crate::image::RgbaImage;

/// The class colours of the perceptual method's heatmap.
pub const LEFT_ALONE: [u8; 4] = [0, 255, 0, 255];
pub const BROUGHT_TO_TARGET: [u8; 4] = [0, 255, 255, 255];
pub const OUT_OF_REACH: [u8; 4] = [255, 0, 255, 255];

/// Each pixel of `output` (the output of any method for `display`) by its class under `model`
/// over the prepared background `bg`; pixels without content near black.
pub fn class_map(
    display: &RgbaImage,
    output: &RgbaImage,
    bg: &PreparedBackground,
    model: &Model,
) -> RgbaImage {
    let linear = |p: [u8; 4]| colour::srgb8_to_linear([p[0], p[1], p[2]]);
    let pixels = display
        .pixels
        .iter()
        .zip(&output.pixels)
        .zip(&bg.linear)
        .map(|((&d, &o), &b)| {
            if d[3] == 0 || d[..3] == [0, 0, 0] {
                return MAP_EMPTY;
            }
            let before = model.perceived_contrast(linear(d), b);
            let after = model.perceived_contrast(linear(o), b);
            match Class::of(before, after, model.target_contrast) {
                Class::LeftAlone => LEFT_ALONE,
                Class::BroughtToTarget => BROUGHT_TO_TARGET,
                _ => OUT_OF_REACH,
            }
        })
        .collect();
    RgbaImage {
        width: display.width,
        height: display.height,
        pixels,
        has_alpha: false,
    }
}

/// One method's row: perceived original | perceived output | classes, under `title`.
pub fn class_row(
    (display, output, camera): (&RgbaImage, &RgbaImage, &RgbaImage),
    bg: &PreparedBackground,
    params: &Params,
    model: &Model,
    title: &str,
) -> RgbaImage {
    let factor = display.width.div_ceil(MAX_PANEL_WIDTH).max(1);
    let panels = [
        (
            shrink(&perceived(display, camera, params), factor),
            "PERCEIVED ORIGINAL",
        ),
        (
            shrink(&perceived(output, camera, params), factor),
            "PERCEIVED OUTPUT",
        ),
        (
            shrink(&class_map(display, output, bg, model), factor),
            "CLASSES",
        ),
    ];
    let (pw, ph) = (panels[0].0.width, panels[0].0.height);
    let header = text_height(LABEL_SCALE) + GAP;
    let width = 3 * pw + 2 * GAP;
    let mut row = RgbaImage::new(width, header + ph, BACKDROP);
    row.has_alpha = false;
    draw_text(&mut row, 0, 0, title, LABEL_SCALE, TEXT);
    let label_scale = if pw >= 240 { LABEL_SCALE } else { 1 };
    for (i, (panel, label)) in panels.iter().enumerate() {
        let x = i as u32 * (pw + GAP);
        blit(&mut row, panel, x, header);
        label_box(&mut row, x + 6, header + 6, label, label_scale);
    }
    row
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::perception::frequency::Frequencies;
    use crate::algorithm::perceptual_settings::PerceptualSettings;

    /// By hand from docs/algorithm.md's second worked example (grey 0.5 over a grey 0.8 world
    /// of 5000 cd/m^2 behind a lens of 0.3, 2 cpd: c' 0.0307): below a target of 0.05 before;
    /// white over it has c 0.0769 and C about 8.5, c' about 0.068, at the target after.
    #[test]
    fn pixels_are_coloured_by_their_class() {
        let settings = PerceptualSettings {
            world_nits: 5000.0,
            ..PerceptualSettings::default()
        };
        let model = Model::new(&settings, 0.3, Frequencies::One(2.0));
        let grey = colour::quantize(colour::srgb_encode(0.5));
        let mut display = RgbaImage::new(3, 1, [grey, grey, grey, 255]);
        display.pixels[2] = [0, 0, 0, 255];
        let mut output = display.clone();
        output.pixels[1] = [255, 255, 255, 255];
        let bg = PreparedBackground {
            width: 3,
            height: 1,
            linear: vec![glam::DVec3::splat(0.8); 3],
            scaled: vec![glam::DVec3::ZERO; 3],
        };
        let map = class_map(&display, &output, &bg, &model);
        assert_eq!(map.pixels, [OUT_OF_REACH, BROUGHT_TO_TARGET, MAP_EMPTY]);
        let low = Model {
            target_contrast: 0.02,
            ..model
        };
        assert_eq!(
            class_map(&display, &output, &bg, &low).pixels[0],
            LEFT_ALONE
        );
    }
}
