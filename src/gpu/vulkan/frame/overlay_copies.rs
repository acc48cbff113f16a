//! The overlay's runs (the layer's in-headset indicator) written into a Vulkan view: a small
//! host-visible buffer holds them in the view's pixel format, with one buffer copy per run.

use super::frame_view::ViewKey;
use crate::gpu::core::{overlay_pixel, OverlayPixels, PixelFormat};
use crate::gpu::vulkan::device::{record_buffer_copy, GpuBuffer, GpuDevice, GpuError, ImageRegion};
use crate::gpu::vulkan::record::ViewTarget;
use ash::vk;
use std::collections::hash_map::{Entry, HashMap};

/// One view's drawing: the lit pixels in a host-visible buffer and the copies into the view.
struct Overlay {
    key: String,
    format: PixelFormat,
    region: (u32, u32),
    buffer: GpuBuffer,
    copies: Vec<vk::BufferCopy>,
}

fn overlay(
    gpu: &GpuDevice,
    pixels: &OverlayPixels,
    target: &ViewTarget,
) -> Result<Option<Overlay>, GpuError> {
    let runs = (pixels.runs)(target.region);
    if runs.is_empty() {
        return Ok(None);
    }
    let pixel = overlay_pixel(target.format, pixels.colour);
    let bpp = pixel.len() as u64;
    let lit: u64 = runs.iter().map(|r| u64::from(r.len)).sum();
    let mut buffer = GpuBuffer::new(
        gpu,
        lit * bpp,
        vk::BufferUsageFlags::TRANSFER_SRC,
        gpu_allocator::MemoryLocation::CpuToGpu,
        "indicator",
    )?;
    let bytes: Vec<u8> = (0..lit).flat_map(|_| pixel.iter().copied()).collect();
    if let Err(e) = buffer.write(&bytes) {
        buffer.destroy(gpu);
        return Err(e);
    }
    let width = u64::from(target.region.0);
    let mut src = 0;
    let copies = runs
        .iter()
        .map(|r| {
            // The view buffer holds the region's rows tightly packed (as the copy out of the
            // app's image writes them).
            let dst = (u64::from(r.y) * width + u64::from(r.x)) * bpp;
            let size = u64::from(r.len) * bpp;
            let copy = vk::BufferCopy::default()
                .src_offset(src)
                .dst_offset(dst)
                .size(size);
            src += size;
            copy
        })
        .collect();
    Ok(Some(Overlay {
        key: pixels.key.to_string(),
        format: target.format,
        region: target.region,
        buffer,
        copies,
    }))
}

/// The runs of `o` copied into the app's image (GENERAL) at the region's place: the copies'
/// buffer offsets are the region's tightly packed layout, as for a view's buffer.
fn record_into_image(gpu: &GpuDevice, cmd: vk::CommandBuffer, o: &Overlay, region: &ImageRegion) {
    let bpp = u64::from(o.format.bytes_per_pixel());
    let width = u64::from(o.region.0);
    let copies: Vec<vk::BufferImageCopy> = o
        .copies
        .iter()
        .map(|c| {
            let pixel = c.dst_offset / bpp;
            let (x, y) = ((pixel % width) as i32, (pixel / width) as i32);
            region.copy_of(c.src_offset, (x, y), ((c.size / bpp) as u32, 1))
        })
        .collect();
    // SAFETY: cmd is recording; the image is in GENERAL with transfer usage and every run lies
    // inside the region, which lies inside the image (the caller's contract).
    unsafe {
        gpu.device.cmd_copy_buffer_to_image(
            cmd,
            o.buffer.raw,
            region.image,
            vk::ImageLayout::GENERAL,
            &copies,
        )
    };
}

/// The drawings of a session's views, kept while they do not change.
#[derive(Default)]
pub struct Overlays {
    drawn: HashMap<ViewKey, Overlay>,
}

impl Overlays {
    /// Records the copies of `pixels` into each view's buffer, or into its region of the app's
    /// image (GENERAL) for a view enhanced in place; true if any was recorded (the caller then
    /// puts a transfer barrier before anything reads them). None frees the drawings. The GPU
    /// must be done with the previous frame.
    pub fn record<'a>(
        &mut self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        pixels: Option<&OverlayPixels>,
        views: impl Iterator<Item = (ViewKey, &'a ViewTarget, ImageRegion)>,
    ) -> Result<bool, GpuError> {
        let Some(pixels) = pixels else {
            self.destroy(gpu);
            return Ok(false);
        };
        let mut drawn = false;
        for (key, target, region) in views {
            let stale = self.drawn.get(&key).is_some_and(|o| {
                o.key != pixels.key || o.format != target.format || o.region != target.region
            });
            if stale {
                if let Some(mut old) = self.drawn.remove(&key) {
                    old.buffer.destroy(gpu);
                }
            }
            let o = match self.drawn.entry(key) {
                Entry::Occupied(o) => o.into_mut(),
                Entry::Vacant(slot) => match overlay(gpu, pixels, target)? {
                    Some(o) => slot.insert(o),
                    None => continue,
                },
            };
            // The overlay buffer is host-written before this submission.
            match target.pixels_in.in_image() {
                true => record_into_image(gpu, cmd, o, &region),
                false => record_buffer_copy(gpu, cmd, (&o.buffer, &target.pixels), &o.copies),
            }
            drawn = true;
        }
        Ok(drawn)
    }

    /// Frees the drawings' buffers. The GPU must be done with them.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        for (_, mut o) in self.drawn.drain() {
            o.buffer.destroy(gpu);
        }
    }
}
