//! `--content image:PATH`: a PNG the client shows in every view instead of its own pattern, so a
//! real frame (UI panels and text on black, as `samples/display-*.png`) goes through the layer
//! as an app's would. Decoded here with the `png` crate, independently of the contrastxr library.

use std::io::Read;
use std::path::Path;

/// The largest side the client accepts, in pixels.
const MAX_SIDE: u32 = 8192;

/// A decoded picture: 8-bit sRGB-encoded RGBA, rows top first.
#[derive(Debug, PartialEq)]
pub struct Picture {
    width: u32,
    height: u32,
    pixels: Vec<[u8; 4]>,
}

impl Picture {
    pub fn load(path: &Path) -> Result<Picture, String> {
        let file = std::fs::File::open(path)
            .map_err(|e| format!("cannot open the image {}: {e}", path.display()))?;
        Picture::decode(std::io::BufReader::new(file))
            .map_err(|e| format!("cannot read the image {} as a PNG: {e}", path.display()))
    }

    /// Any PNG colour type and bit depth, as 8-bit RGBA (grey and palette expanded, 16-bit
    /// channels cut to 8, alpha 255 where the PNG has none).
    pub fn decode(bytes: impl Read) -> Result<Picture, String> {
        let mut decoder = png::Decoder::new(bytes);
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
        let (width, height) = (reader.info().width, reader.info().height);
        if width > MAX_SIDE || height > MAX_SIDE {
            return Err(format!(
                "{width}x{height} is larger than {MAX_SIDE}x{MAX_SIDE}"
            ));
        }
        let mut buf = vec![0; reader.output_buffer_size()];
        let frame = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
        let channels = match reader.output_color_type().0 {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            png::ColorType::Indexed => return Err("an indexed image was not expanded".into()),
        };
        let pixels = buf[..frame.buffer_size()]
            .chunks_exact(frame.line_size)
            .flat_map(|row| row[..width as usize * channels].chunks_exact(channels))
            .map(|p| match *p {
                [g] => [g, g, g, 255],
                [g, a] => [g, g, g, a],
                [r, g, b] => [r, g, b, 255],
                [r, g, b, a] => [r, g, b, a],
                _ => unreachable!("chunks of 1 to 4 bytes"),
            })
            .collect();
        Ok(Picture {
            width,
            height,
            pixels,
        })
    }

    /// The picture stretched over a view: the colour at (u, v), fractions of the view from its
    /// top left, of the nearest texel, as sRGB-encoded RGBA in [0, 1]; None outside [0, 1).
    pub fn at(&self, u: f32, v: f32) -> Option<[f32; 4]> {
        if !(0.0..1.0).contains(&u) || !(0.0..1.0).contains(&v) {
            return None;
        }
        let x = ((u * self.width as f32) as u32).min(self.width - 1);
        let y = ((v * self.height as f32) as u32).min(self.height - 1);
        let p = self.pixels[(y * self.width + x) as usize];
        Some(p.map(|c| f32::from(c) / 255.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(width: u32, height: u32, colour: png::ColorType, data: &[u8]) -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(colour);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(data).unwrap();
        writer.finish().unwrap();
        bytes
    }

    #[test]
    fn an_rgb_picture_is_stretched_over_the_view_nearest_texel_first() {
        // 2x1: red, then green.
        let bytes = png(2, 1, png::ColorType::Rgb, &[255, 0, 0, 0, 255, 0]);
        let picture = Picture::decode(&bytes[..]).unwrap();
        assert_eq!(picture.at(0.1, 0.5), Some([1.0, 0.0, 0.0, 1.0]));
        assert_eq!(picture.at(0.49, 0.99), Some([1.0, 0.0, 0.0, 1.0]));
        assert_eq!(picture.at(0.5, 0.0), Some([0.0, 1.0, 0.0, 1.0]));
        assert_eq!(picture.at(-0.01, 0.5), None);
        assert_eq!(picture.at(1.0, 0.5), None);
    }

    #[test]
    fn grey_and_alpha_become_rgba() {
        let bytes = png(1, 2, png::ColorType::GrayscaleAlpha, &[51, 0, 255, 255]);
        let picture = Picture::decode(&bytes[..]).unwrap();
        assert_eq!(picture.at(0.5, 0.25), Some([0.2, 0.2, 0.2, 0.0]));
        assert_eq!(picture.at(0.5, 0.75), Some([1.0, 1.0, 1.0, 1.0]));
    }

    #[test]
    fn what_is_not_a_png_is_refused() {
        assert!(Picture::decode(&b"not a png"[..]).is_err());
        assert!(Picture::load(Path::new("/nonexistent/picture.png"))
            .unwrap_err()
            .contains("/nonexistent/picture.png"));
    }
}
