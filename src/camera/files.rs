//! File sources: a PNG or JPEG image, a flat colour, and videos (numbered PNG frames or Y4M) played
//! in a loop at their frame rate, following wall-clock time.

use crate::camera::error::CameraError;
use crate::camera::log_sink::log;
use crate::camera::mailbox::{Frame, Shared};
use crate::camera::pool::ImagePool;
use crate::camera::smoothing::Smoother;
use crate::camera::source::CaptureConfig;
use crate::camera::y4m::Y4m;
use crate::gpu::core::blurred_texels::BlurredTexels;
use crate::image::RgbaImage;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The size a still background is used at: the camera size the settings ask for, which the
/// mapping and the blur work at (a `color:` background's size), never over
/// [`MAX_CAMERA_SIDE`](crate::camera::source::MAX_CAMERA_SIDE) a side.
fn still_size(cfg: &CaptureConfig) -> (u32, u32) {
    cfg.frame_size()
}

/// An `image:` background, shrunk as it loads to at most the camera size
/// (`RgbaImage::load_within`): a 12-megapixel photo then costs what a camera frame does.
pub(crate) fn image_frame(path: &Path, cfg: &CaptureConfig) -> Result<Frame, CameraError> {
    let image = RgbaImage::load_within(path, still_size(cfg))
        .map_err(|e| CameraError::File(format!("image:{e}")))?;
    Ok(static_frame(image, cfg))
}

/// A flat colour at the configured camera size, so consumers see one background size.
pub(crate) fn color_frame([r, g, b]: [u8; 3], cfg: &CaptureConfig) -> Frame {
    let (w, h) = still_size(cfg);
    let mut image = RgbaImage::new(w, h, [r, g, b, 255]);
    image.has_alpha = false;
    static_frame(image, cfg)
}

/// A still frame, prepared here (the loading thread) with `cfg.still_blur` when it is set.
fn static_frame(image: RgbaImage, cfg: &CaptureConfig) -> Frame {
    let prepared = cfg
        .still_blur
        .map(|blur| Arc::new(BlurredTexels::prepare_once(&image, blur)));
    Frame {
        image: Arc::new(image),
        sequence: 1,
        captured_at: None,
        prepared,
    }
}

/// The frames of a video, loaded one at a time by the player thread.
pub(crate) trait VideoFrames: Send {
    fn count(&self) -> usize;
    /// Frame `index`, into `into`'s buffer where the format allows (see `pool`).
    fn load(&mut self, index: usize, into: RgbaImage) -> Result<RgbaImage, String>;
}

struct PngFolder {
    files: Vec<PathBuf>,
    /// The camera size each frame is shrunk to as it loads, as an `image:` still is.
    most: (u32, u32),
}

impl VideoFrames for PngFolder {
    fn count(&self) -> usize {
        self.files.len()
    }
    /// Frame `index`, shrunk row by row as it decodes (`RgbaImage::load_within`): a folder of
    /// 8K frames then costs what one of camera-size frames does. (Told apart by their first
    /// bytes, as `image:` is: a JPEG named `.png` plays too.)
    fn load(&mut self, index: usize, _: RgbaImage) -> Result<RgbaImage, String> {
        RgbaImage::load_within(&self.files[index], self.most)
    }
}

impl VideoFrames for Y4m {
    fn count(&self) -> usize {
        self.frame_count()
    }
    fn load(&mut self, index: usize, into: RgbaImage) -> Result<RgbaImage, String> {
        self.read_frame(index, into)
    }
}

/// The slowest and fastest a video plays: a rate outside (a Y4M header's `F1:1e300`, `F0:1`)
/// is clamped, so the player never divides by nothing nor wakes for nothing.
pub(crate) const RATES: std::ops::RangeInclusive<f64> = 0.1..=1000.0;

/// `fps` within [`RATES`]; not a number is refused.
fn playable_rate(fps: f64) -> Result<f64, CameraError> {
    if fps.is_nan() {
        return Err(CameraError::File("video frame rate is not a number".into()));
    }
    let clamped = fps.clamp(*RATES.start(), *RATES.end());
    if clamped != fps {
        log(&format!(
            "video frame rate {fps} fps is out of {}-{} fps: played at {clamped} fps",
            RATES.start(),
            RATES.end()
        ));
    }
    Ok(clamped)
}

/// Opens a video: a folder of PNG frames (at `cfg.video_fps`) or a Y4M file (at its own rate),
/// either clamped to [`RATES`].
pub(crate) fn open_video(
    path: &Path,
    cfg: &CaptureConfig,
) -> Result<(Box<dyn VideoFrames>, f64), CameraError> {
    if path.is_dir() {
        let files = numbered_pngs(path)?;
        let fps = playable_rate(cfg.video_fps)?;
        let most = still_size(cfg);
        Ok((Box::new(PngFolder { files, most }), fps))
    } else {
        let y4m = Y4m::open(path, still_size(cfg))
            .map_err(|e| CameraError::File(format!("video:{e}")))?;
        let fps = playable_rate(y4m.fps)?;
        Ok((Box::new(y4m), fps))
    }
}

/// The PNG files of a folder in frame order: by the number in the name, then by name.
fn numbered_pngs(dir: &Path) -> Result<Vec<PathBuf>, CameraError> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| CameraError::File(format!("cannot read {}: {e}", dir.display())))?;
    let mut files: Vec<(u64, PathBuf)> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("png")))
        .map(|p| (frame_number(&p), p))
        .collect();
    if files.is_empty() {
        return Err(CameraError::File(format!(
            "video folder {} holds no PNG frames",
            dir.display()
        )));
    }
    files.sort();
    Ok(files.into_iter().map(|(_, p)| p).collect())
}

fn frame_number(path: &Path) -> u64 {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    let digits: String = stem.chars().filter(|c| c.is_ascii_digit()).collect();
    digits.parse().unwrap_or(u64::MAX)
}

/// Plays `frames` in a loop until asked to stop. Frame `n` (counted from `start`) is shown from
/// `start + n / fps`; its sequence is `n + 1`, so skipped frames show as a jump in sequence.
pub(crate) fn play(
    mut frames: Box<dyn VideoFrames>,
    fps: f64,
    start: Instant,
    shared: &Shared,
    smoothing: Option<f32>,
) {
    let mut smoother = smoothing.map(Smoother::new);
    let mut pool = ImagePool::default();
    let mut shown = None;
    let mut failed = false;
    let count = frames.count() as u64;
    while !shared.stopping() {
        let n = (start.elapsed().as_secs_f64() * fps) as u64;
        // A one-frame video never changes, so it keeps sequence 1.
        let n = if count == 1 { 0 } else { n };
        if shown != Some(n) {
            shown = Some(n);
            match frames.load((n % count) as usize, pool.take()) {
                Ok(image) => {
                    let image = match smoother.as_mut() {
                        Some(s) => s.apply(image),
                        None => image,
                    };
                    let captured_at = start + Duration::from_secs_f64(n as f64 / fps);
                    shared.publish(Frame {
                        image: pool.share(image),
                        sequence: n + 1,
                        captured_at: Some(captured_at),
                        prepared: None,
                    });
                    failed = false;
                }
                Err(e) if !failed => {
                    failed = true;
                    log(&format!(
                        "video frame {} unreadable, keeping the last one: {e}",
                        n % count
                    ));
                }
                Err(_) => {}
            }
        }
        shared.sleep_until(start + Duration::from_secs_f64((n + 1) as f64 / fps));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::source::MAX_CAMERA_SIDE;

    /// A picture whose shrunk pixels differ from one another.
    fn scene(w: u32, h: u32) -> RgbaImage {
        let mut img = RgbaImage::new(w, h, [0, 0, 0, 255]);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [
                (i % 251) as u8,
                (i / 7 % 256) as u8,
                (i % 13 * 19) as u8,
                255,
            ];
        }
        img
    }

    #[test]
    fn a_colour_is_made_within_the_camera_bound_even_where_u32_wraps() {
        // 2^31 x 2 is 2^32 pixels: 0 in u32, which made an empty buffer under those sides.
        let cfg = CaptureConfig {
            width: 1 << 31,
            height: 2,
            ..CaptureConfig::default()
        };
        let image = color_frame([1, 2, 3], &cfg).image;
        assert_eq!((image.width, image.height), (MAX_CAMERA_SIDE, 2));
        assert_eq!(image.pixels.len(), 2 * MAX_CAMERA_SIDE as usize);
        assert!(image.pixels.iter().all(|p| *p == [1, 2, 3, 255]));
    }

    #[test]
    fn png_video_frames_are_shrunk_to_the_camera_size() {
        let dir = crate::scratch::ScratchDir::new("video-within");
        let (big, small) = (scene(301, 207), scene(40, 30));
        big.save_png(&dir.join("f1.png")).unwrap();
        small.save_png(&dir.join("f2.png")).unwrap();
        let cfg = CaptureConfig {
            width: 64,
            height: 48,
            ..CaptureConfig::default()
        };
        let (mut frames, _) = open_video(&dir, &cfg).unwrap();
        let first = frames.load(0, RgbaImage::new(0, 0, [0; 4])).unwrap();
        assert_eq!((first.width, first.height), (64, 48));
        assert_eq!(first, big.shrunk((64, 48)));
        // Not larger than the camera: as it is.
        assert_eq!(frames.load(1, first).unwrap(), small);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn frames_sort_by_number_not_by_text() {
        let mut v = vec![
            Path::new("f10.png"),
            Path::new("f2.png"),
            Path::new("f1.png"),
        ];
        v.sort_by_key(|p| frame_number(p));
        assert_eq!(
            v,
            [
                Path::new("f1.png"),
                Path::new("f2.png"),
                Path::new("f10.png")
            ]
        );
    }
}
