//! Lit pixels drawn over the enhanced views (the layer's in-headset indicator): one colour,
//! given as horizontal runs per view, written from a small host-visible buffer holding them in
//! the view's pixel format, with one buffer copy per run. The other pixels are left as the
//! enhancement made them.

use super::frame_view::ViewKey;
use crate::colour;
use crate::gpu::device::{
    pixel_codec, record_buffer_copy, GpuBuffer, GpuDevice, GpuError, ImageRegion, PixelFormat,
};
use crate::gpu::recipe::ViewTarget;
use ash::vk;
use std::collections::hash_map::{Entry, HashMap};

/// One horizontal run of lit pixels: region coordinates, length in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    pub x: u32,
    pub y: u32,
    pub len: u32,
}

/// What to draw this frame: `key` names the drawing (a changed key redraws), `runs` gives
/// the lit pixels for a region size, `colour` is sRGB-encoded.
pub struct OverlayPixels<'a> {
    pub key: &'a str,
    pub colour: [u8; 4],
    pub runs: &'a dyn Fn((u32, u32)) -> Vec<Run>,
}

/// One pixel of an sRGB-encoded colour in the view's format (linear formats hold linear light).
pub fn encode(format: PixelFormat, [r, g, b, a]: [u8; 4]) -> Vec<u8> {
    let code = |c: u8| f64::from(c) / 255.0;
    let stored = |c: u8| match format.srgb {
        true => code(c),
        false => colour::srgb_decode(code(c)),
    };
    pixel_codec::encode(format, [stored(r), stored(g), stored(b), code(a)])
}

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
    let pixel = encode(target.format, pixels.colour);
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
            match target.in_place {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::device::PixelLayout;

    #[test]
    fn the_colour_in_every_format() {
        let f = |layout, srgb| PixelFormat { layout, srgb };
        assert_eq!(
            encode(f(PixelLayout::Rgba8, true), [64, 255, 64, 255]),
            [64, 255, 64, 255]
        );
        assert_eq!(
            encode(f(PixelLayout::Bgra8, true), [64, 255, 64, 255]),
            [64, 255, 64, 255]
        );
        // sRGB 64 is linear 0.0513 (IEC 61966-2-1): 13 of 255.
        assert_eq!(
            encode(f(PixelLayout::Rgba8, false), [64, 255, 0, 255]),
            [13, 255, 0, 255]
        );
        assert_eq!(
            encode(f(PixelLayout::Bgra8, false), [64, 255, 0, 255]),
            [0, 255, 13, 255]
        );
        let unorm16 = encode(f(PixelLayout::Rgba16Unorm, false), [255, 0, 255, 255]);
        assert_eq!(unorm16, [255, 255, 0, 0, 255, 255, 255, 255]);
        // Half floats: 1.0 = 0x3c00, 0 = 0.
        let float16 = encode(f(PixelLayout::Rgba16Float, false), [255, 0, 255, 255]);
        assert_eq!(float16, [0x00, 0x3c, 0, 0, 0x00, 0x3c, 0x00, 0x3c]);
        assert_eq!(pixel_codec::half_from_f32(0.5), 0x3800);
        assert_eq!(pixel_codec::half_from_f32(0.0513), 0x2a91);
        let packed = encode(f(PixelLayout::A2b10g10r10, false), [255, 0, 255, 255]);
        assert_eq!(u32::from_le_bytes(packed.try_into().unwrap()), 0xFFF0_03FF);
    }
}
