//! 8-bit RGBA images: PNG and JPEG input, PNG output. Pixels are sRGB-encoded code values.

use std::path::Path;
use zune_jpeg::zune_core::bytestream::ZCursor;
use zune_jpeg::zune_core::colorspace::ColorSpace;
use zune_jpeg::zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

use crate::user_file;

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1A, b'\n'];
const JPEG_SIGNATURE: [u8; 3] = [0xFF, 0xD8, 0xFF];

/// An 8-bit sRGB image, always stored as RGBA (RGB input gets alpha 255).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbaImage {
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first; `width * height` entries.
    pub pixels: Vec<[u8; 4]>,
    /// Whether the source had an alpha channel (so output keeps the same layout).
    pub has_alpha: bool,
}

impl RgbaImage {
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Self {
        RgbaImage {
            width,
            height,
            pixels: vec![fill; (width * height) as usize],
            has_alpha: true,
        }
    }

    pub fn get(&self, x: u32, y: u32) -> [u8; 4] {
        self.pixels[(y * self.width + x) as usize]
    }

    pub fn set(&mut self, x: u32, y: u32, v: [u8; 4]) {
        self.pixels[(y * self.width + x) as usize] = v;
    }

    /// Reads a PNG or a JPEG, told apart by their first bytes (not by the file name). Only a
    /// regular file within `user_file::IMAGE_BYTES` is read, and only a picture within
    /// `user_file::MAX_SIDE` a side is decoded. Errors are one sentence starting with the path.
    pub fn load(path: &Path) -> Result<RgbaImage, String> {
        let shown = path.display();
        let bytes = user_file::read(path, user_file::IMAGE_BYTES)
            .map_err(|why| format!("{shown} {why}"))?;
        if bytes.starts_with(&PNG_SIGNATURE) {
            RgbaImage::decode_png(&bytes).map_err(|why| format!("{shown} {why}"))
        } else if bytes.starts_with(&JPEG_SIGNATURE) {
            RgbaImage::decode_jpeg(&bytes)
                .map_err(|e| format!("{shown} is not a readable JPEG: {e}"))
        } else {
            Err(format!("{shown} is not a readable PNG or JPEG image"))
        }
    }

    /// Decodes a baseline or progressive JPEG (colour or grey) to RGB with alpha 255.
    pub fn decode_jpeg(data: &[u8]) -> Result<RgbaImage, String> {
        // A few bytes can declare a huge picture: the size is checked from the header, before
        // any allocation (zune's own bound is lifted so that the message is ours).
        let options = DecoderOptions::default()
            .jpeg_set_out_colorspace(ColorSpace::RGBA)
            .set_max_width(usize::MAX)
            .set_max_height(usize::MAX);
        let mut decoder = JpegDecoder::new_with_options(ZCursor::new(data), options);
        decoder
            .decode_headers()
            .map_err(|e| format!("it does not decode ({e:?})"))?;
        let info = decoder.info().ok_or("it has no JPEG header")?;
        let (width, height) = (u32::from(info.width), u32::from(info.height));
        user_file::check_dimensions(width, height).map_err(|why| format!("it {why}"))?;
        let pixels = decoder
            .decode()
            .map_err(|e| format!("it does not decode ({e:?})"))?;
        if pixels.len() != width as usize * height as usize * 4 {
            return Err(format!(
                "it decoded to {} bytes for {width}x{height}",
                pixels.len()
            ));
        }
        let pixels = pixels
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], 255])
            .collect();
        Ok(RgbaImage {
            width,
            height,
            pixels,
            has_alpha: false,
        })
    }

    /// Reads a PNG file (a video folder's frame), with [`load`](Self::load)'s bounds.
    pub fn load_png(path: &Path) -> Result<RgbaImage, String> {
        let shown = path.display();
        let bytes = user_file::read(path, user_file::IMAGE_BYTES)
            .map_err(|why| format!("{shown} {why}"))?;
        RgbaImage::decode_png(&bytes).map_err(|why| format!("{shown} {why}"))
    }

    /// Decodes an 8-bit or 16-bit, RGB, RGBA, grey or palette PNG. The error says why, in words
    /// that follow the file's name ("declares 40000x40000 pixels, ...").
    fn decode_png(bytes: &[u8]) -> Result<RgbaImage, String> {
        let unreadable = |e: png::DecodingError| format!("is not a readable PNG: {e}");
        let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let header = decoder.read_header_info().map_err(unreadable)?;
        user_file::check_dimensions(header.width, header.height)?;
        // The decoder's own allocation bound, above the largest picture allowed (16-bit RGBA).
        let side = u64::from(user_file::MAX_SIDE);
        let most = usize::try_from(side * side * 8).unwrap_or(usize::MAX);
        decoder.set_limits(png::Limits { bytes: most });
        decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = decoder.read_info().map_err(unreadable)?;
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).map_err(unreadable)?;
        let data = &buf[..info.buffer_size()];
        let (pixels, has_alpha) = rgba_pixels(info.color_type, data)?;
        Ok(RgbaImage {
            width: info.width,
            height: info.height,
            pixels,
            has_alpha,
        })
    }

    /// Writes an 8-bit PNG: RGBA if the image has alpha, else RGB.
    pub fn save_png(&self, path: &Path) -> Result<(), String> {
        let file = std::fs::File::create(path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        self.write_png(std::io::BufWriter::new(file))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    /// The image as an 8-bit PNG file's bytes (see [`save_png`](Self::save_png)).
    pub fn encode_png(&self) -> Result<Vec<u8>, String> {
        let mut bytes = Vec::new();
        self.write_png(&mut bytes)
            .map_err(|e| format!("cannot encode a PNG: {e}"))?;
        Ok(bytes)
    }

    fn write_png(&self, out: impl std::io::Write) -> Result<(), png::EncodingError> {
        let mut encoder = png::Encoder::new(out, self.width, self.height);
        encoder.set_depth(png::BitDepth::Eight);
        let data: Vec<u8> = if self.has_alpha {
            encoder.set_color(png::ColorType::Rgba);
            self.pixels.iter().flatten().copied().collect()
        } else {
            encoder.set_color(png::ColorType::Rgb);
            self.pixels
                .iter()
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect()
        };
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&data)?;
        writer.finish()
    }
}

/// A decoded PNG's samples (after EXPAND and STRIP_16) as RGBA, and whether it had alpha.
fn rgba_pixels(color: png::ColorType, data: &[u8]) -> Result<(Vec<[u8; 4]>, bool), String> {
    Ok(match color {
        png::ColorType::Rgba => (
            data.chunks_exact(4)
                .map(|p| [p[0], p[1], p[2], p[3]])
                .collect(),
            true,
        ),
        png::ColorType::Rgb => (
            data.chunks_exact(3)
                .map(|p| [p[0], p[1], p[2], 255])
                .collect(),
            false,
        ),
        png::ColorType::GrayscaleAlpha => (
            data.chunks_exact(2)
                .map(|p| [p[0], p[0], p[0], p[1]])
                .collect(),
            true,
        ),
        png::ColorType::Grayscale => (data.iter().map(|&g| [g, g, g, 255]).collect(), false),
        png::ColorType::Indexed => return Err("is an unexpanded palette PNG".into()),
    })
}
