//! Figures: simulated perceived original | simulated perceived enhanced | the paper's cyan map
//! of enhanced pixels with their percentage. One row per run; rows stack for a lambda_e sweep.

use super::font::{draw_text, text_height, text_width};
use super::metric::{enhanced_mask, metrics};
use super::perceived::perceived;
use crate::algorithm::Params;
use crate::background_preparation;
use crate::colour;
use crate::image::RgbaImage;

pub(super) const MARGIN: u32 = 16;
pub(super) const GAP: u32 = 12;
/// Panels wider than this are shrunk by an integer factor so a figure stays a screen wide.
pub(super) const MAX_PANEL_WIDTH: u32 = 640;
pub(super) const BACKDROP: [u8; 4] = [22, 24, 28, 255];
pub(super) const TEXT: [u8; 4] = [236, 238, 242, 255];
const CYAN: [u8; 4] = [0, 255, 255, 255];
/// Map colour of display pixels that are not foreground (transparent on the headset).
pub(super) const MAP_EMPTY: [u8; 4] = [14, 16, 20, 255];
pub(super) const LABEL_SCALE: u32 = 2;
const LABEL_PAD: u32 = 6;

/// One figure row without a title, on its own backdrop.
pub fn figure(
    display: &RgbaImage,
    enhanced: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
) -> RgbaImage {
    stack_rows(&[figure_row(display, enhanced, camera, params, None)])
}

/// The three panels for one enhancement, optionally under a title line (e.g. "λE = 0.4").
pub fn figure_row(
    display: &RgbaImage,
    enhanced: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
    title: Option<&str>,
) -> RgbaImage {
    let layout = Layout {
        app_images: false,
        max_panel_width: MAX_PANEL_WIDTH,
    };
    panels_row(display, enhanced, camera, params, title, layout)
}

/// Like `figure`, with the app's image and the enhanced image (as rendered, before blending
/// with the world) in front: what the demo shows of a captured frame.
pub fn figure_with_app_images(
    display: &RgbaImage,
    enhanced: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
) -> RgbaImage {
    figure_with_app_images_at(display, enhanced, camera, params, MAX_PANEL_WIDTH)
}

/// `figure_with_app_images` with panels shrunk to at most `max_panel_width` (an animation's
/// frames are kept smaller than a still figure).
pub fn figure_with_app_images_at(
    display: &RgbaImage,
    enhanced: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
    max_panel_width: u32,
) -> RgbaImage {
    let layout = Layout {
        app_images: true,
        max_panel_width,
    };
    stack_rows(&[panels_row(display, enhanced, camera, params, None, layout)])
}

#[derive(Clone, Copy)]
struct Layout {
    app_images: bool,
    max_panel_width: u32,
}

fn panels_row(
    display: &RgbaImage,
    enhanced: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
    title: Option<&str>,
    layout: Layout,
) -> RgbaImage {
    let bg = background_preparation::prepare(camera, display.width, display.height, params);
    let percent = metrics(display, enhanced, &bg).enhanced_percent;
    let mask = enhanced_mask(display, enhanced, &bg);
    let factor = display.width.div_ceil(layout.max_panel_width.max(1)).max(1);
    let mut panels = Vec::new();
    if layout.app_images {
        panels.push((shrink(display, factor), "APP IMAGE"));
        panels.push((shrink(enhanced, factor), "ENHANCED IMAGE"));
    }
    panels.push((
        shrink(&perceived(display, camera, params), factor),
        "PERCEIVED ORIGINAL",
    ));
    panels.push((
        shrink(&perceived(enhanced, camera, params), factor),
        "PERCEIVED ENHANCED",
    ));
    panels.push((shrink(&cyan_map(display, &mask), factor), "ENHANCED PIXELS"));
    let n = panels.len() as u32;
    let (pw, ph) = (panels[0].0.width, panels[0].0.height);
    let header = title.map_or(0, |_| text_height(LABEL_SCALE) + GAP);
    let width = n * pw + (n - 1) * GAP;
    let mut row = RgbaImage::new(width, header + ph, BACKDROP);
    row.has_alpha = false;
    if let Some(t) = title {
        draw_text(&mut row, 0, 0, t, LABEL_SCALE, TEXT);
    }
    // Labels of small panels in the small font, so they stay within their panel.
    let label_scale = if pw >= 240 { LABEL_SCALE } else { 1 };
    for (i, (panel, label)) in panels.iter().enumerate() {
        let x = i as u32 * (pw + GAP);
        blit(&mut row, panel, x, header);
        label_box(
            &mut row,
            x + LABEL_PAD,
            header + LABEL_PAD,
            label,
            label_scale,
        );
    }
    let text = format!("{percent:.1}%");
    let scale = match pw {
        400.. => 5,
        240.. => 3,
        _ => 2,
    };
    let x = width.saturating_sub(text_width(&text, scale) + 3 * LABEL_PAD);
    let y = (header + ph).saturating_sub(text_height(scale) + 3 * LABEL_PAD);
    label_box(&mut row, x, y, &text, scale);
    row
}

/// Stacks rows top to bottom with margins on one backdrop.
pub fn stack_rows(rows: &[RgbaImage]) -> RgbaImage {
    let width = rows.iter().map(|r| r.width).max().unwrap_or(0) + 2 * MARGIN;
    let gaps = GAP * rows.len().saturating_sub(1) as u32;
    let height = rows.iter().map(|r| r.height).sum::<u32>() + gaps + 2 * MARGIN;
    let mut out = RgbaImage::new(width, height, BACKDROP);
    out.has_alpha = false;
    let mut y = MARGIN;
    for r in rows {
        blit(&mut out, r, MARGIN, y);
        y += r.height + GAP;
    }
    out
}

/// The paper's map: enhanced pixels cyan, other foreground pixels as a dim grey of their
/// luminance (so the content stays recognisable), transparent pixels near black.
fn cyan_map(display: &RgbaImage, mask: &[bool]) -> RgbaImage {
    let pixels = display
        .pixels
        .iter()
        .zip(mask)
        .map(|(&d, &enhanced)| {
            if enhanced {
                CYAN
            } else if d[3] == 0 || d[..3] == [0, 0, 0] {
                MAP_EMPTY
            } else {
                let y = colour::linear_to_xyz(colour::srgb8_to_linear([d[0], d[1], d[2]])).y;
                let g = colour::quantize(colour::srgb_encode((0.05 + 0.25 * y).min(1.0)));
                [g, g, g, 255]
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

/// Box-filter downscale by an integer factor (1 = copy).
pub(super) fn shrink(img: &RgbaImage, factor: u32) -> RgbaImage {
    if factor <= 1 {
        return img.clone();
    }
    let (w, h) = ((img.width / factor).max(1), (img.height / factor).max(1));
    let mut out = RgbaImage::new(w, h, [0, 0, 0, 255]);
    out.has_alpha = false;
    let n = factor * factor;
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0u32; 3];
            for dy in 0..factor {
                for dx in 0..factor {
                    let p = img.get(x * factor + dx, y * factor + dy);
                    (0..3).for_each(|c| sum[c] += u32::from(p[c]));
                }
            }
            let [r, g, b] = sum.map(|s| ((s + n / 2) / n) as u8);
            out.set(x, y, [r, g, b, 255]);
        }
    }
    out
}

pub(super) fn blit(dst: &mut RgbaImage, src: &RgbaImage, x0: u32, y0: u32) {
    for y in 0..src.height.min(dst.height.saturating_sub(y0)) {
        for x in 0..src.width.min(dst.width.saturating_sub(x0)) {
            dst.set(x0 + x, y0 + y, src.get(x, y));
        }
    }
}

/// Text on a translucent dark box, legible on any panel.
pub(super) fn label_box(img: &mut RgbaImage, x: u32, y: u32, text: &str, scale: u32) {
    let (w, h) = (
        text_width(text, scale) + 2 * LABEL_PAD,
        text_height(scale) + 2 * LABEL_PAD,
    );
    for py in y..(y + h).min(img.height) {
        for px in x..(x + w).min(img.width) {
            let p = img.get(px, py);
            img.set(px, py, [p[0] / 3, p[1] / 3, p[2] / 3, 255]);
        }
    }
    draw_text(img, x + LABEL_PAD, y + LABEL_PAD, text, scale, TEXT);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shrink_averages_blocks() {
        let mut img = RgbaImage::new(4, 2, [0, 0, 0, 255]);
        img.set(0, 0, [200, 100, 40, 255]);
        img.set(1, 1, [100, 50, 20, 255]);
        let s = shrink(&img, 2);
        assert_eq!((s.width, s.height), (2, 1));
        assert_eq!(s.get(0, 0), [75, 38, 15, 255]);
        assert_eq!(s.get(1, 0), [0, 0, 0, 255]);
    }

    #[test]
    fn cyan_map_marks_only_enhanced_foreground() {
        let mut display = RgbaImage::new(3, 1, [0, 0, 0, 255]);
        display.set(1, 0, [255, 255, 255, 255]);
        display.set(2, 0, [255, 255, 255, 255]);
        let map = cyan_map(&display, &[false, true, false]);
        assert_eq!(map.get(0, 0), MAP_EMPTY);
        assert_eq!(map.get(1, 0), CYAN);
        // White at 30% of full luminance, encoded: about code 149.
        let g = map.get(2, 0)[0];
        assert!((145..=152).contains(&g), "{g}");
    }
}
