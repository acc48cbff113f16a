//! The shaders by identity: which embedded SPIR-V module a pass, a blur width, a method, a view
//! mode and a pixel format need (ids into `modules::all()`, generated with it by build.rs).

use super::codes::mode_code;
use super::modules::{self, VariantRow};
use super::plan::ClassifyCover;
use super::variant_key::VariantKey;
use crate::algorithm::params::ViewMode;
use std::fmt;

/// One shader of `modules::all()`, by its id: its index there, which build.rs writes with the
/// list (src/gpu/core/modules.rs), so no id here is counted by position.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ShaderId(pub(crate) usize);

pub const DECODE_CAMERA: ShaderId = ShaderId(modules::ID_DECODE_CAMERA);
pub const FINISH_TILES: ShaderId = ShaderId(modules::ID_FINISH_TILES);
pub const COPY_PIXELS: ShaderId = ShaderId(modules::ID_COPY_PIXELS);
pub const COPY_ROWS: ShaderId = ShaderId(modules::ID_COPY_ROWS);

/// No shader is built for the asked blur, method, view mode and pixel format. A backend turns
/// it into its own error (`GpuError::Unsupported` for Vulkan).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NoShader;

impl fmt::Display for NoShader {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("no shader for this method, mode and format")
    }
}

impl std::error::Error for NoShader {}

/// Whether a shader works on the camera frame (the background's descriptor set) rather than
/// on a view.
pub fn reads_camera(ShaderId(k): ShaderId) -> bool {
    modules::MODULES.get(k).is_some_and(|m| m.camera)
}

/// The background pass for a blur half-width (0..=7).
pub fn decode_blur(half: u32) -> Result<ShaderId, NoShader> {
    modules::DECODE_BLUR
        .get(half as usize)
        .map(|&k| ShaderId(k))
        .ok_or(NoShader)
}

/// The `enhance` shader of a view's variant (`key`): the general one, valid for every mapping;
/// with the cube roots the key asks for where such a variant is built, else the Newton steps'.
pub fn enhance(key: VariantKey) -> Result<ShaderId, NoShader> {
    enhance_variant(key, false).ok_or(NoShader)
}

/// The shared-fetch variant of `enhance` (valid only where gpu/core/shared_fetch.rs says so), where
/// one is built (the defaults: see build.rs).
pub fn enhance_shared(key: VariantKey) -> Option<ShaderId> {
    enhance_variant(key, true)
}

fn enhance_variant(key: VariantKey, shared: bool) -> Option<ShaderId> {
    variant_of(modules::ENHANCE_VARIANTS, key, shared).map(ShaderId)
}

/// The id in a variant table (the SPIR-V one or OpenGL's, whose rows are alike) of `key`'s
/// variant with its sampling (`shared`): with the cube roots the key asks for where built, else
/// the Newton steps'.
pub fn variant_of(table: &[VariantRow], key: VariantKey, shared: bool) -> Option<usize> {
    let by_pow = key.roots.by_pow();
    let found = |pow| row_of(table, key, shared, pow);
    found(by_pow).or_else(|| found(false).filter(|_| by_pow))
}

/// The id of the row for `key`, its sampling and cube roots. MODE_BACKGROUND has one variant,
/// the paper's without extras, whatever the key's method and extras.
fn row_of(table: &[VariantRow], key: VariantKey, shared: bool, pow: bool) -> Option<usize> {
    let background = key.mode == mode_code(ViewMode::Background);
    let (method, extras) = match background {
        true => (0, false),
        false => (key.method, key.extras),
    };
    let wanted = (
        method, key.mode, key.format, key.access, extras, shared, pow,
    );
    table
        .iter()
        .find(|&&(m, v, f, a, e, s, p, _)| (m, v, f, a, e, s, p) == wanted)
        .map(|&(.., k)| k)
}

/// The benchmark's `enhance` of a method (its code) with the ablations `ablate`
/// (interface.rs ABLATE_*), reaching the pixels by `access`, sampling by shared fetches
/// (`shared`: the paper's method only) or the general way, with the cube roots by `pow` or the
/// Newton steps: the paper's or the perceptual method, in mode enhance on RGBA8 sRGB; None for
/// the others.
pub fn enhance_ablated(
    method: u32,
    access: u32,
    ablate: u32,
    (shared, pow): (bool, bool),
) -> Option<ShaderId> {
    modules::ENHANCE_ABLATED
        .iter()
        .find(|&&(m, a, x, s, p, _)| (m, a, x, s, p) == (method, access, ablate, shared, pow))
        .map(|&(.., k)| ShaderId(k))
}

/// The `classify` shader for a pixel format (shader code), pixel access, the method code it
/// lists tiles for and its cover (`VariantKey::classify_taken`).
pub fn classify(
    format: u32,
    access: u32,
    (method, cover): (u32, ClassifyCover),
) -> Result<ShaderId, NoShader> {
    let rows = cover == ClassifyCover::TileRows;
    modules::CLASSIFY_VARIANTS
        .iter()
        .find(|&&(f, a, m, r, _)| (f, a, m, r) == (format, access, method, rows))
        .map(|&(.., k)| ShaderId(k))
        .ok_or(NoShader)
}

/// The FORMAT code of a variant that writes `app_image` (in place, or read through a sampled
/// view); None for the others.
pub fn in_place_format(ShaderId(k): ShaderId) -> Option<u32> {
    modules::MODULES.get(k)?.in_place
}

/// Whether a variant reads the app's image through a sampled view (`app_texels`,
/// interface.rs ACCESS_SAMPLED).
pub fn reads_sampled(ShaderId(k): ShaderId) -> bool {
    modules::MODULES.get(k).is_some_and(|m| m.sampled)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::params::Method;
    use crate::gpu::core::codes::method_code;
    use crate::gpu::core::interface::{ACCESS_IN_PLACE, ACCESS_SAMPLED};
    use crate::gpu::core::variant_key::CubeRoots;

    /// The ids name the shaders they stand for in `modules::all()`.
    #[test]
    fn ids_index_the_shader_list() {
        let all = modules::all();
        let name = |id: ShaderId| all[id.0].name;
        assert_eq!(name(DECODE_CAMERA), "decode_camera");
        assert_eq!(name(FINISH_TILES), "finish_tiles");
        assert_eq!(name(COPY_PIXELS), "copy_pixels");
        assert_eq!(name(COPY_ROWS), "copy_rows");
        assert_eq!(name(decode_blur(3).unwrap()), "decode_blur_3");
        assert!(decode_blur(8).is_err());
        let key = |(method, mode, format), access, extras, pow: bool| VariantKey {
            method,
            mode,
            format,
            access,
            extras,
            roots: [CubeRoots::Newton, CubeRoots::Pow][usize::from(pow)],
        };
        for &(m, v, f, w, e, shared, pow, k) in modules::ENHANCE_VARIANTS {
            let key = key((m, v, f), w, e, pow);
            let id = match shared {
                true => enhance_shared(key),
                false => enhance(key).ok(),
            };
            assert_eq!(id, Some(ShaderId(k)));
            let s = if shared { "_s" } else { "" };
            let p = if pow { "_p" } else { "" };
            let file = format!("enhance_m{m}_v{v}_f{f}_a{w}_e{}{s}{p}", u8::from(e));
            assert_eq!(name(ShaderId(k)), file);
        }
        // The defaults have a shared-fetch variant for every format and access; the others
        // none.
        let (paper, enhance_mode) = (0, mode_code(ViewMode::Enhance));
        for &(f, w, ..) in modules::CLASSIFY_VARIANTS.iter().filter(|v| !v.3) {
            assert!(enhance_shared(key((paper, enhance_mode, f), w, false, false)).is_some());
            assert!(enhance_shared(key((paper, enhance_mode, f), w, true, false)).is_none());
            assert!(enhance_shared(key((1, enhance_mode, f), w, false, false)).is_none());
            let background = (paper, mode_code(ViewMode::Background), f);
            assert!(enhance_shared(key(background, w, false, false)).is_none());
            // Asked for the cube roots by pow: their variant where it is built (the ways a
            // GPU's views take), else the Newton steps' one.
            for shared in [false, true] {
                let variant =
                    |pow| enhance_variant(key((paper, enhance_mode, f), w, false, pow), shared);
                let built = w == ACCESS_IN_PLACE || w == ACCESS_SAMPLED;
                assert_eq!(
                    variant(true) != variant(false),
                    built,
                    "format {f}, access {w}"
                );
                assert!(variant(true).is_some());
            }
            let split = key((paper, mode_code(ViewMode::Split), f), w, false, true);
            assert_eq!(enhance(split), enhance(split.with_roots(CubeRoots::Newton)));
        }
        // Two per format and access: the paper's and the perceptual method's; and the
        // perceptual method's by tile rows for the ablations' accesses of RGBA8 sRGB.
        let perceptual = method_code(Method::Perceptual);
        let srgb8 = crate::gpu::core::PixelFormat::SRGB8.shader_code();
        for &(f, w, m, rows, k) in modules::CLASSIFY_VARIANTS {
            let cover = [ClassifyCover::Tiles, ClassifyCover::TileRows][usize::from(rows)];
            assert_eq!(classify(f, w, (m, cover)).unwrap(), ShaderId(k));
            let own = if m == perceptual { "_perceptual" } else { "" };
            let by_rows = if rows { "_rows" } else { "" };
            assert_eq!(
                name(ShaderId(k)),
                format!("classify_f{f}_a{w}{own}{by_rows}")
            );
            assert!(m == perceptual || m == paper);
            assert!(!rows || (m == perceptual && f == srgb8 && w != ACCESS_SAMPLED));
        }
        let counted = |m, rows| {
            modules::CLASSIFY_VARIANTS
                .iter()
                .filter(|v| (v.2, v.3) == (m, rows))
                .count()
        };
        assert_eq!(counted(perceptual, false), counted(paper, false));
        assert_eq!(counted(perceptual, true), 3);
        assert_eq!(counted(paper, true), 0);
        assert!(reads_camera(decode_blur(7).unwrap()) && reads_camera(DECODE_CAMERA));
        let rgba8 = crate::gpu::core::interface::LAYOUT_RGBA8;
        assert_eq!(
            in_place_format(
                classify(rgba8, ACCESS_IN_PLACE, (paper, ClassifyCover::Tiles)).unwrap()
            ),
            Some(rgba8)
        );
        assert_eq!(
            in_place_format(classify(rgba8, 0, (perceptual, ClassifyCover::Tiles)).unwrap()),
            None
        );
        assert_eq!(in_place_format(FINISH_TILES), None);
        // Each method's ablations for each access of RGBA8 sRGB, in place in its texel.
        use crate::gpu::core::interface::{ABLATIONS, FORMAT_SRGB_BIT, PERCEPTUAL_ABLATIONS};
        let srgb8 = rgba8 | FORMAT_SRGB_BIT;
        for &(m, access, ablate, shared, pow, k) in modules::ENHANCE_ABLATED {
            assert_eq!(
                enhance_ablated(m, access, ablate, (shared, pow)),
                Some(ShaderId(k))
            );
            let file = format!("enhance_ablated_m{m}_f{srgb8}_a{access}_x{ablate}");
            let file = file + if pow { "_p" } else { "" } + if shared { "_s" } else { "" };
            assert_eq!(name(ShaderId(k)), file);
            let in_place = (access == ACCESS_IN_PLACE).then_some(srgb8);
            assert_eq!(in_place_format(ShaderId(k)), in_place);
        }
        // The paper's twice (general sampling and shared fetches), the perceptual method's
        // once; each with both ways of taking the cube roots.
        let ablations = 2 * ABLATIONS.len() + PERCEPTUAL_ABLATIONS.len();
        assert_eq!(modules::ENHANCE_ABLATED.len(), 2 * 3 * ablations);
        assert_eq!(
            enhance_ablated(paper, ACCESS_IN_PLACE, 0, (false, false)),
            None
        );
        assert!(!reads_camera(FINISH_TILES));
    }
}
