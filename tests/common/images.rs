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
