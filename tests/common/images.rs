//! Test images.

use contrastxr::image::RgbaImage;

/// A deterministic pseudo-random image (xorshift), with some black and alpha-0 pixels.
pub fn noise(width: u32, height: u32, seed: u32) -> RgbaImage {
    let mut s = seed.max(1);
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s
    };
    let mut img = RgbaImage::new(width, height, [0, 0, 0, 255]);
    for p in img.pixels.iter_mut() {
        let r = next();
        *p = match r % 10 {
            0 => [0, 0, 0, 255],
            1 => [(r >> 8) as u8, (r >> 16) as u8, (r >> 24) as u8, 0],
            _ => [(r >> 8) as u8, (r >> 16) as u8, (r >> 24) as u8, 255],
        };
    }
    img
}

/// `noise` with one content pixel per 8x8 tile (the engine's TILE) and every other pixel
/// transparent black; tile k's pixel lies at column 3k mod 8 and row k mod 8 of its tile, so
/// the pixels fall in every row and column of the tiles.
pub fn one_pixel_per_tile(width: u32, height: u32, seed: u32) -> RgbaImage {
    let source = noise(width, height, seed);
    let mut img = RgbaImage::new(width, height, [0, 0, 0, 0]);
    let columns = width.div_ceil(8);
    for k in 0..columns * height.div_ceil(8) {
        let x = (k % columns) * 8 + (3 * k) % 8;
        let y = (k / columns) * 8 + k % 8;
        if x < width && y < height {
            let i = (y * width + x) as usize;
            let [r, g, b, _] = source.pixels[i];
            // Opaque and never black: content, whatever the noise gave.
            img.pixels[i] = [r | 1, g, b, 255];
        }
    }
    img
}

/// Every other content pixel (alpha 255) of `img` made one dim primary, codes 3 to 14 of R, G or
/// B in turn: low luminance, where the perceptual model's luminance bands differ most.
pub fn darken_every_other(img: &mut RgbaImage) {
    let content = img.pixels.iter_mut().filter(|p| p[3] == 255);
    for (j, p) in content.step_by(2).enumerate() {
        let mut dim = [0, 0, 0, 255];
        dim[j % 3] = 3 + (j / 3 % 12) as u8;
        *p = dim;
    }
}
