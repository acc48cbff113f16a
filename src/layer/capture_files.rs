//! `CONTRASTXR_CAPTURE_DIR`: writes what the app rendered, what the runtime got and the
//! background used, for each processed view of the selected frames, with the perceived
//! contrast of its content before and after. How users show that the layer works, and how the
//! tests see the null compositor's frames. The layer's own read-back for its out-of-reach
//! check is a capture without files.

use super::graphics::CapturedImage;
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::Params;
use crate::colour;
use crate::config::{Settings, Value, KEYS};
use crate::gpu::core::pixel_codec;
use crate::gpu::PixelFormat;
use crate::image::RgbaImage;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Converts a region's raw pixels to 8-bit sRGB (sRGB formats are copied, linear ones encoded).
pub fn to_srgb8(format: PixelFormat, raw: &[u8], width: u32, height: u32) -> RgbaImage {
    let bpp = format.bytes_per_pixel() as usize;
    let pixels = raw
        .chunks_exact(bpp)
        .take((width * height) as usize)
        .map(|px| {
            let c = pixel_codec::decode(format, px).map(f64::from);
            // sRGB formats already hold encoded values; linear ones are encoded here.
            let encode = |v: f64| {
                if format.srgb {
                    v
                } else {
                    colour::srgb_encode(v.clamp(0.0, 1.0))
                }
            };
            [
                colour::quantize(encode(c[0])),
                colour::quantize(encode(c[1])),
                colour::quantize(encode(c[2])),
                colour::quantize(c[3]),
            ]
        })
        .collect();
    RgbaImage {
        width,
        height,
        pixels,
        has_alpha: true,
    }
}

fn json_value(v: Value) -> serde_json::Value {
    match v {
        Value::Bool(b) => b.into(),
        // Through the shortest decimal, so 0.4 is written 0.4, not 0.4000000059604645.
        Value::Float(x) => serde_json::json!(short(x)),
        Value::Count(n) => n.into(),
        Value::Pair([x, y]) => serde_json::json!([short(x), short(y)]),
        Value::Numbers(v) => v.into_iter().map(short).collect(),
        Value::Text(t) => t.into(),
    }
}

fn short(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// Every setting the frame was processed with, by its config key: the same table the config
/// file, the environment and `contrastxr set` use, so no key can be missing.
pub fn settings_json(settings: &Settings) -> serde_json::Value {
    let map = KEYS
        .iter()
        .map(|k| (k.name.to_string(), json_value(k.get(settings))))
        .collect();
    serde_json::Value::Object(map)
}

/// Makes the capture folder where it is missing; a path that is not a writable folder (a file,
/// a device node, a FIFO) is refused in words, before anything is opened there.
pub fn prepare_folder(dir: &Path) -> Result<(), String> {
    let refused = |why: String| format!("capture folder {} {why}", dir.display());
    if std::fs::symlink_metadata(dir).is_err() {
        std::fs::create_dir_all(dir).map_err(|e| refused(format!("cannot be created ({e})")))?;
    }
    crate::user_file::folder(dir).map_err(refused)
}

/// The graphics API a capture came through, as its JSON names it.
pub struct Api {
    /// "vulkan" or "opengl".
    pub graphics: &'static str,
    /// The swapchain's format by that API's name (`R8G8B8A8_SRGB`, `GL_SRGB8_ALPHA8`).
    pub format: String,
}

/// What a captured view's perception report needs besides its pixels and the camera frame.
#[derive(Clone, Debug)]
pub struct ReportView {
    /// The settings the frame was processed with.
    pub params: Params,
    /// Display uv (v from the view's top edge) to camera uv.
    pub mapping: CameraMapping,
    pub pixels_per_degree: f64,
}

/// One captured view, taken on the app's thread and handed to the capture thread
/// (`capture_writer`), which makes its perception report and writes its files: the pixels as
/// read back, and the JSON as it was at the frame.
pub struct CaptureJob {
    /// The capture folder; None for the out-of-reach check's read-back, which writes no file.
    pub dir: Option<PathBuf>,
    /// `frame-N-view-V`, which every file name starts with.
    pub stem: String,
    pub format: PixelFormat,
    pub extent: (u32, u32),
    pub display: Vec<u8>,
    pub output: Vec<u8>,
    /// The camera frame the view was enhanced against.
    pub background: Arc<RgbaImage>,
    pub json: serde_json::Value,
    pub view: ReportView,
}

impl CaptureJob {
    /// The job of one captured view: its JSON is made here, with `extra`'s keys (the view's
    /// motion, the layer's GPU time so far), its files by [`write`](Self::write).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        dir: &Path,
        frame: u64,
        view: usize,
        captured: CapturedImage,
        api: &Api,
        background: Arc<RgbaImage>,
        settings: &Settings,
        extra: serde_json::Map<String, serde_json::Value>,
    ) -> CaptureJob {
        let item = &captured.view;
        let (w, h) = item.key.extent;
        let mut json = serde_json::json!({
            "frame": frame,
            "view": view,
            "graphics": api.graphics,
            "format": api.format,
            "bytes_per_pixel": item.format.bytes_per_pixel(),
            "srgb": item.format.srgb,
            "rect": {"x": item.key.offset.0, "y": item.key.offset.1, "width": w, "height": h},
            "image_array_index": item.key.array_index,
            // How the view was enhanced: "in-place" in the app's image, "image-copy" (out into an
            // image of the layer's own and back), "image-copy-tiles" (its listed tiles drawn
            // back), "sampled-tiles" (read through a sampled view, its listed tiles drawn
            // back), or "copy" (out into a buffer and back).
            "path": captured.path,
            "camera_mapping": item.mapping.rows,
            "pixels_per_degree": item.pixels_per_degree,
            "background": settings.background,
            "params": settings_json(settings),
        });
        if let Some(object) = json.as_object_mut() {
            object.extend(extra);
        }
        CaptureJob {
            dir: Some(dir.to_path_buf()),
            stem: format!("frame-{frame}-view-{view}"),
            format: item.format,
            extent: (w, h),
            view: ReportView {
                params: settings.params.clone(),
                mapping: item.mapping,
                pixels_per_degree: item.pixels_per_degree,
            },
            display: captured.display,
            output: captured.output,
            background,
            json,
        }
    }

    /// The out-of-reach check's read-back of one view: its report, no files.
    pub fn check(captured: CapturedImage, background: Arc<RgbaImage>, params: &Params) -> Self {
        let item = &captured.view;
        CaptureJob {
            dir: None,
            stem: "check".into(),
            format: item.format,
            extent: item.key.extent,
            view: ReportView {
                params: params.clone(),
                mapping: item.mapping,
                pixels_per_degree: item.pixels_per_degree,
            },
            display: captured.display,
            output: captured.output,
            background,
            json: serde_json::Value::Null,
        }
    }

    /// The memory the job holds until written (the background is shared with the frames).
    pub fn bytes(&self) -> usize {
        self.display.len() + self.output.len()
    }

    /// Writes the view's files, the JSON last (its presence says the others are complete);
    /// nothing without a folder. Errors are one sentence.
    pub fn write(&self) -> Result<(), String> {
        let Some(dir) = &self.dir else {
            return Ok(());
        };
        prepare_folder(dir)?;
        let (w, h) = self.extent;
        let file =
            |suffix: &str, bytes: &[u8]| create_file(dir, &format!("{}{suffix}", self.stem), bytes);
        file(
            "-display.png",
            &to_srgb8(self.format, &self.display, w, h).encode_png()?,
        )?;
        file(
            "-output.png",
            &to_srgb8(self.format, &self.output, w, h).encode_png()?,
        )?;
        // The exact swapchain bytes too (rows tightly packed): 8-bit PNGs lose linear formats' bits.
        file("-display.raw", &self.display)?;
        file("-output.raw", &self.output)?;
        file("-background.png", &self.background.encode_png()?)?;
        let text = serde_json::to_string_pretty(&self.json).expect("plain JSON");
        file(".json", text.as_bytes())
    }
}

/// Writes `name` in `dir` as [`crate::user_file::write_replacing`] does: never through a link
/// or anything else already there, never blocking on a FIFO.
pub fn create_file(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), String> {
    crate::user_file::write_replacing(&dir.join(name), bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::PixelLayout;

    #[test]
    fn every_config_key_is_in_the_capture_json() {
        let mut settings = Settings::default();
        settings.params.achromatic_boost = 0.25;
        let json = settings_json(&settings);
        let object = json.as_object().unwrap();
        assert_eq!(object.len(), KEYS.len());
        for k in KEYS {
            assert!(object.contains_key(k.name), "{} missing", k.name);
        }
        assert_eq!(json["mode"], "enhance");
        assert_eq!(json["lambda_e"], 0.4);
        assert_eq!(json["achromatic_boost"], 0.25);
        assert_eq!(json["luminance_cap"], 0.0);
        assert_eq!(json["fov_scale"], serde_json::json!([0.65, 0.65]));
        assert_eq!(json["blur_size"], 3);
        assert_eq!(json["blur"], true);
    }

    fn job(dir: &Path) -> CaptureJob {
        let f = PixelFormat {
            layout: PixelLayout::Rgba8,
            srgb: true,
        };
        CaptureJob {
            dir: Some(dir.to_path_buf()),
            stem: "frame-0-view-0".into(),
            format: f,
            extent: (2, 1),
            display: vec![1, 2, 3, 255, 4, 5, 6, 255],
            output: vec![7, 8, 9, 255, 10, 11, 12, 255],
            background: Arc::new(RgbaImage::new(2, 1, [20, 30, 40, 255])),
            json: serde_json::json!({"frame": 0}),
            view: ReportView {
                params: Params::default(),
                mapping: Params::default().camera_mapping(),
                pixels_per_degree: 20.0,
            },
        }
    }

    fn temp_dir(name: &str) -> crate::scratch::ScratchDir {
        crate::scratch::ScratchDir::new(&format!("capture-files-{name}"))
    }

    /// A link planted at a capture's name is replaced, not written through: the file it
    /// points at keeps its bytes.
    #[test]
    fn a_link_at_a_capture_name_is_never_written_through() {
        let dir = temp_dir("link");
        let victim = dir.join("victim");
        std::fs::write(&victim, "keep me").unwrap();
        for suffix in ["-display.png", "-output.raw", ".json"] {
            let at = dir.join(format!("frame-0-view-0{suffix}"));
            std::os::unix::fs::symlink(&victim, at).unwrap();
        }
        job(&dir).write().unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me");
        let json = dir.join("frame-0-view-0.json");
        assert!(std::fs::symlink_metadata(&json).unwrap().is_file());
        assert_eq!(
            std::fs::read_to_string(json).unwrap(),
            "{\n  \"frame\": 0\n}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A FIFO at a capture's name (nobody reading it) never blocks the write.
    #[test]
    fn a_fifo_at_a_capture_name_never_blocks() {
        let dir = temp_dir("fifo");
        for suffix in ["-display.png", "-output.raw", "-background.png"] {
            let c = std::ffi::CString::new(
                dir.join(format!("frame-0-view-0{suffix}"))
                    .into_os_string()
                    .into_encoded_bytes(),
            )
            .unwrap();
            // SAFETY: `c` is a valid NUL-terminated path that outlives the call.
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let writing = dir.to_path_buf();
        std::thread::spawn(move || {
            let _ = tx.send(job(&writing).write());
        });
        let done = rx.recv_timeout(std::time::Duration::from_secs(5));
        assert!(done.is_ok(), "the write blocked on a FIFO");
        done.unwrap().unwrap();
        let png = dir.join("frame-0-view-0-display.png");
        assert!(std::fs::symlink_metadata(png).unwrap().is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn linear_formats_are_encoded_to_srgb() {
        let f = PixelFormat {
            layout: PixelLayout::Rgba8,
            srgb: false,
        };
        // Linear 0.2140 (55/255 ~ 0.2157) encodes to sRGB ~ 0.5 -> 128.
        let img = to_srgb8(f, &[55, 0, 255, 255], 1, 1);
        assert_eq!(img.pixels[0], [128, 0, 255, 255]);
        let f = PixelFormat {
            layout: PixelLayout::Bgra8,
            srgb: true,
        };
        assert_eq!(to_srgb8(f, &[1, 2, 3, 4], 1, 1).pixels[0], [3, 2, 1, 4]);
    }
}
