//! The engine's GPU resources: a background frame (the camera frame and its blurred copy, as
//! buffers and as a sampled image), a view's target (its pixels and tile list), where they
//! live, and how they are allocated and freed.

use super::set_pool::SetPool;
use crate::gpu::core::interface::{ACCESS_IN_PLACE, ACCESS_NARROW, ACCESS_SAMPLED, ACCESS_WIDE};
use crate::gpu::core::perceptual_words::PerceptualWords;
use crate::gpu::core::PixelFormat;
use crate::gpu::vulkan::device::{DeviceImage, GpuBuffer, GpuDevice, GpuError};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// One camera frame on the GPU and its blurred linear-light copy (camera grid).
pub struct CameraResources {
    pub size: (u32, u32),
    /// RGBA8 sRGB, one u32 per pixel, rows padded to a multiple of 4 pixels (the shader reads
    /// 16 bytes at a time); host-visible, written with `upload`.
    pub camera: GpuBuffer,
    /// Decoded and blurred, linear light, not attenuated: two texels per 16 bytes (see
    /// `blurred` in shaders/common.wgsl). What every view's enhancement samples. Followed by
    /// the decoded camera texels the blur reads (shaders/background.wgsl).
    pub blurred: GpuBuffer,
    /// `blurred` as an image (R32G32B32A32_UINT, kept in GENERAL), which the enhancement reads.
    pub(super) texels: DeviceImage,
    pub(super) texels_view: vk::ImageView,
    /// The preparation pass's descriptor set (camera, blurred).
    pub(super) set: vk::DescriptorSet,
    pub(super) pool: SetPool,
}

impl CameraResources {
    /// The view of the blurred image that the enhancement samples.
    pub fn texels_view(&self) -> vk::ImageView {
        self.texels_view
    }

    /// Copies a camera frame (RGBA8 sRGB, row-major) into the host-visible camera buffer.
    pub fn upload(&mut self, rgba: &[[u8; 4]]) -> Result<(), GpuError> {
        let (w, h) = (self.size.0 as usize, self.size.1 as usize);
        if rgba.len() != w * h {
            return Err(GpuError::Unsupported("camera frame size changed".into()));
        }
        let stride = camera_stride(self.size.0) as usize;
        if stride == w {
            return self.camera.write(rgba.as_flattened());
        }
        let dst = self
            .camera
            .mapped_mut()
            .ok_or_else(|| GpuError::Unsupported("buffer is not host-visible".into()))?;
        for (row, src) in rgba.chunks_exact(w).enumerate() {
            let at = row * stride * 4;
            dst[at..at + w * 4].copy_from_slice(src.as_flattened());
        }
        Ok(())
    }

    pub fn destroy(&mut self, gpu: &GpuDevice) {
        self.pool.free(gpu, &mut self.set);
        // SAFETY: the view is ours (null is ignored) and the GPU no longer uses it.
        unsafe { gpu.device.destroy_image_view(self.texels_view, None) };
        self.texels_view = vk::ImageView::null();
        self.texels.destroy(gpu);
        for b in [&mut self.camera, &mut self.blurred] {
            b.destroy(gpu);
        }
    }
}

/// The blurred camera image's texel format: one 16-byte entry (two packed texels) per texel.
pub(crate) const TEXELS_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

/// Pixels per camera buffer row: the width rounded up to whole 16-byte entries.
pub(super) fn camera_stride(width: u32) -> u32 {
    width.next_multiple_of(4)
}

/// Where a view's per-pixel passes read and write its pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelsIn {
    /// A buffer of the engine's holding a copy of the region (`ViewTarget::pixels`).
    Buffer,
    /// An image, through a storage view bound with `Recorder::bind_app_image` at `origin`:
    /// the app's image, or the engine's copy of the region; `pixels` is then a stand-in.
    Image,
    /// Read through a sampled view of the app's image (`Recorder::bind_app_texels`) and
    /// written to the engine's image bound with `bind_app_image` (ACCESS_SAMPLED).
    SampledImage,
}

impl PixelsIn {
    /// Whether the passes are the image variants (`Image` or `SampledImage`), whose pixels
    /// are bound per frame rather than held in `pixels`.
    pub fn in_image(self) -> bool {
        self != PixelsIn::Buffer
    }
}

/// What decides a view's shaders: its pixel format, width and where its pixels are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewShape {
    pub format: PixelFormat,
    pub width: u32,
    pub pixels_in: PixelsIn,
}

impl ViewShape {
    /// The pixel access of its per-pixel passes (interface.rs ACCESS_*).
    pub fn access(&self) -> u32 {
        match self.pixels_in {
            PixelsIn::SampledImage => ACCESS_SAMPLED,
            PixelsIn::Image => ACCESS_IN_PLACE,
            PixelsIn::Buffer if rows_aligned(self.width, self.format) => ACCESS_WIDE,
            PixelsIn::Buffer => ACCESS_NARROW,
        }
    }
}

/// One display region (a view): its pixels and tile list, bound to a background frame.
pub struct ViewTarget {
    pub region: (u32, u32),
    pub format: PixelFormat,
    /// Where its per-pixel passes read and write its pixels.
    pub pixels_in: PixelsIn,
    /// Where the region starts in the image (`PixelsIn::Image`, `SampledImage` only).
    pub origin: (u32, u32),
    /// The region's raw pixels in `format`, rows tightly packed (the copy path).
    pub pixels: GpuBuffer,
    /// Indirect dispatch arguments and the list of non-empty tiles (TileList in shaders/common.wgsl).
    pub tiles: GpuBuffer,
    /// The perceptual model of the view's frame (`perceptual` method; src/gpu/core/perceptual_words.rs),
    /// updated in the command buffer before the enhancement.
    pub perceptual: GpuBuffer,
    /// The view's pixels per degree (what resolves the `blur` frequency for it).
    pub pixels_per_degree: f64,
    /// The view's last perceptual words, kept while its model stays the same.
    pub(super) perceptual_words: std::sync::Mutex<PerceptualWords>,
    pub(super) set: vk::DescriptorSet,
    pub(super) camera_size: (u32, u32),
}

/// Whether every row of a region `width` pixels wide starts on a 16-byte boundary, so the
/// per-pixel passes may read and write 16 bytes at a time (shaders/access_wide.wgsl). True for
/// most widths in use.
pub fn rows_aligned(width: u32, format: PixelFormat) -> bool {
    (width * format.bytes_per_pixel()).is_multiple_of(16)
}

impl ViewTarget {
    /// The frame's commands that recorded this view's enhancement were submitted: its
    /// `perceptual` buffer holds the model they uploaded, and later frames need not again.
    pub fn model_submitted(&self) {
        self.perceptual_words
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .set_held();
    }

    pub fn shape(&self) -> ViewShape {
        ViewShape {
            format: self.format,
            width: self.region.0,
            pixels_in: self.pixels_in,
        }
    }

    /// [`rows_aligned`] for this view.
    pub fn rows_aligned(&self) -> bool {
        rows_aligned(self.region.0, self.format)
    }

    /// Whether the benchmark's 16-byte copy (`record_copy_wide`) can run on this view:
    /// aligned rows of 4-byte pixels.
    pub fn copies_wide(&self) -> bool {
        self.rows_aligned() && self.format.bytes_per_pixel() == 4
    }

    pub fn pixel_bytes(&self) -> u64 {
        u64::from(self.region.0)
            * u64::from(self.region.1)
            * u64::from(self.format.bytes_per_pixel())
    }
}

/// Where the engine's working buffers live: device-local inside the layer, host-visible for the
/// offline tool (which reads results back directly).
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub camera: MemoryLocation,
    pub working: MemoryLocation,
}

impl Placement {
    pub const OFFLINE: Placement = Placement {
        camera: MemoryLocation::CpuToGpu,
        working: MemoryLocation::GpuToCpu,
    };
    pub const DEVICE: Placement = Placement {
        camera: MemoryLocation::CpuToGpu,
        working: MemoryLocation::GpuOnly,
    };
}

pub(super) const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::STORAGE_BUFFER;

pub(super) fn transfer_storage() -> vk::BufferUsageFlags {
    STORAGE | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST
}

/// Allocates several buffers; on failure frees the ones already made.
pub(super) fn alloc_all<const N: usize>(
    gpu: &GpuDevice,
    specs: [(u64, vk::BufferUsageFlags, MemoryLocation, &str); N],
) -> Result<[GpuBuffer; N], GpuError> {
    let mut made = Vec::with_capacity(N);
    for (size, usage, location, name) in specs {
        match GpuBuffer::new(gpu, size, usage, location, name) {
            Ok(b) => made.push(b),
            Err(e) => {
                made.iter_mut().for_each(|b: &mut GpuBuffer| b.destroy(gpu));
                return Err(e);
            }
        }
    }
    Ok(made
        .try_into()
        .unwrap_or_else(|_| unreachable!("N buffers were made")))
}
