//! The `luminance` method (docs/algorithm.md, Comparison methods): its CPU reference against
//! its definition, and the GPU within +-1 code value of it (docs/algorithm.md, Conformance).

use contrastxr::algorithm::{
    conformant, enhance_scaled, enhance_srgb8, enhance_srgb8_trace, Method, Params,
};
use contrastxr::colour;
use contrastxr::gpu::OfflineBackend;
use contrastxr::gpu::{DeviceOptions, VkOffline};
use contrastxr::image::RgbaImage;
use glam::DVec3;

fn params(lambda_e: f32) -> Params {
    Params {
        method: Method::Luminance,
        lambda_e,
        ..Params::default()
    }
}

/// Equal up to lambda_e's f32 rounding.
fn assert_close(a: DVec3, b: DVec3) {
    assert!((a - b).length() < 1e-7, "{a} vs {b}");
}

#[test]
fn it_is_a_method_and_a_comparison_mode() {
    assert_eq!(Method::parse("luminance"), Some(Method::Luminance));
    assert!(contrastxr::config::keys::MODES.contains(&"luminance"));
}

#[test]
fn l_moves_away_from_the_background_by_lambda_e_hue_and_chroma_kept() {
    let b = DVec3::new(0.1, 0.2, -0.3);
    let above = DVec3::new(0.3, -0.25, 0.4);
    assert_close(
        enhance_scaled(above, b, &params(0.4)),
        DVec3::new(0.7, -0.25, 0.4),
    );
    let below = DVec3::new(-0.2, 0.1, 0.05);
    assert_close(
        enhance_scaled(below, b, &params(0.25)),
        DVec3::new(-0.45, 0.1, 0.05),
    );
}

#[test]
fn l_stays_within_0_and_100() {
    let b = DVec3::new(0.0, 0.3, 0.0);
    assert_close(
        enhance_scaled(DVec3::new(0.9, 0.1, 0.1), b, &params(0.4)),
        DVec3::new(1.0, 0.1, 0.1),
    );
    assert_close(
        enhance_scaled(DVec3::new(-0.8, 0.1, 0.1), b, &params(1.0)),
        DVec3::new(-1.0, 0.1, 0.1),
    );
}

#[test]
fn equal_l_moves_toward_the_side_with_more_room() {
    let dark = DVec3::new(-0.5, 0.1, 0.0);
    let b = DVec3::new(-0.5, -0.2, 0.3);
    assert_close(
        enhance_scaled(dark, b, &params(0.3)),
        DVec3::new(-0.2, 0.1, 0.0),
    );
    let bright = DVec3::new(0.5, 0.1, 0.0);
    let b = DVec3::new(0.5, -0.2, 0.3);
    assert_close(
        enhance_scaled(bright, b, &params(0.3)),
        DVec3::new(0.2, 0.1, 0.0),
    );
    // Mid grey L' = 0 has as much room either way: up.
    let mid = DVec3::new(0.0, 0.1, 0.0);
    let b = DVec3::new(0.0, -0.2, 0.3);
    assert_close(
        enhance_scaled(mid, b, &params(0.3)),
        DVec3::new(0.3, 0.1, 0.0),
    );
}

#[test]
fn no_change_without_lambda_e_or_a_background_direction() {
    let d = DVec3::new(0.2, 0.1, -0.1);
    assert_eq!(
        enhance_scaled(d, DVec3::new(0.4, 0.0, 0.1), &params(0.0)),
        d
    );
    // A mid-grey background (|B| <= 1e-6): as for every scaled method, P = D.
    assert_eq!(enhance_scaled(d, DVec3::ZERO, &params(0.4)), d);
}

#[test]
fn black_and_transparent_pixels_are_untouched() {
    let bg_linear = DVec3::new(0.8, 0.7, 0.1);
    let bg_scaled = colour::linear_to_scaled(0.4 * bg_linear);
    for px in [[0, 0, 0, 255], [0, 0, 0, 9], [200, 10, 10, 0]] {
        assert_eq!(enhance_srgb8(px, bg_linear, bg_scaled, &params(0.4)), px);
    }
    // An opaque coloured pixel does change.
    let px = [200, 60, 30, 255];
    assert_ne!(enhance_srgb8(px, bg_linear, bg_scaled, &params(0.4)), px);
}

/// A deterministic pseudo-random image (xorshift), with some black and alpha-0 pixels.
fn noise(width: u32, height: u32, seed: u32) -> RgbaImage {
    let mut s = seed.max(1);
    let mut img = RgbaImage::new(width, height, [0, 0, 0, 255]);
    for p in img.pixels.iter_mut() {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        let [_, r, g, b] = s.to_le_bytes();
        *p = match s % 10 {
            0 => [0, 0, 0, 255],
            1 => [r, g, b, 0],
            _ => [r, g, b, 255],
        };
    }
    img
}

#[test]
fn the_gpu_is_within_one_code_value_of_the_reference() {
    let mut e = VkOffline::with_options(&DeviceOptions {
        index: 0,
        validation: true,
        matching: None,
        shader_statistics: false,
    })
    .unwrap_or_else(|e| panic!("GPU engine: {e}"));
    let camera = noise(131, 83, 5);
    // Width 96: the 16-byte access path; 97: the one-word path.
    for width in [96, 97] {
        let display = noise(width, 61, 21);
        for lambda_e in [0.1, 0.4, 1.0] {
            let p = params(lambda_e);
            let mapping = p.camera_mapping();
            let gpu = e.enhance_mapped(&display, &camera, &mapping, &p).unwrap();
            let (w, h) = (display.width, display.height);
            let bg =
                contrastxr::background_preparation::prepare_mapped(&camera, w, h, &mapping, &p);
            let bad = (display.pixels.iter().zip(&gpu.pixels).enumerate())
                .filter(|&(i, (d, g))| {
                    let trace = enhance_srgb8_trace(*d, bg.linear[i], bg.scaled[i], &p);
                    !conformant(&trace, *g)
                })
                .count();
            assert_eq!(
                bad, 0,
                "width {width} lambda_e {lambda_e}: {bad} pixels differ"
            );
        }
    }
    assert_eq!(e.validation_errors(), 0, "Vulkan validation errors");
}
