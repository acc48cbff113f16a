//! The shaders by identity: which embedded SPIR-V module a pass, a blur width, a method, a view
//! mode and a pixel format need (indices into `shaders::all()`).

use super::codes::mode_code;
use super::error::GpuError;
use super::interface::ACCESS_IN_PLACE;
use super::shaders;
use crate::algorithm::params::ViewMode;

/// One shader of `shaders::all()`, by its index there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ShaderId(pub(super) usize);

/// Indices into `shaders::all()` (its order: the fixed shaders, DECODE_BLUR, ENHANCE_VARIANTS,
/// CLASSIFY_VARIANTS).
pub const DECODE_CAMERA: ShaderId = ShaderId(0);
pub const FINISH_TILES: ShaderId = ShaderId(1);
pub const COPY_PIXELS: ShaderId = ShaderId(2);
pub const COPY_ROWS: ShaderId = ShaderId(3);
const FIXED: usize = 4;

fn unsupported() -> GpuError {
    GpuError::Unsupported("no shader for this method, mode and format".into())
}

/// Whether a shader works on the camera frame (the background's descriptor set) rather than
/// on a view.
pub fn reads_camera(ShaderId(k): ShaderId) -> bool {
    k == DECODE_CAMERA.0 || (FIXED..FIXED + shaders::DECODE_BLUR.len()).contains(&k)
}

/// The background pass for a blur half-width (0..=7).
pub fn decode_blur(half: u32) -> Result<ShaderId, GpuError> {
    let k = half as usize;
    (k < shaders::DECODE_BLUR.len())
        .then_some(ShaderId(FIXED + k))
        .ok_or_else(unsupported)
}

/// The `enhance` shader for a method, view mode and pixel format (shader codes), reaching the
/// pixels by `access` (interface.rs ACCESS_*); `extras` where the achromatic boost or the
/// luminance cap is on. The general variant: valid for every mapping.
pub fn enhance(codes: (u32, u32, u32), access: u32, extras: bool) -> Result<ShaderId, GpuError> {
    enhance_variant(codes, access, extras, false).ok_or_else(unsupported)
}

/// The shared-fetch variant of `enhance` (valid only where gpu/shared_fetch.rs says so), where
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
    let k = shaders::ENHANCE_VARIANTS
        .iter()
        .position(|&(m, v, f, a, e, s, _)| (m, v, f, a, e, s) == wanted)?;
    Some(ShaderId(FIXED + shaders::DECODE_BLUR.len() + k))
}

/// The `classify` shader for a pixel format (shader code) and pixel access.
pub fn classify(format: u32, access: u32) -> Result<ShaderId, GpuError> {
    let k = shaders::CLASSIFY_VARIANTS
        .iter()
        .position(|&(f, a, _)| f == format && a == access)
        .ok_or_else(unsupported)?;
    let offset = FIXED + shaders::DECODE_BLUR.len() + shaders::ENHANCE_VARIANTS.len();
    Ok(ShaderId(offset + k))
}

/// The FORMAT code of an in-place variant (it reads and writes `app_image`); None for the
/// others.
pub fn in_place_format(ShaderId(k): ShaderId) -> Option<u32> {
    let enhance = FIXED + shaders::DECODE_BLUR.len();
    let classify = enhance + shaders::ENHANCE_VARIANTS.len();
    let (format, access) = match k {
        k if (enhance..classify).contains(&k) => {
            let (_, _, f, a, _, _, _) = shaders::ENHANCE_VARIANTS[k - enhance];
            (f, a)
        }
        k if k >= classify => {
            let (f, a, _) = *shaders::CLASSIFY_VARIANTS.get(k - classify)?;
            (f, a)
        }
        _ => return None,
    };
    (access == ACCESS_IN_PLACE).then_some(format)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ids name the shaders they stand for in `shaders::all()`.
    #[test]
    fn ids_index_the_shader_list() {
        let all = shaders::all();
        let name = |id: ShaderId| all[id.0].name;
        assert_eq!(name(DECODE_CAMERA), "decode_camera");
        assert_eq!(name(FINISH_TILES), "finish_tiles");
        assert_eq!(name(COPY_PIXELS), "copy_pixels");
        assert_eq!(name(COPY_ROWS), "copy_rows");
        assert_eq!(name(decode_blur(3).unwrap()), "decode_blur_3");
        assert!(decode_blur(8).is_err());
        for &(m, v, f, w, e, shared, ref module) in shaders::ENHANCE_VARIANTS {
            let id = match shared {
                true => enhance_shared((m, v, f), w, e),
                false => enhance((m, v, f), w, e).ok(),
            };
            assert_eq!(name(id.unwrap()), module.name);
        }
        // The defaults have a shared-fetch variant for every format and access; the others
        // none.
        let (paper, enhance_mode) = (0, mode_code(ViewMode::Enhance));
        for &(f, w, _) in shaders::CLASSIFY_VARIANTS {
            assert!(enhance_shared((paper, enhance_mode, f), w, false).is_some());
            assert!(enhance_shared((paper, enhance_mode, f), w, true).is_none());
            assert!(enhance_shared((1, enhance_mode, f), w, false).is_none());
            assert!(
                enhance_shared((paper, mode_code(ViewMode::Background), f), w, false).is_none()
            );
        }
        for &(f, w, ref module) in shaders::CLASSIFY_VARIANTS {
            assert_eq!(name(classify(f, w).unwrap()), module.name);
        }
        assert!(reads_camera(decode_blur(7).unwrap()) && reads_camera(DECODE_CAMERA));
        let rgba8 = crate::gpu::interface::LAYOUT_RGBA8;
        assert_eq!(
            in_place_format(classify(rgba8, ACCESS_IN_PLACE).unwrap()),
            Some(rgba8)
        );
        assert_eq!(in_place_format(classify(rgba8, 0).unwrap()), None);
        assert_eq!(in_place_format(FINISH_TILES), None);
        assert!(!reads_camera(FINISH_TILES));
    }
}
