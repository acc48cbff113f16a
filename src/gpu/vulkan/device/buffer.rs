//! Storage buffers with memory from gpu-allocator.

use super::error::{GpuError, VkResultExt};
use super::gpu_device::GpuDevice;
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

pub struct GpuBuffer {
    pub raw: vk::Buffer,
    pub size: u64,
    /// The bytes asked for (`size` is at least 16): what `mapped` gives, never the
    /// allocation's padding (a driver may round an allocation up: 272 bytes for 260 on NVIDIA).
    requested: u64,
    allocation: Option<Allocation>,
}

impl GpuBuffer {
    pub fn new(
        gpu: &GpuDevice,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
        name: &str,
    ) -> Result<GpuBuffer, GpuError> {
        let requested = size;
        let size = size.max(16);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: a plain buffer create info on a valid device.
        let raw = unsafe { gpu.device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        match Self::bind_memory(gpu, raw, location, name) {
            Ok(allocation) => Ok(GpuBuffer {
                raw,
                size,
                requested,
                allocation: Some(allocation),
            }),
            Err(e) => {
                // SAFETY: the buffer was just created and is not in use.
                unsafe { gpu.device.destroy_buffer(raw, None) };
                Err(e)
            }
        }
    }

    fn bind_memory(
        gpu: &GpuDevice,
        raw: vk::Buffer,
        location: MemoryLocation,
        name: &str,
    ) -> Result<Allocation, GpuError> {
        // SAFETY: raw is a buffer of this device.
        let requirements = unsafe { gpu.device.get_buffer_memory_requirements(raw) };
        let mut allocator = gpu.allocator.lock().map_err(|_| {
            GpuError::Unsupported("the GPU allocator was poisoned by an earlier panic".into())
        })?;
        crate::fault::check("allocation").map_err(GpuError::Unsupported)?;
        let allocation = allocator.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        // SAFETY: the allocation satisfies the buffer's requirements and is not bound elsewhere.
        let bound = unsafe {
            gpu.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        };
        if let Err(result) = bound {
            let _ = allocator.free(allocation);
            return Err(GpuError::Vulkan {
                call: "vkBindBufferMemory",
                result,
            });
        }
        Ok(allocation)
    }

    /// The mapped bytes (host-visible buffers only): exactly the bytes the buffer was made
    /// for, whatever the allocation's size.
    pub fn mapped(&self) -> Option<&[u8]> {
        let n = self.requested as usize;
        self.allocation
            .as_ref()?
            .mapped_slice()
            .map(|s| &s[..n.min(s.len())])
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let n = self.requested as usize;
        self.allocation.as_mut()?.mapped_slice_mut().map(|s| {
            let len = s.len();
            &mut s[..n.min(len)]
        })
    }

    /// Copies `data` to the start of a host-visible buffer.
    pub fn write(&mut self, data: &[u8]) -> Result<(), GpuError> {
        let dst = self
            .mapped_mut()
            .ok_or_else(|| GpuError::Unsupported("buffer is not host-visible".into()))?;
        if data.len() > dst.len() {
            return Err(GpuError::Unsupported(
                "upload larger than its buffer".into(),
            ));
        }
        dst[..data.len()].copy_from_slice(data);
        Ok(())
    }

    /// Frees the memory and the buffer. The GPU must be done with it.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        if let Some(allocation) = self.allocation.take() {
            if let Ok(mut allocator) = gpu.allocator.lock() {
                let _ = allocator.free(allocation);
            }
            // SAFETY: the caller guarantees no pending GPU work uses the buffer.
            unsafe { gpu.device.destroy_buffer(self.raw, None) };
        }
    }
}

/// Records copies of byte ranges from `src` into `dst`. The caller orders them against other
/// work with barriers; every range must lie inside both buffers.
pub fn record_buffer_copy(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    (src, dst): (&GpuBuffer, &GpuBuffer),
    regions: &[vk::BufferCopy],
) {
    let inside = |b: &GpuBuffer, end: u64| end <= b.size;
    let fits = regions
        .iter()
        .all(|r| inside(src, r.src_offset + r.size) && inside(dst, r.dst_offset + r.size));
    assert!(fits, "a buffer copy reaches past its buffers");
    // SAFETY: cmd is recording (the caller's contract); both buffers are valid and every range
    // lies inside them (checked above).
    unsafe { gpu.device.cmd_copy_buffer(cmd, src.raw, dst.raw, regions) };
}
