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
            // In usize: in u32 the product wraps (65536 x 65536 is 0), a buffer too small.
            pixels: vec![fill; width as usize * height as usize],
            has_alpha: true,
        }
    }

    pub fn get(&self, x: u32, y: u32) -> [u8; 4] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    pub fn set(&mut self, x: u32, y: u32, v: [u8; 4]) {
        self.pixels[y as usize * self.width as usize + x as usize] = v;
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

    /// [`load`](Self::load), shrunk to at most `most` (width, height) where it is larger: each
    /// side on its own, each pixel the area average of the pixels it covers, in linear light.
    /// A non-interlaced PNG is shrunk row by row as it decodes, so only the file's bytes and
    /// the shrunk picture are ever held; a JPEG (decoded whole, then shrunk from its decoded
    /// bytes) or an interlaced PNG also holds the decoded picture meanwhile.
    pub fn load_within(path: &Path, most: (u32, u32)) -> Result<RgbaImage, String> {
        let shown = path.display();
        let bytes = user_file::read(path, user_file::IMAGE_BYTES)
            .map_err(|why| format!("{shown} {why}"))?;
        if bytes.starts_with(&PNG_SIGNATURE) {
            decode_png_within(&bytes, most).map_err(|why| format!("{shown} {why}"))
        } else if bytes.starts_with(&JPEG_SIGNATURE) {
            decode_jpeg_within(&bytes, most)
                .map_err(|e| format!("{shown} is not a readable JPEG: {e}"))
        } else {
            Err(format!("{shown} is not a readable PNG or JPEG image"))
        }
    }

    /// The image shrunk to at most `most` (see [`load_within`](Self::load_within)); itself
    /// when it is not larger.
    pub fn shrunk(self, most: (u32, u32)) -> RgbaImage {
        let mut shrink = Shrink::new((self.width, self.height), most, self.has_alpha, Vec::new());
        if shrink.size() == (self.width, self.height) {
            return self;
        }
        for row in self.pixels.chunks_exact(self.width as usize) {
            shrink.row(row);
        }
        shrink.finish()
    }

    /// Decodes a baseline or progressive JPEG (colour or grey) to RGB with alpha 255.
    pub fn decode_jpeg(data: &[u8]) -> Result<RgbaImage, String> {
        let (width, height, pixels) = jpeg_rgba(data)?;
        let pixels = opaque(&pixels).collect();
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
        decoder.set_limits(png_limits());
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

    /// Writes an 8-bit PNG: RGBA if the image has alpha, else RGB. As a capture is written
    /// (`user_file::write_replacing`): a link or FIFO at `path` (a planted name in a shared
    /// folder the command line writes frames to) is replaced, never written through or waited
    /// on.
    pub fn save_png(&self, path: &Path) -> Result<(), String> {
        let bytes = self.encode_png()?;
        crate::user_file::write_replacing(path, &bytes)
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

/// A JPEG's size and RGBA bytes (alpha as decoded: the caller sets it). A few bytes can
/// declare a huge picture: the size is checked from the header, before any allocation (zune's
/// own bound is lifted so that the message is ours).
fn jpeg_rgba(data: &[u8]) -> Result<(u32, u32, Vec<u8>), String> {
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
    Ok((width, height, pixels))
}

/// A JPEG decoded whole, then shrunk from its decoded bytes (no second copy of the picture).
fn decode_jpeg_within(bytes: &[u8], most: (u32, u32)) -> Result<RgbaImage, String> {
    let (width, height, pixels) = jpeg_rgba(bytes)?;
    let mut shrink = Shrink::new((width, height), most, false, Vec::new());
    if shrink.size() == (width, height) {
        let pixels = opaque(&pixels).collect();
        return Ok(RgbaImage {
            width,
            height,
            pixels,
            has_alpha: false,
        });
    }
    let mut row = Vec::with_capacity(width as usize);
    for line in pixels.chunks_exact(4 * width as usize) {
        row.clear();
        row.extend(opaque(line));
        shrink.row(&row);
    }
    Ok(shrink.finish())
}

/// The PNG decoder's own allocation bound, above the largest picture allowed (16-bit RGBA).
fn png_limits() -> png::Limits {
    let side = u64::from(user_file::MAX_SIDE);
    let bytes = usize::try_from(side * side * 8).unwrap_or(usize::MAX);
    png::Limits { bytes }
}

/// A PNG decoded row by row into a [`Shrink`]; an interlaced one decoded whole, then shrunk.
fn decode_png_within(bytes: &[u8], most: (u32, u32)) -> Result<RgbaImage, String> {
    let unreadable = |e: png::DecodingError| format!("is not a readable PNG: {e}");
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let header = decoder.read_header_info().map_err(unreadable)?;
    user_file::check_dimensions(header.width, header.height)?;
    if header.interlaced {
        return RgbaImage::decode_png(bytes).map(|image| image.shrunk(most));
    }
    decoder.set_limits(png_limits());
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(unreadable)?;
    let (color, _) = reader.output_color_type();
    let (width, height) = (reader.info().width, reader.info().height);
    let has_alpha = matches!(color, png::ColorType::Rgba | png::ColorType::GrayscaleAlpha);
    let mut shrink = Shrink::new((width, height), most, has_alpha, Vec::new());
    let mut rows = 0;
    while let Some(row) = reader.next_row().map_err(unreadable)? {
        let (pixels, _) = rgba_pixels(color, row.data())?;
        if pixels.len() != width as usize {
            return Err(format!("has a row of {} pixels, not {width}", pixels.len()));
        }
        shrink.row(&pixels);
        rows += 1;
    }
    if rows != height {
        return Err(format!(
            "is not a readable PNG: {rows} of its {height} rows"
        ));
    }
    Ok(shrink.finish())
}

/// Shrinks a picture fed row by row, top first: each side on its own to at most the wanted
/// size, each output pixel the area average (in linear light, alpha as is) of the input pixels
/// it covers. Positions are counted in units of 1 / (input size x output size) along each
/// side, so the weights are exact integers.
pub(crate) struct Shrink {
    from: (u32, u32),
    to: (u32, u32),
    has_alpha: bool,
    linear: [f32; 256],
    /// Input column x's share of output columns: (column, weight) twice, weights in units.
    columns: Vec<[(u32, u32); 2]>,
    /// Sums of the output row being made and of the next (an input row may straddle them).
    sums: [Vec<f32>; 2],
    /// Input rows taken, output rows made.
    taken: u32,
    pixels: Vec<[u8; 4]>,
    /// The input row, spread over the output columns.
    spread: Vec<f32>,
}

/// An input pixel's share of the output pixels along one side: input pixel `i` of `from`
/// covers units [i * to, (i + 1) * to); output pixel `o` covers [o * from, (o + 1) * from).
fn share(i: u32, from: u32, to: u32) -> [(u32, u32); 2] {
    let (a, b) = (
        u64::from(i) * u64::from(to),
        u64::from(i + 1) * u64::from(to),
    );
    let o = a / u64::from(from);
    let edge = (o + 1) * u64::from(from);
    if b <= edge {
        [(o as u32, (b - a) as u32), (o as u32, 0)]
    } else {
        [
            (o as u32, (edge - a) as u32),
            (o as u32 + 1, (b - edge) as u32),
        ]
    }
}

impl Shrink {
    /// The picture is made in `pixels`' memory when it is large enough (a pooled frame's: a
    /// video's frames are then not each a new allocation).
    pub(crate) fn new(
        from: (u32, u32),
        most: (u32, u32),
        has_alpha: bool,
        mut pixels: Vec<[u8; 4]>,
    ) -> Shrink {
        let to = (from.0.min(most.0.max(1)), from.1.min(most.1.max(1)));
        pixels.clear();
        pixels.reserve_exact(to.0 as usize * to.1 as usize);
        let columns = (0..from.0).map(|x| share(x, from.0, to.0)).collect();
        Shrink {
            from,
            to,
            has_alpha,
            linear: std::array::from_fn(|c| crate::colour::code_to_linear(c as u8) as f32),
            columns,
            sums: [vec![0.0; 4 * to.0 as usize], vec![0.0; 4 * to.0 as usize]],
            taken: 0,
            pixels,
            spread: vec![0.0; 4 * to.0 as usize],
        }
    }

    fn size(&self) -> (u32, u32) {
        self.to
    }

    /// Takes the next input row (`from.0` pixels).
    pub(crate) fn row(&mut self, row: &[[u8; 4]]) {
        if self.taken >= self.from.1 {
            return;
        }
        self.spread.fill(0.0);
        for (p, shares) in row.iter().zip(&self.columns) {
            let c = [
                self.linear[p[0] as usize],
                self.linear[p[1] as usize],
                self.linear[p[2] as usize],
                f32::from(p[3]) / 255.0,
            ];
            for &(o, w) in shares.iter().filter(|(_, w)| *w > 0) {
                let at = 4 * o as usize;
                for (s, v) in self.spread[at..at + 4].iter_mut().zip(c) {
                    *s += v * w as f32;
                }
            }
        }
        let [(first, w0), (_, w1)] = share(self.taken, self.from.1, self.to.1);
        let made = self.pixels.len() as u32 / self.to.0.max(1);
        // `first` is the output row being made or, for the first input row of a new one, the
        // next: the sums in slot 0 are the row being made.
        debug_assert!(first == made);
        for (s, v) in self.sums[0].iter_mut().zip(&self.spread) {
            *s += v * w0 as f32;
        }
        for (s, v) in self.sums[1].iter_mut().zip(&self.spread) {
            *s += v * w1 as f32;
        }
        self.taken += 1;
        // The row being made is complete when this input row reached its lower edge.
        let end = u64::from(self.taken) * u64::from(self.to.1);
        if end >= u64::from(first + 1) * u64::from(self.from.1) {
            self.emit();
        }
    }

    /// Writes out the row being made and moves the next one up.
    fn emit(&mut self) {
        // Each output pixel covers from.0 x from.1 units of unit weight: the sums' divisor.
        let area = self.from.0 as f32 * self.from.1 as f32;
        for px in self.sums[0].as_chunks::<4>().0 {
            let code = |v: f32| {
                crate::colour::quantize(crate::colour::srgb_encode(
                    f64::from(v / area).clamp(0.0, 1.0),
                ))
            };
            let alpha = crate::colour::quantize(f64::from(px[3] / area).clamp(0.0, 1.0));
            self.pixels
                .push([code(px[0]), code(px[1]), code(px[2]), alpha]);
        }
        self.sums.swap(0, 1);
        self.sums[1].fill(0.0);
    }

    pub(crate) fn finish(self) -> RgbaImage {
        RgbaImage {
            width: self.to.0,
            height: self.to.1,
            pixels: self.pixels,
            has_alpha: self.has_alpha,
        }
    }
}

/// The whole N-byte pixels of `data`, in order (a trailing part of a pixel is left out).
fn groups<const N: usize>(data: &[u8]) -> std::slice::Iter<'_, [u8; N]> {
    data.as_chunks::<N>().0.iter()
}

/// `jpeg_rgba`'s samples as pixels with alpha 255 (JPEG has no alpha).
fn opaque(samples: &[u8]) -> impl Iterator<Item = [u8; 4]> + '_ {
    groups::<4>(samples).map(|p| [p[0], p[1], p[2], 255])
}

/// A decoded PNG's samples (after EXPAND and STRIP_16) as RGBA, and whether it had alpha.
fn rgba_pixels(color: png::ColorType, data: &[u8]) -> Result<(Vec<[u8; 4]>, bool), String> {
    Ok(match color {
        png::ColorType::Rgba => (data.as_chunks::<4>().0.to_vec(), true),
        png::ColorType::Rgb => (
            groups::<3>(data).map(|p| [p[0], p[1], p[2], 255]).collect(),
            false,
        ),
        png::ColorType::GrayscaleAlpha => (
            groups::<2>(data)
                .map(|p| [p[0], p[0], p[0], p[1]])
                .collect(),
            true,
        ),
        png::ColorType::Grayscale => (data.iter().map(|&g| [g, g, g, 255]).collect(), false),
        png::ColorType::Indexed => return Err("is an unexpanded palette PNG".into()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(w: u32, h: u32) -> RgbaImage {
        let mut img = RgbaImage::new(w, h, [0; 4]);
        img.has_alpha = false;
        for y in 0..h {
            for x in 0..w {
                img.set(
                    x,
                    y,
                    [
                        (x * 7 % 256) as u8,
                        (y * 5 % 256) as u8,
                        ((x + y) % 256) as u8,
                        255,
                    ],
                );
            }
        }
        img
    }

    #[test]
    fn shrinking_averages_the_covered_pixels_in_linear_light() {
        let mut img = RgbaImage::new(4, 2, [0, 0, 0, 255]);
        for x in [1, 3] {
            img.set(x, 0, [255, 255, 255, 255]);
            img.set(x, 1, [255, 255, 255, 255]);
        }
        let small = img.shrunk((2, 1));
        assert_eq!((small.width, small.height), (2, 1));
        // Half black, half white in linear light: 0.5 linear is code 188.
        assert_eq!(small.pixels, vec![[188, 188, 188, 255]; 2]);
        // 3 -> 2 columns: the middle pixel is shared; a flat picture stays flat.
        let flat = RgbaImage::new(3, 5, [90, 120, 30, 200]).shrunk((2, 2));
        assert_eq!((flat.width, flat.height), (2, 2));
        assert!(
            flat.pixels.iter().all(|p| *p == [90, 120, 30, 200]),
            "{:?}",
            flat.pixels
        );
        // Not larger than the bound: unchanged.
        let same = scene(5, 3);
        assert_eq!(same.clone().shrunk((640, 480)), same);
    }

    #[test]
    fn a_png_shrinks_row_by_row_as_it_would_whole() {
        let dir = crate::scratch::ScratchDir::new("image");
        let path = dir.join("scene.png");
        let img = scene(301, 207);
        img.save_png(&path).unwrap();
        let streamed = RgbaImage::load_within(&path, (64, 48)).unwrap();
        assert_eq!((streamed.width, streamed.height), (64, 48));
        assert_eq!(streamed, img.clone().shrunk((64, 48)));
        assert_eq!(RgbaImage::load_within(&path, (640, 480)).unwrap(), img);
        // A JPEG is shrunk from its decoded bytes as its decoded picture would be.
        let jpeg = dir.join("scene.jpg");
        let rgb: Vec<u8> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        jpeg_encoder::Encoder::new_file(&jpeg, 90)
            .unwrap()
            .encode(&rgb, 301, 207, jpeg_encoder::ColorType::Rgb)
            .unwrap();
        let whole = RgbaImage::load(&jpeg).unwrap();
        let shrunk = RgbaImage::load_within(&jpeg, (64, 48)).unwrap();
        assert_eq!(shrunk, whole.clone().shrunk((64, 48)));
        assert_eq!(RgbaImage::load_within(&jpeg, (640, 480)).unwrap(), whole);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
