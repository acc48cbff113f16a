//! The in-headset indicator: a short line such as `CONTRASTXR ENHANCE λE 0.40`, drawn into
//! each eye image for `indicator_seconds` after the session's first processed frame and after
//! each change of settings, so the wearer can tell the layer is on and what it does.
//!
//! The text is rendered on the CPU with the figures' bitmap font and only its lit pixels are
//! written: one buffer copy per horizontal run of lit pixels, from a small host-visible buffer
//! holding them in the view's pixel format, into the engine's view buffer after the
//! enhancement and before the copy back to the app's image. The app's other pixels are left
//! as the enhancement made them, and captures show what the runtime gets.

use super::work::ViewKey;
use crate::algorithm::params::{Method, ViewMode};
use crate::colour;
use crate::config::Settings;
use crate::evaluate::font;
use crate::gpu::buffer::{record_buffer_copy, GpuBuffer};
use crate::gpu::pixel_codec;
use crate::gpu::{GpuDevice, GpuError, PixelFormat, ViewTarget};
use crate::image::RgbaImage;
use ash::vk;
use std::collections::hash_map::{Entry, HashMap};
use std::time::{Duration, Instant};

/// The text's colour, sRGB-encoded: a bright green, which an additive display shows well.
pub const COLOUR: [u8; 4] = [64, 255, 64, 255];

/// What the indicator says for these settings.
pub fn text(settings: &Settings) -> String {
    let p = &settings.params;
    // A comparison method is shown in mode enhance: name the method then.
    let what = match (p.mode, p.method) {
        (ViewMode::Enhance, m) if m != Method::Paper => m.name(),
        (mode, _) => mode.name(),
    };
    format!("CONTRASTXR {} λE {:.2}", what.to_uppercase(), p.lambda_e)
}

/// When the indicator shows: from the first frame of each settings generation on, for a while.
#[derive(Default)]
pub struct Timer {
    generation: Option<u64>,
    since: Option<Instant>,
    text: String,
    shown_for: Duration,
    enabled: bool,
}

impl Timer {
    /// Called at each processed frame with the session's current settings.
    pub fn update(&mut self, settings: &Settings, now: Instant) {
        if self.generation == Some(settings.generation) {
            return;
        }
        self.generation = Some(settings.generation);
        self.since = Some(now);
        self.text = text(settings);
        self.shown_for = Duration::from_secs_f32(settings.indicator_seconds.clamp(0.0, 60.0));
        self.enabled = settings.indicator;
    }

    /// The text to draw now, if any.
    pub fn showing(&self, now: Instant) -> Option<&str> {
        let since = self.since.filter(|_| self.enabled)?;
        (now.saturating_duration_since(since) < self.shown_for).then_some(self.text.as_str())
    }
}

/// Where the text goes in a region: (x, y, scale). Centred, a fifth of the way down, about a
/// 25th of the region's height tall; None when it does not fit even at scale 1.
pub fn placement(text: &str, (w, h): (u32, u32)) -> Option<(u32, u32, u32)> {
    let mut scale = (h / (font::GLYPH_HEIGHT * 25)).max(1);
    while scale > 1 && font::text_width(text, scale) > w * 9 / 10 {
        scale -= 1;
    }
    let (tw, th) = (font::text_width(text, scale), font::text_height(scale));
    (tw <= w && th <= h).then(|| ((w - tw) / 2, h / 5, scale))
}

/// One horizontal run of lit pixels: region coordinates, length in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    pub x: u32,
    pub y: u32,
    pub len: u32,
}

/// The runs of lit pixels of `text` placed in a region of size `region`.
pub fn runs(text: &str, region: (u32, u32)) -> Vec<Run> {
    let Some((x0, y0, scale)) = placement(text, region) else {
        return Vec::new();
    };
    let (tw, th) = (font::text_width(text, scale), font::text_height(scale));
    let mut mask = RgbaImage::new(tw, th, [0; 4]);
    font::draw_text(&mut mask, 0, 0, text, scale, [255; 4]);
    let mut out = Vec::new();
    for y in 0..th {
        let mut x = 0;
        while x < tw {
            if mask.get(x, y)[0] == 0 {
                x += 1;
                continue;
            }
            let start = x;
            while x < tw && mask.get(x, y)[0] != 0 {
                x += 1;
            }
            out.push(Run {
                x: x0 + start,
                y: y0 + y,
                len: x - start,
            });
        }
    }
    out
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

/// One view's drawn text: the lit pixels in a host-visible buffer and the copies into the view.
struct Overlay {
    text: String,
    format: PixelFormat,
    region: (u32, u32),
    buffer: GpuBuffer,
    copies: Vec<vk::BufferCopy>,
}

fn overlay(gpu: &GpuDevice, text: &str, target: &ViewTarget) -> Result<Option<Overlay>, GpuError> {
    let runs = runs(text, target.region);
    if runs.is_empty() {
        return Ok(None);
    }
    let pixel = encode(target.format, COLOUR);
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
        text: text.to_string(),
        format: target.format,
        region: target.region,
        buffer,
        copies,
    }))
}

/// A session's indicator: when it shows, and each view's drawn text.
#[derive(Default)]
pub struct Indicator {
    pub timer: Timer,
    overlays: HashMap<ViewKey, Overlay>,
}

impl Indicator {
    /// Records the copies of the text into each view's buffer; true if any was recorded (the
    /// caller then puts a transfer barrier before anything reads the view buffers). The GPU
    /// must be done with the previous frame (the processor waits for it before recording).
    pub fn record<'a>(
        &mut self,
        gpu: &GpuDevice,
        cmd: vk::CommandBuffer,
        views: impl Iterator<Item = (ViewKey, &'a ViewTarget)>,
        now: Instant,
    ) -> Result<bool, GpuError> {
        let Some(text) = self.timer.showing(now).map(str::to_string) else {
            self.destroy(gpu);
            return Ok(false);
        };
        let mut drawn = false;
        for (key, target) in views {
            let stale = self.overlays.get(&key).is_some_and(|o| {
                o.text != text || o.format != target.format || o.region != target.region
            });
            if stale {
                if let Some(mut old) = self.overlays.remove(&key) {
                    old.buffer.destroy(gpu);
                }
            }
            let o = match self.overlays.entry(key) {
                Entry::Occupied(o) => o.into_mut(),
                Entry::Vacant(slot) => match overlay(gpu, &text, target)? {
                    Some(o) => slot.insert(o),
                    None => continue,
                },
            };
            // The overlay buffer is host-written before this submission.
            record_buffer_copy(gpu, cmd, (&o.buffer, &target.pixels), &o.copies);
            drawn = true;
        }
        Ok(drawn)
    }

    /// Frees the overlays' buffers. The GPU must be done with them.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        for (_, mut o) in self.overlays.drain() {
            o.buffer.destroy(gpu);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::PixelLayout;

    #[test]
    fn text_names_the_mode_or_method_and_lambda() {
        let mut s = Settings::default();
        assert_eq!(text(&s), "CONTRASTXR ENHANCE λE 0.40");
        s.params.method = Method::HueOnly;
        s.params.lambda_e = 0.6;
        assert_eq!(text(&s), "CONTRASTXR HUE-ONLY λE 0.60");
        s.params.mode = ViewMode::Split;
        assert_eq!(text(&s), "CONTRASTXR SPLIT λE 0.60");
    }

    #[test]
    fn shows_after_start_and_after_each_change_then_expires() {
        let t0 = Instant::now();
        let mut s = Settings::default();
        let mut timer = Timer::default();
        timer.update(&s, t0);
        assert_eq!(timer.showing(t0), Some("CONTRASTXR ENHANCE λE 0.40"));
        let later = t0 + Duration::from_secs(2);
        timer.update(&s, later);
        assert!(
            timer.showing(later).is_some(),
            "same generation: still the first start"
        );
        let expired = t0 + Duration::from_secs_f32(3.01);
        timer.update(&s, expired);
        assert_eq!(timer.showing(expired), None);
        // A change of settings (a new generation) shows the new text for another 3 s.
        s.params.lambda_e = 0.7;
        s.generation += 1;
        timer.update(&s, expired);
        assert_eq!(timer.showing(expired), Some("CONTRASTXR ENHANCE λE 0.70"));
        assert_eq!(timer.showing(expired + Duration::from_secs(4)), None);
        // Switched off: never shown.
        s.indicator = false;
        s.generation += 1;
        timer.update(&s, expired);
        assert_eq!(timer.showing(expired), None);
    }

    #[test]
    fn runs_cover_the_glyphs_inside_the_region() {
        let text = "CONTRASTXR ENHANCE λE 0.40";
        let region = (160, 120);
        let runs = runs(text, region);
        let (x0, y0, scale) = placement(text, region).unwrap();
        assert_eq!(scale, 1);
        assert_eq!(y0, 24);
        // 26 glyphs of 5 columns plus 25 blank columns: 155 pixels wide, centred.
        assert_eq!(x0, (160 - 155) / 2);
        for r in &runs {
            assert!(r.x >= x0 && r.x + r.len <= x0 + 155, "{r:?}");
            assert!(r.y >= y0 && r.y < y0 + 7, "{r:?}");
        }
        // The 'C' of row 0 is the three middle columns of its first glyph.
        assert_eq!(
            runs[0],
            Run {
                x: x0 + 1,
                y: y0,
                len: 3
            }
        );
        assert!(
            super::runs(text, (100, 100)).is_empty(),
            "too narrow: not drawn"
        );
        let big = placement(text, (1268, 720)).unwrap();
        assert_eq!(big.2, 4);
    }

    #[test]
    fn the_colour_in_every_format() {
        let f = |layout, srgb| PixelFormat { layout, srgb };
        assert_eq!(
            encode(f(PixelLayout::Rgba8, true), COLOUR),
            [64, 255, 64, 255]
        );
        assert_eq!(
            encode(f(PixelLayout::Bgra8, true), COLOUR),
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
