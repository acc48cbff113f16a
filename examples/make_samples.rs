//! Generates the sample scenes in `samples/` (run: `cargo run --example make_samples`).
//! Everything is procedural and deterministic, so the images carry no third-party licence.
//! Displays are 640x360 virtual content on black (black is transparent on an additive
//! display); backgrounds are 960x540 "camera frames".

use contrastxr::evaluate::font::draw_text;
use contrastxr::image::RgbaImage;
use std::path::Path;

type Rgb = [f64; 3];

fn hash(x: i64, y: i64, seed: u64) -> f64 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ seed;
    h ^= h >> 29;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 32;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Smooth value noise in [0, 1] with features about `cell` pixels wide.
fn noise(x: f64, y: f64, cell: f64, seed: u64) -> f64 {
    let (fx, fy) = (x / cell, y / cell);
    let (ix, iy) = (fx.floor() as i64, fy.floor() as i64);
    let s = |t: f64| t * t * (3.0 - 2.0 * t);
    let (tx, ty) = (s(fx - fx.floor()), s(fy - fy.floor()));
    let top = hash(ix, iy, seed) * (1.0 - tx) + hash(ix + 1, iy, seed) * tx;
    let bottom = hash(ix, iy + 1, seed) * (1.0 - tx) + hash(ix + 1, iy + 1, seed) * tx;
    top * (1.0 - ty) + bottom * ty
}

fn fbm(x: f64, y: f64, cell: f64, seed: u64) -> f64 {
    (0..4)
        .map(|o| noise(x, y, cell / f64::from(1 << o), seed + o) / f64::from(1 << o))
        .sum::<f64>()
        / 1.875
}

fn mix(a: Rgb, b: Rgb, t: f64) -> Rgb {
    let t = t.clamp(0.0, 1.0);
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
}

fn image(w: u32, h: u32, f: impl Fn(f64, f64) -> Rgb) -> RgbaImage {
    let mut img = RgbaImage::new(w, h, [0, 0, 0, 255]);
    img.has_alpha = false;
    for y in 0..h {
        for x in 0..w {
            let c = f(f64::from(x), f64::from(y)).map(|v| v.round().clamp(0.0, 255.0) as u8);
            img.set(x, y, [c[0], c[1], c[2], 255]);
        }
    }
    img
}

fn yellow_wall() -> RgbaImage {
    image(960, 540, |x, y| {
        let paint = fbm(x, y, 120.0, 1) - 0.5;
        let light = 1.0 - 0.25 * ((x - 300.0).hypot(y - 150.0) / 1100.0);
        let base = [238.0, 204.0, 58.0];
        base.map(|c| c * light * (1.0 + 0.08 * paint))
    })
}

fn blue_sky() -> RgbaImage {
    image(960, 540, |x, y| {
        let sky = mix([70.0, 128.0, 215.0], [175.0, 205.0, 238.0], y / 540.0);
        let cloud = (fbm(x, y * 1.8, 220.0, 7) - 0.52) * 4.0;
        mix(sky, [246.0, 248.0, 252.0], cloud)
    })
}

fn grey_office() -> RgbaImage {
    image(960, 540, |x, y| {
        let wall = 150.0 + 10.0 * (fbm(x, y, 200.0, 3) - 0.5);
        let mut c = [wall, wall, wall + 3.0];
        if (560.0..860.0).contains(&x) && (60.0..300.0).contains(&y) {
            c = mix(
                [235.0, 238.0, 242.0],
                [205.0, 220.0, 235.0],
                (y - 60.0) / 240.0,
            ); // window
            if (x - 710.0).abs() < 4.0 || (y - 180.0).abs() < 4.0 {
                c = [210.0, 210.0, 205.0];
            }
        }
        if (120.0..360.0).contains(&x) && (150.0..300.0).contains(&y) {
            c = [38.0, 40.0, 46.0]; // monitor
        }
        if y > 380.0 {
            let grain = fbm(x * 0.3, y * 4.0, 40.0, 5);
            c = [118.0, 88.0, 62.0].map(|v| v * (0.85 + 0.3 * grain)); // desk
        }
        c
    })
}

fn meadow() -> RgbaImage {
    image(960, 540, |x, y| {
        let horizon = 200.0 + 40.0 * fbm(x, 0.0, 180.0, 11);
        if y < horizon {
            let sky = mix([120.0, 170.0, 225.0], [200.0, 220.0, 235.0], y / horizon);
            let trees = fbm(x, y, 60.0, 13);
            return if y > horizon - 90.0 * trees {
                mix([34.0, 70.0, 38.0], [70.0, 105.0, 50.0], trees)
            } else {
                sky
            };
        }
        let grass = fbm(x, y * 2.0, 50.0, 17);
        let flowers = if fbm(x, y, 12.0, 19) > 0.78 { 1.0 } else { 0.0 };
        let g = mix([60.0, 120.0, 40.0], [150.0, 175.0, 60.0], grass);
        mix(g, [230.0, 210.0, 80.0], flowers * 0.7)
    })
}

fn fill_rect(img: &mut RgbaImage, x0: u32, y0: u32, w: u32, h: u32, f: impl Fn(f64, f64) -> Rgb) {
    for y in y0..(y0 + h).min(img.height) {
        for x in x0..(x0 + w).min(img.width) {
            let c = f(
                f64::from(x - x0) / f64::from(w),
                f64::from(y - y0) / f64::from(h),
            );
            let c = c.map(|v| v.round().clamp(1.0, 255.0) as u8);
            img.set(x, y, [c[0], c[1], c[2], 255]);
        }
    }
}

/// A shaded sphere: looks like a lit 3D model, with a full range of shades of one colour.
fn sphere(img: &mut RgbaImage, cx: f64, cy: f64, r: f64, colour: Rgb) {
    for y in (cy - r) as u32..(cy + r) as u32 {
        for x in (cx - r) as u32..(cx + r) as u32 {
            let (dx, dy) = ((f64::from(x) - cx) / r, (f64::from(y) - cy) / r);
            let d2 = dx * dx + dy * dy;
            if d2 < 1.0 {
                let nz = (1.0 - d2).sqrt();
                let diffuse = (-0.4 * dx - 0.5 * dy + 0.77 * nz).max(0.0);
                let spec = diffuse.powi(40);
                let c = colour
                    .map(|v| (v * (0.15 + 0.85 * diffuse) + 255.0 * 0.6 * spec).clamp(1.0, 255.0));
                img.set(x, y, [c[0] as u8, c[1] as u8, c[2] as u8, 255]);
            }
        }
    }
}

/// A UI panel with text, buttons and a landscape photograph, plus some shaded objects.
fn hand_interaction() -> RgbaImage {
    let mut img = RgbaImage::new(640, 360, [0, 0, 0, 255]);
    img.has_alpha = false;
    fill_rect(&mut img, 24, 24, 360, 312, |_, v| {
        mix([52.0, 60.0, 78.0], [36.0, 42.0, 56.0], v)
    });
    draw_text(&mut img, 44, 42, "CONTRASTXR", 4, [255, 255, 255, 255]);
    draw_text(
        &mut img,
        44,
        84,
        "VIRTUAL CONTENT ON BLACK",
        2,
        [230, 230, 230, 255],
    );
    fill_rect(&mut img, 44, 112, 320, 150, |u, v| {
        let hill = 0.55 + 0.12 * (u * 9.0).sin() * (u * 3.0).cos();
        if v > hill {
            mix([70.0, 140.0, 60.0], [40.0, 90.0, 35.0], (v - hill) * 3.0)
        } else if (u - 0.75).hypot(v - 0.22) < 0.08 {
            [255.0, 230.0, 120.0]
        } else {
            mix([80.0, 150.0, 230.0], [190.0, 215.0, 240.0], v / hill)
        }
    });
    let buttons = [
        [220.0, 60.0, 50.0],
        [60.0, 180.0, 90.0],
        [60.0, 110.0, 220.0],
        [245.0, 160.0, 40.0],
    ];
    for (i, c) in buttons.iter().enumerate() {
        fill_rect(&mut img, 44 + i as u32 * 82, 278, 72, 40, |_, v| {
            c.map(|x| x * (1.0 - 0.2 * v))
        });
    }
    sphere(&mut img, 470.0, 100.0, 62.0, [230.0, 40.0, 40.0]);
    sphere(&mut img, 560.0, 210.0, 52.0, [250.0, 250.0, 250.0]);
    sphere(&mut img, 460.0, 270.0, 58.0, [250.0, 215.0, 60.0]);
    draw_text(&mut img, 420, 330, "HELLO OST-HMD", 2, [255, 255, 255, 255]);
    img
}

/// Text and colour swatches: white, greys, primaries and secondaries.
fn text_and_swatches() -> RgbaImage {
    let mut img = RgbaImage::new(640, 360, [0, 0, 0, 255]);
    img.has_alpha = false;
    draw_text(&mut img, 40, 30, "WHITE TEXT ON", 5, [255, 255, 255, 255]);
    draw_text(&mut img, 40, 80, "ANY BACKGROUND", 5, [255, 255, 255, 255]);
    let swatches = [
        [255.0, 255.0, 255.0],
        [180.0, 180.0, 180.0],
        [100.0, 100.0, 100.0],
        [255.0, 0.0, 0.0],
        [0.0, 255.0, 0.0],
        [0.0, 0.0, 255.0],
        [0.0, 255.0, 255.0],
        [255.0, 0.0, 255.0],
        [255.0, 255.0, 0.0],
    ];
    for (i, c) in swatches.iter().enumerate() {
        let (col, row) = (i as u32 % 5, i as u32 / 5);
        fill_rect(
            &mut img,
            40 + col * 116,
            150 + row * 100,
            100,
            84,
            |_, _| *c,
        );
    }
    fill_rect(&mut img, 40 + 4 * 116, 250, 100, 84, |u, _| {
        mix([20.0, 20.0, 20.0], [255.0, 255.0, 255.0], u)
    });
    img
}

fn main() -> Result<(), String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let images = [
        ("display-hand-interaction.png", hand_interaction()),
        ("display-text-swatches.png", text_and_swatches()),
        ("background-yellow-wall.png", yellow_wall()),
        ("background-blue-sky.png", blue_sky()),
        ("background-grey-office.png", grey_office()),
        ("background-meadow.png", meadow()),
    ];
    for (name, img) in images {
        img.save_png(&dir.join(name))?;
        println!("wrote samples/{name}");
    }
    Ok(())
}
