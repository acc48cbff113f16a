//! The push-constant block every pass shares, laid out as the shaders' `Params`
//! (src/gpu/interface.rs, PARAMS), with the layout checked against that table at compile time.

use super::codes::mode_code;
use super::interface::{self, BLUR_TAPS, PARAMS_SIZE, TILE};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::{Params, MAX_BLUR_SIZE, SUBTRACTION_K_B, SUBTRACTION_K_V};

// The algorithm's largest blur is the shaders' largest half-width.
const _: () = assert!(MAX_BLUR_SIZE == 2 * interface::MAX_BLUR_HALF + 1);

/// The push-constant block, laid out as the shaders' `Params` (src/gpu/interface.rs, PARAMS:
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

/// Each PushConstants field's byte offset, in PARAMS order (the mapping stands for map_00 ..=
/// map_22, one f32 each).
const PUSH_OFFSETS: [usize; interface::PARAMS.len()] = {
    use std::mem::offset_of;
    let m = offset_of!(PushConstants, mapping);
    [
        offset_of!(PushConstants, camera_size),
        offset_of!(PushConstants, region_size),
        offset_of!(PushConstants, lambda_e),
        offset_of!(PushConstants, lambda_jnd),
        offset_of!(PushConstants, transmittance),
        offset_of!(PushConstants, blur_half),
        offset_of!(PushConstants, taps),
        offset_of!(PushConstants, k_v),
        offset_of!(PushConstants, k_b),
        offset_of!(PushConstants, mode),
        offset_of!(PushConstants, tile_columns),
        offset_of!(PushConstants, achromatic_boost),
        offset_of!(PushConstants, luminance_cap),
        m,
        m + 4,
        m + 8,
        m + 12,
        m + 16,
        m + 20,
        m + 24,
        m + 28,
        m + 32,
        offset_of!(PushConstants, region_origin),
    ]
};

const _: () = {
    let (offsets, _) = interface::params_layout();
    let mut i = 0;
    while i < offsets.len() {
        assert!(
            PUSH_OFFSETS[i] == offsets[i] as usize,
            "PushConstants differs from PARAMS"
        );
        i += 1;
    }
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
