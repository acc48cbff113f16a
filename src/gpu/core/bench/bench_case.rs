//! What the benchmark (gpu/vulkan/offline/bench.rs) times: its cases, the display content and the camera
//! frame.

use crate::algorithm::params::Method;
use crate::gpu::core::interface::{
    ABLATE_BACKGROUND, ABLATE_BISECTION, ABLATE_CODEC, ABLATE_CUBE_ROOT, ABLATE_DIRECTIONS,
    ABLATE_ENHANCE_PASS, ABLATE_METHOD, ABLATIONS, PERCEPTUAL_ABLATIONS,
};
use crate::gpu::core::ClassifyChoice;

/// The camera frame size the background preparation is timed with (a common camera mode).
pub const CAMERA_SIZE: (u32, u32) = (1280, 720);
/// Runs before the timed ones (pipeline warm-up, caches, clocks).
pub const WARM_UP_RUNS: u32 = 3;

/// What the display regions hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    /// A typical mixed-reality frame: black (see-through) with two UI panels and a shaded
    /// object, about 17% of the pixels foreground.
    Typical,
    /// Every pixel foreground (a colourful gradient, never black).
    Full,
}

impl Content {
    pub const ALL: [Content; 2] = [Content::Typical, Content::Full];

    pub fn name(self) -> &'static str {
        match self {
            Content::Typical => "typical",
            Content::Full => "full",
        }
    }
}

/// What the benchmark takes out of the enhancement, to show what that part costs
/// (`contrastxr bench --ablate`, either engine; `SharedFetch` Vulkan only); with any but `None`
/// the views' output is not an enhancement. The ablated variants are built for the paper's and the perceptual method on
/// RGBA8 sRGB, the bench's format (src/gpu/core/interface.rs ABLATE_*), each ablation for the
/// methods `applies_to` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ablation {
    /// The enhancement as the layer runs it.
    None,
    /// No scaled-space conversion and no method: each pixel's output is its display colour.
    Method,
    /// A constant mid-grey background instead of the camera texels' reads.
    Background,
    /// No sRGB decode or encode: the stored values taken as linear.
    Codec,
    /// The three above together: the pass's loads, quantisation and stores left.
    PerPixel,
    /// The enhance pass returns at once: classify, finish_tiles and an empty indirect dispatch.
    EnhancePass,
    /// The general background sampling instead of the shared fetches.
    SharedFetch,
    /// The cube roots by the driver's `pow` instead of the Newton steps (replaced, not taken
    /// out: the output is still an enhancement).
    CubeRoot,
    /// The perceptual method's 18 directions: the paper's colour the only candidate.
    Directions,
    /// The perceptual method's bisection back toward the display colour.
    Bisection,
    /// The perceptual method's whole search: its directions and its bisection.
    Search,
    /// The perceptual method's own `classify`: the paper's lists every tile with content.
    Classify,
    /// The perceptual method's own `classify` with an invocation per tile row instead of per
    /// tile (replaced, not taken out: the same tiles listed, the output still the
    /// enhancement).
    ClassifyRows,
}

impl Ablation {
    pub const ALL: [Ablation; 13] = [
        Ablation::None,
        Ablation::Method,
        Ablation::Background,
        Ablation::Codec,
        Ablation::PerPixel,
        Ablation::EnhancePass,
        Ablation::SharedFetch,
        Ablation::CubeRoot,
        Ablation::Directions,
        Ablation::Bisection,
        Ablation::Search,
        Ablation::Classify,
        Ablation::ClassifyRows,
    ];

    /// Its name on the command line and in the bench's output.
    pub fn name(self) -> &'static str {
        match self {
            Ablation::None => "none",
            Ablation::Method => "method",
            Ablation::Background => "background",
            Ablation::Codec => "codec",
            Ablation::PerPixel => "per-pixel",
            Ablation::EnhancePass => "enhance-pass",
            Ablation::SharedFetch => "shared-fetch",
            Ablation::CubeRoot => "cube-root",
            Ablation::Directions => "directions",
            Ablation::Bisection => "bisection",
            Ablation::Search => "search",
            Ablation::Classify => "classify",
            Ablation::ClassifyRows => "classify-rows",
        }
    }

    /// Whether it is built for `method` (interface.rs ABLATIONS for the paper's,
    /// PERCEPTUAL_ABLATIONS for the perceptual method; only the paper's has shared fetches,
    /// only the perceptual method a `classify` of its own).
    pub fn applies_to(self, method: Method) -> bool {
        let bits = self.bits();
        match (method, self) {
            (_, Ablation::None) => true,
            (Method::Paper, Ablation::SharedFetch) => true,
            (Method::Perceptual, Ablation::Classify | Ablation::ClassifyRows) => true,
            (_, Ablation::SharedFetch | Ablation::Classify | Ablation::ClassifyRows) => false,
            (Method::Paper, _) => ABLATIONS.contains(&bits),
            (Method::Perceptual, _) => PERCEPTUAL_ABLATIONS.contains(&bits),
            _ => false,
        }
    }

    /// The `classify` views take under it.
    pub fn classify(self) -> ClassifyChoice {
        match self {
            Ablation::Classify => ClassifyChoice::Paper,
            Ablation::ClassifyRows => ClassifyChoice::OwnByRows,
            _ => ClassifyChoice::Own,
        }
    }

    /// The ABLATE_* bits of its `enhance` variant (0: the layer's own).
    pub fn bits(self) -> u32 {
        match self {
            Ablation::None
            | Ablation::SharedFetch
            | Ablation::Classify
            | Ablation::ClassifyRows => 0,
            Ablation::Method => ABLATE_METHOD,
            Ablation::Background => ABLATE_BACKGROUND,
            Ablation::Codec => ABLATE_CODEC,
            Ablation::PerPixel => ABLATE_METHOD | ABLATE_BACKGROUND | ABLATE_CODEC,
            Ablation::EnhancePass => ABLATE_ENHANCE_PASS,
            Ablation::CubeRoot => ABLATE_CUBE_ROOT,
            Ablation::Directions => ABLATE_DIRECTIONS,
            Ablation::Bisection => ABLATE_BISECTION,
            Ablation::Search => ABLATE_DIRECTIONS | ABLATE_BISECTION,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct BenchCase {
    /// Per view.
    pub region: (u32, u32),
    pub views: u32,
    pub content: Content,
    /// Timed runs; the result is their median.
    pub runs: u32,
    /// Also time the layer's frame in place (the app's images with storage usage, enhanced
    /// through storage views), where the device can.
    pub in_place: bool,
    /// Also time the layer's frame through the image-copy path (each region copied into an
    /// image of the engine's own with storage usage, enhanced there by the in-place shaders,
    /// copied back), where the device can store to its format.
    pub image_copy: bool,
    /// Also time the image-copy path with only the listed tiles drawn back (a render pass)
    /// instead of the regions copied back. On a CPU driver a draw leaves the timestamps of
    /// later compute work unreliable (lavapipe bins them with its rasteriser's scene), so the
    /// CLI asks for it there only with `--path tiles`.
    pub tiles: bool,
    pub ablation: Ablation,
}

/// One RGBA8 pixel (R in the low byte) of the given content at (x, y) of a w x h region.
pub fn content_pixel(content: Content, x: u32, y: u32, w: u32, h: u32) -> u32 {
    let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
    let rgba = |r: f32, g: f32, b: f32| {
        let q = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u32;
        q(r) | q(g) << 8 | q(b) << 16 | 255 << 24
    };
    if content == Content::Full {
        return rgba(u.max(0.01), v, 0.5 + 0.5 * (u - v));
    }
    let inside =
        |x0: f32, x1: f32, y0: f32, y1: f32| (x0..x1).contains(&u) && (y0..y1).contains(&v);
    if inside(0.10, 0.40, 0.30, 0.60) {
        return rgba(0.78, 0.82, 0.90);
    }
    if inside(0.60, 0.85, 0.15, 0.35) {
        return rgba(0.15, 0.63, 0.31);
    }
    let (dx, dy) = ((u - 0.55) * w as f32, (v - 0.65) * h as f32);
    let r = 0.12 * w.min(h) as f32;
    let d2 = (dx * dx + dy * dy) / (r * r);
    if d2 < 1.0 {
        let shade = 1.0 - 0.6 * d2;
        return rgba(0.9 * shade, 0.45 * shade, 0.1 * shade + 0.02);
    }
    0xff00_0000
}

/// A smooth camera frame with some texture (what the blur and FoV mapping see).
pub fn camera_frame(size: (u32, u32)) -> Vec<[u8; 4]> {
    let mut out = Vec::with_capacity((size.0 * size.1) as usize);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let t = ((x * 7 + y * 13) % 32) as u8;
            out.push([
                (x * 255 / size.0) as u8 / 2 + t,
                (y * 255 / size.1) as u8 / 2 + 64,
                160 - t,
                255,
            ]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::core::codes::method_code;
    use crate::gpu::core::interface::ACCESS_WIDE;
    use crate::gpu::core::plan::ClassifyCover;
    use crate::gpu::core::{shader_ids, PixelFormat};

    /// An ablation of the shader applies to a method exactly where its variant is built; the
    /// three that pick another variant, only to the method that has what they replace.
    #[test]
    fn an_ablation_applies_where_its_variant_is_built() {
        for a in Ablation::ALL {
            for m in Method::ALL {
                let built = shader_ids::enhance_ablated(
                    method_code(m),
                    ACCESS_WIDE,
                    a.bits(),
                    (false, false),
                );
                let applies = match a {
                    Ablation::None => true,
                    Ablation::SharedFetch => m == Method::Paper,
                    Ablation::Classify => m == Method::Perceptual,
                    Ablation::ClassifyRows => {
                        let key = (method_code(m), ClassifyCover::TileRows);
                        let srgb8 = PixelFormat::SRGB8.shader_code();
                        shader_ids::classify(srgb8, ACCESS_WIDE, key).is_ok()
                    }
                    _ => built.is_some(),
                };
                assert_eq!(a.applies_to(m), applies, "{} {}", a.name(), m.name());
            }
        }
        let names: std::collections::HashSet<&str> = Ablation::ALL.map(Ablation::name).into();
        assert_eq!(names.len(), Ablation::ALL.len());
        assert!(!names.contains("all"));
    }
}
