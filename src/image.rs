//! 8-bit RGBA images: PNG and JPEG input, PNG output. Pixels are sRGB-encoded code values.

use std::path::Path;
use zune_jpeg::zune_core::bytestream::ZCursor;
use zune_jpeg::zune_core::colorspace::ColorSpace;
use zune_jpeg::zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

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

/// The largest JPEG width or height decoded (camera frames and background images are far
/// smaller; 8192x8192 RGBA is 256 MiB).
const MAX_JPEG_SIDE: usize = 8192;

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

    /// Reads a PNG or a JPEG, told apart by their first bytes (not by the file name).
    pub fn load(path: &Path) -> Result<RgbaImage, String> {
        let bytes =
            std::fs::read(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
        if bytes.starts_with(&PNG_SIGNATURE) {
            RgbaImage::load_png(path)
        } else if bytes.starts_with(&JPEG_SIGNATURE) {
            RgbaImage::decode_jpeg(&bytes)
                .map_err(|e| format!("{} is not a readable JPEG: {e}", path.display()))
        } else {
            Err(format!(
                "{} is not a readable PNG or JPEG image",
                path.display()
            ))
        }
    }

    /// Decodes a baseline or progressive JPEG (colour or grey) to RGB with alpha 255.
    pub fn decode_jpeg(data: &[u8]) -> Result<RgbaImage, String> {
        // A few bytes can declare a huge picture: the size is bounded before any allocation.
        let options = DecoderOptions::default()
            .jpeg_set_out_colorspace(ColorSpace::RGBA)
            .set_max_width(MAX_JPEG_SIDE)
            .set_max_height(MAX_JPEG_SIDE);
        let mut decoder = JpegDecoder::new_with_options(ZCursor::new(data), options);
        let pixels = decoder
            .decode()
            .map_err(|e| format!("it does not decode ({e:?})"))?;
        let info = decoder.info().ok_or("it has no JPEG header")?;
        let (width, height) = (u32::from(info.width), u32::from(info.height));
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

    /// Reads an 8-bit or 16-bit, RGB, RGBA, grey or palette PNG.
    pub fn load_png(path: &Path) -> Result<RgbaImage, String> {
        let file = std::fs::File::open(path)
            .map_err(|e| format!("cannot open {}: {e}", path.display()))?;
        let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
        decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = decoder
            .read_info()
            .map_err(|e| format!("{} is not a readable PNG: {e}", path.display()))?;
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| format!("{} is not a readable PNG: {e}", path.display()))?;
        let data = &buf[..info.buffer_size()];
        let (w, h) = (info.width, info.height);
        let (pixels, has_alpha): (Vec<[u8; 4]>, bool) = match info.color_type {
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
            png::ColorType::Indexed => {
                return Err(format!("{}: unexpanded palette PNG", path.display()))
            }
        };
        Ok(RgbaImage {
            width: w,
            height: h,
            pixels,
            has_alpha,
        })
    }

    /// Writes an 8-bit PNG: RGBA if the image has alpha, else RGB.
    pub fn save_png(&self, path: &Path) -> Result<(), String> {
        let file = std::fs::File::create(path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), self.width, self.height);
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
        let mut writer = encoder
            .write_header()
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        writer
            .write_image_data(&data)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    }
}
