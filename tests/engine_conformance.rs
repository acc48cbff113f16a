//! One conformance suite for every backend's offline engine (`OfflineBackend`): each test runs
//! on Vulkan (the first device, lavapipe in CI, with the validation layer on: any validation
//! error fails the test) and on OpenGL (an EGL surfaceless context, llvmpipe in CI), and holds
//! both to the CPU reference within the ±1 contract (docs/algorithm.md, Conformance).

mod common;

use common::conformance::{check_all_methods, nonconformant, projective, reference_params};
use common::images::noise;
use contrastxr::algorithm::{Method, Params, ViewMode};
use contrastxr::gpu::core::pixel_codec;
use contrastxr::gpu::opengl::GlOffline;
use contrastxr::gpu::{DeviceOptions, OfflineBackend, PixelFormat, PixelLayout, VkOffline};
use contrastxr::image::RgbaImage;

/// Runs `test` on each backend in turn, then checks Vulkan's validation log.
fn each_backend(test: impl Fn(&mut dyn OfflineBackend)) {
    let options = DeviceOptions {
        index: 0,
        validation: true,
        matching: None,
        shader_statistics: false,
    };
    let mut vulkan =
        VkOffline::with_options(&options).unwrap_or_else(|e| panic!("Vulkan engine: {e}"));
    test(&mut vulkan);
    assert_eq!(
        OfflineBackend::validation_errors(&vulkan),
        0,
        "Vulkan validation errors (see stderr)"
    );
    drop(vulkan);
    let mut opengl = GlOffline::new().unwrap_or_else(|e| panic!("OpenGL context: {e}"));
    test(&mut opengl);
}

fn enhance(
    b: &mut dyn OfflineBackend,
    display: &RgbaImage,
    camera: &RgbaImage,
    params: &Params,
) -> RgbaImage {
    let api = b.api();
    b.enhance_mapped(display, camera, &params.camera_mapping(), params)
        .unwrap_or_else(|e| panic!("{api}: {e}"))
}

#[test]
fn matches_cpu_on_random_images() {
    let camera = noise(131, 83, 5);
    each_backend(|b| {
        // Width 96: rows 16-byte aligned, the 16-byte access path (shaders/access_wide.wgsl);
        // width 97: not aligned, the one-word path (access_narrow.wgsl).
        for width in [96, 97] {
            let display = noise(width, 61, 21);
            let params = Params::default();
            check_all_methods(b, (&display, &camera), &params.camera_mapping(), &params);
        }
    });
}

#[test]
fn matches_cpu_with_a_projective_mapping() {
    let camera = noise(131, 83, 5);
    each_backend(|b| {
        for width in [96, 97] {
            let display = noise(width, 61, 23);
            let params = Params::default();
            check_all_methods(b, (&display, &camera), &projective(), &params);
        }
    });
}

#[test]
fn matches_cpu_on_the_corner_cases() {
    let cases = contrastxr::algorithm::corner_cases();
    let width = 64;
    let height = (cases.len() as u32).div_ceil(width);
    // One pixel per case; without blur and FoV mapping, camera pixel i is display pixel i's B.
    let mut display = RgbaImage::new(width, height, [0, 0, 0, 255]);
    let mut camera = RgbaImage::new(width, height, [0, 0, 0, 255]);
    for (i, (d, b)) in cases.iter().enumerate() {
        display.pixels[i] = [d[0], d[1], d[2], 255];
        camera.pixels[i] = [b[0], b[1], b[2], 255];
    }
    let base = Params {
        blur: false,
        fov: false,
        ..Params::default()
    };
    each_backend(|b| check_all_methods(b, (&display, &camera), &base.camera_mapping(), &base));
}

#[test]
fn matches_cpu_with_the_options_beyond_the_paper() {
    let display = noise(61, 47, 33);
    // A greyish camera so the achromatic boost is active on much of the frame.
    let mut camera = noise(40, 30, 8);
    for p in camera.pixels.iter_mut() {
        let g = p[0] / 2 + 64;
        *p = [g, g.saturating_add(p[1] % 6), g, 255];
    }
    let base = Params {
        achromatic_boost: 1.0,
        luminance_cap: 0.1,
        ..Params::default()
    };
    each_backend(|b| check_all_methods(b, (&display, &camera), &base.camera_mapping(), &base));
}

#[test]
fn lambda_zero_is_the_identity_bit_exact() {
    let display = noise(67, 41, 7);
    let camera = noise(90, 50, 3);
    let params = Params {
        lambda_e: 0.0,
        ..Params::default()
    };
    each_backend(|b| {
        assert_eq!(
            enhance(b, &display, &camera, &params),
            display,
            "{}",
            b.api()
        )
    });
}

#[test]
fn black_and_transparent_pixels_are_untouched() {
    let display = noise(64, 64, 11);
    let camera = RgbaImage::new(32, 32, [250, 230, 20, 255]);
    each_backend(|b| {
        for method in Method::ALL {
            let params = Params {
                method,
                ..Params::default()
            };
            let out = enhance(b, &display, &camera, &params);
            let mut changed = 0;
            for (a, o) in display.pixels.iter().zip(&out.pixels) {
                if a[..3] == [0, 0, 0] || a[3] == 0 {
                    assert_eq!(a, o, "{}: {method:?}", b.api());
                }
                assert_eq!(a[3], o[3], "{}: alpha changed", b.api());
                changed += usize::from(a != o);
            }
            assert!(
                changed > 100,
                "{}: {method:?} changed only {changed} pixels on a yellow wall",
                b.api()
            );
        }
    });
}

#[test]
fn every_tile_is_enhanced_when_the_list_needs_more_than_one_dispatch_row() {
    // 257 x 129 = 33153 tiles of 8x8: more than the 32768 workgroups of one indirect row.
    let display = RgbaImage::new(257 * 8, 129 * 8, [30, 200, 60, 255]);
    let camera = RgbaImage::new(16, 16, [250, 230, 20, 255]);
    each_backend(|b| {
        let out = enhance(b, &display, &camera, &Params::default());
        let first = out.pixels[0];
        assert_ne!(first, display.pixels[0], "{}: nothing changed", b.api());
        let missed = out.pixels.iter().filter(|p| **p != first).count();
        assert_eq!(
            missed,
            0,
            "{}: {missed} pixels not enhanced like the others",
            b.api()
        );
    });
}

#[test]
fn isolated_pixels_in_edge_and_partial_tiles_are_enhanced() {
    // 67x41: the last tile column and row are partial. Black (skipped) except a few pixels.
    let mut display = RgbaImage::new(67, 41, [0, 0, 0, 255]);
    let spots = [
        (0, 0),
        (66, 0),
        (0, 40),
        (66, 40),
        (33, 20),
        (8, 8),
        (7, 7),
        (64, 39),
    ];
    for (k, &(x, y)) in spots.iter().enumerate() {
        display.set(x, y, [200, 60 + 20 * k as u8, 90, 255]);
    }
    let camera = RgbaImage::new(20, 20, [230, 220, 40, 255]);
    let params = Params::default();
    each_backend(|b| {
        let out = enhance(b, &display, &camera, &params);
        for &(x, y) in &spots {
            assert_ne!(
                out.get(x, y),
                display.get(x, y),
                "{}: pixel ({x},{y}) was not enhanced",
                b.api()
            );
        }
        let mapping = params.camera_mapping();
        assert!(nonconformant(b, &display, &camera, &mapping, &params).is_empty());
    });
}

/// `method` at settings where it changes most pixels: the defaults, but for the perceptual
/// method a bright world and a target it spends the paper's whole change on.
fn changing(method: Method) -> Params {
    match method {
        Method::Perceptual => perceptual(5000.0, 1.0),
        method => Params {
            method,
            ..Params::default()
        },
    }
}

fn with_mode(mode: ViewMode) -> Params {
    Params {
        mode,
        ..Params::default()
    }
}

#[test]
fn off_mode_leaves_every_pixel_as_it_was() {
    let display = noise(50, 30, 31);
    let camera = noise(64, 40, 2);
    each_backend(|b| {
        let out = enhance(b, &display, &camera, &with_mode(ViewMode::Off));
        assert_eq!(out, display, "{}", b.api());
    });
}

#[test]
fn split_mode_is_original_left_enhanced_right_with_a_white_divider() {
    let (w, h) = (45, 37);
    let display = noise(w, h, 41);
    let camera = noise(70, 50, 13);
    each_backend(|b| {
        let api = b.api();
        for method in Method::ALL {
            let params = changing(method);
            let enhanced = enhance(b, &display, &camera, &params);
            let split_params = Params {
                mode: ViewMode::Split,
                ..changing(method)
            };
            let split = enhance(b, &display, &camera, &split_params);
            let half = w / 2;
            let mut right_changed = 0;
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    let (d, s) = (display.pixels[i], split.pixels[i]);
                    if x + 1 == half || x == half {
                        let white = [255, 255, 255, d[3]];
                        assert_eq!(s, white, "{api} {method:?}: divider at ({x}, {y})");
                    } else if x < half {
                        assert_eq!(s, d, "{api} {method:?}: left half changed at ({x}, {y})");
                    } else {
                        let e = enhanced.pixels[i];
                        assert_eq!(s, e, "{api} {method:?}: right half at ({x}, {y})");
                        right_changed += usize::from(s != d);
                    }
                }
            }
            assert!(
                right_changed > 100,
                "{api} {method:?}: the right half was not enhanced"
            );
        }
    });
}

#[test]
fn heatmap_mode_marks_exactly_the_pixels_the_metric_counts_as_enhanced() {
    let display = noise(60, 40, 51);
    let camera = noise(80, 50, 17);
    each_backend(|b| {
        let api = b.api();
        // The perceptual method's heatmap shows its classes (the test below).
        for method in Method::ALL.into_iter().filter(|&m| m != Method::Perceptual) {
            let params = Params {
                method,
                ..Params::default()
            };
            let enhanced = enhance(b, &display, &camera, &params);
            let heatmap = Params {
                method,
                ..with_mode(ViewMode::Heatmap)
            };
            let heat = enhance(b, &display, &camera, &heatmap);
            let (w, h) = (display.width, display.height);
            let bg = contrastxr::background_preparation::prepare(&camera, w, h, &params);
            let mask = contrastxr::evaluate::metric::enhanced_mask(&display, &enhanced, &bg);
            let (mut marked, mut disagree) = (0, 0);
            for (i, (d, hm)) in display.pixels.iter().zip(&heat.pixels).enumerate() {
                let cyan = *hm == [0, 255, 255, d[3]];
                assert!(
                    cyan || hm == d,
                    "{api} {method:?} pixel {i}: {hm:?} is neither cyan nor the original"
                );
                marked += usize::from(cyan);
                disagree += usize::from(cyan != mask[i]);
            }
            assert!(
                marked > 100,
                "{api} {method:?}: only {marked} pixels marked"
            );
            // f32 against f64 may flip a pixel sitting exactly on a criterion threshold.
            assert!(
                disagree * 1000 <= display.pixels.len(),
                "{api} {method:?}: {disagree} pixels disagree"
            );
        }
    });
}

#[test]
fn background_mode_shows_the_prepared_background_on_every_pixel() {
    let display = noise(48, 27, 61);
    let camera = noise(90, 60, 19);
    let params = with_mode(ViewMode::Background);
    let (w, h) = (display.width, display.height);
    let bg = contrastxr::background_preparation::prepare(&camera, w, h, &params);
    each_backend(|b| {
        let out = enhance(b, &display, &camera, &params);
        for (i, (d, o)) in display.pixels.iter().zip(&out.pixels).enumerate() {
            let seen = bg.linear[i] * f64::from(params.transmittance);
            let want = contrastxr::colour::linear_to_srgb8(seen);
            for k in 0..3 {
                assert!(
                    o[k].abs_diff(want[k]) <= 1,
                    "{}: pixel {i}: {o:?}, CPU background {want:?}",
                    b.api()
                );
            }
            assert_eq!(o[3], d[3], "{}: alpha changed", b.api());
        }
    });
}

fn linear(c: u8) -> f64 {
    contrastxr::colour::code_to_linear(c)
}

/// An 8-bit sRGB colour as a format's raw words, the way an app would store it.
fn encode(format: PixelFormat, p: [u8; 4]) -> Vec<u32> {
    let a = f64::from(p[3]) / 255.0;
    let bytes = if format.srgb {
        p.to_vec()
    } else {
        pixel_codec::encode(format, [linear(p[0]), linear(p[1]), linear(p[2]), a])
    };
    bytes
        .as_chunks::<4>()
        .0
        .iter()
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// A linear value as an sRGB code in f64 (unrounded), clamped to [0, 1] first.
fn srgb_code(l: f64) -> f64 {
    let l = l.clamp(0.0, 1.0);
    let s = if l <= 0.0031308 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    s * 255.0
}

/// A pixel of a format as 8-bit sRGB codes in f64 (unrounded) and alpha in [0, 1].
fn as_srgb(format: PixelFormat, words: &[u32]) -> [f64; 4] {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let v = pixel_codec::decode(format, &bytes);
    let code = |x: f32| match format.srgb {
        true => f64::from(x) * 255.0,
        false => srgb_code(f64::from(x)),
    };
    [code(v[0]), code(v[1]), code(v[2]), f64::from(v[3])]
}

/// Every format a backend enhances against the CPU reference (`enhance_linear` on the colour
/// the image stores, decoded), for every method: within one sRGB code value, widened by a step
/// of linear 8 or 10 bits where the format's own rounding of the output is coarser. The
/// reference's trace of branch thresholds (where f32 may legitimately take the other branch)
/// is made for 8-bit sRGB input only, so a few pixels in a thousand may differ more.
#[test]
fn every_format_matches_cpu_for_every_method() {
    let camera = noise(80, 50, 9);
    let display = noise(64, 40, 77);
    let region = (display.width, display.height);
    let mapping = Params::default().camera_mapping();
    each_backend(|b| {
        let api = b.api();
        for method in Method::ALL {
            let params = Params {
                method,
                ..Params::default()
            };
            let (w, h) = region;
            let bg = contrastxr::background_preparation::prepare_mapped(
                &camera, w, h, &mapping, &params,
            );
            let mut view = reference_params(&params, &mapping, w, camera.width);
            for format in b.pixel_formats() {
                view.stored = format.stored();
                let words = (format.bytes_per_pixel() / 4) as usize;
                let raw: Vec<u32> = display
                    .pixels
                    .iter()
                    .flat_map(|p| encode(format, *p))
                    .collect();
                let got = b
                    .enhance_pixels(&raw, (region, format), &camera, &mapping, &params)
                    .unwrap_or_else(|e| panic!("{api} {format:?}: {e}"));
                assert_ne!(got, raw, "{api} {method:?} {format:?}: nothing changed");
                let step = match (format.layout, format.srgb) {
                    (PixelLayout::Rgba8 | PixelLayout::Bgra8, false) => 1.0 / 255.0,
                    (PixelLayout::A2b10g10r10, _) => 1.0 / 1023.0,
                    _ => 0.0,
                };
                let mut bad = Vec::new();
                for (i, (g, d)) in got
                    .chunks_exact(words)
                    .zip(raw.chunks_exact(words))
                    .enumerate()
                {
                    let bytes: Vec<u8> = d.iter().flat_map(|w| w.to_le_bytes()).collect();
                    let input = pixel_codec::decode(format, &bytes);
                    let lin = |v: f32| match format.srgb {
                        true => contrastxr::colour::code_to_linear((v * 255.0).round() as u8),
                        false => f64::from(v),
                    };
                    let d_lin = glam::DVec3::new(lin(input[0]), lin(input[1]), lin(input[2]));
                    let want = contrastxr::algorithm::enhance_linear(
                        d_lin,
                        f64::from(input[3]),
                        bg.linear[i],
                        bg.scaled[i],
                        &view,
                    )
                    .unwrap_or(d_lin);
                    let g = as_srgb(format, g);
                    let ok = (0..3).all(|c| {
                        let l = want[c];
                        let span = (srgb_code(l + step) - srgb_code(l))
                            .max(srgb_code(l) - srgb_code(l - step));
                        (g[c] - srgb_code(l)).abs() <= 1.0 + span
                    });
                    if !ok || (g[3] - f64::from(input[3])).abs() > 1e-6 {
                        bad.push(format!(
                            "pixel {i}: got {g:?}, want {:?}",
                            want.to_array().map(srgb_code)
                        ));
                    }
                }
                assert!(
                    bad.len() * 1000 <= 2 * got.len() / words,
                    "{api} {method:?} {format:?}: {} pixels differ, e.g. {:?}",
                    bad.len(),
                    &bad[..bad.len().min(4)]
                );
            }
        }
    });
}

/// The perceptual method's params at `world` nits and target `target`.
fn perceptual(world: f64, target: f64) -> Params {
    let mut p = Params {
        method: Method::Perceptual,
        ..Params::default()
    };
    p.perceptual.world_nits = world;
    p.perceptual.target_contrast = target;
    p
}

/// The perceptual method at the three light levels of docs/algorithm.md's evidence, at the
/// default target and at target 1 (every pixel spends the paper's change), both frequency
/// modes: within the contract, with few pixels excused as near a decision (the argmax over
/// the candidates and the bisection may flip within the GPU tables' tolerance), and many
/// changed, unlike the paper.
#[test]
fn perceptual_matches_cpu_at_three_light_levels() {
    use contrastxr::algorithm::enhance_srgb8_trace;
    use contrastxr::algorithm::perceptual_settings::Frequency;
    let camera = noise(131, 83, 5);
    let display = noise(97, 61, 21);
    let mapping = Params::default().camera_mapping();
    each_backend(|b| {
        let api = b.api();
        // At 500 nits most pixels already reach the default target: few change.
        for (world, target, frequency, changing) in [
            (20.0, 1.0, Frequency::Blur, 10),
            (500.0, 0.05, Frequency::Blur, 100),
            (5000.0, 0.05, Frequency::Ensemble, 10),
            (5000.0, 1.0, Frequency::Blur, 10),
        ] {
            let mut params = perceptual(world, target);
            params.perceptual.frequency = frequency;
            let bad = nonconformant(b, &display, &camera, &mapping, &params);
            assert!(bad.is_empty(), "{api} {world} nits: {bad:?}");
            let (w, h) = (display.width, display.height);
            let bg = contrastxr::background_preparation::prepare_mapped(
                &camera, w, h, &mapping, &params,
            );
            let view = reference_params(&params, &mapping, w, camera.width);
            let paper = Params {
                method: Method::Paper,
                ..view.clone()
            };
            let (mut near, mut changed, mut not_paper) = (0, 0, 0);
            for (i, d) in display.pixels.iter().enumerate() {
                let t = enhance_srgb8_trace(*d, bg.linear[i], bg.scaled[i], &view);
                let p = enhance_srgb8_trace(*d, bg.linear[i], bg.scaled[i], &paper);
                near += usize::from(t.near_threshold);
                changed += usize::from(t.out != *d);
                not_paper += usize::from(t.out != p.out);
            }
            let n = display.pixels.len();
            assert!(
                near * 10 < n,
                "{api} {world} nits: {near} of {n} near a decision"
            );
            assert!(
                changed * changing > n,
                "{api} {world} nits: {changed} of {n} changed"
            );
            assert!(
                not_paper * 2 > n,
                "{api} {world} nits: {not_paper} like the paper"
            );
        }
    });
}

/// The perceptual method's heatmap paints each content pixel by its class, as the CPU
/// reference classes it: left alone green, brought to the target cyan, out of reach magenta.
#[test]
fn the_perceptual_heatmap_shows_the_three_classes() {
    use contrastxr::algorithm::perception::perceived_contrast::Model;
    use contrastxr::algorithm::perception::perceptual_pixel::{perceptual_over_paper, Class};
    let display = noise(60, 40, 51);
    let camera = noise(80, 50, 17);
    let mapping = Params::default().camera_mapping();
    each_backend(|b| {
        let api = b.api();
        let params = Params {
            mode: ViewMode::Heatmap,
            ..perceptual(3000.0, 0.2)
        };
        let heat = b
            .enhance_mapped(&display, &camera, &mapping, &params)
            .unwrap_or_else(|e| panic!("{api}: {e}"));
        let (w, h) = (display.width, display.height);
        let bg =
            contrastxr::background_preparation::prepare_mapped(&camera, w, h, &mapping, &params);
        let view = reference_params(&params, &mapping, w, camera.width);
        let model = Model::of_params(&view);
        let mut counts = [0usize; 3];
        let mut disagree = 0;
        for (i, (d, hm)) in display.pixels.iter().zip(&heat.pixels).enumerate() {
            let lin = contrastxr::colour::srgb8_to_linear([d[0], d[1], d[2]]);
            let alpha = f64::from(d[3]) / 255.0;
            let want = match perceptual_over_paper(lin, alpha, bg.linear[i], &view, &model).class {
                Class::NoContent => *d,
                Class::LeftAlone => [0, 255, 0, d[3]],
                Class::BroughtToTarget => [0, 255, 255, d[3]],
                Class::OutOfReach => [255, 0, 255, d[3]],
            };
            for (k, colour) in [[0, 255, 0], [0, 255, 255], [255, 0, 255]]
                .iter()
                .enumerate()
            {
                counts[k] += usize::from(hm[..3] == colour[..]);
            }
            disagree += usize::from(*hm != want);
        }
        assert!(
            counts.iter().all(|&c| c > 20),
            "{api}: classes painted {counts:?}"
        );
        // f32 against f64 may flip a pixel sitting on the target.
        assert!(
            disagree * 100 <= display.pixels.len(),
            "{api}: {disagree} pixels disagree"
        );
    });
}
