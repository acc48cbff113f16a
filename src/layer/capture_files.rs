//! `CONTRASTXR_CAPTURE_DIR`: writes what the app rendered, what the runtime got and the
//! background used, for each processed view of the selected frames. How users show that the
//! layer works, and how the tests see the null compositor's frames.

use super::graphics::CapturedImage;
use crate::colour;
use crate::config::{Settings, Value, KEYS};
use crate::gpu::device::pixel_codec;
use crate::gpu::PixelFormat;
use crate::image::RgbaImage;
use std::path::Path;

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

/// Writes the files of one captured view; errors are returned as one sentence.
#[allow(clippy::too_many_arguments)]
pub fn write_view(
    dir: &Path,
    frame: u64,
    view: usize,
    captured: &CapturedImage,
    api: &Api,
    background: &RgbaImage,
    settings: &Settings,
    motion: serde_json::Map<String, serde_json::Value>,
) -> Result<(), String> {
    prepare_folder(dir)?;
    let item = &captured.view;
    let (w, h) = item.key.extent;
    let stem = dir.join(format!("frame-{frame}-view-{view}"));
    let name = |suffix: &str| stem.with_file_name(format!("frame-{frame}-view-{view}{suffix}"));
    to_srgb8(item.format, &captured.display, w, h).save_png(&name("-display.png"))?;
    to_srgb8(item.format, &captured.output, w, h).save_png(&name("-output.png"))?;
    // The exact swapchain bytes too (rows tightly packed): 8-bit PNGs lose linear formats' bits.
    for (suffix, bytes) in [
        ("-display.raw", &captured.display),
        ("-output.raw", &captured.output),
    ] {
        std::fs::write(name(suffix), bytes).map_err(|e| format!("cannot write capture: {e}"))?;
    }
    background.save_png(&name("-background.png"))?;
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
        // image of the layer's own and back), or "copy" (out into a buffer and back).
        "path": captured.path,
        "camera_mapping": item.mapping.rows,
        "background": settings.background,
        "params": settings_json(settings),
    });
    if let Some(object) = json.as_object_mut() {
        object.extend(motion);
    }
    let text = serde_json::to_string_pretty(&json).expect("plain JSON");
    std::fs::write(name(".json"), text).map_err(|e| format!("cannot write capture JSON: {e}"))
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
