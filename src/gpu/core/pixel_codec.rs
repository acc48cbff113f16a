//! One pixel of a swapchain format on the CPU: its stored channel values (in the format's own
//! encoding: sRGB-encoded for *_SRGB formats, linear light otherwise) to bytes and back. Used
//! where the layer reads or writes the app's pixels outside the shaders (captures, the
//! indicator's overlay); the shaders' side is shaders/enhance.wgsl. The project's XR test client
//! keeps an encoder of its own, so that its checks of the layer stay independent of this one.

use super::pixel_format::{PixelFormat, PixelLayout};
use crate::image::RgbaImage;

/// IEEE 754 binary16 bits of `v` in [0, 1] (what colour channels need), rounded to nearest even.
pub fn half_from_f32(v: f32) -> u16 {
    let v = v.clamp(0.0, 1.0);
    if v == 0.0 {
        return 0;
    }
    let bits = v.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    if exp <= 0 {
        // Subnormal half: value = mantissa * 2^-24.
        return (v * (1 << 24) as f32).round_ties_even() as u16;
    }
    let mantissa = bits & 0x7f_ffff;
    let half = ((exp as u32) << 10) | (mantissa >> 13);
    let rest = mantissa & 0x1fff;
    // Rounding may carry into the exponent, which is still the correctly rounded result.
    let round_up = rest > 0x1000 || (rest == 0x1000 && half & 1 == 1);
    (half + u32::from(round_up)) as u16
}

/// The value of IEEE 754 binary16 bits.
pub fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f32::from(h & 0x3ff);
    match exp {
        0 => sign * frac * 2f32.powi(-24),
        31 => sign * f32::INFINITY,
        e => sign * (1.0 + frac / 1024.0) * 2f32.powi(e - 15),
    }
}

/// One raw pixel as (r, g, b, a) channel values in [0, 1], in the format's own encoding.
pub fn decode(format: PixelFormat, px: &[u8]) -> [f32; 4] {
    let word = |i: usize| u32::from_le_bytes([px[i], px[i + 1], px[i + 2], px[i + 3]]);
    let u16_at = |k: usize| u16::from_le_bytes([px[2 * k], px[2 * k + 1]]);
    match format.layout {
        PixelLayout::Rgba8 => [px[0], px[1], px[2], px[3]].map(|b| f32::from(b) / 255.0),
        PixelLayout::Bgra8 => [px[2], px[1], px[0], px[3]].map(|b| f32::from(b) / 255.0),
        PixelLayout::A2b10g10r10 => {
            let w = word(0);
            let c = |s: u32| ((w >> s) & 1023) as f32 / 1023.0;
            [c(0), c(10), c(20), (w >> 30) as f32 / 3.0]
        }
        PixelLayout::Rgba16Unorm => std::array::from_fn(|k| f32::from(u16_at(k)) / 65535.0),
        PixelLayout::Rgba16Float => std::array::from_fn(|k| half_to_f32(u16_at(k))),
    }
}

/// One pixel's bytes from (r, g, b, a) channel values in [0, 1] in the format's own encoding,
/// each rounded to the nearest code.
pub fn encode(format: PixelFormat, [r, g, b, a]: [f64; 4]) -> Vec<u8> {
    let unorm = |v: f64, max: f64| (v.clamp(0.0, 1.0) * max).round() as u32;
    match format.layout {
        PixelLayout::Rgba8 => [r, g, b, a].map(|v| unorm(v, 255.0) as u8).to_vec(),
        PixelLayout::Bgra8 => [b, g, r, a].map(|v| unorm(v, 255.0) as u8).to_vec(),
        PixelLayout::Rgba16Unorm => [r, g, b, a]
            .iter()
            .flat_map(|&v| (unorm(v, 65535.0) as u16).to_le_bytes())
            .collect(),
        PixelLayout::Rgba16Float => [r, g, b, a]
            .iter()
            .flat_map(|&v| half_from_f32(v as f32).to_le_bytes())
            .collect(),
        PixelLayout::A2b10g10r10 => {
            let word = unorm(r, 1023.0)
                | unorm(g, 1023.0) << 10
                | unorm(b, 1023.0) << 20
                | unorm(a, 3.0) << 30;
            word.to_le_bytes().to_vec()
        }
    }
}

/// An 8-bit sRGB image's pixels as raw words of `PixelFormat::SRGB8`, one per pixel.
pub fn srgb8_words(image: &RgbaImage) -> Vec<u32> {
    image
        .pixels
        .iter()
        .map(|p| u32::from_le_bytes(*p))
        .collect()
}

/// `like` with its pixels replaced by raw words of `PixelFormat::SRGB8`.
pub fn srgb8_image(like: &RgbaImage, words: &[u32]) -> RgbaImage {
    RgbaImage {
        pixels: words.iter().map(|w| w.to_le_bytes()).collect(),
        ..like.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_match_known_bit_patterns() {
        // Values from the IEEE 754 binary16 tables.
        assert_eq!(half_from_f32(1.0), 0x3c00);
        assert_eq!(half_from_f32(0.5), 0x3800);
        assert_eq!(half_from_f32(0.333_333_34), 0x3555);
        assert_eq!(half_from_f32(6.103_515_6e-5), 0x0400);
        assert_eq!(half_from_f32(5.960_464_5e-8), 0x0001);
        assert_eq!(half_to_f32(0x3555), 0.333_251_95);
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0x0000), 0.0);
        assert_eq!(half_to_f32(0x0001), 5.960_464_5e-8);
    }

    /// Every code of every layout survives encode then decode.
    #[test]
    fn encode_then_decode_gives_the_values_back() {
        let layouts = [
            PixelLayout::Rgba8,
            PixelLayout::Bgra8,
            PixelLayout::Rgba16Unorm,
            PixelLayout::Rgba16Float,
            PixelLayout::A2b10g10r10,
        ];
        for layout in layouts {
            let format = PixelFormat {
                layout,
                srgb: false,
            };
            let c = [0.25, 0.5, 1.0, 1.0];
            let back = decode(format, &encode(format, c));
            for (v, w) in c.iter().zip(back) {
                assert!(
                    (v - f64::from(w)).abs() < 2e-3,
                    "{layout:?}: {c:?} -> {back:?}"
                );
            }
            assert_eq!(encode(format, c).len() as u32, format.bytes_per_pixel());
        }
        let bgra = PixelFormat {
            layout: PixelLayout::Bgra8,
            srgb: true,
        };
        assert_eq!(encode(bgra, [1.0, 0.0, 0.0, 1.0]), [0, 0, 255, 255]);
    }
}
