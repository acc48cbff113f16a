//! The known test pattern: coloured panels on black.
//!
//! Black is what an additive (optical see-through) display shows as transparent, so the pattern is
//! content on black: a 4 x 3 grid of panels (primaries, secondaries, white, greys, pastels) and a
//! grey ramp, covering about 37 % of the view; the rest is exactly black. Each view is shifted
//! horizontally by a different amount, so a layer that mixes up views changes the result.
//! `--content typical` draws a sparser frame instead, `--content image:PATH` a PNG (see
//! `Content`).

use std::path::PathBuf;
use std::sync::OnceLock;

use crate::picture::Picture;
use crate::swapchain_format::SwapchainFormat;

/// The panels' colours, sRGB-encoded.
const PANELS: [[f32; 3]; 12] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 0.0],
    [0.5, 0.5, 0.5],
    [1.0, 0.75, 0.8],
    [0.68, 0.85, 0.9],
    [0.6, 0.9, 0.6],
    [0.2, 0.2, 0.2],
];
const COLUMNS: usize = 4;
/// Panel placement, as fractions of the view: column c starts at `LEFT + c * PITCH_X`.
const LEFT: f32 = 0.1;
const PITCH_X: f32 = 0.2;
const PANEL_W: f32 = 0.15;
const TOP: f32 = 0.08;
const PITCH_Y: f32 = 0.22;
const PANEL_H: f32 = 0.17;
/// The grey ramp below the panels.
const RAMP: (f32, f32, f32, f32) = (0.1, 0.76, 0.9, 0.84);

/// Which image the pattern is for: the views of the projection layer, or the quad layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    View(u32),
    Quad,
}

impl Target {
    /// Horizontal shift of the whole pattern, as a fraction of the width.
    fn shift(self) -> f32 {
        match self {
            Target::View(i) => 0.02 * i as f32,
            Target::Quad => -0.04,
        }
    }
}

/// What one array layer of a swapchain image shows.
pub enum LayerContent {
    /// The whole layer is one target's pattern.
    Whole(Target),
    /// The layer is split in two halves side by side: view 0 left, view 1 right.
    SideBySide,
}

/// The order of an image's rows in memory: Vulkan's first row is the image's top, OpenGL's
/// (glTexSubImage, glGetTexImage) its bottom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rows {
    TopFirst,
    BottomFirst,
}

/// The texels of every layer in `format`, tightly packed, layer after layer, rows in `rows`
/// order.
pub fn image_bytes(
    format: SwapchainFormat,
    (width, height): (u32, u32),
    content: &[LayerContent],
    rows: Rows,
) -> Vec<u8> {
    let mut bytes =
        Vec::with_capacity(format.bytes_per_texel() * (width * height) as usize * content.len());
    for layer in content {
        for row in 0..height {
            let y = match rows {
                Rows::TopFirst => row,
                Rows::BottomFirst => height - 1 - row,
            };
            for x in 0..width {
                let colour = match layer {
                    LayerContent::Whole(target) => texel(*target, x, y, width, height),
                    LayerContent::SideBySide => {
                        let half = width / 2;
                        texel(Target::View(x / half), x % half, y, half, height)
                    }
                };
                format.encode(colour, &mut bytes);
            }
        }
    }
    bytes
}

/// What every image shows (`--content`), chosen once at start.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Content {
    /// The panels and ramp above (about 37 % of each view).
    Panels,
    /// A typical mixed-reality frame, about 17 % foreground: the same two UI panels and shaded
    /// disc as `contrastxr bench`'s typical content (src/gpu/vulkan/offline/bench.rs, `content_pixel`), drawn
    /// here independently of the library, so end-to-end and GPU figures describe alike frames.
    Typical,
    /// A PNG (`picture`), stretched over each view (nearest texel), shifted as the pattern is:
    /// UI panels and text as an app would submit them (`samples/display-*.png`, `scripts/demo`).
    Image(PathBuf),
}

/// What `texel` draws: the content chosen, its picture decoded.
enum Drawn {
    Panels,
    Typical,
    Picture(Picture),
}

static DRAWN: OnceLock<Drawn> = OnceLock::new();

/// Sets what `texel` draws, decoding the picture of `Content::Image`; the first call wins (main
/// calls it once, before any image).
pub fn set_content(content: &Content) -> Result<(), String> {
    let drawn = match content {
        Content::Panels => Drawn::Panels,
        Content::Typical => Drawn::Typical,
        Content::Image(path) => Drawn::Picture(Picture::load(path)?),
    };
    let _ = DRAWN.set(drawn);
    Ok(())
}

/// The colour of texel (x, y) of a `width` x `height` image, as sRGB-encoded RGBA.
pub fn texel(target: Target, x: u32, y: u32, width: u32, height: u32) -> [f32; 4] {
    // Sample at the texel centre, in fractions of the image.
    let u = (x as f32 + 0.5) / width as f32 - target.shift();
    let v = (y as f32 + 0.5) / height as f32;
    let colour = match DRAWN.get() {
        Some(Drawn::Picture(picture)) => return picture.at(u, v).unwrap_or([0.0, 0.0, 0.0, 1.0]),
        Some(Drawn::Typical) => typical_colour(u, v, width, height),
        _ => panel_colour(u, v).or_else(|| ramp_grey(u, v)),
    };
    let [r, g, b] = colour.unwrap_or([0.0; 3]);
    [r, g, b, 1.0]
}

/// Two UI panels and a shaded disc of radius 0.12 x the shorter side, on black.
fn typical_colour(u: f32, v: f32, width: u32, height: u32) -> Option<[f32; 3]> {
    let inside =
        |u0: f32, u1: f32, v0: f32, v1: f32| (u0..u1).contains(&u) && (v0..v1).contains(&v);
    if inside(0.10, 0.40, 0.30, 0.60) {
        return Some([0.78, 0.82, 0.90]);
    }
    if inside(0.60, 0.85, 0.15, 0.35) {
        return Some([0.15, 0.63, 0.31]);
    }
    let (dx, dy) = ((u - 0.55) * width as f32, (v - 0.65) * height as f32);
    let r = 0.12 * width.min(height) as f32;
    let d2 = (dx * dx + dy * dy) / (r * r);
    let shade = 1.0 - 0.6 * d2;
    (d2 < 1.0).then_some([0.9 * shade, 0.45 * shade, 0.1 * shade + 0.02])
}

fn panel_colour(u: f32, v: f32) -> Option<[f32; 3]> {
    let (cu, cv) = ((u - LEFT) / PITCH_X, (v - TOP) / PITCH_Y);
    if cu < 0.0 || cv < 0.0 {
        return None;
    }
    let (column, row) = (cu as usize, cv as usize);
    let inside = cu.fract() * PITCH_X < PANEL_W && cv.fract() * PITCH_Y < PANEL_H;
    (column < COLUMNS && inside)
        .then(|| PANELS.get(row * COLUMNS + column).copied())
        .flatten()
}

fn ramp_grey(u: f32, v: f32) -> Option<[f32; 3]> {
    let (u0, v0, u1, v1) = RAMP;
    let grey = (u - u0) / (u1 - u0);
    (u >= u0 && u < u1 && v >= v0 && v < v1).then_some([grey; 3])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn coverage(target: Target) -> f32 {
        let (w, h) = (320, 240);
        let lit = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| texel(target, x, y, w, h)[..3] != [0.0; 3])
            .count();
        lit as f32 / (w * h) as f32
    }

    #[test]
    fn content_covers_a_third_to_a_half_of_each_view() {
        for target in [Target::View(0), Target::View(1), Target::Quad] {
            let c = coverage(target);
            assert!((0.3..0.5).contains(&c), "{target:?}: {c}");
        }
    }

    #[test]
    fn corners_are_black_and_panels_hold_their_colours() {
        let at = |x, y| texel(Target::View(0), x, y, 1000, 1000);
        assert_eq!(at(0, 0), [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(at(999, 999), [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(at(150, 150), [1.0, 0.0, 0.0, 1.0]); // first panel
        assert_eq!(at(750, 590), [0.2, 0.2, 0.2, 1.0]); // last panel
    }

    #[test]
    fn typical_content_is_about_a_sixth_of_a_view() {
        // Not set_content: the process-wide choice would leak into the other tests.
        let (w, h) = (1268, 720);
        let lit = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                typical_colour(u, v, w, h).is_some()
            })
            .count();
        let fraction = lit as f32 / (w * h) as f32;
        assert!((0.16..0.18).contains(&fraction), "{fraction}");
    }

    #[test]
    fn views_differ() {
        let row = |t| {
            (0..320)
                .map(|x| texel(t, x, 40, 320, 240))
                .collect::<Vec<_>>()
        };
        assert_ne!(row(Target::View(0)), row(Target::View(1)));
        assert_ne!(row(Target::View(0)), row(Target::Quad));
    }
}
