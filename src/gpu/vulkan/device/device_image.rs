//! A 2D image the engine allocates on its device, whatever it is for: app-like colour images
//! (usable as a colour attachment and as a transfer source and destination, as the layer makes
//! swapchain images) that the benchmark copies from and to, so that it times the layer's image
//! copies on real images; the blurred camera image the enhancement samples
//! (src/gpu/vulkan/record/recorder.rs), also as a linear image in host-visible memory that the CPU
//! writes (src/gpu/vulkan/texels/texel_ring.rs); the warm-up's storage images.

use super::error::{GpuError, VkResultExt};
use super::gpu_device::GpuDevice;
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

pub struct DeviceImage {
    pub raw: vk::Image,
    pub(super) allocation: Option<Allocation>,
}

impl DeviceImage {
    /// No image yet (a null handle, nothing allocated): what `destroy` leaves, and safe to
    /// destroy again.
    pub fn none() -> DeviceImage {
        DeviceImage {
            raw: vk::Image::null(),
            allocation: None,
        }
    }

    pub fn new(gpu: &GpuDevice, size: (u32, u32), format: vk::Format) -> Result<Self, GpuError> {
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST;
        Self::with_usage(gpu, size, format, usage)
    }

    /// A 2D image of `format` with `usage` (optimal tiling, device-local, UNDEFINED layout).
    pub fn with_usage(
        gpu: &GpuDevice,
        size: (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self, GpuError> {
        Self::with_flags(gpu, size, format, usage, vk::ImageCreateFlags::empty())
    }

    /// An app-like image of `layers` array layers (a swapchain's), with `usage`.
    pub fn layered(
        gpu: &GpuDevice,
        size: (u32, u32),
        layers: u32,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self, GpuError> {
        let info = image_info(size, format, usage)
            .array_layers(layers)
            .tiling(vk::ImageTiling::OPTIMAL)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        Self::create(gpu, &info, MemoryLocation::GpuOnly)
    }

    /// [`DeviceImage::with_usage`] with image create flags (e.g. a mutable format).
    pub fn with_flags(
        gpu: &GpuDevice,
        size: (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        flags: vk::ImageCreateFlags,
    ) -> Result<Self, GpuError> {
        let info = image_info(size, format, usage)
            .flags(flags)
            .tiling(vk::ImageTiling::OPTIMAL)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        Self::create(gpu, &info, MemoryLocation::GpuOnly)
    }

    /// A 2D image of `format` with `usage`, linear tiling, in host-visible memory (mapped for
    /// its life), PREINITIALIZED: what the host writes before its first layout change is kept.
    pub fn linear_mapped(
        gpu: &GpuDevice,
        size: (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self, GpuError> {
        let info = image_info(size, format, usage)
            .tiling(vk::ImageTiling::LINEAR)
            .initial_layout(vk::ImageLayout::PREINITIALIZED);
        Self::create(gpu, &info, MemoryLocation::CpuToGpu)
    }

    fn create(
        gpu: &GpuDevice,
        info: &vk::ImageCreateInfo,
        location: MemoryLocation,
    ) -> Result<Self, GpuError> {
        // SAFETY: a plain 2D image create info on a valid device.
        let raw = unsafe { gpu.device.create_image(info, None) }.vk("vkCreateImage")?;
        let mut image = DeviceImage {
            raw,
            allocation: None,
        };
        let linear = info.tiling == vk::ImageTiling::LINEAR;
        match image.bind_memory(gpu, location, linear) {
            Ok(a) => image.allocation = Some(a),
            Err(e) => {
                image.destroy(gpu);
                return Err(e);
            }
        }
        Ok(image)
    }

    /// The mapped bytes of a host-visible image's memory (from the image's start).
    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        self.allocation.as_mut()?.mapped_slice_mut()
    }

    /// Whether the image's memory is device-local (on a discrete GPU, host-visible memory
    /// usually is not: the GPU would read it across the bus).
    pub fn device_local(&self) -> bool {
        self.allocation.as_ref().is_some_and(|a| {
            a.memory_properties()
                .contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
        })
    }

    fn bind_memory(
        &self,
        gpu: &GpuDevice,
        location: MemoryLocation,
        linear: bool,
    ) -> Result<Allocation, GpuError> {
        // SAFETY: raw is an image of this device.
        let requirements = unsafe { gpu.device.get_image_memory_requirements(self.raw) };
        let mut allocator = gpu.allocator.lock().map_err(|_| {
            GpuError::Unsupported("the GPU allocator was poisoned by an earlier panic".into())
        })?;
        let allocation = allocator.allocate(&AllocationCreateDesc {
            name: "app image",
            requirements,
            location,
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        // SAFETY: the allocation satisfies the image's requirements and is bound nowhere else.
        let bound = unsafe {
            gpu.device
                .bind_image_memory(self.raw, allocation.memory(), allocation.offset())
        };
        if let Err(result) = bound {
            let _ = allocator.free(allocation);
            return Err(GpuError::Vulkan {
                call: "vkBindImageMemory",
                result,
            });
        }
        Ok(allocation)
    }

    /// Frees the image and its memory. The GPU must be done with it.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        if let Some(allocation) = self.allocation.take() {
            if let Ok(mut allocator) = gpu.allocator.lock() {
                let _ = allocator.free(allocation);
            }
        }
        if self.raw != vk::Image::null() {
            // SAFETY: the caller guarantees no pending GPU work uses the image.
            unsafe { gpu.device.destroy_image(self.raw, None) };
            self.raw = vk::Image::null();
        }
    }
}

/// A one-layer, one-level 2D image of `format` with `usage`, exclusive to one queue family.
fn image_info(
    size: (u32, u32),
    format: vk::Format,
    usage: vk::ImageUsageFlags,
) -> vk::ImageCreateInfo<'static> {
    vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: size.0,
            height: size.1,
            depth: 1,
        })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .usage(usage)
        .sharing_mode(vk::SharingMode::EXCLUSIVE)
}
