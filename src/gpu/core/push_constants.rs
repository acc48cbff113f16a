//! The push-constant block every pass shares, laid out as the shaders' `Params`
//! (src/gpu/core/interface.rs, PARAMS), with each field's name and offset checked against that
//! table at compile time.

use super::codes::mode_code;
use super::interface::{self, BLUR_TAPS, PARAMS_SIZE, TILE};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::{Params, MAX_BLUR_SIZE, SUBTRACTION_K_B, SUBTRACTION_K_V};

// The algorithm's largest blur is the shaders' largest half-width.
const _: () = assert!(MAX_BLUR_SIZE == 2 * interface::MAX_BLUR_HALF + 1);

/// The push-constant block, laid out as the shaders' `Params` (src/gpu/core/interface.rs, PARAMS:
/// the same fields in the same order, checked below).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PushConstants {
    pub camera_size: [u32; 2],
    pub region_size: [u32; 2],
    pub lambda_e: f32,
    pub lambda_jnd: f32,
    pub transmittance: f32,
    pub blur_half: u32,
    pub taps: [f32; BLUR_TAPS],
    pub k_v: f32,
    pub k_b: f32,
    pub mode: u32,
    pub tile_columns: u32,
    pub achromatic_boost: f32,
    pub luminance_cap: f32,
    /// The view's CameraMapping, row-major (PARAMS' map_00 ..= map_22).
    pub mapping: [[f32; 3]; 3],
    pub region_origin: u32,
}

/// A PushConstants field by the PARAMS name it stands for, and its byte offset: the name is
/// the field's own (one token gives both), so a field moved, renamed or swapped on either side
/// fails the check below.
macro_rules! field {
    ($name:ident) => {
        (
            stringify!($name),
            std::mem::offset_of!(PushConstants, $name),
        )
    };
}

/// Each PARAMS field as PushConstants holds it, in PARAMS order (the mapping stands for
/// map_00 ..= map_22, one f32 each, row-major).
const PUSH_FIELDS: [(&str, usize); interface::PARAMS.len()] = {
    let m = std::mem::offset_of!(PushConstants, mapping);
    [
        field!(camera_size),
        field!(region_size),
        field!(lambda_e),
        field!(lambda_jnd),
        field!(transmittance),
        field!(blur_half),
        field!(taps),
        field!(k_v),
        field!(k_b),
        field!(mode),
        field!(tile_columns),
        field!(achromatic_boost),
        field!(luminance_cap),
        ("map_00", m),
        ("map_01", m + 4),
        ("map_02", m + 8),
        ("map_10", m + 12),
        ("map_11", m + 16),
        ("map_12", m + 20),
        ("map_20", m + 24),
        ("map_21", m + 28),
        ("map_22", m + 32),
        field!(region_origin),
    ]
};

const fn same_name(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The first PARAMS field (by index) that `fields` does not hold under the same name at the
/// offset `offsets` gives it; None where all agree.
const fn first_mismatch(
    fields: &[(&str, usize)],
    params: &[(&str, interface::ParamType)],
    offsets: &[u32],
) -> Option<usize> {
    if fields.len() != params.len() {
        return Some(0);
    }
    let mut i = 0;
    while i < fields.len() {
        if !same_name(fields[i].0, params[i].0) || fields[i].1 != offsets[i] as usize {
            return Some(i);
        }
        i += 1;
    }
    None
}

const _: () = {
    let (offsets, _) = interface::params_layout();
    assert!(
        first_mismatch(&PUSH_FIELDS, &interface::PARAMS, &offsets).is_none(),
        "PushConstants differs from PARAMS (a field's name or offset)"
    );
    assert!(std::mem::size_of::<PushConstants>() == PARAMS_SIZE as usize);
};

impl PushConstants {
    pub fn new(
        params: &Params,
        camera: (u32, u32),
        region: (u32, u32),
        mapping: &CameraMapping,
    ) -> Self {
        let taps64 = params.blur_taps();
        let half = taps64.len() / 2;
        let mut taps = [0.0f32; BLUR_TAPS];
        for (k, t) in taps.iter_mut().enumerate().take(half + 1) {
            *t = taps64[half + k] as f32;
        }
        PushConstants {
            camera_size: [camera.0, camera.1],
            region_size: [region.0, region.1],
            lambda_e: params.lambda_e,
            lambda_jnd: params.lambda_jnd_scaled,
            transmittance: params.transmittance,
            blur_half: half as u32,
            taps,
            k_v: SUBTRACTION_K_V,
            k_b: SUBTRACTION_K_B,
            mode: mode_code(params.mode),
            tile_columns: region.0.div_ceil(TILE),
            achromatic_boost: params.achromatic_boost,
            luminance_cap: params.luminance_cap,
            mapping: mapping.to_f32_rows(),
            region_origin: 0,
        }
    }

    pub fn bytes(&self) -> &[u8] {
        // SAFETY: PushConstants is repr(C), Copy, made only of 4-byte scalars (no padding).
        unsafe {
            std::slice::from_raw_parts(
                (self as *const Self).cast::<u8>(),
                std::mem::size_of::<Self>(),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The check fails where two PARAMS fields of the same type trade places (the shaders
    /// would read lambda_jnd as lambda_e), or where a name is changed on one side.
    #[test]
    fn swapped_or_renamed_fields_fail_the_check() {
        let (offsets, _) = interface::params_layout();
        assert_eq!(
            first_mismatch(&PUSH_FIELDS, &interface::PARAMS, &offsets),
            None
        );
        let mut swapped = interface::PARAMS;
        swapped.swap(2, 3);
        assert_eq!(swapped[2].0, "lambda_jnd");
        let (offsets, _) = interface::layout_of(&swapped);
        assert_eq!(first_mismatch(&PUSH_FIELDS, &swapped, &offsets), Some(2));
        let mut renamed = interface::PARAMS;
        renamed[7].0 = "k_w";
        let (offsets, _) = interface::layout_of(&renamed);
        assert_eq!(first_mismatch(&PUSH_FIELDS, &renamed, &offsets), Some(7));
    }
}
