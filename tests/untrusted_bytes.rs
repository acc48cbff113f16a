//! Bytes others control, parsed inside the app's process: camera frames (MJPEG, and YUYV, NV12,
//! RGB, grey with sizes that lie), Y4M videos, PNG and JPEG images. Seeded property and
//! mutation runs: every input gives a result or an error, never a panic, and a decoded image
//! has exactly the pixels its size says. (The config file is fuzzed in tests/hardening.rs.)
//!
//! `CONTRASTXR_FUZZ_CASES` (inputs per parser) and `CONTRASTXR_FUZZ_SEED` make a longer run:
//! `scripts/fuzz`.

use contrastxr::camera::convert::{to_rgba, PixelFormat};
use contrastxr::camera::{Background, CaptureConfig, SourceSpec};
use contrastxr::image::RgbaImage;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use std::fmt::Debug;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

fn setting(key: &str, default: u64) -> u64 {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Runs `check` on `cases` inputs from `strategy` (seeded), any panic counting as a failure;
/// prints how many inputs were tried and the (shrunk) failure, if any.
fn fuzz<S: Strategy>(
    name: &str,
    cases: u64,
    strategy: S,
    check: impl Fn(S::Value) -> Result<(), String>,
) where
    S::Value: Debug,
{
    let cases = setting("CONTRASTXR_FUZZ_CASES", cases);
    let seed = setting("CONTRASTXR_FUZZ_SEED", 1);
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    let config = Config {
        cases: cases as u32,
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner =
        TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &key));
    let tried = AtomicU64::new(0);
    let result = runner.run(&strategy, |input| {
        tried.fetch_add(1, Ordering::Relaxed);
        match catch_unwind(AssertUnwindSafe(|| check(input))) {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(TestCaseError::fail(e)),
            Err(_) => Err(TestCaseError::fail("panicked")),
        }
    });
    let failures = usize::from(result.is_err());
    println!(
        "{name}: {} inputs tried (seed {seed}), {failures} failures",
        tried.load(Ordering::Relaxed)
    );
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
}

/// A decoded image must hold exactly width x height pixels.
fn whole(image: Result<RgbaImage, String>) -> Result<(), String> {
    match image {
        Ok(img) if img.pixels.len() != img.width as usize * img.height as usize => Err(format!(
            "{}x{} image with {} pixels",
            img.width,
            img.height,
            img.pixels.len()
        )),
        _ => Ok(()),
    }
}

/// Byte-level mutations of a valid input: flips, overwrites, cuts and insertions.
fn mutated(seed: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let len = seed.len();
    proptest::collection::vec((0..len.max(1), any::<u8>(), 0u8..4), 1..8).prop_map(move |edits| {
        let mut bytes = seed.clone();
        for (at, value, kind) in edits {
            let at = at.min(bytes.len().saturating_sub(1));
            match kind {
                0 if !bytes.is_empty() => bytes[at] ^= value | 1,
                1 if !bytes.is_empty() => bytes[at] = value,
                2 => bytes.truncate(at),
                _ => bytes.insert(at.min(bytes.len()), value),
            }
        }
        bytes
    })
}

fn sample_image() -> RgbaImage {
    let mut img = RgbaImage::new(24, 16, [0, 0, 0, 255]);
    for y in 0..16 {
        for x in 0..24 {
            img.set(x, y, [(x * 10) as u8, (y * 15) as u8, 128, 255]);
        }
    }
    img
}

fn sample_jpeg() -> Vec<u8> {
    let img = sample_image();
    let rgb: Vec<u8> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    let mut out = Vec::new();
    jpeg_encoder::Encoder::new(&mut out, 80)
        .encode(&rgb, 24, 16, jpeg_encoder::ColorType::Rgb)
        .unwrap();
    out
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("untrusted-bytes")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn raw_camera_frames_with_lying_sizes() {
    let formats = prop_oneof![
        Just(PixelFormat::Yuyv),
        Just(PixelFormat::Nv12),
        Just(PixelFormat::Rgb24),
        Just(PixelFormat::Bgr24),
        Just(PixelFormat::Grey),
    ];
    let size = prop_oneof![0u32..64, 0u32..5000, Just(u32::MAX), any::<u32>()];
    let stride = prop_oneof![Just(0u32), 0u32..20_000, any::<u32>()];
    let data = proptest::collection::vec(any::<u8>(), 0..4096);
    fuzz(
        "raw frames",
        512,
        (formats, size.clone(), size, stride, data),
        |(format, w, h, stride, data)| whole(to_rgba(format, &data, w, h, stride)),
    );
}

#[test]
fn mjpeg_frames_mutated() {
    let jpeg = sample_jpeg();
    assert!(to_rgba(PixelFormat::Mjpeg, &jpeg, 24, 16, 0).is_ok());
    fuzz("MJPEG frames", 256, mutated(jpeg), |bytes| {
        whole(to_rgba(PixelFormat::Mjpeg, &bytes, 24, 16, 0))
    });
}

#[test]
fn image_files_mutated() {
    let dir = scratch("images");
    let png_path = dir.join("seed.png");
    sample_image().save_png(&png_path).unwrap();
    let png = std::fs::read(&png_path).unwrap();
    let jpeg = sample_jpeg();
    let path = dir.join("image");
    fuzz(
        "image files",
        256,
        prop_oneof![mutated(png), mutated(jpeg)],
        |bytes| {
            std::fs::write(&path, &bytes).map_err(|e| e.to_string())?;
            whole(RgbaImage::load(&path))
        },
    );
}

fn sample_y4m() -> Vec<u8> {
    let mut out = b"YUV4MPEG2 W8 H4 F30:1 Ip A1:1 C420jpeg\n".to_vec();
    for f in 0..2u8 {
        out.extend_from_slice(b"FRAME\n");
        out.extend((0..8 * 4 + 2 * 4 * 2).map(|i| (i as u8).wrapping_mul(7) ^ f));
    }
    out
}

#[test]
fn y4m_videos_mutated() {
    let dir = scratch("y4m");
    let path = dir.join("video.y4m");
    let seed = sample_y4m();
    std::fs::write(&path, &seed).unwrap();
    let open = |path: &PathBuf| {
        Background::open(&SourceSpec::Video(path.clone()), &CaptureConfig::default())
    };
    assert!(open(&path).is_ok(), "the seed video must open");
    let declared = (
        any::<u32>(),
        any::<u32>(),
        proptest::collection::vec(any::<u8>(), 0..512),
    )
        .prop_map(|(w, h, data)| {
            let mut out = format!("YUV4MPEG2 W{w} H{h} F30:1 C420jpeg\nFRAME\n").into_bytes();
            out.extend(data);
            out
        });
    fuzz(
        "Y4M videos",
        128,
        prop_oneof![mutated(seed), declared],
        |bytes| {
            std::fs::write(&path, &bytes).map_err(|e| e.to_string())?;
            if let Ok(bg) = open(&path) {
                if let Some(frame) = bg.latest() {
                    whole(Ok((*frame.image).clone()))?;
                }
                bg.close();
            }
            Ok(())
        },
    );
}
