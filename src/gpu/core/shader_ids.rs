//! The shaders by identity: which embedded SPIR-V module a pass, a blur width, a method, a view
//! mode and a pixel format need (ids into `modules::all()`, generated with it by build.rs).

use super::codes::mode_code;
use super::modules;
use super::plan::ClassifyCover;
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

/// The `enhance` shader for a method, view mode and pixel format (shader codes), reaching the
/// pixels by `access` (interface.rs ACCESS_*); `extras` where the achromatic boost or the
/// luminance cap is on. The general variant: valid for every mapping.
pub fn enhance(codes: (u32, u32, u32), access: u32, extras: bool) -> Result<ShaderId, NoShader> {
    enhance_variant(codes, access, extras, false).ok_or(NoShader)
}

/// The shared-fetch variant of `enhance` (valid only where gpu/core/shared_fetch.rs says so), where
/// one is built (the defaults: see build.rs).
pub fn enhance_shared(codes: (u32, u32, u32), access: u32, extras: bool) -> Option<ShaderId> {
    enhance_variant(codes, access, extras, true)
}

fn enhance_variant(
    (method, mode, format): (u32, u32, u32),
    access: u32,
    extras: bool,
    shared: bool,
) -> Option<ShaderId> {
    let background = mode == mode_code(ViewMode::Background);
    let (method, extras) = if background {
        (0, false)
    } else {
        (method, extras)
    };
    let wanted = (method, mode, format, access, extras, shared);
    modules::ENHANCE_VARIANTS
        .iter()
        .find(|&&(m, v, f, a, e, s, _)| (m, v, f, a, e, s) == wanted)
        .map(|&(.., k)| ShaderId(k))
}

/// The benchmark's `enhance` of a method (its code) with the ablations `ablate`
/// (interface.rs ABLATE_*), reaching the pixels by `access`, sampling by shared fetches
/// (`shared`: the paper's method only) or the general way: the paper's or the perceptual method,
/// in mode enhance on RGBA8 sRGB; None for the others.
pub fn enhance_ablated(method: u32, access: u32, ablate: u32, shared: bool) -> Option<ShaderId> {
    modules::ENHANCE_ABLATED
        .iter()
        .find(|&&(m, a, x, s, _)| (m, a, x, s) == (method, access, ablate, shared))
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
        for &(m, v, f, w, e, shared, k) in modules::ENHANCE_VARIANTS {
            let id = match shared {
                true => enhance_shared((m, v, f), w, e),
                false => enhance((m, v, f), w, e).ok(),
            };
            assert_eq!(id, Some(ShaderId(k)));
            let s = if shared { "_s" } else { "" };
            let file = format!("enhance_m{m}_v{v}_f{f}_a{w}_e{}{s}", u8::from(e));
            assert_eq!(name(ShaderId(k)), file);
        }
        // The defaults have a shared-fetch variant for every format and access; the others
        // none.
        let (paper, enhance_mode) = (0, mode_code(ViewMode::Enhance));
        for &(f, w, ..) in modules::CLASSIFY_VARIANTS.iter().filter(|v| !v.3) {
            assert!(enhance_shared((paper, enhance_mode, f), w, false).is_some());
            assert!(enhance_shared((paper, enhance_mode, f), w, true).is_none());
            assert!(enhance_shared((1, enhance_mode, f), w, false).is_none());
            assert!(
                enhance_shared((paper, mode_code(ViewMode::Background), f), w, false).is_none()
            );
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
        for &(m, access, ablate, shared, k) in modules::ENHANCE_ABLATED {
            assert_eq!(
                enhance_ablated(m, access, ablate, shared),
                Some(ShaderId(k))
            );
            let file = format!("enhance_ablated_m{m}_f{srgb8}_a{access}_x{ablate}");
            let file = if shared { file + "_s" } else { file };
            assert_eq!(name(ShaderId(k)), file);
            let in_place = (access == ACCESS_IN_PLACE).then_some(srgb8);
            assert_eq!(in_place_format(ShaderId(k)), in_place);
        }
        // The paper's twice (general sampling and shared fetches), the perceptual method's once.
        let ablations = 2 * ABLATIONS.len() + PERCEPTUAL_ABLATIONS.len();
        assert_eq!(modules::ENHANCE_ABLATED.len(), 3 * ablations);
        assert_eq!(enhance_ablated(paper, ACCESS_IN_PLACE, 0, false), None);
        assert!(!reads_camera(FINISH_TILES));
    }
}
