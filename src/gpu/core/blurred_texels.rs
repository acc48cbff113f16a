//! The camera frame decoded and blurred in f32, packed exactly as the GPU's `blurred_texels`
//! image holds it (shaders/background.wgsl; `pack_linear` in shaders/common.wgsl): made on the
//! CPU by a live background's own thread, so that a frame only copies it into that image
//! (gpu/vulkan/frame/prepared_background.rs) instead of running the decode and blur passes. The arithmetic
//! follows the passes' (decoded texels rounded to the packing, the same f32 taps summed in the
//! same order), so both agree to the packing's rounding; src/background_preparation.rs is the f64 reference.

use crate::algorithm::params::{Params, MAX_BLUR_SIZE};
use crate::colour;
use crate::image::RgbaImage;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Bits per linear channel in a packed texel, and its largest code: the shader interface's
/// (src/gpu/core/interface.rs), the one definition.
pub use super::interface::{LINEAR_BITS, LINEAR_MAX};
/// Bytes per texel: two packed texels (the texel and its right neighbour), 8 bytes each.
pub const TEXEL_BYTES: usize = 16;
/// Taps at offsets 0..=half for the widest blur.
const TAPS: usize = MAX_BLUR_SIZE as usize / 2 + 1;

/// The blur texels are made with: the f32 Gaussian taps at offsets 0..=half, as the GPU passes
/// get them in their push constants. A prepared frame is used only with equal taps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlurTaps {
    pub half: usize,
    pub taps: [f32; TAPS],
}

impl BlurTaps {
    /// The taps of `params` (blur on or off, blur_size, blur_sigma).
    pub fn of(params: &Params) -> BlurTaps {
        let weights = params.blur_taps();
        let half = weights.len() / 2;
        let mut taps = [0.0f32; TAPS];
        for (k, t) in taps.iter_mut().enumerate().take(half + 1) {
            *t = weights[half + k] as f32;
        }
        BlurTaps { half, taps }
    }
}

/// A camera frame decoded, blurred and packed: entry (x, y) at byte `16 * (y * width + x)`
/// holds texel x and its right neighbour (itself in the last column), little-endian words.
#[derive(Clone, Debug)]
pub struct BlurredTexels {
    pub width: u32,
    pub height: u32,
    pub blur: BlurTaps,
    pub bytes: Vec<u8>,
    /// Names these texels among all prepared in the process (a clone keeps it): what a mapped
    /// image written with them says it holds.
    pub serial: u64,
}

/// Where a live source hands each frame's texels, on its own thread, before it publishes the
/// frame (camera/mailbox.rs): the frame engine's mapped images (gpu/core/texels/texel_slots.rs), so that
/// the app's frame call finds them already written. Never blocks on the consumer.
pub trait TexelSink: Send + Sync {
    fn offer(&self, texels: &BlurredTexels);
}

/// The next `BlurredTexels::serial` (0 is never given).
static NEXT_SERIAL: AtomicU64 = AtomicU64::new(1);

fn next_serial() -> u64 {
    NEXT_SERIAL.fetch_add(1, Ordering::Relaxed)
}

/// 2^23: adding it rounds an f32 in [0, 2^22] to an integer, ties to even (the default rounding
/// mode) as WGSL's `round`, without a call to `rint` on CPUs lacking SSE4.1.
const ROUNDER: f32 = 8_388_608.0;

/// `pack_linear` of one channel: [0, 1] onto 0..=LINEAR_MAX, ties to even.
fn quantize(v: f32) -> u64 {
    let scaled = v.clamp(0.0, 1.0) * LINEAR_MAX as f32;
    // In [2^23, 2^24) an f32's ulp is 1: its mantissa bits are the rounded integer.
    u64::from((scaled + ROUNDER).to_bits() & 0x7f_ffff)
}

/// One texel's packed bits: R, G, B at bits 0, 21 and 42 (two little-endian u32 words).
fn pack(c: &[f32]) -> u64 {
    quantize(c[0]) | quantize(c[1]) << LINEAR_BITS | quantize(c[2]) << (2 * LINEAR_BITS)
}

/// The decoded value of each 8-bit code as the blur reads it: rounded to the packing.
fn decode_table() -> [f32; 256] {
    std::array::from_fn(|c| {
        let v = colour::code_to_linear(c as u8) as f32;
        quantize(v) as f32 * (1.0 / LINEAR_MAX as f32)
    })
}

impl BlurredTexels {
    /// Decodes and blurs `camera` with `blur` (separable, clamp-to-edge). The horizontal
    /// pass's rows are kept for the thread's next frame: for a live source's own thread.
    pub fn prepare(camera: &RgbaImage, blur: BlurTaps) -> BlurredTexels {
        Self::prepare_keeping(camera, blur, true)
    }

    /// [`prepare`](Self::prepare) for a frame made once (a still background), on any thread:
    /// nothing is kept for the thread afterwards.
    pub fn prepare_once(camera: &RgbaImage, blur: BlurTaps) -> BlurredTexels {
        Self::prepare_keeping(camera, blur, false)
    }

    fn prepare_keeping(camera: &RgbaImage, blur: BlurTaps, keep: bool) -> BlurredTexels {
        let (w, h) = (camera.width as usize, camera.height as usize);
        if w == 0 || h == 0 || camera.pixels.len() != w * h {
            // Nothing to prepare (the GPU refuses empty frames): no texels, never used.
            return BlurredTexels {
                width: 0,
                height: 0,
                blur,
                bytes: Vec::new(),
                serial: next_serial(),
            };
        }
        let mut rows = match keep {
            true => SCRATCH.with_borrow_mut(std::mem::take),
            false => Vec::new(),
        };
        horizontal(camera, &blur, &mut rows);
        let mut bytes = pooled_bytes(w * h * TEXEL_BYTES);
        let mut out = vec![0.0f32; 3 * w];
        let mut packed = vec![0u64; w];
        for (y, dst) in bytes.chunks_exact_mut(w * TEXEL_BYTES).enumerate() {
            vertical(&rows, (w, h), y, &blur, &mut out);
            for (q, c) in packed.iter_mut().zip(out.as_chunks::<3>().0) {
                *q = pack(c);
            }
            for (x, entry) in dst.as_chunks_mut::<TEXEL_BYTES>().0.iter_mut().enumerate() {
                entry[..8].copy_from_slice(&packed[x].to_le_bytes());
                entry[8..].copy_from_slice(&packed[(x + 1).min(w - 1)].to_le_bytes());
            }
        }
        if keep {
            SCRATCH.with_borrow_mut(|scratch| *scratch = rows);
        }
        BlurredTexels {
            width: camera.width,
            height: camera.height,
            blur,
            bytes,
            serial: next_serial(),
        }
    }

    /// Whether these texels are what the GPU passes would make of a `size` frame with `params`.
    pub fn made_for(&self, size: (u32, u32), params: &Params) -> bool {
        (self.width, self.height) == size && self.blur == BlurTaps::of(params)
    }

    /// The entry of texel (x, y) as the four u32 words of the GPU's image.
    pub fn entry(&self, x: u32, y: u32) -> [u32; 4] {
        let at = (y as usize * self.width as usize + x as usize) * TEXEL_BYTES;
        std::array::from_fn(|k| {
            let b = &self.bytes[at + 4 * k..at + 4 * k + 4];
            u32::from_le_bytes([b[0], b[1], b[2], b[3]])
        })
    }
}

/// Texel buffers of frames no longer used, kept for the next frames: a live source prepares
/// one camera-sized buffer per frame, and allocating each anew grows the allocator's arenas
/// (the same reason as camera/pool.rs). A few frames are alive at once at most.
static POOL: Mutex<Vec<Vec<u8>>> = Mutex::new(Vec::new());
const POOLED: usize = 4;

thread_local! {
    /// The horizontal pass's rows, reused by a source thread from frame to frame.
    static SCRATCH: std::cell::RefCell<Vec<f32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// A zeroed-or-reused buffer of `len` bytes (every byte is overwritten by `prepare`).
fn pooled_bytes(len: usize) -> Vec<u8> {
    let mut pool = POOL.lock().unwrap_or_else(|p| p.into_inner());
    match pool.iter().position(|b| b.len() == len) {
        Some(k) => pool.swap_remove(k),
        None => vec![0u8; len],
    }
}

impl Drop for BlurredTexels {
    fn drop(&mut self) {
        let bytes = std::mem::take(&mut self.bytes);
        if bytes.is_empty() {
            return;
        }
        let mut pool = POOL.lock().unwrap_or_else(|p| p.into_inner());
        if pool.len() < POOLED {
            pool.push(bytes);
        }
    }
}

/// Every row decoded and blurred horizontally (the pass's `hblur_row`): RGB floats, row-major,
/// into `out` (resized).
fn horizontal(camera: &RgbaImage, blur: &BlurTaps, out: &mut Vec<f32>) {
    let lut = decode_table();
    let (w, half) = (camera.width as usize, blur.half);
    out.clear();
    out.resize(3 * camera.pixels.len(), 0.0);
    // The row with `half` clamp-to-edge texels on each side, RGB floats.
    let mut padded = vec![0.0f32; 3 * (w + 2 * half)];
    for (row, dst) in camera
        .pixels
        .chunks_exact(w)
        .zip(out.chunks_exact_mut(3 * w))
    {
        for (i, p) in padded.as_chunks_mut::<3>().0.iter_mut().enumerate() {
            let c = row[i.saturating_sub(half).min(w - 1)];
            p.copy_from_slice(&[lut[c[0] as usize], lut[c[1] as usize], lut[c[2] as usize]]);
        }
        // Texel x is padded texel x + half; offset o texels is 3 * o floats.
        let centre = &padded[3 * half..3 * (half + w)];
        for (d, c) in dst.iter_mut().zip(centre) {
            *d = blur.taps[0] * c;
        }
        for o in 1..=half {
            let left = &padded[3 * (half - o)..3 * (half - o + w)];
            let right = &padded[3 * (half + o)..3 * (half + o + w)];
            let t = blur.taps[o];
            for ((d, l), r) in dst.iter_mut().zip(left).zip(right) {
                *d += t * (l + r);
            }
        }
    }
}

/// Output row `y`: the horizontally blurred rows y - half..=y + half (clamped), top first.
fn vertical(rows: &[f32], (w, h): (usize, usize), y: usize, blur: &BlurTaps, out: &mut [f32]) {
    let half = blur.half;
    let row = |k: usize| {
        let source = (y + k).saturating_sub(half).min(h - 1);
        &rows[3 * w * source..3 * w * (source + 1)]
    };
    let first = blur.taps[half];
    for (o, r) in out.iter_mut().zip(row(0)) {
        *o = first * r;
    }
    for k in 1..=2 * half {
        let tap = blur.taps[k.abs_diff(half)];
        for (o, r) in out.iter_mut().zip(row(k)) {
            *o += tap * r;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unpack(bytes: [u8; 8]) -> [f64; 3] {
        let q = u64::from_le_bytes(bytes);
        std::array::from_fn(|k| {
            ((q >> (LINEAR_BITS as usize * k)) & u64::from(LINEAR_MAX)) as f64
                / f64::from(LINEAR_MAX)
        })
    }

    fn noise(w: u32, h: u32) -> RgbaImage {
        let mut img = RgbaImage::new(w, h, [0, 0, 0, 255]);
        let mut s = 12345u32;
        for p in &mut img.pixels {
            for c in p.iter_mut().take(3) {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                *c = (s >> 24) as u8;
            }
        }
        img
    }

    #[test]
    fn matches_the_f64_reference_to_the_packing() {
        let camera = noise(37, 23);
        for (blur, blur_size, blur_sigma) in [(true, 3, 1.5), (true, 15, 5.0), (false, 3, 1.5)] {
            let params = Params {
                blur,
                blur_size,
                blur_sigma,
                ..Params::default()
            };
            let texels = BlurredTexels::prepare(&camera, BlurTaps::of(&params));
            let reference = crate::background_preparation::blurred_camera(&camera, &params);
            for y in 0..23 {
                for x in 0..37 {
                    let at = (y * 37 + x) as usize * TEXEL_BYTES;
                    let bytes = &texels.bytes[at..at + TEXEL_BYTES];
                    let right = (x + 1).min(36);
                    let got = [
                        unpack(bytes[..8].try_into().unwrap()),
                        unpack(bytes[8..].try_into().unwrap()),
                    ];
                    for (g, at) in got.iter().zip([x, right]) {
                        let want = reference.pixels[(y * 37 + at) as usize];
                        for k in 0..3 {
                            // Packing (2.4e-7) and f32 sums: a few codes at most.
                            assert!(
                                (g[k] - want[k]).abs() < 2e-6,
                                "({x}, {y}) {k}: {} vs {}",
                                g[k],
                                want[k]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn taps_follow_the_settings() {
        let on = Params::default();
        let off = Params { blur: false, ..on };
        let wider = Params { blur_size: 5, ..on };
        let texels = BlurredTexels::prepare(&noise(4, 3), BlurTaps::of(&on));
        assert!(texels.made_for((4, 3), &on));
        assert!(!texels.made_for((4, 3), &off) && !texels.made_for((4, 3), &wider));
        assert!(!texels.made_for((3, 4), &on));
        assert_eq!(BlurTaps::of(&off).half, 0);
        assert_eq!(BlurTaps::of(&off).taps[0], 1.0);
    }

    #[test]
    fn an_empty_frame_gives_no_texels() {
        let blur = BlurTaps::of(&Params::default());
        let texels = BlurredTexels::prepare(&RgbaImage::new(0, 3, [0; 4]), blur);
        assert!(texels.bytes.is_empty() && !texels.made_for((0, 3), &Params::default()));
    }

    #[test]
    fn packing_matches_the_shader_layout() {
        // R in bits 0..21 of word 0, G across the words (11 low bits in word 0), B in word 1.
        let q = pack(&[1.0, 1.0, 0.0]);
        assert_eq!(q, u64::from(LINEAR_MAX) | u64::from(LINEAR_MAX) << 21);
        assert_eq!(
            unpack(pack(&[0.25, 0.5, 0.75]).to_le_bytes()).map(|v| (v * 4.0).round()),
            [1.0, 2.0, 3.0]
        );
    }
}
