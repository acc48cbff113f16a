//! A capture of the layer's (`CONTRASTXR_CAPTURE_DIR`) checked against the CPU reference,
//! computed here from the captured display and background, within the tolerance of
//! docs/algorithm.md, Conformance. Formats by their Vulkan or OpenGL names.

use contrastxr::algorithm::mapping::CameraMapping;
use contrastxr::algorithm::perception::frequency::{view_params, ViewGeometry};
use contrastxr::algorithm::perceptual_settings::{Frequency, PerceptualSettings};
use contrastxr::algorithm::{
    conformant, enhance_linear, enhance_srgb8_trace, Method, Params, Stored,
};
use contrastxr::background_preparation::{prepare, PreparedBackground};
use contrastxr::image::RgbaImage;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// A file of the repository's samples/ folder, as an absolute path.
pub fn sample(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// A fresh, empty capture directory under the target folder (visible inside the sandbox).
pub fn capture_dir(tag: &str) -> PathBuf {
    let dir = super::scratch_file(&format!("{tag}.capture"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `n` solid-colour PNG frames (each clearly different) as a `video:` directory.
pub fn video_dir(tag: &str, n: usize) -> PathBuf {
    let dir = capture_dir(&format!("{tag}.video"));
    let colours = [
        [230, 210, 30],
        [40, 90, 220],
        [200, 40, 40],
        [40, 200, 80],
        [240, 240, 240],
        [120, 60, 160],
    ];
    for i in 0..n {
        let c = colours[i % colours.len()];
        let mut img = RgbaImage::new(96, 64, [c[0], c[1], c[2], 255]);
        // A gradient so blur and FoV mapping matter, not just a flat colour.
        for y in 0..64 {
            for x in 0..96 {
                let p = img.get(x, y);
                img.set(
                    x,
                    y,
                    [
                        p[0].saturating_sub((x / 2) as u8),
                        p[1],
                        p[2].saturating_sub((y / 2) as u8),
                        255,
                    ],
                );
            }
        }
        img.save_png(&dir.join(format!("frame-{i:03}.png")))
            .unwrap();
    }
    dir
}

/// The captures of a run that enhanced 12 frames of 2 views against a `video_dir` background:
/// 24 views, each within the CPU reference with the method at work, against at least 3
/// different background frames (the source runs at 30 fps and the null compositor at 20 Hz:
/// 12 frames span ~0.6 s).
pub fn assert_follows_the_video(views: &[Captured]) {
    assert_eq!(views.len(), 24, "12 frames x 2 views captured");
    let mut distinct: Vec<&Vec<[u8; 4]>> = Vec::new();
    for c in views {
        assert!(check_view(c) > 100, "the method changed almost nothing");
        if !distinct.contains(&&c.camera.pixels) {
            distinct.push(&c.camera.pixels);
        }
    }
    assert!(
        distinct.len() >= 3,
        "only {} distinct background frames in 12 captured frames",
        distinct.len()
    );
}

/// One captured view: its metadata and files.
pub struct Captured {
    pub json: serde_json::Value,
    pub display: Vec<u8>,
    pub output: Vec<u8>,
    pub camera: RgbaImage,
}

pub fn captures(dir: &Path) -> Vec<Captured> {
    let mut stems: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    stems.sort();
    stems
        .iter()
        .map(|json| {
            let file = |suffix: &str| {
                let stem = json.file_stem().unwrap().to_string_lossy().into_owned();
                json.with_file_name(format!("{stem}{suffix}"))
            };
            Captured {
                json: serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap(),
                display: std::fs::read(file("-display.raw")).unwrap(),
                output: std::fs::read(file("-output.raw")).unwrap(),
                camera: RgbaImage::load_png(&file("-background.png")).unwrap(),
            }
        })
        .collect()
}

pub fn params_of(json: &serde_json::Value) -> Params {
    let p = &json["params"];
    let f = |k: &str| p[k].as_f64().unwrap() as f32;
    let pair = |k: &str| {
        [
            p[k][0].as_f64().unwrap() as f32,
            p[k][1].as_f64().unwrap() as f32,
        ]
    };
    Params {
        lambda_e: f("lambda_e"),
        lambda_jnd_scaled: f("lambda_jnd_scaled"),
        transmittance: f("transmittance"),
        blur: p["blur"].as_bool().unwrap(),
        blur_size: p["blur_size"].as_u64().unwrap() as u32,
        blur_sigma: f("blur_sigma"),
        fov: p["fov"].as_bool().unwrap(),
        fov_scale: pair("fov_scale"),
        fov_offset: pair("fov_offset"),
        method: Method::parse(p["method"].as_str().unwrap()).unwrap(),
        perceptual: perceptual_of(p),
        ..Params::default()
    }
}

/// The perceptual model's settings of a capture's `params`.
fn perceptual_of(p: &serde_json::Value) -> PerceptualSettings {
    let f = |k: &str| p[k].as_f64().unwrap_or_else(|| panic!("{k} in {p}"));
    PerceptualSettings {
        display_peak_nits: f("display_peak_nits"),
        world_nits: f("world_nits"),
        target_contrast: f("target_contrast"),
        min_luminance: f("min_luminance"),
        frequency: Frequency::parse(p["frequency"].as_str().unwrap()).unwrap(),
    }
}

/// A captured view's params as the layer ran its method: the perceptual model's `blur`
/// frequency resolved for the view (its pixels per degree and camera mapping in the capture).
pub fn view_params_of(json: &serde_json::Value, camera_width: u32) -> Params {
    let rows = &json["camera_mapping"];
    let mapping = CameraMapping {
        rows: std::array::from_fn(|r| std::array::from_fn(|c| rows[r][c].as_f64().unwrap())),
    };
    let view = ViewGeometry {
        mapping: &mapping,
        display_width: json["rect"]["width"].as_u64().unwrap() as u32,
        camera_width,
        pixels_per_degree: json["pixels_per_degree"].as_f64().unwrap(),
    };
    view_params(&params_of(json), &view)
}

/// A raw pixel decoded independently of the layer: channel values as stored, and alpha.
fn decode(format: &str, px: &[u8]) -> ([f64; 3], f64) {
    let u8s = |i: usize| f64::from(px[i]) / 255.0;
    let u16s = |i: usize| f64::from(u16::from_le_bytes([px[2 * i], px[2 * i + 1]]));
    match format {
        "R8G8B8A8_SRGB" | "R8G8B8A8_UNORM" | "GL_SRGB8_ALPHA8" | "GL_RGBA8" => {
            ([u8s(0), u8s(1), u8s(2)], u8s(3))
        }
        "B8G8R8A8_SRGB" | "B8G8R8A8_UNORM" => ([u8s(2), u8s(1), u8s(0)], u8s(3)),
        "R16G16B16A16_UNORM" | "GL_RGBA16" => (
            [u16s(0) / 65535.0, u16s(1) / 65535.0, u16s(2) / 65535.0],
            u16s(3) / 65535.0,
        ),
        "R16G16B16A16_SFLOAT" | "GL_RGBA16F" => {
            let h = |i: usize| f64::from(half(u16::from_le_bytes([px[2 * i], px[2 * i + 1]])));
            ([h(0), h(1), h(2)], h(3))
        }
        f => panic!("unexpected format {f}"),
    }
}

fn half(h: u16) -> f32 {
    let e = i32::from((h >> 10) & 31);
    let m = f32::from(h & 1023);
    let v = if e == 0 {
        m * 2f32.powi(-24)
    } else {
        (1.0 + m / 1024.0) * 2f32.powi(e - 15)
    };
    if h & 0x8000 != 0 {
        -v
    } else {
        v
    }
}

/// Largest difference a linear format may show against the f64 reference: half a step of its
/// quantisation plus f32 noise (and f16's relative precision).
fn linear_tolerance(format: &str, v: f64) -> f64 {
    match format {
        "R16G16B16A16_UNORM" | "GL_RGBA16" => 1.0 / 65535.0 + 2e-5,
        "R16G16B16A16_SFLOAT" | "GL_RGBA16F" => v.abs() / 1024.0 + 2e-5,
        _ => 1.0 / 255.0 + 2e-5,
    }
}

/// How a captured format stores the output (the perceptual method judges it so).
fn stored_of(format: &str, srgb: bool) -> Stored {
    match format {
        _ if srgb => Stored::Srgb8,
        "R16G16B16A16_UNORM" | "GL_RGBA16" => Stored::Unorm(65535),
        "R16G16B16A16_SFLOAT" | "GL_RGBA16F" => Stored::Exact,
        _ => Stored::Unorm(255),
    }
}

/// Checks one captured view against the CPU reference; returns how many pixels the method
/// changed (so callers can insist that it did something).
pub fn check_view(c: &Captured) -> usize {
    let format = c.json["format"].as_str().unwrap().to_string();
    let srgb = c.json["srgb"].as_bool().unwrap();
    let (w, h) = (
        c.json["rect"]["width"].as_u64().unwrap() as u32,
        c.json["rect"]["height"].as_u64().unwrap() as u32,
    );
    let mut params = view_params_of(&c.json, c.camera.width);
    params.stored = stored_of(&format, srgb);
    let bg: PreparedBackground = prepare(&c.camera, w, h, &params);
    let bpp = c.json["bytes_per_pixel"].as_u64().unwrap() as usize;
    assert_eq!(
        c.display.len(),
        (w * h) as usize * bpp,
        "{format}: display capture size"
    );
    let mut changed = 0;
    let mut bad = Vec::new();
    for i in 0..(w * h) as usize {
        let (d_raw, o_raw) = (
            &c.display[i * bpp..(i + 1) * bpp],
            &c.output[i * bpp..(i + 1) * bpp],
        );
        let (rgb, alpha) = decode(&format, d_raw);
        let (out_rgb, _) = decode(&format, o_raw);
        if srgb {
            let code = |v: f64| (v * 255.0).round() as u8;
            let d = [code(rgb[0]), code(rgb[1]), code(rgb[2]), code(alpha)];
            let o = [
                code(out_rgb[0]),
                code(out_rgb[1]),
                code(out_rgb[2]),
                code(alpha),
            ];
            let trace = enhance_srgb8_trace(d, bg.linear[i], bg.scaled[i], &params);
            changed += usize::from(trace.out != d);
            if !conformant(&trace, o) {
                bad.push(format!(
                    "pixel {i}: display {d:?} reference {:?} layer {o:?}",
                    trace.out
                ));
            }
            continue;
        }
        let lin = DVec3::from_array(rgb);
        match enhance_linear(lin, alpha, bg.linear[i], bg.scaled[i], &params) {
            None => {
                if d_raw != o_raw {
                    bad.push(format!(
                        "pixel {i}: skipped pixel changed {d_raw:?} -> {o_raw:?}"
                    ));
                }
            }
            Some(want) => {
                changed += usize::from((want - lin).abs().max_element() > 1e-3);
                let ok = (0..3)
                    .all(|k| (out_rgb[k] - want[k]).abs() <= linear_tolerance(&format, want[k]));
                if !ok {
                    bad.push(format!(
                        "pixel {i}: display {rgb:?} reference {want:?} layer {out_rgb:?}"
                    ));
                }
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{format}: {} of {} pixels differ from the reference, e.g. {:?}",
        bad.len(),
        w * h,
        &bad[..bad.len().min(5)]
    );
    changed
}
