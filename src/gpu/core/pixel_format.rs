//! How the engine reads and writes a display region's raw pixels: the swapchain format's byte
//! layout and whether its values are sRGB-encoded (OpenXR: *_SRGB formats hold sRGB-encoded
//! values, UNORM and float formats hold linear light).

use super::interface::{self, FORMAT_SRGB_BIT};
use crate::algorithm::Stored;

/// Byte layout of one pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelLayout {
    Rgba8,
    Bgra8,
    Rgba16Unorm,
    Rgba16Float,
    A2b10g10r10,
}

impl PixelLayout {
    /// The shaders' LAYOUT_* code (src/gpu/core/interface.rs).
    pub fn shader_code(self) -> u32 {
        match self {
            PixelLayout::Rgba8 => interface::LAYOUT_RGBA8,
            PixelLayout::Bgra8 => interface::LAYOUT_BGRA8,
            PixelLayout::Rgba16Unorm => interface::LAYOUT_RGBA16_UNORM,
            PixelLayout::Rgba16Float => interface::LAYOUT_RGBA16_FLOAT,
            PixelLayout::A2b10g10r10 => interface::LAYOUT_A2B10G10R10,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelFormat {
    pub layout: PixelLayout,
    /// True when stored values are sRGB-encoded.
    pub srgb: bool,
}

impl PixelFormat {
    /// 8-bit sRGB RGBA: PNG files and the camera.
    pub const SRGB8: PixelFormat = PixelFormat {
        layout: PixelLayout::Rgba8,
        srgb: true,
    };

    pub fn bytes_per_pixel(self) -> u32 {
        match self.layout {
            PixelLayout::Rgba16Unorm | PixelLayout::Rgba16Float => 8,
            _ => 4,
        }
    }

    /// The format whose shader code (`FORMAT`) is `code`.
    pub fn from_shader_code(code: u32) -> Option<PixelFormat> {
        use PixelLayout::*;
        [Rgba8, Bgra8, Rgba16Unorm, Rgba16Float, A2b10g10r10]
            .into_iter()
            .flat_map(|layout| [true, false].map(|srgb| PixelFormat { layout, srgb }))
            .find(|f| f.shader_code() == code)
    }

    /// The code of the format a shader variant is built for (`FORMAT` in the shaders).
    pub fn shader_code(self) -> u32 {
        self.layout.shader_code() | if self.srgb { FORMAT_SRGB_BIT } else { 0 }
    }

    /// How the format stores an output colour, as the shaders' `quantised()` reads it back:
    /// what the CPU reference needs to judge it the same way.
    pub fn stored(self) -> Stored {
        match (self.layout, self.srgb) {
            (PixelLayout::Rgba8 | PixelLayout::Bgra8, true) => Stored::Srgb8,
            (PixelLayout::Rgba8 | PixelLayout::Bgra8, false) => Stored::Unorm(255),
            (PixelLayout::A2b10g10r10, _) => Stored::Unorm(1023),
            (PixelLayout::Rgba16Unorm, _) => Stored::Unorm(65535),
            (PixelLayout::Rgba16Float, _) => Stored::Exact,
        }
    }
}
