//! Lit pixels drawn over the enhanced views (the layer's in-headset indicator): one colour,
//! given as horizontal runs per view, each backend writing them in the view's pixel format over
//! what the enhancement made. The other pixels are left as they are.

use super::pixel_codec;
use super::pixel_format::PixelFormat;
use crate::colour;

/// One horizontal run of lit pixels: region coordinates, length in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    pub x: u32,
    pub y: u32,
    pub len: u32,
}

/// What to draw this frame: `key` names the drawing (a changed key redraws), `runs` gives
/// the lit pixels for a region size, `colour` is sRGB-encoded.
pub struct OverlayPixels<'a> {
    pub key: &'a str,
    pub colour: [u8; 4],
    pub runs: &'a dyn Fn((u32, u32)) -> Vec<Run>,
}

/// One pixel of an sRGB-encoded colour in the view's format (linear formats hold linear light).
pub fn encode(format: PixelFormat, [r, g, b, a]: [u8; 4]) -> Vec<u8> {
    let code = |c: u8| f64::from(c) / 255.0;
    let stored = |c: u8| match format.srgb {
        true => code(c),
        false => colour::srgb_decode(code(c)),
    };
    pixel_codec::encode(format, [stored(r), stored(g), stored(b), code(a)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::core::PixelLayout;

    #[test]
    fn the_colour_in_every_format() {
        let f = |layout, srgb| PixelFormat { layout, srgb };
        assert_eq!(
            encode(f(PixelLayout::Rgba8, true), [64, 255, 64, 255]),
            [64, 255, 64, 255]
        );
        assert_eq!(
            encode(f(PixelLayout::Bgra8, true), [64, 255, 64, 255]),
            [64, 255, 64, 255]
        );
        // sRGB 64 is linear 0.0513 (IEC 61966-2-1): 13 of 255.
        assert_eq!(
            encode(f(PixelLayout::Rgba8, false), [64, 255, 0, 255]),
            [13, 255, 0, 255]
        );
        assert_eq!(
            encode(f(PixelLayout::Bgra8, false), [64, 255, 0, 255]),
            [0, 255, 13, 255]
        );
        let unorm16 = encode(f(PixelLayout::Rgba16Unorm, false), [255, 0, 255, 255]);
        assert_eq!(unorm16, [255, 255, 0, 0, 255, 255, 255, 255]);
        // Half floats: 1.0 = 0x3c00, 0 = 0.
        let float16 = encode(f(PixelLayout::Rgba16Float, false), [255, 0, 255, 255]);
        assert_eq!(float16, [0x00, 0x3c, 0, 0, 0x00, 0x3c, 0x00, 0x3c]);
        assert_eq!(pixel_codec::half_from_f32(0.5), 0x3800);
        assert_eq!(pixel_codec::half_from_f32(0.0513), 0x2a91);
        let packed = encode(f(PixelLayout::A2b10g10r10, false), [255, 0, 255, 255]);
        assert_eq!(u32::from_le_bytes(packed.try_into().unwrap()), 0xFFF0_03FF);
    }
}
