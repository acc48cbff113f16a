//! What `contrastxr bench` reports of a case, whichever backend timed it.

use super::bench_case::BenchCase;

/// Medians in milliseconds over all views of a case.
#[derive(Clone, Copy, Debug)]
pub struct BenchResult {
    pub case: BenchCase,
    pub copy_ms: f64,
    /// The copy with the enhancement's 16-byte accesses (None where rows are not aligned).
    pub copy_wide_ms: Option<f64>,
    pub enhance_ms: f64,
    /// Everything the layer records per display frame: the layout transitions, the copies of
    /// each view from the app's image into its buffer and back, and the enhancement.
    pub frame_ms: f64,
    /// The same without the enhancement: the layer's image copies alone.
    pub image_copy_ms: f64,
    /// The layer's frame in place: layout transitions and the enhancement in the app's
    /// images, no copies (None when not asked for or the device cannot store the format).
    pub frame_in_place_ms: Option<f64>,
    /// The layer's frame through the image-copy path: layout transitions, the copies of each
    /// view's region into an image of the engine's own and back (vkCmdCopyImage), and the
    /// enhancement there by the in-place shaders (None when not asked for or the device cannot
    /// store the format).
    pub frame_image_copy_ms: Option<f64>,
    /// The same without the enhancement: the image-copy path's copies alone.
    pub image_copy_copies_ms: Option<f64>,
    /// The image-copy path with only the tiles the enhancement listed drawn back into the
    /// app's images (a render pass) instead of the whole regions copied back (None where
    /// `frame_image_copy_ms` is, and on OpenGL).
    pub frame_image_copy_tiles_ms: Option<f64>,
    /// The sampled read: each region read through a sampled view of the app's image (no copy
    /// in), enhanced into the engine's image and its listed tiles drawn back (None where
    /// `frame_image_copy_tiles_ms` is).
    pub frame_sampled_tiles_ms: Option<f64>,
    /// Per camera frame: decode and blur on the camera grid (once, whatever the views).
    pub background_ms: f64,
    /// Fraction of pixels that are foreground (neither black nor alpha 0).
    pub foreground: f64,
}

impl BenchResult {
    /// Enhancement time over copy time.
    pub fn ratio(&self) -> f64 {
        self.enhance_ms / self.copy_ms
    }

    /// Enhancement time over the 16-byte copy's time.
    pub fn ratio_wide(&self) -> Option<f64> {
        self.copy_wide_ms.map(|c| self.enhance_ms / c)
    }

    /// The layer's whole per-frame work over the copy's time.
    pub fn frame_ratio(&self) -> f64 {
        self.frame_ms / self.copy_ms
    }

    /// The frame in place over the frame through copies.
    pub fn in_place_ratio(&self) -> Option<f64> {
        self.frame_in_place_ms.map(|f| f / self.frame_ms)
    }

    /// The frame through the image-copy path over the frame in place.
    pub fn image_copy_in_place_ratio(&self) -> Option<f64> {
        Some(self.frame_image_copy_ms? / self.frame_in_place_ms?)
    }

    /// The image-copy path with the tiles drawn back over the frame in place.
    pub fn image_copy_tiles_in_place_ratio(&self) -> Option<f64> {
        Some(self.frame_image_copy_tiles_ms? / self.frame_in_place_ms?)
    }

    /// The sampled read with the tiles drawn back over the frame in place.
    pub fn sampled_tiles_in_place_ratio(&self) -> Option<f64> {
        Some(self.frame_sampled_tiles_ms? / self.frame_in_place_ms?)
    }

    /// The frame through the image-copy path over the frame through buffer copies.
    pub fn image_copy_frame_ratio(&self) -> Option<f64> {
        self.frame_image_copy_ms.map(|f| f / self.frame_ms)
    }

    /// A display frame that also brings a new camera frame (a live camera at or above the
    /// display's rate): the background preparation then the frame, one after the other on the
    /// queue, so the sum of the two medians.
    pub fn live_frame_ms(&self) -> f64 {
        self.frame_ms + self.background_ms
    }

    pub fn megapixels(&self) -> f64 {
        let (w, h) = self.case.region;
        f64::from(w) * f64::from(h) * f64::from(self.case.views) / 1e6
    }
}

/// The median of `v` (NaN for none): the middle value, or the mean of the two middle ones.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}
