//! The unit of a frame's GPU work: one view region of an app's image, the key its buffers are
//! kept under, and what a capture reads back of it.

use crate::algorithm::mapping::CameraMapping;
use crate::gpu::core::PixelFormat;
use crate::gpu::vulkan::device::ImageRegion;
use crate::gpu::vulkan::record::{PixelsIn, ViewShape};
use ash::vk;

/// One region of an app's image to enhance.
#[derive(Clone, Debug)]
pub struct FrameView {
    pub key: ViewKey,
    /// The app's image (its handle stays in the frame room; `region` gives it to a copy).
    pub(super) image: vk::Image,
    pub format: PixelFormat,
    pub(super) vk_format: vk::Format,
    /// How the region is enhanced: in place (the swapchain was made with storage usage for
    /// it), or through a copy of the region into an image or a buffer of the engine's own.
    pub path: ViewPath,
    /// Where this view's display pixels lie in the camera image.
    pub mapping: CameraMapping,
    /// The view's display pixels per degree (the perceptual model's frequency needs it).
    pub pixels_per_degree: f64,
}

impl FrameView {
    /// The view `key` of the app's `image`, whose Vulkan format is `vk_format` (`format` as the
    /// engine reads it), with `pixels_per_degree` display pixels per degree.
    pub fn new(
        key: ViewKey,
        image: vk::Image,
        format: PixelFormat,
        vk_format: vk::Format,
        path: ViewPath,
        mapping: CameraMapping,
        pixels_per_degree: f64,
    ) -> FrameView {
        FrameView {
            key,
            image,
            format,
            vk_format,
            path,
            mapping,
            pixels_per_degree,
        }
    }

    /// The app image's Vulkan format (for a capture's description).
    pub fn vk_format(&self) -> vk::Format {
        self.vk_format
    }

    pub fn shape(&self) -> ViewShape {
        ViewShape {
            format: self.format,
            width: self.key.extent.0,
            pixels_in: self.path.pixels_in(),
        }
    }

    pub fn region(&self) -> ImageRegion {
        ImageRegion {
            image: self.image,
            array_index: self.key.array_index,
            offset: self.key.offset,
            extent: self.key.extent,
        }
    }
}

/// How a view's region is enhanced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewPath {
    /// In the app's image, through a storage view of its layer (the swapchain has storage
    /// usage, and for sRGB a mutable format).
    InPlace,
    /// Copied (vkCmdCopyImage, raw bytes) into an image of the engine's own in a
    /// size-compatible format with storage usage (`PixelFormat::image_copy_format`), enhanced
    /// there by the in-place shaders, and copied back: for images the layer may not store to.
    ImageCopy,
    /// The image-copy path with only the tiles the enhancement listed drawn back into the
    /// app's image (a render pass, `copy_back = "tiles"`) instead of the whole region copied
    /// back; the region is copied back whole while the draw's pipeline is being built.
    ImageCopyTiles,
    /// Read through a sampled view of the app's image (8-bit sRGB formats, whose runtimes
    /// refuse storage usage; the swapchain needs sampled usage), enhanced into an image of the
    /// engine's own as in the image-copy path, and the listed tiles drawn back: no copy of the
    /// region in either direction.
    SampledTiles,
    /// Copied into a buffer of the engine's own, enhanced there and copied back: where the
    /// device cannot store to the image-copy path's format.
    BufferCopy,
}

impl ViewPath {
    /// Its name in the log and in a capture's JSON (`"path"`): `in-place`, `image-copy`,
    /// `image-copy-tiles`, `sampled-tiles`, `copy` (the buffer path's name since before the
    /// image-copy path).
    pub fn name(self) -> &'static str {
        match self {
            ViewPath::InPlace => "in-place",
            ViewPath::ImageCopy => "image-copy",
            ViewPath::ImageCopyTiles => "image-copy-tiles",
            ViewPath::SampledTiles => "sampled-tiles",
            ViewPath::BufferCopy => "copy",
        }
    }

    /// Whether the region is copied into an image of the engine's own (the image-copy path,
    /// whichever way it comes back).
    pub fn copies_into_own_image(self) -> bool {
        matches!(self, ViewPath::ImageCopy | ViewPath::ImageCopyTiles)
    }

    /// Whether the enhancement writes an image of the engine's own (the image-copy path and
    /// the sampled read) rather than the app's image or a buffer.
    pub fn writes_own_image(self) -> bool {
        self.copies_into_own_image() || self == ViewPath::SampledTiles
    }

    /// Whether the tiles the enhancement listed are drawn back into the app's image.
    pub fn draws_tiles_back(self) -> bool {
        matches!(self, ViewPath::ImageCopyTiles | ViewPath::SampledTiles)
    }

    /// Whether its passes read the app's image through a sampled view (ACCESS_SAMPLED).
    pub fn reads_sampled(self) -> bool {
        self == ViewPath::SampledTiles
    }

    /// Where its passes read and write the pixels: the app's image or the engine's copy of
    /// the region (`Image`), read through a sampled view (`SampledImage`), or a buffer.
    pub fn pixels_in(self) -> PixelsIn {
        match self {
            ViewPath::BufferCopy => PixelsIn::Buffer,
            ViewPath::SampledTiles => PixelsIn::SampledImage,
            _ => PixelsIn::Image,
        }
    }
}

/// A view region's identity across frames: its swapchain (an opaque handle value), rectangle
/// and array layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ViewKey {
    pub swapchain: u64,
    pub offset: (i32, i32),
    pub extent: (u32, u32),
    pub array_index: u32,
}

/// Raw bytes of one view read back for a capture: before and after the enhancement.
pub struct CapturedView {
    pub view: FrameView,
    pub display: Vec<u8>,
    pub output: Vec<u8>,
}
