//! Memory the CPU writes a live background's prepared texels into (gpu/vulkan/frame/prepared_background.rs),
//! a ring of three so that a frame's texels never go into memory a submitted frame may still
//! read, and so that a live source's thread can write each new frame's texels into one before
//! it publishes the frame (gpu/core/texels/texel_slots.rs keeps what each holds and who may write it); the
//! frame then only uses it. Either
//! - sampled images: where the device samples R32G32B32A32_UINT images with linear tiling and
//!   has device-local host-visible memory for them (integrated GPUs, CPU drivers, standalone
//!   headsets), images mapped for their life, which the enhancement samples as its
//!   `blurred_texels`: no image copy; or
//! - staging buffers (elsewhere, e.g. a discrete GPU), which the frame's commands copy into the
//!   background frame's image with one vkCmdCopyBufferToImage.

use super::prepared_staging::new_staging;
use crate::gpu::core::blurred_texels::{BlurredTexels, TexelSink, TEXEL_BYTES};
use crate::gpu::core::texels::MappedRows;
use crate::gpu::core::texels::RingSink;
use crate::gpu::core::texels::Taken;
use crate::gpu::core::texels::TexelSlots;
use crate::gpu::core::CameraRect;
use crate::gpu::vulkan::device::{
    colour_layer, layout_change, DeviceImage, GpuBuffer, GpuDevice, GpuError,
};
use crate::gpu::vulkan::record::TEXELS_FORMAT;
use ash::vk;
use std::sync::Arc;

/// Slots in the ring: the one a submitted frame reads, the newest the source wrote (which the
/// next frame takes), and the one the source writes next.
const SLOTS: usize = 3;

/// One mapped image of the ring.
struct MappedTexels {
    image: DeviceImage,
    view: vk::ImageView,
    /// Where the image's texels lie in its memory (vkGetImageSubresourceLayout).
    rows: MappedRows,
    /// Moved from PREINITIALIZED to GENERAL (once, by the first frame that samples it).
    in_general: bool,
}

impl MappedTexels {
    fn new(gpu: &GpuDevice, size: (u32, u32)) -> Result<MappedTexels, GpuError> {
        let usage = vk::ImageUsageFlags::SAMPLED;
        let mut image = DeviceImage::linear_mapped(gpu, size, TEXELS_FORMAT, usage)?;
        let sub = vk::ImageSubresource::default().aspect_mask(vk::ImageAspectFlags::COLOR);
        // SAFETY: a linear image of this device, one colour subresource.
        let layout = unsafe { gpu.device.get_image_subresource_layout(image.raw, sub) };
        let info = vk::ImageViewCreateInfo::default()
            .image(image.raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(TEXELS_FORMAT)
            .subresource_range(colour_layer());
        // SAFETY: a view of our own image, with its format, on a valid device.
        let view = match unsafe { gpu.device.create_image_view(&info, None) } {
            Ok(v) => v,
            Err(result) => {
                image.destroy(gpu);
                return Err(GpuError::Vulkan {
                    call: "vkCreateImageView",
                    result,
                });
            }
        };
        let row = size.0 as usize * TEXEL_BYTES;
        let (offset, row_pitch) = (layout.offset as usize, layout.row_pitch as usize);
        let mapped = image.mapped_mut().map(|m| (m.as_mut_ptr(), m.len()));
        let fits = mapped.is_some_and(|(_, len)| {
            row_pitch >= row && offset + row_pitch * (size.1 as usize - 1) + row <= len
        });
        let (ptr, len) = mapped.unwrap_or((std::ptr::null_mut(), 0));
        let rows = MappedRows {
            ptr,
            len,
            offset,
            row_pitch,
        };
        let mut texels = MappedTexels {
            image,
            view,
            rows,
            in_general: false,
        };
        if !fits {
            texels.destroy(gpu);
            return Err(GpuError::Unsupported(
                "a linear texel image is not mapped whole".into(),
            ));
        }
        // Every pixel samples it: memory the GPU reads across the bus would cost more per
        // frame than the staging copy into a device-local image.
        if !texels.image.device_local() {
            texels.destroy(gpu);
            return Err(GpuError::Unsupported(
                "no device-local host-visible memory for the texels".into(),
            ));
        }
        Ok(texels)
    }

    fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: the view is ours (null is ignored) and the GPU no longer uses it.
        unsafe { gpu.device.destroy_image_view(self.view, None) };
        self.view = vk::ImageView::null();
        self.image.destroy(gpu);
    }
}

/// A slot's memory: an image the views sample, or a buffer copied into the background's image.
enum SlotMemory {
    Image(MappedTexels),
    Buffer(GpuBuffer),
}

impl SlotMemory {
    fn destroy(&mut self, gpu: &GpuDevice) {
        match self {
            SlotMemory::Image(i) => i.destroy(gpu),
            SlotMemory::Buffer(b) => b.destroy(gpu),
        }
    }
}

/// The frame engine's texel ring, made at the camera's size when first needed.
#[derive(Default)]
pub struct TexelRing {
    memory: Vec<SlotMemory>,
    /// What the slots hold and who may write them; shared with the source's thread.
    slots: Option<Arc<TexelSlots>>,
    /// The source's way in, the same for the ring's life: it reaches `slots` while they are
    /// open.
    sink: Arc<RingSink>,
    size: (u32, u32),
    /// The slots are images the views sample (else staging buffers).
    sampled: bool,
    /// The slot the frame uses (when `active`).
    current: usize,
    /// The frame being recorded uses the current slot: samples it (images), or copies from it
    /// (buffers; `copy` says which rectangle).
    active: bool,
    copy: Option<CameraRect>,
    /// Frames that used texels the source's thread wrote, and all frames that used the ring.
    from_source: u64,
    frames: u64,
}

impl TexelRing {
    /// Whether the frame being recorded uses the current slot (samples it, or copies from it).
    pub fn active(&self) -> bool {
        self.active
    }

    /// The frame being recorded uses no slot of the ring.
    pub fn set_inactive(&mut self) {
        self.active = false;
    }

    /// Frames that used texels the source's thread wrote, and all frames that used the ring.
    pub fn texels_from_source(&self) -> (u64, u64) {
        (self.from_source, self.frames)
    }

    /// Whether `gpu` samples the texel format with linear tiling.
    pub fn supported(gpu: &GpuDevice) -> bool {
        // SAFETY: the physical device belongs to this instance.
        let props = unsafe {
            gpu.instance
                .get_physical_device_format_properties(gpu.physical, TEXELS_FORMAT)
        };
        let features = props.linear_tiling_features;
        features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE)
    }

    /// Makes the frame to be submitted as `submission` use a slot holding `rect` of `texels`:
    /// one the source's thread wrote them into, else one written now that no unfinished
    /// submission reads. With `sampled` the slots are images the views sample, else staging
    /// buffers the frame copies `rect` from. False, with nothing done, when every slot may still
    /// be read, or when the slots must be (re)made (at the texels' size or of the other kind)
    /// and a submission may be in flight (not `idle`); an error when they cannot be made.
    pub fn write(
        &mut self,
        gpu: &GpuDevice,
        texels: &BlurredTexels,
        rect: &CameraRect,
        (submission, sampled): (u64, bool),
        idle: bool,
    ) -> Result<bool, GpuError> {
        let size = (texels.width, texels.height);
        if self.size != size || self.slots.is_none() || self.sampled != sampled {
            if !idle {
                return Ok(false);
            }
            self.make(gpu, size, sampled)?;
        }
        let slots = self.slots.as_ref().expect("made above");
        let taken = slots
            .take(texels.serial, rect, submission)
            .or_else(|| slots.write_for_frame(texels, rect, submission));
        let Some(Taken { slot, by_source }) = taken else {
            return Ok(false);
        };
        self.current = slot;
        self.active = true;
        self.copy = (!sampled).then_some(*rect);
        self.frames += 1;
        self.from_source += u64::from(by_source);
        Ok(true)
    }

    /// Where a live source writes its frames' texels: one sink for the ring's life, which
    /// takes them while the slots are made and open.
    pub fn sink(&self) -> Arc<dyn TexelSink> {
        self.sink.clone()
    }

    /// Submissions up to `n` have finished.
    pub fn finished_through(&self, n: u64) {
        if let Some(slots) = &self.slots {
            slots.finished_through(n);
        }
    }

    fn make(&mut self, gpu: &GpuDevice, size: (u32, u32), sampled: bool) -> Result<(), GpuError> {
        self.destroy(gpu);
        if sampled && !fits_device(gpu, size) {
            return Err(GpuError::Unsupported(format!(
                "no linear texel image of {}x{}",
                size.0, size.1
            )));
        }
        for _ in 0..SLOTS {
            let memory = match sampled {
                true => MappedTexels::new(gpu, size).map(SlotMemory::Image),
                false => staging_slot(gpu, size).map(SlotMemory::Buffer),
            };
            match memory {
                Ok(m) => self.memory.push(m),
                Err(e) => {
                    self.destroy(gpu);
                    return Err(e);
                }
            }
        }
        let rows = self.memory.iter_mut().map(|m| rows_of(m, size.0)).collect();
        self.slots = Some(Arc::new(TexelSlots::new(size, rows)));
        self.sink.connect(self.slots.clone());
        self.size = size;
        self.sampled = sampled;
        self.current = 0;
        Ok(())
    }

    /// The view of the image the frame samples, when it is one of the ring's.
    pub fn sampled_view(&self) -> Option<vk::ImageView> {
        match self.memory.get(self.current).filter(|_| self.active)? {
            SlotMemory::Image(i) => Some(i.view),
            SlotMemory::Buffer(_) => None,
        }
    }

    /// The staging buffer and rectangle the frame copies into the background's image, once:
    /// laid out as the image, 16 bytes per texel (`Recorder::record_texels_upload`).
    pub fn take_copy(&mut self) -> Option<(&GpuBuffer, CameraRect)> {
        let rect = self.copy.take().filter(|_| self.active)?;
        match self.memory.get(self.current)? {
            SlotMemory::Buffer(b) => Some((b, rect)),
            SlotMemory::Image(_) => None,
        }
    }

    /// Records, for submission `submission`, that it reads the current slot, and an image's
    /// first layout change (PREINITIALIZED keeps what the host wrote) before the shaders read.
    pub fn record_use(&mut self, gpu: &GpuDevice, cmd: vk::CommandBuffer, submission: u64) {
        if !self.active {
            return;
        }
        if let Some(slots) = &self.slots {
            slots.sampled_by(self.current, submission);
        }
        let Some(SlotMemory::Image(image)) = self.memory.get_mut(self.current) else {
            return;
        };
        if image.in_general {
            return;
        }
        image.in_general = true;
        let to_general = [layout_change(
            image.image.raw,
            (vk::ImageLayout::PREINITIALIZED, vk::ImageLayout::GENERAL),
            (vk::AccessFlags::HOST_WRITE, vk::AccessFlags::SHADER_READ),
        )];
        // SAFETY: cmd is recording; the image is ours, in PREINITIALIZED until now.
        unsafe {
            gpu.device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::HOST,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &to_general,
            )
        };
    }

    /// The frame uses no slot of the ring, and the source's thread writes none from now on.
    pub fn close_to_source(&mut self) {
        self.active = false;
        self.copy = None;
        self.sink.connect(None);
        if let Some(slots) = &self.slots {
            slots.close();
        }
    }

    /// Frees the slots' memory, once the source's thread can no longer write it (a write under
    /// way ends first). No submission may still read it.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        self.sink.connect(None);
        if let Some(slots) = self.slots.take() {
            slots.close();
        }
        for mut m in self.memory.drain(..) {
            m.destroy(gpu);
        }
        self.size = (0, 0);
        self.active = false;
        self.copy = None;
    }
}

/// A host-visible staging buffer for a `size` frame's texels, laid out as the image.
fn staging_slot(gpu: &GpuDevice, size: (u32, u32)) -> Result<GpuBuffer, GpuError> {
    let bytes = u64::from(size.0) * u64::from(size.1) * TEXEL_BYTES as u64;
    let mut buffer = new_staging(gpu, bytes.max(16))?;
    if buffer.mapped_mut().is_none() {
        buffer.destroy(gpu);
        return Err(GpuError::Unsupported(
            "the staging buffer is not host-visible".into(),
        ));
    }
    Ok(buffer)
}

/// Where a slot's texels of a `width`-wide frame lie in its mapped memory (mapped: checked when
/// it was made; a buffer's rows are packed).
fn rows_of(memory: &mut SlotMemory, width: u32) -> MappedRows {
    match memory {
        SlotMemory::Image(i) => i.rows,
        SlotMemory::Buffer(b) => {
            let m = b.mapped_mut().expect("checked in staging_slot");
            MappedRows {
                ptr: m.as_mut_ptr(),
                len: m.len(),
                offset: 0,
                row_pitch: width as usize * TEXEL_BYTES,
            }
        }
    }
}

/// Whether the device makes linear sampled texel images of `size`.
fn fits_device(gpu: &GpuDevice, size: (u32, u32)) -> bool {
    // SAFETY: the physical device belongs to this instance; plain enum and flag arguments.
    let props = unsafe {
        gpu.instance.get_physical_device_image_format_properties(
            gpu.physical,
            TEXELS_FORMAT,
            vk::ImageType::TYPE_2D,
            vk::ImageTiling::LINEAR,
            vk::ImageUsageFlags::SAMPLED,
            vk::ImageCreateFlags::empty(),
        )
    };
    props.is_ok_and(|p| size.0 <= p.max_extent.width && size.1 <= p.max_extent.height)
}
