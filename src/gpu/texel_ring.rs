//! Sampled images the CPU writes: where the device samples R32G32B32A32_UINT images with linear
//! tiling and has device-local host-visible memory for them (integrated GPUs, CPU drivers, standalone
//! headsets), a live background's prepared texels go straight into such an image, mapped for
//! its life, which the enhancement then samples as its `blurred_texels`: no staging buffer and
//! no image copy (gpu/prepared_background.rs). A ring of them, so that a frame's texels never
//! go into an image a submitted frame may still sample.

use super::app_image::AppImage;
use super::barrier::layout_change;
use super::device::GpuDevice;
use super::engine::CameraRect;
use super::error::GpuError;
use super::resources::{colour_layer, TEXELS_FORMAT};
use crate::blurred_texels::{BlurredTexels, TEXEL_BYTES};
use ash::vk;

/// Images in the ring: the one the frame in flight samples and the one the next frame writes.
const SLOTS: usize = 2;

/// One mapped image of the ring.
struct MappedTexels {
    image: AppImage,
    view: vk::ImageView,
    /// Where the image's texels lie in its memory (vkGetImageSubresourceLayout).
    offset: usize,
    row_pitch: usize,
    /// The camera frame (sequence) and rectangle of texels the image holds.
    holds: Option<(u64, CameraRect)>,
    /// The submission that last sampled it (Commands::next_submission when recorded).
    read_by: u64,
    /// Moved from PREINITIALIZED to GENERAL (once, by the first frame that samples it).
    in_general: bool,
}

impl MappedTexels {
    fn new(gpu: &GpuDevice, size: (u32, u32)) -> Result<MappedTexels, GpuError> {
        let usage = vk::ImageUsageFlags::SAMPLED;
        let mut image = AppImage::linear_mapped(gpu, size, TEXELS_FORMAT, usage)?;
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
        let fits = image.mapped_mut().is_some_and(|m| {
            row_pitch >= row && offset + row_pitch * (size.1 as usize - 1) + row <= m.len()
        });
        let mut texels = MappedTexels {
            image,
            view,
            offset,
            row_pitch,
            holds: None,
            read_by: 0,
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

    /// Copies the rows of `rect` from `texels` (16 bytes per texel, rows packed).
    fn write(&mut self, texels: &BlurredTexels, rect: &CameraRect) {
        let (offset, pitch) = (self.offset, self.row_pitch);
        let dst = self.image.mapped_mut().expect("checked in new");
        let row = texels.width as usize * TEXEL_BYTES;
        let right = (rect.x + rect.width).min(texels.width) as usize;
        let span = rect.x as usize * TEXEL_BYTES..right * TEXEL_BYTES;
        for y in rect.y as usize..(rect.y + rect.height) as usize {
            let (src, at) = (y * row, offset + y * pitch);
            dst[at + span.start..at + span.end]
                .copy_from_slice(&texels.bytes[src + span.start..src + span.end]);
        }
    }

    fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: the view is ours (null is ignored) and the GPU no longer uses it.
        unsafe { gpu.device.destroy_image_view(self.view, None) };
        self.view = vk::ImageView::null();
        self.image.destroy(gpu);
    }
}

/// The frame engine's mapped texel images, made at the camera's size when first needed.
#[derive(Default)]
pub struct TexelRing {
    slots: Vec<MappedTexels>,
    size: (u32, u32),
    /// The slot written last.
    current: usize,
    /// The frame being recorded samples the current slot (else the background frame's image).
    pub(super) active: bool,
}

impl TexelRing {
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

    /// Makes the current slot hold `rect` of `texels` (camera frame `sequence`), writing only
    /// a slot whose last reader is `finished`, and makes the frame sample it. False, with
    /// nothing done, when every slot may still be sampled, or when the images must be (re)made
    /// at the texels' size and a submission may be in flight (not `idle`); an error when they
    /// cannot be made.
    pub fn write(
        &mut self,
        gpu: &GpuDevice,
        (texels, sequence): (&BlurredTexels, u64),
        rect: &CameraRect,
        finished: impl Fn(u64) -> bool,
        idle: bool,
    ) -> Result<bool, GpuError> {
        let size = (texels.width, texels.height);
        if self.size != size || self.slots.len() < SLOTS {
            if !idle {
                return Ok(false);
            }
            self.make(gpu, size)?;
        }
        let rect = match self.slots[self.current].holds {
            Some((s, done)) if s == sequence && done.contains(rect) => {
                self.active = true;
                return Ok(true);
            }
            Some((s, done)) if s == sequence => done.union(rect),
            _ => *rect,
        };
        let free = (1..=SLOTS)
            .map(|k| (self.current + k) % SLOTS)
            .find(|&i| finished(self.slots[i].read_by));
        let Some(next) = free else {
            return Ok(false);
        };
        let slot = &mut self.slots[next];
        slot.write(texels, &rect);
        slot.holds = Some((sequence, rect));
        self.current = next;
        self.active = true;
        Ok(true)
    }

    fn make(&mut self, gpu: &GpuDevice, size: (u32, u32)) -> Result<(), GpuError> {
        self.destroy(gpu);
        if !fits_device(gpu, size) {
            return Err(GpuError::Unsupported(format!(
                "no linear texel image of {}x{}",
                size.0, size.1
            )));
        }
        for _ in 0..SLOTS {
            let slot = MappedTexels::new(gpu, size);
            match slot {
                Ok(s) => self.slots.push(s),
                Err(e) => {
                    self.destroy(gpu);
                    return Err(e);
                }
            }
        }
        self.size = size;
        self.current = 0;
        Ok(())
    }

    /// The view of the image the frame samples, when it is one of the ring's.
    pub(super) fn sampled_view(&self) -> Option<vk::ImageView> {
        self.active
            .then(|| self.slots.get(self.current))?
            .map(|s| s.view)
    }

    /// Records, for submission `submission`, that it samples the current slot, and the slot's
    /// first layout change (PREINITIALIZED keeps what the host wrote) before the shaders read.
    pub(super) fn record_use(&mut self, gpu: &GpuDevice, cmd: vk::CommandBuffer, submission: u64) {
        let Some(slot) = self.slots.get_mut(self.current).filter(|_| self.active) else {
            return;
        };
        slot.read_by = submission;
        if slot.in_general {
            return;
        }
        slot.in_general = true;
        let to_general = [layout_change(
            slot.image.raw,
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

    /// Frees the images. No submission may still sample them.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        for mut s in self.slots.drain(..) {
            s.destroy(gpu);
        }
        self.size = (0, 0);
        self.active = false;
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
