//! Vulkan's names for the engine's neutral types: pixel formats to and from `vk::Format`.

use crate::gpu::core::interface;
use crate::gpu::core::{PixelFormat, PixelLayout};
use ash::vk;

/// A pixel format as Vulkan knows it.
pub trait VkFormat: Sized {
    /// The engine's reading of a Vulkan colour format; None for formats it does not handle
    /// (depth, compressed, ...), which the layer then leaves untouched.
    fn from_vk(format: vk::Format) -> Option<Self>;
    /// The format of the storage view a region of this format is enhanced in place through
    /// (interface.rs `in_place_texel`: UNORM for the sRGB formats); None where it is not.
    fn in_place_view_format(self) -> Option<vk::Format>;
    /// The format of the layer's own image a region of this format is copied into (raw bytes,
    /// vkCmdCopyImage between size-compatible formats) and enhanced in by the in-place shaders
    /// when the app's image cannot be stored to (the image-copy path): the storage texel format
    /// of its in-place variants (interface.rs `in_place_texel`). None where it has none.
    fn image_copy_format(self) -> Option<vk::Format>;
}

impl VkFormat for PixelFormat {
    fn from_vk(format: vk::Format) -> Option<Self> {
        use PixelLayout::*;
        let (layout, srgb) = match format {
            vk::Format::R8G8B8A8_SRGB => (Rgba8, true),
            vk::Format::R8G8B8A8_UNORM => (Rgba8, false),
            vk::Format::B8G8R8A8_SRGB => (Bgra8, true),
            vk::Format::B8G8R8A8_UNORM => (Bgra8, false),
            vk::Format::R16G16B16A16_UNORM => (Rgba16Unorm, false),
            vk::Format::R16G16B16A16_SFLOAT => (Rgba16Float, false),
            vk::Format::A2B10G10R10_UNORM_PACK32 => (A2b10g10r10, false),
            _ => return None,
        };
        Some(PixelFormat { layout, srgb })
    }

    fn in_place_view_format(self) -> Option<vk::Format> {
        interface::in_place_texel(self.shader_code())?;
        match self.layout {
            PixelLayout::Rgba8 => Some(vk::Format::R8G8B8A8_UNORM),
            PixelLayout::Rgba16Float => Some(vk::Format::R16G16B16A16_SFLOAT),
            _ => None,
        }
    }

    fn image_copy_format(self) -> Option<vk::Format> {
        interface::in_place_texel(self.shader_code())?;
        Some(match self.layout {
            PixelLayout::Rgba8 | PixelLayout::Bgra8 => vk::Format::R8G8B8A8_UNORM,
            PixelLayout::Rgba16Float => vk::Format::R16G16B16A16_SFLOAT,
            PixelLayout::Rgba16Unorm => vk::Format::R16G16B16A16_UINT,
            PixelLayout::A2b10g10r10 => vk::Format::R32_UINT,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The storage view's Vulkan format is the texel format the shader declares.
    #[test]
    fn in_place_view_formats_match_the_shaders_texel_formats() {
        let formats = [
            vk::Format::R8G8B8A8_SRGB,
            vk::Format::R8G8B8A8_UNORM,
            vk::Format::B8G8R8A8_SRGB,
            vk::Format::B8G8R8A8_UNORM,
            vk::Format::R16G16B16A16_UNORM,
            vk::Format::R16G16B16A16_SFLOAT,
            vk::Format::A2B10G10R10_UNORM_PACK32,
        ];
        for f in formats {
            let pixel = PixelFormat::from_vk(f).unwrap();
            let texel = interface::in_place_texel(pixel.shader_code());
            let expected = match pixel.in_place_view_format() {
                Some(vk::Format::R8G8B8A8_UNORM) => Some("rgba8unorm"),
                Some(vk::Format::R16G16B16A16_SFLOAT) => Some("rgba16float"),
                Some(other) => panic!("{other:?}"),
                None => None,
            };
            assert_eq!(texel, expected.or(texel), "{f:?}");
            let copy = match pixel.image_copy_format() {
                Some(vk::Format::R8G8B8A8_UNORM) => Some("rgba8unorm"),
                Some(vk::Format::R16G16B16A16_SFLOAT) => Some("rgba16float"),
                Some(vk::Format::R16G16B16A16_UINT) => Some("rgba16uint"),
                Some(vk::Format::R32_UINT) => Some("r32uint"),
                Some(other) => panic!("{other:?}"),
                None => None,
            };
            assert_eq!(texel, copy, "{f:?}");
            // The image-copy path copies raw bytes: the two formats are size-compatible.
            assert_eq!(
                copy.map(|_| pixel.bytes_per_pixel()),
                pixel.image_copy_format().map(texel_bytes),
                "{f:?}"
            );
        }
    }

    fn texel_bytes(f: vk::Format) -> u32 {
        match f {
            vk::Format::R16G16B16A16_SFLOAT | vk::Format::R16G16B16A16_UINT => 8,
            _ => 4,
        }
    }

    /// The app's own images are enhanced in place only in the RGBA8 and RGBA16 float formats.
    #[test]
    fn only_rgba8_and_rgba16_float_images_are_viewed_in_place() {
        for f in [vk::Format::R8G8B8A8_SRGB, vk::Format::R16G16B16A16_SFLOAT] {
            assert!(PixelFormat::from_vk(f)
                .unwrap()
                .in_place_view_format()
                .is_some());
        }
        for f in [
            vk::Format::B8G8R8A8_SRGB,
            vk::Format::R16G16B16A16_UNORM,
            vk::Format::A2B10G10R10_UNORM_PACK32,
        ] {
            assert_eq!(
                PixelFormat::from_vk(f).unwrap().in_place_view_format(),
                None
            );
        }
    }
}
