//! The Vulkan backend's own behaviour on the first Vulkan device (lavapipe in CI) with the
//! validation layer on (every validation error fails the test): its shaders' SPIR-V, the
//! in-place, image-copy and buffer paths, the background's preparation, the shared fetches and
//! the benchmark. What every backend must do is tests/engine_conformance.rs.

mod common;

use common::conformance::{
    assert_every_classify_lists_the_same, assert_the_bound_lists_every_tile_that_changes,
    check_all_methods, nonconformant, projective,
};
use common::images::noise;
use contrastxr::algorithm::mapping::CameraMapping;
use contrastxr::algorithm::{Method, Params, ViewMode};
use contrastxr::gpu::core::pixel_codec::half_from_f32;
use contrastxr::gpu::core::ClassifyChoice;
use contrastxr::gpu::vulkan::offline::AppImage;
use contrastxr::gpu::vulkan::VkFormat;
use contrastxr::gpu::OfflineBackend;
use contrastxr::gpu::{DeviceOptions, PixelFormat, PixelLayout, ViewPath, VkOffline};
use contrastxr::image::RgbaImage;
use std::process::Command;

fn engine() -> VkOffline {
    VkOffline::with_options(&DeviceOptions {
        index: 0,
        validation: true,
        matching: None,
        shader_statistics: false,
    })
    .unwrap_or_else(|e| panic!("GPU engine: {e}"))
}

fn assert_clean(e: &VkOffline) {
    assert_eq!(
        e.validation_errors(),
        0,
        "Vulkan validation errors (see stderr)"
    );
}

#[test]
fn every_embedded_shader_passes_spirv_val() {
    let dir = common::scratch_dir("gpu-engine-spirv-val");
    let compute = contrastxr::gpu::core::modules::all()
        .into_iter()
        .map(|m| (m.name.to_string(), m.bytes()));
    let write_back = contrastxr::gpu::vulkan::pipelines::write_back_modules();
    assert_eq!(
        write_back.len(),
        8,
        "the vertex stage and 7 formats' fragment stages"
    );
    for (name, bytes) in compute.chain(write_back) {
        let path = dir.join(format!("{name}.spv"));
        std::fs::write(&path, bytes).unwrap();
        let out = Command::new("spirv-val")
            .args(["--target-env", "vulkan1.0"])
            .arg(&path)
            .output()
            .expect("spirv-val not found: run scripts/install-deps (package spirv-tools)");
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// Encodes an 8-bit sRGB colour into each format's raw words, the way an app would store it.
fn encode(format: PixelFormat, p: [u8; 4]) -> Vec<u32> {
    let lin = |c: u8| {
        let v = f64::from(c) / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let a = f64::from(p[3]) / 255.0;
    match (format.layout, format.srgb) {
        (PixelLayout::Rgba8, true) => vec![u32::from_le_bytes(p)],
        (PixelLayout::Bgra8, true) => vec![u32::from_le_bytes([p[2], p[1], p[0], p[3]])],
        (PixelLayout::Rgba8, false) => {
            let q = |v: f64| (v * 255.0 + 0.5).floor() as u8;
            vec![u32::from_le_bytes([
                q(lin(p[0])),
                q(lin(p[1])),
                q(lin(p[2])),
                p[3],
            ])]
        }
        (PixelLayout::Rgba16Unorm, _) => {
            let q = |v: f64| (v * 65535.0 + 0.5).floor() as u32;
            vec![q(lin(p[0])) | q(lin(p[1])) << 16, q(lin(p[2])) | q(a) << 16]
        }
        (PixelLayout::A2b10g10r10, _) => {
            let q = |v: f64| (v * 1023.0 + 0.5).floor() as u32;
            vec![q(lin(p[0])) | q(lin(p[1])) << 10 | q(lin(p[2])) << 20 | (p[3] as u32 / 85) << 30]
        }
        (l, s) => unimplemented!("{l:?} srgb={s}"),
    }
}

#[test]
fn formats_agree_with_the_8bit_srgb_path() {
    let mut e = engine();
    let camera = RgbaImage::new(16, 16, [40, 120, 230, 255]);
    let colours: Vec<[u8; 4]> = vec![
        [200, 180, 40, 255],
        [30, 200, 60, 255],
        [128, 128, 128, 255],
        [250, 20, 20, 255],
        [90, 60, 200, 255],
    ];
    // 4 pixels: rows 16-byte aligned in every format (the 16-byte access path); 5 pixels: in
    // none (the one-word path).
    for n in [4, 5] {
        formats_agree_on(&mut e, &camera, &colours[..n]);
    }
    assert_clean(&e);
}

fn formats_agree_on(e: &mut VkOffline, camera: &RgbaImage, colours: &[[u8; 4]]) {
    let region = (colours.len() as u32, 1);
    let params = Params::default();
    let srgb: Vec<u32> = colours.iter().map(|p| u32::from_le_bytes(*p)).collect();
    let want = e
        .enhance_raw(&srgb, region, PixelFormat::SRGB8, camera, &params)
        .unwrap();
    for (layout, srgb_flag) in [
        (PixelLayout::Bgra8, true),
        (PixelLayout::Rgba16Unorm, false),
        (PixelLayout::A2b10g10r10, false),
    ] {
        let format = PixelFormat {
            layout,
            srgb: srgb_flag,
        };
        let raw: Vec<u32> = colours.iter().flat_map(|p| encode(format, *p)).collect();
        let got = e
            .enhance_raw(&raw, region, format, camera, &params)
            .unwrap();
        let expect: Vec<u32> = want
            .iter()
            .flat_map(|w| encode(format, w.to_le_bytes()))
            .collect();
        assert_ne!(got, raw, "{format:?}: nothing changed");
        // Compare as 8-bit sRGB-equivalent: within 1 code value after re-encoding the expectation.
        for (k, (g, x)) in got.iter().zip(&expect).enumerate() {
            let tol = match layout {
                PixelLayout::Rgba16Unorm => 65535 / 255 * 2,
                PixelLayout::A2b10g10r10 => 8,
                _ => 1,
            };
            let fields: &[(u32, u32)] = match layout {
                PixelLayout::Rgba16Unorm => &[(0, 16), (16, 16)],
                PixelLayout::A2b10g10r10 => &[(0, 10), (10, 10), (20, 10), (30, 2)],
                _ => &[(0, 8), (8, 8), (16, 8), (24, 8)],
            };
            for &(shift, bits) in fields {
                let m = (1u32 << bits) - 1;
                let (a, b) = ((g >> shift) & m, (x >> shift) & m);
                assert!(
                    a.abs_diff(b) <= tol,
                    "{format:?} word {k}: {g:#x} vs {x:#x}"
                );
            }
        }
    }
}

#[test]
fn gpu_background_matches_cpu_preparation() {
    // The per-camera-frame part: decode and blur on the camera grid.
    let mut e = engine();
    let camera = noise(150, 90, 9);
    for params in [
        Params::default(),
        Params {
            blur_size: 7,
            blur_sigma: 2.5,
            ..Params::default()
        },
        // The widest kernel: its window spans more rows than one invocation's block.
        Params {
            blur_size: 15,
            blur_sigma: 5.0,
            ..Params::default()
        },
    ] {
        let gpu = e.prepare_background(&camera, &params).unwrap();
        let cpu = contrastxr::background_preparation::blurred_camera(&camera, &params);
        assert_eq!((gpu.width, gpu.height), (cpu.width, cpu.height));
        for i in 0..cpu.pixels.len() {
            // Each entry also holds its right neighbour (itself in the last column).
            let right = if (i + 1) % 150 == 0 { i } else { i + 1 };
            for k in 0..3 {
                let dl = (f64::from(gpu.linear[i][k]) - cpu.pixels[i][k]).abs();
                let dr = (f64::from(gpu.right[i][k]) - cpu.pixels[right][k]).abs();
                assert!(
                    dl < 1e-5 && dr < 1e-5,
                    "texel {i} channel {k}: {dl}, right neighbour {dr}"
                );
            }
        }
    }
    assert_clean(&e);
}

#[test]
fn gpu_background_of_a_part_of_the_camera_matches_cpu_preparation() {
    // The layer prepares only the texels the views sample: at the rectangle's edges the blur
    // still reads the texels beyond it, for every kernel width.
    let mut e = engine();
    let camera = noise(150, 90, 9);
    let rect = contrastxr::gpu::CameraRect {
        x: 36,
        y: 21,
        width: 61,
        height: 35,
    };
    for (blur_size, blur_sigma) in [(3, 0.8), (7, 2.5), (15, 5.0)] {
        let params = Params {
            blur_size,
            blur_sigma,
            ..Params::default()
        };
        let gpu = e.prepare_background_in(&camera, &params, &rect).unwrap();
        let cpu = contrastxr::background_preparation::blurred_camera(&camera, &params);
        for y in rect.y..rect.y + rect.height {
            for x in rect.x..rect.x + rect.width {
                let i = (y * 150 + x) as usize;
                for k in 0..3 {
                    let d = (f64::from(gpu.linear[i][k]) - cpu.pixels[i][k]).abs();
                    assert!(
                        d < 1e-5,
                        "blur {blur_size}: texel ({x}, {y}) channel {k}: {d}"
                    );
                }
            }
        }
    }
    assert_clean(&e);
}

#[test]
fn cpu_prepared_texels_match_the_gpu_passes() {
    // What a live source prepares on its thread is what the decode and blur passes make,
    // entry for entry, to the 21-bit packing's rounding (one code).
    use contrastxr::gpu::core::blurred_texels::{BlurTaps, BlurredTexels, LINEAR_MAX};
    let mut e = engine();
    // Width 151: rows not a multiple of the passes' 4-texel blocks.
    let camera = noise(151, 90, 9);
    for (blur, blur_size, blur_sigma) in [
        (true, 3, 1.5),
        (true, 7, 2.5),
        (true, 15, 5.0),
        (false, 3, 1.5),
    ] {
        let params = Params {
            blur,
            blur_size,
            blur_sigma,
            ..Params::default()
        };
        let gpu = e.prepare_background(&camera, &params).unwrap();
        let cpu = BlurredTexels::prepare(&camera, BlurTaps::of(&params));
        let code = |v: f32| (v * LINEAR_MAX as f32).round() as i64;
        let mut worst = 0;
        for (i, (l, r)) in gpu.linear.iter().zip(&gpu.right).enumerate() {
            let (x, y) = (i as u32 % 151, i as u32 / 151);
            let w = cpu.entry(x, y);
            let packed = [
                u64::from(w[0]) | u64::from(w[1]) << 32,
                u64::from(w[2]) | u64::from(w[3]) << 32,
            ];
            for (texel, bits) in [l, r].into_iter().zip(packed) {
                for (k, v) in texel.iter().enumerate() {
                    let c = ((bits >> (21 * k)) & u64::from(LINEAR_MAX)) as i64;
                    let d = (c - code(*v)).abs();
                    worst = worst.max(d);
                    assert!(
                        d <= 1,
                        "blur {blur} {blur_size}: texel ({x}, {y}) channel {k}: {d} codes"
                    );
                }
            }
        }
        eprintln!("blur {blur} {blur_size}: largest difference {worst} codes");
    }
    assert_clean(&e);
}

#[test]
fn gpu_matches_cpu_with_texels_prepared_on_the_cpu() {
    // The enhancement of a frame whose background texels its source prepared, as the layer
    // makes it: within the conformance tolerance of the CPU reference, through any mapping.
    let mut e = engine();
    e.set_cpu_background(true);
    let camera = noise(131, 83, 5);
    let display = noise(97, 61, 21);
    let params = Params::default();
    check_all_methods(
        &mut e,
        (&display, &camera),
        &params.camera_mapping(),
        &params,
    );
    let wide = Params {
        blur_size: 9,
        blur_sigma: 3.0,
        ..Params::default()
    };
    check_all_methods(&mut e, (&display, &camera), &projective(), &wide);
    assert_clean(&e);
}

#[test]
fn sampled_background_matches_cpu_preparation_through_any_mapping() {
    // The per-pixel part (FoV sampling, transmittance), seen through the background view on a
    // 16-bit linear format: the output is transmittance x the sampled background.
    let mut e = engine();
    let camera = noise(150, 90, 9);
    let params = with_mode(ViewMode::Background);
    let format = PixelFormat {
        layout: PixelLayout::Rgba16Unorm,
        srgb: false,
    };
    let region = (40u32, 27u32);
    let opaque = vec![0xffff_0000u32; (region.0 * region.1 * 2) as usize];
    for mapping in [params.camera_mapping(), projective()] {
        let out = e
            .enhance_raw_mapped(&opaque, (region, format), &camera, &mapping, &params)
            .unwrap();
        let cpu = contrastxr::background_preparation::prepare_mapped(
            &camera, region.0, region.1, &mapping, &params,
        );
        let t = f64::from(params.transmittance);
        for (i, want) in cpu.linear.iter().enumerate() {
            let (w0, w1) = (out[2 * i], out[2 * i + 1]);
            let got = [w0 & 0xffff, w0 >> 16, w1 & 0xffff].map(|c| f64::from(c) / 65535.0);
            for k in 0..3 {
                let d = (got[k] - t * want[k]).abs();
                assert!(
                    d <= 1.5 / 65535.0,
                    "{mapping:?} pixel {i} channel {k}: off by {d}"
                );
            }
        }
    }
    assert_clean(&e);
}

fn cli(args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_contrastxr"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .unwrap()
}

#[test]
fn cli_gpu_and_cpu_engines_agree_on_a_sample_scene() {
    let dir = common::scratch_dir("gpu-engine-cli");
    let samples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("samples");
    let display = samples.join("display-text-swatches.png");
    let background = samples.join("background-blue-sky.png");
    let mut outs = Vec::new();
    for engine in ["gpu", "cpu"] {
        let out = dir.join(format!("{engine}.png"));
        let o = cli(
            &[
                "enhance",
                "--engine",
                engine,
                "--display",
                display.to_str().unwrap(),
                "--background",
                background.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ],
            &[("CONTRASTXR_VK_VALIDATION", "1")],
        );
        assert!(
            o.status.success(),
            "{engine}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!String::from_utf8_lossy(&o.stderr).contains("validation error"));
        outs.push(RgbaImage::load_png(&out).unwrap());
    }
    let input = RgbaImage::load_png(&display).unwrap();
    let (gpu, cpu) = (&outs[0], &outs[1]);
    assert_ne!(gpu, &input, "the GPU engine changed nothing");
    let worst = gpu
        .pixels
        .iter()
        .zip(&cpu.pixels)
        .flat_map(|(g, c)| (0..4).map(move |k| g[k].abs_diff(c[k])))
        .max();
    assert!(worst <= Some(1), "engines differ by {worst:?} code values");
}

#[test]
fn cli_without_a_vulkan_device_names_the_fix() {
    let samples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("samples");
    let o = cli(
        &[
            "enhance",
            "--display",
            samples.join("display-text-swatches.png").to_str().unwrap(),
            "--background",
            samples.join("background-blue-sky.png").to_str().unwrap(),
            "-o",
            "/tmp/never.png",
        ],
        &[
            ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
            ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("mesa-vulkan-drivers") && err.contains("--engine cpu"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "one sentence: {err}");
}

fn with_mode(mode: ViewMode) -> Params {
    Params {
        mode,
        ..Params::default()
    }
}

/// `contrastxr bench` of one 64x40 view, full content, 3 runs, with `extra` options: its JSON.
fn small_bench(extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["bench", "--sizes", "64x40", "--runs", "3"];
    args.extend(["--content", "full", "--json"]);
    if !extra.contains(&"--views") {
        args.extend(["--views", "1"]);
    }
    args.extend(extra);
    let o = cli(&args, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

#[test]
fn bench_reports_every_figure_for_the_contents_asked_for() {
    let v = small_bench(&[]);
    assert!(v["device"].as_str().is_some_and(|d| !d.is_empty()));
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 1, "only the full content was asked for");
    let r = &results[0];
    assert_eq!(
        (r["width"].as_u64(), r["height"].as_u64()),
        (Some(64), Some(40))
    );
    assert_eq!(r["content"], "full");
    assert_eq!(r["foreground_fraction"].as_f64(), Some(1.0));
    let ms = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {r}"));
    for k in [
        "copy_ms",
        "copy_wide_ms",
        "enhance_ms",
        "background_ms",
        "frame_ms",
        "image_copy_ms",
    ] {
        assert!(ms(k) > 0.0, "{k} {}", ms(k));
    }
    assert!((ms("frame_ratio") - ms("frame_ms") / ms("copy_ms")).abs() < 1e-9 * ms("frame_ratio"));
    let live = ms("frame_ms") + ms("background_ms");
    assert!((ms("live_frame_ms") - live).abs() < 1e-9 * live);
    assert_eq!(
        (r["camera_width"].as_u64(), r["camera_height"].as_u64()),
        (Some(1280), Some(720))
    );
    let ratio = ms("enhance_ms") / ms("copy_ms");
    assert!((ms("ratio") - ratio).abs() < 1e-9 * ratio);
    // Width 64 x 4 bytes: rows 16-byte aligned, so the stricter floor is measured too.
    assert!((ms("ratio_wide") - ms("enhance_ms") / ms("copy_wide_ms")).abs() < 1e-9 * ratio);
    // The default (both) leaves the image-copy path out; all times it beside the others.
    assert!(r["frame_image_copy_ms"].is_null(), "{r}");
    let v = small_bench(&["--path", "all"]);
    let r = &v["results"][0];
    let ms = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {r}"));
    for k in [
        "frame_ms",
        "frame_in_place_ms",
        "frame_image_copy_ms",
        "image_copy_copies_ms",
    ] {
        assert!(ms(k) > 0.0, "{k} {}", ms(k));
    }
    let over_frame = ms("frame_image_copy_ms") / ms("frame_ms");
    assert!((ms("image_copy_frame_ratio") - over_frame).abs() < 1e-9 * over_frame);
    let over_in_place = ms("frame_image_copy_ms") / ms("frame_in_place_ms");
    assert!((ms("image_copy_in_place_ratio") - over_in_place).abs() < 1e-9 * over_in_place);
    // On a CPU driver all leaves the tiles drawn back out (a draw there spoils the timestamps
    // of later compute work); on a GPU it times them; tiles times them everywhere.
    let cpu = v["device"].as_str().is_some_and(|d| d.contains("llvmpipe"));
    // The cube roots the device takes: by the Newton steps on a CPU driver, by pow on a GPU.
    assert_eq!(v["cube_roots"], if cpu { "newton" } else { "pow" }, "{v}");
    assert_eq!(r["frame_image_copy_tiles_ms"].is_null(), cpu, "{r}");
    assert_eq!(r["frame_sampled_tiles_ms"].is_null(), cpu, "{r}");
    // Two views: each holds four of the engine's views (buffer, in place, image copy,
    // sampled), more than a pool sized for the tools' four would give out on a GPU.
    let v = small_bench(&["--path", "tiles", "--views", "2"]);
    let r = &v["results"][0];
    assert_eq!(r["views"].as_u64(), Some(2), "{r}");
    let ms = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {r}"));
    assert!(ms("frame_image_copy_tiles_ms") > 0.0, "{r}");
    let tiles_over_in_place = ms("frame_image_copy_tiles_ms") / ms("frame_in_place_ms");
    let ratio = ms("image_copy_tiles_in_place_ratio");
    assert!((ratio - tiles_over_in_place).abs() < 1e-9 * ratio);
    assert!(ms("frame_sampled_tiles_ms") > 0.0, "{r}");
    let sampled_over_in_place = ms("frame_sampled_tiles_ms") / ms("frame_in_place_ms");
    let ratio = ms("sampled_tiles_in_place_ratio");
    assert!((ratio - sampled_over_in_place).abs() < 1e-9 * ratio);
    let bad = cli(&["bench", "--path", "buffer"], &[]);
    assert_eq!(bad.status.code(), Some(2));
    let bad = cli(&["bench", "--content", "sparse"], &[]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("'sparse' is not typical or full"));
}

/// The in-place path (the region in an image of the app's format, enhanced through a storage
/// view) gives the same words as the path through a buffer, in every format the layer
/// enhances in place, at widths with and without 16-byte aligned rows and with pixels past a
/// row's last full group of four.
#[test]
fn in_place_matches_the_copy_path_bit_for_bit() {
    use ash::vk;
    let mut e = engine();
    let camera = noise(24, 16, 7);
    let params = Params::default();
    for (vk_format, layout, srgb) in [
        (vk::Format::R8G8B8A8_SRGB, PixelLayout::Rgba8, true),
        (vk::Format::R8G8B8A8_UNORM, PixelLayout::Rgba8, false),
        (
            vk::Format::R16G16B16A16_SFLOAT,
            PixelLayout::Rgba16Float,
            false,
        ),
    ] {
        let format = PixelFormat { layout, srgb };
        for region in [(16, 8), (13, 5)] {
            let display = noise(region.0, region.1, region.0 * 31 + u32::from(srgb));
            let raw: Vec<u32> = match layout {
                PixelLayout::Rgba16Float => display
                    .pixels
                    .iter()
                    .flat_map(|p| {
                        let h = |c: u8| half_from_f32(f32::from(c) / 255.0);
                        let w = |a: u16, b: u16| u32::from(a) | u32::from(b) << 16;
                        [w(h(p[0]), h(p[1])), w(h(p[2]), h(p[3]))]
                    })
                    .collect(),
                _ => display
                    .pixels
                    .iter()
                    .map(|p| u32::from_le_bytes(*p))
                    .collect(),
            };
            let copy = e
                .enhance_raw(&raw, region, format, &camera, &params)
                .unwrap();
            let in_place = e
                .enhance_raw_in_place(&raw, (region, vk_format), &camera, &params)
                .unwrap_or_else(|err| panic!("{vk_format:?}: {err}"));
            assert_ne!(copy, raw, "{vk_format:?} {region:?}: nothing changed");
            // Exactly the region's words (the read-back once returned the allocation's
            // padding too: 68 pixels for 13x5 on a GPU that rounds allocations up).
            assert_eq!(in_place.len(), raw.len(), "{vk_format:?} {region:?}");
            assert_eq!(in_place, copy, "{vk_format:?} {region:?}");
            // The image-copy path, on the whole image at layer 0.
            let app = AppImage {
                size: region,
                layers: 1,
                offset: (0, 0),
                extent: region,
                layer: 0,
            };
            let image_copy = e
                .enhance_raw_image_copy(&raw, (vk_format, app), &camera, &params)
                .unwrap_or_else(|err| panic!("{vk_format:?}: {err}"));
            assert_eq!(image_copy, copy, "{vk_format:?} {region:?}: image copy");
        }
    }
    assert_clean(&e);
}

/// A host-visible buffer's mapped bytes are exactly those it was made for, whatever the
/// driver's allocation size (what the read-backs take as the result).
#[test]
fn mapped_buffers_give_exactly_their_bytes() {
    use contrastxr::gpu::vulkan::device::GpuBuffer;
    let e = engine();
    for size in [13u64, 16, 13 * 5 * 4, 13 * 5 * 4 + 2, 1000] {
        let usage = ash::vk::BufferUsageFlags::TRANSFER_DST;
        let location = gpu_allocator::MemoryLocation::GpuToCpu;
        let mut b = GpuBuffer::new(&e.gpu, size, usage, location, "test").unwrap();
        assert_eq!(b.mapped().map(<[u8]>::len), Some(size as usize), "{size}");
        b.destroy(&e.gpu);
    }
    assert_clean(&e);
}

/// Every Vulkan format the layer enhances, with the engine's reading of it.
fn every_format() -> Vec<(ash::vk::Format, PixelFormat)> {
    use ash::vk::Format as F;
    [
        F::R8G8B8A8_SRGB,
        F::R8G8B8A8_UNORM,
        F::B8G8R8A8_SRGB,
        F::B8G8R8A8_UNORM,
        F::R16G16B16A16_UNORM,
        F::R16G16B16A16_SFLOAT,
        F::A2B10G10R10_UNORM_PACK32,
    ]
    .into_iter()
    .map(|f| (f, PixelFormat::from_vk(f).unwrap()))
    .collect()
}

/// An image's raw words in `format`, from its 8-bit channels as the format's codes (the
/// colour's meaning differs between formats; the paths are compared on the same words).
fn raw_words(format: PixelFormat, image: &RgbaImage) -> Vec<u32> {
    let w16 = |a: u16, b: u16| u32::from(a) | u32::from(b) << 16;
    image
        .pixels
        .iter()
        .flat_map(|&[r, g, b, a]| match format.layout {
            PixelLayout::Rgba8 => vec![u32::from_le_bytes([r, g, b, a])],
            PixelLayout::Bgra8 => vec![u32::from_le_bytes([b, g, r, a])],
            PixelLayout::Rgba16Unorm => {
                let c = |v: u8| u16::from(v) * 257;
                vec![w16(c(r), c(g)), w16(c(b), c(a))]
            }
            PixelLayout::Rgba16Float => {
                let h = |v: u8| half_from_f32(f32::from(v) / 255.0);
                vec![w16(h(r), h(g)), w16(h(b), h(a))]
            }
            PixelLayout::A2b10g10r10 => {
                let c = |v: u8| u32::from(v) << 2 | u32::from(v) >> 6;
                vec![c(r) | c(g) << 10 | c(b) << 20 | (u32::from(a) >> 6) << 30]
            }
        })
        .collect()
}

/// The image-copy path (the region copied out of an image without storage usage into an
/// image of the engine's own, enhanced there by the in-place shaders, copied back whole, or
/// its listed tiles drawn back), and for the 8-bit sRGB formats the sampled read (the region
/// read through a sampled view, its listed tiles drawn back), gives the words of the path
/// through a buffer in every format the layer enhances, on a sub-rectangle of either layer of a 2-layer image, at widths with
/// and without 16-byte aligned rows, with see-through tiles (left out of the draw) and
/// without; every word outside the region is left as it was.
#[test]
fn image_copy_matches_the_copy_path_bit_for_bit_on_any_region_and_layer() {
    let mut e = engine();
    let camera = noise(24, 16, 7);
    let params = Params::default();
    let cases = [
        ((16, 8), (5, 3), 1, false),
        ((13, 5), (0, 6), 0, false),
        ((21, 11), (1, 2), 1, true),
    ];
    for (vk_format, format) in every_format() {
        let wpp = (format.bytes_per_pixel() / 4) as usize;
        let sampled = format.srgb && format.bytes_per_pixel() == 4;
        let paths: Vec<ViewPath> = [ViewPath::ImageCopy, ViewPath::ImageCopyTiles]
            .into_iter()
            .chain(sampled.then_some(ViewPath::SampledTiles))
            .collect();
        for ((extent, offset, layer, sparse), back) in cases
            .into_iter()
            .flat_map(|c| paths.iter().map(move |&b| (c, b)))
        {
            let size = (23, 13);
            let layers = 2;
            let mut image = noise(size.0, size.1 * layers, extent.0 * 7 + layer);
            if sparse {
                // Black (see-through) pixels but for the region's second tile column.
                for (i, p) in image.pixels.iter_mut().enumerate() {
                    let x = i as u32 % size.0;
                    if !(offset.0 as u32 + 8..offset.0 as u32 + 16).contains(&x) {
                        *p = [0, 0, 0, 0];
                    }
                }
            }
            let words = raw_words(format, &image);
            // The region's words, rows tightly packed.
            let at = |x: u32, y: u32, l: u32| ((l * size.1 + y) * size.0 + x) as usize * wpp;
            let region: Vec<u32> = (0..extent.1)
                .flat_map(|y| {
                    let start = at(offset.0 as u32, offset.1 as u32 + y, layer);
                    words[start..start + extent.0 as usize * wpp].to_vec()
                })
                .collect();
            let copy = e
                .enhance_raw(&region, extent, format, &camera, &params)
                .unwrap();
            assert_ne!(copy, region, "{vk_format:?} {extent:?}: nothing changed");
            let app = AppImage {
                size,
                layers,
                offset,
                extent,
                layer,
            };
            let out = e
                .enhance_raw_image_copy_back(&words, (vk_format, app), (&camera, &params), back)
                .unwrap_or_else(|err| panic!("{vk_format:?} {back:?}: {err}"));
            assert_eq!(out.len(), words.len(), "{vk_format:?}");
            let mut expected = words.clone();
            for y in 0..extent.1 {
                let start = at(offset.0 as u32, offset.1 as u32 + y, layer);
                let row = extent.0 as usize * wpp;
                let from = y as usize * row;
                expected[start..start + row].copy_from_slice(&copy[from..from + row]);
            }
            let differ = differing(&out, &expected);
            assert_eq!(
                differ, 0,
                "{vk_format:?} {extent:?} at {offset:?} layer {layer}, {back:?}"
            );
        }
    }
    assert_clean(&e);
}

/// The listed tiles drawn back bring every 8-bit code back exactly through the sRGB
/// attachment's encoding (the fragment stage returns the code's linear value), and the sampled
/// read reads every code exactly through the sampler's sRGB decode: with no change to spend
/// (`lambda_e` 0) a region holding all 256 codes in each channel comes back as it was, as
/// through the buffer path.
#[test]
fn tiles_drawn_back_keep_every_srgb_code() {
    let mut e = engine();
    let camera = noise(24, 16, 7);
    let params = Params {
        lambda_e: 0.0,
        ..Params::default()
    };
    let (size, extent) = ((16, 16), (16, 16));
    let codes: Vec<[u8; 4]> = (0..=255u8)
        .map(|i| [i, 255 - i, i.wrapping_mul(7), 255])
        .collect();
    let image = RgbaImage {
        width: size.0,
        height: size.1,
        pixels: codes,
        ..noise(size.0, size.1, 1)
    };
    let app = AppImage {
        size,
        layers: 1,
        offset: (0, 0),
        extent,
        layer: 0,
    };
    for vk_format in [
        ash::vk::Format::R8G8B8A8_SRGB,
        ash::vk::Format::B8G8R8A8_SRGB,
    ] {
        let format = PixelFormat::from_vk(vk_format).unwrap();
        let words = raw_words(format, &image);
        let copy = e
            .enhance_raw(&words, extent, format, &camera, &params)
            .unwrap();
        assert_eq!(
            copy, words,
            "{vk_format:?}: lambda_e 0 changed the buffer path's pixels"
        );
        for path in [ViewPath::ImageCopyTiles, ViewPath::SampledTiles] {
            let tiles = e
                .enhance_raw_image_copy_back(&words, (vk_format, app), (&camera, &params), path)
                .unwrap();
            assert_eq!(differing(&tiles, &words), 0, "{vk_format:?} {path:?}");
        }
    }
    assert_clean(&e);
}

/// The image-copy path holds the CPU reference's contract (±1 code value, docs/algorithm.md)
/// for every method, on a region of the second layer of an 8-bit sRGB image.
#[test]
fn image_copy_conforms_to_the_cpu_reference() {
    let mut e = engine();
    let camera = noise(131, 83, 5);
    for method in Method::ALL {
        let bad = image_copy_nonconformant(&mut e, &camera, method, ViewPath::ImageCopy);
        assert_eq!(bad.0, 0, "{method:?}: {} of {} pixels differ", bad.0, bad.1);
    }
    assert_clean(&e);
}

/// How many pixels of a 61x29 sub-rectangle of layer 1 of an 8-bit sRGB image, enhanced by
/// `method` along `path` (one that writes the engine's own image), do not conform to the CPU
/// reference; and how many there are.
fn image_copy_nonconformant(
    e: &mut VkOffline,
    camera: &RgbaImage,
    method: Method,
    path: ViewPath,
) -> (usize, u32) {
    use contrastxr::algorithm::{conformant, enhance_srgb8_trace};
    let (size, extent, offset) = ((70, 40), (61, 29), (6, 9));
    let image = noise(size.0, size.1 * 2, 77);
    let display = RgbaImage {
        width: extent.0,
        height: extent.1,
        pixels: (0..extent.1)
            .flat_map(|y| {
                let start = ((size.1 + offset.1 + y) * size.0 + offset.0) as usize;
                image.pixels[start..start + extent.0 as usize].to_vec()
            })
            .collect(),
        ..image.clone()
    };
    let words = raw_words(PixelFormat::SRGB8, &image);
    let vk_format = ash::vk::Format::R8G8B8A8_SRGB;
    let app = AppImage {
        size,
        layers: 2,
        offset: (offset.0 as i32, offset.1 as i32),
        extent,
        layer: 1,
    };
    let params = Params {
        method,
        ..Params::default()
    };
    let out = e
        .enhance_raw_image_copy_back(&words, (vk_format, app), (camera, &params), path)
        .unwrap();
    let mapping = params.camera_mapping();
    let (w, h) = extent;
    let bg = contrastxr::background_preparation::prepare_mapped(camera, w, h, &mapping, &params);
    let view = common::conformance::reference_params(&params, &mapping, w, camera.width);
    let mut bad = 0;
    for (i, d) in display.pixels.iter().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let word = out[((size.1 + offset.1 + y) * size.0 + offset.0 + x) as usize];
        let trace = enhance_srgb8_trace(*d, bg.linear[i], bg.scaled[i], &view);
        bad += usize::from(!conformant(&trace, word.to_le_bytes()));
    }
    (bad, w * h)
}

/// The variants with the cube roots by `pow`, which a GPU's views take (forced here: a CPU
/// driver takes the Newton steps), hold the ±1 contract against the CPU reference along the
/// ways a GPU takes for an image without storage usage (the region copied into the engine's
/// image, or read through a sampled view), for both methods that have them; and in place, in
/// every format that has an in-place variant, they give the Newton steps' output within one
/// step in every channel (and not bit for bit: the pow variant ran).
#[test]
fn cube_roots_by_pow_conform_on_the_ways_a_gpu_takes() {
    use contrastxr::gpu::core::interface::in_place_texel;
    use contrastxr::gpu::core::CubeRoots;
    let mut e = engine();
    assert_eq!(e.cube_roots(), CubeRoots::for_device(e.is_cpu()));
    let camera = noise(131, 83, 5);
    e.set_cube_roots(CubeRoots::Pow);
    for method in [Method::Paper, Method::Perceptual] {
        for path in [ViewPath::ImageCopy, ViewPath::SampledTiles] {
            let (bad, n) = image_copy_nonconformant(&mut e, &camera, method, path);
            assert_eq!(bad, 0, "{method:?} {path:?}: {bad} of {n} pixels differ");
        }
    }
    let region = (37, 21);
    let mut moved = 0;
    for (vk_format, format) in every_format() {
        if in_place_texel(format.shader_code()).is_none() {
            continue;
        }
        let raw = raw_words(format, &noise(region.0, region.1, 9));
        for method in [Method::Paper, Method::Perceptual] {
            let params = Params {
                method,
                ..Params::default()
            };
            let mut run = |roots| {
                e.set_cube_roots(roots);
                e.enhance_raw_in_place(&raw, (region, vk_format), &camera, &params)
            };
            let (by_pow, newton) = match (run(CubeRoots::Pow), run(CubeRoots::Newton)) {
                (Ok(p), Ok(n)) => (p, n),
                // A format the device has no storage for (lavapipe: BGRA8).
                (Err(err), _) if err.to_string().contains("not enhanced in place on this") => {
                    continue
                }
                (p, n) => panic!("{vk_format:?}: {:?} {:?}", p.err(), n.err()),
            };
            let what = format!("{vk_format:?} {method:?}");
            // (The perceptual method may find every random pixel of a format at its target.)
            assert!(
                method != Method::Paper || newton != raw,
                "{what}: nothing changed"
            );
            let (a, b) = (
                format_channels(format, &by_pow),
                format_channels(format, &newton),
            );
            assert_within_one(&a, &b, &what);
            moved += differing(&a, &b);
        }
    }
    assert!(
        moved > 0,
        "the pow variants gave the Newton steps' output bit for bit"
    );
    assert_clean(&e);
}

/// The channels of a format's words as integers (codes, or half floats' bits).
fn format_channels(format: PixelFormat, words: &[u32]) -> Vec<u32> {
    match format.layout {
        PixelLayout::Rgba8 | PixelLayout::Bgra8 => rgba8_channels(words),
        PixelLayout::Rgba16Unorm | PixelLayout::Rgba16Float => halves(words),
        PixelLayout::A2b10g10r10 => words
            .iter()
            .flat_map(|w| [w & 0x3ff, w >> 10 & 0x3ff, w >> 20 & 0x3ff, w >> 30])
            .collect(),
    }
}

/// Mappings under which the shared-fetch variant serves views of 96 to 128 pixels on a 64-wide
/// camera frame: the default, a mirrored one, one shifted per row (the v -> u term), and one
/// reaching past the camera's left and right edges (clamp-to-edge).
fn shared_fetch_mappings() -> Vec<CameraMapping> {
    let mut shifted = Params::default().camera_mapping();
    shifted.rows[0][1] = 0.1;
    vec![
        Params::default().camera_mapping(),
        CameraMapping::affine([-0.65, 0.65], [0.78, 0.17]),
        shifted,
        CameraMapping::affine([0.9, 0.8], [0.3, -0.1]),
        CameraMapping::affine([0.9, -0.8], [-0.2, 0.9]),
    ]
}

/// How many of two outputs' pixels (or words) differ.
fn differing<T: PartialEq>(a: &[T], b: &[T]) -> usize {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).filter(|(x, y)| x != y).count()
}

/// The output with the shared-fetch variant allowed and with the general one forced.
fn shared_and_general(
    e: &mut VkOffline,
    display: &RgbaImage,
    camera: &RgbaImage,
    mapping: &CameraMapping,
) -> (RgbaImage, RgbaImage) {
    let params = Params::default();
    let shared = e.enhance_mapped(display, camera, mapping, &params).unwrap();
    e.set_shared_fetch(false);
    let general = e.enhance_mapped(display, camera, mapping, &params).unwrap();
    e.set_shared_fetch(true);
    (shared, general)
}

/// The shared fetches' contract with the general variant: the same arithmetic per pixel on the
/// same texels, so bit for bit where the driver compiles both pipelines' arithmetic alike (a CPU
/// driver: checked exactly). A GPU compiler may fuse a multiply and an add in one pipeline and
/// not the other (naga's SPIR-V carries no NoContraction), which moves a value at a rounding
/// boundary by one step: there, at most one step (8-bit code or half-float unit) in any
/// channel, on at most 1 in 1000 values. `shared` and `general` are the outputs' channels as
/// integers.
fn assert_shared_fetch_contract(e: &VkOffline, shared: &[u32], general: &[u32], what: &str) {
    assert_eq!(shared.len(), general.len(), "{what}");
    let differ = differing(shared, general);
    if e.is_cpu() {
        assert_eq!(differ, 0, "{what}: values differ");
        return;
    }
    let worst = shared
        .iter()
        .zip(general)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap_or(0);
    assert!(worst <= 1, "{what}: values differ by up to {worst}");
    assert!(
        differ * 1000 <= shared.len(),
        "{what}: {differ} of {} values differ",
        shared.len()
    );
}

/// The channels of 8-bit pixels, and of words holding two half floats each (as unsigned 16-bit
/// integers: for values of one sign, adjacent floats are adjacent integers).
fn channels(pixels: &[[u8; 4]]) -> Vec<u32> {
    pixels.iter().flatten().map(|&c| u32::from(c)).collect()
}

/// The channels of RGBA8 words.
/// Every value of `a` within one step of `b`'s.
fn assert_within_one(a: &[u32], b: &[u32], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    let worst = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max();
    assert!(worst <= Some(1), "{what}: values differ by up to {worst:?}");
}

fn rgba8_channels(words: &[u32]) -> Vec<u32> {
    words
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .map(u32::from)
        .collect()
}

fn halves(words: &[u32]) -> Vec<u32> {
    words.iter().flat_map(|w| [w & 0xffff, w >> 16]).collect()
}

#[test]
fn shared_fetches_give_the_general_variants_output() {
    use contrastxr::gpu::core::shares_fetches;
    let mut e = engine();
    let camera = noise(64, 40, 11);
    // 96, 128: 16-byte aligned rows (access_wide.wgsl); 97, 101: not (access_narrow.wgsl),
    // with a last group of four past the row's end.
    for width in [96, 97, 101, 128] {
        let display = noise(width, 37, width);
        for mapping in shared_fetch_mappings() {
            assert!(
                shares_fetches(&mapping, (width, 37), (64, 40)),
                "{mapping:?}"
            );
            let (shared, general) = shared_and_general(&mut e, &display, &camera, &mapping);
            assert_ne!(general, display, "{width} {mapping:?}: nothing changed");
            let (s, g) = (channels(&shared.pixels), channels(&general.pixels));
            assert_shared_fetch_contract(&e, &s, &g, &format!("{width} {mapping:?}"));
        }
    }
    // The 16-bit float format through the same variant dimension.
    let format = PixelFormat {
        layout: PixelLayout::Rgba16Float,
        srgb: false,
    };
    let raw: Vec<u32> = noise(100, 9, 5)
        .pixels
        .iter()
        .flat_map(|p| {
            let h = |c: u8| u32::from(half_from_f32(f32::from(c) / 255.0));
            [h(p[0]) | h(p[1]) << 16, h(p[2]) | h(p[3]) << 16]
        })
        .collect();
    let params = Params::default();
    for mapping in shared_fetch_mappings() {
        let run = |e: &mut VkOffline| {
            e.enhance_raw_mapped(&raw, ((100, 9), format), &camera, &mapping, &params)
                .unwrap()
        };
        let shared = run(&mut e);
        e.set_shared_fetch(false);
        let general = run(&mut e);
        e.set_shared_fetch(true);
        assert_ne!(general, raw);
        let what = format!("RGBA16F {mapping:?}");
        assert_shared_fetch_contract(&e, &halves(&shared), &halves(&general), &what);
    }
    assert_clean(&e);
}

#[test]
fn shared_fetches_conform_to_the_cpu_reference() {
    let mut e = engine();
    let camera = noise(64, 40, 13);
    for (width, mapping) in [96, 97].into_iter().zip(shared_fetch_mappings()) {
        let display = noise(width, 29, 3 * width);
        check_all_methods(&mut e, (&display, &camera), &mapping, &Params::default());
    }
    assert_clean(&e);
}

#[test]
fn shared_fetches_in_place_match_the_general_variant() {
    use ash::vk;
    let mut e = engine();
    let camera = noise(16, 8, 7);
    let params = Params::default();
    for region in [(48, 9), (45, 5)] {
        let raw: Vec<u32> = noise(region.0, region.1, 17)
            .pixels
            .iter()
            .map(|p| u32::from_le_bytes(*p))
            .collect();
        let run = |e: &mut VkOffline| {
            let format = vk::Format::R8G8B8A8_SRGB;
            e.enhance_raw_in_place(&raw, (region, format), &camera, &params)
                .unwrap()
        };
        let shared = run(&mut e);
        e.set_shared_fetch(false);
        let general = run(&mut e);
        e.set_shared_fetch(true);
        assert_ne!(general, raw, "{region:?}");
        let what = format!("in place {region:?}");
        let (shared, general) = (rgba8_channels(&shared), rgba8_channels(&general));
        assert_shared_fetch_contract(&e, &shared, &general, &what);
    }
    assert_clean(&e);
}

/// Rotation, vertical shear and a projective divide: the group's pixels sample different
/// camera rows, so they take the general variant, and the output conforms.
#[test]
fn mappings_the_shared_fetches_cannot_serve_take_the_general_variant() {
    use contrastxr::gpu::core::shares_fetches;
    let mut e = engine();
    let camera = noise(64, 40, 19);
    let (c, s) = (0.6 * 0.2f64.cos(), 0.6 * 0.2f64.sin());
    let rotated = CameraMapping {
        rows: [[c, -s, 0.2], [s, c, 0.1], [0.0, 0.0, 1.0]],
    };
    let mut sheared = Params::default().camera_mapping();
    sheared.rows[1][0] = 0.3;
    for mapping in [rotated, sheared, projective()] {
        let display = noise(96, 31, 29);
        assert!(!shares_fetches(&mapping, (96, 31), (64, 40)));
        let (shared, general) = shared_and_general(&mut e, &display, &camera, &mapping);
        let differ = differing(&shared.pixels, &general.pixels);
        assert_eq!(differ, 0, "{mapping:?}: pixels differ");
        let bad = nonconformant(&mut e, &display, &camera, &mapping, &Params::default());
        assert!(
            bad.is_empty(),
            "{mapping:?}: {:?}",
            &bad[..bad.len().min(5)]
        );
    }
    assert_clean(&e);
}

/// The benchmark's ablations (`contrastxr bench --ablate`) take out what they name: without
/// the method (alone or with the background and the codec) or without the enhance pass, every
/// pixel keeps its words; without the codec, the sRGB words are enhanced as UNORM words are;
/// with a constant background, the camera no longer matters. Wide and narrow rows, and in place.
#[test]
fn bench_ablations_take_out_what_they_name() {
    use contrastxr::gpu::core::interface::{
        ABLATE_BACKGROUND, ABLATE_CODEC, ABLATE_CUBE_ROOT, ABLATE_ENHANCE_PASS, ABLATE_METHOD,
    };
    let mut e = engine();
    let (camera, other_camera) = (noise(64, 40, 23), noise(64, 40, 29));
    let params = Params::default();
    let unorm8 = PixelFormat {
        layout: PixelLayout::Rgba8,
        srgb: false,
    };
    for width in [96, 97] {
        let region = (width, 9);
        let raw = raw_words(PixelFormat::SRGB8, &noise(width, 9, 41 + width));
        let run = |e: &mut VkOffline, ablate, format, camera: &RgbaImage| {
            e.set_ablation(ablate);
            let out = e.enhance_raw(&raw, region, format, camera, &params);
            e.set_ablation(0);
            out.unwrap_or_else(|err| panic!("ablation {ablate}: {err}"))
        };
        let enhanced = run(&mut e, 0, PixelFormat::SRGB8, &camera);
        assert_ne!(enhanced, raw, "{width}: nothing changed");
        let all_three = ABLATE_METHOD | ABLATE_BACKGROUND | ABLATE_CODEC;
        for ablate in [ABLATE_METHOD, all_three, ABLATE_ENHANCE_PASS] {
            let out = run(&mut e, ablate, PixelFormat::SRGB8, &camera);
            assert_eq!(differing(&out, &raw), 0, "{width}: ablation {ablate}");
        }
        let without_codec = run(&mut e, ABLATE_CODEC, PixelFormat::SRGB8, &camera);
        let as_unorm = run(&mut e, 0, unorm8, &camera);
        assert_ne!(without_codec, enhanced, "{width}: the codec still ran");
        let what = format!("{width}: no codec against UNORM");
        assert_shared_fetch_contract(
            &e,
            &rgba8_channels(&without_codec),
            &rgba8_channels(&as_unorm),
            &what,
        );
        let grey = run(&mut e, ABLATE_BACKGROUND, PixelFormat::SRGB8, &camera);
        let grey_too = run(&mut e, ABLATE_BACKGROUND, PixelFormat::SRGB8, &other_camera);
        let other = run(&mut e, 0, PixelFormat::SRGB8, &other_camera);
        assert_ne!(other, enhanced, "{width}: the camera made no difference");
        assert_ne!(grey, raw, "{width}: no enhancement over the grey");
        assert_eq!(grey, grey_too, "{width}: the camera still read");
        // The cube roots by pow: replaced, not taken out, so still the enhancement.
        let by_pow = run(&mut e, ABLATE_CUBE_ROOT, PixelFormat::SRGB8, &camera);
        let what = format!("{width}: cube roots by pow");
        assert_within_one(&rgba8_channels(&by_pow), &rgba8_channels(&enhanced), &what);
    }
    // In place, in the app's image.
    let raw = raw_words(PixelFormat::SRGB8, &noise(48, 9, 43));
    let format = ash::vk::Format::R8G8B8A8_SRGB;
    e.set_ablation(ABLATE_METHOD);
    let out = e.enhance_raw_in_place(&raw, ((48, 9), format), &camera, &params);
    e.set_ablation(0);
    assert_eq!(out.unwrap(), raw, "in place without the method");
    // Built for the paper's method on RGBA8 sRGB only: other methods and formats are refused.
    e.set_ablation(ABLATE_METHOD);
    let luminance = Params {
        method: Method::Luminance,
        ..Params::default()
    };
    let refused = e.enhance_raw(&raw, (48, 9), PixelFormat::SRGB8, &camera, &luminance);
    let refused_unorm = e.enhance_raw(&raw, (48, 9), unorm8, &camera, &params);
    e.set_ablation(0);
    for r in [refused, refused_unorm] {
        let err = r.expect_err("no ablated variant").to_string();
        assert!(
            err.contains("paper's and the perceptual method on RGBA8 sRGB"),
            "{err}"
        );
    }
    assert_clean(&e);
}

/// The perceptual method's ablations: without its directions and with every pixel below the
/// target (target_contrast 1), its output is the paper's; without its bisection it is its own
/// where no pixel reaches the target, and not at the default target; listing tiles by the
/// paper's classify changes nothing (each pixel is judged again), nor by its own over tile
/// rows (`classify-rows`).
#[test]
fn perceptual_ablations_take_out_what_they_name() {
    use contrastxr::gpu::core::interface::{ABLATE_BISECTION, ABLATE_DIRECTIONS};
    let mut e = engine();
    let camera = noise(64, 40, 31);
    let raw = raw_words(PixelFormat::SRGB8, &noise(96, 9, 37));
    let perceptual = |target_contrast| {
        let mut p = Params {
            method: Method::Perceptual,
            ..Params::default()
        };
        p.perceptual.target_contrast = target_contrast;
        p
    };
    let run = |e: &mut VkOffline, ablate, params: &Params| {
        e.set_ablation(ablate);
        let out = e.enhance_raw(&raw, (96, 9), PixelFormat::SRGB8, &camera, params);
        e.set_ablation(0);
        out.unwrap_or_else(|err| panic!("ablation {ablate}: {err}"))
    };
    let (never, default) = (
        perceptual(1.0),
        perceptual(Params::default().perceptual.target_contrast),
    );
    let paper = run(&mut e, 0, &Params::default());
    let full = run(&mut e, 0, &never);
    assert_ne!(full, paper, "the directions changed nothing");
    let paper_only = run(&mut e, ABLATE_DIRECTIONS, &never);
    let what = "no directions against the paper";
    assert_shared_fetch_contract(
        &e,
        &rgba8_channels(&paper_only),
        &rgba8_channels(&paper),
        what,
    );
    let unreached = run(&mut e, ABLATE_BISECTION, &never);
    assert_shared_fetch_contract(
        &e,
        &rgba8_channels(&unreached),
        &rgba8_channels(&full),
        "no bisection, target 1",
    );
    let own = run(&mut e, 0, &default);
    assert_ne!(own, raw, "nothing below the default target");
    assert_ne!(
        run(&mut e, ABLATE_BISECTION, &default),
        own,
        "no bisection ran"
    );
    e.set_classify(ClassifyChoice::Paper);
    let all_tiles = run(&mut e, 0, &default);
    e.set_classify(ClassifyChoice::OwnByRows);
    let by_rows = run(&mut e, 0, &default);
    e.set_classify(ClassifyChoice::Own);
    for (out, what) in [
        (all_tiles, "the paper's classify"),
        (by_rows, "by tile rows"),
    ] {
        let (out, own) = (rgba8_channels(&out), rgba8_channels(&own));
        assert_shared_fetch_contract(&e, &out, &own, what);
    }
    assert_clean(&e);
}

/// The perceptual method's classify by tile rows lists every tile its own classify lists: with
/// one content pixel per tile, in each row and column of the tiles in turn, and every pixel
/// below the target (target_contrast 1), the outputs are the same word for word, through a
/// buffer and in place, and the same as with every tile with content listed (the paper's
/// classify).
#[test]
fn the_classify_by_tile_rows_lists_the_tiles_its_own_does() {
    let mut e = engine();
    let camera = noise(64, 40, 53);
    // 12 x 3 tiles, the last row of tiles one pixel high.
    let image = common::images::one_pixel_per_tile(96, 17, 59);
    let raw = raw_words(PixelFormat::SRGB8, &image);
    let mut params = Params {
        method: Method::Perceptual,
        ..Params::default()
    };
    params.perceptual.target_contrast = 1.0;
    let srgb = ash::vk::Format::R8G8B8A8_SRGB;
    for in_place in [false, true] {
        let run = |choice| {
            e.set_classify(choice);
            let region = (96, 17);
            let out = match in_place {
                false => e.enhance_raw(&raw, region, PixelFormat::SRGB8, &camera, &params),
                true => e.enhance_raw_in_place(&raw, (region, srgb), &camera, &params),
            };
            e.set_classify(ClassifyChoice::Own);
            out.unwrap_or_else(|err| panic!("in place {in_place}, {choice:?}: {err}"))
        };
        assert_every_classify_lists_the_same(&raw, run, &format!("in place {in_place}"));
    }
    assert_clean(&e);
}

/// The perceptual method's own classify, with its lower bound of c', lists every tile whose
/// pixel the enhancement changes: one content pixel per tile of a 256x64 view, three light
/// levels (common::conformance::assert_the_bound_lists_every_tile_that_changes).
#[test]
fn the_bound_of_the_own_classify_lists_every_tile_that_changes() {
    let mut e = engine();
    let camera = noise(64, 40, 61);
    let mut image = common::images::one_pixel_per_tile(256, 64, 67);
    common::images::darken_every_other(&mut image);
    let raw = raw_words(PixelFormat::SRGB8, &image);
    let run = |choice, params: &Params| {
        e.set_classify(choice);
        let out = e.enhance_raw(&raw, (256, 64), PixelFormat::SRGB8, &camera, params);
        e.set_classify(ClassifyChoice::Own);
        out.unwrap_or_else(|err| panic!("{choice:?}: {err}"))
    };
    assert_the_bound_lists_every_tile_that_changes(&raw, run, "Vulkan");
    assert_clean(&e);
}

/// `--ablate` gives each case a row per ablation, the baseline first, with its enhancement over
/// that baseline; unknown names and another method's ablations are refused.
#[test]
fn bench_ablations_are_rows_of_their_own() {
    let v = small_bench(&["--ablate", "enhance-pass,method"]);
    let results = v["results"].as_array().unwrap();
    let names: Vec<&str> = results
        .iter()
        .map(|r| r["ablation"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["none", "enhance-pass", "method"]);
    let enh = |k: usize| results[k]["enhance_ms"].as_f64().unwrap();
    assert!(enh(0) > 0.0 && enh(1) > 0.0 && enh(2) > 0.0);
    // Each ablation against the baseline measured just before it.
    assert!(results[0]["enhance_vs_none"].is_null());
    for k in [1, 2] {
        let ratio = results[k]["enhance_vs_none"].as_f64().unwrap();
        assert!((ratio - enh(k) / enh(0)).abs() < 1e-9 * ratio, "{ratio}");
    }
    let bad = cli(&["bench", "--ablate", "blur"], &[]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("'blur' is not none, method"));
    // The perceptual method's own ablations are not the paper's.
    let other = cli(&["bench", "--ablate", "directions"], &[]);
    assert_eq!(other.status.code(), Some(2));
    let err = String::from_utf8_lossy(&other.stderr);
    assert!(
        err.contains("directions is not built for the method paper"),
        "{err}"
    );
}

/// Whether the first device offers the compiler's statistics, asked of Vulkan here (not
/// through the engine's own check).
fn device_offers_statistics(e: &VkOffline) -> bool {
    use ash::vk;
    let (instance, physical) = (&e.gpu.instance, e.gpu.physical);
    // SAFETY: physical is the engine's device, of its live instance.
    let listed = unsafe { instance.enumerate_device_extension_properties(physical) }
        .unwrap()
        .iter()
        .any(|x| x.extension_name_as_c_str() == Ok(ash::khr::pipeline_executable_properties::NAME));
    let mut feature = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut feature);
    // SAFETY: as above; the engine needs Vulkan 1.1.
    unsafe { instance.get_physical_device_features2(physical, &mut features) };
    listed && feature.pipeline_executable_info == vk::TRUE
}

#[test]
fn shader_statistics_are_reported_where_the_driver_has_them() {
    let e = VkOffline::with_options(&DeviceOptions {
        index: 0,
        validation: true,
        matching: None,
        shader_statistics: true,
    })
    .unwrap_or_else(|e| panic!("GPU engine: {e}"));
    let offered = device_offers_statistics(&e);
    assert_eq!(e.gpu.shader_statistics, offered);
    match e.bench_shader_statistics(&Params::default()) {
        Ok(all) => {
            assert!(offered, "statistics from a device that does not offer them");
            assert_eq!(all.len(), 10, "{all:?}");
            for shader in &all {
                assert!(!shader.executables.is_empty(), "{}", shader.shader);
                assert!(
                    shader.executables.iter().all(|x| !x.statistics.is_empty()),
                    "{shader:?}"
                );
            }
        }
        Err(why) => {
            assert!(!offered, "the device offers statistics, yet: {why}");
            assert!(why
                .to_string()
                .contains("VK_KHR_pipeline_executable_properties"));
        }
    }
    assert_clean(&e);
    // The command line gives them (or why not) in the bench's JSON.
    let v = small_bench(&["--shader-stats"]);
    match offered {
        true => assert_eq!(
            v["shader_statistics"].as_array().map(Vec::len),
            Some(10),
            "{v}"
        ),
        false => assert!(v["shader_statistics_error"].is_string(), "{v}"),
    }
}

/// An engine sized for one view (and two background frames) refuses the sets of three views
/// and a background on every driver, as a GPU's driver does (lavapipe would hand them out):
/// the bench sizes its engine by its views.
#[test]
fn an_engine_refuses_more_views_than_it_was_sized_for() {
    use contrastxr::gpu::core::bench::{Ablation, BenchCase, Content};
    let options = DeviceOptions {
        validation: true,
        ..DeviceOptions::from_env()
    };
    let case = |views| BenchCase {
        region: (32, 16),
        views,
        content: Content::Full,
        runs: 1,
        in_place: false,
        image_copy: false,
        tiles: false,
        ablation: Ablation::None,
    };
    let params = Params::default();
    let mut small = VkOffline::with_views(&options, 1).expect("a Vulkan device");
    small.bench(&case(1), &params).expect("one view fits");
    let err = small.bench(&case(3), &params).unwrap_err().to_string();
    assert!(err.contains("ERROR_OUT_OF_POOL_MEMORY"), "{err}");
    assert_clean(&small);
    let mut sized = VkOffline::with_views(&options, 3).expect("a Vulkan device");
    sized.bench(&case(3), &params).expect("three views fit");
    assert_clean(&sized);
}

/// The bench's `cube-root` ablation (the cube roots the other way than the device's: on a CPU
/// driver by `pow`, on a GPU by the Newton steps) holds the ±1 contract against the CPU
/// reference on random images at three lambda_e, through the buffer path's variants; through
/// the shared fetches and the general sampling (a camera frame the view's mapping shares
/// fetches over, and one it does not: the ablated variants sample as the view otherwise would).
#[test]
fn the_other_cube_roots_conform_to_the_cpu_reference() {
    use contrastxr::gpu::core::interface::ABLATE_CUBE_ROOT;
    let mut e = engine();
    e.set_ablation(ABLATE_CUBE_ROOT);
    for camera in [noise(64, 40, 5), noise(131, 83, 5)] {
        for (k, lambda_e) in [0.1f32, 0.4, 1.0].into_iter().enumerate() {
            let params = Params {
                lambda_e,
                ..Params::default()
            };
            let display = noise(97, 61, 31 + k as u32);
            let bad = nonconformant(&mut e, &display, &camera, &params.camera_mapping(), &params);
            let size = (camera.width, camera.height);
            assert!(
                bad.is_empty(),
                "camera {size:?}, lambda_e {lambda_e}: {bad:?}"
            );
        }
    }
    e.set_ablation(0);
    assert_clean(&e);
}
