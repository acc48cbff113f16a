//! Swapchain formats the client can render, and how a colour is stored in each.
//!
//! sRGB formats hold sRGB-encoded values (the GPU decodes them when sampling); UNORM and float
//! formats hold linear light. Encoding is done here on the CPU, independently of the contrastxr
//! library, so the test patterns are an independent reference for the layer's tests.

use ash::vk;

/// One swapchain format the client knows how to fill.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SwapchainFormat {
    pub name: &'static str,
    pub vk: vk::Format,
}

/// Every format of the `--format` flag, by its Vulkan name without the `VK_FORMAT_` prefix.
pub const FORMATS: [SwapchainFormat; 7] = [
    SwapchainFormat {
        name: "R8G8B8A8_SRGB",
        vk: vk::Format::R8G8B8A8_SRGB,
    },
    SwapchainFormat {
        name: "B8G8R8A8_SRGB",
        vk: vk::Format::B8G8R8A8_SRGB,
    },
    SwapchainFormat {
        name: "R8G8B8A8_UNORM",
        vk: vk::Format::R8G8B8A8_UNORM,
    },
    SwapchainFormat {
        name: "B8G8R8A8_UNORM",
        vk: vk::Format::B8G8R8A8_UNORM,
    },
    SwapchainFormat {
        name: "R16G16B16A16_UNORM",
        vk: vk::Format::R16G16B16A16_UNORM,
    },
    SwapchainFormat {
        name: "R16G16B16A16_SFLOAT",
        vk: vk::Format::R16G16B16A16_SFLOAT,
    },
    SwapchainFormat {
        name: "A2B10G10R10_UNORM",
        vk: vk::Format::A2B10G10R10_UNORM_PACK32,
    },
];

impl SwapchainFormat {
    pub fn by_name(name: &str) -> Option<Self> {
        FORMATS
            .iter()
            .copied()
            .find(|f| f.name.eq_ignore_ascii_case(name))
    }

    pub fn by_vk(format: vk::Format) -> Option<Self> {
        FORMATS.iter().copied().find(|f| f.vk == format)
    }

    pub fn bytes_per_texel(self) -> usize {
        match self.vk {
            vk::Format::R16G16B16A16_UNORM | vk::Format::R16G16B16A16_SFLOAT => 8,
            _ => 4,
        }
    }

    fn is_srgb(self) -> bool {
        matches!(
            self.vk,
            vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_SRGB
        )
    }

    /// Appends one texel. `srgb` is the colour as sRGB-encoded RGBA in [0, 1]; alpha is linear.
    pub fn encode(self, srgb: [f32; 4], out: &mut Vec<u8>) {
        let [r, g, b, a] = if self.is_srgb() {
            srgb
        } else {
            [
                srgb_decode(srgb[0]),
                srgb_decode(srgb[1]),
                srgb_decode(srgb[2]),
                srgb[3],
            ]
        };
        match self.vk {
            vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM => {
                out.extend([b, g, r, a].map(|c| unorm(c, 8) as u8))
            }
            vk::Format::R16G16B16A16_UNORM => [r, g, b, a]
                .iter()
                .for_each(|&c| out.extend((unorm(c, 16) as u16).to_le_bytes())),
            vk::Format::R16G16B16A16_SFLOAT => [r, g, b, a]
                .iter()
                .for_each(|&c| out.extend(f16_bits(c).to_le_bytes())),
            vk::Format::A2B10G10R10_UNORM_PACK32 => {
                let packed =
                    unorm(a, 2) << 30 | unorm(b, 10) << 20 | unorm(g, 10) << 10 | unorm(r, 10);
                out.extend(packed.to_le_bytes())
            }
            _ => out.extend([r, g, b, a].map(|c| unorm(c, 8) as u8)),
        }
    }
}

/// The sRGB transfer function, encoded value -> linear light (IEC 61966-2-1).
pub fn srgb_decode(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Quantises `v` in [0, 1] to an unsigned normalised integer of `bits` bits, rounding to nearest.
fn unorm(v: f32, bits: u32) -> u32 {
    let max = ((1u64 << bits) - 1) as f32;
    (v.clamp(0.0, 1.0) * max).round() as u32
}

/// IEEE 754 binary16 bits of `v`, for `v` in [0, 1] (all the patterns need): round to nearest even.
fn f16_bits(v: f32) -> u16 {
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
    (half + round_up as u32) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encoded(name: &str, srgb: [f32; 4]) -> Vec<u8> {
        let mut out = Vec::new();
        SwapchainFormat::by_name(name)
            .unwrap()
            .encode(srgb, &mut out);
        out
    }

    #[test]
    fn f16_matches_known_bit_patterns() {
        // Values from the IEEE 754 binary16 tables.
        assert_eq!(f16_bits(1.0), 0x3c00);
        assert_eq!(f16_bits(0.5), 0x3800);
        assert_eq!(f16_bits(0.333_333_34), 0x3555);
        assert_eq!(f16_bits(6.103_515_6e-5), 0x0400); // smallest normal
        assert_eq!(f16_bits(5.960_464_5e-8), 0x0001); // smallest subnormal
    }

    #[test]
    fn srgb_formats_keep_encoded_values_and_unorm_formats_hold_linear_light() {
        assert_eq!(
            encoded("R8G8B8A8_SRGB", [0.5, 0.0, 1.0, 1.0]),
            [128, 0, 255, 255]
        );
        assert_eq!(
            encoded("B8G8R8A8_SRGB", [0.5, 0.0, 1.0, 1.0]),
            [255, 0, 128, 255]
        );
        // sRGB 0.5 is 0.2140 linear: 0.2140 * 255 = 54.6.
        assert_eq!(
            encoded("R8G8B8A8_UNORM", [0.5, 0.0, 1.0, 1.0]),
            [55, 0, 255, 255]
        );
        assert_eq!(
            encoded("B8G8R8A8_UNORM", [0.5, 0.0, 1.0, 1.0]),
            [255, 0, 55, 255]
        );
    }

    #[test]
    fn wide_formats_pack_as_vulkan_defines_them() {
        let r16 = encoded("R16G16B16A16_UNORM", [1.0, 0.0, 0.5, 1.0]);
        assert_eq!(r16, [0xff, 0xff, 0, 0, 0xcb, 0x36, 0xff, 0xff]); // 0.214041 * 65535 = 14027 = 0x36cb.
        let f16 = encoded("R16G16B16A16_SFLOAT", [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(f16, [0x00, 0x3c, 0, 0, 0, 0, 0x00, 0x3c]);
        // A2B10G10R10: red in the low 10 bits, alpha in the top 2.
        assert_eq!(
            encoded("A2B10G10R10_UNORM", [1.0, 0.0, 0.0, 1.0]),
            0xc000_03ffu32.to_le_bytes()
        );
        assert_eq!(
            encoded("A2B10G10R10_UNORM", [0.0, 0.0, 1.0, 0.0]),
            0x3ff0_0000u32.to_le_bytes()
        );
    }
}
