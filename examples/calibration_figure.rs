//! Draws `docs/calibration.png` (run: `cargo run --example calibration_figure`): what one eye
//! sees in `mode = background` before and after `contrastxr calibrate`, simulated with the CPU
//! reference. The camera frame is a sample scene; the eye sees a part of it that the default
//! mapping (the paper's HoloLens values) misses, so the displayed background and the real
//! world behind it show double edges. The per-eye correction that lines them up is solved
//! exactly here (it is what the calibrate keys reach step by step) and printed.

use contrastxr::algorithm::mapping::CameraMapping;
use contrastxr::algorithm::registration::Nudge;
use contrastxr::algorithm::Params;
use contrastxr::background_preparation::fov_sharp;
use contrastxr::colour;
use contrastxr::evaluate::font::{draw_text, text_height};
use contrastxr::evaluate::{perceived, stack_rows};
use contrastxr::image::RgbaImage;
use glam::DVec2;
use std::path::Path;

const WIDTH: u32 = 480;
const HEIGHT: u32 = 270;
const GAP: u32 = 12;

/// Where the eye's view really lies in this camera frame (made up for the figure).
const TRUE_SCALE: [f32; 2] = [0.52, 0.56];
const TRUE_OFFSET: [f32; 2] = [0.21, 0.25];

fn params(scale: [f32; 2], offset: [f32; 2]) -> Params {
    Params {
        fov_scale: scale,
        fov_offset: offset,
        ..Params::default()
    }
}

/// The background as the layer maps it onto the eye's display (sharp, full brightness).
fn displayed(camera: &RgbaImage, p: &Params) -> RgbaImage {
    let linear = fov_sharp(camera, WIDTH, HEIGHT, p);
    let pixels = linear
        .iter()
        .map(|&c| {
            let [r, g, b] = colour::linear_to_srgb8(c);
            [r, g, b, 255]
        })
        .collect();
    RgbaImage {
        width: WIDTH,
        height: HEIGHT,
        pixels,
        has_alpha: false,
    }
}

/// The correction that turns `from` into `to` (both affine): `to = from * N` with N the
/// nudge's matrix, solved for its scale and offset.
fn solve(from: &CameraMapping, to: &CameraMapping) -> Nudge {
    let n = from.to_mat3().inverse() * to.to_mat3();
    let inverse_scale = DVec2::new(n.x_axis.x, n.y_axis.y);
    let shift = DVec2::new(n.z_axis.x, n.z_axis.y);
    let scale = DVec2::ONE / inverse_scale;
    let c = DVec2::splat(0.5);
    Nudge {
        offset: (c - shift) * scale - c,
        scale,
    }
}

fn panel(camera: &RgbaImage, shown: &Params, label: &str) -> RgbaImage {
    let world = params(TRUE_SCALE, TRUE_OFFSET);
    let mut img = perceived(&displayed(camera, shown), camera, &world);
    let h = text_height(2);
    for y in 0..h + 12 {
        for x in 0..WIDTH {
            let [r, g, b, a] = img.get(x, y);
            img.set(x, y, [r / 3, g / 3, b / 3, a]);
        }
    }
    draw_text(&mut img, 8, 6, label, 2, [236, 238, 242, 255]);
    img
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let camera = RgbaImage::load_png(&root.join("samples/background-grey-office.png"))
        .expect("samples/background-grey-office.png");
    let default = Params::default();
    let truth = CameraMapping::affine(TRUE_SCALE.map(f64::from), TRUE_OFFSET.map(f64::from));
    let nudge = solve(&default.camera_mapping(), &truth);
    let corrected = nudge.apply(&default.camera_mapping());
    for (a, b) in corrected
        .rows
        .iter()
        .flatten()
        .zip(truth.rows.iter().flatten())
    {
        assert!(
            (a - b).abs() < 1e-9,
            "the solved correction must reach the truth"
        );
    }
    println!(
        "left_eye_offset = [{:.4}, {:.4}], left_eye_scale = [{:.4}, {:.4}]",
        nudge.offset.x, nudge.offset.y, nudge.scale.x, nudge.scale.y
    );
    // The corrected mapping is affine: as fov_scale/fov_offset for the CPU reference.
    let after = params(
        [corrected.rows[0][0] as f32, corrected.rows[1][1] as f32],
        [corrected.rows[0][2] as f32, corrected.rows[1][2] as f32],
    );
    let before = panel(&camera, &default, "BEFORE: DOUBLE EDGES");
    let after = panel(&camera, &after, "AFTER CALIBRATE: ONE IMAGE");
    let mut row = RgbaImage::new(2 * WIDTH + GAP, HEIGHT, [22, 24, 28, 255]);
    row.has_alpha = false;
    for (i, p) in [before, after].iter().enumerate() {
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                row.set(i as u32 * (WIDTH + GAP) + x, y, p.get(x, y));
            }
        }
    }
    let out = root.join("docs/calibration.png");
    stack_rows(&[row]).save_png(&out).expect("write the figure");
    println!("wrote {}", out.display());
}
