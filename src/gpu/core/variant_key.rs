//! Which variant of the per-pixel shaders a view takes: the codes build.rs specialises them on,
//! derived from the settings once for every backend.

use super::codes::{method_code, mode_code};
use super::interface::{MODE_ENHANCE, MODE_SPLIT};
use super::pixel_format::PixelFormat;
use super::plan::ClassifyCover;
use crate::algorithm::params::{Method, Params};

/// The specialisation of a view's `classify` and `enhance`: the method, the view mode, the pixel
/// format, how the pixels are reached (interface.rs ACCESS_*) and whether the method's extra
/// steps run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VariantKey {
    pub method: u32,
    pub mode: u32,
    /// The FORMAT code (`PixelFormat::shader_code`).
    pub format: u32,
    pub access: u32,
    /// The achromatic boost or the luminance cap is on: the variant with those steps.
    pub extras: bool,
    /// How the device would take the CIELAB cube roots (a variant without `pow` ones takes
    /// the Newton steps).
    pub roots: CubeRoots,
}

/// How the CIELAB conversions take their cube roots (shaders/common.wgsl `cbrt`), to within
/// 1e-6 relative either way.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum CubeRoots {
    /// Newton steps from a bit-pattern seed: every variant is built with them.
    #[default]
    Newton,
    /// The driver's `pow`: built for the paper's and the perceptual method in mode enhance,
    /// extras off, in place and through the sampled read (build/variants.rs).
    Pow,
}

impl CubeRoots {
    /// The way a device takes: `pow` on a GPU, whose special-function unit computes it in a
    /// few cycles (on an NVIDIA H200 the paper's enhancement took 10-17% less time with it);
    /// the Newton steps on a CPU driver (lavapipe, llvmpipe), where `pow` costs as much or more.
    pub fn for_device(cpu: bool) -> CubeRoots {
        match cpu {
            true => CubeRoots::Newton,
            false => CubeRoots::Pow,
        }
    }

    /// The variant tables' column: whether the cube roots are by `pow`.
    pub fn by_pow(self) -> bool {
        self == CubeRoots::Pow
    }

    /// As the bench and the logs name it.
    pub fn name(self) -> &'static str {
        match self {
            CubeRoots::Newton => "newton",
            CubeRoots::Pow => "pow",
        }
    }
}

impl VariantKey {
    /// The variant views of `format`, reached by `access`, take under `params` (with the
    /// Newton steps' cube roots: `with_roots` gives a device's own).
    pub fn of(params: &Params, format: PixelFormat, access: u32) -> VariantKey {
        VariantKey {
            method: method_code(params.method),
            mode: mode_code(params.mode),
            format: format.shader_code(),
            access,
            extras: params.achromatic_boost > 0.0 || params.luminance_cap > 0.0,
            roots: CubeRoots::Newton,
        }
    }

    /// The same key on a device that takes its cube roots by `roots`.
    pub fn with_roots(self, roots: CubeRoots) -> VariantKey {
        VariantKey { roots, ..self }
    }

    /// The method code of the view's `classify` variant: the perceptual method's own, which
    /// lists only tiles with a pixel below its target, where it leaves every other pixel as
    /// it is (its enhance and split modes; its heatmap paints every content pixel); the
    /// paper's, which lists every tile with content, for every other method and mode.
    pub fn classify_method(self) -> u32 {
        let perceptual = method_code(Method::Perceptual);
        let leaves_alone = self.mode == MODE_ENHANCE || self.mode == MODE_SPLIT;
        match self.method == perceptual && leaves_alone {
            true => perceptual,
            false => method_code(Method::Paper),
        }
    }

    /// The method code and cover of the `classify` this view takes under `choice`.
    pub fn classify_taken(self, choice: ClassifyChoice) -> (u32, ClassifyCover) {
        let own = self.classify_method();
        match choice {
            ClassifyChoice::Own => (own, ClassifyCover::Tiles),
            ClassifyChoice::Paper => (method_code(Method::Paper), ClassifyCover::Tiles),
            ClassifyChoice::OwnByRows if own == method_code(Method::Perceptual) => {
                (own, ClassifyCover::TileRows)
            }
            ClassifyChoice::OwnByRows => (own, ClassifyCover::Tiles),
        }
    }

    /// Whether the benchmark's ablated `enhance` variants can stand for this one: they are
    /// built in mode enhance on RGBA8 sRGB, extras off (for the paper's and the perceptual
    /// method: the backend's table says which ablations).
    pub fn has_ablated_variants(self) -> bool {
        let srgb8 = PixelFormat::SRGB8.shader_code();
        (self.mode, self.format, self.extras) == (MODE_ENHANCE, srgb8, false)
    }

    /// (method, mode, format): the codes the variant tables are keyed by.
    pub fn codes(self) -> (u32, u32, u32) {
        (self.method, self.mode, self.format)
    }
}

/// Which `classify` views take: their method's own (the layer's), or one the benchmark puts in
/// its place: the paper's, which lists every tile with content (`--ablate classify`), or the
/// perceptual method's own with an invocation per tile row (`--ablate classify-rows`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ClassifyChoice {
    #[default]
    Own,
    Paper,
    OwnByRows,
}

/// Why a view has no ablated variant for the ablations `ablate` (interface.rs ABLATE_*): the
/// backends' error text.
pub fn no_ablated_variant(ablate: u32) -> String {
    format!(
        "no ablated variant {ablate} of this method and format: they are built for the paper's \
         and the perceptual method on RGBA8 sRGB (contrastxr bench --help)"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::params::ViewMode;
    use crate::gpu::core::interface::{ACCESS_IN_PLACE, FORMAT_SRGB_BIT, LAYOUT_RGBA8};

    /// Only the perceptual method's enhance and split modes, where it leaves a pixel at the
    /// target as it is, list tiles by its own classify.
    #[test]
    fn the_perceptual_classify_serves_only_the_modes_that_leave_pixels_alone() {
        let classify = |method, mode| {
            let params = Params {
                method,
                mode,
                ..Params::default()
            };
            VariantKey::of(&params, PixelFormat::SRGB8, ACCESS_IN_PLACE).classify_method()
        };
        let (paper, perceptual) = (method_code(Method::Paper), method_code(Method::Perceptual));
        assert_eq!(classify(Method::Perceptual, ViewMode::Enhance), perceptual);
        assert_eq!(classify(Method::Perceptual, ViewMode::Split), perceptual);
        assert_eq!(classify(Method::Perceptual, ViewMode::Heatmap), paper);
        assert_eq!(classify(Method::Perceptual, ViewMode::Background), paper);
        for method in Method::ALL.into_iter().filter(|&m| m != Method::Perceptual) {
            assert_eq!(classify(method, ViewMode::Enhance), paper);
            assert_eq!(classify(method, ViewMode::Split), paper);
        }
    }

    /// The ablated variants stand only for mode enhance on RGBA8 sRGB with the extras off.
    #[test]
    fn ablated_variants_stand_for_srgb8_in_mode_enhance_without_extras() {
        let key = |mode, format, boost| {
            let params = Params {
                mode,
                achromatic_boost: boost,
                ..Params::default()
            };
            VariantKey::of(&params, format, ACCESS_IN_PLACE)
        };
        let unorm8 = PixelFormat {
            srgb: false,
            ..PixelFormat::SRGB8
        };
        assert!(key(ViewMode::Enhance, PixelFormat::SRGB8, 0.0).has_ablated_variants());
        assert!(!key(ViewMode::Split, PixelFormat::SRGB8, 0.0).has_ablated_variants());
        assert!(!key(ViewMode::Enhance, unorm8, 0.0).has_ablated_variants());
        assert!(!key(ViewMode::Enhance, PixelFormat::SRGB8, 0.2).has_ablated_variants());
        assert!(no_ablated_variant(16).starts_with("no ablated variant 16 "));
        // The benchmark's classify ablation lists every tile, as the paper's classify does.
        let perceptual = VariantKey::of(
            &Params {
                method: Method::Perceptual,
                ..Params::default()
            },
            PixelFormat::SRGB8,
            ACCESS_IN_PLACE,
        );
        let (paper, own) = (method_code(Method::Paper), perceptual.classify_method());
        let (tiles, rows) = (ClassifyCover::Tiles, ClassifyCover::TileRows);
        assert_eq!(perceptual.classify_taken(ClassifyChoice::Own), (own, tiles));
        assert_eq!(
            perceptual.classify_taken(ClassifyChoice::Paper),
            (paper, tiles)
        );
        assert_eq!(
            perceptual.classify_taken(ClassifyChoice::OwnByRows),
            (own, rows)
        );
        // Only the perceptual method's own classify is built by tile rows.
        let paper_key = VariantKey::of(&Params::default(), PixelFormat::SRGB8, ACCESS_IN_PLACE);
        let by_rows = paper_key.classify_taken(ClassifyChoice::OwnByRows);
        assert_eq!(by_rows, (paper, tiles));
    }

    #[test]
    fn the_extras_follow_either_setting() {
        let key = |boost, cap| {
            let params = Params {
                achromatic_boost: boost,
                luminance_cap: cap,
                ..Params::default()
            };
            VariantKey::of(&params, PixelFormat::SRGB8, ACCESS_IN_PLACE)
        };
        assert!(!key(0.0, 0.0).extras);
        assert!(key(0.2, 0.0).extras);
        assert!(key(0.0, 0.9).extras);
        let k = key(0.0, 0.0);
        assert_eq!(k.format, LAYOUT_RGBA8 | FORMAT_SRGB_BIT);
        let method = method_code(Params::default().method);
        assert_eq!(k.codes(), (method, k.mode, k.format));
    }
}
